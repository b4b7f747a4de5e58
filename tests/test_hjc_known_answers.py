"""Paper C's Gauss–Markov fit: the noise it estimates from the rigid-body residuals of two
segments that carry different numbers of markers."""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.estimators.hjc import fit_analytic, fit_gauss_markov
from jointbench.geometry import rotation_matrix
from jointbench.numerics.poses import fit_rigid_poses


def _rigid_residual_ss(markers: np.ndarray) -> float:
    """The residual sum of squares [mm^2] of a rigid-body fit of ``markers`` ``(N, n, 3)``."""
    fit = fit_rigid_poses(markers[None])
    fitted = np.einsum("fij,pj->fpi", fit.rotation[0], fit.body[0]) + fit.translation[0][:, None]
    return float(np.sum((markers - fitted) ** 2))


def _two_segments(seed: int, n_frames: int = 40):
    """Proximal (3 markers) and distal (6 markers) clusters ``(N, n, 3)`` [mm] joined at a
    ball joint, each with 0.4 mm isotropic noise."""
    rng = np.random.default_rng(seed)
    centre = np.array([10.0, -20.0, 5.0])
    proximal_body = rng.normal(scale=40.0, size=(3, 3)) + centre
    distal_body = rng.normal(scale=40.0, size=(6, 3)) + centre
    pelvis = rotation_matrix(rng.normal(scale=0.2, size=(n_frames, 3)))
    hip = rotation_matrix(rng.normal(scale=0.5, size=(n_frames, 3)))
    shift = rng.normal(scale=50.0, size=(n_frames, 3))
    proximal = np.einsum("fij,pj->fpi", pelvis, proximal_body) + shift[:, None]
    thigh = np.einsum("fij,fjk->fik", pelvis, hip)
    distal = np.einsum("fij,pj->fpi", thigh, distal_body - centre)
    distal += (np.einsum("fij,j->fi", pelvis, centre) + shift)[:, None]
    proximal = proximal + rng.normal(scale=0.4, size=proximal.shape)
    return proximal, distal + rng.normal(scale=0.4, size=distal.shape)


def test_noise_is_pooled_over_segments_by_their_degrees_of_freedom():
    """``s^2 = (RSS_0 + RSS_1) / (dof_0 + dof_1)`` with ``dof = 3 (n - 2) (N - 1)``: with 3
    proximal and 6 distal markers the segments' dof are 3 (N - 1) and 12 (N - 1), so the pooled
    variance is not the mean of the two segments' own."""
    n_frames = 40
    proximal, distal = _two_segments(17, n_frames)
    result = fit_gauss_markov(proximal, distal)
    dof = 3 * (3 - 2) * (n_frames - 1) + 3 * (6 - 2) * (n_frames - 1)
    pooled = (_rigid_residual_ss(proximal) + _rigid_residual_ss(distal)) / dof
    assert result.diagnostics["noise_source"] == "rigid-body residuals"
    assert result.diagnostics["noise_mm"] == pytest.approx(np.sqrt(3.0 * pooled), rel=1e-6)


def test_analytic_cost_sums_every_frames_mismatch_of_the_centre():
    """``cost = sum_t |R0_t c + d0_t - R1_t c - d1_t|^2`` (paper C eq. 6) over all frames, the
    poses those of the rigid-body fits (body frames the world at frame 0, which adds
    nothing)."""
    proximal, distal = _two_segments(19)
    result = fit_analytic(proximal, distal)
    poses = [fit_rigid_poses(markers[None]) for markers in (proximal, distal)]
    centre = np.asarray(result.center)
    world = [np.einsum("fij,j->fi", p.rotation[0], centre) + p.translation[0] for p in poses]
    assert result.cost == pytest.approx(float(np.sum((world[0] - world[1]) ** 2)), rel=1e-6)
