"""Paper C's analytic and Gauss–Markov joint centre, and the frame-0 extension."""

from __future__ import annotations

import contextlib
import dataclasses
import math

import numpy as np
import pytest
from rigs import HINGE, JOINT, PROXIMAL, two_segments
from scipy import stats

import jointbench as jb
from jointbench.configuration.seeds import trial_rng
from jointbench.estimators import hjc
from jointbench.estimators.hjc import (
    align_to_markers,
    fit_gauss_markov,
    point_covariance,
)
from jointbench.estimators.segment_poses import trial_poses
from jointbench.estimators.twosegment import eigen_solution
from jointbench.geometry import rotation_matrix, skew
from jointbench.numerics import reuse
from jointbench.numerics.poses import rigid_poses
from jointbench.simulate.hip import HipProtocol, marker_layout, nominal_recording, simulate
from jointbench.simulate.noise import isotropic_noise

METHODS = ("analytic", "gauss-markov", "gauss-markov-frame0")
CHI2_3_95 = stats.chi2(3).ppf(0.95)


def _noisy(markers, seed, sd=1.7):
    return markers + isotropic_noise(np.random.default_rng(seed), markers.shape[:2], sd)


@pytest.mark.parametrize("method", METHODS)
def test_noise_free_recovery(method):
    proximal, distal = two_segments()
    result = jb.fit_joint_center(proximal, distal, method=method)
    np.testing.assert_allclose(result.center, JOINT, atol=1e-9)
    assert result.converged and result.status == "ok" and result.method == method
    if method != "analytic":
        assert result.diagnostics["noise_mm"] < 1e-9
        assert np.sqrt(np.trace(result.covariance)) < 1e-9
        exact = jb.fit_joint_center(proximal, distal, method=method, noise_mm=0.0)
        np.testing.assert_array_equal(exact.covariance, np.zeros((3, 3)))
    else:
        assert result.covariance is None


def test_frame0_extension_noise_free_segment_centres():
    result = jb.fit_joint_center(*two_segments(), method="gauss-markov-frame0")
    np.testing.assert_allclose(result.diagnostics["center_proximal"], JOINT, atol=1e-9)
    np.testing.assert_allclose(result.diagnostics["center_distal"], JOINT, atol=1e-9)
    np.testing.assert_allclose(result.diagnostics["proximal_body"], PROXIMAL, atol=1e-9)


def test_point_covariance_matches_pennec_pose_covariance():
    """Closed form R A R' equals dh/dx W_f dh/dx' with W_f = (sum J'J)^-1, J = [-[Rx]x, I]."""
    rng = np.random.default_rng(0)
    body = rng.normal(scale=80.0, size=(4, 3)) + np.array([200.0, -50.0, 700.0])
    point = np.array([10.0, 40.0, 150.0])
    rotation = rotation_matrix(rng.normal(size=3))
    jacobians = np.concatenate(
        [-skew(body @ rotation.T), np.broadcast_to(np.eye(3), (4, 3, 3))], axis=2
    )
    pose_covariance = np.linalg.inv(np.einsum("mki,mkj->ij", jacobians, jacobians))
    dh_dx = np.concatenate([-skew(rotation @ point), np.eye(3)], axis=1)
    explicit = dh_dx @ pose_covariance @ dh_dx.T
    closed = rotation @ point_covariance(point, body) @ rotation.T
    np.testing.assert_allclose(closed, explicit, rtol=1e-10, atol=1e-12)
    # Two segments: the constraint covariance is the sum (paper C eq. 20 with eq. 12), and the
    # iteration weighs each frame by its inverse taken in the proximal body frame.
    other = rotation_matrix(rng.normal(size=3))
    a0, a1 = point_covariance(point, body), point_covariance(point, body[::-1] * 1.5)
    summed = rotation @ a0 @ rotation.T + other @ a1 @ other.T
    local = np.linalg.inv(rotation.T @ summed @ rotation)
    relative = (rotation.T @ other).reshape(9, 1)
    for form in (hjc._frame_weights, hjc._frame_weights.__wrapped__):
        weight = np.empty((6, 1))
        form(relative, np.stack([a0, a1]), weight)
        np.testing.assert_allclose(weight[:, 0], local[np.triu_indices(3)], rtol=1e-10)


