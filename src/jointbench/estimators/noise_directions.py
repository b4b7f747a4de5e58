"""Whether the markers' noise is the same in every direction of the world, and whether a
difference could move an answer.

Every SD and test of the checked calls takes the marker noise to have one variance in every
direction. A measurement volume whose cameras see one direction worse than the others breaks
that, and on a short arc it can move an answer far beyond its SD: the noise along the arcs'
normal then passes for the arcs' own shape.

**The residuals.** The support verdict reads a rigid body's noise from its inter-marker
distances (:mod:`jointbench.estimators.support`, "one segment"): frame ``k``'s distance
deviations ``dd_k`` from their means are, to first order, ``J_k e_k`` of the markers' noise
``e_k`` ``(3 n,)``, and ``r_k = J_k' H dd_k`` (``H`` the pseudo-inverse of ``G = J J'`` at
the mean figure over its shape modes, :mod:`jointbench.numerics.distances`) is the part of
the noise a rigid body cannot absorb, ``P_k e_k`` with ``P_k = J_k' H J_k`` the projection
off the rigid motions (and off a nearly flat cluster's flexes, which move no distance): the
rigid-body residual, without fitting a pose. Its world directions are frame ``k``'s own:
``J_k`` holds that frame's unit vectors between the markers. The noise's scatter is therefore
not isotropic even for isotropic noise: it depends on the cluster's shape and pose.

**The test.** Let marker ``m``'s noise have the covariance ``tau_m I + D``: a variance of its
own (markers nearer the cameras, or better seen, are less noisy) and a part ``D``, traceless
and the same for every marker, that differs by direction. The stacked noise's covariance,
``sum_c theta_c A_c``, is linear in ``theta = (tau_1 .. tau_n, d_1 .. d_5)``, with ``A_c``
the ``n`` matrices ``e_m e_m' (x) I`` and the five ``I_n (x) F_a`` (``F_a`` traceless and
symmetric, ``D = sum_a d_a F_a``). So are the means of the residual moments
``R_k,c = r_k' A_c r_k`` (each marker's squared residual, and the five traceless ones pooled
over the markers): ``E R_k = M_k theta``, ``M_k,cd = tr(A_c P_k A_d P_k)``, scaled by
``(N - 1) / N`` for the mean distances' share of each deviation. With
``C_mm' = S_m H S_m'`` (``S_m`` the signs of the pairs at marker ``m``), the marker block
``M_k,mm' = tr(C_mm' Gamma C_m'm Gamma)`` (``Gamma`` the pairs' unit vectors' Gram) keeps no
world direction and is the same in every frame, and the traceless rows of a marker's
column are ``tr(F_a U_k' K_m U_k)`` (``U_k`` ``(P, 3)`` the frame's unit vectors,
``K_m = (H S_m Gamma S_m H) o c``, :mod:`jointbench.numerics.distances`'s ``c``), read with
``U_k = diag(1 / dbar) Delta X_k`` (the centred markers ``X_k`` ``(n, 3)`` through the pairs'
incidence ``Delta`` and mean distances ``dbar``), so that summed over the frames they need
only the markers' second moments ``sum_k x_ka x_kb'``.

Isotropic noise has ``D = 0``. Under that hypothesis each marker's own variance ``theta_0``
solves the marker rows (read, to first order, from the distances' scatter,
``tr(H Gamma_m H sum_k dd_k dd_k')``, before the pass over the residuals), and the sums of the
deviations from what ``theta_0`` gives, projected off the marker rows,
``s = A sum_k (R_k - M_k theta_0)`` with ``A = [-M_Dtau M_tautau^-1, I]`` (``M`` summed over
the frames), are the score of ``D``, of mean zero under the hypothesis whatever the
``theta_0``; its variance is taken from the scatter of those projected deviations, summed
over ``B`` blocks of frames, about their mean (a sandwich), not from the normal distribution's
fourth moments: paper A's and B's noise (uniform directions, normal
lengths) and skin markers have heavier tails, and a normal-theory variance would take their
spread for anisotropy. With ``V`` that scatter, the statistic
``W = (B - 1) / B s' V^-1 s`` is Hotelling's ``T^2`` of the blocks' mean, a Wald statistic of
``D_hat = (M^-1 sum_k R_k)_D`` with the sandwich variance ``M^-1 C M^-1`` (the Schur complement
of ``M``'s traceless block cancels), held as ``F = W (B - 5) / (5 (B - 1))`` on
``(5, B - 5)`` degrees of freedom to its critical value at :data:`NOISE_DIRECTION_ALPHA`;
the ``p_value`` is stated where it rejects. The scatter about zero would not do: it holds
the score itself, ``s' V^-1 s`` could not exceed ``B``, and with a few tens of blocks no
anisotropy could reach the critical value. Frames
that share their errors (filtered, or skin markers) make that scatter understate the
variance: the deviations are summed over blocks of about as many frames as one independent
frame spans (the support verdict's count, ``N / independent``), and ``B`` is the blocks'
(``tests/test_noise_directions.py`` holds isotropic noise smoothed over 5 frames to it). A
model of one variance for every marker would not do: the projection mixes the markers, and
one isotropic marker noisier than the others would read as noise differing by direction. The
whole is invariant to a rotation of the world. Where ``V`` is singular (a Cholesky pivot
under ``1 / _MAX_CONDITION`` of its largest diagonal entry: a direction of ``D`` no residual
reaches, as three markers leave residuals in their own plane only and a motion that hardly
turns that plane leaves the noise along its normal unseen) or fewer than 7 blocks remain, the
test is not made
(``statistic`` NaN).

The support verdict's pass over the frames makes the test where the frames are independent
(:func:`trial_test_into`, from what that pass keeps, at a few tens of microseconds on a
checked call of 120 frames); where they are not, :func:`sphericity_numbers` makes it over
blocks, from a pass of its own. Unlike a rigid-body fit of every frame, the distances leave
out the flexes of a nearly flat cluster (the support verdict's ``_FLEX``), whose residual the
test then does not read.

**Whether it matters.** Both a centre and an axis are read, by every method, from the markers'
scatter about their mean positions, ``S = sum_m sum_k (x_km - xbar_m)(x_km - xbar_m)'``, of
which noise adds ``(N - 1) n Sigma`` (``Sigma`` the markers' mean variance times ``I`` plus
``D``). Its isotropic part moves no eigenvector and is the part the methods' own bias
corrections and SDs account for; ``D`` is not, and to first order it pulls

* an axis, the normal of the arcs' planes (``S``'s least eigenvector ``v_0`` once the noise
  is taken off, ``S_0 = S - (N - 1) n Sigma_hat``), by
  ``sum_{j=1,2} v_j v_j' (N - 1) n D v_0 / (lambda_j - lambda_0)`` (first-order eigenvector
  perturbation), :func:`axis_pull_deg`;
* a centre ``c``, as the spheres' normal equations read it
  (``2 S c = sum (x - xbar)(|x|^2 - mean |x|^2)``, an errors-in-variables regression), by
  ``S_0^-1 (N - 1) D sum_m (xbar_m - c)``, :func:`centre_pull_mm`.

``D_hat`` itself, which only the pulls read, needs ``M``'s traceless block, a sum over the
frames of fourth powers of their unit vectors: it is summed where the test rejects, and the
covariance and pulls are stated there only. Where the test rejects at
:data:`NOISE_DIRECTION_ALPHA` and the pull is larger than the SD the answer states, the
answer's precision is not determined by an SD that assumes one noise variance
(:func:`statement`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from jointbench.estimators.results import PRECISION_NOT_DETERMINED
from jointbench.numerics.compiled import kernel, kernel_array
from jointbench.numerics.distances import distance_gram_into, distance_modes_into

__all__ = [
    "NOISE_DIRECTION_ALPHA",
    "NoiseDirections",
    "axis_pull_deg",
    "centre_pull_mm",
    "inverse_gram_into",
    "judged",
    "row_length",
    "sphericity_numbers",
    "statement",
    "trial_test_into",
]

#: Noise is reported as differing by direction when its sphericity is rejected at this level:
#: the support verdict's level (:data:`jointbench.estimators.support.ROTATION_ALPHA`).
NOISE_DIRECTION_ALPHA = 1e-3

# The five traceless symmetric matrices F_a whose combinations D = sum_a d_a F_a are the
# part of the noise covariance that differs by direction.
_TRACELESS = np.zeros((5, 3, 3))
_TRACELESS[0, 0, 0], _TRACELESS[0, 1, 1] = 1.0, -1.0
_TRACELESS[1, 1, 1], _TRACELESS[1, 2, 2] = 1.0, -1.0
for _a, (_i, _j) in enumerate(((0, 1), (0, 2), (1, 2)), start=2):
    _TRACELESS[_a, _i, _j] = _TRACELESS[_a, _j, _i] = 1.0
# A score variance whose Cholesky pivot is this much smaller than its largest diagonal entry
# has a direction of D no residual reaches: the test is not made.
_MAX_CONDITION = 1e10
# The fewest blocks of frames whose scatter is read as the score's variance.
_MIN_BLOCKS = 7
# Frames whose residuals the test's pass forms side by side (:func:`_frame_terms_into`).
_CHUNK = 128


class NoiseDirections(NamedTuple):
    """The test of one segment's markers (module docstring): ``statistic`` ``W`` (NaN where
    the test was not made) and, where it rejects, its ``p_value`` (else NaN), ``covariance``
    ``(3, 3)``
    [mm^2] the estimate of ``Sigma``, ``scatter`` ``(3, 3)`` [mm^2] the markers' scatter about
    their mean positions ``S`` and ``marker_sum`` ``(3,)`` [mm] the sum of those positions,
    which the pulls read, else ``None``; ``n_markers`` and ``n_frames``."""

    statistic: float
    p_value: float
    n_markers: int
    n_frames: int
    covariance: np.ndarray | None = None
    scatter: np.ndarray | None = None
    marker_sum: np.ndarray | None = None

    def rejected(self) -> bool:
        """Whether the noise differs by direction at :data:`NOISE_DIRECTION_ALPHA`."""
        return self.covariance is not None

    def anisotropy(self) -> np.ndarray:
        """``D = Sigma - tr(Sigma) / 3 I`` ``(3, 3)`` [mm^2]."""
        return self.covariance - np.trace(self.covariance) / 3.0 * np.eye(3)

    def signal_scatter(self) -> np.ndarray:
        """``S_0 = S - (N - 1) n Sigma``, the scatter less its noise ``(3, 3)`` [mm^2]."""
        return self.scatter - self._count() * self.covariance

    def _count(self) -> float:
        return float((self.n_frames - 1) * self.n_markers)

    def numbers(self) -> dict[str, object]:
        """The diagnostics: the test's statistic and, where it rejects, its p-value and the
        noise's SDs along its principal directions [mm], ascending."""
        if self.covariance is None:
            return {"noise_direction_statistic": self.statistic}
        values = np.linalg.eigvalsh(self.covariance)
        return {
            "noise_direction_statistic": self.statistic,
            "noise_direction_p_value": self.p_value,
            "noise_direction_sds_mm": [math.sqrt(max(v, 0.0)) for v in values],
        }


