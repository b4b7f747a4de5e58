"""SCoRE and SARA (Ehrig et al. 2006, 2007)."""

from __future__ import annotations

import numpy as np
import pytest
from rigs import DISTAL, HINGE, JOINT, apply_pose, two_segments

import jointbench as jb
from jointbench.estimators.twosegment import fit_sara, fit_sara_two_segment
from jointbench.geometry import angle_between_lines_deg, rotation_matrix, unit
from jointbench.numerics.poses import rigid_fit
from jointbench.simulate.noise import isotropic_noise


def one_segment(n_frames=200, *, hinge=False):
    """Noise-free moving markers in the reference frame about JOINT (ball or HINGE)."""
    t = np.linspace(0.0, 4.0, n_frames)
    if hinge:
        rel = 0.7 * np.sin(1.9 * t)[:, None] * HINGE
    else:
        rel = np.stack([0.6 * np.sin(1.9 * t), 0.4 * np.sin(1.3 * t), 0.1 * np.sin(t)], -1)
    rotation = rotation_matrix(rel)
    return apply_pose(rotation, JOINT - rotation @ JOINT, DISTAL)


def _noisy(markers, seed, sd=1.0):
    return markers + isotropic_noise(np.random.default_rng(seed), markers.shape[:2], sd)


def _random_rigid(seed):
    rng = np.random.default_rng(seed)
    return rotation_matrix(rng.normal(size=3)), rng.normal(scale=500.0, size=3)


def test_score_recovers_centre_noise_free():
    proximal, distal = two_segments()
    result = jb.fit_joint_center(proximal, distal, method="SCoRE")
    np.testing.assert_allclose(result.center, JOINT, atol=1e-9)
    np.testing.assert_allclose(result.diagnostics["center_proximal"], JOINT, atol=1e-9)
    np.testing.assert_allclose(result.diagnostics["center_distal"], JOINT, atol=1e-9)
    assert result.cost < 1e-15
    assert result.converged and result.covariance is None and result.method == "SCoRE"


def test_score_with_a_still_proximal_segment():
    proximal, distal = two_segments(proximal_moves=False)
    result = jb.fit_joint_center(proximal, distal, method="SCoRE")
    np.testing.assert_allclose(result.center, JOINT, atol=1e-9)


def test_score_one_segment_centre_in_reference_frame():
    result = jb.fit_center(one_segment(), method="SCoRE")
    np.testing.assert_allclose(result.center, JOINT, atol=1e-9)
    assert result.method == "SCoRE" and result.radii is None


def test_score_noisy_is_close():
    proximal, distal = two_segments(300)
    result = jb.fit_joint_center(_noisy(proximal, 1), _noisy(distal, 2), method="SCoRE")
    assert np.linalg.norm(result.center - JOINT) < 10.0


def test_sara_one_segment_recovers_hinge():
    markers = one_segment(hinge=True)
    result = jb.fit_axis(markers, method="SARA")
    assert angle_between_lines_deg(result.direction, HINGE) < 1e-8
    # The point lies on the axis: the one nearest the moving markers' centroid at frame 0.
    offset = result.point - JOINT
    assert np.linalg.norm(offset - (offset @ HINGE) * HINGE) < 1e-9
    assert abs((result.point - markers[0].mean(axis=0)) @ HINGE) < 1e-9
    radii = np.linalg.norm((DISTAL - JOINT) - np.outer((DISTAL - JOINT) @ HINGE, HINGE), axis=1)
    np.testing.assert_allclose(result.radii, radii, atol=1e-9)
    assert result.diagnostics["ratio"] < 1e-12


def test_sara_two_segment_recovers_hinge_in_frame0_world():
    proximal, distal = two_segments(relative="hinge")
    result = fit_sara_two_segment(proximal, distal)
    assert angle_between_lines_deg(result.direction, HINGE) < 1e-8
    offset = result.point - JOINT
    assert np.linalg.norm(offset - (offset @ HINGE) * HINGE) < 1e-9
    radii = np.linalg.norm((DISTAL - JOINT) - np.outer((DISTAL - JOINT) @ HINGE, HINGE), axis=1)
    np.testing.assert_allclose(result.radii, radii, atol=1e-8)


def test_sara_noisy_hinge_direction():
    proximal, distal = two_segments(300, relative="hinge")
    result = fit_sara_two_segment(_noisy(proximal, 3), _noisy(distal, 4))
    assert angle_between_lines_deg(result.direction, HINGE) < 2.0


