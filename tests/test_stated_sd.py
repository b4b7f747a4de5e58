"""An SD whose result's status says its precision is not determined is no precision: every
producer of that warning says it in one phrase
(:data:`jointbench.estimators.results.PRECISION_NOT_DETERMINED`), and
:meth:`jointbench.RecordingFit.stated_sd` reads it, whatever the SD's size."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_axis_sd_validity import swing
from test_gauss_markov_fit import _skin_thigh
from test_pose_noise import _PULLED, _hip, _noisy

import jointbench
from jointbench.estimators import precision, results, support
from jointbench.estimators.centre_precision import MAX_CENTER_SD_MM, MAX_POSE_NOISE_PULL_MM
from jointbench.estimators.registry import KINDS
from jointbench.io.fit import NOT_DETERMINED, SD_NAMES, RecordingFit

SOURCE = Path(jointbench.__file__).resolve().parent


def planar_ok():
    """A planar axis on a 60 deg swing: ``ok``, its SD well under the bound."""
    result = jointbench.fit_axis(swing(0, 60.0), "planar")
    assert result.status == "ok"
    assert result.diagnostics["axis_sd_deg"] < precision.MAX_AXIS_SD_DEG
    return result


def stated_sd(result) -> float | str | None:
    frames = np.arange(50)
    return RecordingFit("axis", result.method, result, None, frames, 0).stated_sd()


def eigen_gap_within_the_noise(result):
    return precision.annotate_validity(result, 3.0, 2.0, "the planar cost's scatter")


def anisotropic_pull(result):
    return precision.annotate_validity(result, 1.0, 2.0, "SARA's normal matrix", bias_deg=50.0)


def no_marker_reads_the_rotation(result):
    arcs = np.array([6.0, 7.0, 8.0, 9.0])  # every lever reads it to more than 5 deg a frame
    reference = support.MotionAxis(result.direction, 1.0, 0.1, 1.0, arcs)
    return precision.annotate_motion_axis(result, reference)


def too_few_first_order_markers(result):
    first_order = np.array([True, False, False, False])
    return precision.annotate_first_order(result, 20.0, first_order)


@pytest.mark.parametrize(
    "warn",
    [
        eigen_gap_within_the_noise,
        anisotropic_pull,
        no_marker_reads_the_rotation,
        too_few_first_order_markers,
    ],
)
def test_a_status_saying_the_precision_is_not_determined_states_no_sd(warn):
    result = planar_ok()
    assert isinstance(stated_sd(result), float)
    warned = warn(result)
    assert results.PRECISION_NOT_DETERMINED in warned.status  # the case
    assert not results.states_precision(warned)
    assert stated_sd(warned) == NOT_DETERMINED


def test_a_status_saying_nothing_of_the_precision_keeps_the_sd():
    result = planar_ok()
    assert results.states_precision(result)
    assert stated_sd(result) == result.diagnostics["axis_sd_deg"]
    # Another warning (the answer's cost against another's) leaves the SD as it is.
    crossed = precision.annotate_agreement(result, result.direction, 1.0, "a", "b")
    assert stated_sd(crossed) == result.diagnostics["axis_sd_deg"]


def test_every_kind_names_its_sd():
    assert SD_NAMES.keys() == set(KINDS)


def test_every_producer_of_the_warning_says_it_in_the_one_phrase():
    """The reader recognises a status by :data:`~results.PRECISION_NOT_DETERMINED`: a warning
    typing the words itself would pass unrecognised the day they drift apart."""
    phrase = results.PRECISION_NOT_DETERMINED
    typed = [
        path.relative_to(SOURCE)
        for path in SOURCE.rglob("*.py")
        if path != Path(results.__file__).resolve() and phrase in path.read_text()
    ]
    assert typed == []
    # The producers this names read the constant (their wording is kept to the letter).
    for module in ("estimators/precision.py", "estimators/centre_precision.py"):
        assert "PRECISION_NOT_DETERMINED" in (SOURCE / module).read_text()


def joint_centre_sd(result) -> float | str | None:
    frames = np.arange(60)
    return RecordingFit("joint_center", result.method, result, None, frames, 0).stated_sd()


@pytest.mark.parametrize("method", ["SCoRE", "gauss-markov-frame0"])
def test_a_joint_centre_the_poses_noise_pulled_states_no_sd(method):
    """Nearly a hinge, 0.5 mm noise: the noise in the poses pulls the answer tens of
    millimetres towards the markers, a bias its SD of a few millimetres (the scatter's) does
    not contain, so that SD is no statement of the answer's precision."""
    result = jointbench.fit_joint_center(*_noisy(_hip(0, ratio=0.06), 100), method=method)
    assert _PULLED in result.status  # the case
    assert result.diagnostics["center_pose_noise_pull_mm"] > MAX_POSE_NOISE_PULL_MM
    assert result.diagnostics["center_sd_mm"] < MAX_CENTER_SD_MM
    assert joint_centre_sd(result) == NOT_DETERMINED


@pytest.mark.parametrize("method", ["SCoRE", "analytic"])
def test_a_joint_centre_whose_model_the_data_reject_states_no_sd(method):
    """A thigh cluster sliding with the hip angles: the fixed-centre model's test rejects, and
    the status says the SD does not describe the answer's error; it is no precision."""
    result = jointbench.fit_joint_center(*_skin_thigh(0)[:2], method=method)
    assert "its SD does not describe its error" in result.status  # the case
    assert result.diagnostics["center_sd_mm"] < MAX_CENTER_SD_MM
    assert joint_centre_sd(result) == NOT_DETERMINED


def test_a_zero_noise_given_states_no_sd():
    """``noise_mm=0`` given to paper C's fit on noisy data: a zero covariance, which its status
    says does not describe the error, is no precision of 0 mm."""
    result = jointbench.fit_joint_center(*_skin_thigh(0)[:2], method="gauss-markov", noise_mm=0.0)
    assert "noise_mm = 0 was given" in result.status  # the case
    assert result.diagnostics["center_sd_mm"] == 0.0
    assert joint_centre_sd(result) == NOT_DETERMINED


@pytest.mark.parametrize("method", ["SCoRE", "gauss-markov-frame0"])
def test_a_joint_centre_whose_data_the_verdict_refuses_states_no_sd(method):
    """A noisy pure hinge: the support verdict says the centre is not determined along the
    hinge's axis, so the SD the method computes (a few millimetres, from a covariance that
    takes the centre as determined) is no statement of its precision."""
    result = jointbench.fit_joint_center(*_noisy(_hip(1, ratio=0.0), 3), method=method)
    assert "the centre is not determined along it" in result.status  # the case
    assert result.diagnostics["center_sd_mm"] < MAX_CENTER_SD_MM
    assert joint_centre_sd(result) == NOT_DETERMINED


def test_a_centre_whose_data_the_verdict_refuses_states_no_sd():
    """One segment held still: the verdict refuses a centre (no rotation), whatever SD the
    method's precision step would give."""
    result = jointbench.fit_axis(swing(0, 60.0), "planar")
    refused = support.annotate(result, support.Support(("range of motion too small",), {}))
    assert stated_sd(refused) == NOT_DETERMINED
    caveat = support.annotate(result, support.Support((), {}, caveats=("frames not independent",)))
    assert stated_sd(caveat) == result.diagnostics["axis_sd_deg"]
