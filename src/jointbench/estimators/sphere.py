"""Sphere-fitting centre-of-rotation estimators: LS, NM, BC and IS.

All take the moving segment's markers in the reference frame, ``(n_frames, n_markers, 3)``
[mm], and fit concentric spheres (one radius per marker, common centre). Equation numbers refer
to paper A (Chang & Pollard 2007, J Biomech 40:1392).

The two iterative methods reproduce paper A's MATLAB settings (§5): IS is minimised by
``fminsearch`` at its defaults (:mod:`jointbench.numerics.simplex`), and "the convergence
criterion for BC was set to the same values as fminsearch" (TolX = TolFun = 1e-4, at most
200·n = 600 iterations for the n = 3 unknowns of a centre). :data:`FMINSEARCH_OPTIONS` holds
those settings.

Each method is written once, over a stack of trials ``(n_trials, n_frames, n_markers, 3)``
(``_ls_fits``, ``_nm_fits``, ``_bc_fits``, ``_is_fits``): the one-trial function is that
implementation on a batch of one, and its ``batched`` form the same over many trials. The loops
over samples and iterations run in compiled kernels (:mod:`jointbench.numerics.compiled`) whose
Python source is the implementation.
"""

from __future__ import annotations

import math
from functools import lru_cache, partial
from typing import NamedTuple

import numpy as np

from jointbench.declared import Count, Point, Positive
from jointbench.estimators import selfcheck
from jointbench.estimators.batching import isolated
from jointbench.estimators.registry import register, register_many
from jointbench.estimators.results import CenterResult, frozen_rows
from jointbench.estimators.validation import check_markers, check_moves, prepare_trials
from jointbench.numerics.compiled import kernel, kernel_array
from jointbench.numerics.magnitudes import largest_coordinate
from jointbench.numerics.rank import RCOND
from jointbench.numerics.simplex import FMINSEARCH_OPTIONS, lockstep, stop_status
from jointbench.numerics.small import symmetric_eigen_into
from jointbench.numerics.spheres import ls_system, mean_weights, row_sq, solve_ls_system

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


def mean_sq_radii(markers: np.ndarray, center: np.ndarray) -> np.ndarray:
    """``r_p^2 = mean_k |v_k^p - c|^2`` ``(n_markers,)`` [mm^2]."""
    n_frames = markers.shape[0]
    sq = row_sq(markers.reshape(-1, 3) - center).reshape(n_frames, -1)
    return sq.sum(axis=0) / n_frames


def _one(outcomes: list) -> CenterResult:
    """The outcome of a batch of one trial: its result, or its error raised."""
    (outcome,) = outcomes
    if isinstance(outcome, Exception):
        raise outcome
    return outcome


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
        magnitudes = np.abs(array, out=offsets)
        touches_zero = magnitudes.min(axis=(1, 2, 3)) == 0
        # Finite but too large for the fits' sums: the one-trial checks refuse it.
        too_large = magnitudes.max(axis=(1, 2, 3)) > largest_coordinate(
            array.shape[1] * array.shape[2]
        )
    return array, ~finite | still | touches_zero | too_large | (array.shape[2] < 1)


def _screened(markers: np.ndarray, good: np.ndarray) -> np.ndarray:
    """The trials ``good`` of ``markers``: the array itself when that is all of them (copying
    a whole batch costs as much as a closed-form fit)."""
    return markers if good.size == markers.shape[0] else markers[good]


def _over_trials(fits, fit_one, markers: object, **options) -> list[CenterResult | ValueError]:
    """A method's many-trial form: ``fits(data, **options)`` (its implementation over validated
    trials ``(T, N, P, 3)`` [mm], one outcome per trial) on the trials :func:`_screen` passes;
    a trial it does not is given to the one-trial ``fit_one``, whose checks decide (its
    ``ValueError`` becomes that trial's outcome)."""
    markers, bad = _screen(markers)
    outcomes: list = [None] * len(bad)
    good = np.flatnonzero(~bad)
    if good.size:
        for trial, outcome in zip(good, fits(_screened(markers, good), **options), strict=True):
            outcomes[trial] = outcome
    for trial in np.flatnonzero(bad):
        try:
            outcomes[trial] = fit_one(markers[trial], **options)
        except ValueError as error:
            outcomes[trial] = error
    return outcomes


@kernel
def _sphere_moments(data: np.ndarray, origins: np.ndarray, means: np.ndarray, grams: np.ndarray):
    """Per-marker moments of each trial's samples ``y = v - origin`` augmented to
    ``x = (y, |y|^2)``: ``means`` (T, P, 4) the means over frames [mm, mm^2] and ``grams``
    (T, P, 4, 4) the sums over frames of ``(x - mean x)(x - mean x)'``, into the arrays given,
    for ``data`` (T, N, P, 3) [mm] and ``origins`` (T, 3) [mm]. A compiled kernel
    (:mod:`jointbench.numerics.compiled`): this source is the implementation.

    Every sum Gamage & Lasenby's fit and Halvorsen's iteration need is a product with these:
    ``A = 2 sum_p G_p[:3, :3] / N`` and ``b = sum_p G_p[:3, 3] / N`` (paper A eq. 4 minimised
    over the centre), and ``sum_k (|y - d|^2 - mean_k |y - d|^2)^2 = w' G_p w`` for
    ``w = (-2 d, 1)``. Relative to an origin near the data ``|y|^2`` keeps the precision that
    ``|v|^2`` would lose far from the coordinates' origin.
    """
    n_trials, n_frames, n_markers, _ = data.shape
    rows = np.empty((n_frames, 4))
    for t in range(n_trials):
        for p in range(n_markers):
            means[t, p] = 0.0
            grams[t, p] = 0.0
            for f in range(n_frames):
                squared = 0.0
                for i in range(3):
                    rows[f, i] = data[t, f, p, i] - origins[t, i]
                    squared += rows[f, i] * rows[f, i]
                rows[f, 3] = squared
                for i in range(4):
                    means[t, p, i] += rows[f, i]
            for i in range(4):
                means[t, p, i] /= n_frames
            for f in range(n_frames):
                for i in range(4):
                    rows[f, i] -= means[t, p, i]
                for i in range(4):
                    for j in range(i + 1):
                        grams[t, p, i, j] += rows[f, i] * rows[f, j]
            for i in range(4):
                for j in range(i):
                    grams[t, p, j, i] = grams[t, p, i, j]