def test_analytic_is_paper_eq9():
    """Eq. 9 as printed, with p = -R' d (eq. 7), equals the implementation."""
    proximal, distal = two_segments(100)
    proximal, distal = _noisy(proximal, 1), _noisy(distal, 2)
    r0, d0, _ = rigid_poses(proximal)
    r1, d1, _ = rigid_poses(distal)
    p0, p1 = -np.einsum("fji,fj->fi", r0, d0), -np.einsum("fji,fj->fi", r1, d1)
    r01 = np.swapaxes(r0, -1, -2) @ r1
    matrix = 2 * len(r0) * np.eye(3) - r01.sum(0) - np.swapaxes(r01, -1, -2).sum(0)
    vector = (p0 + p1 - np.einsum("fij,fj->fi", r01, p1) - np.einsum("fji,fj->fi", r01, p0)).sum(0)
    result = jb.fit_joint_center(proximal, distal, method="analytic")
    np.testing.assert_allclose(result.center, np.linalg.solve(matrix, vector), atol=1e-8)


def test_the_analytic_normal_equations_are_the_stacked_rows_product():
    """Eq. 9's sums from one pass over the frames (:func:`hjc._analytic_sums`) are ``M' M``
    and ``M' y`` of the frames' stacked rows ``M_t = R0 - R1``, ``y_t = d1 - d0`` (``t >= 1``),
    per trial of a stack as for one trial's own poses, and the centre solves them."""
    trials = [two_segments(40) for _ in range(2)]
    trials = [(_noisy(p, 2 * k), _noisy(d, 2 * k + 1)) for k, (p, d) in enumerate(trials)]
    poses = trial_poses(
        {"proximal": [p for p, _ in trials], "distal": [d for _, d in trials]}, min_frames=3
    )
    for trial in poses:
        prox, dist = trial["proximal"], trial["distal"]
        rows = (prox.rotation[1:] - dist.rotation[1:]).reshape(-1, 3)
        y = (dist.translation[1:] - prox.translation[1:]).reshape(-1)
        normal, rhs = hjc._analytic_sums(
            prox.rotation[None], dist.rotation[None], prox.translation[None], dist.translation[None]
        )
        np.testing.assert_allclose(normal[0], rows.T @ rows, rtol=1e-13, atol=1e-12)
        np.testing.assert_allclose(rhs[0], rows.T @ y, rtol=1e-13, atol=1e-9)
        centers, _, errors = hjc._analytic(prox, dist, "analytic")
        assert errors == [None]
        np.testing.assert_allclose(centers[0], np.linalg.solve(rows.T @ rows, rows.T @ y))


@pytest.mark.parametrize("relative", ["ball", "hinge", "none"])
def test_the_compiled_analytic_solution_is_the_eigen_solution(relative):
    """The compiled solve of eq. 9 (:func:`hjc._analytic_solution`) gives NumPy's eigenvalues
    to rounding, their ratio as ``rcond`` and the centre
    :func:`~jointbench.estimators.twosegment.eigen_solution` gives from them; a trial of
    degenerate motion gets its error and a finite centre no one reads."""
    proximal, distal = two_segments(60, relative=relative)
    poses = trial_poses({"proximal": [proximal], "distal": [distal]}, min_frames=3)[0]
    prox, dist = poses["proximal"], poses["distal"]
    arrays = [a[None] for a in (prox.rotation, dist.rotation, prox.translation, dist.translation)]
    centres, values, rcond = hjc._analytic_solution(*arrays)
    normal, rhs = hjc._analytic_sums(*arrays)
    expected_values, vectors = np.linalg.eigh(normal)
    # Two LAPACK builds (NumPy's, and SciPy's that the kernel calls) may round differently:
    # equal to a few units in the last place of the largest eigenvalue, not to the bit.
    rounding = 8 * np.finfo(float).eps * np.abs(expected_values[:, -1:])
    assert np.all(np.abs(values - expected_values) <= rounding)
    with np.errstate(divide="ignore", invalid="ignore"):
        np.testing.assert_array_equal(rcond, values[:, 0] / values[:, -1])
    expected = eigen_solution(vectors, expected_values, rhs)
    np.testing.assert_allclose(centres, expected, rtol=1e-13, atol=1e-12)
    assert np.isfinite(centres).all()
    (error,) = hjc._analytic(prox, dist, "analytic")[2]
    assert (error is None) == (relative == "ball")


