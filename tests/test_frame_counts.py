"""A condition's frame count, which the config's check holds against the fewest frames every
listed estimator fits, read from the study's protocol where the study says how
(:attr:`~jointbench.simulate.Study.frame_count`), without simulating a trial; a study that does
not say (one from outside the package) has one trial of each condition simulated."""

from __future__ import annotations

import copy
import dataclasses
import os
import subprocess
import sys

import numpy as np
import pytest
import yaml
from snakemake.utils import update_config
from workflow_copy import ROOT

from jointbench.configuration import config as study_config
from jointbench.configuration.studies import get_study, study_names
from jointbench.estimators.batching import ProgrammingError
from jointbench.running import run

FOURTH = ROOT / "tests" / "data" / "fourth_study"


def _default() -> dict:
    return study_config.load_config(ROOT / "config" / "config.yaml")


def _reduced() -> dict:
    merged = copy.deepcopy(_default())
    # Merged as `--configfile` merges an overlay: key by key, at every depth.
    update_config(merged, yaml.safe_load((ROOT / "tests" / "data" / "reduced.yaml").read_text()))
    return merged


def _fourth() -> dict:
    paths = [ROOT / "config" / "config.yaml", FOURTH / "toy.yaml"]
    return dict(study_config.open_config(study_config.read_configs(paths), FOURTH))


CONFIGS = {"default": _default, "reduced": _reduced, "fourth study": _fourth}


def _simulated_frames(spec, protocol, condition) -> int:
    trials = spec.simulate(condition, protocol, [np.random.default_rng(0)])
    return trials.segments[spec.segments[0]].shape[1]


@pytest.mark.parametrize("study", study_names())
def test_every_study_of_the_package_declares_its_frame_count(study):
    """So that its config's check simulates nothing (a frame count typed a few digits too long
    is refused, not simulated: tests/test_config_validation.py); the count is checked against
    the simulator's below."""
    assert get_study(study).frame_count is not None


@pytest.mark.parametrize("name", CONFIGS)
def test_a_declared_frame_count_is_the_simulated_trials(name, forget_registrations):
    config = CONFIGS[name]()
    for study in study_config.study_names(config):
        spec, settings = get_study(study), config["studies"][study]
        protocol = spec.protocol(settings.get("protocol"))
        for condition in study_config.conditions(config, study):
            simulated = _simulated_frames(spec, protocol, condition)
            counted = study_config.trial_frames(spec, protocol, settings.get("protocol"), condition)
            assert counted == simulated, (study, condition)


def test_the_sta_study_declares_its_frame_count_and_an_outside_study_need_not(
    forget_registrations,
):
    assert get_study("hip_sta").frame_count is not None
    _fourth()
    assert get_study("toy").frame_count is None


def test_checking_the_default_config_runs_no_compiled_kernel():
    """The STA study's trials are fitted by a compiled kernel (their pelvis poses), which the
    frame count of a protocol does not need: checking the config loads no compiler."""
    code = (
        "import sys\n"
        "from jointbench.configuration import config\n"
        "config.load_config('config/config.yaml')\n"
        "assert 'numba' not in sys.modules, 'numba imported'\n"
    )
    checked = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, env=os.environ
    )
    assert checked.returncode == 0, checked.stderr[-2000:]


def test_a_study_whose_trials_miss_its_declared_frame_count_is_refused_when_simulated(monkeypatch):
    """The config's check trusts a declared count without simulating: a study whose simulator
    gives other frames than it declares is a mistake in the study, refused where its trials
    are simulated, naming the study, the condition and both counts."""
    config = _reduced()
    condition = study_config.conditions(config, "hip_sta")[0]
    wrong = dataclasses.replace(
        get_study("hip_sta"), frame_count=lambda condition, protocol: protocol.n_frames + 1
    )
    monkeypatch.setattr(run, "get_study", lambda name: wrong)
    with pytest.raises(ProgrammingError, match=r"hip_sta.*motion-.*declares \d+ frames.*\d+"):
        run.simulate_condition(config, "hip_sta", condition, range(1))
