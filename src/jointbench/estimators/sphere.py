"""Sphere-fitting centre-of-rotation estimators: LS, NM, BC and IS.

All take the moving segment's markers in the reference frame, ``(n_frames, n_markers, 3)``
[mm], and fit concentric spheres (one radius per marker, common centre). Equation numbers refer
to paper A (Chang & Pollard 2007, J Biomech 40:1392).

The two iterative methods reproduce paper A's MATLAB settings (§5): IS is minimised by
``fminsearch`` at its defaults (:mod:`jointbench.numerics.simplex`), and "the convergence
criterion for BC was set to the same values as fminsearch" (TolX = TolFun = 1e-4, at most
200·n = 600 iterations for the n = 3 unknowns of a centre). :data:`FMINSEARCH_OPTIONS` holds
those settings.
"""

from __future__ import annotations

import math
from functools import lru_cache, partial
from typing import NamedTuple

import numpy as np

from jointbench.declared import Count, Point, Positive
from jointbench.estimators import selfcheck
from jointbench.estimators.batching import isolated
from jointbench.estimators.registry import register
from jointbench.estimators.results import CenterResult, frozen_rows
from jointbench.estimators.validation import check_markers, check_moves, prepare_trials
from jointbench.numerics.compiled import kernel, kernel_array
from jointbench.numerics.rank import RCOND, negligible
from jointbench.numerics.simplex import FMINSEARCH_OPTIONS, lockstep, nelder_mead, stop_status
from jointbench.numerics.spheres import (
    LSMoments,
    ls_moments,
    ls_system,
    mean_weights,
    row_sq,
    solve_ls_system,
)

__all__ = [
    "FMINSEARCH_OPTIONS",
    "fit_bc",
    "fit_is",
    "fit_ls",
    "fit_nm",
    "geometric_cost",
    "ls_system",
    "mean_sq_radii",
    "solve_ls_system",
]

_EPS = float(np.finfo(float).eps)
# Fewest frames a sphere fit takes (registered as each method's claim, checked in _prepare).
_MIN_FRAMES = 4


@lru_cache(maxsize=1)
def _lapack():
    """SciPy's LAPACK wrappers, imported on first use: the one-trial fits call them directly
    (NumPy's wrappers cost more than a 3x3 factorisation), but a job that fits whole batches
    never needs them and should not pay for importing ``scipy.linalg``."""
    from scipy.linalg import lapack

    return lapack


def _prepare(markers: object, min_frames: int = _MIN_FRAMES) -> np.ndarray:
    array = check_markers(markers, min_frames=min_frames, min_markers=1)
    check_moves(array)
    return array


def _check_point(point: object, name: str) -> np.ndarray:
    array = np.asarray(point, dtype=float)
    if array.shape != (3,):
        raise ValueError(f"{name} must be a point shaped (3,), got shape {array.shape}")
    if not np.all(np.isfinite(array)):
        raise ValueError(f"{name} contains NaN or inf")
    return array


def _symmetric_pinv(a_matrix: np.ndarray) -> np.ndarray:
    """Pseudo-inverse of the symmetric ``A`` with the rule of :func:`solve_ls_system`.

    For a symmetric matrix the singular values are the eigenvalues' magnitudes, so this is the
    same pseudo-inverse; LAPACK's ``dsyev`` is called directly because NumPy's wrappers cost more
    than the 3×3 factorisation itself.
    """
    eigenvalues, vectors, info = _lapack().dsyev(a_matrix)
    if info != 0:
        return np.linalg.pinv(a_matrix, rcond=RCOND)
    # Three scalars: plain Python is cheaper than NumPy calls on a 3-vector.
    values = eigenvalues.tolist()
    threshold = RCOND * max(abs(value) for value in values)
    inverse = [1.0 / value if abs(value) > threshold else 0.0 for value in values]
    return (vectors * inverse) @ vectors.T


def mean_sq_radii(markers: np.ndarray, center: np.ndarray) -> np.ndarray:
    """``r_p^2 = mean_k |v_k^p - c|^2`` ``(n_markers,)`` [mm^2]."""
    n_frames = markers.shape[0]
    sq = row_sq(markers.reshape(-1, 3) - center).reshape(n_frames, -1)
    return sq.sum(axis=0) / n_frames


def _algebraic_fit(moments: LSMoments, center: np.ndarray) -> tuple[np.ndarray, float]:
    """Radii ``(P,)`` [mm] with ``r_p^2`` profiled out of eq. 4, and the cost f2 [mm^4].

    From the moments instead of another pass over the data: with ``w = (-2 c, 1)``,
    ``|v - c|^2 - mean_k |v - c|^2 = (x - mean_k x) . w`` and
    ``r_p^2 = mean_k |v - c|^2 = mean_k x . w + |c|^2``.
    """
    x, y, z = center.tolist()
    weights = np.array([-2.0 * x, -2.0 * y, -2.0 * z, 1.0])
    residual = moments.centred @ weights
    sq_radii = moments.means @ weights + center @ center
    return np.sqrt(np.maximum(sq_radii, 0.0)), float(residual @ residual)


def _ls_solve(a_matrix: np.ndarray, b_vector: np.ndarray) -> np.ndarray:
    """``A^+ b`` by the rule of :func:`solve_ls_system`; by Cholesky where it drops nothing.

    For the positive semi-definite ``A`` with eigenvalues ``l1 >= l2 >= l3``,
    ``l3 / l1 >= 4 det(A) / trace(A)^3`` (``l1 l2 <= ((l1 + l2) / 2)^2`` and ``l1 <= trace``).
    When that bound exceeds 1e-10, a hundred times the rank threshold, no singular value would be
    dropped and ``A^+ b = A^-1 b``, which a Cholesky solve gives in half the time of an
    eigen-decomposition; otherwise (a hinge, a static marker set) the pseudo-inverse is used.
    """
    lower, info = _lapack().dpotrf(a_matrix, lower=1)
    if info == 0:
        l00, l11, l22 = lower.diagonal().tolist()
        determinant = (l00 * l11 * l22) ** 2
        if 4.0 * determinant > 1e-10 * float(a_matrix.trace()) ** 3:
            solution, info = _lapack().dpotrs(lower, b_vector, lower=1)
            if info == 0:
                return solution
    return _symmetric_pinv(a_matrix) @ b_vector


