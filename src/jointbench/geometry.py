"""Rotations and small shared linear algebra (rigid-body poses: :mod:`jointbench.numerics.poses`).

Conventions used throughout jointbench:

* points and marker positions are millimetres;
* a marker array is ``float64`` shaped ``(n_frames, n_markers, 3)``;
* a rotation vector ``r = theta * axis`` has its angle ``theta`` in radians;
* a pose ``(R, t)`` maps body-fixed coordinates ``x`` to the world as ``R @ x + t``.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "angle_between_lines_deg",
    "rotation_about_axis",
    "rotation_matrix",
    "rotation_vector",
    "skew",
    "unit",
]


def unit(vectors: np.ndarray) -> np.ndarray:
    """Normalise vectors along the last axis. Shape is preserved."""
    vectors = np.asarray(vectors, dtype=float)
    return vectors / np.linalg.norm(vectors, axis=-1, keepdims=True)


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix ``[v]x`` such that ``skew(v) @ w == cross(v, w)``.

    ``v`` is ``(..., 3)``; the result is ``(..., 3, 3)``.
    """
    v = np.asarray(v, dtype=float)
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def rotation_matrix(rotvec: np.ndarray) -> np.ndarray:
    """Rodrigues' formula: rotation vectors ``(..., 3)`` [rad] to matrices ``(..., 3, 3)``."""
    rotvec = np.asarray(rotvec, dtype=float)
    theta = np.linalg.norm(rotvec, axis=-1)[..., None, None]
    k = skew(rotvec)
    # Taylor coefficients near zero keep the formula exact to machine precision.
    small = theta < 1e-8
    safe = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - theta**2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    return np.eye(3) + a * k + b * (k @ k)


def rotation_about_axis(axis: np.ndarray, angle_rad: np.ndarray | float) -> np.ndarray:
    """Rotations by ``angle_rad`` (scalar or ``(n,)``) about the unit ``axis`` ``(3,)``."""
    angle = np.asarray(angle_rad, dtype=float)
    return rotation_matrix(angle[..., None] * unit(axis))


def rotation_vector(matrix: np.ndarray) -> np.ndarray:
    """Inverse of :func:`rotation_matrix` for angles in ``[0, pi]``: ``(..., 3, 3) -> (..., 3)``."""
    matrix = np.asarray(matrix, dtype=float)
    cos_theta = np.clip((np.trace(matrix, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0)
    theta = np.arccos(cos_theta)
    axial = np.stack(
        [
            matrix[..., 2, 1] - matrix[..., 1, 2],
            matrix[..., 0, 2] - matrix[..., 2, 0],
            matrix[..., 1, 0] - matrix[..., 0, 1],
        ],
        axis=-1,
    )
    sin_theta = np.sin(theta)
    small = theta < 1e-6
    scale = np.where(small, 0.5 + theta**2 / 12.0, theta / (2.0 * np.where(small, 1.0, sin_theta)))
    rotvec = scale[..., None] * axial
    # Near pi the axial part vanishes; recover the axis from the symmetric part instead.
    near_pi = theta > np.pi - 1e-4
    if np.any(near_pi):
        sym = (matrix[near_pi] + np.eye(3)) / 2.0
        cols = np.argmax(np.diagonal(sym, axis1=-2, axis2=-1), axis=-1)
        axis = unit(np.take_along_axis(sym, cols[:, None, None], axis=-1)[..., 0])
        rotvec[near_pi] = axis * theta[near_pi][:, None]
    return rotvec


def _unit_any_length(vectors: np.ndarray) -> np.ndarray:
    """:func:`unit` of vectors ``(..., 3)`` scaled by their largest component first; NaN for a
    zero vector."""
    vectors = np.asarray(vectors, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return unit(vectors / np.max(np.abs(vectors), axis=-1, keepdims=True))


def angle_between_lines_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Sign-free angle between line directions ``a`` and ``b`` ``(..., 3)``, in [0, 90] degrees.

    From both the sine and the cosine: the cosine alone rounds to 1 below ~1e-8 rad. Each
    vector is first divided by its largest component, so that a direction of any finite length
    has its angle (a norm of ~1e155 or more overflows); a zero vector has none (NaN).
    """
    a, b = _unit_any_length(a), _unit_any_length(b)
    sine = np.linalg.norm(np.cross(a, b), axis=-1)
    cosine = np.abs(np.sum(a * b, axis=-1))
    return np.degrees(np.arctan2(sine, cosine))
