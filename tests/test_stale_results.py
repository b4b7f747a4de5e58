"""The mutation suite: no edit leaves a stale result, and no text-only edit reruns anything.

Two finished runs the session shares (``tests/conftest.py``) are edited, each in a work tree with
its own copy of the package, which its jobs import (``PYTHONPATH``): the reduced grid of the
three built-in studies with the external LM rule (``builtin``), and the fourth study from
``tests/data/fourth_study`` without them, its module loaded as an extension beside a second,
``tests/data/second_study.py`` (``extension``). Each case
below applies one kind of edit a user makes: to library code, to the workflow's scripts and
rules, to data files jobs read, to the config. It then asks ``snakemake --dry-run`` what it would
run, and holds that to the jobs the edit must rerun (``reruns``) and to jobs it must leave alone
(``spares``), and puts the file back as it was. A new kind of edit is one more ``Edit`` in
``EDITS`` (or entry in ``CONFIG_EDITS``). An edit marked ``backdated`` leaves the edited file
older than every result, as a copy that keeps time stamps does (``cp -p``, ``rsync -a``,
``tar x``): only its content can tell it changed. One with ``targets`` asks about those files,
made first in a copy of the run, instead of the default target.

Every job loads the extension modules, so the modules an extension imports count for every job
of a run that lists it: there, a paper's or a figure's edit reruns every job.

Set ``JOINTBENCH_MUTATION_REPORT`` to a file path to have every case's scheduled jobs written
there as JSON (``benchmarks/stale_results.py`` prints them as a table).
"""

from __future__ import annotations

import copy
import dataclasses
import json
import os
import re
import shutil
import subprocess
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import pytest
import yaml
from workflow_copy import OVERLAY, FinishedRun

pytestmark = pytest.mark.pipeline


@dataclass(frozen=True)
class Edit:
    """One edit: in ``path`` (relative to the work tree) replace ``old`` by ``new`` (``old``
    must occur); or, with ``old`` empty, append ``new``. ``reruns``: jobs the dry run must
    schedule; ``spares``: jobs it must not; a job is ``rule`` or ``rule[wildcard=value]``."""

    kind: str
    path: str
    old: str
    new: str
    reruns: frozenset[str] = field(default_factory=frozenset)
    spares: frozenset[str] = field(default_factory=frozenset)
    scenario: str = "builtin"
    backdated: bool = False
    targets: tuple[str, ...] = ()

    def apply(self, text: str) -> str:
        if not self.old:
            return text + self.new
        assert self.old in text, f"{self.kind}: {self.old!r} is no longer in {self.path}"
        return text.replace(self.old, self.new, 1)


def _jobs(*names: str) -> frozenset[str]:
    return frozenset(names)


PKG = "src/jointbench"
NOTHING = _jobs()
EVERY_ESTIMATE = _jobs("estimate_cmc", "estimate_hinge", "estimate_hip")
SIMULATIONS = _jobs("simulate_cmc", "simulate_hinge", "simulate_hip")
DATA_JOBS = EVERY_ESTIMATE | SIMULATIONS | _jobs("estimate_cmc_LM", "poses_hip")

LM_PROGRAM = Edit(
    "an external estimator's program (LM)",
    "workflow/external/lm_sphere.py",
    "",
    "\n_EDITED = 1.0\n",
    reruns=_jobs("estimate_cmc_LM", "collect[study=cmc]", "render_cmc"),
    spares=_jobs("estimate_cmc", "simulate_cmc", "estimate_hinge"),
)