def test_a_relative_rotation_within_the_rounding_of_each_frame_is_none():
    """Eq. 9's motion check reads the frames' count: a relative rotation whose normal matrix's
    largest eigenvalue is below :data:`hjc._NO_ROTATION` per frame (here 3e-9 rad, 4.5e-18 per
    frame: above that bound for one frame) is no rotation, for one trial's poses and for each
    trial of a stack, not a hinge."""
    n_frames = 60
    t = np.linspace(0.0, 4.0, n_frames)
    r0 = rotation_matrix(np.stack([0.3 * np.sin(t), 0.2 * np.sin(0.7 * t), 0.1 * t], -1))
    r1 = r0 @ rotation_matrix(3e-9 * np.sin(1.9 * t)[:, None] * HINGE)
    d0, d1 = np.zeros((n_frames, 3)), np.ones((n_frames, 3))
    # Only the poses' rotations and translations are read.
    poses = dataclasses.make_dataclass("Poses", ["rotation", "translation"])
    for prox, dist in (
        (poses(r0, d0), poses(r1, d1)),
        (
            poses(np.stack([r0, r0]), np.stack([d0, d0])),
            poses(np.stack([r1, r1]), np.stack([d1, d1])),
        ),
    ):
        errors = hjc._analytic(prox, dist, "analytic")[2]
        assert len(errors) == prox.rotation.size // (n_frames * 9)
        for error in errors:
            assert "do not rotate relative to each other" in str(error)


def test_gauss_markov_agrees_with_analytic_at_low_noise():
    proximal, distal = two_segments(300)
    proximal, distal = _noisy(proximal, 3, 0.01), _noisy(distal, 4, 0.01)
    analytic = jb.fit_joint_center(proximal, distal, method="analytic")
    for method in ("gauss-markov", "gauss-markov-frame0"):
        result = jb.fit_joint_center(proximal, distal, method=method)
        assert np.linalg.norm(result.center - analytic.center) < 0.05
        assert result.diagnostics["noise_mm"] == pytest.approx(0.01, rel=0.1)
    # Only the extension's covariance covers the true centre (frame-0 errors, see below).
    sd = np.sqrt(np.trace(result.covariance))
    assert np.linalg.norm(result.center - JOINT) < 4 * sd


@pytest.mark.parametrize("method", METHODS)
def test_world_transform_marker_order_and_segment_swap(method):
    proximal, distal = two_segments(150)
    proximal, distal = _noisy(proximal, 5), _noisy(distal, 6)
    rng = np.random.default_rng(11)
    rotation, shift = rotation_matrix(rng.normal(size=3)), rng.normal(scale=500.0, size=3)
    base = jb.fit_joint_center(proximal, distal, method=method)
    moved = jb.fit_joint_center(
        proximal @ rotation.T + shift, distal @ rotation.T + shift, method=method
    )
    np.testing.assert_allclose(moved.center, rotation @ base.center + shift, atol=1e-7)
    reordered = jb.fit_joint_center(proximal[:, [1, 2, 0]], distal[:, [2, 0, 1]], method=method)
    np.testing.assert_allclose(reordered.center, base.center, atol=1e-7)
    if method != "gauss-markov-frame0":  # the paper's single-c model is symmetric in h -> -h
        swapped = jb.fit_joint_center(distal, proximal, method=method)
        np.testing.assert_allclose(swapped.center, base.center, atol=1e-7)
    if base.covariance is not None:
        rotated = rotation @ base.covariance @ rotation.T
        np.testing.assert_allclose(moved.covariance, rotated, rtol=1e-6, atol=1e-12)
        np.testing.assert_allclose(reordered.covariance, base.covariance, rtol=1e-6)


def test_noise_estimate_from_rigid_body_residuals():
    """s^2 = RSS / (3 (n - 2)(N - 1)) per segment, pooled: unbiased even at Nt = 8."""
    protocol = HipProtocol()
    full = simulate({}, protocol, [trial_rng(3, "hip-test", {}, 0)])
    one = fit_gauss_markov(full.segments["proximal"][0], full.segments["distal"][0])
    assert one.diagnostics["noise_source"] == "rigid-body residuals"
    assert one.diagnostics["noise_mm"] == pytest.approx(1.7, rel=0.03)
    short = simulate(
        {"n_frames": 8}, protocol, [trial_rng(3, "hip-test", {}, k) for k in range(100)]
    )
    variances = [
        fit_gauss_markov(p, d).diagnostics["noise_mm"] ** 2 / 3.0
        for p, d in zip(short.segments["proximal"], short.segments["distal"], strict=True)
    ]
    # 42 degrees of freedom per trial; counting 3nN - 6N = 24 per segment would be 14 % low.
    assert np.mean(variances) == pytest.approx(1.7**2 / 3.0, rel=0.08)
    given = fit_gauss_markov(
        short.segments["proximal"][0], short.segments["distal"][0], noise_mm=1.7
    )
    assert given.diagnostics["noise_source"] == "given" and given.diagnostics["noise_mm"] == 1.7