def _ls_start(markers: np.ndarray) -> tuple[np.ndarray, LSMoments]:
    """LS centre ``(3,)`` and the moments it came from, which are of the data relative to its
    first sample: far from the origin ``|v|^2`` would lose the radii to rounding."""
    moments = ls_moments(markers - markers[0, 0])
    return markers[0, 0] + _ls_solve(moments.a_matrix, moments.b_vector), moments


@register("center", "LS", min_frames=_MIN_FRAMES, color="#d95f02", marker="s")
def fit_ls(markers: np.ndarray) -> CenterResult:
    """Least-squares sphere fit of Gamage & Lasenby (2002): closed form, cost f2 (paper A eq. 4).

    For a pure hinge ``A`` is singular and the centre is the point on the axis given by the
    pseudo-inverse with the vanishing singular value dropped.

    Parameters
    ----------
    markers : (n_frames >= 4, n_markers, 3) array [mm], reference frame.

    Returns
    -------
    CenterResult with ``center`` (3,) [mm], ``radii`` (n_markers,) [mm] (``r_p^2`` the mean
    squared distance, the minimiser of eq. 4 over ``r_p``) and ``cost`` = f2 [mm^4].
    """
    markers = _prepare(markers)
    center, moments = _ls_start(markers)
    radii, cost = _algebraic_fit(moments, center - markers[0, 0])
    return CenterResult(
        center=center,
        radii=radii,
        converged=True,
        iterations=0,
        status="ok",
        method="LS",
        cost=cost,
    )


# --------------------------------------------------------------------------------------------
# NM — Chang & Pollard (2007), paper A §3–4
# --------------------------------------------------------------------------------------------


def _nm_scatter(scaled: np.ndarray) -> np.ndarray:
    """``S = D'D`` ``(4 + P, 4 + P)`` for the data matrix ``D`` of paper A eq. 22, built by blocks.

    Rows of ``D`` for marker ``p`` are ``[|v|^2, x, y, z, e_p]`` with ``e_p`` the one-hot
    indicator of the marker's own constant term.
    """
    n_frames, n_markers, _ = scaled.shape
    flat = scaled.reshape(-1, 3)
    basis = np.empty((flat.shape[0], 4))
    basis[:, 0] = row_sq(flat)
    basis[:, 1:] = flat
    scatter = np.zeros((4 + n_markers, 4 + n_markers))
    scatter[:4, :4] = basis.T @ basis
    # Per-marker sums over frames as a vector-matrix product (cheaper than a reduction here).
    scatter[:4, 4:] = (np.ones(n_frames) @ basis.reshape(n_frames, -1)).reshape(n_markers, 4).T
    scatter[4:, :4] = scatter[:4, 4:].T
    scatter[4:, 4:].flat[:: n_markers + 1] = n_frames
    return scatter


def _nm_design(scaled: np.ndarray) -> np.ndarray:
    """The data matrix ``D`` ``(P N, 4 + P)`` itself (paper A eq. 22)."""
    n_frames, n_markers, _ = scaled.shape
    per_marker = np.transpose(scaled, (1, 0, 2))
    w = np.sum(per_marker**2, axis=-1, keepdims=True)
    one_hot = np.repeat(np.eye(n_markers)[:, None, :], n_frames, axis=1)
    return np.concatenate([w, per_marker, one_hot], axis=-1).reshape(n_markers * n_frames, -1)


@lru_cache(maxsize=16)
def _nm_constraint(n_markers: int) -> np.ndarray:
    """Constraint matrix ``C`` of paper A eq. 24: ``u' C u = sum_p (b^2 + c^2 + d^2 - 4 a e_p)``.

    Cached per marker count and returned read-only.
    """
    constraint = np.zeros((4 + n_markers, 4 + n_markers))
    constraint[1:4, 1:4] = n_markers * np.eye(3)
    constraint[0, 4:] = constraint[4:, 0] = -2.0
    constraint.setflags(write=False)
    return constraint


def _largest_admissible(whitened: np.ndarray, constraint: np.ndarray) -> tuple[np.ndarray, float]:
    """Solve ``M y = mu y`` with ``M = W C W'``; return ``u = W' y`` of the largest ``mu > 0``."""
    m_matrix = whitened @ constraint @ whitened.T
    m_matrix = (m_matrix + m_matrix.T) / 2.0
    mu, y, info = _lapack().dsyev(m_matrix)
    if info != 0:
        mu, y = np.linalg.eigh(m_matrix)
    largest = float(mu[-1])
    if largest <= 0:
        raise ValueError("NM: no admissible sphere (every generalised eigenvalue is negative)")
    u = whitened.T @ y[:, -1]
    return u / np.sqrt(u @ constraint @ u), 1.0 / largest


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
    # LAPACK directly: for these (4+P)-square matrices NumPy's wrapper overhead dominates.
    lower, info = _lapack().dpotrf(scatter, lower=1)
    pivots = (lower.diagonal() ** 2).tolist() if info == 0 else None
    if pivots is not None and min(pivots) > 1e-9 * max(pivots):
        inverse, info = _lapack().dtrtri(lower, lower=1)
        if info == 0:
            return _largest_admissible(inverse, constraint)
    _, s, vt = np.linalg.svd(_nm_design(scaled), full_matrices=False)
    if s[-1] <= 1e-13 * s[0]:
        u = vt[-1]
        norm = u @ constraint @ u
        if norm > 0:
            return u / np.sqrt(norm), 0.0
    return _largest_admissible((vt.T / s).T, constraint)