def _moments(data: np.ndarray, origins: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_sphere_moments` of ``data`` (T, N, P, 3) about ``origins`` (T, 3) [mm]:
    ``means`` (T, P, 4) and ``grams`` (T, P, 4, 4)."""
    n_trials, _, n_markers, _ = data.shape
    means, grams = np.empty((n_trials, n_markers, 4)), np.empty((n_trials, n_markers, 4, 4))
    _sphere_moments(kernel_array(data), kernel_array(origins), means, grams)
    return means, grams


@kernel
def _ls_solve(
    grams: np.ndarray, n_frames: int, rcond: float, a_pinv: np.ndarray, shifts: np.ndarray
) -> None:
    """Gamage & Lasenby's centre of each trial from the moments of :func:`_sphere_moments`
    (``grams`` (T, P, 4, 4)) about its origin: ``A = 2 sum_p G_p[:3, :3] / N``,
    ``b = sum_p G_p[:3, 3] / N``, ``A^+`` (T, 3, 3) into ``a_pinv`` and ``A^+ b`` (T, 3) [mm]
    into ``shifts``. ``A^+`` by the rule of :func:`solve_ls_system`, eigenvalues of magnitude
    at most ``rcond`` times the largest dropped (for a symmetric matrix the singular values
    are the eigenvalues' magnitudes). A compiled kernel (:mod:`jointbench.numerics.compiled`):
    this source is the implementation."""
    n_trials, n_markers = grams.shape[0], grams.shape[1]
    a_matrix = np.empty((3, 3))
    b_vector = np.empty(3)
    for t in range(n_trials):
        for i in range(3):
            b_vector[i] = 0.0
            for j in range(3):
                a_matrix[i, j] = 0.0
        for p in range(n_markers):
            for i in range(3):
                b_vector[i] += grams[t, p, i, 3]
                for j in range(3):
                    a_matrix[i, j] += grams[t, p, i, j]
        for i in range(3):
            b_vector[i] *= 1.0 / n_frames
            for j in range(3):
                a_matrix[i, j] = 2.0 * (a_matrix[i, j] * (1.0 / n_frames))
        values, vectors = np.linalg.eigh(a_matrix)
        largest = max(abs(values[0]), abs(values[2]))  # ascending
        for i in range(3):
            for j in range(3):
                a_pinv[t, i, j] = 0.0
        for k in range(3):
            if abs(values[k]) > rcond * largest:
                for i in range(3):
                    for j in range(3):
                        a_pinv[t, i, j] += vectors[i, k] * vectors[j, k] / values[k]
        for i in range(3):
            shifts[t, i] = 0.0
            for j in range(3):
                shifts[t, i] += a_pinv[t, i, j] * b_vector[j]


@kernel
def _algebraic_fits(
    data: np.ndarray,
    origins: np.ndarray,
    means: np.ndarray,
    shifts: np.ndarray,
    radii: np.ndarray,
    costs: np.ndarray,
) -> None:
    """Radii (T, P) [mm] with ``r_p^2`` profiled out of eq. 4, and the cost f2 (T,) [mm^4], of
    each trial of ``data`` (T, N, P, 3) [mm] at the centre ``origins + shifts`` (T, 3) [mm],
    into ``radii`` and ``costs``; ``means`` (T, P, 4) are those of :func:`_sphere_moments`
    about ``origins``. A compiled kernel (:mod:`jointbench.numerics.compiled`): this source is
    the implementation.

    With ``y = v - origin``, ``x = (y, |y|^2)`` and ``w = (-2 shift, 1)``:
    ``r_p^2 = mean_k |y - shift|^2 = mean_k x . w + |shift|^2``, and each residual
    ``|y - shift|^2 - mean_k |y - shift|^2`` is ``(x - mean_k x) . w``, summed in squares.
    """
    n_trials, n_frames, n_markers, _ = data.shape
    x = np.empty(4)
    for t in range(n_trials):
        squared_shift = shifts[t, 0] ** 2 + shifts[t, 1] ** 2 + shifts[t, 2] ** 2
        for p in range(n_markers):
            value = 0.0
            for i in range(3):
                value += means[t, p, i] * (-2.0 * shifts[t, i])
            value += means[t, p, 3]
            radii[t, p] = math.sqrt(max(value + squared_shift, 0.0))
        cost = 0.0
        for f in range(n_frames):
            for p in range(n_markers):
                squared = 0.0
                for i in range(3):
                    x[i] = data[t, f, p, i] - origins[t, i]
                    squared += x[i] * x[i]
                x[3] = squared
                residual = x[3] - means[t, p, 3]
                for i in range(3):
                    residual += (x[i] - means[t, p, i]) * (-2.0 * shifts[t, i])
                cost += residual * residual
        costs[t] = cost


def _algebraic_fit(
    data: np.ndarray, origins: np.ndarray, means: np.ndarray, shifts: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_algebraic_fits`: radii (T, P) [mm] and f2 (T,) [mm^4]."""
    radii, costs = np.empty(means.shape[:2]), np.empty(shifts.shape[0])
    _algebraic_fits(*(kernel_array(a) for a in (data, origins, means, shifts)), radii, costs)
    return radii, costs


class _LSFit(NamedTuple):
    """Gamage & Lasenby's fit of each trial, in coordinates relative to its first sample
    (far from the origin ``|v|^2`` would lose the radii to rounding)."""

    origin: np.ndarray  # (T, 3) [mm], each trial's first sample
    shift: np.ndarray  # (T, 3) [mm], the LS centre relative to ``origin``
    a_pinv: np.ndarray  # (T, 3, 3) [mm^-2], A^+ (A does not change with the origin)
    means: np.ndarray  # (T, P, 4), of :func:`_sphere_moments` about ``origin``


def _ls_fit(data: np.ndarray) -> _LSFit:
    """:class:`_LSFit` of validated trials ``(T, N, P, 3)`` [mm]."""
    n_trials, n_frames = data.shape[:2]
    origin = data[:, 0, 0]
    means, grams = _moments(data, origin)
    a_pinv, shift = np.empty((n_trials, 3, 3)), np.empty((n_trials, 3))
    _ls_solve(grams, n_frames, RCOND, a_pinv, shift)
    return _LSFit(origin, shift, a_pinv, means)


def _closed_form_results(method, centers, radii, costs) -> list[CenterResult]:
    """A closed form's :class:`CenterResult` per trial (centres ``(T, 3)``, radii ``(T, P)``
    [mm], costs ``(T,)``), its fields taken from one read-only copy each."""
    return [
        CenterResult(
            center=center,
            radii=radius,
            converged=True,
            iterations=0,
            status="ok",
            method=method,
            cost=cost,
        )
        for center, radius, cost in zip(
            frozen_rows(centers), frozen_rows(radii), costs.tolist(), strict=True
        )
    ]


def _ls_fits(data: np.ndarray) -> list[CenterResult]:
    """:func:`fit_ls` of validated trials ``(T, N, P, 3)`` [mm]."""
    fit = _ls_fit(data)
    radii, costs = _algebraic_fit(data, fit.origin, fit.means, fit.shift)
    return _closed_form_results("LS", fit.origin + fit.shift, radii, costs)


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
    return _one(_ls_fits(_prepare(markers)[None]))


def _fit_ls_batch(markers: object) -> list[CenterResult | ValueError]:
    return _over_trials(_ls_fits, fit_ls, markers)


# --------------------------------------------------------------------------------------------
# NM — Chang & Pollard (2007), paper A §3–4
# --------------------------------------------------------------------------------------------


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


# Why a trial has no NM centre, by the code :func:`_nm_trials` gives it.
_NM_FAILURES = {
    1: "NM: no admissible sphere (every generalised eigenvalue is negative)",
    2: "NM: the best fit is a plane (a = 0); the markers do not rotate",
}


def _nm_design(scaled: np.ndarray) -> np.ndarray:
    """The data matrix ``D`` ``(P N, 4 + P)`` of paper A eq. 22 for markers ``(N, P, 3)``:
    rows ``[|v|^2, x, y, z, e_p]``, ``e_p`` the one-hot indicator of marker ``p``'s constant."""
    n_frames, n_markers, _ = scaled.shape
    per_marker = np.transpose(scaled, (1, 0, 2))
    w = np.sum(per_marker**2, axis=-1, keepdims=True)
    one_hot = np.repeat(np.eye(n_markers)[:, None, :], n_frames, axis=1)
    return np.concatenate([w, per_marker, one_hot], axis=-1).reshape(n_markers * n_frames, -1)


