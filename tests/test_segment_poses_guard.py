"""A segment's poses cannot be altered after their fit: their arrays are read-only and shared
with no caller, and poses rebuilt with other rotations, translations or body coordinates than
those that leave their stored residual on their markers are refused when built."""

from __future__ import annotations

import copy
import dataclasses
import pickle

import numpy as np
import pytest
from rigs import two_segments

from jointbench.estimators import hjc, registry, segment_poses
from jointbench.estimators.segment_poses import POSE_MIN_FRAMES, SegmentPoses, trial_poses
from jointbench.numerics.poses import fit_rigid_poses
from jointbench.resultfiles import parquet

FIELDS = ("markers", "rotation", "translation", "body")
ALTERED = "leave a residual of .* mm\\^2 on their markers, not the .* mm\\^2 they were fitted with"


def _segments(n_trials: int = 2, n_frames: int = 60) -> dict[str, np.ndarray]:
    """Noisy ball-joint trials, ``(n_trials, n_frames, 3, 3)`` [mm] per segment."""
    rng = np.random.default_rng(0)
    ball = two_segments(n_frames)
    return {
        name: markers + rng.normal(scale=0.5, size=(n_trials, *markers.shape))
        for name, markers in zip(("proximal", "distal"), ball, strict=True)
    }


def _fitted(segments=None) -> list[dict[str, SegmentPoses]]:
    fitted = trial_poses(_segments() if segments is None else segments, min_frames=POSE_MIN_FRAMES)
    assert all(isinstance(trial, dict) for trial in fitted)
    return fitted


def _other(pose: SegmentPoses, field: str) -> np.ndarray:
    """``field`` of ``pose`` as another fit could not have left it: frames out of order for the
    per-frame poses, the body-fixed coordinates moved."""
    value = getattr(pose, field)
    return value[::-1].copy() if field in ("rotation", "translation") else value + 1.0


@pytest.mark.parametrize("field", FIELDS)
def test_a_poses_array_cannot_be_edited_in_place(field):
    pose = _fitted()[0]["distal"]
    array = getattr(pose, field)
    kept = array.copy()
    with pytest.raises(ValueError, match="read-only"):
        array[0] = array[-1]
    with pytest.raises(ValueError, match="read-only"):
        array += 1.0
    np.testing.assert_array_equal(getattr(pose, field), kept)


def test_an_edited_rotation_cannot_reach_a_fit():
    """The edit of the task's example, ``rotation[5] = another frame's``, fails before any fit
    reads it, and the fit answers as on the untouched poses."""
    segments = _segments()
    poses = _fitted(segments)
    fit = registry.many("joint_center", "SCoRE")
    before = fit(segments["proximal"], segments["distal"], poses=poses)
    with pytest.raises(ValueError, match="read-only"):
        poses[0]["distal"].rotation[5] = poses[0]["distal"].rotation[40]
    after = fit(segments["proximal"], segments["distal"], poses=poses)
    np.testing.assert_array_equal(after[0].center, before[0].center)


@pytest.mark.parametrize("field", ["rotation", "translation", "body"])
def test_poses_replaced_with_other_arrays_are_refused(field):
    pose = _fitted()[0]["distal"]
    with pytest.raises(ValueError, match=f"{ALTERED}: they were altered after their fit"):
        dataclasses.replace(pose, **{field: _other(pose, field)})


@pytest.mark.parametrize("field", ["rotation", "translation", "body"])
def test_poses_built_by_hand_with_other_arrays_are_refused(field):
    pose = _fitted()[0]["proximal"]
    parts = {name: getattr(pose, name) for name in FIELDS}
    parts[field] = _other(pose, field)
    with pytest.raises(ValueError, match=ALTERED):
        SegmentPoses(**parts, residual_ss=pose.residual_ss, dof=pose.dof)


def test_poses_that_leave_no_finite_residual_are_refused():
    pose = _fitted()[0]["distal"]
    rotation = pose.rotation.copy()
    rotation[3, 0, 0] = np.nan
    with pytest.raises(ValueError, match="residual of nan mm\\^2"):
        dataclasses.replace(pose, rotation=rotation)


