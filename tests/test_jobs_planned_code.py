"""A workflow job runs only the code the run planned it on.

Snakemake fingerprints each job's code when it plans the run (``params.code``,
``script_code`` in ``workflow/rules/common.smk``) and the job records that fingerprint. A file
saved meanwhile would run under it unrecorded, so the job computes the fingerprint again from
the same arguments (its script, the run's extensions, the data files ``params.code_plan``
names) once its modules are loaded, and refuses to run code other than the planned, naming
the versions that differ from the planned ones (``params.code_plan``'s too).
``tests/test_stale_results.py`` does the same through Snakemake.

On a cluster the node runs each job through a Snakemake that reads the workflow again, so its
``params.code`` is the code as the node found it, not as the run planned it: the submitting
Snakemake hands its plan down in the environment (``jobs.PLANNED_CODE_VARIABLE``), which the
job checks against instead.
"""

from __future__ import annotations

import json
import os
import shutil
import sys
from pathlib import Path
from types import SimpleNamespace

import pytest

from jointbench import fingerprint, jobs
from jointbench.fingerprint import code_fingerprint, data_closure, data_names, module_closure
from jointbench.papers import get_paper, paper_names

SCRIPTS = Path(__file__).resolve().parents[1] / "workflow" / "scripts"
# What the workflow leaves out of the code: every paper's published values (common.smk).
CODE_INPUTS = data_names(get_paper(name).published for name in paper_names())


@pytest.fixture
def script(tmp_path, monkeypatch) -> Path:
    """A copy of the render script, as the one this process runs (Snakemake sets ``__file__``
    of the job's ``__main__`` to the script's path)."""
    path = tmp_path / "render.py"
    shutil.copy(SCRIPTS / "render.py", path)
    monkeypatch.setitem(sys.modules, "__main__", SimpleNamespace(__file__=str(path)))
    # A plan handed down by a Snakemake that started this test process is not this test's.
    monkeypatch.delenv(jobs.PLANNED_CODE_VARIABLE, raising=False)
    return path


def _job(code: str, config: dict | None = None, versions: dict | None = None) -> SimpleNamespace:
    """What a workflow script is given as ``snakemake``, for a rule planned on ``code`` under
    ``versions`` (by default those of this process)."""
    plan = {"inputs": CODE_INPUTS, "versions": versions or fingerprint.dependency_versions()}
    return SimpleNamespace(
        rule="render_cmc",
        input=[],
        output=[],
        log=[],
        config=config or {},
        params=SimpleNamespace(code=code, code_plan=plan),
    )


def test_a_job_planned_on_the_code_it_runs_runs(script):
    ran = False
    with jobs.job(_job(code_fingerprint(script, inputs=CODE_INPUTS))):
        ran = True
    assert ran


def test_a_job_whose_script_changed_after_planning_is_refused_naming_the_rule(script):
    planned = code_fingerprint(script, inputs=CODE_INPUTS)
    script.write_text(script.read_text() + "\nEDITED = 1\n")
    with pytest.raises(ValueError) as error, jobs.job(_job(planned)):
        pytest.fail("the job ran code other than the planned")
    message = str(error.value)
    assert message.startswith("rule render_cmc: the code changed after the run planned this job")
    assert planned in message and code_fingerprint(script, inputs=CODE_INPUTS) in message


def test_a_job_planned_anew_by_its_node_is_checked_against_the_runs_plan(script, monkeypatch):
    """A file saved after the run planned the job but before the node read the workflow again:
    the node's ``params.code`` is the edited code's, which the job runs; the plan handed down
    by the submitting Snakemake is not, and the job is refused."""
    planned = code_fingerprint(script, inputs=CODE_INPUTS)
    script.write_text(script.read_text() + "\nEDITED = 1\n")
    on_node = code_fingerprint(script, inputs=CODE_INPUTS)
    monkeypatch.setenv(jobs.PLANNED_CODE_VARIABLE, "{}")
    jobs.publish_planned_code({"render_cmc": planned, "collect": "0123456789abcdef"})
    with pytest.raises(ValueError) as error, jobs.job(_job(on_node)):
        pytest.fail("the job ran code other than the run planned")
    message = str(error.value)
    assert message.startswith("rule render_cmc: the code changed after the run planned this job")
    assert f"its fingerprint was {planned}, it is {on_node} now" in message


def test_a_job_runs_and_records_the_runs_plan_when_its_node_found_the_same_code(
    script, monkeypatch
):
    """The plan handed down names the code the job runs: it runs, and its files record that
    fingerprint, whatever the node's reading of the workflow found."""
    planned = code_fingerprint(script, inputs=CODE_INPUTS)
    monkeypatch.setenv(jobs.PLANNED_CODE_VARIABLE, json.dumps({"render_cmc": planned}))
    snakemake = _job("fedcba9876543210")
    snakemake.wildcards = {}
    with jobs.job(snakemake):
        recorded = jobs.provenance(snakemake)["code"]
    assert recorded == planned


def test_a_rule_the_handed_down_plan_does_not_name_is_checked_against_its_own(script, monkeypatch):
    """A plan from another workflow's Snakemake (a job that starts one of its own) names other
    rules: the job's own ``params.code`` is its plan."""
    monkeypatch.setenv(jobs.PLANNED_CODE_VARIABLE, json.dumps({"other": "0123456789abcdef"}))
    ran = False
    with jobs.job(_job(code_fingerprint(script, inputs=CODE_INPUTS))):
        ran = True
    assert ran


