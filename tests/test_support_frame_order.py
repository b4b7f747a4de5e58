"""The one-segment support verdict does not depend on the order of the frames.

Every estimator's answer is a function of the set of frames, and so must the verdict on it
be: reversing the frames, or shuffling them so that another frame comes first, must give the
same warnings word for word (numbers masked) and the same numbers to rounding. The trials are
drawn where the verdict is closest to changing its mind: rotations from below to above what
the noise resolves, hinges with a small rotation about a second axis, static clusters, flat
plates and elongated clusters, and the support sweep's random trials. A verdict that takes any
one frame as its reference (its noise, or where it sits in the motion) fails here.

The one exception is the test of the frames' independence, which is about their sequence
(``tests/test_frame_independence.py``): its numbers are not compared, but its warning is, and on
these trials, whose noise is independent in each frame, it is given in no order.
"""

from __future__ import annotations

import math
import re

import numpy as np
import pytest
from test_support_calibration import _draw, _elongated, _plate, _trial
from test_support_sweep import TRIALS as SWEEP

from jointbench.estimators import support
from jointbench.geometry import unit

_NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?")
# The verdict's numbers that read the frames' order: whether the frames are independent.
SEQUENCE_NUMBERS = frozenset(
    {
        "frame_correlation",
        "frame_variance_ratio",
        "frame_variance_ratio_block",
        "independent_frames",
    }
)


def _near_boundaries() -> list[np.ndarray]:
    """Calibration-like trials ``(N, n, 3)`` [mm] near each test's boundary: hinges from well
    below to above what the noise resolves, hinges with a second rotation of a few noise SDs,
    static clusters, and flat plates and an elongated cluster on hinges."""
    rng = np.random.default_rng(20261204)
    found = []
    for _ in range(40):
        t, body, noise_mm = _draw(rng)
        radius = np.sqrt(np.mean(np.sum((body - body.mean(axis=0)) ** 2, axis=1)))
        # From a tenth to ten times the rotation that moves the markers by their noise.
        resolved = noise_mm / radius / np.sqrt(t.size)
        amplitude = resolved * 10.0 ** rng.uniform(-1.0, 1.5)
        main, second = unit(rng.normal(size=3)), unit(rng.normal(size=3))
        angle = amplitude * np.sin(2.0 * np.pi * rng.uniform(0.5, 2.0) * t + rng.uniform(0, 6))
        found.append(_trial(rng, np.outer(angle, main), body, noise_mm))
        off_axis = noise_mm / radius * 10.0 ** rng.uniform(-1.0, 0.7)
        wide = np.outer(10.0 * angle, main) + np.outer(off_axis * np.cos(7.0 * t), second)
        found.append(_trial(rng, wide, body, noise_mm))
        found.append(_trial(rng, np.zeros((t.size, 3)), body, noise_mm))
    for _ in range(8):
        n_frames, noise_mm = int(rng.integers(30, 200)), 10.0 ** rng.uniform(-1.0, 0.3)
        angle = 10.0 ** rng.uniform(-2.5, 0.0) * np.sin(np.linspace(0.0, 9.0, n_frames))
        plate = _plate(rng, noise_mm)
        found.append(_trial(rng, np.outer(angle, unit(rng.normal(size=3))), plate, noise_mm))
    for amplitude_deg in (0.3, 3.0, 60.0):
        angle = np.radians(amplitude_deg) * np.sin(np.linspace(0.0, 4.0 * np.pi, 150))
        axis = unit(np.array([0.2, 1.0, 0.3]))
        found.append(_trial(rng, np.outer(angle, axis), _elongated(0.5), 0.5))
    return found


TRIALS = _near_boundaries() + [arrays[0] for kind, arrays in SWEEP[:2400:6]]


def _orders(n_frames: int, seed: int) -> list[np.ndarray]:
    """The frames reversed, and two random orders that each move frame 0."""
    rng = np.random.default_rng(seed)
    orders = [np.arange(n_frames)[::-1]]
    while len(orders) < 3:
        order = rng.permutation(n_frames)
        if order[0] != 0:
            orders.append(order)
    return orders


