"""The support verdict refuses fewer frames than its tests need, for every kind.

Two frames leave the verdict's tests of a straight line and of a hinge no degrees of freedom
(``2 (N - 2)``): two frames of collinear markers divided by zero, and two frames of random,
non-rigid markers were judged with no warning at all (a rigid residual of 0 mm, the rotation
"resolved"). :func:`jointbench.estimators.support.assess` and ``assess_many`` are public, so
such arrays get a ``ValueError`` naming the array and its count; three frames are judged, the
rigid fit then has a residual, and three random markers read as not one rigid body.
"""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.estimators import support, validation


def _random(n_frames: int, n_markers: int, seed: int = 0) -> np.ndarray:
    """Markers of no rigid body: ``(n_frames, n_markers, 3)`` [mm], the draw after a discarded
    one of the same shape."""
    rng = np.random.default_rng(seed)
    rng.normal(size=(n_frames, n_markers, 3))
    return rng.normal(size=(n_frames, n_markers, 3)) * 30.0


def _collinear(n_frames: int, n_markers: int) -> np.ndarray:
    """Markers along a line, moving, with noise: ``(n_frames, n_markers, 3)`` [mm]."""
    rng = np.random.default_rng(1)
    line = np.arange(n_markers)[:, None] * np.array([50.0, 0.0, 0.0])
    steps = np.arange(n_frames)[:, None, None] * np.array([0.0, 10.0, 5.0])
    return line + steps + rng.normal(scale=0.3, size=(n_frames, n_markers, 3))


def _arrays(kind: str, markers: np.ndarray) -> tuple[np.ndarray, ...]:
    if kind == "joint_center":
        return (_random(*markers.shape[:2], seed=2), markers)
    return (markers,)


@pytest.mark.parametrize("make", [_random, _collinear], ids=["random", "collinear"])
@pytest.mark.parametrize("n_markers", [3, 4])
@pytest.mark.parametrize("n_frames", [1, 2])
@pytest.mark.parametrize("kind", list(validation.ARRAY_NAMES))
def test_fewer_frames_than_the_tests_need_are_refused_naming_array_and_count(
    kind, n_frames, n_markers, make
):
    arrays = _arrays(kind, make(n_frames, n_markers))
    name = validation.ARRAY_NAMES[kind][0]
    expected = rf"^{name} has {n_frames} frames; the support verdict needs at least 3"
    with pytest.raises(ValueError, match=expected):
        support.assess(kind, arrays)
    with pytest.raises(ValueError, match=expected):
        support.assess_many(kind, tuple(array[None] for array in arrays))


@pytest.mark.parametrize("n_markers", [3, 4])
@pytest.mark.parametrize("kind", list(validation.ARRAY_NAMES))
def test_three_frames_leave_the_rigid_fit_a_residual(kind, n_markers):
    """Three frames leave the rigid fit residual degrees of freedom: random markers leave a
    residual of their own size (30 mm per coordinate), not the 0 mm of two frames."""
    verdict = support.assess(kind, _arrays(kind, _random(3, n_markers)))
    assert verdict.diagnostics["assessed"]
    assert verdict.diagnostics["rigid_residual_mm"] > 10.0


@pytest.mark.parametrize("kind", list(validation.ARRAY_NAMES))
def test_three_frames_of_three_random_markers_are_not_one_rigid_body(kind):
    verdict = support.assess(kind, _arrays(kind, _random(3, 3)))
    assert "not one rigid body" in verdict.warnings[0], verdict.warnings


@pytest.mark.parametrize("n_frames", [3, 4])
@pytest.mark.parametrize("kind", list(validation.ARRAY_NAMES))
def test_a_sphere_through_every_sample_leaves_the_arc_test_undone(kind, n_frames):
    """One marker over three or four frames: a sphere (centre and radius) passes through every
    sample, so nothing tells an arc from a line; the verdict says the test was not made
    instead of reading the exact fit as a resolved arc (p = 0)."""
    verdict = support.assess(kind, _arrays(kind, _random(n_frames, 1)))
    assert np.isnan(verdict.diagnostics["straight_line_p_value"])
    assert any("arcs was not tested" in warning for warning in verdict.warnings)
