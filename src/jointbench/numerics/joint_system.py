"""The least-squares system of a point fixed in two moving segments (SCoRE's), in one home for
the joint-centre and axis methods (:mod:`jointbench.estimators.twosegment`) and the check of
what the poses' noise does to their answers (:mod:`jointbench.estimators.pose_noise`).

A point ``c1`` in the proximal segment and ``c2`` in the distal one with the same world
position in every frame, ``R1 c1 + t1 = R2 c2 + t2``, stacked over the ``N`` frames, is
``A [c1; c2] = b`` with ``A = [R1, -R2]`` and ``b = t2 - t1``. Its normal matrix is built from
3 x 3 sums, ``A'A = [[N I, -S], [-S', N I]]`` with ``S = sum_k R1' R2``, so no ``3N x 6``
matrix is formed.
"""

from __future__ import annotations

import numpy as np

from jointbench.numerics.compiled import kernel

__all__ = ["normal_matrix", "stacked_normal_equations"]


@kernel
def normal_matrix(relative_sum: np.ndarray, n_frames: int) -> np.ndarray:
    """``A'A`` ``(T, 6, 6)`` from the sum of the relative rotations ``S`` ``(T, 3, 3)`` over
    ``n_frames`` frames. A compiled kernel, which the covariance of SCoRE's answer calls
    (:func:`jointbench.estimators.pose_noise.score_covariance`)."""
    normal = np.zeros((relative_sum.shape[0], 6, 6))
    for t in range(relative_sum.shape[0]):
        for i in range(3):
            normal[t, i, i] = normal[t, 3 + i, 3 + i] = n_frames
            for j in range(3):
                normal[t, i, 3 + j] = normal[t, 3 + j, i] = -relative_sum[t, i, j]
    return normal


def stacked_normal_equations(
    r1: np.ndarray | None, t1: np.ndarray | None, r2: np.ndarray, t2: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Per trial, ``A'A`` ``(T, 6, 6)`` and ``A'b`` ``(T, 6)`` for rotations ``(T, N, 3, 3)``
    and translations ``(T, N, 3)`` [mm].

    ``r1 = t1 = None`` means the identity reference pose (one-segment data).
    """
    n_frames = r2.shape[1]
    rhs = t2 if t1 is None else t2 - t1
    if r1 is None:
        relative_sum = r2.sum(axis=1)
        g1 = rhs.sum(axis=1)
    else:
        relative_sum = np.einsum("tfji,tfjk->tik", r1, r2)
        g1 = np.einsum("tfji,tfj->ti", r1, rhs)
    g2 = -np.einsum("tfji,tfj->ti", r2, rhs)
    return normal_matrix(relative_sum, n_frames), np.concatenate([g1, g2], axis=1)