#: The first columns of :func:`sphericity_numbers` per trial: the statistic ``W``, Hotelling's
#: ``T^2`` (NaN where the test was not made), the blocks ``B``, and the F ratio
#: ``W (B - 5) / (5 (B - 1))`` and its denominator's degrees of freedom ``B - 5``, for the
#: caller's F survival function.
_COLUMNS = ("statistic", "blocks", "f_ratio", "f_dof")


class _Parts(NamedTuple):
    """What the estimate of ``Sigma`` reads besides the frames, of one trial: the moments'
    deviations from what ``theta_0`` gives, summed over the frames, ``(n + 5,)``,
    ``theta_0`` ``(n,)`` [mm^2], ``M_tautau`` ``(n, n)`` and ``M_Dtau`` ``(5, n)`` (each
    summed over the frames) and ``H`` ``(P, P)``."""

    score: np.ndarray
    own: np.ndarray
    markers_map: np.ndarray
    mixed_map: np.ndarray
    inverse_gram: np.ndarray


def sphericity_numbers(
    markers: np.ndarray,
    variance: np.ndarray,
    ranks: np.ndarray,
    blocks: np.ndarray,
    flex: float,
    rounding: float,
) -> np.ndarray:
    """The test of the module docstring on ``T`` trials of one segment's ``markers``
    ``(T, N, n >= 3, 3)`` [mm], with the support verdict's rigid residual per coordinate
    ``variance`` ``(T,)`` [mm^2], its count of the distances' shape modes ``ranks`` ``(T,)``
    and its ``flex``, and blocks of ``blocks`` ``(T,)`` frames: per trial ``(T, K)`` the
    columns of :data:`_COLUMNS` (not tested where the residual is at rounding level,
    ``rounding`` of the largest coordinate, the support verdict's), then the parts the
    estimate of ``Sigma`` reads (:func:`_trial_parts`)."""
    n_trials, _, n_markers, _ = markers.shape
    if n_markers < 3:
        # The pass over the frames (:func:`_frame_terms_into`) needs three pairs' rows.
        raise ValueError(
            f"the noise-direction test needs 3 markers or more per segment, got {n_markers} markers"
        )
    out = np.empty((n_trials, row_length(n_markers)))
    _sphericity_into(
        kernel_array(markers),
        kernel_array(variance),
        kernel_array(ranks, np.int64),
        kernel_array(blocks, np.int64),
        flex,
        rounding,
        out,
    )
    return out


