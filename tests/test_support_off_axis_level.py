"""The two-segment verdict's test for rotation about a second axis holds its level on pure
hinges of long recordings and wide ranges (:func:`jointbench.estimators.support._rotation_spreads`).

Each frame's rotation vector about the mean relative pose carries the reference segment's pose
noise turned by that frame's own relative rotation, and both segments' noise through the
logarithm's Jacobian there: over a 30 degree flexion, three-marker clusters (whose inertia is far
from isotropic) make that noise differ from frame to frame by more than a long recording
resolves. Read with the mean pose's covariance for every frame, the pure hinges below were
passed as rotating about two axes at the 0.1 % level in 29 of 100 trials of 300 frames and 42 of
100 of 1200 (8 of 100 with four markers per segment), their median p-values 0.07, 0.01 and 0.17.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_pose_noise import _hip, _noisy

from jointbench.estimators import support
from jointbench.estimators.segment_poses import trial_poses


def _off_axis_p_values(n_frames: int, n_markers: int) -> np.ndarray:
    """The off-axis p-values of pure hinges (:func:`test_pose_noise._hip`, a 30 degree flexion
    with the pelvis swaying, ``n_frames`` frames, the first ``n_markers`` markers of each
    segment) in 10 geometries x 10 draws of 0.5 mm noise: ``(100,)``."""
    p_values = []
    for geometry in range(10):
        clean = _hip(geometry, ratio=0.0, n_frames=n_frames)
        clean = tuple(segment[:, :n_markers] for segment in clean)
        for seed in range(10):
            verdict = support.assess("joint_center", _noisy(clean, 500 + seed))
            p_values.append(verdict.diagnostics["off_axis_p_value"])
    return np.array(p_values)


@pytest.mark.parametrize(("n_frames", "n_markers"), [(300, 3), (1200, 3), (1200, 4)])
def test_a_pure_hinge_is_passed_as_two_axes_at_the_verdicts_level(n_frames, n_markers):
    """At most 2 of 100 pure hinges resolve a second axis at the level of a thousandth (3 or
    more has a binomial chance of 1.5e-4), and the p-values are centred: between 35 and 65 of
    100 fall below 0.5 (three binomial SDs either side of 50), so that a test made blind to a
    second axis does not pass either."""
    p_values = _off_axis_p_values(n_frames, n_markers)
    assert np.sum(p_values < support.ROTATION_ALPHA) <= 2, np.sort(p_values)[:5]
    assert 35 <= np.sum(p_values < 0.5) <= 65, np.median(p_values)


@pytest.mark.parametrize("ratio", [0.0, 0.3])
def test_the_way_near_pi_reads_a_hinge_as_the_compiled_pass_does(ratio):
    """Away from pi the rotations' own way (:func:`support._spreads_near_pi`, which holds near
    pi too) gives the compiled pass's numbers, the hinge's residual among them, to rounding."""
    proximal, distal = _noisy(tuple(s[:, :3] for s in _hip(2, ratio=ratio, n_frames=300)), 1)
    poses = trial_poses({"proximal": proximal[None], "distal": distal[None]}, min_frames=2)[0]
    reference, moving = (
        support._clusters(a[None], [poses[n]])
        for a, n in ((proximal, "proximal"), (distal, "distal"))
    )
    variance = (reference.residual_ss + moving.residual_ss) / (reference.dof + moving.dof)
    compiled = support._rotation_spreads(
        moving.rotation, moving.inertia_inv, reference.rotation, reference.inertia_inv, variance
    )
    relative = np.swapaxes(reference.rotation, -1, -2) @ moving.rotation
    own_way = support._spreads_near_pi(
        relative, moving.inertia_inv, reference.inertia_inv, variance
    )
    assert not compiled[-1]
    for found, expected in zip(own_way, compiled[:5], strict=True):
        np.testing.assert_allclose(found, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