EDITS = (
    # -- library code: every construct counts, wherever the job can import it from ------------
    Edit(
        "keyword default of an estimator (BC tol_x)",
        f"{PKG}/estimators/sphere.py",
        "    tol_x: Positive = 1e-4,\n",
        "    tol_x: Positive = 1e-3,\n",
        reruns=_jobs("estimate_cmc[method=BC]", "collect[study=cmc]", "render_cmc"),
    ),
    Edit(
        "function body of an estimator",
        f"{PKG}/estimators/sphere.py",
        "if step <= tol_x and change <= tol_fun:",
        "if step <= tol_x and change <= 2 * tol_fun:",
        reruns=_jobs("estimate_cmc[method=BC]", "estimate_cmc[method=NM]"),
    ),
    Edit(
        "staticmethod body",
        f"{PKG}/estimators/axis.py",
        "return np.zeros(len(directions), dtype=int) if trials is None",
        "return np.zeros(len(directions), dtype=np.int64) if trials is None",
        reruns=_jobs("estimate_hinge[method=radial]", "estimate_hinge[method=combined]"),
    ),
    Edit(
        "property body",
        f"{PKG}/simulate/__init__.py",
        "return next(iter(self.segments.values())).shape[0]",
        "return int(next(iter(self.segments.values())).shape[0])",
        reruns=SIMULATIONS | EVERY_ESTIMATE,
    ),
    Edit(
        "module-level constant (a simulator's marker distance table)",
        f"{PKG}/simulate/cmc.py",
        '_TABLE_1_DISTANCES_MM = {"M": (13.8, 29.0, 15.7)',
        '_TABLE_1_DISTANCES_MM = {"M": (13.8, 29.0, 15.8)',
        reruns=_jobs("simulate_cmc", "estimate_cmc_LM", "collect[study=cmc]", "render_cmc"),
    ),
    Edit(
        "module-level instance (a hinge marker layout)",
        f"{PKG}/simulate/hinge.py",
        "markers_mm=((57.5, 36.0, -143.5)",
        "markers_mm=((57.5, 36.0, -143.0)",
        reruns=_jobs("simulate_hinge", "estimate_hinge[method=planar]", "render_hinge"),
    ),
    Edit(
        "a Study's own field",
        f"{PKG}/simulate/cmc.py",
        'exclusive_minimum=True, maximum=180, label="RoM"',
        'exclusive_minimum=True, maximum=179, label="RoM"',
        reruns=_jobs("simulate_cmc", "render_cmc", "check_published"),
    ),
    Edit(
        "dataclass default factory",
        f"{PKG}/simulate/cmc.py",
        "default_factory=lambda: _as_tuples(_TABLE_1_DISTANCES_MM)",
        "default_factory=lambda: dict(_as_tuples(_TABLE_1_DISTANCES_MM))",
        reruns=_jobs("simulate_cmc", "estimate_cmc[method=LS]"),
    ),
    Edit(
        "cached_property, classmethod and lambda added to a shared module",
        f"{PKG}/geometry.py",
        "",
        "\n\nimport functools\n\n\nclass _Unused:\n    @functools.cached_property\n"
        "    def x(self):\n        return 1\n\n    @classmethod\n    def y(cls):\n"
        "        return lambda: 2\n",
        reruns=SIMULATIONS,
    ),
    Edit(
        "a compiled kernel's Python source",
        f"{PKG}/numerics/compiled.py",
        "",
        "\n\n_KERNEL_NOTE = 1\n",
        reruns=_jobs("estimate_cmc[method=NM]", "poses_hip"),
    ),
    Edit(
        "figure code",
        f"{PKG}/figures/common.py",
        "",
        "\n\n_FIGURE_NOTE = 1\n",
        reruns=_jobs("render_cmc", "render_hinge", "render_hip"),
        spares=DATA_JOBS | _jobs("collect"),
    ),
    Edit(
        "a paper's measure (paper B)",
        f"{PKG}/papers/paper_b.py",
        "",
        "\n\n_MEASURE_NOTE = 1\n",
        reruns=_jobs("render_hinge", "check_published", "report_captions"),
        spares=DATA_JOBS | _jobs("collect"),
    ),
    Edit(
        "report code",
        f"{PKG}/report.py",
        "",
        "\n\n_REPORT_NOTE = 1\n",
        reruns=_jobs("report_captions"),
        spares=DATA_JOBS | _jobs("collect", "render_cmc", "check_published"),
    ),
    Edit(
        "collect code",
        f"{PKG}/running/collected.py",
        "",
        "\n\n_COLLECT_NOTE = 1\n",
        reruns=_jobs("collect[study=cmc]", "collect[study=hip]"),
        spares=DATA_JOBS,
    ),
    Edit(
        "a constant of a kernel two calls away (the 3 x 3 Jacobi sweeps)",
        f"{PKG}/numerics/small.py",
        "    for _ in range(60):\n        off = a01**2",
        "    for _ in range(59):\n        off = a01**2",
        reruns=SIMULATIONS | EVERY_ESTIMATE | _jobs("poses_hip"),
    ),
    Edit(
        "a module only the input checks import (centre precision)",
        f"{PKG}/estimators/centre_precision.py",
        "MIN_REJECTED_STEP_MM = 5.0",
        "MIN_REJECTED_STEP_MM = 4.0",
        reruns=SIMULATIONS | EVERY_ESTIMATE,
    ),
    Edit(
        "the simulators' noise model",
        f"{PKG}/simulate/noise.py",
        "",
        "\n\n_NOISE_NOTE = 1\n",
        reruns=SIMULATIONS | EVERY_ESTIMATE,
    ),
    Edit(
        "a claim's measure (paper B B5)",
        f"{PKG}/papers/paper_b.py",
        "difference {gap.max():.2f}°",
        "difference {gap.max():.3f}°",
        reruns=_jobs("render_hinge", "check_published", "report_captions"),
        spares=DATA_JOBS | _jobs("collect"),
    ),
    # -- text that does not change what code does: nothing reruns ------------------------------
    Edit(
        "docstring only (an estimator module's)",
        f"{PKG}/estimators/sphere.py",
        '"""',
        '"""Edited. ',
        spares=DATA_JOBS | _jobs("collect", "render_cmc", "check_published"),
    ),
    Edit(
        "comment only",
        f"{PKG}/estimators/sphere.py",
        "",
        "\n# A comment changes nothing.\n",
        spares=DATA_JOBS | _jobs("collect", "render_cmc", "check_published"),
    ),
    Edit(
        "formatting only (blank lines, a line split)",
        f"{PKG}/simulate/cmc.py",
        '_TABLE_1_DISTANCES_MM = {"M": (13.8, 29.0, 15.7),',
        '\n\n_TABLE_1_DISTANCES_MM = {\n    "M": (13.8, 29.0, 15.7),',
        spares=DATA_JOBS | _jobs("collect", "render_cmc", "check_published"),
    ),
    # -- the workflow and the programs its rules run ---------------------------------------
    Edit(
        "a workflow script",
        "workflow/scripts/render.py",
        "",
        '\nlog_note = "rendered"\n',
        reruns=_jobs("render_cmc", "render_hinge", "render_hip"),
        spares=DATA_JOBS,
    ),
    LM_PROGRAM,
    Edit(
        "an external rule's command line",
        "workflow/rules/estimators/lm_sphere.smk",
        "--out-dir {params.out_dir:q}",
        "--out-dir {params.out_dir:q} ",
        reruns=_jobs("estimate_cmc_LM", "collect[study=cmc]"),
        spares=_jobs("estimate_cmc", "simulate_cmc"),
    ),
    Edit(
        "a rule's parameters (render)",
        "workflow/rules/render.smk",
        "            study=_study,\n",
        "            study=_study,\n            note=1,\n",
        reruns=_jobs("render_cmc", "render_hinge", "render_hip"),
        spares=DATA_JOBS | _jobs("collect"),
    ),
    Edit(
        "an extension module (the fourth study)",
        "toy_study.py",
        "",
        "\n_EDITED = 1\n",
        reruns=_jobs("simulate_toy", "estimate_toy[method=toy-centroid]", "render_toy"),
        scenario="extension",
    ),
    # Not listed under extensions: found on PYTHONPATH, beside the package.
    Edit(
        "a module of the user's own an extension imports",
        "src/second_helper.py",
        "",
        "\n_EDITED = 1\n",
        reruns=_jobs("simulate_second", "simulate_toy", "render_toy"),
        scenario="extension",
    ),
    Edit(
        "a figure module an extension imports",
        f"{PKG}/figures/common.py",
        "",
        "\n\n_FIGURE_NOTE = 1\n",
        reruns=_jobs("render_toy", "estimate_toy[method=NM]", "simulate_toy"),
        scenario="extension",
    ),
    Edit(
        "the collect script",
        "workflow/scripts/collect.py",
        "",
        "\n_COLLECT_NOTE = 1\n",
        reruns=_jobs("collect[study=cmc]", "collect[study=hip]", "render_hip"),
        spares=DATA_JOBS,
    ),
    Edit(
        "a rule's parameters (simulate)",
        "workflow/rules/simulate.smk",
        "        params:\n            study=_study,\n",
        "        params:\n            study=_study,\n            note=1,\n",
        reruns=SIMULATIONS | EVERY_ESTIMATE,
    ),
    # -- data files that jobs read -----------------------------------------------------------
    Edit(
        "a published value (paper B Table 1)",
        f"{PKG}/papers/paper_b.yaml",
        "  published: 4.3\n",
        "  published: 5.3\n",
        reruns=_jobs("render_hinge", "check_published", "report_captions"),
        spares=DATA_JOBS | _jobs("collect"),
    ),
    Edit(
        "an extension's published values",
        "paper_t.yaml",
        "published: 5.0\n",
        "published: 4.0\n",
        reruns=_jobs("render_toy", "check_published"),
        spares=_jobs("simulate_toy", "estimate_toy", "collect"),
        scenario="extension",
    ),
    Edit(
        "a claim's tolerance (paper B B1)",
        f"{PKG}/papers/paper_b.yaml",
        "    at_least: 0.8\n  tolerance_reason: stated as a trend",
        "    at_least: 0.99\n  tolerance_reason: stated as a trend",
        reruns=_jobs("render_hinge", "check_published", "report_captions"),
        spares=DATA_JOBS | _jobs("collect", "render_cmc"),
    ),
    # Read by the sensitivity target alone (its backdated edit below), not by the default one.
    Edit(
        "a named protocol's overlay, for the default target",
        "config/variants/hinge_anatomical_knee.yaml",
        "[45, 20, -210]",
        "[45, 20, -200]",
        spares=DATA_JOBS | _jobs("collect", "render_hinge", "check_published"),
    ),
    # -- the same data files replaced by a copy dated before every result ----------------------
    Edit(
        "a published value, dated before the results (paper A)",
        f"{PKG}/papers/paper_a.yaml",
        "  published: 8.0\n",
        "  published: 80.0\n",
        reruns=_jobs("render_cmc", "check_published", "report_captions"),
        spares=DATA_JOBS | _jobs("collect", "render_hinge"),
        backdated=True,
    ),
    Edit(
        "the published values' schema, dated before the results",
        f"{PKG}/schemas/published.schema.yaml",
        "abs: {type: number, minimum: 0}",
        "abs: {type: number, minimum: 1000}",
        reruns=_jobs("check_published", "render_cmc", "render_hinge", "report_captions"),
        spares=DATA_JOBS | _jobs("collect"),
        backdated=True,
    ),
    Edit(
        "the config's schema, dated before the results",
        f"{PKG}/schemas/config.schema.yaml",
        "trials:\n          type: integer\n          minimum: 1",
        "trials:\n          type: integer\n          minimum: 2",
        reruns=SIMULATIONS | EVERY_ESTIMATE | _jobs("check_published"),
        backdated=True,
    ),
    dataclasses.replace(
        LM_PROGRAM, kind=f"{LM_PROGRAM.kind}, dated before the results", backdated=True
    ),
    Edit(
        "an external estimator's script, dated before the results (centroid)",
        "workflow/external/centroid.py",
        "",
        "\n_EDITED = 1.0\n",
        reruns=_jobs("estimate_centroid[condition=marker_set-M__rom_deg-5__noise_mm-1.0]"),
        spares=_jobs("blind_dataset", "simulate_cmc"),
        backdated=True,
        targets=("results/estimates/cmc/centroid/marker_set-M__rom_deg-5__noise_mm-1.0.parquet",),
    ),
    Edit(
        "an external estimator's C source, dated before the results (LS-C)",
        "workflow/external/ls_sphere.c",
        "",
        "\n/* edited */ static const int EDITED = 1;\n",
        reruns=_jobs("compile_ls_sphere"),
        backdated=True,
        targets=("results/bin/ls_sphere",),
    ),
    # -- edits that change no result: text only, a copy of the same bytes, what no job reads ---
    Edit(
        "a comment in the config",
        "config/config.yaml",
        "",
        "\n# A comment changes nothing.\n",
        spares=DATA_JOBS | _jobs("collect", "render_cmc", "render_hinge", "check_published"),
    ),
    Edit(
        "a comment in a named protocol's overlay",
        "config/variants/hinge_anatomical_knee.yaml",
        "",
        "\n# A comment changes nothing.\n",
        spares=DATA_JOBS | _jobs("collect", "render_hinge", "check_published"),
    ),
    Edit(
        "a comment at the end of a rule file",
        "workflow/rules/render.smk",
        "",
        "\n# A comment changes nothing.\n",
        spares=DATA_JOBS | _jobs("collect", "render_cmc", "render_hinge", "check_published"),
    ),
    Edit(
        "a published value rewritten with the same bytes (paper A)",
        f"{PKG}/papers/paper_a.yaml",
        "",
        "",
        spares=DATA_JOBS | _jobs("collect", "render_cmc", "check_published"),
    ),
    Edit(
        "an external estimator's program rewritten with the same bytes (LM)",
        "workflow/external/lm_sphere.py",
        "",
        "",
        spares=DATA_JOBS | _jobs("collect", "render_cmc"),
    ),
    Edit(
        "a new external estimator's rule, not yet listed",
        "workflow/rules/estimators/centroid.smk",
        "",
        "\n\nrule estimate_newcomer:\n    input:\n"
        '        "results/blind/{study}/{condition}.parquet",\n    output:\n'
        '        "results/estimates/{study}/newcomer/{condition}.parquet",\n    log:\n'
        '        "results/logs/estimate/{study}/newcomer/{condition}.log",\n    script:\n'
        '        "../../external/centroid.py"\n',
        spares=DATA_JOBS | _jobs("collect", "render_cmc", "check_published", "blind_dataset"),
    ),
    Edit(
        "a published value (paper C)",
        f"{PKG}/papers/paper_c.yaml",
        "  published: 96.04\n",
        "  published: 96.05\n",
        reruns=_jobs("render_hip", "check_published"),
        spares=DATA_JOBS | _jobs("collect", "render_cmc", "render_hinge"),
    ),
    Edit(
        "an extension's docstring",
        "toy_study.py",
        "The study spins three markers",
        "The study turns three markers",
        spares=_jobs("simulate_toy", "estimate_toy", "collect", "render_toy", "check_published"),
        scenario="extension",
    ),
    Edit(
        "a named protocol's overlay, dated before the results",
        "config/variants/hinge_anatomical_knee.yaml",
        "[45, 20, -210]",
        "[45, 20, -200]",
        reruns=_jobs("sensitivity_member_hinge[member=anatomical-knee]"),
        backdated=True,
        targets=("results/sensitivity/hinge/anatomical-knee.csv",),
    ),
)


