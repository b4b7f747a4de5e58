"""A fourth study with its own paper, added from outside the package in three files.

The files are ``tests/data/fourth_study/``: ``toy_study.py`` (the study's simulator and its
paper: one figure, two published values), ``paper_t.yaml`` (the published values with typed
tolerances, one recorded deviation) and ``toy.yaml`` (the config overlay naming the module under
``extensions``). Nothing in the package or the workflow is edited.
"""

from __future__ import annotations

import shutil
import subprocess

import pandas as pd
import pytest
from workflow_copy import ROOT, SNAKEMAKE, copy_workflow

pytestmark = pytest.mark.pipeline

FILES = ("toy_study.py", "paper_t.yaml", "toy.yaml")
# The README's way to run the example from a clone's root, its overlay and its command.
README_OVERLAY = "extensions: [tests/data/fourth_study/toy_study.py]"
README_COMMAND = "snakemake -j2 --configfile tests/data/fourth_study/toy.yaml fourth.yaml"


@pytest.fixture(scope="module")
def toy_run(fourth_study_run):
    """The session's finished run of the three files (``tests/conftest.py``), read only."""
    return fourth_study_run.workdir


def test_the_extension_needs_at_most_five_files():
    assert len(FILES) <= 5


def test_the_toy_study_runs_and_draws_its_figure(toy_run):
    results = toy_run / "results"
    collected = pd.read_parquet(results / "collected" / "toy.parquet")
    assert set(collected["method"]) == {"NM", "LS", "toy-centroid"}
    assert len(collected) == 3 * 2 * 4
    assert (results / "figures" / "paper_t_errors.png").stat().st_size > 1000
    assert (results / "tables" / "extended_toy.csv").exists()
    assert (results / "report" / "captions" / "paper_t_errors.rst").exists()


def test_its_published_values_are_checked(toy_run):
    comparison = pd.read_csv(toy_run / "results" / "tables" / "published_comparison.csv")
    rows = comparison.set_index("id")
    assert rows.loc["T1", "status"] == "reproduced"
    assert rows.loc["T2", "status"] == "not reproduced"
    assert "biased by noise" in rows.loc["T2", "reason"]
    assert set(comparison["study"]) == {"toy"}


def test_its_figure_is_in_the_report(fourth_study_run, tmp_path):
    # Written outside the run, which stays as finished (and up to date: a copy is not).
    report = fourth_study_run.snakemake("--report", str(tmp_path / "report.html"))
    assert report.returncode == 0, report.stderr[-4000:]
    html = (tmp_path / "report.html").read_text(errors="replace")
    for name in ("paper_t_errors.png", "published_comparison.html", "extended_toy.png"):
        assert name in html, f"{name} missing from the report"


def test_the_readmes_command_runs_the_example_from_a_clones_root(tmp_path):
    """A path under ``extensions`` is the working directory's, not the listing file's: the
    README's overlay names the module by its path from the root, and its command plans."""
    readme = (ROOT / "README.md").read_text()
    assert README_OVERLAY in readme and README_COMMAND in readme
    copy_workflow(tmp_path)
    example = tmp_path / "tests" / "data" / "fourth_study"
    shutil.copytree(ROOT / "tests" / "data" / "fourth_study", example)
    (tmp_path / "fourth.yaml").write_text(README_OVERLAY + "\n")
    command = [str(SNAKEMAKE), *README_COMMAND.split()[1:], "--dry-run"]
    run = subprocess.run(command, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "estimate_toy" in run.stdout and "render_toy" in run.stdout