def _monte_carlo(nt=300, trials=100, *, exact_frame0=False):
    protocol = HipProtocol()
    rngs = [trial_rng(20070507, "hip-calibration", {}, k) for k in range(trials)]
    data = simulate({"n_frames": nt}, protocol, rngs)
    proximal, distal = data.segments["proximal"], data.segments["distal"]
    if exact_frame0:  # paper C's assumption: the frame-0 poses are known exactly
        clean = nominal_recording(protocol)
        proximal, distal = proximal.copy(), distal.copy()
        proximal[:, 0], distal[:, 0] = clean[0][0], clean[1][0]
    return protocol, proximal, distal


def _mahalanobis(centers, covariances, truth):
    offsets = np.asarray(centers) - truth
    return np.array([o @ np.linalg.solve(w, o) for o, w in zip(offsets, covariances, strict=True)])


def _assert_calibrated(mahalanobis):
    """Coverage of the 95 % ellipsoid within Binomial(100, 0.95)'s central 99.8 %, and
    E[v^2] = E[e / 3] = 1 within about 3.5 standard errors (0.08 each for 100 trials)."""
    low, high = stats.binom(len(mahalanobis), 0.95).ppf([0.001, 0.999]) / len(mahalanobis)
    inside = np.mean(mahalanobis <= CHI2_3_95)
    assert low <= inside <= high, inside
    assert 0.72 <= np.mean(mahalanobis / 3.0) <= 1.3, np.mean(mahalanobis / 3.0)


def test_frame0_extension_covariance_covers_the_true_centre():
    protocol, proximal, distal = _monte_carlo()
    results = [
        jb.fit_joint_center(p, d, method="gauss-markov-frame0", noise_mm=1.7)
        for p, d in zip(proximal, distal, strict=True)
    ]
    assert all(r.converged for r in results)
    truth = np.asarray(protocol.joint_mm)
    _assert_calibrated(
        _mahalanobis([r.center for r in results], [r.covariance for r in results], truth)
    )
    # The centre relative to the proximal markers: free of the frame-0 placement error.
    layout = marker_layout(protocol)[0]
    moved = [
        align_to_markers(
            r.diagnostics["center_proximal"],
            r.diagnostics["covariance_proximal"],
            r.diagnostics["proximal_body"],
            layout,
        )
        for r in results
    ]
    relative = _mahalanobis([m[0] for m in moved], [m[1] for m in moved], truth)
    _assert_calibrated(relative)
    assert np.median([np.trace(m[1]) for m in moved]) < 0.2 * np.median(
        [np.trace(r.covariance) for r in results]
    )


def test_paper_covariance_is_honest_given_exact_frame0_poses():
    protocol, proximal, distal = _monte_carlo(exact_frame0=True)
    results = [fit_gauss_markov(p, d, noise_mm=1.7) for p, d in zip(proximal, distal, strict=True)]
    truth = np.asarray(protocol.joint_mm)
    _assert_calibrated(
        _mahalanobis([r.center for r in results], [r.covariance for r in results], truth)
    )


def test_paper_covariance_ignores_the_frame0_pose_errors():
    """With noise on frame 0 too, paper C's W_c is far too small for the true centre."""
    protocol, proximal, distal = _monte_carlo(trials=30)
    results = [fit_gauss_markov(p, d, noise_mm=1.7) for p, d in zip(proximal, distal, strict=True)]
    truth = np.asarray(protocol.joint_mm)
    mahalanobis = _mahalanobis([r.center for r in results], [r.covariance for r in results], truth)
    assert np.mean(mahalanobis / 3.0) > 4.0
    # ... and its own chi^2 shows the misfit: the frame-0 errors enter every constraint.
    assert np.mean([r.diagnostics["chi2"] / r.diagnostics["chi2_dof"] for r in results]) > 1.2


