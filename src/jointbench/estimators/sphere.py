"""Sphere-fitting centre-of-rotation estimators: LS, NM (and BC, IS added below).

All take the moving segment's markers in the reference frame, ``(n_frames, n_markers, 3)``
[mm], and fit concentric spheres (one radius per marker, common centre).
"""

from __future__ import annotations

import numpy as np

from jointbench.estimators.registry import register
from jointbench.estimators.results import CenterResult
from jointbench.estimators.validation import check_markers, check_moves

__all__ = ["fit_ls", "fit_nm", "ls_system", "mean_sq_radii"]

# The LS normal matrix of a pure hinge is singular to rounding; only then is a singular
# value dropped (Gamage & Lasenby). Ill-conditioned but regular systems are solved as they are:
# their poor answers at small RoM are what the benchmark measures.
_SINGULAR_RCOND = 1e-12


def _prepare(markers: object, min_frames: int = 4) -> np.ndarray:
    array = check_markers(markers, min_frames=min_frames, min_markers=1)
    check_moves(array)
    return array


def ls_system(markers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gamage & Lasenby's normal equations ``A c = b`` (paper A eq. 4 minimised over ``c``).

    ``A = 2 sum_p Cov(v^p)`` ``(3, 3)`` [mm^2] and
    ``b = sum_p [mean(|v|^2 v) - mean(v) mean(|v|^2)]`` ``(3,)`` [mm^3], covariances with 1/N.
    """
    mean = markers.mean(axis=0)  # (P, 3)
    centred = markers - mean
    n_frames = markers.shape[0]
    a_matrix = 2.0 * np.einsum("kpi,kpj->ij", centred, centred) / n_frames
    sq = np.einsum("kpi,kpi->kp", markers, markers)  # (N, P)
    b_vector = np.einsum("kp,kpi->i", sq - sq.mean(axis=0), centred) / n_frames
    return a_matrix, b_vector


def solve_ls_system(a_matrix: np.ndarray, b_vector: np.ndarray) -> np.ndarray:
    """Solve ``A c = b``, dropping singular values below ``1e-12`` of the largest (pure hinge)."""
    u, s, vt = np.linalg.svd(a_matrix)
    inverse = np.where(s > _SINGULAR_RCOND * s[0], 1.0 / np.where(s > 0, s, 1.0), 0.0)
    return vt.T @ (inverse * (u.T @ b_vector))


def mean_sq_radii(markers: np.ndarray, center: np.ndarray) -> np.ndarray:
    """``r_p^2 = mean_k |v_k^p - c|^2`` ``(n_markers,)`` [mm^2]."""
    return np.mean(np.sum((markers - center) ** 2, axis=-1), axis=0)


@register("center", "LS")
def fit_ls(markers: np.ndarray) -> CenterResult:
    """Least-squares sphere fit of Gamage & Lasenby (2002): closed form, cost f2 (paper A eq. 4).

    For a pure hinge ``A`` is singular and the centre is the point on the axis given by the
    pseudo-inverse with the vanishing singular value dropped.
    """
    markers = _prepare(markers)
    a_matrix, b_vector = ls_system(markers)
    center = solve_ls_system(a_matrix, b_vector)
    sq_radii = mean_sq_radii(markers, center)
    residual = np.sum((markers - center) ** 2, axis=-1) - sq_radii
    return CenterResult(
        center=center,
        radii=np.sqrt(sq_radii),
        converged=True,
        iterations=0,
        status="ok",
        method="LS",
        cost=float(np.sum(residual**2)),
    )


def _nm_scatter(scaled: np.ndarray) -> np.ndarray:
    """``S = D'D`` ``(4 + P, 4 + P)`` for the data matrix ``D`` of paper A eq. 22, built by blocks.

    Rows of ``D`` for marker ``p`` are ``[|v|^2, x, y, z, e_p]`` with ``e_p`` the one-hot
    indicator of the marker's own constant term.
    """
    n_frames, n_markers, _ = scaled.shape
    basis = np.concatenate([np.sum(scaled**2, axis=-1, keepdims=True), scaled], axis=-1)
    flat = basis.reshape(-1, 4)
    scatter = np.empty((4 + n_markers, 4 + n_markers))
    scatter[:4, :4] = flat.T @ flat
    scatter[:4, 4:] = basis.sum(axis=0).T
    scatter[4:, :4] = scatter[:4, 4:].T
    scatter[4:, 4:] = n_frames * np.eye(n_markers)
    return scatter


def _nm_design(scaled: np.ndarray) -> np.ndarray:
    """The data matrix ``D`` ``(P N, 4 + P)`` itself (paper A eq. 22)."""
    n_frames, n_markers, _ = scaled.shape
    per_marker = np.transpose(scaled, (1, 0, 2))
    w = np.sum(per_marker**2, axis=-1, keepdims=True)
    one_hot = np.repeat(np.eye(n_markers)[:, None, :], n_frames, axis=1)
    return np.concatenate([w, per_marker, one_hot], axis=-1).reshape(n_markers * n_frames, -1)


def _nm_constraint(n_markers: int) -> np.ndarray:
    """Constraint matrix ``C`` of paper A eq. 24: ``u' C u = sum_p (b^2 + c^2 + d^2 - 4 a e_p)``."""
    constraint = np.zeros((4 + n_markers, 4 + n_markers))
    constraint[1:4, 1:4] = n_markers * np.eye(3)
    constraint[0, 4:] = constraint[4:, 0] = -2.0
    return constraint


def _largest_admissible(whitened: np.ndarray, constraint: np.ndarray) -> tuple[np.ndarray, float]:
    """Solve ``M y = mu y`` with ``M = W C W'``; return ``u = W' y`` of the largest ``mu > 0``."""
    m_matrix = whitened @ constraint @ whitened.T
    mu, y = np.linalg.eigh((m_matrix + m_matrix.T) / 2.0)
    if mu[-1] <= 0:
        raise ValueError("NM: no admissible sphere (every generalised eigenvalue is negative)")
    u = whitened.T @ y[:, -1]
    return u / np.sqrt(u @ constraint @ u), float(1.0 / mu[-1])


def _nm_coefficients(scaled: np.ndarray) -> tuple[np.ndarray, float]:
    """Minimise ``|D u|^2`` subject to ``u' C u = 1`` (paper A eq. 15); returns ``u`` and the cost.

    ``S u = lambda C u`` (eq. 17) is whitened with a factor ``S = L L'``: ``u = L^-T y`` gives the
    symmetric problem ``L^-1 C L^-T y = mu y`` with ``mu = 1 / lambda``, so the admissible
    eigenvector of least cost ``lambda`` is the one of largest positive ``mu``. When ``S`` is
    (nearly) singular, as for noise-free data, the factor comes from the SVD of ``D`` instead,
    and an exact fit is ``D``'s null vector.
    """
    constraint = _nm_constraint(scaled.shape[1])
    scatter = _nm_scatter(scaled)
    try:
        lower = np.linalg.cholesky(scatter)
    except np.linalg.LinAlgError:
        lower = None
    pivots = None if lower is None else np.diag(lower) ** 2
    if pivots is not None and pivots.min() > 1e-9 * pivots.max():
        return _largest_admissible(np.linalg.inv(lower), constraint)
    _, s, vt = np.linalg.svd(_nm_design(scaled), full_matrices=False)
    if s[-1] <= 1e-13 * s[0]:
        u = vt[-1]
        norm = u @ constraint @ u
        if norm > 0:
            return u / np.sqrt(norm), 0.0
    return _largest_admissible((vt.T / s).T, constraint)


@register("center", "NM")
def fit_nm(markers: np.ndarray) -> CenterResult:
    """Normalisation method of Chang & Pollard (2007), paper A §3–4: constrained least squares.

    Minimises the algebraic cost ``u' S u`` (eq. 13) under Pratt's normalisation summed over
    the markers, ``a^2 sum_p r_p^2 = 1`` (eq. 23), by the generalised eigenproblem (eq. 17);
    ``m = -(b, c, d) / 2a`` (eq. 18). The radii follow from eqs. 6–7 with ``a = 1``:
    ``e_p = |m|^2 - r_p^2``, so ``r_p^2 = |m|^2 - e_p / a``; eqs. 19 and 25 as printed have the
    opposite sign, which would give negative squared radii.

    The constraint is invariant to translation, rotation and scale, so the data are first centred
    on their centroid and scaled to unit RMS; this changes nothing but the conditioning. The
    reported ``cost`` is that of the unit-RMS data.
    """
    markers = _prepare(markers)
    origin = markers.reshape(-1, 3).mean(axis=0)
    scale = float(np.sqrt(np.mean(np.sum((markers - origin) ** 2, axis=-1))))
    scaled = (markers - origin) / scale
    u, cost = _nm_coefficients(scaled)
    a, bcd, e = u[0], u[1:4], u[4:]
    if abs(a) < np.finfo(float).eps * np.abs(u).max():
        raise ValueError("NM: the best fit is a plane (a = 0); the markers do not rotate")
    center_scaled = -bcd / (2.0 * a)
    sq_radii_scaled = center_scaled @ center_scaled - e / a
    return CenterResult(
        center=origin + scale * center_scaled,
        radii=scale * np.sqrt(np.clip(sq_radii_scaled, 0.0, None)),
        converged=True,
        iterations=0,
        status="ok",
        method="NM",
        cost=cost,
    )