def test_world_transform_moves_results_consistently():
    """The answer is in the world at frame 0: transforming the world transforms it."""
    proximal, distal = two_segments(150)
    proximal, distal = _noisy(proximal, 5), _noisy(distal, 6)
    rotation, shift = _random_rigid(0)
    moved = [m @ rotation.T + shift for m in (proximal, distal)]
    before = jb.fit_joint_center(proximal, distal, method="SCoRE")
    after = jb.fit_joint_center(*moved, method="SCoRE")
    np.testing.assert_allclose(after.center, rotation @ before.center + shift, atol=1e-8)
    axis_before = fit_sara_two_segment(proximal, distal)
    axis_after = fit_sara_two_segment(*moved)
    # An axis is a line: its direction's sign is whatever the eigen-solver returns.
    assert angle_between_lines_deg(axis_after.direction, rotation @ axis_before.direction) < 1e-8


def test_one_segment_methods_follow_the_reference_frame():
    markers = _noisy(one_segment(), 7)
    rotation, shift = _random_rigid(1)
    moved = markers @ rotation.T + shift
    before, after = jb.fit_center(markers, method="SCoRE"), jb.fit_center(moved, method="SCoRE")
    np.testing.assert_allclose(after.center, rotation @ before.center + shift, atol=1e-8)
    hinge = _noisy(one_segment(hinge=True), 8)
    axis_before = fit_sara(hinge)
    axis_after = fit_sara(hinge @ rotation.T + shift)
    assert angle_between_lines_deg(axis_after.direction, rotation @ axis_before.direction) < 1e-8


def test_marker_order_and_segment_order_do_not_matter():
    proximal, distal = two_segments(150)
    proximal, distal = _noisy(proximal, 9), _noisy(distal, 10)
    reference = jb.fit_joint_center(proximal, distal, method="SCoRE").center
    shuffled = jb.fit_joint_center(proximal[:, [2, 0, 1]], distal[:, [1, 2, 0]], method="SCoRE")
    np.testing.assert_allclose(shuffled.center, reference, atol=1e-8)
    # SCoRE is symmetrical: swapping the segments gives the same centre.
    swapped = jb.fit_joint_center(distal, proximal, method="SCoRE")
    np.testing.assert_allclose(swapped.center, reference, atol=1e-8)


def test_degenerate_motion_raises():
    proximal, distal = two_segments(relative="hinge")
    with pytest.raises(ValueError, match="single axis"):
        jb.fit_joint_center(proximal, distal, method="SCoRE")
    with pytest.raises(ValueError, match="single axis"):
        jb.fit_center(one_segment(hinge=True), method="SCoRE")
    still_p, still_d = two_segments(relative="none")
    with pytest.raises(ValueError, match="do not rotate relative to each other"):
        jb.fit_joint_center(still_p, still_d, method="SCoRE")
    with pytest.raises(ValueError, match="do not rotate relative to each other"):
        fit_sara_two_segment(still_p, still_d)
    with pytest.raises(ValueError, match="do not rotate"):
        fit_sara(np.repeat(DISTAL[None], 10, axis=0) + np.arange(10)[:, None, None])


def test_bad_input_is_named():
    proximal, distal = two_segments(20)
    with pytest.raises(ValueError, match="proximal must be shaped"):
        jb.fit_joint_center(proximal[..., :2], distal, method="SCoRE")
    bad = distal.copy()
    bad[3, 1, 2] = np.nan
    with pytest.raises(ValueError, match="distal contains NaN"):
        jb.fit_joint_center(proximal, bad, method="SCoRE")
    with pytest.raises(ValueError, match="distal has 2 markers"):
        jb.fit_joint_center(proximal, distal[:, :2], method="SCoRE")
    with pytest.raises(ValueError, match="must share frames"):
        jb.fit_joint_center(proximal, distal[:-1], method="SCoRE")
    with pytest.raises(ValueError, match="at least 3"):
        jb.fit_joint_center(proximal[:2], distal[:2], method="SCoRE")
    line = np.repeat(np.array([[1.0, 0, 0], [2, 0, 0], [3, 0, 0]])[None], 20, axis=0)
    with pytest.raises(ValueError, match="collinear"):
        jb.fit_joint_center(proximal, line, method="SCoRE")
    with pytest.raises(ValueError, match="collinear"):
        fit_sara(line)


def test_registered():
    assert "SCoRE" in jb.methods("joint_center")
    assert "SCoRE" in jb.methods("center")
    assert "SARA" in jb.methods("axis")


