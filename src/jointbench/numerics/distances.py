"""The first-order geometry of a cluster's inter-marker distances at its mean figure.

The distances between ``n`` markers, one per pair ``p = (a, b)``, move to first order by
``J e`` for a displacement ``e`` ``(3 n,)`` of the markers: row ``p`` of ``J`` holds the unit
vector ``u_p`` of ``x_a - x_b`` at marker ``a`` and ``-u_p`` at ``b``. A rigid motion moves no
distance, so ``J``'s rows span the displacements a rigid-body fit leaves as its residual
(less a cluster's flexes, below), and ``G = J J'`` (the pairs' Gram, ``G_pq = c_pq u_p . u_q``
with ``c_pq = sum_m s_pm s_qm`` from the signs ``s_pm`` of pair ``p`` at marker ``m``) follows
from the mean distances alone, by the law of cosines.
"""

from __future__ import annotations

import numpy as np

from jointbench.numerics.compiled import kernel
from jointbench.numerics.small import symmetric_eigen_into

__all__ = ["distance_gram_into", "distance_modes_into"]


@kernel
def distance_gram_into(
    mean_d: np.ndarray,
    pair_a: np.ndarray,
    pair_b: np.ndarray,
    squared: np.ndarray,
    cosines: np.ndarray,
    g: np.ndarray,
) -> float:
    """``G = J J'`` ``g`` ``(P, P)`` at the figure of mean distances ``mean_d`` ``(P,)`` [mm]
    between markers ``pair_a`` and ``pair_b`` ``(P,)`` (module docstring), with the pairs'
    unit vectors' Gram ``cosines`` ``(P, P)`` (``u_p . u_q``) and the squared distances
    ``squared`` ``(n, n)`` [mm^2] it is read from; returns the mean squared distance [mm^2]. A
    compiled kernel."""
    n_pairs = mean_d.shape[0]
    rms_sq = 0.0
    squared[:] = 0.0
    for p in range(n_pairs):
        squared[pair_a[p], pair_b[p]] = mean_d[p] ** 2
        squared[pair_b[p], pair_a[p]] = mean_d[p] ** 2
        rms_sq += mean_d[p] ** 2 / n_pairs
    for p in range(n_pairs):
        a, b = pair_a[p], pair_b[p]
        for q in range(n_pairs):
            c, d = pair_a[q], pair_b[q]
            shared = int(a == c) - int(a == d) - int(b == c) + int(b == d)
            if mean_d[p] == 0.0 or mean_d[q] == 0.0:
                cosines[p, q] = 0.0
            else:
                dot = 0.5 * (squared[a, d] + squared[b, c])
                dot -= 0.5 * (squared[a, c] + squared[b, d])
                cosines[p, q] = dot / (mean_d[p] * mean_d[q])
            g[p, q] = shared * cosines[p, q]
    return rms_sq


@kernel
def distance_modes_into(
    mean_d: np.ndarray,
    corrected: bool,
    variance: float,
    flex: float,
    pair_a: np.ndarray,
    pair_b: np.ndarray,
    scratch: tuple[np.ndarray, ...],
) -> float:
    """The modes of ``G`` (:func:`distance_gram_into`) at the figure of mean distances
    ``mean_d`` ``(P,)`` [mm] between markers ``pair_a`` and ``pair_b`` ``(P,)``, and the
    strength below which a mode is a flex, not shape: ``flex`` of the strongest and, for mean
    distances ``corrected`` for the noise ``variance`` [mm^2], the strength whose first-order
    signal is under 3 times the second-order one, ``s^2 / d`` (``d`` the RMS distance), which
    noise adds to a flex. ``scratch`` holds ``squared`` ``(n, n)``, ``cosines`` ``(P, P)``,
    ``g`` ``(P, P)``, ``strength`` ``(P,)`` (ascending), ``modes`` ``(P, P)`` (as columns) and
    ``work`` ``(P, P)``, all written. A compiled kernel."""
    squared, cosines, g, strength, modes, work = scratch
    n_pairs = mean_d.shape[0]
    rms_sq = distance_gram_into(mean_d, pair_a, pair_b, squared, cosines, g)
    symmetric_eigen_into(g, strength, modes, work)
    weakest_mode = flex * strength[n_pairs - 1]
    if corrected and rms_sq > 0.0:
        weakest_mode = max(weakest_mode, 9.0 * variance / rms_sq)
    return weakest_mode