@register("center", "NM", min_frames=_MIN_FRAMES, color="#1b9e77", marker="o")
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

    Parameters
    ----------
    markers : (n_frames >= 4, n_markers, 3) array [mm], reference frame.
    """
    markers = _prepare(markers)
    n_rows = markers.shape[0] * markers.shape[1]
    shifted = markers.reshape(-1, 3)
    origin = mean_weights(n_rows) @ shifted
    shifted = shifted - origin
    flat = shifted.reshape(-1)
    scale = float(np.sqrt((flat @ flat) / n_rows))
    scaled = (shifted / scale).reshape(markers.shape)
    u, cost = _nm_coefficients(scaled)
    a, bcd, e = float(u[0]), u[1:4], u[4:]
    if abs(a) < _EPS * float(np.abs(u).max()):
        raise ValueError("NM: the best fit is a plane (a = 0); the markers do not rotate")
    center_scaled = bcd / (-2.0 * a)
    sq_radii_scaled = center_scaled @ center_scaled - e / a
    return CenterResult(
        center=origin + scale * center_scaled,
        radii=scale * np.sqrt(np.maximum(sq_radii_scaled, 0.0)),
        converged=True,
        iterations=0,
        status="ok",
        method="NM",
        cost=cost,
    )


# --------------------------------------------------------------------------------------------
# BC — Halvorsen (2003), bias-compensated LS
# --------------------------------------------------------------------------------------------

# A centre that has moved this many times the markers' RMS distance from the LS centre away
# from it counts as divergence: no physical joint lies there and the fixed-point iteration does
# not come back from it.
_BC_DIVERGENCE_FACTOR = 1e3


class _BCState(NamedTuple):
    """What one BC iteration needs, in coordinates relative to the LS centre ``c_0``.

    With ``y = v - c_0`` and the centre ``c = c_0 + d``, ``u^2 = |y - d|^2`` and, for
    ``w = (-2 d, 1)``, ``u^2 - mean_k u^2 = (x - mean_k x) . w`` with ``x = (y, |y|^2)``: the sum
    of squares over frames is ``w' G_p w`` with ``G_p`` marker ``p``'s 4 x 4 Gram matrix of the
    centred ``x``. Each iteration then costs O(P), not O(N P). Working relative to ``c_0``
    keeps ``|y|^2`` of the order of the radii, so the Gram matrices lose no precision to
    cancellation even for data far from the origin.
    """

    moments: LSMoments  # of the shifted data y
    grams: np.ndarray  # (P, 4, 4)
    means: np.ndarray  # (P, 4): mean_k y and mean_k |y|^2
    b_vector: np.ndarray  # (3,) b of the shifted data
    sum_of_means: np.ndarray  # (3,) sum_p mean_k y_k^p
    n_frames: int


def _bc_state(markers: np.ndarray, origin: np.ndarray) -> _BCState:
    n_frames, n_markers, _ = markers.shape
    moments = ls_moments(markers - origin)
    rows = moments.centred.reshape(n_frames, n_markers, 4)
    grams = np.einsum("kpi,kpj->pij", rows, rows)
    sum_of_means = moments.means[:, :3].sum(axis=0)
    return _BCState(moments, grams, moments.means, moments.b_vector, sum_of_means, n_frames)


def _bc_noise_variance(state: _BCState, shift: np.ndarray) -> float:
    """Halvorsen's per-coordinate noise variance estimate ``sigma^2`` [mm^2] at ``c_0 + shift``.

    ``sigma_p^2 = sum_k (u_k^2 - mean u^2)^2 / (4 mean(u^2) N)`` with ``u_k = |v_k^p - c|``,
    averaged over the markers. The squared deviations of ``u^2`` are ``4 r^2 sigma^2`` to first
    order in the noise, hence the division by ``4 mean(u^2)``.
    """
    weights = np.empty(4)
    weights[:3] = -2.0 * shift
    weights[3] = 1.0
    spread = (state.grams @ weights) @ weights
    mean_sq = state.means @ weights + shift @ shift
    with np.errstate(divide="ignore", invalid="ignore"):
        return float(np.mean(spread / (4.0 * state.n_frames * mean_sq)))


# Stops on steps of 1e-4 mm.
@register("center", "BC", invariances=1e-3, min_frames=_MIN_FRAMES, color="#7570b3", marker="^")
def fit_bc(
    markers: np.ndarray,
    *,
    max_iterations: Count = 600,
    tol_x: Positive = 1e-4,
    tol_fun: Positive = 1e-4,
) -> CenterResult:
    """Bias-compensated least squares of Halvorsen (2003), started from the LS centre.

    Noise of per-coordinate variance ``sigma^2`` biases Gamage & Lasenby's normal equations:
    ``E[A] = A_0 + 2 P sigma^2 I`` and ``E[b] = b_0 + 2 sigma^2 sum_p mean(v^p)``. Starting from
    ``c_0 = A^+ b`` (the LS centre, :func:`fit_ls`), every iteration ``j = 0, 1, ...``

    1. estimates ``sigma_j^2 = mean_p sum_k (u_k^2 - mean u^2)^2 / (4 mean(u^2) N)`` with
       ``u_k = |v_k^p - c_j|`` (one variance shared by the markers);
    2. forms ``db = 2 sigma_j^2 sum_p (mean(v^p) - c_j)``;
    3. updates ``c_{j+1} = A^+ (b - db)`` (``A`` and ``b`` stay those of the data; ``A^+`` is
       the pseudo-inverse of :func:`solve_ls_system`).

    The sums over frames are evaluated from per-marker moments (see ``_BCState``); the
    arithmetic is that of the formulas above.

    Stopping rule. Paper A (§5): "The convergence criterion for BC was set to the same values as
    fminsearch", i.e. TolX = TolFun = 1e-4 and at most 200·n = 600 iterations for n = 3
    unknowns. Halvorsen's own rule is not known, so, as ``fminsearch`` requires both its x and
    its function-value tests, the iteration has converged after update ``j`` when
    ``max_i |c_{j+1,i} - c_{j,i}| <= tol_x`` [mm] **and** ``|sigma^2(c_{j+1}) - sigma^2(c_j)|
    <= tol_fun`` [mm^2] (``sigma^2`` is the quantity BC re-estimates besides the centre; it has
    no cost function of its own). ``iterations`` counts the updates made.

    Failure is reported, never raised: ``converged=False`` with ``status`` saying
    ``"maximum iterations (600) reached without convergence"``, ``"non-finite ..."`` (the last
    finite centre is returned) or ``"diverged ..."`` (the centre has moved more than ``1e3``
    times the markers' RMS distance from the LS centre away from the LS centre).

    Parameters
    ----------
    markers : (n_frames >= 4, n_markers, 3) array [mm], reference frame.
    max_iterations, tol_x, tol_fun : the fminsearch-equivalent limits above.

    Returns
    -------
    CenterResult with ``center`` (3,) [mm], ``radii`` (n_markers,) [mm] (root mean squared
    distances, as for LS), ``cost`` = f2 (eq. 4) at the centre [mm^4], and
    ``diagnostics["noise_variance"]`` the final ``sigma^2`` [mm^2].
    """
    markers = _prepare(markers)
    n_markers = markers.shape[1]
    origin, moments = _ls_start(markers)
    a_pinv = _symmetric_pinv(moments.a_matrix)
    state = _bc_state(markers, origin)
    # Relative to c_0: d_{j+1} = A^+ (b_y - 2 sigma^2 (sum_p mean y^p - P d_j)), d_0 = 0.
    shift = np.zeros(3)
    limit = _BC_DIVERGENCE_FACTOR * float(np.sqrt(np.mean(state.means[:, 3])))

    sigma2 = _bc_noise_variance(state, shift)
    converged = False
    status = f"maximum iterations ({max_iterations}) reached without convergence"
    iterations = 0
    if not math.isfinite(sigma2):
        status = "non-finite noise variance at the LS start"
    else:
        for iterations in range(1, max_iterations + 1):
            compensation = (2.0 * sigma2) * (state.sum_of_means - n_markers * shift)
            new_shift = a_pinv @ (state.b_vector - compensation)
            new_sigma2 = _bc_noise_variance(state, new_shift)
            step = float(np.abs(new_shift - shift).max())
            if not (math.isfinite(step) and math.isfinite(new_sigma2)):
                status = f"non-finite centre or noise variance at iteration {iterations}"
                break
            change = abs(new_sigma2 - sigma2)
            shift, sigma2 = new_shift, new_sigma2
            if step <= tol_x and change <= tol_fun:
                converged, status = True, "ok"
                break
            if math.sqrt(shift @ shift) > limit:
                status = (
                    f"diverged at iteration {iterations}: centre more than {limit:.3g} mm "
                    "from the LS centre"
                )
                break
    # Radii and f2 are translation invariant: evaluate them in the shifted coordinates.
    radii, cost = _algebraic_fit(state.moments, shift)
    center = origin + shift
    return CenterResult(
        center=center,
        radii=radii,
        converged=converged,
        iterations=iterations,
        status=status,
        method="BC",
        cost=cost,
        diagnostics={"noise_variance": sigma2},
    )


# --------------------------------------------------------------------------------------------
# IS — iterative search on the geometric cost f1
# --------------------------------------------------------------------------------------------


def _geometric_costs(
    centers: np.ndarray, flats: np.ndarray, trials: np.ndarray, n_frames: int
) -> np.ndarray:
    """f1 with the radii profiled out for centres ``(k, 3)`` [mm], each on its trial's rows
    ``flats[trials]`` (``flats`` ``(n_trials, n_frames * n_markers, 3)`` frame-major).

    Element by element, so a centre's cost is the same whichever centres share the call (the
    one-trial search and the many-trial one then take the same path).
    """
    # Distances from differences, not |v|^2 - 2 v.c + |c|^2: no cancellation far from the origin.
    rows = flats[trials]
    dx = rows[..., 0] - centers[:, 0, None]
    dy = rows[..., 1] - centers[:, 1, None]
    dz = rows[..., 2] - centers[:, 2, None]
    distance = np.sqrt(dx * dx + dy * dy + dz * dz).reshape(len(centers), n_frames, -1)
    distance -= np.add.reduce(distance, axis=1, keepdims=True) / n_frames
    distance = distance.reshape(len(centers), -1)
    return np.einsum("kr,kr->k", distance, distance)


def geometric_cost(markers: np.ndarray, center: np.ndarray) -> float:
    """Geometric sphere-fit cost f1 (paper A eq. 2) at ``center``, radii profiled out.

    ``f1 = sum_p sum_k (|v_k^p - c| - r_p)^2`` with ``r_p = mean_k |v_k^p - c|``, the radius that
    minimises f1 for a fixed centre.

    Parameters
    ----------
    markers : (n_frames, n_markers, 3) array [mm].
    center : (3,) array [mm].

    Returns
    -------
    f1 [mm^2].
    """
    markers = check_markers(markers)
    center = _check_point(center, "center")
    flat = markers.reshape(1, -1, 3)
    return float(_geometric_costs(center[None], flat, np.zeros(1, int), markers.shape[0])[0])


# A simplex stopped at 1e-4 mm.
@register("center", "IS", invariances=1e-3, min_frames=_MIN_FRAMES, color="#66a61e", marker="v")
def fit_is(markers: np.ndarray, start: Point | None = None) -> CenterResult:
    """Iterative search: minimise the geometric cost f1 (paper A eq. 2) by Nelder–Mead.

    Paper A (§5) minimised f1 with MATLAB's ``fminsearch`` started from the LS centre; here
    :func:`jointbench.numerics.simplex.nelder_mead` with :data:`FMINSEARCH_OPTIONS`, the same
    initial simplex, moves and termination test. The radii are
    profiled out (``r_p`` = mean distance, the closed-form minimiser for a fixed centre), so the
    search is over the 3 coordinates of the centre only — paper A does not say whether it
    searched over the radii too; profiling them out is the cheaper and better-posed choice.

    Choices the paper leaves open, made here:

    * the simplex is built in the caller's coordinates: its initial edges are 5 % of the start's
      coordinates (0.00025 mm where a coordinate is zero), so a translation of the data changes
      the search path and the result moves with the data only to within the tolerance (and, in
      hard cases, may fall into a different local minimum);
    * ``start`` lets a study restart from another point, e.g. the true centre, to classify a
      result as a local minimum (paper A claim A7): a trial whose IS result has a higher f1 than
      IS restarted from the true centre.

    On small-RoM data f1 flattens towards the plane limit (centre at infinity along the
    trajectories' normal); a simplex that wanders onto that plateau can meet fminsearch's test
    there and stop metres away with ``converged=True``. That is the behaviour of the method as
    specified, reported as it is; ``fatol`` is absolute, so compare f1 values to about 1e-4.

    Parameters
    ----------
    markers : (n_frames >= 4, n_markers, 3) array [mm], reference frame.
    start : (3,) [mm] starting centre; default the LS centre (:func:`fit_ls`).

    Returns
    -------
    CenterResult with ``center`` (3,) [mm], ``radii`` (n_markers,) the mean distances [mm],
    ``cost`` = f1 [mm^2], ``converged`` the optimiser's success (False when it stops at 600
    iterations or function evaluations) and ``iterations`` its iteration count;
    ``diagnostics["function_evaluations"]``.
    """
    markers, start = _is_prepare(markers, start)
    n_frames = markers.shape[0]
    flat = np.ascontiguousarray(markers.reshape(1, -1, 3))
    trial = np.zeros(1, dtype=int)
    search = nelder_mead(
        lambda *x: float(_geometric_costs(np.array([x]), flat, trial, n_frames)[0]),
        start,
        **FMINSEARCH_OPTIONS,
    )
    return _is_result(search, flat[0], n_frames)


def _is_prepare(markers: object, start: object | None) -> tuple[np.ndarray, np.ndarray]:
    """IS's validated markers and starting centre (the LS centre by default)."""
    markers = _prepare(markers)
    return markers, _ls_start(markers)[0] if start is None else _check_point(start, "start")