def _nm_singular(markers: np.ndarray) -> CenterResult | ValueError:
    """NM of one trial ``(N, P, 3)`` [mm] whose scatter ``S = D'D`` is (nearly) singular, as
    for noise-free data, which :func:`_nm_trials` leaves: the problem of :func:`_nm_trials`,
    whitened with ``W = diag(1 / s) V'`` from the SVD of ``D`` at its full size
    (``W' W = S^+``); an exact fit is ``D``'s null vector."""
    n_rows = markers.shape[0] * markers.shape[1]
    shifted = markers.reshape(-1, 3)
    origin = mean_weights(n_rows) @ shifted
    shifted = shifted - origin
    flat = shifted.reshape(-1)
    scale = float(np.sqrt((flat @ flat) / n_rows))
    constraint = _nm_constraint(markers.shape[1])
    _, s, vt = np.linalg.svd(_nm_design((shifted / scale).reshape(markers.shape)), False)
    u, cost = vt[-1], 0.0
    norm = u @ constraint @ u
    if not (s[-1] <= 1e-13 * s[0] and norm > 0):
        whitened = (vt.T / s).T
        m_matrix = whitened @ constraint @ whitened.T
        mu, y = np.linalg.eigh((m_matrix + m_matrix.T) / 2.0)
        if not mu[-1] > 0:
            return ValueError(_NM_FAILURES[1])
        u, cost = whitened.T @ y[:, -1], 1.0 / float(mu[-1])
        norm = u @ constraint @ u
    u = u / np.sqrt(norm)
    a, bcd, e = float(u[0]), u[1:4], u[4:]
    if not abs(a) >= _EPS * float(np.abs(u).max()):
        return ValueError(_NM_FAILURES[2])
    center = bcd / (-2.0 * a)
    (result,) = _closed_form_results(
        "NM",
        (origin + scale * center)[None],
        (scale * np.sqrt(np.maximum(center @ center - e / a, 0.0)))[None],
        np.array([cost]),
    )
    return result


def _nm_fits(data: np.ndarray) -> list[CenterResult | ValueError]:
    """:func:`fit_nm` of validated trials ``(T, N, P, 3)`` [mm] by the kernel
    :func:`_nm_trials`, a trial with a singular scatter by :func:`_nm_singular`; a trial
    without a centre carries the ``ValueError`` saying why."""
    data = kernel_array(data)
    n_trials, _, n_markers, _ = data.shape
    centers, radii = np.empty((n_trials, 3)), np.empty((n_trials, n_markers))
    costs, failures = np.empty(n_trials), np.zeros(n_trials, dtype=np.int64)
    _nm_trials(data, _EPS, centers, radii, costs, failures)
    outcomes: list = _closed_form_results("NM", centers, radii, costs)
    for trial in np.flatnonzero(failures):
        code = int(failures[trial])
        outcomes[trial] = _nm_singular(data[trial]) if code == 3 else ValueError(_NM_FAILURES[code])
    return outcomes


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
    return _one(_nm_fits(_prepare(markers)[None]))


def _fit_nm_batch(markers: object) -> list[CenterResult | ValueError]:
    return _over_trials(_nm_fits, fit_nm, markers)


