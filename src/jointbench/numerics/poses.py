"""Rigid-body poses of marker clusters: the least-squares rotation and paper C's iterated fit.

A pose ``(R, t)`` maps body-fixed coordinates ``x`` to the world as ``R @ x + t``; markers are
``float64`` arrays shaped ``(n_frames, n_markers, 3)`` [mm].
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["best_rotation", "rigid_fit", "rigid_poses"]

# Frames per chunk of a many-trial pose fit.
_CHUNK_FRAMES = 4096


def rigid_fit(source: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares rotation and translation mapping ``source`` onto ``target``.

    Kabsch/Umeyama without scale (Kanatani's SVD solution): minimises
    ``sum_i ||target_i - (R @ source_i + t)||^2`` with ``det(R) = +1``. The rotation is
    computed by :func:`best_rotation` (same minimiser, element-wise on the stack of frames).

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
    centred_target = target - target_mean[..., None, :]
    centred_source = source - source_mean[..., None, :]
    cross = np.einsum("...mi,...mj->...ij", centred_target, centred_source)
    bound = _eigenvalue_bound(_squared_length(centred_target), _squared_length(centred_source))
    rotation = best_rotation(cross, bound=bound)
    translation = target_mean - np.einsum("...ij,...j->...i", rotation, source_mean)
    return rotation, translation


def _kabsch_rotation(cross: np.ndarray) -> np.ndarray:
    """Kabsch/Kanatani: ``U diag(1, 1, det(U V')) V'`` from the SVD of ``cross`` (..., 3, 3)."""
    u, _, vt = np.linalg.svd(cross)
    d = np.sign(np.linalg.det(u @ vt))
    d = np.where(d == 0, 1.0, d)
    u = u.copy()
    u[..., :, 2] *= d[..., None]
    return u @ vt


def _squared_length(centred: np.ndarray) -> np.ndarray:
    """``sum_i |p_i|^2`` over the points (axis -2) of ``(..., n, 3)``: ``(...)``."""
    return np.einsum("...mi,...mi->...", centred, centred)


def _eigenvalue_bound(target_sq: np.ndarray, source_sq: np.ndarray) -> np.ndarray:
    """``(sum_i |target_i|^2 + sum_i |source_i|^2) / 2`` for centred points, from the two sums:
    at least ``max trace(R' H) = sum_i target_i . R source_i`` (each term is at most the mean
    of the two squared lengths), with equality for a perfect fit."""
    return 0.5 * (target_sq + source_sq)


def best_rotation(cross: np.ndarray, *, bound: np.ndarray | None = None) -> np.ndarray:
    """Proper rotations ``R`` maximising ``trace(R' H)`` for ``H = sum_i target_i source_i'``.

    This is the rotation of :func:`rigid_fit` (Kanatani's / Kabsch's SVD solution). It is
    computed as Horn's unit quaternion, the eigenvector of the largest eigenvalue of the 4x4
    symmetric key matrix of ``H``: the eigenvalue by Newton's method on the characteristic
    quartic started above the largest root (Theobald's QCP; the start is the smaller of
    ``sqrt(3) |H|_F`` and ``bound``, an upper bound the caller knows, such as half the summed
    squared lengths of the centred points, which a close fit nearly attains, so that Newton
    needs a step or two), the eigenvector as the largest
    column of the adjugate of ``N - lambda I``. Everything is element-wise on the stack, which
    is an order of magnitude faster than batched LAPACK SVDs of 3x3 matrices and agrees with
    them to ~1e-15. Matrices where the largest eigenvalue is (nearly) repeated -- collinear or
    coincident points, where the rotation is not unique -- fall back to the SVD.

    ``cross`` is ``(..., 3, 3)``, ``bound`` ``(...)`` or ``None``; the result has the shape of
    ``cross``.
    """
    shape = np.shape(cross)
    cross = np.asarray(cross, dtype=float).reshape(-1, 3, 3)
    # Horn's key matrix is built from M = H' (M_ab = sum_i source_a target_b).
    sxx, syx, szx = cross[..., 0, 0], cross[..., 0, 1], cross[..., 0, 2]
    sxy, syy, szy = cross[..., 1, 0], cross[..., 1, 1], cross[..., 1, 2]
    sxz, syz, szz = cross[..., 2, 0], cross[..., 2, 1], cross[..., 2, 2]
    n00, n01, n02, n03 = sxx + syy + szz, syz - szy, szx - sxz, sxy - syx
    n11, n12, n13 = sxx - syy - szz, sxy + syx, szx + sxz
    n22, n23, n33 = -sxx + syy - szz, syz + szy, -sxx - syy + szz
    # Characteristic polynomial of the traceless N: l^4 + c2 l^2 + c1 l + c0.
    flat = cross.reshape(-1, 9)
    c2 = -2.0 * np.einsum("...i,...i->...", flat, flat)
    c1 = -8.0 * (
        sxx * (syy * szz - syz * szy)
        - sxy * (syx * szz - syz * szx)
        + sxz * (syx * szy - syy * szx)
    )
    # det N by Laplace expansion along rows (0, 1) with complementary minors of rows (2, 3).
    a01, a02, a03 = n00 * n11 - n01 * n01, n00 * n12 - n02 * n01, n00 * n13 - n03 * n01
    a12, a13, a23 = n01 * n12 - n02 * n11, n01 * n13 - n03 * n11, n02 * n13 - n03 * n12
    b01, b02, b03 = n02 * n13 - n12 * n03, n02 * n23 - n22 * n03, n02 * n33 - n23 * n03
    b12, b13, b23 = n12 * n23 - n22 * n13, n12 * n33 - n23 * n13, n22 * n33 - n23 * n23
    c0 = a01 * b23 - a02 * b13 + a03 * b12 + a12 * b03 - a13 * b02 + a23 * b01
    # sqrt(3) |H|_F >= s1 + s2 + s3 >= lambda_max: Newton from above converges monotonically
    # (the key matrix is symmetric, so every root of its quartic is real).
    lam = np.sqrt(-1.5 * c2)
    scale = np.where(lam > 0, lam, 1.0)
    if bound is not None:
        # Raised by a millionth: the bound equals the eigenvalue for an exact fit, and rounding
        # could put it just below, where a double root (collinear points) sends Newton's step
        # anywhere; from above, Newton still needs only a step or two more.
        raised = np.asarray(bound, dtype=float).reshape(lam.shape) * (1.0 + 1e-6)
        lam = np.minimum(lam, raised)
    tolerance = 1e-13 * scale
    # A matrix stops stepping once its own step is small, so its answer does not depend on the
    # other matrices of the stack.
    active = np.ones(lam.shape, dtype=bool)
    for _ in range(60):
        l2 = lam * lam
        slope = (4.0 * l2 + 2.0 * c2) * lam + c1
        slope[slope == 0] = 1.0
        step = ((l2 + c2) * l2 + c1 * lam + c0) / slope
        step *= active
        lam -= step
        active &= np.abs(step) > tolerance
        if not active.any():
            break
    d0, d1, d2, d3 = n00 - lam, n11 - lam, n22 - lam, n33 - lam
    # Adjugate of A = N - lam I (symmetric); its columns span A's null vector, the quaternion.
    m01, m02, m03 = n02 * n13 - n12 * n03, n02 * n23 - d2 * n03, n02 * d3 - n23 * n03
    m12, m13, m23 = n12 * n23 - d2 * n13, n12 * d3 - n23 * n13, d2 * d3 - n23 * n23
    u01, u02, u03 = d0 * d1 - n01 * n01, d0 * n12 - n02 * n01, d0 * n13 - n03 * n01
    u12, u13 = n01 * n12 - n02 * d1, n01 * n13 - n03 * d1
    c00 = d1 * m23 - n12 * m13 + n13 * m12
    c01 = -(n01 * m23 - n12 * m03 + n13 * m02)
    c02 = n01 * m13 - d1 * m03 + n13 * m01
    c03 = -(n01 * m12 - d1 * m02 + n12 * m01)
    c11 = d0 * m23 - n02 * m03 + n03 * m02
    c12 = -(d0 * m13 - n01 * m03 + n03 * m01)
    c13 = d0 * m12 - n01 * m02 + n02 * m01
    c22 = n03 * u13 - n13 * u03 + d3 * u01
    c23 = -(n02 * u13 - n12 * u03 + n23 * u01)
    c33 = n02 * u12 - n12 * u02 + d2 * u01
    # The quaternion is the adjugate column of largest norm (selected element-wise).
    columns = (
        (c00, c01, c02, c03),
        (c01, c11, c12, c13),
        (c02, c12, c22, c23),
        (c03, c13, c23, c33),
    )
    q, q_sq = columns[0], c00 * c00 + c01 * c01 + c02 * c02 + c03 * c03
    for column in columns[1:]:
        column_sq = sum(c * c for c in column)
        larger = column_sq > q_sq
        q_sq = np.where(larger, column_sq, q_sq)
        q = tuple(np.where(larger, new, old) for new, old in zip(column, q, strict=True))
    q_norm = np.sqrt(q_sq)
    # A simple largest eigenvalue leaves a cofactor of order gap * lambda^2; below 1e-8 lambda^3
    # the eigenvector is too ill-determined for element-wise arithmetic: use the SVD there.
    # So does a matrix whose Newton search did not settle.
    fallback = ~(q_norm > 1e-8 * scale**3) | ~np.isfinite(q_norm) | active
    inverse_norm = 1.0 / np.where(fallback, 1.0, q_norm)
    w, x, y, z = (component * inverse_norm for component in q)
    ww, xx, yy, zz = w * w, x * x, y * y, z * z
    xy, xz, yz, wx, wy, wz = x * y, x * z, y * z, w * x, w * y, w * z
    rotation = np.stack(
        [
            *(ww + xx - yy - zz, 2.0 * (xy - wz), 2.0 * (xz + wy)),
            *(2.0 * (xy + wz), ww - xx + yy - zz, 2.0 * (yz - wx)),
            *(2.0 * (xz - wy), 2.0 * (yz + wx), ww - xx - yy + zz),
        ],
        axis=-1,
    ).reshape(-1, 3, 3)
    if np.any(fallback):
        rotation[fallback] = _kabsch_rotation(cross[fallback])
    return rotation.reshape(shape)


def rigid_poses(
    markers: np.ndarray, *, max_iterations: int = 20, tol_mm: float = 1e-12
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pose of a rigid marker cluster in every frame, with estimated body-fixed coordinates.

    Follows paper C §5: start from the body-fixed coordinates equal to the first frame,
    fit the pose of every frame by SVD, re-estimate the body-fixed coordinates as the mean
    of the back-transformed measurements (paper C eq. 5) and repeat until they stop changing.
    The body-fixed frame coincides with the world at frame 0 (``R[0] = I``, ``t[0] = 0``).

    Leading axes are independent trials, fitted together: each stops iterating when its own
    body-fixed coordinates stop changing, so a trial's poses do not depend on its batch.

    Parameters
    ----------
    markers : (..., n_frames, n_markers, 3) [mm], ``n_markers >= 3`` and not collinear.

    Returns
    -------
    R : (..., n_frames, 3, 3), t : (..., n_frames, 3) [mm], body : (..., n_markers, 3) [mm]
    """
    markers = np.asarray(markers, dtype=float)
    n_frames = markers.shape[-3]
    batch = markers.shape[:-3]
    per_chunk = max(1, _CHUNK_FRAMES // max(n_frames, 1))
    if math.prod(batch) > per_chunk:
        # Element-wise work on a few thousand frames at a time stays in cache; whole batches
        # of long recordings would stream every temporary through memory.
        flat = markers.reshape(-1, *markers.shape[-3:])
        parts = [
            rigid_poses(flat[i : i + per_chunk], max_iterations=max_iterations, tol_mm=tol_mm)
            for i in range(0, flat.shape[0], per_chunk)
        ]
        return tuple(
            np.concatenate([part[k] for part in parts]).reshape(*batch, *parts[0][k].shape[1:])
            for k in range(3)
        )
    # What rigid_fit recomputes on every call is hoisted out of the loop: the frames' centroids
    # and centred markers do not change between iterations. Stacking every frame's coordinates
    # as rows ``(frame, coordinate)`` turns the sums over markers and over frames into single
    # matrix products per trial.
    n_markers = markers.shape[-2]
    target_mean = markers.mean(axis=-2)
    centred = markers - target_mean[..., None, :]
    rows = np.ascontiguousarray(np.swapaxes(centred, -1, -2)).reshape(
        *batch, n_frames * 3, n_markers
    )

    target_sq = _squared_length(centred)

    def fit(body: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        body_mean = body.mean(axis=-2)
        centred_body = body - body_mean[..., None, :]
        cross = rows @ centred_body
        bound = _eigenvalue_bound(target_sq, _squared_length(centred_body)[..., None])
        rotation = best_rotation(cross.reshape(*batch, n_frames, 3, 3), bound=bound)
        translation = target_mean - (rotation @ body_mean[..., None, :, None])[..., 0]
        return rotation, translation, body_mean

    body = markers[..., 0, :, :].copy()
    active = np.ones(markers.shape[:-3], dtype=bool)
    for _ in range(max_iterations):
        rotation, translation, body_mean = fit(body)
        # Back-transform every frame into the body frame, then re-anchor at frame 0 (eq. 5):
        # R'(y - t) = R'(y - mean(y)) + mean(body), averaged over the frames.
        summed = np.swapaxes(rotation.reshape(*batch, n_frames * 3, 3), -1, -2) @ rows
        mean_local = np.swapaxes(summed, -1, -2) / n_frames + body_mean[..., None, :]
        new_body = (
            mean_local @ np.swapaxes(rotation[..., 0, :, :], -1, -2) + translation[..., 0, None, :]
        )
        converged = np.max(np.abs(new_body - body), axis=(-2, -1)) < tol_mm
        # A converged trial keeps the coordinates its poses were just fitted to (within
        # ``tol_mm`` of the fixed point) while the others iterate on; refitting it gives the
        # same poses, so a trial's answer does not depend on its batch.
        active &= ~converged
        body = np.where(active[..., None, None], new_body, body)
        if not active.any():
            return rotation, translation, body
    rotation, translation, _ = fit(body)
    return rotation, translation, body