@pytest.mark.parametrize(
    ("field", "value", "wrong"),
    [
        (
            "rotation",
            lambda p: p.rotation[1:],
            "rotation is shaped \\(59, 3, 3\\), not \\(60, 3, 3\\)",
        ),
        ("translation", lambda p: p.translation[:, :2], "translation is shaped \\(60, 2\\)"),
        ("body", lambda p: p.body[:2], "body is shaped \\(2, 3\\), not \\(3, 3\\)"),
        ("markers", lambda p: p.markers[:, :2], "markers is shaped \\(60, 2, 3\\)"),
        ("dof", lambda p: p.dof + 1, f"dof is {3 * 1 * 59 + 1}, not the {3 * 1 * 59}"),
    ],
)
def test_parts_that_do_not_fit_the_markers_are_refused(field, value, wrong):
    pose = _fitted()[0]["distal"]
    with pytest.raises(ValueError, match=wrong):
        dataclasses.replace(pose, **{field: value(pose)})


@pytest.mark.parametrize("relative", [1e-9, -1e-9])
def test_a_residual_off_by_rounding_is_accepted(relative):
    pose = _fitted()[0]["distal"]
    rounded = dataclasses.replace(pose, residual_ss=pose.residual_ss * (1.0 + relative))
    assert rounded.residual_ss == pose.residual_ss * (1.0 + relative)


def test_noise_free_poses_accept_a_residual_of_zero():
    """Noise-free markers leave a residual of rounding alone, which a stored 0 may stand for."""
    proximal, distal = two_segments(60)
    pose = _fitted({"proximal": proximal[None], "distal": distal[None]})[0]["distal"]
    assert pose.residual_ss < 1e-12
    assert dataclasses.replace(pose, residual_ss=0.0).residual_ss == 0.0


def test_callers_markers_stay_writeable_and_apart_from_the_poses():
    segments = _segments()
    pose = _fitted(segments)[0]["distal"]
    markers = segments["distal"][0].copy()
    by_hand = SegmentPoses(
        markers, pose.rotation, pose.translation, pose.body, pose.residual_ss, pose.dof
    )
    for array in (*segments.values(), markers):
        assert array.flags.writeable
    markers[4] += 1.0
    segments["distal"][0, 4] += 1.0
    np.testing.assert_array_equal(by_hand.markers, pose.markers)
    assert not np.array_equal(pose.markers, segments["distal"][0])


def test_poses_read_back_from_a_file_are_the_fitted_ones_and_read_only(tmp_path):
    segments = _segments(3)
    fitted = _fitted(segments)
    path = tmp_path / "poses.parquet"
    parquet.write_poses_blocks(
        path, [fitted[:2], fitted[2:]], shapes={k: v.shape for k, v in segments.items()}
    )
    stored = parquet.read_poses(path, 0, segments)
    for trial, name in ((0, "proximal"), (2, "distal")):
        a, b = fitted[trial][name], stored[trial][name]
        for field in FIELDS:
            np.testing.assert_array_equal(getattr(b, field), getattr(a, field))
            assert not getattr(b, field).flags.writeable
        assert (b.residual_ss, b.dof) == (a.residual_ss, a.dof)
    assert all(markers.flags.writeable for markers in segments.values())
    # An edit of the dataset's markers after the read reaches no poses read from them.
    kept = stored[1]["distal"].markers.copy()
    segments["distal"][1, 7] += 2.0
    np.testing.assert_array_equal(stored[1]["distal"].markers, kept)


def _three_ways(tmp_path) -> dict[str, SegmentPoses]:
    """The same segment's poses as fitted, as read back from a file, and as built by hand."""
    segments = _segments()
    fitted = _fitted(segments)
    path = tmp_path / "poses.parquet"
    parquet.write_poses_blocks(path, [fitted], shapes={k: v.shape for k, v in segments.items()})
    pose = fitted[0]["distal"]
    parts = {name: getattr(pose, name).copy() for name in FIELDS}
    return {
        "fitted": pose,
        "read": parquet.read_poses(path, 0, segments)[0]["distal"],
        "by hand": SegmentPoses(**parts, residual_ss=pose.residual_ss, dof=pose.dof),
    }


