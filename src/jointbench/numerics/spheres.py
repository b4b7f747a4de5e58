"""Gamage & Lasenby's least-squares sphere fit (2002): the normal equations and their solution.

The concentric-sphere model behind every centre estimator of paper A, in one place: the
estimators (:mod:`jointbench.estimators.sphere`) build LS, BC and their costs on it, and the
support verdict (:mod:`jointbench.estimators.support`) tests whether markers without a pose
move on spheres at all. Markers are ``(n_frames, n_markers, 3)`` [mm].
"""

from __future__ import annotations

from functools import lru_cache
from typing import NamedTuple

import numpy as np

from jointbench.numerics.rank import negligible

__all__ = ["LSMoments", "ls_moments", "ls_system", "mean_weights", "row_sq", "solve_ls_system"]

_ONES3 = np.ones(3)


def row_sq(flat: np.ndarray) -> np.ndarray:
    """Squared norms of the rows of a ``(n, 3)`` array (a matmul is cheaper than einsum here)."""
    return (flat * flat) @ _ONES3


@lru_cache(maxsize=64)
def mean_weights(n: int) -> np.ndarray:
    """``(n,)`` of ``1 / n``, read-only: ``weights @ x`` is the mean of the rows of ``x``."""
    weights = np.full(n, 1.0 / n)
    weights.setflags(write=False)
    return weights


class LSMoments(NamedTuple):
    """Gamage & Lasenby's normal equations with the per-marker moments they are made of.

    Each (frame, marker) row is augmented to ``x = (v, |v|^2)`` and centred on its marker's
    mean over frames; every sum the LS, BC and cost formulas need is then a product with these
    rows, and ``A`` and ``b`` are blocks of one 4 x 4 Gram matrix.
    """

    a_matrix: np.ndarray  # (3, 3) [mm^2]
    b_vector: np.ndarray  # (3,) [mm^3]
    means: np.ndarray  # (P, 4): mean_k v_k^p [mm] and mean_k |v_k^p|^2 [mm^2]
    centred: np.ndarray  # (N P, 4): x_k^p - mean_k x_k^p, frame-major rows


def ls_moments(markers: np.ndarray) -> LSMoments:
    n_frames, n_markers, _ = markers.shape
    augmented = np.empty((n_frames, n_markers, 4))
    augmented[..., :3] = markers
    augmented[..., 3] = row_sq(markers.reshape(-1, 3)).reshape(n_frames, n_markers)
    # Means over frames as one vector-matrix product with the (frames, markers * 4) view, and
    # the sums over frames and markers as one matmul of the (frames * markers, 4) rows: at the
    # usual 100-1000 frames NumPy's per-call overhead, not arithmetic, sets the cost.
    wide = augmented.reshape(n_frames, -1)
    means = mean_weights(n_frames) @ wide
    wide -= means
    centred = wide.reshape(-1, 4)
    gram = (centred.T @ centred) * (1.0 / n_frames)
    return LSMoments(2.0 * gram[:3, :3], gram[:3, 3].copy(), means.reshape(-1, 4), centred)


def ls_system(markers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Gamage & Lasenby's normal equations ``A c = b`` (paper A eq. 4 minimised over ``c``).

    ``A = 2 sum_p Cov(v^p)`` ``(3, 3)`` [mm^2] and
    ``b = sum_p [mean(|v|^2 v) - mean(v) mean(|v|^2)]`` ``(3,)`` [mm^3], covariances with 1/N.
    """
    moments = ls_moments(markers)
    return moments.a_matrix, moments.b_vector


def solve_ls_system(a_matrix: np.ndarray, b_vector: np.ndarray) -> np.ndarray:
    """Solve ``A c = b``, dropping singular values negligible by
    :func:`jointbench.numerics.rank.negligible` (a pure hinge)."""
    u, s, vt = np.linalg.svd(a_matrix)
    inverse = np.where(negligible(s, s[0]), 0.0, 1.0 / np.where(s > 0, s, 1.0))
    return vt.T @ (inverse * (u.T @ b_vector))