@kernel
def row_length(n_markers: int) -> int:
    """The columns of a row of :func:`sphericity_numbers` for ``n_markers`` markers. A
    compiled kernel."""
    n_pairs = n_markers * (n_markers - 1) // 2
    return len(_COLUMNS) + (n_markers + 5) + n_markers * (1 + n_markers + 5) + n_pairs**2


def _trial_parts(row: np.ndarray, n_markers: int) -> _Parts:
    """The :class:`_Parts` of one trial's ``row`` of :func:`sphericity_numbers`."""
    n_pairs = n_markers * (n_markers - 1) // 2
    widths = (len(_COLUMNS), n_markers + 5, n_markers, n_markers**2, 5 * n_markers)
    _, sums, own, markers_map, mixed, inverse_gram = np.split(row, np.cumsum(widths))
    return _Parts(
        sums,
        own,
        markers_map.reshape(n_markers, n_markers),
        mixed.reshape(n_markers, 5).T,
        inverse_gram.reshape(n_pairs, n_pairs),
    )


@kernel
def _pairs(n_markers: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The pairs of ``n_markers`` markers, ``(a, b)`` with ``a < b`` in order: ``pair_a`` and
    ``pair_b`` ``(P,)``, the signs ``s_pm`` ``(P, n)`` (+1 at ``a``, -1 at ``b``) and
    ``c_pq = sum_m s_pm s_qm`` ``(P, P)``. A compiled kernel."""
    n_pairs = n_markers * (n_markers - 1) // 2
    pair_a = np.empty(n_pairs, dtype=np.int64)
    pair_b = np.empty(n_pairs, dtype=np.int64)
    sign = np.zeros((n_pairs, n_markers))
    p = 0
    for a in range(n_markers):
        for b in range(a + 1, n_markers):
            pair_a[p], pair_b[p] = a, b
            sign[p, a], sign[p, b] = 1.0, -1.0
            p += 1
    shared = np.empty((n_pairs, n_pairs))
    for p in range(n_pairs):
        for q in range(n_pairs):
            a, b, c, d = pair_a[p], pair_b[p], pair_a[q], pair_b[q]
            shared[p, q] = int(a == c) - int(a == d) - int(b == c) + int(b == d)
    return pair_a, pair_b, sign, shared


@kernel
def _inverse_gram_into(
    mean_sq: np.ndarray,
    variance: float,
    flex: float,
    rank: int,
    pairs: tuple,
    cosines: np.ndarray,
    inverse_gram: np.ndarray,
    scratch: tuple,
) -> None:
    """From the pairs' mean squared distances ``mean_sq`` ``(P,)`` [mm^2] less their noise
    (``6 variance`` per pair, as the support verdict reads them): the unit vectors' Gram
    ``cosines`` ``(P, P)`` at that figure and ``H`` ``inverse_gram`` ``(P, P)``, ``G``'s
    pseudo-inverse over its shape modes
    (:func:`jointbench.numerics.distances.distance_modes_into`, whose work arrays ``scratch``
    holds but for the cosines, and one ``(P,)`` more): ``G``'s inverse where the support
    verdict counted ``rank`` modes of shape, all of them. A compiled kernel."""
    pair_a, pair_b = pairs[0], pairs[1]
    n_pairs = mean_sq.shape[0]
    squared, g, strength, modes, work, corrected = scratch
    for p in range(n_pairs):
        corrected[p] = np.sqrt(max(mean_sq[p] - 6.0 * variance, 0.0))
    if rank == n_pairs:
        distance_gram_into(corrected, pair_a, pair_b, squared, cosines, g)
        for p in range(n_pairs):
            for q in range(n_pairs):
                inverse_gram[p, q] = 1.0 if p == q else 0.0
        if _cholesky_solve(g, inverse_gram, work) > 0.0:
            return
    weakest = distance_modes_into(
        corrected,
        True,
        variance,
        flex,
        pair_a,
        pair_b,
        (squared, cosines, g, strength, modes, work),
    )
    inverse_gram[:] = 0.0
    for k in range(n_pairs):
        if strength[k] > weakest:
            for p in range(n_pairs):
                for q in range(n_pairs):
                    inverse_gram[p, q] += modes[p, k] * modes[q, k] / strength[k]


@kernel
def _traceless_moments(q00, q01, q02, q11, q12, q22, out: np.ndarray, start: int) -> None:
    """``tr(F_a Q)`` of the symmetric ``Q`` (its upper entries) for the five ``F_a`` of
    :data:`_TRACELESS`, into ``out[start:start + 5]``. A compiled kernel."""
    out[start] = q00 - q11
    out[start + 1] = q11 - q22
    out[start + 2] = 2.0 * q01
    out[start + 3] = 2.0 * q02
    out[start + 4] = 2.0 * q12


@kernel
def _cholesky_solve(matrix: np.ndarray, vectors: np.ndarray, factor: np.ndarray) -> float:
    """Solves ``matrix x = v`` ``(k, k)``, symmetric positive definite, in place for each
    column ``v`` of ``vectors`` ``(k, c)`` by its Cholesky factor, written into ``factor``
    ``(k, k)``; returns the least pivot over the largest diagonal entry (0 where a pivot is not
    positive, the matrix then not definite: nothing is solved). A compiled kernel."""
    k = matrix.shape[0]
    largest = 0.0
    for i in range(k):
        largest = max(largest, matrix[i, i])
    least = np.inf
    for j in range(k):
        value = matrix[j, j]
        for i in range(j):
            value -= factor[j, i] * factor[j, i]
        if not value > 0.0 or not largest > 0.0:
            return 0.0
        least = min(least, value)
        factor[j, j] = np.sqrt(value)
        for i in range(j + 1, k):
            value = matrix[i, j]
            for r in range(j):
                value -= factor[i, r] * factor[j, r]
            factor[i, j] = value / factor[j, j]
    for c in range(vectors.shape[1]):
        for i in range(k):
            value = vectors[i, c]
            for r in range(i):
                value -= factor[i, r] * vectors[r, c]
            vectors[i, c] = value / factor[i, i]
        for i in range(k - 1, -1, -1):
            value = vectors[i, c]
            for r in range(i + 1, k):
                value -= factor[r, i] * vectors[r, c]
            vectors[i, c] = value / factor[i, i]
    return least / largest


@kernel
def _marker_maps(
    n_frames: int, pairs: tuple, mean_d: np.ndarray, cosines: np.ndarray, inverse_gram, maps
) -> None:
    """Per marker ``m``, the marker block's column ``M_tautau[:, m]`` per frame into
    ``maps[0]`` ``(n, n)``, ``H Gamma_m H`` into ``maps[1]`` ``(n, P, P)`` and ``K~_m``
    ``(n, n)``, the map of the centred markers ``X_k`` onto ``B_m = X_k' K~_m X_k`` (module
    docstring), into ``maps[2]`` ``(n, n, n)``, the first and last scaled by ``(N - 1) / N``;
    ``maps[3]`` and ``maps[4]`` are work arrays ``(P, P)`` and ``(max(n, P), P)``. A compiled
    kernel."""
    sign, shared = pairs[2], pairs[3]
    per_frame, spreads, through, local, spread = maps
    n_pairs, n_markers = sign.shape
    shrink = (n_frames - 1) / n_frames
    for m in range(n_markers):
        # Y_m = H Gamma_m H, Gamma_m the Gram of marker m's pairs, signed.
        for p in range(n_pairs):
            for q in range(n_pairs):
                value = 0.0
                for r in range(n_pairs):
                    value += inverse_gram[p, r] * sign[r, m] * sign[q, m] * cosines[r, q]
                local[p, q] = value
        for p in range(n_pairs):
            for q in range(n_pairs):
                value = 0.0
                for r in range(n_pairs):
                    value += local[p, r] * inverse_gram[r, q]
                spreads[m, p, q] = value
        # M_tautau[mm, m] = tr(Y_m Gamma_mm); K_m = Y_m o c, read through the incidence
        # and the mean distances.
        for mm in range(n_markers):
            value = 0.0
            for p in range(n_pairs):
                for q in range(n_pairs):
                    value += spreads[m, p, q] * sign[q, mm] * sign[p, mm] * cosines[q, p]
            per_frame[mm, m] = shrink * value
        for p in range(n_pairs):
            for q in range(n_pairs):
                local[p, q] = shared[p, q] * spreads[m, p, q] / (mean_d[p] * mean_d[q])
        for a in range(n_markers):
            for q in range(n_pairs):
                value = 0.0
                for p in range(n_pairs):
                    value += sign[p, a] * local[p, q]
                spread[a, q] = value
        for a in range(n_markers):
            for b in range(n_markers):
                value = 0.0
                for q in range(n_pairs):
                    value += spread[a, q] * sign[q, b]
                through[m, a, b] = shrink * value


@kernel
def _sphericity_into(
    markers: np.ndarray,
    variance: np.ndarray,
    ranks: np.ndarray,
    blocks: np.ndarray,
    flex: float,
    rounding: float,
    out: np.ndarray,
) -> None:
    """:func:`sphericity_numbers` into ``out`` ``(T, K)``. Per trial: a pass over the frames
    for their centred markers, pair differences and distances, as the support verdict's pass
    keeps them (:func:`jointbench.estimators.support._one_segment_numbers`), the distances'
    scatter about their means and ``H`` at the mean figure (:func:`_inverse_gram_into`); then
    :func:`trial_test_into`. A compiled kernel."""
    n_trials, n_frames, n_markers, _ = markers.shape
    n_pairs = n_markers * (n_markers - 1) // 2
    pairs = _pairs(n_markers)
    pair_a, pair_b = pairs[0], pairs[1]
    by_pair = np.empty((3, n_pairs))
    first, total, mean_sq = by_pair[0], by_pair[1], by_pair[2]
    pair_squares = np.empty((3, n_pairs, n_pairs))
    cosines, inverse_gram, scatter_d = pair_squares[0], pair_squares[1], pair_squares[2]
    scratch = (
        np.empty((n_markers, n_markers)),
        np.empty((n_pairs, n_pairs)),
        np.empty(n_pairs),
        np.empty((n_pairs, n_pairs)),
        np.empty((n_pairs, n_pairs)),
        np.empty(n_pairs),
    )
    positions = np.empty((n_frames, n_markers, 3))
    differences = np.empty((n_pairs, 3, n_frames))
    deviations = np.empty((n_pairs, n_frames))
    for t in range(n_trials):
        trial = markers[t]
        row = out[t]
        row[:] = 0.0
        row[0] = row[2] = np.nan
        row[3] = 1.0
        largest = 0.0
        total[:] = 0.0
        mean_sq[:] = 0.0
        scatter_d[:] = 0.0
        for f in range(n_frames):
            x = positions[f]
            for i in range(3):
                mean = 0.0
                for m in range(n_markers):
                    mean += trial[f, m, i]
                    largest = max(largest, abs(trial[f, m, i]))
                mean /= n_markers
                for m in range(n_markers):
                    x[m, i] = trial[f, m, i] - mean
            for p in range(n_pairs):
                a, b = pair_a[p], pair_b[p]
                squared = 0.0
                for i in range(3):
                    differences[p, i, f] = x[a, i] - x[b, i]
                    squared += differences[p, i, f] ** 2
                length = np.sqrt(squared)
                if f == 0:
                    first[p] = length
                deviations[p, f] = length - first[p]
                total[p] += deviations[p, f]
                mean_sq[p] += squared / n_frames
            for p in range(n_pairs):
                for q in range(p, n_pairs):
                    scatter_d[p, q] += deviations[p, f] * deviations[q, f]
        if not variance[t] > (rounding * largest) ** 2:
            continue
        for p in range(n_pairs):
            for q in range(p, n_pairs):
                scatter_d[p, q] -= total[p] * total[q] / n_frames
                scatter_d[q, p] = scatter_d[p, q]
        _inverse_gram_into(
            mean_sq, variance[t], flex, ranks[t], pairs, cosines, inverse_gram, scratch
        )
        trial_test_into(
            positions,
            differences,
            deviations,
            first,
            total,
            scatter_d,
            inverse_gram,
            cosines,
            blocks[t],
            row,
        )


@kernel
def inverse_gram_into(
    strength: np.ndarray, modes: np.ndarray, rank: int, inverse_gram: np.ndarray
) -> None:
    """``H`` ``inverse_gram`` ``(P, P)``, the pseudo-inverse of ``G`` over its ``rank``
    strongest modes, from its ``strength`` ``(P,)`` (ascending) and ``modes`` ``(P, P)`` (as
    columns). A compiled kernel."""
    n_pairs = strength.shape[0]
    inverse_gram[:] = 0.0
    for k in range(n_pairs - rank, n_pairs):
        for p in range(n_pairs):
            for q in range(n_pairs):
                inverse_gram[p, q] += modes[p, k] * modes[q, k] / strength[k]


@kernel
def _frame_terms_into(
    begin: int,
    count: int,
    positions: np.ndarray,
    differences: np.ndarray,
    deviations: np.ndarray,
    first: np.ndarray,
    z: np.ndarray,
    inverse_gram: np.ndarray,
    pairs: tuple,
    expected_own: np.ndarray,
    isotropic: np.ndarray,
    work: tuple,
) -> None:
    """The residual moments' deviations from what ``theta_0`` gives (:func:`trial_test_into`)
    of the ``count`` frames from ``begin``, into ``work[3]`` ``(n + 5, >= count)``: each
    marker's squared residual less ``expected_own`` ``(n,)`` [mm^2], then the five traceless
    moments less those of ``X_k' K~ X_k`` (``isotropic`` ``(n, n)``). ``work[0]``
    ``(P, >= count)``, ``work[1]`` and ``work[2]`` ``(3 n, >= count)`` and ``work[4]``
    ``(6, >= count)`` are work arrays (the residuals and the markers by coordinate, frames
    innermost), ``work[0]``'s first three rows then each marker's row of ``isotropic X_k``
    (``P >= 3`` as ``n >= 3``): ``r_k = J_k' H dd_k`` from the deviations ``deviations``
    ``(P, N)`` [mm] from ``first`` ``(P,)`` less their means ``first + z``, the frames' pair
    differences ``differences`` ``(P, 3, N)`` and centred markers ``positions`` ``(N, n, 3)``
    [mm], ``H`` ``inverse_gram``. Each frame's numbers by the operations of one frame alone,
    in the same order, with the frames innermost so that they run side by side. A compiled
    kernel."""
    values, residuals, markers_t, terms, moments = work
    pair_a, pair_b = pairs[0], pairs[1]
    n_markers = positions.shape[1]
    n_pairs = first.shape[0]
    # The chunk's frames through rows of its own, indexed from 0: an index offset by
    # ``begin`` could be negative for all the compiler knows, and its wraparound test on every
    # load keeps these loops from running several frames at once.
    end = begin + count
    for p in range(n_pairs):
        pair_values = values[p]
        for j in range(count):
            pair_values[j] = 0.0
        for q in range(n_pairs):
            h, mean = inverse_gram[p, q], z[q]
            deviation = deviations[q, begin:end]
            for j in range(count):
                pair_values[j] += h * (deviation[j] - mean)
        start = first[p]
        deviation = deviations[p, begin:end]
        for j in range(count):
            pair_values[j] *= 1.0 / (deviation[j] + start)
    residuals[:, :count] = 0.0
    for p in range(n_pairs):
        a, b = pair_a[p], pair_b[p]
        pair_values = values[p]
        for i in range(3):
            difference = differences[p, i, begin:end]
            at_a, at_b = residuals[3 * a + i], residuals[3 * b + i]
            for j in range(count):
                step = pair_values[j] * difference[j]
                at_a[j] += step
                at_b[j] -= step
    moments[:, :count] = 0.0
    for m in range(n_markers):
        expected = expected_own[m]
        for j in range(count):
            r0, r1, r2 = residuals[3 * m, j], residuals[3 * m + 1, j], residuals[3 * m + 2, j]
            terms[m, j] = r0 * r0 + r1 * r1 + r2 * r2 - expected
            moments[0, j] += r0 * r0
            moments[1, j] += r0 * r1
            moments[2, j] += r0 * r2
            moments[3, j] += r1 * r1
            moments[4, j] += r1 * r2
            moments[5, j] += r2 * r2
    frames = positions[begin:end]
    for j in range(count):
        for m in range(n_markers):
            for i in range(3):
                markers_t[3 * m + i, j] = frames[j, m, i]
    # The residuals made, the first three of the pairs' rows hold row a of isotropic X_k
    # (P >= 3), each a sum over b in order as before, the frames innermost: a sum per frame
    # over b innermost would run the frames one at a time.
    weighted = values[:3]
    for a in range(n_markers):
        weighted[:, :count] = 0.0
        for b in range(n_markers):
            weight = isotropic[a, b]
            for i in range(3):
                to, marker = weighted[i], markers_t[3 * b + i]
                for j in range(count):
                    to[j] += weight * marker[j]
        w0, w1, w2 = weighted[0], weighted[1], weighted[2]
        x0, x1, x2 = markers_t[3 * a], markers_t[3 * a + 1], markers_t[3 * a + 2]
        for j in range(count):
            moments[0, j] -= x0[j] * w0[j]
            moments[1, j] -= x0[j] * w1[j]
            moments[2, j] -= x0[j] * w2[j]
            moments[3, j] -= x1[j] * w1[j]
            moments[4, j] -= x1[j] * w2[j]
            moments[5, j] -= x2[j] * w2[j]
    for j in range(count):
        _traceless_moments(
            moments[0, j],
            moments[1, j],
            moments[2, j],
            moments[3, j],
            moments[4, j],
            moments[5, j],
            terms[:, j],
            n_markers,
        )


@kernel
def trial_test_into(
    positions: np.ndarray,
    differences: np.ndarray,
    deviations: np.ndarray,
    first: np.ndarray,
    total: np.ndarray,
    scatter_d: np.ndarray,
    inverse_gram: np.ndarray,
    cosines: np.ndarray,
    block: int,
    row: np.ndarray,
) -> None:
    """The test of the module docstring on one trial, from what the support verdict's pass
    over its frames keeps (:func:`jointbench.estimators.support._one_segment_numbers`): each
    frame's centred markers ``positions`` ``(N, n, 3)`` [mm] and pair differences
    ``differences`` ``(P, 3, N)`` [mm], the distances' deviations ``deviations`` ``(P, N)``
    [mm] from frame 0's ``first`` ``(P,)`` [mm] and their sums ``total`` ``(P,)`` [mm], their
    scatter about their means ``scatter_d`` ``(P, P)`` [mm^2], and at the mean figure ``H``
    ``inverse_gram`` ``(P, P)`` and the pairs' unit vectors' Gram ``cosines`` ``(P, P)``; the
    deviations summed over blocks of ``block`` frames. Into ``row`` ``(K,)``: the columns of
    :data:`_COLUMNS`, then the parts the estimate of ``Sigma`` reads (:func:`_trial_parts`).

    The marker columns' maps (:func:`_marker_maps`); ``theta_0`` from the marker rows' sums,
    ``tr(H Gamma_m H sum_k dd_k dd_k')``; the markers' second moments, which give ``M_Dtau``;
    a pass for the residuals ``r_k = J_k' H dd_k`` and their moments' deviations from what
    ``theta_0`` gives, projected by ``A = [-M_Dtau M_tautau^-1, I]`` (which leaves the score
    exact whatever the ``theta_0``: it sets the marker rows' sums to zero only to first order)
    and summed over blocks; and ``W``. A compiled kernel."""
    n_frames, n_markers, _ = positions.shape
    n_pairs = first.shape[0]
    n_terms = n_markers + 5
    # Where each part of ``row`` starts.
    at_sums = len(_COLUMNS)
    at_own = at_sums + n_terms
    at_markers = at_own + n_markers
    at_mixed = at_markers + n_markers * n_markers
    at_inverse = at_mixed + 5 * n_markers
    pairs = _pairs(n_markers)
    by_pair = np.empty((2, n_pairs))
    mean_d, z = by_pair[0], by_pair[1]
    marker_squares = np.empty((4, n_markers, n_markers))
    per_frame, isotropic, inverse_markers, work = (
        marker_squares[0],
        marker_squares[1],
        marker_squares[2],
        marker_squares[3],
    )
    spreads = np.empty((n_markers, n_pairs, n_pairs))
    through = np.empty((n_markers, n_markers, n_markers))
    maps = (
        per_frame,
        spreads,
        through,
        np.empty((n_pairs, n_pairs)),
        np.empty((max(n_pairs, n_markers), n_pairs)),
    )
    # Sum over the frames of d_a d_b' (a <= b < n - 1), d_a marker a's position less the last
    # marker's, and the pair (a, n - 1) that holds it.
    second = np.zeros((n_markers - 1, n_markers - 1, 3, 3))
    to_last = np.empty(n_markers - 1, dtype=np.int64)
    own = np.empty(n_markers)
    sums = np.empty(6)
    expected_own = np.empty(n_markers)
    projector = np.empty((5, n_markers))
    summed = np.empty(n_terms)
    five = np.empty((3, 5, 5))
    variance5, factor5 = five[0], five[1]
    score, along = five[2, 0], five[2, 1:2].T
    for p in range(n_pairs):
        mean_d[p] = first[p] + total[p] / n_frames
    _marker_maps(n_frames, pairs, mean_d, cosines, inverse_gram, maps)
    # theta_0 from the marker rows' sums; M_tautau and M_Dtau summed over the frames.
    for m in range(n_markers):
        value = 0.0
        for p in range(n_pairs):
            for q in range(n_pairs):
                value += spreads[m, p, q] * scatter_d[q, p]
        own[m] = value / n_frames
        for mm in range(n_markers):
            inverse_markers[m, mm] = 1.0 if m == mm else 0.0
    if not _cholesky_solve(per_frame, inverse_markers, work) > 0.0:
        return
    for m in range(n_markers):
        value = 0.0
        for mm in range(n_markers):
            value += inverse_markers[m, mm] * own[mm]
        row[at_own + m] = value
        for mm in range(n_markers):
            row[at_markers + m * n_markers + mm] = n_frames * per_frame[m, mm]
    for m in range(n_markers):
        own[m] = row[at_own + m]
    # K~_m's rows and columns sum to zero (each pair's signs do), so sum_ab K~_m,ab x_a x_b'
    # is the same sum over the markers a, b < L of their differences d_a = x_a - x_L from the
    # last marker L, which the pairs (a, L) hold: sum_k d_a d_b', fewer sums than of every
    # x_a x_b'. Pair by pair, each sum in frame order, its sums in registers through the frames.
    last = n_markers - 1
    for p in range(n_pairs):
        if pairs[1][p] == last:
            to_last[pairs[0][p]] = p
    for a in range(last):
        da = differences[to_last[a]]
        for b in range(a, last):
            db = differences[to_last[b]]
            s00 = s01 = s02 = s10 = s11 = s12 = s20 = s21 = s22 = 0.0
            for f in range(n_frames):
                x0, x1, x2 = da[0, f], da[1, f], da[2, f]
                y0, y1, y2 = db[0, f], db[1, f], db[2, f]
                s00 += x0 * y0
                s01 += x0 * y1
                s02 += x0 * y2
                s10 += x1 * y0
                s11 += x1 * y1
                s12 += x1 * y2
                s20 += x2 * y0
                s21 += x2 * y1
                s22 += x2 * y2
            second[a, b, 0, 0], second[a, b, 0, 1], second[a, b, 0, 2] = s00, s01, s02
            second[a, b, 1, 0], second[a, b, 1, 1], second[a, b, 1, 2] = s10, s11, s12
            second[a, b, 2, 0], second[a, b, 2, 1], second[a, b, 2, 2] = s20, s21, s22
    for a in range(last):
        for b in range(a):
            for i in range(3):
                for j in range(3):
                    second[a, b, i, j] = second[b, a, j, i]
    for m in range(n_markers):
        sums[:] = 0.0
        for a in range(last):
            for b in range(last):
                weight = through[m, a, b]
                for i in range(3):
                    for j in range(i, 3):
                        sums[3 * i + j - (i * (i + 1)) // 2] += weight * second[a, b, i, j]
        _traceless_moments(
            sums[0], sums[1], sums[2], sums[3], sums[4], sums[5], row, at_mixed + 5 * m
        )
    for a in range(n_markers):
        value = 0.0
        for m in range(n_markers):
            value += per_frame[a, m] * own[m]
        expected_own[a] = value
        for b in range(n_markers):
            value = 0.0
            for m in range(n_markers):
                value += own[m] * through[m, a, b]
            isotropic[a, b] = value
    for p in range(n_pairs):
        for q in range(n_pairs):
            row[at_inverse + p * n_pairs + q] = inverse_gram[p, q]
    # A's marker columns, -M_Dtau M_tautau^-1 with M_tautau summed over the frames.
    for a in range(5):
        for m in range(n_markers):
            value = 0.0
            for mm in range(n_markers):
                value += row[at_mixed + 5 * mm + a] * inverse_markers[mm, m]
            projector[a, m] = -value / n_frames
    # Each frame's residuals and their moments' deviations from what theta_0 gives
    # (X_k' K~ X_k for the traceless ones), projected by A and summed over blocks of frames.
    # Frames are taken _CHUNK at a time: each frame's numbers by the operations, in the order,
    # of a frame alone, but with the frames innermost, where they run side by side; then the
    # sums over the frames, in frame order.
    summed[:] = 0.0
    n_blocks = 0
    in_block = 0
    block = max(block, 1)
    for p in range(n_pairs):
        z[p] = total[p] / n_frames
    chunk = np.empty((n_pairs + 6 * n_markers + n_terms + 11, _CHUNK))
    values = chunk[:n_pairs]
    residuals = chunk[n_pairs : n_pairs + 3 * n_markers]
    markers_t = chunk[n_pairs + 3 * n_markers : n_pairs + 6 * n_markers]
    terms = chunk[n_pairs + 6 * n_markers : n_pairs + 6 * n_markers + n_terms]
    moments = chunk[n_pairs + 6 * n_markers + n_terms : n_pairs + 6 * n_markers + n_terms + 6]
    scores = chunk[n_pairs + 6 * n_markers + n_terms + 6 :]
    # The blocks' sums, their sum and their products (upper triangle), as scalars: the five
    # directions of D are the model's, and the sums stay in registers through the frames.
    b0 = b1 = b2 = b3 = b4 = 0.0
    s0 = s1 = s2 = s3 = s4 = 0.0
    v00 = v01 = v02 = v03 = v04 = v11 = v12 = v13 = v14 = 0.0
    v22 = v23 = v24 = v33 = v34 = v44 = 0.0
    for begin in range(0, n_frames, _CHUNK):
        count = min(_CHUNK, n_frames - begin)
        _frame_terms_into(
            begin,
            count,
            positions,
            differences,
            deviations,
            first,
            z,
            inverse_gram,
            pairs,
            expected_own,
            isotropic,
            (values, residuals, markers_t, terms, moments),
        )
        for c in range(n_terms):
            value = summed[c]
            for j in range(count):
                value += terms[c, j]
            summed[c] = value
        for a in range(5):
            for j in range(count):
                scores[a, j] = terms[n_markers + a, j]
            for m in range(n_markers):
                weight = projector[a, m]
                for j in range(count):
                    scores[a, j] += weight * terms[m, j]
        for j in range(count):
            b0 += scores[0, j]
            b1 += scores[1, j]
            b2 += scores[2, j]
            b3 += scores[3, j]
            b4 += scores[4, j]
            in_block += 1
            if in_block == block or begin + j == n_frames - 1:
                in_block = 0
                n_blocks += 1
                s0 += b0
                s1 += b1
                s2 += b2
                s3 += b3
                s4 += b4
                v00 += b0 * b0
                v01 += b0 * b1
                v02 += b0 * b2
                v03 += b0 * b3
                v04 += b0 * b4
                v11 += b1 * b1
                v12 += b1 * b2
                v13 += b1 * b3
                v14 += b1 * b4
                v22 += b2 * b2
                v23 += b2 * b3
                v24 += b2 * b4
                v33 += b3 * b3
                v34 += b3 * b4
                v44 += b4 * b4
                b0 = b1 = b2 = b3 = b4 = 0.0
    score[0], score[1], score[2], score[3], score[4] = s0, s1, s2, s3, s4
    variance5[0, 0], variance5[0, 1], variance5[0, 2] = v00, v01, v02
    variance5[0, 3], variance5[0, 4], variance5[1, 1] = v03, v04, v11
    variance5[1, 2], variance5[1, 3], variance5[1, 4] = v12, v13, v14
    variance5[2, 2], variance5[2, 3], variance5[2, 4] = v22, v23, v24
    variance5[3, 3], variance5[3, 4], variance5[4, 4] = v33, v34, v44
    for c in range(n_terms):
        row[at_sums + c] = summed[c]
    row[1] = n_blocks
    row[2] = np.nan
    row[3] = 1.0
    if n_blocks < _MIN_BLOCKS:
        return
    # The blocks' scatter about their mean: about zero it would hold the score itself, and
    # s' V^-1 s could not exceed the blocks' count.
    for a in range(5):
        along[a, 0] = score[a]
        for b in range(a, 5):
            variance5[a, b] -= score[a] * score[b] / n_blocks
        for b in range(a):
            variance5[a, b] = variance5[b, a]
    if not _cholesky_solve(variance5, along, factor5) > 1.0 / _MAX_CONDITION:
        return
    statistic = 0.0
    for a in range(5):
        statistic += score[a] * along[a, 0]
    statistic *= (n_blocks - 1.0) / n_blocks
    row[0] = statistic
    row[2] = statistic * (n_blocks - 5.0) / (5.0 * (n_blocks - 1.0))
    row[3] = n_blocks - 5.0


def judged(
    markers: np.ndarray,
    numbers: np.ndarray,
    critical: Callable[[int], float],
    survival: Callable[[float, float, float], float],
) -> list[NoiseDirections]:
    """The :class:`NoiseDirections` of ``T`` trials of one segment's ``markers``
    ``(T, N, n, 3)`` [mm] from their rows ``numbers`` of :func:`sphericity_numbers`: the
    F ratio against ``critical(dof)``, the F ratio on ``(5, dof)`` degrees of freedom whose
    survival is :data:`NOISE_DIRECTION_ALPHA`, and where it is beyond it, the p-value
    ``survival(5, dof, ratio)`` (the F survival function), the estimate of ``Sigma`` and the
    scatter the pulls read."""
    _, n_frames, n_markers, _ = markers.shape
    found = []
    for t, (statistic, _, ratio, dof) in enumerate(numbers[:, :4].tolist()):
        if not ratio > critical(int(dof)):
            found.append(NoiseDirections(statistic, math.nan, n_markers, n_frames))
            continue
        means = markers[t].mean(axis=0)
        centred = (markers[t] - means).reshape(-1, 3)
        found.append(
            NoiseDirections(
                statistic,
                float(survival(5.0, dof, ratio)),
                n_markers,
                n_frames,
                _covariance(markers[t], _trial_parts(numbers[t], n_markers)),
                centred.T @ centred,
                means.sum(axis=0),
            )
        )
    return found


def _covariance(trial: np.ndarray, parts: _Parts) -> np.ndarray:
    """``Sigma_hat`` ``(3, 3)`` [mm^2] of one trial's markers ``trial`` ``(N, n, 3)`` [mm]
    from its :class:`_Parts` (module docstring):
    ``theta_hat = theta_0 + M^-1 sum_k (R_k - M_k theta_0)``, with ``M``'s traceless block
    summed over the frames (:func:`_traceless_map`): the markers' mean variance and
    ``D_hat``."""
    n_frames, n_markers, _ = trial.shape
    traceless_map = _traceless_map(kernel_array(trial), parts.inverse_gram) * (
        (n_frames - 1) / n_frames
    )
    mixed = parts.mixed_map
    full = np.block([[parts.markers_map, mixed.T], [mixed, traceless_map]])
    theta = np.linalg.solve(full, parts.score)
    own, traceless = parts.own + theta[:n_markers], theta[n_markers:]
    return np.mean(own) * np.eye(3) + np.einsum("a,aij->ij", traceless, _TRACELESS)


@kernel
def _traceless_map(trial: np.ndarray, inverse_gram: np.ndarray) -> np.ndarray:
    """``sum_k M_k,ab = tr(X_a H X_b H)`` ``(5, 5)`` over the frames of ``trial``
    ``(N, n, 3)`` [mm], ``X_a = (U_k F_a U_k') o c`` with the frame's unit vectors ``U_k``
    ``(P, 3)`` and ``H`` ``inverse_gram`` ``(P, P)``. A compiled kernel."""
    n_frames, n_markers, _ = trial.shape
    n_pairs = inverse_gram.shape[0]
    pair_a, pair_b, _, shared = _pairs(n_markers)
    unit = np.empty((n_pairs, 3))
    products = np.empty((5, n_pairs, n_pairs))
    x = np.empty((n_pairs, n_pairs))
    total = np.zeros((5, 5))
    for f in range(n_frames):
        for p in range(n_pairs):
            a, b = pair_a[p], pair_b[p]
            for i in range(3):
                unit[p, i] = trial[f, a, i] - trial[f, b, i]
            length = np.sqrt(unit[p, 0] ** 2 + unit[p, 1] ** 2 + unit[p, 2] ** 2)
            for i in range(3):
                unit[p, i] /= length
        for a in range(5):
            for p in range(n_pairs):
                for q in range(n_pairs):
                    value = 0.0
                    for i in range(3):
                        for j in range(3):
                            value += unit[p, i] * _TRACELESS[a, i, j] * unit[q, j]
                    x[p, q] = shared[p, q] * value
            products[a] = inverse_gram @ x
        for a in range(5):
            for b in range(5):
                value = 0.0
                for p in range(n_pairs):
                    for q in range(n_pairs):
                        value += products[a, p, q] * products[b, q, p]
                total[a, b] += value
    return total


def axis_pull_deg(noise: NoiseDirections) -> float:
    """How far the anisotropy of ``noise`` pulls the normal of the arcs' planes [deg] (module
    docstring): ``inf`` where the scatter less its noise has no least eigenvalue apart from
    the others."""
    values, vectors = np.linalg.eigh(noise.signal_scatter())
    gaps = values[1:] - values[0]
    if not (gaps > 0.0).all():
        return math.inf
    forced = noise._count() * vectors[:, 1:].T @ noise.anisotropy() @ vectors[:, 0]
    return math.degrees(math.atan(float(np.linalg.norm(forced / gaps))))


def centre_pull_mm(noise: NoiseDirections, centre: np.ndarray) -> float:
    """How far the anisotropy of ``noise`` pulls a centre ``centre`` ``(3,)`` [mm] fitted to
    the markers' spheres [mm] (module docstring): ``inf`` where the scatter less its noise is
    not positive definite."""
    signal = noise.signal_scatter()
    if not np.linalg.eigvalsh(signal)[0] > 0.0:
        return math.inf
    lever = noise.marker_sum - noise.n_markers * np.asarray(centre, dtype=float)
    forced = (noise.n_frames - 1) * noise.anisotropy() @ lever
    return float(np.linalg.norm(np.linalg.solve(signal, forced)))


def statement(result, noise: NoiseDirections) -> tuple[tuple[str, ...], dict[str, object]]:
    """The warning (none, or one) and the numbers that the test of ``noise`` adds to
    ``result``, a centre or an axis of the segment whose markers gave it: its numbers in
    ``diagnostics`` (``noise_direction_...``) and, where the noise differs by direction and
    pulls the answer further than the SD it states (``diagnostics["center_sd_mm"]`` or
    ``["axis_sd_deg"]``), that its precision is not determined. An answer without a stated SD
    is not judged."""
    numbers = noise.numbers()
    if not noise.rejected():
        return (), numbers
    if hasattr(result, "direction"):
        pull, sd, unit = axis_pull_deg(noise), result.diagnostics.get("axis_sd_deg"), "deg"
    else:
        pull = centre_pull_mm(noise, result.center)
        sd, unit = result.diagnostics.get("center_sd_mm"), "mm"
    numbers[f"noise_direction_pull_{unit}"] = pull
    if sd is None or not pull > sd:
        return (), numbers
    sds = ", ".join(f"{value:.3g}" for value in numbers["noise_direction_sds_mm"])
    return (
        f"{PRECISION_NOT_DETERMINED}: the noise differs by direction (SDs of {sds} mm along "
        f"its principal directions, p = {noise.p_value:.2g}), which pulls the answer by about "
        f"{pull:.3g} {unit}, more than its SD of {sd:.3g} {unit} (an SD for noise of one "
        "variance in every direction)",
    ), numbers