@pytest.mark.parametrize("made", ["fitted", "read", "by hand"])
@pytest.mark.parametrize("field", FIELDS)
def test_a_poses_array_cannot_be_made_writeable_again(tmp_path, made, field):
    array = getattr(_three_ways(tmp_path)[made], field)
    with pytest.raises(ValueError, match="WRITEABLE"):
        array.setflags(write=True)
    with pytest.raises(ValueError, match="WRITEABLE"):
        array.flags.writeable = True


@pytest.mark.parametrize("made", ["fitted", "read", "by hand"])
@pytest.mark.parametrize("field", FIELDS)
def test_no_array_under_a_poses_array_can_be_made_writeable(tmp_path, made, field):
    """Not the array's ``base`` either, through which an edit would reach the poses."""
    array = getattr(_three_ways(tmp_path)[made], field)
    kept = array.copy()
    under = array.base
    while isinstance(under, np.ndarray):
        with pytest.raises(ValueError, match="WRITEABLE"):
            under.setflags(write=True)
        under = under.base
    np.testing.assert_array_equal(array, kept)


def _in_another_body_frame(pose: SegmentPoses, turn: float, shift: np.ndarray) -> SegmentPoses:
    """The same motion with the body frame turned by ``turn`` [rad] about z and moved by
    ``shift`` [mm]: rotation ``R Q'``, body ``Q b + v``, translation ``t - R Q' v``, which
    leave the same residual on the markers."""
    c, s = np.cos(turn), np.sin(turn)
    q = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    rotation = pose.rotation @ q.T
    return dataclasses.replace(
        pose,
        rotation=rotation,
        body=pose.body @ q.T + shift,
        translation=pose.translation - rotation @ shift,
    )


@pytest.mark.parametrize("segment", ["proximal", "distal"])
@pytest.mark.parametrize(("turn", "shift"), [(0.4, (30.0, -20.0, 10.0)), (0.0, (0.0, 0.0, 1e-3))])
def test_poses_in_another_body_frame_are_refused(segment, turn, shift):
    """Paper C's fits read the body-fixed coordinates, and answered 17 to 59 mm away in
    another body frame, with status "ok"."""
    pose = _fitted()[0][segment]
    with pytest.raises(ValueError, match="not the world at frame 0"):
        _in_another_body_frame(pose, turn, np.array(shift))


@pytest.mark.parametrize("how", ["deepcopy", "pickle"])
def test_copied_poses_are_checked_and_read_only(how):
    pose = _fitted()[0]["distal"]
    copied = copy.deepcopy(pose) if how == "deepcopy" else pickle.loads(pickle.dumps(pose))
    for field in FIELDS:
        np.testing.assert_array_equal(getattr(copied, field), getattr(pose, field))
        with pytest.raises(ValueError, match="read-only"):
            getattr(copied, field)[0] = 0.0
    assert (copied.residual_ss, copied.dof) == (pose.residual_ss, pose.dof)


def test_a_callers_read_only_array_made_writeable_again_does_not_reach_the_poses():
    pose = _fitted()[0]["distal"]
    rotation = pose.rotation.copy()
    rotation.setflags(write=False)
    by_hand = SegmentPoses(
        pose.markers, rotation, pose.translation, pose.body, pose.residual_ss, pose.dof
    )
    rotation.setflags(write=True)
    rotation[5] = rotation[40]
    np.testing.assert_array_equal(by_hand.rotation, pose.rotation)


def test_poses_of_no_numbers_are_refused():
    pose = _fitted()[0]["distal"]
    with pytest.raises(ValueError, match="body is no array of numbers"):
        dataclasses.replace(pose, body="coordinates")
    with pytest.raises(ValueError, match="residual_ss is 'small', not a number"):
        dataclasses.replace(pose, residual_ss="small")