# The shared run each scenario edits, by fixture: a case asks for it by name, so it joins the
# run's group itself (tests/conftest.py).
SHARED_RUN = {"builtin": "reduced_run", "extension": "fourth_study_run"}


def _config_edit(
    kind: str, change: Callable[[dict], None], reruns, spares=NOTHING, scenario="builtin"
):
    return pytest.param(
        kind,
        change,
        frozenset(reruns),
        frozenset(spares),
        scenario,
        id=kind,
        marks=pytest.mark.xdist_group(SHARED_RUN[scenario]),
    )


def _set(path: str, value):
    def change(config: dict) -> None:
        *parents, last = path.split(".")
        node = config
        for key in parents:
            node = node.setdefault(key, {})
        node[last] = value

    return change


def _without_extension(entry: str, study: str) -> Callable[[dict], None]:
    """An edit that drops ``entry`` from the extensions and its ``study`` from the studies."""

    def change(config: dict) -> None:
        config["extensions"].remove(entry)
        del config["studies"][study]

    return change


CONFIG_EDITS = (
    _config_edit(
        "trials",
        _set("studies.cmc.trials", 4),
        {"simulate_cmc", "estimate_cmc[method=NM]", "estimate_cmc_LM", "collect[study=cmc]"},
        {"simulate_hinge", "estimate_hinge"},
    ),
    _config_edit("base_seed", _set("base_seed", 1), SIMULATIONS, set()),
    # The blind copies an external estimator reads, and so its answers and their scores.
    _config_edit(
        "the blind copies' placement",
        _set("blind_placement.translation_mm", 250.0),
        {"blind_dataset", "estimate_cmc_LM", "collect[study=cmc]"},
        {"simulate_cmc", "estimate_cmc", "estimate_hinge", "simulate_hip", "estimate_hip"},
    ),
    _config_edit(
        "protocol field",
        _set("studies.cmc.protocol.spiral_turns", 3.0),
        {"simulate_cmc", "render_cmc"},
        {"simulate_hinge", "simulate_hip"},
    ),
    # The comparison's note says over how many seeds the verdicts are judged.
    _config_edit(
        "the verdicts' seeds",
        _set("verdicts.seeds", 7),
        {"check_published"},
        DATA_JOBS | _jobs("collect"),
    ),
    _config_edit(
        "one estimator's options",
        _set("studies.cmc.options.BC.tol_x", 1e-3),
        {"estimate_cmc[method=BC]", "collect[study=cmc]"},
        {"estimate_cmc[method=NM]", "estimate_cmc[method=LS]", "simulate_cmc"},
    ),
    _config_edit(
        "a grid value added",
        _set("studies.cmc.grid.noise_mm", [1.0, 2.0]),
        {"simulate_cmc", "collect[study=cmc]"},
        {"simulate_hinge"},
    ),
    _config_edit(
        "an estimator removed from a study",
        _set("studies.cmc.estimators", ["NM", "LS", "BC", "MA", "IS"]),
        {"collect[study=cmc]", "render_cmc", "check_published"},
        {"simulate_cmc", "estimate_cmc"},
    ),
    # Every job loads every extension: one fewer reruns the jobs of the study left.
    _config_edit(
        "an extension removed",
        _without_extension("second_study.py", "second"),
        {"simulate_toy", "estimate_toy[method=NM]", "render_toy", "check_published"},
        scenario="extension",
    ),
)