@kernel
def _nm_trials(
    data: np.ndarray,
    eps: float,
    centers: np.ndarray,
    radii: np.ndarray,
    costs: np.ndarray,
    failures: np.ndarray,
) -> None:
    """NM's fit of each trial of ``data`` (T, N, P, 3) [mm] (see :func:`fit_nm`): centres
    (T, 3) [mm], radii (T, P) [mm] and costs (T,) into the arrays given, and ``failures`` (T,)
    a key of :data:`_NM_FAILURES` where a trial has no centre, 3 where its scatter is (nearly)
    singular, 0 where it has a centre; ``eps`` the float64 machine epsilon. A compiled kernel
    (:mod:`jointbench.numerics.compiled`): this source is the implementation.

    Minimise ``|D u|^2`` subject to ``u' C u = 1`` (paper A eq. 15) for the data matrix ``D``
    of the unit-RMS markers (eq. 22, rows ``[|s|^2, s, e_p]``, :func:`_nm_design`) and ``C`` of
    eq. 24 (:func:`_nm_constraint`): ``S u = lambda C u`` (eq. 17) with ``S = D'D``, whose
    admissible eigenvector of least cost ``lambda`` is that of the largest positive
    ``mu = 1 / lambda``; ``m = -(b, c, d) / 2a`` (eq. 18), ``r_p^2 = |m|^2 - e_p / a``. A
    (nearly) singular ``S``, as for noise-free data, is left to :func:`_nm_singular` (code 3).
    Never formed at its size ``4 + P``: the problem's structure reduces it to five unknowns,
    in time and memory linear in the markers.

    The scatter ``S = [[A, B], [B', N I]]`` (``A`` 4 x 4, ``B`` 4 x P, ``N`` frames) and the
    constraint ``C = G K G'`` of rank 5 (``G = [e_0, e_1, e_2, e_3, (0, 1_P)]``,
    ``K = [[0, 0, -2], [0, P I_3, 0], [-2, 0, 0]]`` by blocks 1, 3, 1) have structure:

    * Cholesky's pivots of ``S`` (``A``'s rows first) are those of ``A``, then of
      ``N I - U U'`` with ``U = B' L_A^-T`` (P x 4), each ``d_p = N - u_p' Q_p u_p`` with
      ``Q_0 = I``, ``Q_{p+1} = Q_p + Q_p u_p u_p' Q_p / d_p`` (the Schur complement of the
      pivots before it), the test of a singular scatter (code 3) the same;
    * ``S u = lambda C u`` has its positive ``mu = 1 / lambda`` where ``u = S^-1 G x`` with
      ``K H x = mu x``, ``H = G' S^-1 G`` (5 x 5); with any ``H = F F'`` and ``y = F' x``,
      ``F' K F y = mu y`` is symmetric; ``S``'s problem whitened, ``W C W' y = mu y``
      with ``W' W = S^-1``, has these five eigenvalues and zeros;
    * ``S^-1`` by the Schur complement of the diagonal block,
      ``Z = A - B B' / N = sum_p sum_f (s_f - m_p)(s_f - m_p)'`` over marker ``p``'s basis
      rows ``s_f = (|v|^2, v)`` about their mean ``m_p``: ``S [u_1; u_2] = [v_1; v_2]`` gives
      ``u_1 = Z^-1 (v_1 - B v_2 / N)``, ``u_2 = (v_2 - B' u_1) / N``; so
      ``H = E' diag(Z^-1, P / N) E`` with ``E = [[I, -b / N], [0, 1]]``, ``b`` the sum of
      ``B``'s columns, and ``F`` follows from ``Z``'s Cholesky factor
      (:func:`_nm_factor_into`), neither ``Z^-1`` nor ``H`` formed; a pivot of ``Z`` that is
      not positive is a singular scatter's rounding (code 3).

    Every matrix is 4 x 4 or 5 x 5, its entries in loops or in the package's Jacobi
    eigen-solve (:func:`jointbench.numerics.small.symmetric_eigen_into`): a few markers' fit
    takes microseconds, and LAPACK's calls on matrices this small spend more on their overhead
    than on the arithmetic.
    """
    n_trials, n_frames, n_markers, _ = data.shape
    size = 4 + n_markers
    sums = np.empty((4, n_markers))
    u = np.empty(size)
    corner = np.empty((4, 4))
    lower = np.empty((4, 4))
    within = np.empty((4, 4))
    carried = np.empty((4, 4))
    row = np.empty(4)
    q_row = np.empty(4)
    total = np.empty(4)
    factor = np.empty((5, 5))
    reduced = np.empty((5, 5))
    mu = np.empty(5)
    eigenvectors = np.empty((5, 5))
    work = np.empty((5, 5))
    for t in range(n_trials):
        trial = data[t]
        failures[t] = 0
        ox, oy, oz, scale = _nm_origin_scale(trial)
        inverse_scale = 1.0 / scale
        # A and Z by their ten distinct entries, in scalars that stay in registers: the basis
        # of a row is (w, x, y, z), w = |s|^2 of the scaled sample s.
        a_ww = a_wx = a_wy = a_wz = a_xx = a_xy = a_xz = a_yy = a_yz = a_zz = 0.0
        z_ww = z_wx = z_wy = z_wz = z_xx = z_xy = z_xz = z_yy = z_yz = z_zz = 0.0
        t_w = t_x = t_y = t_z = 0.0
        for p in range(n_markers):
            m_w = m_x = m_y = m_z = 0.0
            for f in range(n_frames):
                x = (trial[f, p, 0] - ox) * inverse_scale
                y = (trial[f, p, 1] - oy) * inverse_scale
                z = (trial[f, p, 2] - oz) * inverse_scale
                w = x * x + y * y + z * z
                m_w += w
                m_x += x
                m_y += y
                m_z += z
                a_ww += w * w
                a_wx += w * x
                a_wy += w * y
                a_wz += w * z
                a_xx += x * x
                a_xy += x * y
                a_xz += x * z
                a_yy += y * y
                a_yz += y * z
                a_zz += z * z
            sums[0, p], sums[1, p], sums[2, p], sums[3, p] = m_w, m_x, m_y, m_z
            # Z about each marker's own mean, in a second pass: one pass's A - B B' / N
            # would cancel where a marker moves little against its distance from the origin.
            c_w, c_x, c_y, c_z = m_w / n_frames, m_x / n_frames, m_y / n_frames, m_z / n_frames
            for f in range(n_frames):
                x = (trial[f, p, 0] - ox) * inverse_scale
                y = (trial[f, p, 1] - oy) * inverse_scale
                z = (trial[f, p, 2] - oz) * inverse_scale
                w = x * x + y * y + z * z - c_w
                x -= c_x
                y -= c_y
                z -= c_z
                z_ww += w * w
                z_wx += w * x
                z_wy += w * y
                z_wz += w * z
                z_xx += x * x
                z_xy += x * y
                z_xz += x * z
                z_yy += y * y
                z_yz += y * z
                z_zz += z * z
            t_w += m_w
            t_x += m_x
            t_y += m_y
            t_z += m_z
        _nm_symmetric_into(a_ww, a_wx, a_wy, a_wz, a_xx, a_xy, a_xz, a_yy, a_yz, a_zz, corner)
        _nm_symmetric_into(z_ww, z_wx, z_wy, z_wz, z_xx, z_xy, z_xz, z_yy, z_yz, z_zz, within)
        total[0], total[1], total[2], total[3] = t_w, t_x, t_y, t_z
        # Cholesky's pivots of S: A's, then the Schur complements' of N I - U U'.
        regular, smallest, largest_pivot = _nm_cholesky_into(corner, lower)
        carried[:] = 0.0
        for i in range(4):
            carried[i, i] = 1.0
        for p in range(n_markers if regular else 0):
            for j in range(4):
                value = sums[j, p]
                for k in range(j):
                    value -= row[k] * lower[j, k]
                row[j] = value / lower[j, j]
            pivot = float(n_frames)
            for i in range(4):
                q_row[i] = 0.0
                for j in range(4):
                    q_row[i] += carried[i, j] * row[j]
                pivot -= row[i] * q_row[i]
            if not pivot > 0.0:
                regular = False
                break
            smallest, largest_pivot = min(smallest, pivot), max(largest_pivot, pivot)
            for i in range(4):
                for j in range(4):
                    carried[i, j] += q_row[i] * q_row[j] / pivot
        if not (regular and smallest > 1e-9 * largest_pivot):
            failures[t] = 3
            continue
        # H = G' S^-1 G = F F' with F = [[R, 0], [-b' R / N, sqrt(P / N)]], R = L_Z^-T from
        # Z = L_Z L_Z' and b the sum of B's columns; a pivot of Z that is not positive is a
        # singular scatter's rounding.
        if not _nm_factor_into(within, total, n_frames, n_markers, lower, factor):
            failures[t] = 3
            continue
        _nm_reduced_into(factor, n_markers, reduced)
        symmetric_eigen_into(reduced, mu, eigenvectors, work)
        largest = mu[4]
        # u = S^-1 G x with x = F^-T y: u_1 = R y_1, x_5 = y_5 / sqrt(P / N), and
        # u_2 = (x_5 - B' u_1) / N by the Schur complement of the diagonal block.
        for i in range(4):
            value = 0.0
            for k in range(i, 4):
                value += factor[i, k] * eigenvectors[k, 4]
            u[i] = value
        x_5 = eigenvectors[4, 4] / factor[4, 4]
        for p in range(n_markers):
            value = x_5
            for i in range(4):
                value -= sums[i, p] * u[i]
            u[4 + p] = value / n_frames
        spread = 0.0
        for p in range(n_markers):
            spread += u[4 + p]
        norm = n_markers * (u[1] * u[1] + u[2] * u[2] + u[3] * u[3]) - 4.0 * u[0] * spread
        _nm_answer_into(
            u, largest, norm, eps, scale, ox, oy, oz, t, centers, radii, costs, failures
        )


