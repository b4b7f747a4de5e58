"""How far the noise in two segments' poses pulls a joint centre
(:mod:`jointbench.estimators.pose_noise`, held to every checked joint-centre call by
:func:`jointbench.estimators.centre_precision.annotate_joint_centres`): the pull against the
mean error over noise draws, answers it must not pass as found (nearly hinged motion, a small
swing, nearly collinear markers), motions it must pass, noise-free data and invariances."""

from __future__ import annotations

import numpy as np
import pytest

import jointbench
from jointbench.estimators import centre_precision, support
from jointbench.estimators import pose_noise as pose_noise_module
from jointbench.estimators.pose_noise import NoisyPoses, pose_noise, pull_mm
from jointbench.estimators.results import JointCenterResult
from jointbench.geometry import rotation_about_axis, rotation_matrix

CENTRE = np.array([10.0, -20.0, 5.0])
# Where the thigh's and the pelvis's markers lie about the joint [mm].
_THIGH = np.array([150.0, 0.0, 30.0])
_PELVIS = np.array([0.0, 0.0, 120.0])
_METHODS = ("SCoRE", "analytic", "gauss-markov", "gauss-markov-frame0")
_PULLED = "the noise in the poses"


def _hip(
    geometry: int,
    *,
    ratio: float,
    rom_deg: float = 30.0,
    n_frames: int = 60,
    spreads_mm: tuple[float, float] = (40.0, 20.0),
) -> tuple:
    """Noise-free pelvis and thigh markers ``(N, 4, 3)`` each [mm], both moving in the world:
    a flexion of ``rom_deg`` about an axis tilted from z, with a rotation about x of ``ratio``
    times its amplitude at another frequency beside it (0.06: nearly a hinge; 1.0 with a small
    ``rom_deg``: a small two-axis swing). The markers are drawn from ``geometry``, scattered by
    ``spreads_mm`` (pelvis, thigh) about points 120 mm (pelvis) and 150 mm (thigh) from the
    joint."""
    rng = np.random.default_rng(geometry)
    t = np.linspace(0.0, 1.0, n_frames)
    amplitude = np.radians(rom_deg)
    flexion = amplitude * np.sin(2 * np.pi * t)
    second = ratio * amplitude * np.sin(2 * np.pi * 2.3 * t + 1.0)
    joint = rotation_matrix(np.column_stack([second, 0.3 * flexion, flexion]))
    thigh = rng.normal(scale=spreads_mm[1], size=(4, 3)) + _THIGH
    pelvis = rng.normal(scale=spreads_mm[0], size=(4, 3)) + _PELVIS
    pelvis_motion = rotation_matrix(
        np.radians(10.0) * np.column_stack([np.sin(8 * t), np.sin(4 * t), np.sin(2.5 * t)])
    )
    origin = 30.0 * np.column_stack([np.sin(3 * t), np.sin(2 * t), t]) + CENTRE
    proximal = np.einsum("kij,pj->kpi", pelvis_motion, pelvis) + origin[:, None]
    distal = np.einsum("kij,kjl,pl->kpi", pelvis_motion, joint, thigh) + origin[:, None]
    return proximal, distal


def _noisy(segments: tuple, seed: int, noise_mm=0.5) -> tuple:
    """``segments`` with normal noise of SD ``noise_mm`` [mm]: one for all, or one per segment,
    each a number or a per-axis ``(3,)``."""
    rng = np.random.default_rng(seed)
    per_segment = noise_mm if isinstance(noise_mm, tuple) else (noise_mm,) * len(segments)
    return tuple(
        array + rng.normal(size=array.shape) * np.asarray(sd)
        for array, sd in zip(segments, per_segment, strict=True)
    )


def second_axes_resolved(spreads_mm: tuple, noise_mm: tuple, n_draws: int) -> int:
    """On pure hinges (:func:`_hip` of 10 geometries, markers scattered by ``spreads_mm``,
    ``n_draws`` draws of noise ``noise_mm`` each), how many times the support verdict resolves
    rotation off the hinge at its level."""
    resolved = 0
    for geometry in range(10):
        clean = _hip(geometry, ratio=0.0, spreads_mm=spreads_mm)
        for seed in range(n_draws):
            verdict = support.assess("joint_center", _noisy(clean, seed, noise_mm))
            resolved += verdict.diagnostics["off_axis_p_value"] < support.ROTATION_ALPHA
    return resolved


def _status(segments: tuple, method: str):
    return jointbench.fit_joint_center(*segments, method=method)


def errors_and_pulls(clean: tuple, n_draws: int) -> tuple[np.ndarray, np.ndarray]:
    """SCoRE's errors and the pulls at its answers ``(n_draws, 3)`` each [mm], over draws of
    0.5 mm noise on the segments ``clean``."""
    errors, pulls = [], []
    for seed in range(n_draws):
        segments = _noisy(clean, seed)
        verdict = support.assess("joint_center", segments)
        answer = jointbench.fit_joint_center(*segments, method="SCoRE").center
        errors.append(answer - CENTRE)
        pulls.append(pull_mm(verdict.pose_noise, answer))
    return np.array(errors), np.array(pulls)