def _reordered(path: str):
    """An edit that lists the mapping at ``path`` in reverse key order, or the list there in
    reverse order, values unchanged."""

    def change(config: dict) -> None:
        *parents, last = path.split(".")
        node = config
        for key in parents:
            node = node[key]
        listed = node[last]
        node[last] = (
            list(reversed(listed)) if isinstance(listed, list) else dict(reversed(listed.items()))
        )

    return change


def _both(*changes: Callable[[dict], None]) -> Callable[[dict], None]:
    def change(config: dict) -> None:
        for one in changes:
            one(config)

    return change


# No job reads meaning into a key's place: a grid's conditions, their names and their order
# follow the study's own key order, the other keys are looked up by name. A reorder alone
# changes no result. Written as listed, not sorted, so that the order reaches the workflow.
ORDER_EDITS = (
    _config_edit(
        "the grids' keys reordered",
        _both(_reordered("studies.cmc.grid"), _reordered("studies.hinge.grid")),
        NOTHING,
    ),
    _config_edit(
        "a study's settings reordered",
        _both(_reordered("studies.cmc"), _reordered("studies.hip")),
        NOTHING,
    ),
    # The studies' order: the order of the report's sections is the registry's, not this.
    _config_edit("the studies reordered", _reordered("studies"), NOTHING),
    # The extensions' order: their studies' is the registry's, by file name, not this.
    _config_edit(
        "the extensions reordered", _reordered("extensions"), NOTHING, scenario="extension"
    ),
    _config_edit(
        "the grid's keys reordered and a value added",
        _both(_reordered("studies.cmc.grid"), _set("studies.cmc.grid.noise_mm", [1.0, 2.0])),
        {"simulate_cmc", "collect[study=cmc]"},
        {"simulate_hinge"},
    ),
)


