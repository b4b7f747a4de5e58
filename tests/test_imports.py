"""What a workflow job imports: each loads what its own work needs, not the whole package.

Every job is a fresh interpreter, so what its script imports is paid once per job: matplotlib,
scipy.stats and the recording readers cost seconds of CPU between them. So is what the workflow
imports as it starts, once per ``snakemake`` invocation (every dry run). Each check runs in a
subprocess, which starts with nothing imported.
"""

from __future__ import annotations

import ast
import json
import re
import subprocess
import sys
import textwrap

import pytest
from workflow_copy import ROOT

import jointbench

SCRIPTS = ROOT / "workflow" / "scripts"
# Nothing at start-up needs these: figures import matplotlib when they draw, and the checks that
# read a distribution function import scipy.special when they test (jointbench.numerics.special).
NEVER = ("matplotlib", "mpl_toolkits", "scipy.stats", "scipy.special", "ezc3d", "jointbench.io")
# The jobs that simulate, fit poses, estimate, collect and summarise render and check nothing.
RUN_SIDE = (
    "simulate",
    "poses",
    "estimate",
    "collect",
    "summarise",
    "blind_dataset",
    "dataset_csv",
    "estimates_from_csv",
)
RENDER_SIDE = ("render", "check_published", "report_captions", "sensitivity_figures")
# The seed and protocol ensembles' jobs (`snakemake verdicts`, `snakemake sensitivity`): they
# run a study and judge its papers.
ENSEMBLE_SIDE = (
    "verdicts_member",
    "verdicts_summary",
    "sensitivity_member",
    "sensitivity_summary",
)
RENDERING = ("jointbench.figures", "jointbench.papers", "jointbench.pipeline", "jointbench.report")


def _run(code: str) -> str:
    """What ``code`` prints, run in a fresh interpreter."""
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT)
    assert run.returncode == 0, run.stderr[-3000:]
    return run.stdout


def _loaded(code: str) -> list[str]:
    """The modules loaded after running ``code`` in a fresh interpreter."""
    code += "\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))\n"
    return json.loads(_run(code).splitlines()[-1])


def _within(modules: list[str], packages: tuple[str, ...]) -> list[str]:
    return [m for m in modules if any(m == p or m.startswith(f"{p}.") for p in packages)]


def _script_imports(scripts: tuple[str, ...]) -> str:
    """The import statements of the named workflow scripts, as they are written there."""
    lines = []
    for name in scripts:
        tree = ast.parse((SCRIPTS / f"{name}.py").read_text())
        lines += [ast.unparse(n) for n in tree.body if isinstance(n, ast.Import | ast.ImportFrom)]
    assert lines, scripts
    return "\n".join(lines)


# An import statement at the top level of a Snakefile or rule file, over its lines.
_WORKFLOW_IMPORT = re.compile(r"^(?:from \S+ )?import (?:\([^)]*\)|.*)$", re.MULTILINE)


def _workflow_imports() -> str:
    """The import statements of the Snakefile and of every rule file it can include."""
    files = [ROOT / "Snakefile", *sorted((ROOT / "workflow" / "rules").rglob("*.smk"))]
    lines = [m.group(0) for path in files for m in _WORKFLOW_IMPORT.finditer(path.read_text())]
    assert any("jointbench" in line for line in lines), lines
    return "\n".join(lines)


def test_the_workflows_start_imports_nothing_only_a_job_needs():
    """What every ``snakemake`` invocation pays before it plans: the package's configuration,
    rules and fingerprints, never the drawing nor scipy.special."""
    loaded = _loaded(_workflow_imports())
    assert "jointbench.report" in loaded and "jointbench.running.run" in loaded
    assert not _within(loaded, NEVER), _within(loaded, NEVER)


def test_every_script_is_checked_here():
    assert {p.stem for p in SCRIPTS.glob("*.py")} == {*RUN_SIDE, *RENDER_SIDE, *ENSEMBLE_SIDE}


def test_ensemble_jobs_start_without_matplotlib_or_scipy_stats():
    loaded = _loaded(_script_imports(ENSEMBLE_SIDE))
    assert "jointbench.ensembles.members" in loaded and "jointbench.ensembles.verdicts" in loaded
    assert not _within(loaded, NEVER), _within(loaded, NEVER)


def test_simulate_estimate_collect_and_summarise_jobs_import_no_drawing_or_papers():
    loaded = _loaded(_script_imports(RUN_SIDE))
    assert "jointbench.jobs" in loaded and "jointbench.running.run" in loaded
    assert not _within(loaded, NEVER + RENDERING), _within(loaded, NEVER + RENDERING)


