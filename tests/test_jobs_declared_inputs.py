"""A workflow job reads published values only from its declared inputs.

The code fingerprint leaves the papers' published values to the inputs of the jobs that read
them, so a job reading one it does not declare would never be rerun by its edit. The job fails
instead, naming the rule and the file, the first time it runs.
"""

from __future__ import annotations

import os
from pathlib import Path
from types import SimpleNamespace

import pytest

from jointbench import jobs
from jointbench.comparison.published import load_published
from jointbench.papers import get_paper

PAPER_A = Path(get_paper("paper_a").published)
PAPER_B = Path(get_paper("paper_b").published)


def _job(*inputs) -> SimpleNamespace:
    """What a workflow script is given as ``snakemake``, for a rule declaring ``inputs``."""
    return SimpleNamespace(rule="render_cmc", input=list(inputs), output=[], log=[], config={})


def test_a_declared_file_is_read():
    with jobs.job(_job(PAPER_A)):
        assert load_published(PAPER_A)["paper"] == "A"


def test_an_undeclared_file_stops_the_job_naming_the_rule_and_the_file():
    with pytest.raises(ValueError) as error, jobs.job(_job(PAPER_A)):
        load_published(PAPER_B)
    message = str(error.value)
    assert message.startswith(f"rule render_cmc reads published values {PAPER_B} but does not")
    assert "would not rerun the job" in message and "published_files" in message


@pytest.mark.parametrize(
    "declared",
    [
        [[str(PAPER_B), str(PAPER_A)]],  # a named input holding a list
        [os.path.relpath(PAPER_A)],  # the same file by another path
    ],
    ids=["a list", "a relative path"],
)
def test_a_file_is_declared_however_the_rule_lists_it(declared):
    with jobs.job(_job(*declared)):
        load_published(str(PAPER_A))


def test_outside_a_job_and_after_one_any_file_is_read():
    load_published(PAPER_B)
    with pytest.raises(RuntimeError), jobs.job(_job(PAPER_A)):
        raise RuntimeError("the job's own failure")
    assert load_published(PAPER_B)["paper"] == "B"


@pytest.mark.pipeline
def test_a_rule_that_stops_declaring_its_published_values_fails_naming_them(reduced_run, tmp_path):
    """The workflow itself: the render rule, its published values dropped from its inputs,
    fails the first time it runs instead of making results no edit of them would rerun."""
    run = reduced_run.copy(tmp_path / "run")
    rules = run.workdir / "workflow" / "rules" / "render.smk"
    declared = "            published=published_files([_study]),\n"
    assert declared in rules.read_text()
    rules.write_text(rules.read_text().replace(declared, ""))
    done = run.snakemake("render_cmc", "--forcerun", "render_cmc")
    assert done.returncode != 0
    log = (run.workdir / "results" / "logs" / "render" / "cmc.log").read_text()
    assert "rule render_cmc reads published values" in log
    assert "paper_a.yaml but does not declare it as an input" in log