def test_the_pull_is_the_mean_error_of_a_least_squares_centre():
    """Over 80 noise draws of one near-hinge (a second rotation of 15 % of the flexion), the
    mean pull at SCoRE's answers equals SCoRE's mean error, vector for vector, to a fifth of
    it and three standard errors; the error is mostly that bias (its mean is several times its
    scatter over the draws' standard error)."""
    errors, pulls = errors_and_pulls(_hip(0, ratio=0.15), 80)
    mean_error, mean_pull = errors.mean(axis=0), pulls.mean(axis=0)
    standard_error = np.linalg.norm(errors.std(axis=0)) / np.sqrt(len(errors))
    assert np.linalg.norm(mean_error) > 5.0 * standard_error
    assert np.linalg.norm(mean_pull - mean_error) <= (
        0.2 * np.linalg.norm(mean_error) + 3.0 * standard_error
    )


@pytest.mark.parametrize(("ratio", "rom_deg"), [(0.06, 30.0), (1.0, 3.0)])
def test_a_centre_the_poses_noise_pulled_is_not_ok(ratio, rom_deg):
    """Nearly a hinge (a second rotation of 6 % of a 30 deg flexion) and a 3 deg two-axis
    swing, 0.5 mm noise: every method's answer lies tens of millimetres off, and none reads
    ``ok``. Where the support verdict finds the rotation off the main axis resolved (in most
    geometries), the pull is what says so."""
    passed_by_the_verdict = 0
    for geometry in range(6):
        segments = _noisy(_hip(geometry, ratio=ratio, rom_deg=rom_deg), 100 + geometry)
        refused = support.assess("joint_center", segments).warnings
        passed_by_the_verdict += not refused
        for method in _METHODS:
            result = _status(segments, method)
            assert result.status != "ok", (geometry, method)
            if not refused:
                assert _PULLED in result.status, (geometry, method, result.status)
    assert passed_by_the_verdict >= 4


def test_a_pull_beyond_the_answers_sd_is_not_ok():
    """Nearly a hinge (a second rotation of a fifth of a 30 deg flexion), 0.5 mm noise, in the
    two geometries where the share and the pull stay under their own bounds: the pull, a
    bias its SD does not hold, is still over ``MAX_STEP_SDS`` of that SD and over
    ``MIN_POSE_NOISE_PULL_MM`` (answers read ``ok`` up to 8 mm off, three of their SDs, before
    this was held). Every answer so pulled says so, and none reads ``ok``."""
    pulled_beyond_sd = 0
    for geometry in (3, 5):
        segments = _noisy(_hip(geometry, ratio=0.2), 400 + geometry)
        refused = support.assess("joint_center", segments).warnings
        for method in _METHODS:
            result = _status(segments, method)
            numbers = result.diagnostics
            if numbers["center_pose_noise_pull_mm"] >= max(
                centre_precision.MIN_POSE_NOISE_PULL_MM,
                centre_precision.MAX_STEP_SDS * numbers["center_sd_mm"],
            ):
                pulled_beyond_sd += 1
                assert result.status != "ok", (geometry, method)
                if not refused:
                    assert _PULLED in result.status, (geometry, method, result.status)
    assert pulled_beyond_sd >= 4


def test_a_centre_on_a_two_axis_swing_reads_ok():
    """A 30 deg swing about two axes, 0.5 mm noise: no answer is said to be pulled (the
    Gauss–Markov fits test their own model besides), and the noise takes under 2 % of the
    information along the least determined direction."""
    for geometry in range(6):
        segments = _noisy(_hip(geometry, ratio=1.0), 200 + geometry)
        for method in _METHODS:
            result = _status(segments, method)
            assert _PULLED not in result.status, (geometry, method, result.status)
            if method in ("SCoRE", "analytic"):
                assert result.status == "ok", (geometry, method, result.status)
            assert result.diagnostics["center_pose_noise_share"] < 0.02
            assert result.diagnostics["center_pose_noise_pull_mm"] < 2.0