# -- the finished run, and what a dry run schedules ---------------------------------------------


_RULE = re.compile(r"^(?:local)?rule (\S+):$")
_WILDCARDS = re.compile(r"^\s+wildcards: (.*)$")


def scheduled(dry_run_output: str) -> set[str]:
    """Jobs a dry run lists: ``rule`` and, for a job with wildcards, ``rule[name=value]`` per
    wildcard."""
    jobs: set[str] = set()
    rule = None
    for line in dry_run_output.splitlines():
        match = _RULE.match(line)
        if match:
            rule = match.group(1)
            jobs.add(rule)
            continue
        match = _WILDCARDS.match(line)
        if match and rule:
            for pair in match.group(1).split(", "):
                jobs.add(f"{rule}[{pair}]")
    return jobs - {"all"}


# Edited in place, not in a copy: Snakemake records the published-value files by absolute path,
# so in a copy the jobs reading them would be out of date before any edit.
@pytest.fixture(scope="module")
def builtin(reduced_run) -> FinishedRun:
    return reduced_run


@pytest.fixture(scope="module")
def extension(fourth_study_run) -> FinishedRun:
    return fourth_study_run


def _dry_run(finished_run: FinishedRun, *targets: str) -> set[str]:
    run = finished_run.snakemake(*targets, "--dry-run")
    assert run.returncode == 0, run.stdout[-4000:] + run.stderr[-4000:]
    if os.environ.get("JOINTBENCH_MUTATION_DEBUG"):
        print(run.stdout[-3000:], run.stderr[-3000:])
    return scheduled(run.stdout)


