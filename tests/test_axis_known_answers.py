"""The axis methods' statement of precision and their diagnostics against answers known in
closed form: the planar cost's eigen-perturbation SD, the cost a Newton step reaches on a
linear least-squares problem, the misfit's kurtosis floor, the rigid-body residual's degrees
of freedom and the foot of the markers' centroid on the axis."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.special import fdtrc
from test_axis_sd import checked, hinge

from jointbench.estimators import axis, precision
from jointbench.geometry import rotation_matrix
from jointbench.numerics.poses import fit_rigid_poses


@pytest.mark.parametrize(("n_frames", "n_markers"), [(10, 3), (40, 4)])
def test_planar_sd_is_the_eigenvector_perturbation_of_its_scatter(n_frames, n_markers):
    """For ``f_p = n' S n`` at its least eigenvector, the Hessian in the tangent angles is
    ``2 (diag(l1, l2) - l0 I)`` and the residual variance ``l0 / (P (N - 1) - 2)`` (``P N``
    residuals less the ``P`` centroids and the 2 angles), so the SD [rad] is
    ``sqrt(l0 / dof (1 / (l1 - l0) + 1 / (l2 - l0)))`` with ``l0 < l1 < l2`` the eigenvalues
    of ``S``. Few frames, so that the degrees of freedom matter."""
    markers = hinge(seed=3, arc_deg=40.0, noise=0.3, n_frames=n_frames, n_markers=n_markers)
    offsets = markers - markers.mean(axis=0)
    scatter = np.einsum("kpi,kpj->ij", offsets, offsets)
    l0, l1, l2 = np.linalg.eigvalsh(scatter)
    dof = n_markers * (n_frames - 1) - 2
    expected = math.degrees(math.sqrt(l0 / dof * (1.0 / (l1 - l0) + 1.0 / (l2 - l0))))
    result = checked("planar", markers)
    assert result.diagnostics["axis_sd_deg"] == pytest.approx(expected, rel=1e-3)


@pytest.mark.parametrize("method", ["planar", "radial", "combined"])
def test_centroid_foot_is_the_centroids_projection_on_the_axis(method):
    """``centroid_foot`` lies on the returned axis and the markers' centroid lies square to
    the axis from it."""
    markers = hinge(seed=1, arc_deg=60.0)
    result = checked(method, markers)
    foot = np.asarray(result.diagnostics["centroid_foot"])
    direction = np.asarray(result.direction)
    point = np.asarray(result.point)
    centroid = markers.reshape(-1, 3).mean(axis=0)
    along = foot - point
    np.testing.assert_allclose(np.cross(along, direction), 0.0, atol=1e-9)
    assert float((centroid - foot) @ direction) == pytest.approx(0.0, abs=1e-9)


def test_cost_at_reaches_the_least_squares_minimum_of_a_linear_problem():
    """For residuals ``r(x) = J x - y`` the cost ``|r|^2`` is exactly quadratic: at ``x = 0``
    its gradient is ``-2 J' y`` and Hessian ``2 J' J``, and the cost at the minimum a Newton
    step reaches is the least-squares residual ``min |J x - y|^2``."""
    rng = np.random.default_rng(11)
    jacobian = rng.normal(size=(30, 4))
    target = rng.normal(size=30)
    _, (least,), _, _ = np.linalg.lstsq(jacobian, target, rcond=None)
    at = precision.cost_at(
        gradient=-2.0 * jacobian.T @ target,
        hessian=2.0 * jacobian.T @ jacobian,
        cost=float(target @ target),
        fourths=float(np.sum(target**4)),
        n_residuals=30,
        dof=26,
    )
    assert at.least == pytest.approx(least, rel=1e-9)


def test_misfit_does_not_credit_light_tailed_residuals_with_extra_degrees_of_freedom():
    """The Satterthwaite scaling of the misfit's F test uses the residuals' excess kurtosis
    floored at a normal one's (zero): residuals lighter-tailed than normal (here those of a
    uniform distribution, excess kurtosis -1.2) keep the unscaled F test."""
    residuals = np.random.default_rng(2).uniform(-1.0, 1.0, size=400)
    cost = float(residuals @ residuals)
    at = precision.cost_at(
        gradient=np.zeros(2),
        hessian=2.0 * np.eye(2),
        cost=cost,
        fourths=float(np.sum(residuals**4)),
        n_residuals=400,
        dof=398,
    )
    assert 400 * at.fourths / at.cost**2 - 3.0 < -1.0
    noise_variance, noise_dof = 0.3, 500
    found = precision.misfit(at, noise_variance, noise_dof)
    ratio = (at.least / at.dof) / noise_variance
    assert found.ratio == pytest.approx(ratio, rel=1e-12)
    assert found.p_value == pytest.approx(fdtrc(398, noise_dof, ratio), rel=1e-9)
    # The tilt scale: the cost's excess over the noise's share on its dof, ``f - dof s^2``,
    # along the direction block of (H / 2)^-1 (the identity here).
    excess = at.least - 398 * noise_variance
    assert excess > 0.0
    assert found.tilt_scale_deg == pytest.approx(math.degrees(math.sqrt(excess)), rel=1e-12)


def test_rigid_dof_is_the_mean_rigid_body_residual_over_the_noise_variance():
    """Noise of variance ``s^2`` per coordinate leaves a rigid-body fit (poses and body
    re-estimated) a residual sum of squares of mean ``s^2 dof``: over 400 trials of 4
    markers and 6 frames, ``dof = (3 * 4 - 6) * (6 - 1) = 30``, to within 3 %."""
    n_trials, n_frames, n_markers, sigma = 400, 6, 4, 0.05
    rng = np.random.default_rng(7)
    body = rng.normal(scale=40.0, size=(n_markers, 3))
    rotvecs = rng.normal(scale=0.5, size=(n_trials, n_frames, 3))
    rotations = rotation_matrix(rotvecs.reshape(-1, 3)).reshape(n_trials, n_frames, 3, 3)
    translations = rng.normal(scale=100.0, size=(n_trials, n_frames, 3))
    clean = np.einsum("tfij,pj->tfpi", rotations, body) + translations[:, :, None, :]
    markers = clean + rng.normal(scale=sigma, size=clean.shape)
    fit = fit_rigid_poses(markers)
    fitted = np.einsum("tfij,tpj->tfpi", fit.rotation, fit.body) + fit.translation[:, :, None]
    residual_ss = np.sum((markers - fitted) ** 2, axis=(1, 2, 3))
    dof = precision.rigid_dof(n_markers, n_frames)
    assert np.mean(residual_ss) / sigma**2 == pytest.approx(dof, rel=0.03)


def test_planar_self_check_replaces_an_answer_a_few_fatol_above_the_eigenvector():
    """An answer tilted from the scatter's least eigenvector towards the next one until its
    planar cost is 5 fatol above the least eigenvalue (``l0 + (l1 - l0) sin^2 t``): more than
    fatol, less than ten times it, so the restart from the eigenvector must replace it."""
    markers = hinge(seed=2, arc_deg=40.0)
    result = axis.fit_planar(markers)
    offsets = markers - markers.mean(axis=0)
    values, vectors = np.linalg.eigh(np.einsum("kpi,kpj->ij", offsets, offsets))
    tilt = math.asin(math.sqrt(5.0 * axis.FATOL / (values[1] - values[0])))
    direction = math.cos(tilt) * vectors[:, 0] + math.sin(tilt) * vectors[:, 1]
    cost = float(direction @ np.einsum("kpi,kpj->ij", offsets, offsets) @ direction)
    assert cost - values[0] == pytest.approx(5.0 * axis.FATOL, rel=1e-6)
    tilted = dataclasses.replace(result, direction=direction, cost=cost)
    checked = axis.fit_planar.self_check(tilted, markers)
    assert checked.status.startswith("restarted: ")
    assert checked.cost == pytest.approx(values[0], abs=axis.FATOL)
