"""What every workflow job shares: its context (extensions loaded, messages and any error written
to the rule's log) and the provenance its files record.

Each script in ``workflow/scripts`` runs its work inside :func:`job`, calling the module that
does it: :mod:`jointbench.running.run` to simulate, estimate, collect and summarise,
:mod:`jointbench.pipeline` for paper outputs, the extended ranking and the published-value check,
:mod:`jointbench.report` for the report's texts. This module imports none of them, so that a job
loads only what its own work needs.

Every job loads the run's extensions (a study or paper outside the package, listed under
``extensions`` in the config; :mod:`jointbench.configuration.extensions`), as the Snakemake
process does, so the rules and the jobs see the same registries.

Every job then runs only the code the run planned it on (:func:`check_planned_code`): the
fingerprint it records is the one Snakemake computed when it planned the run, and a file saved
since would otherwise run unrecorded under it. On a cluster the node reads the workflow again
before it runs a job, so the run's plan reaches the job through the environment
(:func:`publish_planned_code`) rather than through its parameters. What this module imports
counts in every job's fingerprint, so that is the fingerprint's module and nothing of the
papers or the studies.
"""

from __future__ import annotations

import contextlib
import contextvars
import importlib.metadata
import json
import logging
import os
import sys
from collections.abc import Iterator
from pathlib import Path

from jointbench.configuration.extensions import load_extensions
from jointbench.fingerprint import code_fingerprint, dependency_versions

__all__ = [
    "PLANNED_CODE_VARIABLE",
    "check_planned_code",
    "job",
    "provenance",
    "publish_planned_code",
    "require_declared",
]

#: The environment variable through which the Snakemake that plans a run hands each rule's code
#: fingerprint down to its jobs: a JSON object, rule name -> fingerprint.
PLANNED_CODE_VARIABLE = "JOINTBENCH_PLANNED_CODE"

# The package's logger: every module's messages (``getLogger(__name__)``) reach the job's log
# through it.
log = logging.getLogger("jointbench")


@contextlib.contextmanager
def job(snakemake) -> Iterator[None]:
    """Run one Snakemake job's work: extensions loaded, the code checked against the planned
    (:func:`check_planned_code`), messages and any error written to the job's log (the file
    Snakemake points to when the job fails)."""
    handlers = []
    for path in list(snakemake.log):
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        handler = logging.FileHandler(path, mode="w")
        handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s"))
        handlers.append(handler)
        log.addHandler(handler)
    log.setLevel(logging.INFO)
    running = _RUNNING.set((snakemake.rule, _declared_inputs(snakemake.input)))
    try:
        load_extensions(snakemake.config)
        # Once the script's and the extensions' modules are loaded: an edit saved after this
        # check is not what the job runs (every module of the package imports at module level).
        check_planned_code(snakemake)
        log.info(
            "rule %s: %d input(s) -> %d output(s)",
            snakemake.rule,
            len(snakemake.input),
            len(snakemake.output),
        )
        yield
        log.info("done")
    except Exception:
        log.exception("rule %s failed", snakemake.rule)
        raise
    finally:
        _RUNNING.reset(running)
        for handler in handlers:
            log.removeHandler(handler)
            handler.close()


def check_planned_code(snakemake) -> None:
    """``ValueError`` naming the rule when the code this job runs is not the code Snakemake
    planned it on: the fingerprint its rule computed when the run started (``params.code``,
    ``script_code`` in ``workflow/rules/common.smk``) against the one computed now from the same
    arguments, the job's script, the run's extensions and the data files left out of the code
    (``params.code_plan["inputs"]``). A file saved while the run goes on would otherwise run
    under the planned fingerprint, and once reverted the results it made would read as current;
    a job in an environment of its own (a conda environment) would record the versions of the
    Snakemake process's, which the message names where they differ
    (``params.code_plan["versions"]``). A job whose rule states no fingerprint (a rule of the
    user's) is not checked. The planned fingerprint is the one handed down in the environment
    where there is one (:func:`_planned_code`): a node reading the workflow again computes
    ``params.code`` from the code as it finds it."""
    planned = _planned_code(snakemake)
    if planned is None:
        return
    plan = snakemake.params.code_plan
    script = Path(sys.modules["__main__"].__file__)
    extensions = [Path(entry).resolve() for entry in snakemake.config.get("extensions", [])]
    now = code_fingerprint(script, *extensions, inputs=plan["inputs"])
    if now != planned:
        raise ValueError(
            f"rule {snakemake.rule}: the code changed after the run planned this job (its "
            f"fingerprint was {planned}, it is {now} now) and would run unrecorded: "
            + _why_changed(plan["versions"], dependency_versions(), script.name)
        )