def _report(kind: str, jobs: set[str]) -> None:
    target = os.environ.get("JOINTBENCH_MUTATION_REPORT")
    if target:
        path = Path(target)
        report = json.loads(path.read_text()) if path.exists() else {}
        report[kind] = sorted(jobs)
        path.write_text(json.dumps(report, indent=1))


#: A time stamp older than every result: 1 January 2000.
LONG_AGO_NS = 946_684_800 * 10**9


def _edited(workdir: Path, path: str, text: str, backdated: bool = False):
    """Write ``text`` to ``path`` (dated :data:`LONG_AGO_NS` if ``backdated``); return a
    function that restores the file and its time."""
    target = workdir / path
    original, stat = target.read_text(), target.stat()

    def restore() -> None:
        target.write_text(original)
        os.utime(target, ns=(stat.st_atime_ns, stat.st_mtime_ns))

    target.write_text(text)
    if backdated:
        os.utime(target, ns=(LONG_AGO_NS, LONG_AGO_NS))
    return restore


def _check(kind: str, jobs: set[str], reruns, spares) -> None:
    _report(kind, jobs)
    missing = sorted(set(reruns) - jobs)
    assert not missing, f"{kind}: stale results, not rerun: {missing}; scheduled: {sorted(jobs)}"
    wasted = sorted(set(spares) & jobs)
    assert not wasted, f"{kind}: reran {wasted}, which the edit cannot change"


@pytest.mark.parametrize(
    "edit",
    [
        pytest.param(e, id=e.kind, marks=pytest.mark.xdist_group(SHARED_RUN[e.scenario]))
        for e in EDITS
    ],
)
def test_an_edit_reruns_what_it_can_change_and_nothing_else(request, tmp_path, edit):
    finished_run = request.getfixturevalue(edit.scenario)
    if edit.targets:
        # Made in a copy: the shared run stays as finished. The targets' jobs record the copy's
        # own files, so the copy is up to date for them.
        finished_run = finished_run.copy(tmp_path / "run")
        made = finished_run.snakemake(*edit.targets)
        assert made.returncode == 0, made.stderr[-4000:]
    text = (finished_run.workdir / edit.path).read_text()
    restore = _edited(finished_run.workdir, edit.path, edit.apply(text), edit.backdated)
    try:
        jobs = _dry_run(finished_run, *edit.targets)
    finally:
        restore()
    _check(edit.kind, jobs, edit.reruns, edit.spares)


@pytest.mark.parametrize("kind, change, reruns, spares, scenario", CONFIG_EDITS)
def test_a_config_edit_reruns_what_it_can_change_and_nothing_else(
    request, kind, change, reruns, spares, scenario
):
    finished_run = request.getfixturevalue(scenario)
    config = copy.deepcopy(finished_run.overlay)
    change(config)
    restore = _edited(finished_run.workdir, OVERLAY, yaml.safe_dump(config))
    try:
        jobs = _dry_run(finished_run)
    finally:
        restore()
    _check(kind, jobs, reruns, spares)


def test_the_dry_run_parser_reads_rules_and_wildcards():
    output = (
        "rule estimate_cmc:\n    input: a\n    wildcards: method=BC\n"
        "localrule check_published:\n    input: b\nrule all:\n"
    )
    assert scheduled(output) == {"estimate_cmc", "estimate_cmc[method=BC]", "check_published"}


@pytest.mark.parametrize("kind, change, reruns, spares, scenario", ORDER_EDITS)
def test_a_reordered_config_reruns_only_what_its_values_change(
    request, kind, change, reruns, spares, scenario
):
    finished_run = request.getfixturevalue(scenario)
    # The overlay in the order its file lists it, so that the edit's order is the only change.
    config = yaml.safe_load((finished_run.workdir / OVERLAY).read_text())
    change(config)
    restore = _edited(finished_run.workdir, OVERLAY, yaml.safe_dump(config, sort_keys=False))
    try:
        jobs = _dry_run(finished_run)
    finally:
        restore()
    if not reruns:
        assert not jobs, f"{kind}: reran {sorted(jobs)}, which the edit cannot change"
    _check(kind, jobs, reruns, spares)


# Started by every Python process of a run (beside the package, on ``PYTHONPATH``): in a job's,
# before the job imports anything, it saves an edit of a module the job runs, as a user saves
# one while a run goes on, after Snakemake has planned the job on the module as it was.
EDIT_IN_JOB = """
import sys
from pathlib import Path

if ".snakemake" in sys.argv[0] and Path({marker!r}).exists():
    Path({marker!r}).unlink()
    module = Path({module!r})
    module.write_text(module.read_text() + "\\n\\n_EDITED_WHILE_PLANNED = 1\\n")
"""


