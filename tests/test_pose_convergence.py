"""A pose fit that stops short says so, and poses that converged do not depend on frame order.

Paper C §5's alternation of SVD poses and body-fixed coordinates converges in a few
iterations on a well-spread cluster, linearly and slowly on one that is thin or small against
its noise. Stopped short, its poses are not the least-squares ones and depend on the frame it
started from, so every answer from them moves with the order of the frames: each pose-based
method must then report ``converged=False``, naming the segment. Converged, the poses are the
least-squares ones whatever the first frame, and so is what the support verdict and SCoRE
read from them. Coordinates far from the origin round every change of the body-fixed
coordinates to a multiple of their last place: the fit must still see when it has converged.
"""

from __future__ import annotations

import dataclasses
import functools
import pickle
from pathlib import Path

import numpy as np
import pytest
from test_support_frame_order import _assert_same_verdict, _orders
from test_support_sweep import TRIALS as SWEEP

import jointbench
from jointbench.estimators import support
from jointbench.estimators.registry import many
from jointbench.estimators.segment_poses import trial_poses
from jointbench.numerics.poses import fit_rigid_poses

KNEE = Path(__file__).resolve().parents[1] / "data" / "functional-trials" / "right_knee.c3d"
THIGH = ["RTHI1", "RTHI2", "RTHI3", "RGT"]

TWO_SEGMENTS = [arrays for kind, arrays in SWEEP if kind == "joint_center"]


def _converged(arrays: tuple[np.ndarray, ...]) -> bool:
    return all(bool(fit_rigid_poses(markers).converged) for markers in arrays)


# The sweep's trials in their recorded order are fitted and judged once per process: several
# tests pick their trials by these pure results (a pass over the sweep costs seconds), and
# each test still fits and judges for itself what it checks.
@functools.cache
def _clusters_converged(index: int) -> tuple[bool, ...]:
    """Whether each cluster's pose fit of two-segment trial ``index``, frames as recorded,
    converged (proximal, distal)."""
    return tuple(bool(fit_rigid_poses(markers).converged) for markers in TWO_SEGMENTS[index])


@functools.cache
def _recorded_verdict(index: int) -> support.Support:
    """The support verdict of two-segment trial ``index``, frames as recorded."""
    return support.assess("joint_center", TWO_SEGMENTS[index])


@pytest.fixture(scope="module")
def thigh() -> np.ndarray:
    """The real knee trial's thigh cluster in its visible frames, ``(N, 4, 3)`` [mm]."""
    recording = jointbench.read(KNEE)
    markers = recording.markers[:, [recording.labels.index(label) for label in THIGH]]
    return markers[np.isfinite(markers).all(axis=(1, 2))]


@pytest.mark.parametrize("metres", [5.0, 10.0, 20.0, 50.0])
def test_a_laboratory_origin_metres_away_converges_as_at_the_markers(thigh, metres):
    near = fit_rigid_poses(thigh)
    far = fit_rigid_poses(thigh + 1000.0 * metres * np.array([1.0, -0.6, 0.3]))
    assert far.iterations <= near.iterations + 1, (near.change_mm, far.change_mm)
    assert near.converged and far.converged


def test_the_sweep_has_both_kinds_of_two_segment_trial():
    converged = [all(_clusters_converged(index)) for index in range(len(TWO_SEGMENTS))]
    assert sum(converged) >= 100 and len(converged) - sum(converged) >= 100


def test_every_pose_based_method_says_when_its_poses_did_not_converge():
    """Trials whose alternation stops short, through every pose-based method's many-trial
    form, checked and bare."""
    judged = [
        arrays
        for index, arrays in enumerate(TWO_SEGMENTS)
        if not all(_clusters_converged(index))
        and "collinear" not in " ".join(_recorded_verdict(index).warnings)
    ]
    assert len(judged) >= 20
    methods = jointbench.methods("joint_center")
    assert {"SCoRE", "analytic", "gauss-markov"} <= set(methods)
    answered = 0
    for arrays in judged[:20]:
        poses = trial_poses({"proximal": arrays[0][None], "distal": arrays[1][None]}, min_frames=3)[
            0
        ]
        if isinstance(poses, ValueError):
            continue
        names = [name for name in ("proximal", "distal") if poses[name].converged is False]
        for method in methods:
            for checked in (True, False):
                (result,) = many("joint_center", method, checked=checked)(
                    arrays[0][None], arrays[1][None]
                )
                if isinstance(result, BaseException):
                    continue
                answered += 1
                assert not result.converged, (method, result.status)
                assert result.status.startswith("did not converge: "), result.status
                for name in names:
                    assert f"the {name} markers' pose fit stopped after" in result.status
    assert answered >= 20 * len(methods)


def test_one_segment_pose_methods_say_when_their_poses_did_not_converge():
    stopped = [
        markers
        for index, arrays in enumerate(TWO_SEGMENTS)
        for markers, converged in zip(arrays, _clusters_converged(index), strict=True)
        if not converged
    ]
    tried = 0
    for markers in stopped[:30]:
        for kind, method in (("center", "SCoRE"), ("axis", "SARA")):
            (result,) = many(kind, method, checked=False)(markers[None])
            if isinstance(result, BaseException):
                continue
            tried += 1
            assert not result.converged, result.status
            assert result.status.startswith("did not converge: the markers' pose fit"), (
                result.status
            )
    assert tried >= 20