def test_render_and_check_jobs_start_without_matplotlib_or_scipy_stats():
    loaded = _loaded(_script_imports(RENDER_SIDE))
    assert "jointbench.pipeline" in loaded and "jointbench.report" in loaded
    assert not _within(loaded, NEVER), _within(loaded, NEVER)


def test_a_job_registers_the_study_and_paper_of_an_extension():
    """Loading extensions finds the paper registry through the extension that defines a paper."""
    folder = ROOT / "tests" / "data" / "fourth_study"
    code = textwrap.dedent(
        f"""
        from jointbench.configuration.extensions import load_extensions
        load_extensions({{"extensions": ["toy_study.py"]}}, base={str(folder)!r})
        from jointbench.papers import get_paper
        from jointbench.configuration.studies import get_study
        print(get_study("toy").name, get_paper("paper_t").key)
        """
    )
    assert _run(code).split() == ["toy", "paper_t"]


def test_a_table_job_never_imports_matplotlib_and_a_figure_job_does(tmp_path):
    collected, folder = tmp_path / "cmc.parquet", tmp_path / "extended"
    code = textwrap.dedent(
        f"""
        import sys
        import pandas as pd
        from jointbench import pipeline

        rows = [
            dict(marker_set="M", rom_deg=5, noise_mm=1.0, trial=t, method=m, error_mm=e,
                 converged=True, seconds=0.1)
            for m, e in (("NM", 1.0), ("a user's method", 2.0)) for t in range(2)
        ]
        pd.DataFrame(rows).to_parquet({str(collected)!r})
        outputs = {{ext: {str(folder)!r} + "." + ext for ext in ("csv", "md", "png")}}
        for what in ("table", "figure"):
            pipeline.render_extended("cmc", {str(collected)!r}, outputs, {{}}, what=what)
            print(what, "matplotlib" in sys.modules)
        """
    )
    assert _run(code).split() == ["table", "False", "figure", "True"]


def test_import_jointbench_loads_its_public_names_on_first_use():
    loaded = _loaded("import jointbench")
    assert not _within(loaded, ("jointbench.io", "jointbench.api", "ezc3d")), loaded
    loaded = _loaded("from jointbench import fit_center")
    assert "jointbench.api" in loaded and "jointbench.io" not in loaded


def test_the_public_names_are_those_of_their_modules():
    """``__all__``, the lazily imported names and the imports type checkers read agree."""
    tree = ast.parse((ROOT / "src" / "jointbench" / "__init__.py").read_text())
    (checking,) = [n for n in tree.body if isinstance(n, ast.If)]  # if TYPE_CHECKING:
    typed = {(n.module, a.name) for n in checking.body for a in n.names}
    assert typed == {(module, name) for name, module in jointbench._HOMES.items()}
    assert sorted(jointbench.__all__) == sorted(jointbench._HOMES)
    for name, module in jointbench._HOMES.items():
        assert getattr(jointbench, name) is getattr(sys.modules[module], name)
        assert name in dir(jointbench)
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        jointbench.nothing  # noqa: B018


def test_simulating_fitting_poses_and_estimating_never_import_pandas(tmp_path):
    """These are most of a run's jobs: pandas would double their start-up (Arrow's compute
    module adds a sixth of it). Every built-in
    estimator runs, on one condition of each study, through the functions the jobs call."""
    code = textwrap.dedent(
        f"""
        import sys
        from pathlib import Path
        from jointbench import jobs
        from jointbench.configuration import config as study_config
        from jointbench.running import run

        config = study_config.load_config({str(ROOT / "config" / "config.yaml")!r})
        folder = Path({str(tmp_path)!r})
        for study, settings in config["studies"].items():
            settings["trials"] = 3
            settings["grid"] = {{k: v[-1:] for k, v in settings["grid"].items()}}
            (condition,) = study_config.conditions(config, study)
            name = study_config.condition_id(condition) + ".parquet"
            dataset = str(folder / study / "datasets" / name)
            run.run_simulate_files(config, study, [dataset])
            poses = None
            if run.methods_sharing_poses(config, study):
                poses = [str(folder / study / "poses" / name)]
                run.run_poses_files(study, [dataset], poses)
            for method in study_config.estimator_names(config, study, source="builtin"):
                output = str(folder / study / method / name)
                shared = poses if method in run.methods_sharing_poses(config, study) else None
                run.run_estimate_files(config, study, method, [dataset], [output], poses=shared)
                print(study, method, Path(output).exists())
        print("pandas" in sys.modules, "pyarrow.compute" in sys.modules)
        """
    )
    printed = _run(code).splitlines()
    assert printed[-1] == "False False"
    assert len(printed) > 10 and all(line.endswith("True") for line in printed[:-1]), printed