def test_nearly_collinear_thigh_markers_are_not_ok():
    """Three thigh markers 3 mm off a 50 mm line, 0.5 mm noise, a 30 deg two-axis swing: where
    their pose about the line is still known to better than the verdict's limit, the noise it
    carries pulls SCoRE's and the analytic centre, and no answer more than 10 mm off reads
    ``ok``."""
    pulled = 0
    for geometry in range(8):
        rng = np.random.default_rng(geometry)
        proximal, distal = _hip(geometry, ratio=1.0)
        line = rng.normal(size=3)
        line /= np.linalg.norm(line)
        thin = np.outer([-25.0, 0.0, 25.0], line) + rng.normal(scale=3.0, size=(3, 3))
        segments = _noisy((proximal, _thin_thigh(distal, thin)), 300 + geometry)
        for method in ("SCoRE", "analytic"):
            result = _status(segments, method)
            pulled += _PULLED in result.status
            if np.linalg.norm(result.center - CENTRE) > 10.0:
                assert result.status != "ok", (geometry, method)
    assert pulled >= 6


def _thin_thigh(distal: np.ndarray, body: np.ndarray) -> np.ndarray:
    """``body`` ``(3, 3)`` [mm] placed 150 mm from the joint in the thigh, moved as the thigh
    markers ``distal`` ``(N, 4, 3)`` move."""
    reference = distal[0] - distal[0].mean(axis=0)
    placed = body + _THIGH + CENTRE
    moved = []
    for frame in distal:
        rotation = _kabsch(reference, frame - frame.mean(axis=0))
        moved.append((placed - distal[0].mean(axis=0)) @ rotation.T + frame.mean(axis=0))
    return np.array(moved)