def _fit_is_batch(markers: object, start: object | None = None) -> list[CenterResult | ValueError]:
    """:func:`fit_is` for every trial of ``markers`` ``(n_trials, N, P, 3)``, the searches
    advanced together (:func:`jointbench.numerics.simplex.lockstep`), each on its own path."""
    outcomes, prepared = prepare_trials(markers, lambda data: _is_prepare(data, start))
    if prepared:
        arrays, starts = zip(*prepared.values(), strict=True)
        n_frames = arrays[0].shape[0]
        flats = np.ascontiguousarray(np.stack(arrays).reshape(len(arrays), -1, 3))
        searches = lockstep(
            lambda centers, owners: _geometric_costs(centers, flats, owners, n_frames),
            np.stack(starts),
            **FMINSEARCH_OPTIONS,
        )
        for index, (trial, search) in enumerate(zip(prepared, searches, strict=True)):
            outcomes[trial] = _is_result(search, flats[index], n_frames)
    return outcomes


def _is_result(search, flat: np.ndarray, n_frames: int) -> CenterResult:
    """IS's :class:`CenterResult` from its simplex search on rows ``(n_frames * P, 3)``."""
    center = np.array(search.x)
    finite = bool(np.all(np.isfinite(center)) and math.isfinite(search.fun))
    radii = mean_weights(n_frames) @ np.sqrt(row_sq(flat - center)).reshape(n_frames, -1)
    status = stop_status(search, FMINSEARCH_OPTIONS["max_fev"])
    return CenterResult(
        center=center,
        radii=radii,
        converged=search.converged and finite,
        iterations=search.iterations,
        status="ok" if search.converged and finite else status,
        method="IS",
        cost=float(search.fun),
        diagnostics={"function_evaluations": search.evaluations},
    )


