"""The analytic joint centre's bias from the frame-0 poses that anchor its body frames
(:func:`jointbench.estimators.pose_noise.anchor_bias_mm`), added to the pull its checked call
holds it to: on a small circumduction an answer its SD understated now says its precision is
not determined, and on an ordinary swing none does."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

import jointbench
from jointbench.estimators import centre_precision, support
from jointbench.estimators.centre_precision import stated_covariance
from jointbench.estimators.pose_noise import pull_mm
from jointbench.geometry import rotation_about_axis

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
from anchor_bias_frame0 import formula
from joint_centre_degenerate import circumduction, two_segments

_PULLED = "the noise in the poses pulls a least-squares joint centre"


def _analytic(rom_deg: float, seed: int):
    """The checked analytic answer to ``benchmarks/joint_centre_stated_sd.py``'s trial of
    ``seed`` on a circumduction of ``rom_deg``, and its Mahalanobis distance from the truth
    under the covariance it states."""
    proximal, distal, centre = two_segments(
        np.random.default_rng(seed), circumduction(rom_deg, 200), noise_mm=0.5
    )
    result = jointbench.fit_joint_center(proximal, distal, "analytic")
    error = result.center - centre[0]
    distance = float(np.sqrt(error @ np.linalg.solve(stated_covariance(result)[0], error)))
    return result, distance


@pytest.mark.parametrize("seed", [15, 23])
def test_a_small_swing_biased_by_its_anchor_is_not_ok(seed):
    # Read ok before, 14.2 and 21.1 mm off, 3.5 and 3.3 of their SDs.
    result, distance = _analytic(3.0, seed)
    assert distance > 3.0
    assert result.status != "ok"
    assert _PULLED in result.status
    # The pull alone was under its bound: the anchor's bias is what it now adds.
    assert np.linalg.norm(result.diagnostics["center_anchor_bias_mm"]) > 1.0


@pytest.mark.parametrize("seed", range(3))
def test_an_ordinary_swing_is_not_biased_by_its_anchor(seed):
    result, distance = _analytic(30.0, seed)
    assert result.status == "ok", result.status
    assert distance < 3.0


def test_the_stated_pull_adds_the_anchor_bias():
    """The pull the checked analytic call states is the length of the pull of independent
    frames plus its anchor bias, added (not subtracted, not left out)."""
    proximal, distal, _ = two_segments(
        np.random.default_rng(15), circumduction(3.0, 200), noise_mm=0.5
    )
    result = jointbench.fit_joint_center(proximal, distal, "analytic")
    noise = support.assess("joint_center", (proximal, distal)).pose_noise
    pulled = pull_mm(noise, result.center) + result.diagnostics["center_anchor_bias_mm"]
    stated = result.diagnostics["center_pose_noise_pull_mm"]
    assert stated == pytest.approx(float(np.linalg.norm(pulled)), rel=1e-9)


def test_the_anchor_bias_turns_with_the_trial():
    """Moved and turned as a whole, a trial's anchor bias ``(3,)`` [mm] turns with it (a
    displacement, not a position) and does not depend on the markers' order."""
    proximal, distal, _ = two_segments(
        np.random.default_rng(15), circumduction(3.0, 200), noise_mm=0.5
    )
    turn = rotation_about_axis(np.array([1.0, 2.0, -0.5]), 0.7)
    shift = np.array([500.0, -300.0, 2000.0])
    bias = _anchor_bias(proximal, distal)
    assert np.linalg.norm(bias) > 1.0
    moved = _anchor_bias(proximal @ turn.T + shift, distal @ turn.T + shift)
    np.testing.assert_allclose(moved, turn @ bias, atol=1e-9)
    reordered = _anchor_bias(proximal[:, [2, 0, 3, 1]], distal[:, [3, 1, 0, 2]])
    np.testing.assert_allclose(reordered, bias, atol=1e-9)


def _anchor_bias(proximal: np.ndarray, distal: np.ndarray) -> np.ndarray:
    """The anchor bias ``(3,)`` [mm] the checked analytic call states on markers ``proximal``,
    ``distal`` ``(N, n, 3)`` [mm]."""
    result = jointbench.fit_joint_center(proximal, distal, "analytic")
    return np.asarray(result.diagnostics["center_anchor_bias_mm"])


@pytest.mark.parametrize(
    ("sd", "bound"),
    [
        (None, centre_precision.MAX_POSE_NOISE_PULL_MM),
        (math.inf, centre_precision.MAX_POSE_NOISE_PULL_MM),
        (math.nan, centre_precision.MAX_POSE_NOISE_PULL_MM),
        (0.0, centre_precision.MIN_POSE_NOISE_PULL_MM),
        (1.0, centre_precision.MIN_POSE_NOISE_PULL_MM),
        (6.0, centre_precision.MAX_STEP_SDS * 6.0),
        (30.0, centre_precision.MAX_POSE_NOISE_PULL_MM),
    ],
)
def test_the_pull_bound_is_the_sds_share_between_its_floor_and_cap(sd, bound):
    assert centre_precision.pull_bound_mm(sd) == bound


@pytest.mark.parametrize("rom_deg", [3.0, 10.0])
def test_the_anchor_bias_is_the_second_order_mean_of_frame0_errors(rom_deg):
    """On a noise-free circumduction the analytic centre's mean error from noise of variance
    ``s^2`` on frame 0's markers alone is, to second order, ``s^2 / 2`` times the trace of
    its Hessian in those 24 coordinates, here by central second differences: the formula,
    read with that variance, is it (the terms it leaves out, of the body-fixed markers' own
    errors, are a few percent)."""
    proximal, distal, centre = two_segments(
        np.random.default_rng(0), circumduction(rom_deg, 200), noise_mm=0.0
    )
    step_mm, noise_mm = 1e-2, 0.02

    def answer(shift: np.ndarray) -> np.ndarray:
        moved = [proximal.copy(), distal.copy()]
        moved[0][0] += shift[:12].reshape(4, 3)
        moved[1][0] += shift[12:].reshape(4, 3)
        return jointbench.fit_joint_center(*moved, "analytic").center

    still = answer(np.zeros(24))
    trace = (
        sum(answer(step) + answer(-step) - 2.0 * still for step in step_mm * np.eye(24))
        / step_mm**2
    )
    second_order = noise_mm**2 / 2.0 * trace
    bias = formula(proximal, distal, centre[0], noise_mm)
    assert np.linalg.norm(bias - second_order) < 0.06 * np.linalg.norm(second_order)