@pytest.mark.parametrize("text", ["[1, 2]", "render_cmc=0123"])
def test_a_plan_handed_down_that_is_not_a_mapping_of_rules_is_named(script, monkeypatch, text):
    monkeypatch.setenv(jobs.PLANNED_CODE_VARIABLE, text)
    with pytest.raises(ValueError, match=jobs.PLANNED_CODE_VARIABLE):
        with jobs.job(_job(code_fingerprint(script, inputs=CODE_INPUTS))):
            pytest.fail("the job ran on a plan it could not read")


def test_publishing_the_plan_leaves_it_in_this_process_environment(monkeypatch):
    monkeypatch.setenv(jobs.PLANNED_CODE_VARIABLE, "{}")
    jobs.publish_planned_code({"collect": "0123456789abcdef"})
    assert json.loads(os.environ[jobs.PLANNED_CODE_VARIABLE]) == {"collect": "0123456789abcdef"}


def test_a_job_of_an_extension_the_run_did_not_plan_on_is_refused(script, tmp_path):
    """The run's extensions are part of the planned code: a job that would load another
    extension's code than the one planned is refused too."""
    extension = tmp_path / "lab_study.py"
    extension.write_text("SCALE = 1.0\n")
    config = {"extensions": [str(extension)]}
    planned = code_fingerprint(script, extension, inputs=CODE_INPUTS)
    extension.write_text("SCALE = 2.0\n")
    with pytest.raises(ValueError, match="rule render_cmc: the code changed"):
        with jobs.job(_job(planned, config)):
            pytest.fail("the job ran code other than the planned")


def test_the_published_values_stay_out_of_the_code_as_planned(script):
    """Left out by their names in the package: the job finds them wherever the package is."""
    assert "papers/paper_a.yaml" in CODE_INPUTS
    assert all(not Path(name).is_absolute() for name in CODE_INPUTS)
    assert "papers/paper_a.yaml" in data_closure(script)
    assert code_fingerprint(script, inputs=CODE_INPUTS) != code_fingerprint(script)


def test_the_check_adds_no_module_of_the_package_to_the_jobs_code_but_the_fingerprints():
    """Every job imports ``jointbench.jobs``: what the check imports counts for every job, so
    it reaches the fingerprint's module and none of the package's registries or lazy names."""
    estimate = set(module_closure(SCRIPTS / "estimate.py"))
    assert "jointbench.fingerprint" in estimate
    for module in ("jointbench.papers", "jointbench.api", "jointbench.io", "jointbench.figures"):
        assert module not in estimate


@pytest.mark.parametrize(
    "value, counts", [("1", True), ("0", False), ("", False)], ids=["1", "0", "empty"]
)
def test_numbas_jit_switched_off_is_part_of_the_fingerprint(monkeypatch, value, counts):
    """``NUMBA_DISABLE_JIT`` runs the kernels as Python, whose results differ from the compiled
    ones in the last bits: a run under it is another run, and a job planned without it is
    refused under it."""
    estimate = SCRIPTS / "estimate.py"
    monkeypatch.delenv("NUMBA_DISABLE_JIT", raising=False)
    compiled = code_fingerprint(estimate)
    monkeypatch.setenv("NUMBA_DISABLE_JIT", value)
    assert (code_fingerprint(estimate) != compiled) is counts
    assert ("numba_jit" in fingerprint.dependency_versions()) is counts


def test_a_job_planned_with_the_jit_and_run_without_it_is_refused_naming_it(script, monkeypatch):
    monkeypatch.delenv("NUMBA_DISABLE_JIT", raising=False)
    job = _job(code_fingerprint(script, inputs=CODE_INPUTS))
    monkeypatch.setenv("NUMBA_DISABLE_JIT", "1")
    with pytest.raises(ValueError, match="rule render_cmc: the code changed") as error:
        with jobs.job(job):
            pytest.fail("the job ran code other than the planned")
    assert "numba_jit: on when planned, disabled here" in str(error.value)


def test_a_job_planned_under_other_versions_is_refused_naming_them(script):
    """A job run in another environment than Snakemake's (a conda environment of its own)
    records the versions Snakemake planned it under, not those it ran."""
    versions = fingerprint.dependency_versions()
    planned = {**versions, "numpy": "1.0.0"}
    job = _job(code_fingerprint(script, inputs=CODE_INPUTS) + "0", versions=planned)
    with pytest.raises(ValueError, match="rule render_cmc: the code changed") as error:
        with jobs.job(job):
            pytest.fail("the job ran code other than the planned")
    message = str(error.value)
    assert f"numpy: 1.0.0 when planned, {versions['numpy']} here" in message
    assert "python:" not in message


@pytest.mark.parametrize(
    "setting, environment, counts",
    [
        ("disable_jit: 1\n", None, True),
        ("disable_jit: 1\n", "0", False),
        ("other: 1\n", None, False),
        ("DISABLE_JIT: 1\n", None, True),
        ("disable_jit: 1\nDisable_Jit: 0\n", None, False),
    ],
    ids=["the file", "the variable over the file", "another key", "upper case", "the last key"],
)
def test_numbas_config_file_switches_the_jit_off_as_numba_reads_it(
    tmp_path, monkeypatch, setting, environment, counts
):
    """Numba also reads ``.numba_config.yaml`` of the working directory, keys without the
    ``NUMBA_`` prefix in any case (the last of one name counts); its environment variable
    wins."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("NUMBA_DISABLE_JIT", raising=False)
    if environment is not None:
        monkeypatch.setenv("NUMBA_DISABLE_JIT", environment)
    (tmp_path / ".numba_config.yaml").write_text(setting)
    assert fingerprint.numba_jit_disabled() is counts