@kernel
def _nm_cholesky_into(matrix: np.ndarray, lower: np.ndarray) -> tuple[bool, float, float]:
    """The Cholesky factor ``L`` of the symmetric ``matrix`` ``(4, 4)`` (its lower triangle
    read) into the lower triangle of ``lower`` ``(4, 4)``: ``(every pivot positive, least
    pivot, largest pivot)``, stopping at the first pivot that is not positive (the pivots
    then those before it). A compiled kernel."""
    smallest, largest = np.inf, 0.0
    for j in range(4):
        pivot = matrix[j, j]
        for k in range(j):
            pivot -= lower[j, k] * lower[j, k]
        if not pivot > 0.0:
            return False, smallest, largest
        smallest, largest = min(smallest, pivot), max(largest, pivot)
        lower[j, j] = math.sqrt(pivot)
        for i in range(j + 1, 4):
            value = matrix[i, j]
            for k in range(j):
                value -= lower[i, k] * lower[j, k]
            lower[i, j] = value / lower[j, j]
    return True, smallest, largest


@kernel
def _nm_factor_into(
    within: np.ndarray,
    total: np.ndarray,
    n_frames: int,
    n_markers: int,
    lower: np.ndarray,
    factor: np.ndarray,
) -> bool:
    """A factor ``F`` ``(5, 5)`` of NM's reduced matrix ``H = G' S^-1 G = F F'`` (see
    :func:`_nm_trials`) into ``factor``, from ``Z`` (``within``, ``(4, 4)``), ``b`` (``total``,
    ``(4,)``, the sum of the scatter's columns ``B``), ``N`` frames and ``P`` markers:
    ``F = [[R, 0], [-b' R / N, sqrt(P / N)]]`` with ``R = L^-T`` from ``Z = L L'``
    (``lower`` ``(4, 4)``, scratch), as ``H = E' diag(Z^-1, P / N) E`` with
    ``E = [[I, -b / N], [0, 1]]``. False where a pivot of ``Z`` is not positive. A compiled
    kernel."""
    if not _nm_cholesky_into(within, lower)[0]:
        return False
    # R = L^-T, upper triangular: row j of R is column j of L^-1, by forward substitution.
    for j in range(4):
        factor[j, j] = 1.0 / lower[j, j]
        for i in range(j + 1, 4):
            value = 0.0
            for k in range(j, i):
                value -= lower[i, k] * factor[j, k]
            factor[j, i] = value / lower[i, i]
        for i in range(j):
            factor[j, i] = 0.0
        factor[j, 4] = 0.0
    for j in range(4):
        value = 0.0
        for k in range(j + 1):
            value -= total[k] * factor[k, j]
        factor[4, j] = value / n_frames
    factor[4, 4] = math.sqrt(n_markers / n_frames)
    return True


@kernel
def _nm_reduced_into(factor: np.ndarray, n_markers: int, out: np.ndarray) -> None:
    """``F' K F`` ``(5, 5)`` into ``out`` for NM's factor ``F`` (:func:`_nm_factor_into`) and
    ``K = [[0, 0, -2], [0, P I_3, 0], [-2, 0, 0]]`` by blocks 1, 3, 1, ``P`` markers: the
    symmetric matrix whose eigenvector of the largest eigenvalue is NM's (see
    :func:`_nm_trials`). Both triangles written. A compiled kernel."""
    for i in range(5):
        for j in range(i, 5):
            value = n_markers * (
                factor[1, i] * factor[1, j]
                + factor[2, i] * factor[2, j]
                + factor[3, i] * factor[3, j]
            ) - 2.0 * (factor[0, i] * factor[4, j] + factor[4, i] * factor[0, j])
            out[i, j] = out[j, i] = value


@kernel
def _nm_origin_scale(trial: np.ndarray) -> tuple[float, float, float, float]:
    """The centroid ``(x, y, z)`` [mm] of one trial's markers ``(N, P, 3)`` [mm] and their RMS
    distance from it [mm], the origin and scale of NM's unit-RMS data. A compiled kernel."""
    n_frames, n_markers, _ = trial.shape
    n_rows = n_frames * n_markers
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
    return ox, oy, oz, math.sqrt(spread / n_rows)