# --------------------------------------------------------------------------------------------
# Many trials at once: LS, NM and BC over markers (n_trials, n_frames, n_markers, 3)
# --------------------------------------------------------------------------------------------


def _screen(markers: object, min_frames: int = _MIN_FRAMES) -> tuple[np.ndarray, np.ndarray]:
    """Stacked trials as float64 and the mask of those :func:`_prepare` would reject, or
    might (a coordinate at exactly zero).

    The checks are vectorised over trials; a masked trial is then passed to the one-trial
    function, which fits it or raises its own ``ValueError``.
    """
    array = np.asarray(markers, dtype=float)
    if array.ndim != 4 or array.shape[-1] != 3 or array.shape[1] < min_frames:
        return array, np.ones(array.shape[0] if array.ndim else 1, dtype=bool)
    first = array[:, :1]
    with np.errstate(invalid="ignore", over="ignore"):
        # A sum is finite only if every term is (an overflow merely sends a trial to the
        # one-trial path, which decides).
        finite = np.isfinite(array.sum(axis=(1, 2, 3)))
        # In place: a second full-size temporary costs more than the arithmetic.
        offsets = array - first
        spread = np.abs(offsets, out=offsets).max(axis=(1, 2, 3))
        scale = np.maximum(1.0, np.abs(first).max(axis=(1, 2, 3)))
        still = spread <= 1e-9 * scale
        # A coordinate at exactly zero may belong to a sample at (0, 0, 0), how some readers
        # store gaps, which the one-trial checks refuse; a coordinate is cheaper to test than a
        # sample.
        touches_zero = np.abs(array, out=offsets).min(axis=(1, 2, 3)) == 0
    return array, ~finite | still | touches_zero | (array.shape[2] < 1)


def _screened(markers: np.ndarray, good: np.ndarray) -> np.ndarray:
    """The trials ``good`` of ``markers``: the array itself when that is all of them (copying
    a whole batch costs as much as a closed-form fit)."""
    return markers if good.size == markers.shape[0] else markers[good]


def _with_fallback(fit, markers: np.ndarray, outcomes: list, redo: np.ndarray) -> list:
    """Fill ``outcomes`` for the trials in ``redo`` with the one-trial ``fit`` (or its error)."""
    for trial in np.flatnonzero(redo):
        try:
            outcomes[trial] = fit(markers[trial])
        except ValueError as error:
            outcomes[trial] = error
    return outcomes