def publish_planned_code(codes: dict[str, str]) -> None:
    """Hand ``codes`` (rule name -> the code fingerprint the run planned its jobs on) down to
    every job this process starts, through the environment (:data:`PLANNED_CODE_VARIABLE`):
    a job on a cluster node runs in a Snakemake that reads the workflow again, whose own
    ``params.code`` would be the code as the node finds it. Called by the Snakemake that plans
    the run, not by the one a node starts (``plan_code_checks`` in
    ``workflow/rules/common.smk``)."""
    os.environ[PLANNED_CODE_VARIABLE] = json.dumps(codes, sort_keys=True)


def _planned_code(snakemake) -> str | None:
    """The code fingerprint the run planned ``snakemake``'s job on: the one handed down in the
    environment for its rule (:func:`publish_planned_code`), else its ``params.code`` (a job
    started without the plan: a cluster whose jobs do not inherit the environment, a rule the
    plan does not name); ``None`` for a rule that states none. ``ValueError`` naming the
    variable when it holds anything but a JSON object."""
    params = getattr(snakemake, "params", None)
    own = getattr(params, "code", None)
    if own is None:
        return None
    text = os.environ.get(PLANNED_CODE_VARIABLE)
    if text is None:
        return own
    try:
        codes = json.loads(text)
    except json.JSONDecodeError as error:
        raise ValueError(f"{PLANNED_CODE_VARIABLE} is not JSON ({error}): {text[:80]!r}") from None
    if not isinstance(codes, dict):
        raise ValueError(
            f"{PLANNED_CODE_VARIABLE} holds {type(codes).__name__}, not an object of rule "
            f"names and fingerprints: {text[:80]!r}"
        )
    return codes.get(snakemake.rule, own)


def _why_changed(planned: dict[str, str], now: dict[str, str], script: str) -> str:
    """What changed a job's fingerprint, running ``script``, since the planning, and what to
    do: the versions that differ between ``planned`` and ``now`` (:func:`_changed_versions`),
    else a file saved meanwhile."""
    versions = _changed_versions(planned, now)
    if versions:
        return (
            f"{versions} (this job's environment against Snakemake's); run snakemake from an "
            "environment with the versions its jobs run"
        )
    return (
        f"a module of the package, the script {script}, an extension or a module of your own "
        "was saved while the run went on; run snakemake again, which plans on the code as it is"
    )


def _changed_versions(planned: dict[str, str], now: dict[str, str]) -> str:
    """The entries of :func:`jointbench.fingerprint.dependency_versions` that differ between
    ``planned`` and ``now``, as ``name: planned when planned, now here`` (``numba_jit`` is
    there only when the compiler is off: ``on`` otherwise); empty when none does."""
    unset = {"numba_jit": "on"}
    names = sorted(name for name in {*planned, *now} if planned.get(name) != now.get(name))
    return "; ".join(
        f"{name}: {planned.get(name, unset.get(name))} when planned, "
        f"{now.get(name, unset.get(name))} here"
        for name in names
    )


#: The rule of the job running in this process and the files it declares as inputs, resolved;
#: ``None`` outside a job.
_RUNNING: contextvars.ContextVar[tuple[str, frozenset[Path]] | None] = contextvars.ContextVar(
    "running_job", default=None
)


def _declared_inputs(inputs) -> frozenset[Path]:
    """Every file of a job's ``snakemake.input``, resolved (a named input may be a list)."""
    flat = (
        path for entry in inputs for path in ([entry] if isinstance(entry, str | Path) else entry)
    )
    return frozenset(Path(path).resolve() for path in flat)


def require_declared(path: str | Path, what: str) -> None:
    """``ValueError`` when the workflow job running in this process reads ``path`` (``what`` it
    holds) without declaring it as an input. The code fingerprint leaves such files to the
    inputs of the jobs that read them (the papers' published values, so that one paper's
    values rerun only its study's jobs): read undeclared, an edit of the file would rerun
    nothing and leave the job's results stale. Outside a job, nothing is required."""
    running = _RUNNING.get()
    if running is None:
        return
    rule, declared = running
    if Path(path).resolve() not in declared:
        raise ValueError(
            f"rule {rule} reads {what} {path} but does not declare it as an input: an edit of "
            "the file would not rerun the job; add it to the rule's input "
            "(published_files in workflow/rules/common.smk)"
        )


def provenance(snakemake) -> dict[str, object]:
    """What a job's files record of how they were made: the package version, the rule, the
    fingerprint of the code it ran (the planned one, :func:`check_planned_code`), and the
    config values its study depends on."""
    study = getattr(snakemake.params, "study", None) or snakemake.wildcards.get("study")
    settings = snakemake.config.get("studies", {}).get(study, {}) if study else {}
    return {
        "jointbench": importlib.metadata.version("jointbench"),
        "rule": snakemake.rule,
        "code": _planned_code(snakemake) or "",
        "config": {"base_seed": snakemake.config.get("base_seed"), "study": settings},
    }