@kernel
def _nm_symmetric_into(
    ww: float,
    wx: float,
    wy: float,
    wz: float,
    xx: float,
    xy: float,
    xz: float,
    yy: float,
    yz: float,
    zz: float,
    out: np.ndarray,
) -> None:
    """The symmetric 4 x 4 matrix of the basis ``(w, x, y, z)`` of NM's data matrix (paper A
    eq. 22) with these distinct entries into ``out`` ``(4, 4)``. A compiled kernel."""
    out[0, 0], out[0, 1], out[0, 2], out[0, 3] = ww, wx, wy, wz
    out[1, 0], out[1, 1], out[1, 2], out[1, 3] = wx, xx, xy, xz
    out[2, 0], out[2, 1], out[2, 2], out[2, 3] = wy, xy, yy, yz
    out[3, 0], out[3, 1], out[3, 2], out[3, 3] = wz, xz, yz, zz


@kernel
def _nm_answer_into(
    u: np.ndarray,
    largest: float,
    norm: float,
    eps: float,
    scale: float,
    ox: float,
    oy: float,
    oz: float,
    t: int,
    centers: np.ndarray,
    radii: np.ndarray,
    costs: np.ndarray,
    failures: np.ndarray,
) -> None:
    """Trial ``t``'s NM answer from the eigenvector ``u`` ``(4 + P,)`` of the largest
    eigenvalue ``largest`` of the whitened problem, ``norm = u' C u``: its centre [mm], radii
    [mm] and cost into row ``t`` of ``centers``, ``radii`` and ``costs``, or its failure code
    (:data:`_NM_FAILURES`) into ``failures[t]``; ``u`` is normalised in place. A compiled
    kernel."""
    n_markers = u.shape[0] - 4
    if not (largest > 0.0 and norm > 0.0):
        failures[t] = 1
        return
    for i in range(u.shape[0]):
        u[i] /= math.sqrt(norm)
    costs[t] = 1.0 / largest
    a = u[0]
    biggest = 0.0
    for i in range(u.shape[0]):
        biggest = max(biggest, abs(u[i]))
    if not abs(a) >= eps * biggest:
        failures[t] = 2
        return
    # The scaled centre in scalars: slices and their quotient would be allocated per trial.
    cx, cy, cz = u[1] / (-2.0 * a), u[2] / (-2.0 * a), u[3] / (-2.0 * a)
    squared_distance = cx * cx + cy * cy + cz * cz
    centers[t, 0] = ox + scale * cx
    centers[t, 1] = oy + scale * cy
    centers[t, 2] = oz + scale * cz
    for p in range(n_markers):
        radii[t, p] = scale * math.sqrt(max(squared_distance - u[4 + p] / a, 0.0))


# --------------------------------------------------------------------------------------------
# BC — Halvorsen (2003), bias-compensated LS
# --------------------------------------------------------------------------------------------

# A centre that has moved this many times the markers' RMS distance from the LS centre away
# from it counts as divergence: no physical joint lies there and the fixed-point iteration does
# not come back from it.
_BC_DIVERGENCE_FACTOR = 1e3


# How a BC iteration ended, per trial.
_EXHAUSTED, _CONVERGED, _NONFINITE_START, _NONFINITE, _DIVERGED = range(5)


def _bc_status(stop: int, iterations: int, max_iterations: int, limit: float) -> str:
    return {
        _EXHAUSTED: f"maximum iterations ({max_iterations}) reached without convergence",
        _CONVERGED: "ok",
        _NONFINITE_START: "non-finite noise variance at the LS start",
        _NONFINITE: f"non-finite centre or noise variance at iteration {iterations}",
        _DIVERGED: (
            f"diverged at iteration {iterations}: centre more than {limit:.3g} mm "
            "from the LS centre"
        ),
    }[stop]


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

    The sums over frames are evaluated from per-marker moments (see :func:`_bc_fits`); the
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
    options = {"max_iterations": max_iterations, "tol_x": tol_x, "tol_fun": tol_fun}
    return _one(_bc_fits(_prepare(markers)[None], **options))


def _fit_bc_batch(markers: object, **options) -> list[CenterResult | ValueError]:
    return _over_trials(_bc_fits, fit_bc, markers, **options)


def _bc_fits(
    data: np.ndarray, *, max_iterations: int = 600, tol_x: float = 1e-4, tol_fun: float = 1e-4
) -> list[CenterResult]:
    """:func:`fit_bc` of validated trials ``(T, N, P, 3)`` [mm], iterated together; each trial
    stops by its own test.

    Relative to each trial's LS centre ``c_0``: with ``y = v - c_0`` and the centre
    ``c = c_0 + d``, ``u^2 = |y - d|^2`` and, for ``w = (-2 d, 1)``,
    ``u^2 - mean_k u^2 = (x - mean_k x) . w`` with ``x = (y, |y|^2)``: the sum of squares over
    frames is ``w' G_p w`` with ``G_p`` marker ``p``'s 4 x 4 Gram matrix of the centred ``x``.
    Each iteration then costs O(P), not O(N P), and ``|y|^2`` stays of the order of the radii,
    so the Gram matrices lose no precision to cancellation even far from the origin.
    """
    n_trials, n_frames, _, _ = data.shape
    ls = _ls_fit(data)
    origin = ls.origin + ls.shift
    means, grams = _moments(data, origin)
    total = grams.sum(axis=1)
    b_vector = total[:, :3, 3] * (1.0 / n_frames)
    sum_of_means = means[..., :3].sum(axis=1)
    limits = _BC_DIVERGENCE_FACTOR * np.sqrt(means[..., 3].mean(axis=1))

    shifts, sigma2 = np.empty((n_trials, 3)), np.empty(n_trials)
    iterations, stops = np.empty(n_trials, dtype=np.int64), np.empty(n_trials, dtype=np.int64)
    _bc_iterations(
        *(kernel_array(a) for a in (grams, means, sum_of_means, ls.a_pinv, b_vector, limits)),
        n_frames,
        int(max_iterations),
        float(tol_x),
        float(tol_fun),
        shifts,
        sigma2,
        iterations,
        stops,
    )
    # Radii and f2 are translation invariant: evaluate them in the shifted coordinates.
    radii, costs = _algebraic_fit(data, origin, means, shifts)
    return [
        CenterResult(
            center=center,
            radii=radius,
            converged=stop == _CONVERGED,
            iterations=count,
            status=_bc_status(stop, count, max_iterations, limit),
            method="BC",
            cost=cost,
            diagnostics={"noise_variance": variance},
        )
        for center, radius, stop, count, limit, cost, variance in zip(
            origin + shifts,
            radii,
            stops.tolist(),
            iterations.tolist(),
            limits.tolist(),
            costs.tolist(),
            sigma2.tolist(),
            strict=True,
        )
    ]