def test_a_job_whose_code_changed_after_planning_is_not_left_current(reduced_run, tmp_path):
    run = reduced_run.copy(tmp_path / "run")
    module = run.workdir / PKG / "papers" / "paper_a.py"
    planned = module.read_text()
    marker = tmp_path / "edit-once"
    marker.touch()
    hook = run.workdir / "src" / "sitecustomize.py"
    hook.write_text(EDIT_IN_JOB.format(marker=str(marker), module=str(module)))
    target = "results/tables/paper_a_claims.csv"
    try:
        made = run.snakemake(target, "--forcerun", "render_cmc")
    finally:
        hook.unlink()
    assert not marker.exists(), "the job did not start"
    ran = module.read_text()
    module.write_text(planned)  # the edit reverted: the code the run was planned on
    assert ran != planned
    # The job refuses to run code it was not planned on, as a failed job the run's closing
    # lines name, and is left to be made again.
    assert made.returncode != 0
    log = (run.workdir / "results" / "logs" / "render" / "cmc.log").read_text()
    assert "rule render_cmc: the code changed after the run planned this job" in log, log
    assert "jointbench: 1 job failed:\n  render_cmc: " in made.stderr, made.stderr[-3000:]
    assert "render_cmc" in _dry_run(run, target), "results of unrecorded code left current"
    assert (run.workdir / "results" / "collected" / "cmc.parquet").is_file(), "inputs lost"