def test_degenerate_motion():
    hinge = two_segments(relative="hinge")
    still = two_segments(relative="none")
    for method in METHODS:
        with pytest.raises(ValueError, match="single axis"):
            jb.fit_joint_center(*hinge, method=method)
        with pytest.raises(ValueError, match="do not rotate relative to each other"):
            jb.fit_joint_center(*still, method=method)


def test_noisy_hinge_is_ill_conditioned_not_an_error():
    """Noise makes a hinge regular but poorly conditioned: a large, honest uncertainty along
    the axis, not an exception."""
    proximal, distal = two_segments(300, relative="hinge")
    result = fit_gauss_markov(_noisy(proximal, 7), _noisy(distal, 8), noise_mm=1.7)
    assert result.converged
    along = np.sqrt(HINGE @ result.covariance @ HINGE)
    smallest = np.sqrt(np.linalg.eigvalsh(result.covariance)[0])
    assert along > 5 * smallest


def test_few_frames_give_a_large_uncertainty_not_an_error():
    """Paper C Table 1: Nt = 4 (0.05 s) is valid but nearly uninformative."""
    data = simulate({"n_frames": 4}, HipProtocol(), [trial_rng(1, "hip-test", {}, 0)])
    result = fit_gauss_markov(
        data.segments["proximal"][0], data.segments["distal"][0], noise_mm=1.7
    )
    assert np.all(np.isfinite(result.center))
    assert np.sqrt(np.trace(result.covariance)) > 20.0


def test_iteration_cap_reports_non_convergence():
    proximal, distal = two_segments(150)
    result = fit_gauss_markov(_noisy(proximal, 9), _noisy(distal, 10), max_iterations=1)
    assert not result.converged
    assert result.iterations == 1
    assert "did not converge" in result.status
    full = fit_gauss_markov(_noisy(proximal, 9), _noisy(distal, 10))
    assert full.converged and 1 < full.iterations < 20


def test_bad_input_is_named():
    proximal, distal = two_segments(20)
    with pytest.raises(ValueError, match="noise_mm must be a finite number >= 0"):
        fit_gauss_markov(proximal, distal, noise_mm=-1.0)
    with pytest.raises(ValueError, match="max_iterations"):
        fit_gauss_markov(proximal, distal, max_iterations=0)
    with pytest.raises(ValueError, match="at least 3"):
        jb.fit_joint_center(proximal[:2], distal[:2], method="gauss-markov")
    with pytest.raises(ValueError, match="must share frames"):
        jb.fit_joint_center(proximal, distal[:10], method="analytic")
    with pytest.raises(ValueError, match="proximal has 2 markers"):
        jb.fit_joint_center(proximal[:, :2], distal, method="gauss-markov-frame0")


def test_align_to_markers():
    rng = np.random.default_rng(4)
    rotation, shift = rotation_matrix(rng.normal(size=3)), rng.normal(size=3)
    covariance = np.diag([1.0, 2.0, 3.0])
    point, moved = align_to_markers(
        [1.0, 2.0, 3.0], covariance, PROXIMAL, PROXIMAL @ rotation.T + shift
    )
    np.testing.assert_allclose(point, rotation @ [1.0, 2.0, 3.0] + shift, atol=1e-9)
    np.testing.assert_allclose(moved, rotation @ covariance @ rotation.T, atol=1e-12)
    assert align_to_markers(np.zeros(3), None, PROXIMAL, PROXIMAL)[1] is None
    with pytest.raises(ValueError, match="markers_from and markers_to"):
        align_to_markers(np.zeros(3), None, PROXIMAL, PROXIMAL[:2])


def test_registered():
    for method in (*METHODS, "SCoRE"):
        assert method in jb.methods("joint_center")