@kernel
def _bc_iterations(
    grams: np.ndarray,
    means: np.ndarray,
    sum_of_means: np.ndarray,
    a_pinv: np.ndarray,
    b_vector: np.ndarray,
    limits: np.ndarray,
    n_frames: int,
    max_iterations: int,
    tol_x: float,
    tol_fun: float,
    shifts: np.ndarray,
    sigma2: np.ndarray,
    iterations: np.ndarray,
    stops: np.ndarray,
) -> None:
    """Halvorsen's iteration of each trial, relative to its LS centre (see :func:`_bc_fits`):
    from Gram matrices ``grams`` (T, P, 4, 4), ``means`` (T, P, 4), ``sum_of_means`` (T, 3)
    [mm], ``A^+`` (T, 3, 3), ``b`` (T, 3) and divergence ``limits`` (T,) [mm], the final shift
    from the LS centre (T, 3) [mm], ``sigma^2`` (T,) [mm^2], the updates made and how each
    trial stopped (``_EXHAUSTED``, ...) into the arrays given. A compiled kernel
    (:mod:`jointbench.numerics.compiled`): this source is the implementation.

    Each pass estimates ``sigma^2`` at the candidate shift ``d``,
    ``mean_p (w' G_p w) / (4 N (mean_p . w + |d|^2))`` with ``w = (-2 d, 1)``, tests it
    against the last accepted one, then updates
    ``d = A^+ (b - 2 sigma^2 (sum_p mean y^p - P d))``.
    """
    n_trials, n_markers = means.shape[0], means.shape[1]
    weights = np.empty(4)
    candidate = np.empty(3)
    shift = np.empty(3)
    for t in range(n_trials):
        candidate[:] = 0.0
        shift[:] = 0.0
        variance = math.nan
        stops[t] = 0  # _EXHAUSTED unless another stop comes first
        iterations[t] = 0
        for iteration in range(max_iterations + 1):
            for i in range(3):
                weights[i] = -2.0 * candidate[i]
            weights[3] = 1.0
            squared = candidate[0] ** 2 + candidate[1] ** 2 + candidate[2] ** 2
            estimate = 0.0
            for p in range(n_markers):
                spread = 0.0
                for i in range(4):
                    row = 0.0
                    for j in range(4):
                        row += grams[t, p, i, j] * weights[j]
                    spread += row * weights[i]
                mean_sq = squared
                for i in range(4):
                    mean_sq += means[t, p, i] * weights[i]
                estimate += spread / (4.0 * n_frames * mean_sq)
            estimate /= n_markers
            if iteration == 0:
                if not math.isfinite(estimate):
                    stops[t] = 2  # _NONFINITE_START
                    break
            else:
                step = 0.0
                for i in range(3):
                    step = max(step, abs(candidate[i] - shift[i]))
                if not (math.isfinite(step) and math.isfinite(estimate)):
                    stops[t], iterations[t] = 3, iteration  # _NONFINITE
                    break
                change = abs(estimate - variance)
                shift[:] = candidate
                iterations[t] = iteration
                if step <= tol_x and change <= tol_fun:
                    stops[t] = 1  # _CONVERGED
                    variance = estimate
                    break
                if math.sqrt(shift[0] ** 2 + shift[1] ** 2 + shift[2] ** 2) > limits[t]:
                    stops[t] = 4  # _DIVERGED
                    variance = estimate
                    break
            variance = estimate
            if iteration == max_iterations:
                break
            for i in range(3):
                value = 0.0
                for j in range(3):
                    compensation = 2.0 * variance * (sum_of_means[t, j] - n_markers * shift[j])
                    value += a_pinv[t, i, j] * (b_vector[t, j] - compensation)
                candidate[i] = value
        shifts[t] = shift
        sigma2[t] = variance


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
    return _is_fits([markers], [start])[0]


def _is_prepare(markers: object, start: object | None) -> tuple[np.ndarray, np.ndarray]:
    """IS's validated markers and starting centre (the LS centre by default)."""
    markers = _prepare(markers)
    return markers, _ls_center(markers) if start is None else _check_point(start, "start")


def _ls_center(markers: np.ndarray) -> np.ndarray:
    """The LS centre ``(3,)`` [mm] of validated markers ``(N, P, 3)``."""
    fit = _ls_fit(markers[None])
    return fit.origin[0] + fit.shift[0]


def _is_fits(arrays: list[np.ndarray], starts: list[np.ndarray]) -> list[CenterResult]:
    """:func:`fit_is` of validated trials (each ``(N, P, 3)`` [mm], the same ``N``) from
    ``starts`` (each ``(3,)`` [mm]), the searches advanced together
    (:func:`jointbench.numerics.simplex.lockstep`), each on its own path."""
    n_frames = arrays[0].shape[0]
    flats = np.ascontiguousarray(np.stack(arrays).reshape(len(arrays), -1, 3))
    searches = lockstep(
        lambda centers, owners: _geometric_costs(centers, flats, owners, n_frames),
        np.stack(starts),
        **FMINSEARCH_OPTIONS,
    )
    return [
        _is_result(search, flat, n_frames) for search, flat in zip(searches, flats, strict=True)
    ]


def _fit_is_batch(markers: object, start: object | None = None) -> list[CenterResult | ValueError]:
    """:func:`fit_is` for every trial of ``markers`` ``(n_trials, N, P, 3)``."""
    return _prepared_fits(markers, lambda data: _is_prepare(data, start), _is_fits)


def _prepared_fits(markers: object, prepare, fits) -> list:
    """A search's many-trial form: ``fits(arrays, starts)`` over the trials of ``markers``
    ``(n_trials, ...)`` that ``prepare`` (the one-trial checks, returning the trial and its
    start) passes; a trial it refuses carries its ``ValueError``."""
    outcomes, prepared = prepare_trials(markers, prepare)
    if prepared:
        arrays, starts = zip(*prepared.values(), strict=True)
        for trial, result in zip(prepared, fits(arrays, starts), strict=True):
            outcomes[trial] = result
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


