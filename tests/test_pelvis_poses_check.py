"""A skin-marker hip protocol whose pelvis cluster cannot determine its poses is refused before
any job, naming the keys and the numbers.

The simulate job fits the pelvis poses of every trial (paper C §5) and refuses a trial whose fit
stops before converging (:func:`jointbench.simulate.hip_sta.thigh_in_pelvis_frame`); the
config's check simulates nothing, and refuses such a protocol from the pelvis cluster's geometry
against its noise and artefact (:func:`jointbench.configuration.bounds.pelvis_poses_problem`).
Each protocol below is one the simulate job refuses and the check passed before."""

from __future__ import annotations

import copy
import warnings

import numpy as np
import pytest
from workflow_copy import ROOT, refused_dry_run

from jointbench.configuration import config as study_config
from jointbench.simulate import hip_sta

# The ASIS pair of the default pelvis with the PSIS pair moved onto a line a few millimetres
# behind it: the cluster's width is then that distance.
_ASIS = [[52.8, -33.6, 72.0], [52.8, 206.4, 72.0]]


def _behind_the_asis(depth_mm: float) -> list[list[float]]:
    return [*_ASIS, [52.8 - depth_mm, 41.4, 72.0], [52.8 - depth_mm, 131.4, 72.0]]


#: name -> (protocol overrides, a condition of the default grid, words the refusal names)
CASES = {
    # 1.8 mm RMS from the ASIS line, above the 1.7 mm noise that the collinearity bound holds
    # every cluster to.
    "narrow against its noise": (
        {"pelvis_markers_mm": _behind_the_asis(3.6)},
        {"motion": "star_arc", "rom_deg": 20.0, "sta_mm": 0.0},
        ["studies.hip_sta.protocol.pelvis_markers_mm, noise_mm:", "1.8 mm", "1.7 mm"],
    ),
    # 5 mm wide, with pelvis artefact half the thigh's.
    "narrow against its artefact": (
        {"pelvis_markers_mm": _behind_the_asis(10.0), "pelvis_sta_ratio": 0.5},
        {"motion": "star_arc", "rom_deg": 45.0, "sta_mm": 30.0},
        [
            "studies.hip_sta.protocol.pelvis_markers_mm, noise_mm, pelvis_sta_ratio:",
            "5 mm",
            "sta_rigid_share",
            "grid's sta_mm 30",
        ],
    ),
    # 300 mm long, 0.28 mm RMS off its line, against 0.01 mm of noise.
    "long and narrow": (
        {"pelvis_markers_mm": [[0, -150, 72], [0, 150, 72], [0.6, 0, 72]], "noise_mm": 0.01},
        {"motion": "star_arc", "rom_deg": 20.0, "sta_mm": 0.0},
        ["studies.hip_sta.protocol.pelvis_markers_mm:", "433 times", "0.283 mm"],
    ),
}


@pytest.fixture(scope="module")
def config():
    return study_config.load_config(ROOT / "config" / "config.yaml")


def _with_protocol(config: dict, overrides: dict) -> dict:
    new = copy.deepcopy(config)
    new["studies"]["hip_sta"]["protocol"] = overrides
    return new


@pytest.mark.parametrize("name", CASES)
def test_the_simulate_job_refuses_the_protocol(config, name):
    overrides, condition, _ = CASES[name]
    protocol = hip_sta.HipStaProtocol.from_config(overrides)
    trials = config["studies"]["hip_sta"]["trials"]
    rngs = [np.random.default_rng(seed) for seed in range(trials)]
    with pytest.raises(ValueError, match="the protocol's pelvis cluster does not determine"):
        hip_sta.simulate(condition, protocol, rngs)


@pytest.mark.parametrize("name", CASES)
def test_the_config_check_refuses_it_naming_the_keys_and_numbers(config, name):
    overrides, _, words = CASES[name]
    with pytest.raises(ValueError) as raised:
        study_config.check_config(_with_protocol(config, overrides))
    message = str(raised.value)
    assert message.startswith("config: studies.hip_sta.protocol.pelvis_markers_mm"), message
    for word in words:
        assert word in message, message


def test_a_pelvis_artefact_as_large_as_the_thighs_passes_and_runs(config):
    """The bound refuses what the simulate job would refuse, not every artefact: the default
    pelvis with the thigh's artefact passes, and its largest condition runs."""
    overrides = {"pelvis_sta_ratio": 1.0}
    study_config.check_config(_with_protocol(config, overrides))
    protocol = hip_sta.HipStaProtocol.from_config(overrides)
    grid = config["studies"]["hip_sta"]["grid"]
    condition = {"motion": "circumduction", "rom_deg": max(grid["rom_deg"]), "sta_mm": 30.0}
    rngs = [np.random.default_rng(seed) for seed in range(config["studies"]["hip_sta"]["trials"])]
    hip_sta.simulate(condition, protocol, rngs)


@pytest.mark.pipeline
def test_dry_run_stops_before_any_job_naming_the_pelvis_cluster(tmp_path):
    overrides = CASES["narrow against its noise"][0]
    message = refused_dry_run(tmp_path, {"studies": {"hip_sta": {"protocol": overrides}}})
    expected = "config: studies.hip_sta.protocol.pelvis_markers_mm, noise_mm: "
    assert expected in message, message[-2000:]


def test_a_recording_too_long_to_hold_is_refused_naming_its_frames_not_a_memory_error(config):
    """A ``duration_s`` within a day (its declared bound) and an ``fps`` within what cameras
    record (``jointbench.simulate.ranges``) can still make trials of more frames than any job
    can hold: the check refuses them as a mistake, before the pelvis check tries to lay out the
    motion's frames."""
    with pytest.raises(ValueError) as raised:
        study_config.check_config(_with_protocol(config, {"duration_s": 86400, "fps": 1e4}))
    message = str(raised.value)
    assert message.startswith("config: studies.hip_sta.protocol.duration_s, fps: condition "), (
        message
    )
    assert "864000000 frame(s)" in message, message


def test_a_recording_of_no_frames_is_refused_for_its_frames_without_a_numpy_warning(config):
    """Trials of no frames have no RMS departure: the frame count's refusal comes first, and
    the pelvis check never averages over an empty recording."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(
            ValueError, match=r"duration_s, fps: .* 0 frame\(s\) \(from .*\), fewer than"
        ):
            study_config.check_config(_with_protocol(config, {"duration_s": 0.001}))