@pytest.mark.parametrize("frame0", [False, True])
def test_a_singular_gauss_markov_system_is_a_result_not_a_crash(monkeypatch, frame0):
    """Each trial of a batch is iterated alone, so its answer is the one-trial answer; a trial
    whose normal equations turn singular becomes a non-converged result naming it, centred on
    the analytic start."""
    proximal, distal = two_segments(40)
    trials = [(_noisy(proximal, seed), _noisy(distal, seed + 100)) for seed in range(3)]
    stacked = [np.stack(part) for part in zip(*trials, strict=True)]
    fit = hjc.fit_gauss_markov_frame0 if frame0 else fit_gauss_markov
    many = jb.estimators.registry.many(
        "joint_center", "gauss-markov-frame0" if frame0 else "gauss-markov", checked=False
    )
    alone = [fit(*trial) for trial in trials]
    for result, single in zip(many(*stacked), alone, strict=True):
        np.testing.assert_array_equal(result.center, single.center)
        assert result.iterations == single.iterations and result.status == "ok"

    def singular(*arguments):
        return 1, math.inf, True, math.nan

    monkeypatch.setattr(hjc, "_relinearised", singular)
    for result, single in zip(many(*stacked), alone, strict=True):
        assert not result.converged and result.covariance is None
        assert result.status == "singular Gauss–Markov information matrix (Singular matrix)"
        np.testing.assert_array_equal(result.center, single.diagnostics["analytic_center"])


def _frame0_covariance(proximal, distal, center, variance):
    """``s^2 (H^-1 + H^-1 (F_0 A_0 F_0' + F_1 A_1 F_1') H^-1)`` [mm^2] of paper C's centre with
    every term at ``center`` (``hjc`` module docstring, "Frame 0"), from the segments' poses."""
    poses = trial_poses({"proximal": [proximal], "distal": [distal]}, min_frames=3)[0]
    rotations, at_joint = [], []
    for segment in (poses["proximal"], poses["distal"]):
        offsets = segment.body - segment.body.mean(axis=0)
        inertia = np.sum(offsets**2) * np.eye(3) - offsets.T @ offsets
        lever = skew(center - segment.body.mean(axis=0))
        at_joint.append(lever @ np.linalg.inv(inertia) @ lever.T + np.eye(3) / len(offsets))
        rotations.append(segment.rotation[1:])
    inverses = np.linalg.inv(
        sum(r @ a @ np.swapaxes(r, 1, 2) for r, a in zip(rotations, at_joint, strict=True))
    )
    m = rotations[0] - rotations[1]
    unit = np.linalg.inv(np.einsum("tki,tkl,tlj->ij", m, inverses, m))
    added = sum(
        gain @ a @ gain.T
        for gain, a in zip(
            (np.einsum("tki,tkl,tlj->ij", m, inverses, r) for r in rotations),
            at_joint,
            strict=True,
        )
    )
    return variance * (unit + unit @ added @ unit)


def test_a_fit_stopped_early_states_its_covariance_at_one_centre():
    """Stopped at its iteration cap, paper C's fit states W_c at the centre its last weights
    were formed at; the covariance with the frame-0 errors added takes the frame-0 fits' error
    at the joint there too, not at the centre the last step moved to."""
    proximal, distal = _noisy(two_segments(150)[0], 9), _noisy(two_segments(150)[1], 10)
    result = fit_gauss_markov(proximal, distal, max_iterations=1)
    assert not result.converged
    start = np.asarray(result.diagnostics["analytic_center"])
    variance = result.diagnostics["noise_mm"] ** 2 / 3.0
    expected = _frame0_covariance(proximal, distal, start, variance)
    stated = np.asarray(result.diagnostics["center_covariance_mm2"])
    np.testing.assert_allclose(stated, expected, rtol=1e-8)
    converged = fit_gauss_markov(proximal, distal)
    at_answer = _frame0_covariance(proximal, distal, converged.center, variance)
    np.testing.assert_allclose(converged.diagnostics["center_covariance_mm2"], at_answer, rtol=1e-6)