def _is_self_check(result: CenterResult, markers: np.ndarray, start=None) -> CenterResult:
    """IS's f1 against f1 at its closed-form neighbours, the LS and NM centres; where one is
    lower by more than fminsearch's TolFun, IS restarted from it (one more search, paid only
    then). See :mod:`jointbench.estimators.selfcheck`."""
    del start  # the answer is judged, wherever it was started
    neighbours = {"the LS centre": _ls_center(markers)}
    try:
        neighbours["the NM centre"] = np.asarray(fit_nm(markers).center)
    except ValueError:
        pass  # no NM centre to compare with (a plane); the LS one remains
    n_frames = markers.shape[0]
    flat = np.ascontiguousarray(markers.reshape(1, -1, 3))
    points = np.stack(list(neighbours.values()))
    costs = _geometric_costs(points, flat, np.zeros(len(points), dtype=int), n_frames)
    return selfcheck.lowest_neighbour(
        result,
        neighbours,
        costs,
        partial(fit_is, markers),
        tol_fun=FMINSEARCH_OPTIONS["fatol"],
        cost_name="f1",
    )


def _bc_update_steps(data: np.ndarray, centers: np.ndarray) -> np.ndarray:
    """How far one more of Halvorsen's updates moves each trial's centre: ``(T,)`` [mm], its
    largest coordinate (``nan`` where the update is not finite), for validated trials ``data``
    ``(T, N, P, 3)`` [mm] and ``centers`` ``(T, 3)`` [mm]: :func:`_bc_steps` on the moments
    recomputed from the markers about each centre, not those an iteration used."""
    means, grams = _moments(data, centers)
    steps = np.empty(len(data))
    _bc_steps(grams, means, data.shape[1], RCOND, steps)
    return steps


@kernel
def _bc_steps(
    grams: np.ndarray, means: np.ndarray, n_frames: int, rcond: float, steps: np.ndarray
) -> None:
    """The largest coordinate of the shift one of Halvorsen's updates makes from a centre,
    into ``steps`` (T,) [mm], from the moments of :func:`_sphere_moments` about it (``grams``
    (T, P, 4, 4), ``means`` (T, P, 4)). A compiled kernel
    (:mod:`jointbench.numerics.compiled`): this source is the implementation.

    The shift is ``A^+ (b - 2 sigma^2 sum_p mean_k y^p)`` with ``y = v - c``: ``A`` and ``b``
    Gamage & Lasenby's normal equations of the ``y`` with the pseudo-inverse rule of
    :func:`_ls_solve`, and ``sigma^2 = mean_p G_p[3, 3] / (4 N mean_k |y^p|^2)``, the
    estimate :func:`_bc_iterations` makes at a zero shift.
    """
    n_trials, n_markers = grams.shape[0], grams.shape[1]
    a_matrix, b_vector = np.empty((3, 3)), np.empty(3)
    for t in range(n_trials):
        variance = 0.0
        for p in range(n_markers):
            variance += grams[t, p, 3, 3] / (4.0 * n_frames * means[t, p, 3])
        variance /= n_markers
        for i in range(3):
            b_vector[i] = 0.0
            sum_of_means = 0.0
            for p in range(n_markers):
                b_vector[i] += grams[t, p, i, 3]
                sum_of_means += means[t, p, i]
            b_vector[i] = b_vector[i] * (1.0 / n_frames) - 2.0 * variance * sum_of_means
            for j in range(3):
                a_matrix[i, j] = 0.0
                for p in range(n_markers):
                    a_matrix[i, j] += grams[t, p, i, j]
                a_matrix[i, j] = 2.0 * (a_matrix[i, j] * (1.0 / n_frames))
        values, vectors = np.linalg.eigh(a_matrix)
        largest = max(abs(values[0]), abs(values[2]))  # ascending
        step = 0.0 if math.isfinite(variance) else math.nan
        for i in range(3):
            shift = 0.0
            for k in range(3):
                if abs(values[k]) > rcond * largest:
                    along = 0.0
                    for j in range(3):
                        along += vectors[j, k] * b_vector[j]
                    shift += vectors[i, k] * along / values[k]
            # max() passes over a nan; a nan shift must make the step nan.
            step = math.nan if math.isnan(shift) else max(step, abs(shift))
        steps[t] = step


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
    move it by at most ``tol_x`` (:func:`_bc_update_steps`). BC has no cost to compare
    (:func:`fit_bc`); the update is its defining equation. See
    :mod:`jointbench.estimators.selfcheck`."""
    return _bc_self_check_many(
        [result], markers[None], max_iterations=max_iterations, tol_x=tol_x, tol_fun=tol_fun
    )[0]


def _bc_self_check_many(
    results: list[CenterResult],
    markers: np.ndarray,
    *,
    max_iterations: int = 600,
    tol_x: float = 1e-4,
    tol_fun: float = 1e-4,
) -> list[CenterResult]:
    """:func:`_bc_self_check` of BC's answers ``results`` for the trials of ``markers``
    ``(T, N, P, 3)`` [mm] (or a list of equal-shape trials), the updates computed together."""
    del max_iterations, tol_fun
    judged = [trial for trial, result in enumerate(results) if result.converged]
    if not judged:
        return list(results)
    data = markers if isinstance(markers, np.ndarray) else np.stack(markers)
    if len(judged) < len(results):
        data = data[judged]
    centers = np.array([results[trial].center for trial in judged])
    checked = list(results)
    for trial, step in zip(judged, _bc_update_steps(data, centers).tolist(), strict=True):
        checked[trial] = _bc_judged(results[trial], step, tol_x)
    return checked


def _bc_judged(result: CenterResult, step: float, tol_x: float) -> CenterResult:
    """``result``, whose next update moves it by ``step`` [mm], held or failed against
    ``tol_x``."""
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
fit_bc.self_check_many = _bc_self_check_many
register_many("center", "LS", isolated(_fit_ls_batch, min_frames=_MIN_FRAMES))
register_many("center", "NM", isolated(_fit_nm_batch, min_frames=_MIN_FRAMES))
register_many("center", "BC", isolated(_fit_bc_batch, min_frames=_MIN_FRAMES))
register_many("center", "IS", isolated(_fit_is_batch, min_frames=_MIN_FRAMES))