def test_fresh_poses_that_leave_no_finite_residual_are_refused():
    """Poses given without their residual, whose residual is then computed, must leave a
    number on their markers: a gap in the markers leaves none."""
    pose = _fitted()[0]["distal"]
    markers = pose.markers.copy()
    markers[9, 1] = np.nan
    with pytest.raises(ValueError, match="leave a residual of nan mm\\^2 on their markers"):
        SegmentPoses(markers, pose.rotation, pose.translation, pose.body)


@pytest.mark.parametrize("stored", [np.inf, -np.inf, np.nan])
def test_a_stored_residual_that_is_no_finite_number_is_refused(stored):
    pose = _fitted()[0]["distal"]
    with pytest.raises(ValueError, match=f"not the {stored} mm\\^2 they were fitted with"):
        dataclasses.replace(pose, residual_ss=stored)


def test_a_dof_that_is_no_number_is_refused():
    pose = _fitted()[0]["distal"]
    with pytest.raises(ValueError, match="dof is \\[177 177\\], not the 177"):
        dataclasses.replace(pose, dof=np.array([177, 177]))


@pytest.mark.parametrize("max_iterations", [1, 2, 3])
def test_a_pose_fit_stopped_by_its_iteration_limit_is_anchored_at_frame_0(max_iterations):
    """Its last poses are fitted to a body that was still moving: they are put in the body
    frame that is the world at frame 0, with the residual they leave unchanged."""
    segments = _segments(n_trials=3)
    fit = fit_rigid_poses(segments["distal"], max_iterations=max_iterations, tol_mm=0.0)
    assert np.all(fit.iterations == max_iterations)
    np.testing.assert_allclose(
        fit.rotation[:, 0], np.broadcast_to(np.eye(3), (3, 3, 3)), atol=1e-12
    )
    np.testing.assert_allclose(fit.translation[:, 0], 0.0, atol=1e-9)
    for trial in range(3):
        SegmentPoses(
            segments["distal"][trial], fit.rotation[trial], fit.translation[trial], fit.body[trial]
        )


def test_the_model_test_reads_the_residuals_the_poses_leave():
    """The residuals ``x_fi - (R_f b_i + t_f)`` the poses leave on their markers are formed
    in one place (:func:`segment_poses._pose_residuals`), its compiled part and its Python
    source alike: their sum of squares is the poses' ``residual_ss``, the sum of their
    lengths' fourth powers the poses' ``residual_fourths``, which paper C's model test reads
    the noise's kurtosis from."""
    proximal, _ = two_segments(30)
    rng = np.random.default_rng(4)
    markers = proximal + rng.normal(scale=0.5, size=proximal.shape)
    (poses,) = trial_poses({"markers": [markers]}, min_frames=POSE_MIN_FRAMES)
    poses = poses["markers"]
    explicit = markers - np.einsum("fij,mj->fmi", poses.rotation, poses.body)
    explicit = explicit - poses.translation[:, None, :]
    fourths = np.sum(np.sum(explicit**2, axis=-1) ** 2)
    residuals, summed = segment_poses._pose_residuals(
        poses.markers, poses.rotation, poses.translation, poses.body
    )
    np.testing.assert_allclose(residuals, explicit, atol=1e-9)
    assert summed == pytest.approx(fourths, rel=1e-12)
    assert poses.residual_ss == float(np.sum(residuals * residuals))
    assert poses.residual_fourths == summed
    turned = poses.rotation.reshape(-1, 3) @ poses.body.T
    python = segment_poses._less_turned.__wrapped__(poses.markers, turned, poses.translation)
    np.testing.assert_array_equal(python[0], residuals)
    assert python[1] == pytest.approx(summed, rel=1e-12)
    variance = poses.residual_ss / poses.dof
    kurtosis, _ = hjc._noise_kurtosis((poses,), variance)
    n_frames = len(markers)
    shrink = (n_frames - 1) / n_frames
    own, shared = hjc._residual_moments(poses.body)
    expected = (fourths / variance**2 - n_frames * shrink**2 * own) / (
        n_frames * shrink**4 * shared
    )
    assert kurtosis == pytest.approx(expected, rel=1e-12)