def test_best_rotation_matches_the_svd_solution():
    """poses.best_rotation (Horn/QCP, used by rigid_fit and rigid_poses) = Kabsch SVD."""
    from jointbench.numerics.poses import _kabsch_rotation, best_rotation

    rng = np.random.default_rng(12)
    # Random clusters and targets (3 and 5 markers), exact rotations up to pi, degenerate ones.
    for n_markers in (3, 5):
        source = rng.normal(scale=100.0, size=(n_markers, 3))
        target = rng.normal(scale=100.0, size=(400, n_markers, 3))
        cross = np.einsum("fmi,mj->fij", target - target.mean(1, keepdims=True), source)
        np.testing.assert_allclose(best_rotation(cross), _kabsch_rotation(cross), atol=1e-11)
    angles = np.concatenate([rng.uniform(0, np.pi, 200), [np.pi, np.pi - 1e-9, 0.0]])
    rotations = rotation_matrix(unit(rng.normal(size=(203, 3))) * angles[:, None])
    source = rng.normal(scale=100.0, size=(3, 3))
    source -= source.mean(0)
    cross = rotations @ (source.T @ source)
    np.testing.assert_allclose(best_rotation(cross), rotations, atol=1e-12)
    collinear = np.outer([1.0, 2.0, 3.0], [1.0, 0.0, 0.0])
    np.testing.assert_allclose(best_rotation(collinear), _kabsch_rotation(collinear), atol=1e-12)
    np.testing.assert_allclose(best_rotation(np.zeros((3, 3))), np.eye(3))


def test_rigid_fit_of_collinear_points_is_the_best_rotation():
    """Exactly collinear points make the largest eigenvalue of Horn's matrix a double root,
    which the summed squared lengths then equal: Newton's search must still end on it (or
    leave the matrix to the SVD), never on the negative double root, the worst rotation."""
    rng = np.random.default_rng(5)
    worst = 0.0
    for _ in range(2000):
        direction = unit(rng.normal(size=3))
        points = np.outer(rng.normal(scale=50.0, size=3), direction) + rng.normal(size=3)
        rotation, translation = rigid_fit(points, points[None])
        fitted = points @ rotation[0].T + translation[0]
        worst = max(worst, float(np.abs(fitted - points).max()))
    assert worst < 1e-9


def test_one_trial_call_checks_the_input_as_given():
    """The one-trial function is its many-trial form on a batch of one that holds the caller's
    array as given: a masked gap and complex coordinates are named, not converted away."""
    proximal, distal = two_segments(20)
    masked = np.ma.masked_array(distal, mask=np.zeros(distal.shape, dtype=bool))
    masked.mask[4, 1, 0] = True
    with pytest.raises(ValueError, match="distal is a masked array with masked values"):
        jb.estimators.twosegment.fit_score(proximal, masked)
    with pytest.raises(ValueError, match="markers is complex"):
        fit_sara(one_segment(hinge=True).astype(complex))


@pytest.mark.parametrize("method", ["SCoRE", "analytic", "SARA two-segment"])
def test_degenerate_trial_in_a_stack_fails_alone(method):
    """Trials are solved as one stack; a trial whose motion does not determine the answer
    carries the degenerate-motion error, and the others get what they get alone."""
    from jointbench.estimators import hjc, twosegment

    fits = {
        "SCoRE": twosegment._score_trials,
        "analytic": hjc._analytic_trials,
        "SARA two-segment": twosegment._sara_two_segment_trials,
    }
    fit = fits[method]
    ball, still = two_segments(40), two_segments(40, relative="none")
    trials = [
        (_noisy(ball[0], 1), _noisy(ball[1], 2)),
        still,
        (_noisy(ball[0], 3), _noisy(ball[1], 4)),
    ]
    outcomes = fit(*(np.stack(segment) for segment in zip(*trials, strict=True)))
    assert isinstance(outcomes[1], ValueError)
    assert "do not rotate relative to each other" in str(outcomes[1])
    for index in (0, 2):
        (alone,) = fit(*(segment[None] for segment in trials[index]))
        answer = "point" if method.startswith("SARA") else "center"
        np.testing.assert_array_equal(getattr(outcomes[index], answer), getattr(alone, answer))
        assert outcomes[index].diagnostics == alone.diagnostics


@pytest.mark.parametrize("checked", [True, False])
@pytest.mark.parametrize(("kind", "name"), [("center", "SCoRE"), ("axis", "SARA")])
def test_one_segment_poses_of_other_trials_are_refused(kind, name, checked):
    """The one-segment pose-based methods refuse poses fitted to other trials' markers, as the
    two-segment ones do, instead of answering about the other trials' motion."""
    from jointbench.estimators import registry
    from jointbench.estimators.segment_poses import trial_poses

    markers = np.stack([_noisy(one_segment(hinge=kind == "axis"), seed) for seed in range(3)])
    poses = trial_poses({"markers": markers}, min_frames=3)
    many = registry.many(kind, name, checked=checked)
    assert [r.center if kind == "center" else r.direction for r in many(markers, poses=poses)]
    with pytest.raises(ValueError, match=r"^poses: trial 0's markers poses were not fitted"):
        many(markers, poses=poses[::-1])
