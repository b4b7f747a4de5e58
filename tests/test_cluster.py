"""The SLURM profile, the conda environment and the helpers of the cluster and scaling benchmarks.

Fast checks only; the end-to-end proof on a real SLURM is benchmarks/slurm_single_node.sh.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from workflow_copy import ROOT, SNAKEMAKE, copy_workflow, load_benchmark

PROFILE = ROOT / "profiles" / "slurm" / "config.v8+.yaml"
ENVIRONMENT = ROOT / "workflow" / "envs" / "jointbench.yaml"


compare_collected = load_benchmark("compare_collected")
scaling = load_benchmark("scaling")


@pytest.fixture(scope="module")
def profile():
    return yaml.safe_load(PROFILE.read_text())


@pytest.fixture(scope="module")
def workflow_rules(tmp_path_factory):
    """Every rule name of the workflow under the default config."""
    workdir = copy_workflow(tmp_path_factory.mktemp("workflow"))
    listed = subprocess.run(
        [
            str(SNAKEMAKE),
            "--list-rules",
            "--directory",
            str(workdir),
            "-s",
            str(workdir / "Snakefile"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert listed.returncode == 0, listed.stderr[-2000:]
    return set(listed.stdout.split())


def test_profile_runs_on_slurm_with_memory_and_runtime_for_every_job(profile):
    assert profile["executor"] == "slurm"
    # Without mem_mb a job holds the whole node's memory under CR_Core_Memory.
    assert {"mem_mb", "runtime"} <= set(profile["default-resources"])
    for rule, resources in profile["set-resources"].items():
        assert {"mem_mb", "runtime"} <= set(resources), rule
        assert resources["mem_mb"] > 0 and resources["runtime"] > 0, rule


def test_profile_names_only_rules_that_exist(profile, workflow_rules):
    named = set(profile["set-resources"]) | set(profile["set-threads"])
    assert named <= workflow_rules, f"profile names unknown rules: {sorted(named - workflow_rules)}"


def test_snakemake_reads_the_profile_as_command_line_options():
    from snakemake.profiles import ProfileConfigFileParser

    with PROFILE.open() as stream:
        options = ProfileConfigFileParser().parse(stream)
    assert "estimate_hip:mem_mb=" in " ".join(options["set-resources"])
    assert any(item.startswith("mem_mb=") for item in options["default-resources"])


def test_conda_environment_has_every_runtime_dependency():
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    # Jobs import Snakemake from the main process's installation; conda names matplotlib's
    # headless package matplotlib-base.
    needed = {_name(d) for d in project["dependencies"]} - {"snakemake"}
    listed = {_name(d) for d in yaml.safe_load(ENVIRONMENT.read_text())["dependencies"]}
    listed = {"matplotlib" if name == "matplotlib-base" else name for name in listed}
    assert needed <= listed, f"missing from {ENVIRONMENT.name}: {sorted(needed - listed)}"
    assert os.access(ENVIRONMENT.with_name("jointbench.post-deploy.sh"), os.X_OK)


def _name(requirement: str) -> str:
    for separator in "<>=! ":
        requirement = requirement.split(separator)[0]
    return requirement.strip().lower()


def _collected(**changes) -> pd.DataFrame:
    frame = pd.DataFrame(
        {
            "method": ["LS", "NM", "BC"],
            "trial": [0, 1, 2],
            "error_mm": [0.5, np.nan, 1.25],
            "converged": [True, False, True],
            "status": ["ok", None, "ok"],
            "seconds": [1e-4, 2e-4, 3e-4],
        }
    )
    for column, values in changes.items():
        frame[column] = values
    return frame


def test_equal_collected_tables_agree_whatever_their_timings():
    slower = _collected(seconds=[1.0, 2.0, 3.0])
    assert compare_collected.compare_frames(_collected(), slower) == []


def test_collected_tables_differing_beyond_tolerance_are_named():
    shifted = _collected(error_mm=[0.5, np.nan, 1.25 + 1e-9])
    problems = compare_collected.compare_frames(_collected(), shifted, atol=1e-12)
    assert len(problems) == 1 and problems[0].startswith("error_mm: 1 values differ")
    assert compare_collected.compare_frames(_collected(), shifted, atol=1e-8) == []


def test_collected_tables_with_other_values_or_missing_places_differ():
    assert compare_collected.compare_frames(_collected(), _collected(status=["ok", "x", "ok"]))
    assert compare_collected.compare_frames(_collected(), _collected(error_mm=[0.5, 1.0, 1.25]))
    assert compare_collected.compare_frames(_collected(), _collected().iloc[:2])


def test_probe_records_the_cost_of_a_python_process(tmp_path):
    environment = {
        **os.environ,
        "PYTHONPATH": str(ROOT / "benchmarks" / "probe"),
        "JOINTBENCH_RUSAGE_DIR": str(tmp_path),
    }
    # Touch 200 MB so that the peak is clearly the program's own.
    program = "import numpy as np; np.ones(25_000_000).sum()"
    subprocess.run([sys.executable, "-c", program], env=environment, check=True, timeout=60)
    (record,) = [json.loads(path.read_text()) for path in tmp_path.glob("*.json")]
    assert record["rule"] is None and record["argv"] == ["-c"]
    assert record["peak_rss_mb"] > 190
    assert record["cpu_s"] > 0 and record["wall_s"] >= record["cpu_s"] * 0.5


def _record(argv, rule=None, wildcards=None, cpu=1.0, children_cpu=0.0, rss=100.0, start=0.0):
    return {
        "argv": argv,
        "rule": rule,
        "wildcards": wildcards or {},
        "start": start,
        "wall_s": 2.0,
        "cpu_s": cpu,
        "children_cpu_s": children_cpu,
        "peak_rss_mb": rss,
        "children_peak_rss_mb": 0.0,
    }


def test_scaling_names_each_process_by_its_job():
    records = [
        _record(["/venv/bin/snakemake", "study_cmc"], cpu=3.0, children_cpu=40.0, start=0),
        _record(["tmp.estimate.py"], "estimate_cmc", {"method": "NM"}, cpu=5.0, start=1),
        _record(["workflow/external/lm_sphere.py", "in.parquet", "out/M__5.parquet"], start=2),
    ]
    table = scaling.job_table(records)
    assert list(table["rule"]) == [scaling.SCHEDULER, "estimate_cmc", "lm_sphere.py"]
    assert list(table["job"]) == ["", "NM", "M__5"]
    # The scheduler's children are the jobs: counted on their own rows, not twice.
    assert table["cpu_s"].iloc[0] == 3.0
    assert scaling.total_cpu(records) == 43.0


def test_scaling_growth_is_relative_to_the_first_factor():
    tables = {
        1: scaling.job_table([_record(["s.py"], "estimate_cmc", {"method": "NM"}, cpu=2.0)]),
        10: scaling.job_table([_record(["s.py"], "estimate_cmc", {"method": "NM"}, cpu=5.0)]),
    }
    growth = scaling.rule_growth(tables)
    assert growth.loc["estimate_cmc", ("cpu_ratio", 10)] == 2.5


def test_scaling_runs_copies_with_the_repositorys_own_profile(tmp_path):
    # As the cluster check's runs: Snakemake applies profiles/default (keep-going) in a clone,
    # and a copy without it is not the run whose cost the benchmark states.
    workdir = scaling.workflow_clone(tmp_path / "x1")
    assert workdir.parent == tmp_path / "x1"
    for path in ("Snakefile", "config/config.yaml"):
        assert (workdir / path).is_file(), path
    assert (workdir / "workflow" / "rules").is_dir()
    assert (workdir / "profiles" / "default" / "config.yaml").is_file()
    assert not (workdir / "results").exists()


def test_scaling_reduces_the_grid_from_the_chosen_factor():
    scales = scaling.scales("cmc", [1, 10, 100], reduce_from=100)
    base = scaling.study_config("cmc")["trials"]
    assert [s.trials for s in scales] == [base, 10 * base, 100 * base]
    assert scales[0].grid is None and scales[2].grid == scaling.reduced_grid("cmc")


def test_the_reduced_config_shrinks_every_study_of_the_config():
    # A study it leaves out runs its full grid and trials in the cluster check and in
    # scaling.py's reduced factors: most of the jobs, and an error for that study.
    full = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())["studies"]
    reduced = yaml.safe_load(scaling.REDUCED.read_text())["studies"]
    for study, block in full.items():
        grid = scaling.reduced_grid(study)
        assert reduced[study]["trials"] < block["trials"], study
        assert scaling.Scale(1, 1, grid).conditions({}) < scaling.Scale(1, 1, None).conditions(
            block["grid"]
        ), study


def _cluster_check_steps(program: str, work) -> str:
    """What ``program`` prints, run by bash after sourcing benchmarks/slurm_single_node.sh
    (sourced, the script only defines its steps) with ``work`` as its work folder."""
    script = ROOT / "benchmarks" / "slurm_single_node.sh"
    environment = {**os.environ, "SLURM_CHECK_DIR": str(work)}
    printed = subprocess.run(
        ["bash", "-c", f"source {script}\n{program}"],
        env=environment,
        capture_output=True,
        text=True,
        timeout=30,
    )
    assert printed.returncode == 0, printed.stderr
    return printed.stdout


def test_the_cluster_check_keeps_the_daemons_files_out_of_both_runs(tmp_path):
    # Copying stands in for each run: this prints where each run's workflow copy goes and
    # where the daemons keep state and logs.
    printed = _cluster_check_steps(
        'echo "daemons $STATE"\n'
        'copy_workflow() { echo "run $1"; exit 0; }\n'
        "(run_local)\n"
        "(run_slurm)\n",
        tmp_path,
    )
    folders = [line.split(" ", 1) for line in printed.splitlines()]
    (daemons,) = [Path(path) for kind, path in folders if kind == "daemons"]
    runs = [Path(path) for kind, path in folders if kind == "run"]
    assert len(runs) == 2 and runs[0] != runs[1], printed
    for run in runs:
        assert not daemons.is_relative_to(run) and not run.is_relative_to(daemons), run


def test_the_cluster_check_runs_copies_with_the_repositorys_own_profile(tmp_path):
    # Snakemake applies profiles/default (keep-going: a failed job fails alone) under
    # --profile profiles/slurm too: a copy without it is not the run a user's clone makes.
    _cluster_check_steps(f"copy_workflow {tmp_path / 'run'}", tmp_path)
    assert (tmp_path / "run" / "profiles" / "default" / "config.yaml").is_file()