@pytest.mark.parametrize("frame0", [False, True])
def test_the_compiled_iteration_is_its_python_source(frame0):
    """The Gauss–Markov iteration's kernel answers as its Python source, the specification,
    run as written."""
    proximal, distal = two_segments(20)
    proximal, distal = _noisy(proximal, 5), _noisy(distal, 6)
    poses = trial_poses({"proximal": [proximal], "distal": [distal]}, min_frames=3)[0]
    trial = hjc._prepared(poses["proximal"], poses["distal"], None, "gauss-markov")
    answers = []
    for iterate in (hjc._relinearised, hjc._relinearised.__wrapped__):
        k = 9 if frame0 else 3
        state = np.tile(trial.analytic_center, k // 3)
        information, added = np.full((k, k), np.nan), np.full((3, 3), np.nan)
        arrays = (trial.r0, trial.r1, trial.y, trial.means, trial.inertia_invs, trial.counts)
        ended = iterate(*arrays, frame0, 100, 1e-6, state, information, added)
        answers.append((ended, state, information, added))
    (compiled, *arrays), (python, *expected) = answers
    assert compiled[:3] == python[:3] and compiled[0] > 1
    np.testing.assert_allclose(compiled[3], python[3], rtol=1e-12)
    for mine, theirs in zip(arrays, expected, strict=True):
        np.testing.assert_allclose(mine, theirs, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("frame0", [False, True])
def test_an_iteration_without_iterations_is_refused_by_name(frame0):
    """The public fits refuse ``max_iterations`` below 1 before any pose is fitted; the
    iteration itself does too, naming it, instead of stating a chi^2 from weights it never
    formed."""
    proximal, distal = two_segments(20)
    proximal, distal = _noisy(proximal, 5), _noisy(distal, 6)
    poses = trial_poses({"proximal": [proximal], "distal": [distal]}, min_frames=3)[0]
    trial = hjc._prepared(poses["proximal"], poses["distal"], None, "gauss-markov")
    with pytest.raises(ValueError, match="max_iterations"):
        hjc._iterated(trial, frame0=frame0, max_iterations=0, tol_mm=1e-6)


def test_the_marker_gains_are_the_fits_hat_and_place_the_point_covariance():
    """``B_pi = I/n - [p - m]x K^-1 [u_i]x``: summed as ``B B'`` over the markers it is
    ``A(p)``, and at the markers themselves it is the rigid fit's hat matrix (idempotent)."""
    rng = np.random.default_rng(8)
    body = PROXIMAL + rng.normal(scale=5.0, size=PROXIMAL.shape)
    point = JOINT + rng.normal(scale=20.0, size=3)
    for gains_of in (hjc._marker_gains, hjc._marker_gains.__wrapped__):
        gains = gains_of(point[None], body)[0]
        np.testing.assert_allclose(
            np.einsum("ikl,iml->km", gains, gains), point_covariance(point, body), rtol=1e-12
        )
        hat = gains_of(body, body).transpose(0, 2, 1, 3).reshape(9, 9)
        np.testing.assert_allclose(hat @ hat, hat, atol=1e-12)


@pytest.mark.parametrize("frame0", [False, True])
def test_a_correction_that_is_not_a_number_ends_the_fit_unconverged(frame0):
    """A correction that is not a number (here from a residual that is not one) stops the
    iteration with its step NaN, as not converged: never as a step of zero read as
    convergence, which would state a centre of NaN as "ok"."""
    proximal, distal = two_segments(20)
    proximal, distal = _noisy(proximal, 5), _noisy(distal, 6)
    poses = trial_poses({"proximal": [proximal], "distal": [distal]}, min_frames=3)[0]
    method = "gauss-markov-frame0" if frame0 else "gauss-markov"
    trial = hjc._prepared(poses["proximal"], poses["distal"], None, method)
    y = trial.y.copy()
    y[3, 1] = np.nan
    broken = dataclasses.replace(trial, y=y)
    done = hjc._iterated(broken, frame0=frame0, max_iterations=100, tol_mm=1e-6)
    assert math.isnan(done.step)
    result = hjc._result(broken, done, method, 1e-6)
    assert not result.converged and result.status.startswith("did not converge")


@pytest.mark.parametrize("method", ["analytic", "gauss-markov"])
@pytest.mark.parametrize("noise_mm", [None, 1.7])
def test_the_fixed_centre_test_from_the_fits_analytic_centre_is_that_of_solving_it(
    method, noise_mm
):
    """The checked call's fixed-centre test starts gauss-markov-frame0 from the analytic
    centre: the analytic answer, or the one paper C's fit started from, on the same poses,
    taken as found rather than solved again, to the bit."""
    options = {} if method == "analytic" else {"noise_mm": noise_mm}
    for seed in range(3):
        proximal, distal = (_noisy(markers, seed) for markers in two_segments(150))
        (poses,) = trial_poses({"proximal": [proximal], "distal": [distal]}, min_frames=3)
        result = jb.estimators.registry.get("joint_center", method, checked=False)(
            proximal, distal, **options
        )
        start = (
            hjc._analytic_answer(result)
            if method == "analytic"
            else hjc._gauss_markov_start(result)
        )
        given = hjc._fixed_centre_test(result, poses["proximal"], poses["distal"], start)
        solved = hjc._fixed_centre_test(result, poses["proximal"], poses["distal"])
        assert repr(given.diagnostics) == repr(solved.diagnostics)
        assert given.status == solved.status


@pytest.mark.parametrize("method", ["analytic", "gauss-markov"])
def test_the_fixed_centre_test_of_many_trials_starts_from_each_trials_own_analytic_centre(method):
    """The many-trial form solves eq. 9 for all trials in one batch; the fixed-centre test of
    each trial, started from its answer, is that of solving its trial alone, to the bit, with
    trials of other noise (one noise-free, one a noisy hinge, nearly degenerate) beside it."""
    proximal, distal = two_segments(90)
    sds = (0.2, 3.0, 0.0, 1.1, 7.0)
    stacked = [
        np.stack([_noisy(markers, seed + 10 * index, sd) for seed, sd in enumerate(sds)])
        for index, markers in enumerate((proximal, distal))
    ]
    hinge = two_segments(90, relative="hinge")
    for segment in range(2):
        stacked[segment][3] = _noisy(hinge[segment], 40 + segment)
    poses = trial_poses({"proximal": stacked[0], "distal": stacked[1]}, min_frames=3)
    results = jb.estimators.registry.many("joint_center", method, checked=False)(
        *stacked, poses=poses
    )
    start_of = hjc._analytic_answer if method == "analytic" else hjc._gauss_markov_start
    for result, trial in zip(results, poses, strict=True):
        if isinstance(result, ValueError):
            continue
        given = hjc._fixed_centre_test(result, trial["proximal"], trial["distal"], start_of(result))
        solved = hjc._fixed_centre_test(result, trial["proximal"], trial["distal"])
        assert repr(given.diagnostics) == repr(solved.diagnostics)
        assert given.status == solved.status


def test_the_weight_moments_are_the_full_sum_of_each_frames_outer_product():
    """``S_a = sum_t vec(V_at) vec(V_at)'`` (:func:`hjc._local_weight_moments`), summed over
    its upper triangle: every entry, below the diagonal too, is that of the full outer
    products summed over the frames asked for, and ``S_a`` is exactly symmetric."""
    rng = np.random.default_rng(31)
    r0, r1 = (rotation_matrix(rng.normal(scale=0.8, size=(12, 3))) for _ in range(2))
    factors = rng.normal(size=(2, 3, 3))
    covariances = factors @ np.swapaxes(factors, 1, 2) + 0.1 * np.eye(3)
    frames = np.array([0, 3, 4, 7, 11])
    seconds = hjc._local_weight_moments(r0, r1, frames, covariances)
    expected = np.zeros((2, 9, 9))
    for t in frames:
        relative = r0[t].T @ r1[t]
        for a, turned in enumerate((relative, relative.T)):
            local = np.linalg.inv(covariances[a] + turned @ covariances[1 - a] @ turned.T)
            expected[a] += np.outer(local.ravel(), local.ravel())
    np.testing.assert_allclose(seconds, expected, rtol=1e-12, atol=0.0)
    np.testing.assert_array_equal(seconds, np.swapaxes(seconds, 1, 2))


def test_the_model_tests_read_each_trials_own_segments_once_in_a_call():
    """The largest |coordinate| of the segments (the scale of their rounding) and each
    cluster's residual moments are those of the segments asked about: the largest over both
    segments' markers and every frame (here the distal's, negative), and within one call's
    scope (:func:`jointbench.numerics.reuse.one_call`) each of two trials of the same shape,
    asked in turn, its own."""
    proximal, distal = two_segments(20)
    trials = [
        trial_poses({"proximal": [proximal], "distal": [_noisy(d, seed)]}, min_frames=3)[0]
        for seed, d in ((1, distal - 5000.0), (2, distal))
    ]
    segments = [(poses["proximal"], poses["distal"]) for poses in trials]
    largest = [max(float(np.abs(p.markers).max()) for p in pair) for pair in segments]
    assert largest[0] == -float(segments[0][1].markers.min()) > largest[1]
    alone = [hjc._noise_kurtosis(pair, 1.0) for pair in segments]
    assert alone[0] != alone[1]
    for scope in (contextlib.nullcontext(), reuse.one_call()):
        with scope:
            for trial in (0, 1, 0, 1):
                assert hjc._largest_coordinate(segments[trial]) == largest[trial]
                assert hjc._noise_kurtosis(segments[trial], 1.0) == alone[trial]
