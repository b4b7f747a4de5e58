"""An external estimator's rule file declares the kind of estimates it writes
(``external_estimator(name, kind=...)``); a study of another kind that lists it, or a rule
that declares none, stops the run before any job, naming the study, the estimator and both
kinds. Through the package's check and a real dry run."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from workflow_copy import ROOT, copy_workflow, run_snakemake

from jointbench.configuration import config as study_config


def _overlay(folder: Path, study: str, external: list[str]) -> str:
    """A config overlay running ``study`` alone, two trials of its first conditions, beside
    its first built-in estimator, with the ``external`` estimators."""
    defaults = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    studies = {name: {"enabled": False} for name in defaults["studies"] if name != study}
    settings = defaults["studies"][study]
    grid = {key: values[:1] for key, values in settings["grid"].items()}
    studies[study] = {
        "trials": 2,
        "grid": grid,
        "estimators": settings["estimators"][:1],
        "external_estimators": external,
    }
    path = folder / "overlay.yaml"
    path.write_text(yaml.safe_dump({"studies": studies}))
    return str(path)


def _dry_run(folder: Path, study: str, external: list[str]):
    folder.mkdir(exist_ok=True)
    copy_workflow(folder)
    overlay = _overlay(folder, study, external)
    run = run_snakemake(folder, "-n", "--configfile", overlay, timeout=300)
    return run.returncode, run.stdout + run.stderr


@pytest.mark.parametrize(
    ("study", "kind"), [("hinge", "axis"), ("hip", "joint_center"), ("hip_sta", "joint_center")]
)
@pytest.mark.parametrize("name", ["centroid", "LM", "LS-C"])
def test_a_centre_estimator_listed_by_a_study_of_another_kind_is_refused(name, study, kind):
    with pytest.raises(ValueError) as raised:
        study_config.check_external_kind(study, name, "center")
    message = str(raised.value)
    for word in (f"studies.{study}.external_estimators", repr(name), "center", kind, "cmc"):
        assert word in message, message


def test_an_estimator_of_its_studys_kind_passes():
    study_config.check_external_kind("cmc", "centroid", "center")
    study_config.check_external_kind("hinge", "mine", "axis")
    study_config.check_external_kind("hip_sta", "mine", "joint_center")


def test_a_rule_that_declares_no_kind_is_refused_saying_how():
    with pytest.raises(ValueError) as raised:
        study_config.check_external_kind("hinge", "mine", None)
    message = str(raised.value)
    assert "studies.hinge.external_estimators" in message and "'mine'" in message, message
    assert 'external_estimator("mine", kind="axis")' in message, message


@pytest.mark.parametrize("kind", ["centre", "", None, 3])
def test_a_kind_that_is_none_of_the_estimates_kinds_is_refused(kind):
    with pytest.raises(ValueError) as raised:
        study_config.external_kind("mine", kind, None)
    assert "'mine'" in str(raised.value) and "joint_center" in str(raised.value)


def test_a_name_declared_twice_with_two_kinds_is_refused():
    assert study_config.external_kind("mine", "axis", "axis") == "axis"
    with pytest.raises(ValueError) as raised:
        study_config.external_kind("mine", "axis", "center")
    assert "'mine'" in str(raised.value) and "center" in str(raised.value)


@pytest.mark.parametrize(("study", "kind"), [("hinge", "axis"), ("hip", "joint_center")])
def test_dry_run_refuses_the_centroid_template_under_a_study_of_another_kind(tmp_path, study, kind):
    code, message = _dry_run(tmp_path, study, ["centroid"])
    assert code != 0 and "Job stats" not in message, message[-3000:]
    for word in (f"studies.{study}.external_estimators", "'centroid'", "center", kind):
        assert word in message, message[-3000:]
    assert not (tmp_path / "results").exists()


def test_dry_run_refuses_a_rule_that_declares_no_kind(tmp_path):
    tmp_path.mkdir(exist_ok=True)
    copy_workflow(tmp_path)
    rule = tmp_path / "workflow" / "rules" / "estimators" / "centroid.smk"
    lines = rule.read_text().splitlines(keepends=True)
    rule.write_text("".join(line for line in lines if "external_estimator(" not in line))
    run = run_snakemake(
        tmp_path, "-n", "--configfile", _overlay(tmp_path, "cmc", ["centroid"]), timeout=300
    )
    message = run.stdout + run.stderr
    assert run.returncode != 0 and "Job stats" not in message, message[-3000:]
    assert 'external_estimator("centroid", kind="center")' in message, message[-3000:]


def test_dry_run_plans_the_shipped_external_estimators_on_a_centre_study(tmp_path):
    code, message = _dry_run(tmp_path, "cmc", ["centroid", "LM", "LS-C"])
    assert code == 0, message[-3000:]
    for rule in ("estimate_centroid", "estimate_cmc_LM", "estimate_LS_C"):
        assert rule in message, message[-3000:]