def _ls_moments_batch(markers: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """:class:`LSMoments` of every trial: ``A`` (T, 3, 3), ``b`` (T, 3), means (T, P, 4),
    centred rows (T, N P, 4)."""
    n_trials, n_frames, n_markers, _ = markers.shape
    augmented = np.empty((n_trials, n_frames, n_markers, 4))
    augmented[..., :3] = markers
    np.einsum("...i,...i->...", markers, markers, out=augmented[..., 3])
    # The sum over frames as a vector-matrix product: reducing the middle axis is slower.
    means = (np.ones(n_frames) @ augmented.reshape(n_trials, n_frames, -1)).reshape(
        n_trials, n_markers, 4
    )
    means *= 1.0 / n_frames
    augmented -= means[:, None]
    centred = augmented.reshape(n_trials, -1, 4)
    gram = np.swapaxes(centred, 1, 2) @ centred
    gram *= 1.0 / n_frames
    return 2.0 * gram[:, :3, :3], gram[:, :3, 3].copy(), means, centred


def _pinv_solve_batch(a_matrix: np.ndarray, b_vector: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``A^+ b`` (T, 3) and ``A^+`` (T, 3, 3) by the rule of :func:`solve_ls_system`."""
    values, vectors = np.linalg.eigh(a_matrix)
    largest = np.abs(values).max(axis=-1, keepdims=True)
    keep = ~negligible(values, largest)
    inverse = np.where(keep, 1.0 / np.where(keep, values, 1.0), 0.0)
    pinv = (vectors * inverse[:, None, :]) @ np.swapaxes(vectors, 1, 2)
    return np.einsum("tij,tj->ti", pinv, b_vector), pinv


def _algebraic_fit_batch(means, centred, center) -> tuple[np.ndarray, np.ndarray]:
    """Radii (T, P) [mm] and cost f2 (T,) of :func:`_algebraic_fit` for every trial."""
    weights = np.concatenate([-2.0 * center, np.ones((center.shape[0], 1))], axis=1)
    residual = np.einsum("tri,ti->tr", centred, weights)
    sq_radii = (
        np.einsum("tpi,ti->tp", means, weights) + np.einsum("ti,ti->t", center, center)[:, None]
    )
    return np.sqrt(np.maximum(sq_radii, 0.0)), np.einsum("tr,tr->t", residual, residual)


def _fit_ls_batch(markers: np.ndarray) -> list[CenterResult | ValueError]:
    markers, bad = _screen(markers)
    outcomes: list = [None] * len(bad)
    good = np.flatnonzero(~bad)
    if good.size:
        a_matrix, b_vector, means, centred = _ls_moments_batch(_screened(markers, good))
        centers, _ = _pinv_solve_batch(a_matrix, b_vector)
        radii, costs = _algebraic_fit_batch(means, centred, centers)
        _closed_form_results(outcomes, "LS", good, centers, radii, costs)
    return _with_fallback(fit_ls, markers, outcomes, bad)


def _closed_form_results(outcomes, method, trials, centers, radii, costs) -> None:
    """Fill ``outcomes[trials]`` with a closed form's :class:`CenterResult` (centres ``(T, 3)``,
    radii ``(T, P)`` [mm], costs ``(T,)``), its fields taken from one read-only copy each."""
    for trial, center, radius, cost in zip(
        trials, frozen_rows(centers), frozen_rows(radii), costs.tolist(), strict=True
    ):
        outcomes[trial] = CenterResult(
            center=center,
            radii=radius,
            converged=True,
            iterations=0,
            status="ok",
            method=method,
            cost=cost,
        )


def _fit_nm_batch(markers: np.ndarray) -> list[CenterResult | ValueError]:
    markers, bad = _screen(markers)
    outcomes: list = [None] * len(bad)
    good = np.flatnonzero(~bad)
    if good.size:
        data = kernel_array(_screened(markers, good))
        n_trials, _, n_markers, _ = data.shape
        centers, radii = np.empty((n_trials, 3)), np.empty((n_trials, n_markers))
        costs, solved = np.empty(n_trials), np.empty(n_trials, dtype=bool)
        _nm_trials(data, _nm_constraint(n_markers), _EPS, centers, radii, costs, solved)
        # A trial without a solution here -- a (nearly) singular scatter, as for noise-free
        # data, or no admissible sphere -- goes to the one-trial function, which solves it
        # otherwise or says why not.
        bad[good[~solved]] = True
        _closed_form_results(
            outcomes, "NM", good[solved], centers[solved], radii[solved], costs[solved]
        )
    return _with_fallback(fit_nm, markers, outcomes, bad)


@kernel
def _nm_trials(
    data: np.ndarray,
    constraint: np.ndarray,
    eps: float,
    centers: np.ndarray,
    radii: np.ndarray,
    costs: np.ndarray,
    solved: np.ndarray,
) -> None:
    """:func:`fit_nm` of each trial of ``data`` (T, N, P, 3) [mm] whose scatter is regular:
    centres (T, 3) [mm], radii (T, P) [mm] and costs (T,) into the arrays given, and
    ``solved`` (T,) false where the scatter is (nearly) singular or no admissible sphere
    exists. ``constraint`` is :func:`_nm_constraint`, ``eps`` the float64 machine epsilon. A
    compiled kernel (:mod:`jointbench.numerics.compiled`).

    The same steps as :func:`_nm_coefficients`, written out for small matrices: the scatter of
    the unit-RMS design (paper A eq. 22) by blocks, its Cholesky factor ``L``, the admissible
    eigenvector of largest ``mu`` of ``W C W'`` with ``W = L^-1``, ``u = W' y``.
    """
    n_trials, n_frames, n_markers, _ = data.shape
    size = 4 + n_markers
    n_rows = n_frames * n_markers
    scatter = np.empty((size, size))
    lower = np.empty((size, size))
    whitened = np.empty((size, size))
    product = np.empty((size, size))
    m_matrix = np.empty((size, size))
    for t in range(n_trials):
        trial = data[t]
        ox = oy = oz = 0.0
        for f in range(n_frames):
            for p in range(n_markers):
                ox += trial[f, p, 0]
                oy += trial[f, p, 1]
                oz += trial[f, p, 2]
        ox, oy, oz = ox / n_rows, oy / n_rows, oz / n_rows
        spread = 0.0
        for f in range(n_frames):
            for p in range(n_markers):
                dx, dy, dz = trial[f, p, 0] - ox, trial[f, p, 1] - oy, trial[f, p, 2] - oz
                spread += dx * dx + dy * dy + dz * dz
        scale = math.sqrt(spread / n_rows)
        inverse_scale = 1.0 / scale
        # The 4 x 4 block sums basis' basis over every row, basis = (|s|^2, s) for the scaled
        # sample s; column 4 + p sums the basis over marker p's rows. Scalars, so that the sums
        # stay in registers.
        s00 = s01 = s02 = s03 = s11 = s12 = s13 = s22 = s23 = s33 = 0.0
        scatter[:] = 0.0
        for p in range(n_markers):
            m0 = m1 = m2 = m3 = 0.0
            for f in range(n_frames):
                x = (trial[f, p, 0] - ox) * inverse_scale
                y = (trial[f, p, 1] - oy) * inverse_scale
                z = (trial[f, p, 2] - oz) * inverse_scale
                w = x * x + y * y + z * z
                s00 += w * w
                s01 += w * x
                s02 += w * y
                s03 += w * z
                s11 += x * x
                s12 += x * y
                s13 += x * z
                s22 += y * y
                s23 += y * z
                s33 += z * z
                m0 += w
                m1 += x
                m2 += y
                m3 += z
            scatter[0, 4 + p], scatter[1, 4 + p] = m0, m1
            scatter[2, 4 + p], scatter[3, 4 + p] = m2, m3
            scatter[4 + p, 4 + p] = n_frames
        scatter[0, 0], scatter[0, 1], scatter[0, 2], scatter[0, 3] = s00, s01, s02, s03
        scatter[1, 1], scatter[1, 2], scatter[1, 3] = s11, s12, s13
        scatter[2, 2], scatter[2, 3], scatter[3, 3] = s22, s23, s33
        for i in range(size):
            for j in range(i):
                scatter[i, j] = scatter[j, i]
        solved[t] = False
        # Cholesky: a pivot that is not positive means a singular scatter.
        regular = True
        for j in range(size):
            pivot = scatter[j, j]
            for k in range(j):
                pivot -= lower[j, k] * lower[j, k]
            if not pivot > 0.0:
                regular = False
                break
            lower[j, j] = math.sqrt(pivot)
            for i in range(j + 1, size):
                value = scatter[i, j]
                for k in range(j):
                    value -= lower[i, k] * lower[j, k]
                lower[i, j] = value / lower[j, j]
        if not regular:
            continue
        smallest, largest_pivot = lower[0, 0] ** 2, lower[0, 0] ** 2
        for j in range(1, size):
            smallest = min(smallest, lower[j, j] ** 2)
            largest_pivot = max(largest_pivot, lower[j, j] ** 2)
        if not smallest > 1e-9 * largest_pivot:
            continue
        # W = L^-1, lower triangular, by forward substitution column by column.
        whitened[:] = 0.0
        for j in range(size):
            whitened[j, j] = 1.0 / lower[j, j]
            for i in range(j + 1, size):
                value = 0.0
                for k in range(j, i):
                    value -= lower[i, k] * whitened[k, j]
                whitened[i, j] = value / lower[i, i]
        # M = W C W', exactly symmetric, then its eigenvector of the largest eigenvalue.
        for i in range(size):
            for j in range(size):
                value = 0.0
                for k in range(j + 1):
                    value += constraint[i, k] * whitened[j, k]
                product[i, j] = value
        for i in range(size):
            for j in range(i + 1):
                value = 0.0
                for k in range(i + 1):
                    value += whitened[i, k] * product[k, j]
                m_matrix[i, j] = m_matrix[j, i] = value
        mu, eigenvectors = np.linalg.eigh(m_matrix)
        largest = mu[-1]
        vectors = eigenvectors[:, -1]
        u = np.zeros(size)
        for i in range(size):
            for k in range(i, size):
                u[i] += whitened[k, i] * vectors[k]
        norm = 0.0
        for i in range(size):
            for j in range(size):
                norm += u[i] * constraint[i, j] * u[j]
        if not (largest > 0.0 and norm > 0.0):
            continue
        u /= math.sqrt(norm)
        a = u[0]
        if not abs(a) >= eps * np.abs(u).max():
            continue
        center_scaled = u[1:4] / (-2.0 * a)
        squared_distance = 0.0
        for i in range(3):
            squared_distance += center_scaled[i] * center_scaled[i]
        centers[t, 0] = ox + scale * center_scaled[0]
        centers[t, 1] = oy + scale * center_scaled[1]
        centers[t, 2] = oz + scale * center_scaled[2]
        for p in range(n_markers):
            radii[t, p] = scale * math.sqrt(max(squared_distance - u[4 + p] / a, 0.0))
        costs[t] = 1.0 / largest
        solved[t] = True


def _fit_bc_batch(
    markers: np.ndarray,
    *,
    max_iterations: int = 600,
    tol_x: float = 1e-4,
    tol_fun: float = 1e-4,
) -> list[CenterResult | ValueError]:
    """:func:`fit_bc` for every trial, iterated in lockstep; each trial stops by its own test.

    Trials that fail otherwise than by reaching the iteration limit (non-finite, diverged) are
    re-run one at a time, so their statuses are the one-trial function's.
    """
    markers, bad = _screen(markers)
    outcomes: list = [None] * len(bad)
    good = np.flatnonzero(~bad)
    if good.size:
        data = _screened(markers, good)
        n_trials, n_frames, n_markers, _ = data.shape
        a_matrix, b_vector, _, _ = _ls_moments_batch(data)
        origin, a_pinv = _pinv_solve_batch(a_matrix, b_vector)
        _, b_shifted, means, centred = _ls_moments_batch(data - origin[:, None, None, :])
        rows = centred.reshape(n_trials, n_frames, n_markers, 4)
        grams = np.einsum("tkpi,tkpj->tpij", rows, rows)
        sum_of_means = means[..., :3].sum(axis=1)
        limit = _BC_DIVERGENCE_FACTOR * np.sqrt(means[..., 3].mean(axis=1))

        def noise_variance(shift: np.ndarray) -> np.ndarray:
            weights = np.concatenate([-2.0 * shift, np.ones((n_trials, 1))], axis=1)
            spread = np.einsum("tpij,ti,tj->tp", grams, weights, weights)
            mean_sq = (
                np.einsum("tpi,ti->tp", means, weights)
                + np.einsum("ti,ti->t", shift, shift)[:, None]
            )
            return np.mean(spread / (4.0 * n_frames * mean_sq), axis=1)

        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            shift = np.zeros((n_trials, 3))
            sigma2 = noise_variance(shift)
            active = np.isfinite(sigma2)
            iterations = np.zeros(n_trials, dtype=int)
            converged = np.zeros(n_trials, dtype=bool)
            for iteration in range(1, max_iterations + 1):
                if not active.any():
                    break
                compensation = (2.0 * sigma2)[:, None] * (sum_of_means - n_markers * shift)
                new_shift = np.einsum("tij,tj->ti", a_pinv, b_shifted - compensation)
                new_sigma2 = noise_variance(new_shift)
                step = np.abs(new_shift - shift).max(axis=1)
                active &= np.isfinite(step) & np.isfinite(new_sigma2)
                change = np.abs(new_sigma2 - sigma2)
                shift = np.where(active[:, None], new_shift, shift)
                sigma2 = np.where(active, new_sigma2, sigma2)
                iterations[active] = iteration
                done = active & (step <= tol_x) & (change <= tol_fun)
                converged |= done
                active &= ~done
                active &= np.sqrt(np.einsum("ti,ti->t", shift, shift)) <= limit
        radii, costs = _algebraic_fit_batch(means, centred, shift)
        exhausted = f"maximum iterations ({max_iterations}) reached without convergence"
        for index, trial in enumerate(good):
            if not (converged[index] or active[index]):
                bad[trial] = True
                continue
            outcomes[trial] = CenterResult(
                center=origin[index] + shift[index],
                radii=radii[index],
                converged=bool(converged[index]),
                iterations=int(iterations[index]),
                status="ok" if converged[index] else exhausted,
                method="BC",
                cost=float(costs[index]),
                diagnostics={"noise_variance": float(sigma2[index])},
            )
    one_trial = partial(fit_bc, max_iterations=max_iterations, tol_x=tol_x, tol_fun=tol_fun)
    return _with_fallback(one_trial, markers, outcomes, bad)


def _is_self_check(result: CenterResult, markers: np.ndarray, start=None) -> CenterResult:
    """IS's f1 against f1 at its closed-form neighbours, the LS and NM centres; where one is
    lower by more than fminsearch's TolFun, IS restarted from it (one more search, paid only
    then). See :mod:`jointbench.estimators.selfcheck`."""
    del start  # the answer is judged, wherever it was started
    neighbours = {"the LS centre": _ls_start(markers)[0]}
    try:
        neighbours["the NM centre"] = np.asarray(fit_nm(markers).center)
    except ValueError:
        pass  # no NM centre to compare with (a plane); the LS one remains
    n_frames = markers.shape[0]
    flat = np.ascontiguousarray(markers.reshape(1, -1, 3))
    points = np.stack(list(neighbours.values()))
    costs = _geometric_costs(points, flat, np.zeros(len(points), dtype=int), n_frames)
    best = int(np.argmin(costs))
    name = list(neighbours)[best]
    if not costs[best] < result.cost - FMINSEARCH_OPTIONS["fatol"]:
        return selfcheck.held(
            result,
            f"f1 at {' and '.join(neighbours)} is not below the answer's {result.cost:.6g} "
            f"by more than TolFun (least {float(costs[best]):.6g})",
        )
    better = fit_is(markers, start=points[best])
    moved = float(np.linalg.norm(better.center - result.center))
    return selfcheck.restarted(
        result, better, name, f"{moved:.3g} mm from the first answer, which is replaced"
    )


def _bc_self_check(
    result: CenterResult,
    markers: np.ndarray,
    *,
    max_iterations: int = 600,
    tol_x: float = 1e-4,
    tol_fun: float = 1e-4,
) -> CenterResult:
    """Whether BC's answer is its fixed point: one more of Halvorsen's updates, computed from
    the markers about the returned centre (not from the moments the iteration used), must
    move it by at most ``tol_x``. BC has no cost to compare (:func:`fit_bc`); the update is
    its defining equation. See :mod:`jointbench.estimators.selfcheck`."""
    del max_iterations, tol_fun
    if not result.converged:
        return result
    n_frames = markers.shape[0]
    # About the returned centre c: y = v - c, and the update's shift from c is
    # A^+ (b_y - 2 sigma^2 sum_p mean_k y^p) (A does not change with the shift).
    offsets = markers - np.asarray(result.center)
    a_matrix, b_vector = ls_system(offsets)
    squared = np.einsum("kpi,kpi->kp", offsets, offsets)
    mean_squared = squared.mean(axis=0)
    sigma2 = float(
        np.mean(((squared - mean_squared) ** 2).sum(axis=0) / (4.0 * mean_squared * n_frames))
    )
    compensation = 2.0 * sigma2 * offsets.mean(axis=0).sum(axis=0)
    step = float(np.abs(solve_ls_system(a_matrix, b_vector - compensation)).max())
    if step <= tol_x:
        return selfcheck.held(
            result,
            f"one more update from the returned centre moves it by {step:.3g} mm "
            f"(tol_x = {tol_x:g})",
        )
    return selfcheck.failed(
        result,
        f"not BC's fixed point: one more update from the returned centre moves it by "
        f"{step:.3g} mm, more than tol_x = {tol_x:g}",
    )


fit_is.self_check = _is_self_check
fit_bc.self_check = _bc_self_check
fit_ls.batched = isolated(_fit_ls_batch)
fit_nm.batched = isolated(_fit_nm_batch)
fit_bc.batched = isolated(_fit_bc_batch)
fit_is.batched = isolated(_fit_is_batch)
