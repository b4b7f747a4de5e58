"""Rotations, rigid-body pose and small shared linear algebra.

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
    "rigid_fit",
    "rigid_poses",
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


def rigid_fit(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares rotation and translation mapping ``source`` onto ``target``.

    Kabsch/Umeyama without scale (Kanatani's SVD solution): minimises
    ``sum_i ||target_i - (R @ source_i + t)||^2`` with ``det(R) = +1``.

    Parameters
    ----------
    source : (n_markers, 3) or (n_frames, n_markers, 3)
        Body-fixed marker coordinates [mm]; broadcast against ``target``.
    target : (n_frames, n_markers, 3)
        Measured marker positions [mm].

    Returns
    -------
    R : (n_frames, 3, 3)
    t : (n_frames, 3) [mm]
    """
    target = np.asarray(target, dtype=float)
    source = np.broadcast_to(np.asarray(source, dtype=float), target.shape)
    source_mean = source.mean(axis=-2)
    target_mean = target.mean(axis=-2)
    cross = np.einsum(
        "...mi,...mj->...ij", target - target_mean[..., None, :], source - source_mean[..., None, :]
    )
    u, _, vt = np.linalg.svd(cross)
    d = np.sign(np.linalg.det(u @ vt))
    d = np.where(d == 0, 1.0, d)
    u = u.copy()
    u[..., :, 2] *= d[..., None]
    rotation = u @ vt
    translation = target_mean - np.einsum("...ij,...j->...i", rotation, source_mean)
    return rotation, translation


def rigid_poses(
    markers: np.ndarray, *, max_iterations: int = 20, tol_mm: float = 1e-12
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pose of a rigid marker cluster in every frame, with estimated body-fixed coordinates.

    Follows paper C §5: start from the body-fixed coordinates equal to the first frame,
    fit the pose of every frame by SVD, re-estimate the body-fixed coordinates as the mean
    of the back-transformed measurements (paper C eq. 5) and repeat until they stop changing.
    The body-fixed frame coincides with the world at frame 0 (``R[0] = I``, ``t[0] = 0``).

    Parameters
    ----------
    markers : (n_frames, n_markers, 3) [mm], ``n_markers >= 3`` and not collinear.

    Returns
    -------
    R : (n_frames, 3, 3), t : (n_frames, 3) [mm], body : (n_markers, 3) [mm]
    """
    body = markers[0].copy()
    for _ in range(max_iterations):
        rotation, translation = rigid_fit(body, markers)
        # Back-transform every frame into the body frame, then re-anchor at frame 0 (eq. 5).
        local = np.einsum("fji,fmj->fmi", rotation, markers - translation[:, None, :])
        mean_local = local.mean(axis=0)
        new_body = mean_local @ rotation[0].T + translation[0]
        change = np.max(np.abs(new_body - body))
        body = new_body
        if change < tol_mm:
            break
    rotation, translation = rigid_fit(body, markers)
    return rotation, translation, body


def angle_between_lines_deg(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Sign-free angle between line directions ``a`` and ``b`` ``(..., 3)``, in [0, 90] degrees."""
    cos_angle = np.abs(np.sum(unit(a) * unit(b), axis=-1))
    return np.degrees(np.arccos(np.clip(cos_angle, 0.0, 1.0)))