def _kabsch(source: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The rotation taking the centred points ``source`` onto ``target`` ``(n, 3)``."""
    u, _, vt = np.linalg.svd(target.T @ source)
    sign = np.sign(np.linalg.det(u @ vt))
    return u @ np.diag([1.0, 1.0, sign]) @ vt


def test_each_segment_is_held_to_its_own_noise():
    """A wide pelvis cluster with 3 mm of noise and a compact thigh cluster with 0.1 mm, on a
    30 deg two-axis swing: the answers lie within a few millimetres and none is said to be
    pulled (the pelvis's noise, charged to the compact thigh, would make its poses look far
    noisier than they are). A noise-free pelvis and a compact thigh with 1 mm, a second
    rotation of 30 %: no answer more than 10 mm off reads ``ok``."""
    for geometry in (3, 4, 5):
        clean = _hip(geometry, ratio=1.0, spreads_mm=(60.0, 8.0))
        for seed in range(8):
            result = _status(_noisy(clean, seed, (3.0, 0.1)), "SCoRE")
            assert np.linalg.norm(result.center - CENTRE) < 8.0
            assert _PULLED not in result.status, (geometry, seed, result.status)
    for geometry in (0, 1, 2):
        clean = _hip(geometry, ratio=0.3, spreads_mm=(60.0, 10.0))
        for seed in range(8):
            result = _status(_noisy(clean, seed, (0.0, 1.0)), "SCoRE")
            if np.linalg.norm(result.center - CENTRE) > 10.0:
                assert result.status != "ok", (geometry, seed)


def test_noise_free_poses_pull_nothing():
    """Noise-free, even nearly a hinge: the share and the pull are rounding, the status ``ok``."""
    segments = _hip(0, ratio=0.06)
    for method in _METHODS:
        result = _status(segments, method)
        assert result.status == "ok"
        assert result.diagnostics["center_pose_noise_pull_mm"] < 1e-6
        assert result.diagnostics["center_pose_noise_share"] < 1e-9


def test_share_and_pull_do_not_depend_on_the_world_the_order_or_the_labels():
    """A rigid move of the world and each segment's markers relabelled leave the share and the
    pull at SCoRE's answer as they were (to 1e-6 relative); the frames reversed leave the
    share. Not the pull: SCoRE's answer is the midpoint at frame 0 of its two local points
    (here some millimetres apart along the hinge), which another first frame moves."""
    segments = _noisy(_hip(1, ratio=0.15), 7)
    axis = np.array([0.3, -0.5, 0.8])
    rotation = rotation_about_axis(axis / np.linalg.norm(axis), 1.1)
    variants = {
        "moved": tuple(array @ rotation.T + [400.0, -250.0, 900.0] for array in segments),
        "relabelled": tuple(array[:, ::-1] for array in segments),
        "reversed": tuple(array[::-1] for array in segments),
    }
    given = _status(segments, "SCoRE").diagnostics
    for name, arrays in variants.items():
        numbers = _status(arrays, "SCoRE").diagnostics
        for key in ("center_pose_noise_share", "center_pose_noise_pull_mm"):
            if key.endswith("pull_mm") and name == "reversed":
                continue
            assert numbers[key] == pytest.approx(given[key], rel=1e-6), (name, key)


def test_noise_that_takes_the_whole_rotation_off_the_axis_leaves_no_bound():
    """Poses whose noise is far beyond the rotation off a hinge: the share and the pull are
    ``inf`` and the warning says no bound holds."""
    n_frames = 60
    flexion = np.radians(30.0) * np.sin(np.linspace(0.0, 2.0 * np.pi, n_frames))
    distal = rotation_about_axis(np.array([0.0, 0.0, 1.0]), flexion)[None]
    body = np.array([[[100.0, 0.0, 0.0], [0.0, 100.0, 0.0], [0.0, 0.0, 100.0]]])
    centred = body - body.mean(axis=1, keepdims=True)
    inertia = np.einsum("tm,ij->tij", (centred**2).sum(-1), np.eye(3)) - np.einsum(
        "tmi,tmj->tij", centred, centred
    )
    segments = [
        NoisyPoses(rotation, body, np.linalg.inv(inertia), np.array([25.0]))
        for rotation in (np.broadcast_to(np.eye(3), distal.shape), distal)
    ]
    (noise,) = pose_noise(*segments)
    assert np.isinf(noise.share)
    assert np.isinf(pull_mm(noise, np.array([0.0, 0.0, 50.0]))).all()
    verdict = support.Support((), {}, pose_noise=noise)
    result = JointCenterResult(
        converged=True, iterations=1, status="ok", method="test", center=np.zeros(3)
    )
    (annotated,) = centre_precision.annotate_joint_centres([result], [verdict])
    assert "more than the data can bound" in annotated.status


def test_a_refusal_of_the_verdict_is_not_repeated():
    """A hinge with no rotation off its axis: the verdict refuses the data, and the pull is
    reported without a second warning."""
    segments = _noisy(_hip(2, ratio=0.0), 11)
    result = _status(segments, "SCoRE")
    assert "rotation about a single axis" in result.status
    assert _PULLED not in result.status
    assert "center_pose_noise_share" in result.diagnostics


def test_the_pose_noise_kernel_is_its_python_source_and_the_docstrings_formulas():
    """The compiled pose-noise numbers answer as their Python source, run as written, and as
    the module docstring's ``M``, ``B``, share and ``(M + B)^-1 B`` in NumPy, trial by trial,
    a trial whose noise takes all the information (share and operator ``inf``) among them."""
    rng = np.random.default_rng(3)
    n_trials, n_frames = 3, 25
    angles = rng.normal(scale=0.4, size=(2, n_trials, n_frames, 3))
    rotations = [
        rotation_matrix(a.reshape(-1, 3)).reshape(n_trials, n_frames, 3, 3) for a in angles
    ]
    bodies = rng.normal(scale=50.0, size=(2, n_trials, 4, 3))
    inertia_invs = []
    for body in bodies:
        centred = body - body.mean(axis=1, keepdims=True)
        inertia = np.einsum("tm,ij->tij", (centred**2).sum(-1), np.eye(3)) - np.einsum(
            "tmi,tmj->tij", centred, centred
        )
        inertia_invs.append(np.linalg.inv(inertia))
    variances = np.array([[0.3, 1.0, 4e4], [0.5, 2.0, 4e4]])
    segments = [
        NoisyPoses(rotations[s], bodies[s], inertia_invs[s], variances[s]) for s in range(2)
    ]
    compiled = pose_noise(*segments)
    arrays = [a for s in segments for a in s]
    python = pose_noise_module._pose_noise_numbers.__wrapped__(*arrays)
    for t, noise in enumerate(compiled):
        relative = np.einsum("fki,fkj->ij", rotations[0][t], rotations[1][t])
        g_p, g_d = (
            (v[t] * k[t] - np.trace(v[t] * k[t]) * np.eye(3)) / 2.0
            for v, k in zip(variances, inertia_invs, strict=True)
        )
        normal = np.block([[n_frames * np.eye(3), -relative], [-relative.T, n_frames * np.eye(3)]])
        attenuation = np.block(
            [[n_frames * g_p, relative @ g_d], [relative.T @ g_p, n_frames * g_d]]
        )
        corrected = normal + attenuation
        values, vectors = np.linalg.eigh((corrected + corrected.T) / 2.0)
        centroids = bodies[:, t].mean(axis=1)
        np.testing.assert_allclose(noise.centroids, centroids, rtol=1e-12)
        np.testing.assert_array_equal(python[1][t], noise.centroids)
        if values[0] <= 0.0:
            assert t == 2 and np.isinf(noise.share) and np.isinf(noise.operator).all()
            assert np.isinf(python[2][t]) and np.isinf(python[0][t]).all()
            continue
        share = -(vectors[:, 0] @ attenuation @ vectors[:, 0]) / values[0]
        operator = np.linalg.solve(corrected, attenuation)
        assert noise.share == pytest.approx(share, rel=1e-10) and noise.share > 0.0
        np.testing.assert_allclose(noise.operator, operator, rtol=1e-10, atol=1e-12)
        assert python[2][t] == pytest.approx(noise.share, rel=1e-12)
        np.testing.assert_allclose(python[0][t], noise.operator, rtol=1e-12, atol=1e-14)
    assert [np.isinf(noise.share) for noise in compiled] == [False, False, True]
