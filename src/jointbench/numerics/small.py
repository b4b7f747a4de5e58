"""Stacks of 3 x 3 matrices, element-wise: LAPACK and ``matmul`` spend microseconds of call
overhead per 3 x 3 matrix, the arithmetic takes nanoseconds.

Matrices are ``float64`` arrays shaped ``(..., 3, 3)``.
"""

from __future__ import annotations

import numpy as np

__all__ = ["inverse3", "rotated3"]


def inverse3(matrices: np.ndarray) -> np.ndarray:
    """Inverses of ``(..., 3, 3)`` matrices from their cofactors (adjugate over determinant).

    Accurate to ``cond * eps`` like an LU solve; a singular matrix gives inf/NaN entries
    rather than an error, so callers check the conditioning they need.
    """
    m = np.asarray(matrices, dtype=float)
    a, b, c = m[..., 0, 0], m[..., 0, 1], m[..., 0, 2]
    d, e, f = m[..., 1, 0], m[..., 1, 1], m[..., 1, 2]
    g, h, i = m[..., 2, 0], m[..., 2, 1], m[..., 2, 2]
    c00, c01, c02 = e * i - f * h, f * g - d * i, d * h - e * g
    determinant = a * c00 + b * c01 + c * c02
    inverse = np.stack(
        [
            c00,
            c * h - b * i,
            b * f - c * e,
            c01,
            a * i - c * g,
            c * d - a * f,
            c02,
            b * g - a * h,
            a * e - b * d,
        ],
        axis=-1,
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        inverse /= determinant[..., None]
    return inverse.reshape(m.shape)


def rotated3(rotations: np.ndarray, matrix: np.ndarray) -> np.ndarray:
    """``R M R'`` for rotations ``(..., N, 3, 3)`` and one symmetric matrix ``M`` ``(..., 3, 3)``
    per leading index (e.g. per trial): ``(..., N, 3, 3)``, exactly symmetric.

    One matrix product gives ``R M`` for all frames; the six distinct entries of the product
    with ``R'`` are then formed element-wise and the lower triangle mirrors the upper one.
    """
    rotations = np.asarray(rotations, dtype=float)
    *lead, n_frames, _, _ = rotations.shape
    rows = rotations.reshape(*lead, n_frames * 3, 3)
    left = (rows @ np.asarray(matrix, dtype=float)).reshape(rotations.shape)
    out = np.empty(rotations.shape)
    for i in range(3):
        for j in range(i, 3):
            entry = (
                left[..., i, 0] * rotations[..., j, 0]
                + left[..., i, 1] * rotations[..., j, 1]
                + left[..., i, 2] * rotations[..., j, 2]
            )
            out[..., i, j] = entry
            out[..., j, i] = entry
    return out