def _assert_same_verdict(found: support.Support, expected: support.Support) -> None:
    """The same warnings (numbers masked) and the same numbers to 1e-9 relative; numbers
    that are rounding themselves (a p-value of 1e-300; noise-free data's angle off the hinge,
    the root of a difference of sums of squares, 1e-8 of the rotation) to 1e-9 absolute, and
    as the pinned sweep has it, 1e-6 for those in degrees or mm. A p-value to 2e-8: the F
    tail multiplies its statistic's relative rounding by ``d log p / d log F``, some ten, and
    the statistic off the hinge carries the rounding of the direction the markers move least
    along, an eigenvector of a scatter whose eigenvalues can span six orders (measured: 1e-9
    relative in the statistic, 1.1e-8 in its p-value). The motion's axis up to its sign."""
    masked = [[_NUMBER.sub("#", w) for w in v.warnings + v.caveats] for v in (found, expected)]
    assert masked[0] == masked[1], (found.warnings, expected.warnings)
    assert found.diagnostics.keys() == expected.diagnostics.keys()
    for key, value in expected.diagnostics.items():
        if key in SEQUENCE_NUMBERS:
            continue
        if isinstance(value, float):
            floor = 1e-6 if key.endswith(("_deg", "_mm")) else 1e-9
            relative = 2e-8 if key.endswith("_p_value") else 1e-9
            assert math.isclose(found.diagnostics[key], value, rel_tol=relative, abs_tol=floor), (
                key,
                found.diagnostics[key],
                value,
            )
        else:
            assert found.diagnostics[key] == value, key
    assert (found.motion_axis is None) == (expected.motion_axis is None)
    _assert_same_noise_directions(found.noise_directions, expected.noise_directions)
    if expected.motion_axis is not None:
        axis, other = expected.motion_axis, found.motion_axis
        sign = 1.0 if float(axis.direction @ other.direction) >= 0.0 else -1.0
        np.testing.assert_allclose(sign * other.direction, axis.direction, rtol=0, atol=1e-9)
        np.testing.assert_allclose(
            [other.sd_deg, other.noise_share, other.pose_sd_deg],
            [axis.sd_deg, axis.noise_share, axis.pose_sd_deg],
            rtol=1e-9,
            atol=1e-9,
        )


def _assert_same_noise_directions(found, expected) -> None:
    """The same noise-direction test (:mod:`jointbench.estimators.noise_directions`): made or
    not, rejecting or not, its statistic to 1e-9 relative and, where it rejects, its estimate
    of the noise's covariance to 1e-9 of that covariance's size."""
    assert (found is None) == (expected is None)
    if expected is None:
        return
    assert math.isnan(found.statistic) == math.isnan(expected.statistic)
    if not math.isnan(expected.statistic):
        assert math.isclose(found.statistic, expected.statistic, rel_tol=1e-9, abs_tol=1e-9), (
            found.statistic,
            expected.statistic,
        )
    assert found.rejected() == expected.rejected()
    if expected.rejected():
        size = np.abs(expected.covariance).max()
        np.testing.assert_allclose(found.covariance, expected.covariance, atol=1e-9 * size)


@pytest.mark.parametrize("kind", ["center", "axis"])
def test_the_verdict_ignores_the_order_of_the_frames(kind):
    for index, markers in enumerate(TRIALS):
        expected = support.assess(kind, (markers,))
        for order in _orders(markers.shape[0], index):
            found = support.assess(kind, (markers[order],))
            try:
                _assert_same_verdict(found, expected)
            except AssertionError as error:
                raise AssertionError(f"trial {index}, {markers.shape}: {error}") from error


def test_a_batch_of_reordered_trials_is_judged_as_each_alone():
    """Reordered trials judged together, in one compiled call, decide as the originals."""
    markers = np.stack([_trial_of(seed) for seed in range(6)])
    expected = support.assess_many("center", (markers,))
    reordered = np.stack([m[order] for m, order in zip(markers, _batch_orders(), strict=True)])
    for found, alone in zip(support.assess_many("center", (reordered,)), expected, strict=True):
        _assert_same_verdict(found, alone)


def _trial_of(seed: int) -> np.ndarray:
    """A hinge of 60 frames with a second rotation near the noise, ``(60, n, 3)`` [mm]."""
    rng = np.random.default_rng(seed)
    _, body, noise_mm = _draw(rng)
    body = body[:4] if body.shape[0] >= 4 else np.vstack([body, body[:1] + 30.0])
    t = np.linspace(0.0, 1.0, 60)
    radius = np.sqrt(np.mean(np.sum((body - body.mean(axis=0)) ** 2, axis=1)))
    vectors = np.outer(0.3 * np.sin(5.0 * t), unit(rng.normal(size=3)))
    vectors += np.outer(noise_mm / radius * np.cos(9.0 * t), unit(rng.normal(size=3)))
    return _trial(rng, vectors, body, noise_mm)


def _batch_orders() -> list[np.ndarray]:
    return [_orders(60, seed)[seed % 3] for seed in range(6)]