def test_converged_poses_give_results_that_say_nothing_of_them():
    done = [arrays for index, arrays in enumerate(TWO_SEGMENTS) if all(_clusters_converged(index))]
    done = done[:20]
    answered = 0
    for arrays in done:
        (result,) = many("joint_center", "SCoRE", checked=False)(arrays[0][None], arrays[1][None])
        if not isinstance(result, BaseException):
            answered += 1
            assert result.converged and "pose fit" not in result.status
    assert answered >= 15


def _rigid_and_converged() -> list[tuple[np.ndarray, ...]]:
    """The sweep's two-segment trials whose clusters are rigid and spread out (a rigid-body
    fit leaves under 1 % of their scatter; the thinner extent of each cluster's mean shape
    at least 2 % of the largest, so that rounding does not dominate the pose about its long
    axis) and whose poses converge in their recorded order and every other tried."""
    found = []
    for index, arrays in enumerate(TWO_SEGMENTS):
        verdict = _recorded_verdict(index)
        if (
            verdict.diagnostics.get("nonrigid_share", 1.0) >= 0.01
            or min(map(_thinness, arrays)) < 0.02
        ):
            continue
        if all(_clusters_converged(index)) and all(
            _converged(tuple(m[order] for m in arrays))
            for order in _orders(arrays[0].shape[0], index)
        ):
            found.append((index, arrays))
    return found


def _thinness(markers: np.ndarray) -> float:
    """The mean shape's second extent over its first (singular values of the centred shape)."""
    shape = markers.mean(axis=0)
    values = np.linalg.svd(shape - shape.mean(axis=0), compute_uv=False)
    return float(values[1] / values[0])


@pytest.fixture(scope="module")
def settled() -> list[tuple[int, tuple[np.ndarray, ...]]]:
    return _rigid_and_converged()


def test_the_two_segment_verdict_on_converged_poses_ignores_the_order_of_the_frames(settled):
    assert len(settled) >= 40
    for index, arrays in settled:
        expected = support.assess("joint_center", arrays)
        for order in _orders(arrays[0].shape[0], index):
            found = support.assess("joint_center", tuple(markers[order] for markers in arrays))
            try:
                _assert_same_verdict(found, expected)
            except AssertionError as error:
                raise AssertionError(f"trial {index}: {error}") from error


def test_score_on_converged_poses_puts_the_joint_where_any_frame_order_does(settled):
    """SCoRE gives the joint in the proximal body frame of the first frame
    (``center_proximal``); in the world, at any one recorded frame, it must not depend on
    which frame came first."""
    fit = many("joint_center", "SCoRE", checked=False)
    compared = 0
    for index, arrays in settled:
        (expected,) = fit(arrays[0][None], arrays[1][None])
        if isinstance(expected, BaseException):
            continue
        world = _in_world(arrays[0], expected)
        for order in _orders(arrays[0].shape[0], index):
            (found,) = fit(arrays[0][order][None], arrays[1][order][None])
            # Rounding of the converged poses, amplified by how well the motion determines
            # the centre (rcond, the normal matrix's eigenvalue ratio).
            tolerance = 1e-9 * (1.0 + float(np.abs(world).max())) / expected.diagnostics["rcond"]
            np.testing.assert_allclose(
                _in_world(arrays[0][order], found), world[order], rtol=0, atol=tolerance
            )
        compared += 1
    assert compared >= 40


def _in_world(proximal: np.ndarray, result) -> np.ndarray:
    """SCoRE's proximal centre in the world in every frame, ``(N, 3)`` [mm]."""
    (poses,) = trial_poses({"proximal": proximal[None]}, min_frames=3)
    centre = np.asarray(result.diagnostics["center_proximal"])
    return poses["proximal"].rotation @ centre + poses["proximal"].translation


def test_poses_keep_how_their_fit_ended_and_refuse_half_a_record(thigh):
    (poses,) = trial_poses({"markers": thigh[None]}, min_frames=3)
    pose = poses["markers"]
    fit = fit_rigid_poses(thigh)
    assert (pose.iterations, pose.change_mm, pose.converged) == (
        int(fit.iterations),
        float(fit.change_mm),
        True,
    )
    assert pickle.loads(pickle.dumps(pose)).change_mm == pose.change_mm
    assert dataclasses.replace(pose, iterations=None, change_mm=None).converged is None
    for iterations, change_mm in ((None, 1e-13), (5, None), (0, 1e-13), (True, 1e-13), (5, -1.0)):
        with pytest.raises(ValueError, match="must be both None or a count >= 1"):
            dataclasses.replace(pose, iterations=iterations, change_mm=change_mm)
    assert dataclasses.replace(pose, change_mm=1e-6).converged is False
    assert dataclasses.replace(pose, change_mm=0).converged is True