# Python takes a module's cached bytecode as current by the source's size and modification
# second: an edit keeping both reruns the job (the fingerprint reads the source), which must then
# run the edited code, not the old bytecode.
def test_an_edit_that_keeps_size_and_time_reruns_on_the_edited_code(
    reduced_run, tmp_path, monkeypatch
):
    run = reduced_run.copy(tmp_path / "run")
    # Bytecode written as a user's Python writes it.
    monkeypatch.delenv("PYTHONDONTWRITEBYTECODE", raising=False)
    target = "results/tables/paper_b_claims.csv"
    made = run.snakemake(target, "--forcerun", "render_hinge")
    assert made.returncode == 0, made.stderr[-4000:]
    module = run.workdir / PKG / "papers" / "paper_b.py"
    old, new = "gap.max():.2f}°", "gap.max():.3f}°"
    stat = module.stat()
    module.write_text(module.read_text().replace(old, new, 1))
    os.utime(module, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    assert module.stat().st_size == stat.st_size
    assert "render_hinge" in _dry_run(run, target)
    made = run.snakemake(target)
    assert made.returncode == 0, made.stderr[-4000:]
    claims = (run.workdir / target).read_text()
    assert re.search(r"knee–MCP difference \d+\.\d\d\d°", claims), "the old code ran"


# Snakemake reruns a job whose code, settings or sources changed only by its record of the job
# that made the files (.snakemake/metadata). Without it (the folder deleted to clear a lock,
# results/ copied from another clone or a cluster) it took every file as current, so an edit
# left stale results and "Nothing to be done": such files are refused before any job.
@pytest.mark.xdist_group("reduced_run")
def test_results_snakemake_has_no_record_of_are_not_taken_as_current(reduced_run, tmp_path):
    run = reduced_run.copy(tmp_path / "run")
    records = run.workdir / ".snakemake" / "metadata"
    shutil.move(records, tmp_path / "records")
    edit = EDITS[0]  # an estimator's keyword default
    path = run.workdir / edit.path
    path.write_text(edit.apply(path.read_text()))
    planned = run.snakemake("--dry-run")
    message = planned.stdout + planned.stderr
    assert "Nothing to be done" not in message, "stale results taken as current"
    assert planned.returncode != 0, message[-3000:]
    assert "Snakemake has no record of" in message, message[-3000:]
    assert re.search(r"results/ holds \d+ files", message), message[-3000:]
    # Moved aside, they are made again from the edited code.
    shutil.move(run.workdir / "results", tmp_path / "old-results")
    assert "estimate_cmc" in _dry_run(run)


# Commands that run no job and take no result as current: listing the rules, and deleting the
# workflow's output, one of the ways out of results without a record. Refused, they left the
# deletion to a shell command alone and the rules unlisted.
@pytest.mark.xdist_group("reduced_run")
@pytest.mark.parametrize("command", ["--list-rules", "--list-target-rules", "--delete-all-output"])
def test_results_without_a_record_refuse_no_command_that_runs_no_job(
    reduced_run, tmp_path, command
):
    run = reduced_run.copy(tmp_path / "run")
    shutil.move(run.workdir / ".snakemake" / "metadata", tmp_path / "records")
    done = run.snakemake(command)
    message = done.stdout + done.stderr
    assert done.returncode == 0, message[-3000:]
    assert "Snakemake has no record of" not in message, message[-3000:]
    if command == "--delete-all-output":
        assert not list((run.workdir / "results" / "collected").glob("*.parquet"))
        assert "estimate_cmc" in _dry_run(run)
    else:
        assert "estimate_cmc" in message, message[-3000:]


# A run with --drop-metadata writes no record of the jobs it runs, and leaves each file it
# rewrites with the record of the job that made it before, which describes other code or
# settings: reverting them would then leave that file, made by neither, current. It is refused
# before any job, naming the option.
# Given in full, shortened as Snakemake's parser takes it, or in a profile, which the command
# line does not show.
@pytest.mark.xdist_group("reduced_run")
@pytest.mark.parametrize("given", ["--drop-metadata", "--drop-meta", "profile"])
def test_a_run_with_drop_metadata_is_refused_before_any_job(reduced_run, tmp_path, given):
    run = reduced_run.copy(tmp_path / "run")
    target = run.workdir / "results" / "tables" / "paper_a_claims.csv"
    before = target.stat().st_mtime_ns
    option = [given]
    if given == "profile":
        profile = tmp_path / "my profile"
        profile.mkdir()
        (profile / "config.yaml").write_text("drop-metadata: true\n")
        option = ["--profile", str(profile)]
    made = run.snakemake("results/tables/paper_a_claims.csv", "--forcerun", "render_cmc", *option)
    message = made.stdout + made.stderr
    assert made.returncode != 0, message[-3000:]
    assert "--drop-metadata" in message and "refused" in message, message[-3000:]
    if given != "profile":  # a profile's is seen once Snakemake hands its settings over
        assert "Building DAG of jobs" not in message, message[-3000:]
    assert "Finished job" not in message, message[-3000:]
    assert target.stat().st_mtime_ns == before


# Files Snakemake holds no record of (records lost, results/ copied, a run with --drop-metadata
# of an older version): the refusal lists them in a file and names the two ways out, each taken
# here as the message words it: recording them as they are (``--touch --force`` on the listed
# files), and deleting them, which makes them again.
@pytest.mark.xdist_group("reduced_run")
def test_unrecorded_results_are_refused_naming_the_ways_out_which_work(reduced_run, tmp_path):
    run = reduced_run.copy(tmp_path / "run")
    shutil.rmtree(run.workdir / ".snakemake" / "metadata")
    planned = run.snakemake("--dry-run")
    message = planned.stdout + planned.stderr
    assert planned.returncode != 0, message[-3000:]
    assert "--drop-metadata" in message, message[-3000:]
    listing = re.search(r"listed in (\S+):", message)
    assert listing, message[-3000:]
    assert "--touch --force $(cat " + listing.group(1) + ")" in message, message[-3000:]
    removal = "xargs -d '\\n' rm -- < .snakemake/jointbench/unrecorded.txt)"
    assert removal in message, message[-3000:]
    files = Path(listing.group(1)).read_text().splitlines()
    assert "results/tables/paper_a_claims.csv" in files, files
    # Recorded as they are: the next run plans again.
    recorded = run.copy(tmp_path / "recorded")
    touched = recorded.snakemake(*files, "--touch", "--force")
    assert touched.returncode == 0, (touched.stdout + touched.stderr)[-3000:]
    again = recorded.snakemake("--dry-run")
    assert again.returncode == 0, (again.stdout + again.stderr)[-3000:]
    # Deleted: made again.
    for name in files:
        (run.workdir / name).unlink()
    assert {"estimate_cmc", "render_cmc"} <= _dry_run(run)


# The ways out as the refusal words them, run by a shell in another folder than the run's, which
# a run given --directory leaves its user in, the run's folder's path holding a space: the list
# named where it is, its files where they are.
@pytest.mark.xdist_group("reduced_run")
def test_the_ways_out_of_unrecorded_results_work_as_worded_from_another_folder(
    reduced_run, tmp_path
):
    run = reduced_run.copy(tmp_path / "my run")
    shutil.rmtree(run.workdir / ".snakemake" / "metadata")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    planned = run.snakemake("--dry-run")
    message = planned.stdout + planned.stderr
    assert planned.returncode != 0, message[-3000:]
    touch = re.search(r"snakemake --touch --force (\$\(cat .+?\)), with this run", message)
    remove = re.search(r"which makes them anew: (.+?)\. Or, only", message)
    assert touch and remove, message[-3000:]
    listed = subprocess.run(
        ["bash", "-c", f"printf '%s\\n' {touch.group(1)}"],
        cwd=elsewhere,
        capture_output=True,
        text=True,
        check=False,
    )
    assert listed.returncode == 0, listed.stderr
    files = listed.stdout.splitlines()
    assert "results/tables/paper_a_claims.csv" in files, files
    removed = subprocess.run(
        ["bash", "-c", remove.group(1)], cwd=elsewhere, capture_output=True, text=True, check=False
    )
    assert removed.returncode == 0, removed.stderr
    assert not any((run.workdir / name).exists() for name in files), "not deleted"


# Python's site imports a sitecustomize (or usercustomize) module by name at start-up, from
# anywhere on the path: one of the user's own, beside the package, runs in every job before its
# script, and can change what each computes.
@pytest.mark.xdist_group("reduced_run")
def test_a_start_up_module_on_the_jobs_path_reruns_every_job_it_runs_in(reduced_run):
    hook = reduced_run.workdir / "src" / "sitecustomize.py"
    hook.write_text("import numpy\n\nnumpy.seterr(all='ignore')\n")
    try:
        jobs = _dry_run(reduced_run)
    finally:
        hook.unlink()
    _check("a start-up module on the jobs' path", jobs, DATA_JOBS | _jobs("collect"), NOTHING)
