"""Rigid-body poses of marker clusters: the least-squares rotation and paper C's iterated fit.

A pose ``(R, t)`` maps body-fixed coordinates ``x`` to the world as ``R @ x + t``; markers are
``float64`` arrays shaped ``(n_frames, n_markers, 3)`` [mm].
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from jointbench.numerics.compiled import kernel, kernel_array

__all__ = [
    "POSE_MAX_ITERATIONS",
    "POSE_TOL_MM",
    "PoseFit",
    "best_rotation",
    "change_limit",
    "fit_rigid_poses",
    "rigid_fit",
    "rigid_poses",
]

#: The alternation of :func:`fit_rigid_poses` stops once no body-fixed coordinate changes by
#: this much [mm]: 15 significant digits of coordinates of order 1000 mm (paper C §5's "15
#: decimals of precision"), or after this many re-estimations. The paper's rig converges in
#: under 5; a cluster that is thin or small against its noise converges at a slower linear
#: rate, and a fit stopped short leaves poses that depend on the starting frame, which the
#: pose-based methods then report (:mod:`jointbench.estimators.twosegment`).
POSE_TOL_MM = 1e-12
POSE_MAX_ITERATIONS = 100

#: Units in the last place of the largest coordinate that a change of the body-fixed
#: coordinates can be from rounding alone (see :func:`change_limit`).
_ROUNDING_ULPS = 4

# Frames per block of a many-trial pose fit.
_BLOCK_FRAMES = 65536


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

    This is the rotation of :func:`rigid_fit` (Kanatani's / Kabsch's SVD solution), computed
    matrix by matrix by the compiled :func:`_horn_rotations`; matrices where that cannot settle
    the answer go to the SVD. ``cross`` is ``(..., 3, 3)``; ``bound`` ``(...)``, an upper bound
    of ``max trace(R' H)`` the caller knows (such as half the summed squared lengths of the
    centred points), or ``None``. The result has the shape of ``cross``.
    """
    shape = np.shape(cross)
    flat = kernel_array(np.reshape(cross, (-1, 3, 3)))
    if bound is None:
        limits = np.full(flat.shape[0], np.inf)
    else:
        # np.broadcast_to costs more than a closed-form fit: taken only when shapes differ.
        if np.shape(bound) != shape[:-2]:
            bound = np.broadcast_to(bound, shape[:-2])
        limits = kernel_array(np.reshape(bound, -1))
    rotation = np.empty_like(flat)
    unsettled = np.empty(flat.shape[0], dtype=bool)
    _horn_rotations(flat, limits, rotation, unsettled)
    if unsettled.any():
        rotation[unsettled] = _kabsch_rotation(flat[unsettled])
    return rotation.reshape(shape)


@kernel
def _horn_rotations(
    cross: np.ndarray, bound: np.ndarray, rotation: np.ndarray, unsettled: np.ndarray
) -> None:
    """Horn's best rotation of each cross-covariance ``cross[k]`` (n, 3, 3) into ``rotation``
    (n, 3, 3); ``unsettled[k]`` (n,) marks those left to the SVD. A compiled kernel
    (:mod:`jointbench.numerics.compiled`).

    Horn's unit quaternion is the eigenvector of the largest eigenvalue of the 4x4 symmetric
    key matrix ``N`` of ``H``. The eigenvalue comes from Newton's method on the characteristic
    quartic, started above the largest root (Theobald's QCP) at the smaller of
    ``sqrt(3) |H|_F >= s1 + s2 + s3`` and ``bound[k]``: a close fit nearly attains the bound,
    so Newton needs a step or two. The eigenvector is the longest column of the adjugate of
    ``N - lambda I``. A matrix whose largest eigenvalue is (nearly) repeated -- collinear or
    coincident points, where the rotation is not unique -- or whose Newton search does not
    settle is marked unsettled.
    """
    for k in range(cross.shape[0]):
        h = cross[k]
        # Horn's key matrix is built from M = H' (M_ab = sum_i source_a target_b).
        sxx, syx, szx = h[0, 0], h[0, 1], h[0, 2]
        sxy, syy, szy = h[1, 0], h[1, 1], h[1, 2]
        sxz, syz, szz = h[2, 0], h[2, 1], h[2, 2]
        n00, n01, n02, n03 = sxx + syy + szz, syz - szy, szx - sxz, sxy - syx
        n11, n12, n13 = sxx - syy - szz, sxy + syx, szx + sxz
        n22, n23, n33 = -sxx + syy - szz, syz + szy, -sxx - syy + szz
        # Characteristic polynomial of the traceless N: l^4 + c2 l^2 + c1 l + c0.
        c2 = 0.0
        for i in range(3):
            for j in range(3):
                c2 += h[i, j] * h[i, j]
        c2 *= -2.0
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
        lam = math.sqrt(-1.5 * c2)
        scale = lam if lam > 0 else 1.0
        # Raised by a millionth: the bound equals the eigenvalue for an exact fit, and rounding
        # could put it just below, where a double root (collinear points) sends Newton's step
        # anywhere; from above, Newton still needs only a step or two more.
        lam = min(lam, bound[k] * (1.0 + 1e-6))
        tolerance = 1e-13 * scale
        settled = False
        for _ in range(60):
            l2 = lam * lam
            slope = (4.0 * l2 + 2.0 * c2) * lam + c1
            if slope == 0:
                slope = 1.0
            step = ((l2 + c2) * l2 + c1 * lam + c0) / slope
            lam -= step
            if not abs(step) > tolerance:
                settled = True
                break
        d0, d1, d2, d3 = n00 - lam, n11 - lam, n22 - lam, n33 - lam
        # Adjugate of A = N - lam I (symmetric); its columns span A's null vector.
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
        # The quaternion is the adjugate column of largest norm (the first, on a tie).
        w, x, y, z = c00, c01, c02, c03
        q_sq = c00 * c00 + c01 * c01 + c02 * c02 + c03 * c03
        column_sq = c01 * c01 + c11 * c11 + c12 * c12 + c13 * c13
        if column_sq > q_sq:
            w, x, y, z, q_sq = c01, c11, c12, c13, column_sq
        column_sq = c02 * c02 + c12 * c12 + c22 * c22 + c23 * c23
        if column_sq > q_sq:
            w, x, y, z, q_sq = c02, c12, c22, c23, column_sq
        column_sq = c03 * c03 + c13 * c13 + c23 * c23 + c33 * c33
        if column_sq > q_sq:
            w, x, y, z, q_sq = c03, c13, c23, c33, column_sq
        q_norm = math.sqrt(q_sq)
        # A simple largest eigenvalue leaves a cofactor of order gap * lambda^2; below
        # 1e-8 lambda^3 the eigenvector is too ill-determined for this arithmetic.
        unsettled[k] = not (
            settled and q_norm > 1e-8 * (scale * scale * scale) and math.isfinite(q_norm)
        )
        inverse_norm = 1.0 if unsettled[k] else 1.0 / q_norm
        w, x, y, z = w * inverse_norm, x * inverse_norm, y * inverse_norm, z * inverse_norm
        ww, xx, yy, zz = w * w, x * x, y * y, z * z
        xy, xz, yz, wx, wy, wz = x * y, x * z, y * z, w * x, w * y, w * z
        r = rotation[k]
        r[0, 0], r[0, 1], r[0, 2] = ww + xx - yy - zz, 2.0 * (xy - wz), 2.0 * (xz + wy)
        r[1, 0], r[1, 1], r[1, 2] = 2.0 * (xy + wz), ww - xx + yy - zz, 2.0 * (yz - wx)
        r[2, 0], r[2, 1], r[2, 2] = 2.0 * (xz - wy), 2.0 * (yz + wx), ww - xx - yy + zz


class PoseFit(NamedTuple):
    """:func:`fit_rigid_poses`: the poses, the body-fixed coordinates and how the alternation
    of paper C §5 ended, per trial (leading axes ``...``).

    ``rotation`` (..., n_frames, 3, 3), ``translation`` (..., n_frames, 3) [mm], ``body``
    (..., n_markers, 3) [mm]; ``iterations`` (...) the re-estimations of the body-fixed
    coordinates (eq. 5) made, ``change_mm`` (...) the largest change of a body-fixed
    coordinate in the last of them [mm], ``converged`` (...) whether that was below
    :func:`change_limit`.
    """

    rotation: np.ndarray
    translation: np.ndarray
    body: np.ndarray
    iterations: np.ndarray
    change_mm: np.ndarray
    converged: np.ndarray


def change_limit(markers: np.ndarray, tol_mm: float = POSE_TOL_MM) -> np.ndarray:
    """The change of the body-fixed coordinates ``(T,)`` [mm] below which the alternation of
    :func:`fit_rigid_poses` on trials ``markers`` ``(T, N, n, 3)`` [mm] has converged: ``tol_mm``,
    or :data:`_ROUNDING_ULPS` units in the last place of the trial's largest coordinate where
    that is more. Coordinates far from the origin (a laboratory whose origin lies metres away)
    round every change to a multiple of their last place, so a fixed ``tol_mm`` below it could
    never be reached."""
    largest = np.abs(markers).max(axis=(1, 2, 3))
    return np.maximum(tol_mm, _ROUNDING_ULPS * np.spacing(largest))


def rigid_poses(
    markers: np.ndarray, *, max_iterations: int = POSE_MAX_ITERATIONS, tol_mm: float = POSE_TOL_MM
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Pose of a rigid marker cluster in every frame, with estimated body-fixed coordinates:
    ``(R, t, body)`` of :func:`fit_rigid_poses`, which says how the alternation ended."""
    return tuple(fit_rigid_poses(markers, max_iterations=max_iterations, tol_mm=tol_mm)[:3])


def fit_rigid_poses(
    markers: np.ndarray, *, max_iterations: int = POSE_MAX_ITERATIONS, tol_mm: float = POSE_TOL_MM
) -> PoseFit:
    """Pose of a rigid marker cluster in every frame, with estimated body-fixed coordinates.

    Follows paper C §5: start from the body-fixed coordinates equal to the first frame,
    fit the pose of every frame by SVD, re-estimate the body-fixed coordinates as the mean
    of the back-transformed measurements (paper C eq. 5) and repeat until they change by less
    than :func:`change_limit` (``tol_mm``, or rounding for coordinates far from the origin),
    at most ``max_iterations`` times. The body-fixed frame coincides with the
    world at frame 0 (``R[0] = I``, ``t[0] = 0``).

    Leading axes are independent trials, fitted together: each stops iterating when its own
    body-fixed coordinates stop changing, so a trial's poses do not depend on its batch.

    Parameters
    ----------
    markers : (..., n_frames, n_markers, 3) [mm], ``n_markers >= 3`` and not collinear.

    Returns
    -------
    :class:`PoseFit`
    """
    markers = np.asarray(markers, dtype=float)
    n_frames, n_markers = markers.shape[-3:-1]
    batch = markers.shape[:-3]
    flat = markers.reshape(-1, n_frames, n_markers, 3)
    # Blocks of trials bound the temporaries' size, whatever the batch.
    per_block = max(1, _BLOCK_FRAMES // max(n_frames, 1))
    parts = [
        _rigid_poses_block(flat[i : i + per_block], max_iterations, tol_mm)
        for i in range(0, max(flat.shape[0], 1), per_block)
    ]
    return PoseFit(
        *(
            np.concatenate([part[k] for part in parts]).reshape(batch + parts[0][k].shape[1:])
            for k in range(len(PoseFit._fields))
        )
    )


def _rigid_poses_block(markers: np.ndarray, max_iterations: int, tol_mm: float) -> PoseFit:
    """:func:`fit_rigid_poses` of trials ``(T, N, P, 3)``, fitted together.

    What :func:`rigid_fit` would recompute on every iteration is hoisted out of the loop: the
    frames' centroids and centred markers do not change. Stacking every frame's coordinates as
    rows ``(frame, coordinate)`` turns the sums over markers and over frames into one matrix
    product per trial. Only the trials still iterating are refitted.
    """
    n_trials, n_frames, n_markers, _ = markers.shape
    # einsum: NumPy's mean over a middle axis of three is several times slower.
    target_mean = np.einsum("tfmi->tfi", markers) / n_markers
    centred = markers - target_mean[:, :, None, :]
    rows = np.ascontiguousarray(np.swapaxes(centred, -1, -2)).reshape(
        n_trials, n_frames * 3, n_markers
    )
    target_sq = _squared_length(centred)
    rotation = np.empty((n_trials, n_frames, 3, 3))

    def fit(trials: slice | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Fit the poses of ``trials`` to their current ``body`` (kept in ``rotation``);
        return the rotations (k, N, 3, 3) and the body-fixed centroids (k, 3) [mm]."""
        part = body[trials]
        body_mean = part.mean(axis=1)
        centred_body = part - body_mean[:, None, :]
        cross = (rows[trials] @ centred_body).reshape(-1, n_frames, 3, 3)
        bound = _eigenvalue_bound(target_sq[trials], _squared_length(centred_body)[:, None])
        fitted = rotation[trials] = best_rotation(cross, bound=bound)
        return fitted, body_mean

    body = markers[:, 0].copy()
    limit = change_limit(markers, tol_mm)
    active = np.ones(n_trials, dtype=bool)
    iterations = np.zeros(n_trials, dtype=int)
    change = np.full(n_trials, np.nan)
    for _ in range(max_iterations):
        trials = np.flatnonzero(active)
        if not trials.size:
            break
        take = slice(None) if trials.size == n_trials else trials
        fitted, body_mean = fit(take)
        # Back-transform every frame into the body frame, then re-anchor at frame 0 (eq. 5):
        # R'(y - t) = R'(y - mean(y)) + mean(body), averaged over the frames.
        summed = np.swapaxes(fitted.reshape(-1, n_frames * 3, 3), 1, 2) @ rows[take]
        mean_local = np.swapaxes(summed, 1, 2) / n_frames + body_mean[:, None, :]
        first = fitted[:, 0]
        first_translation = target_mean[take, 0] - (first @ body_mean[:, :, None])[..., 0]
        new_body = mean_local @ np.swapaxes(first, 1, 2) + first_translation[:, None, :]
        change[trials] = np.max(np.abs(new_body - body[take]), axis=(1, 2))
        iterations[trials] += 1
        converged = change[trials] < limit[trials]
        # A converged trial keeps the coordinates its poses were just fitted to (within
        # ``tol_mm`` of the fixed point) while the others iterate on, so a trial's answer does
        # not depend on its batch.
        active[trials[converged]] = False
        body[trials[~converged]] = new_body[~converged]
    else:
        if active.any():
            fit(np.flatnonzero(active))
    # t = mean(y) - R mean(body), every frame's rotation applied as one product per trial.
    turned = rotation.reshape(n_trials, n_frames * 3, 3) @ body.mean(axis=1)[:, :, None]
    translation = target_mean - turned.reshape(n_trials, n_frames, 3)
    return PoseFit(
        *_anchored_at_frame_0(rotation, translation, body), iterations, change, change < limit
    )


def _anchored_at_frame_0(
    rotation: np.ndarray, translation: np.ndarray, body: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The same poses ``rotation`` ``(T, N, 3, 3)``, ``translation`` ``(T, N, 3)`` [mm] of the
    body-fixed coordinates ``body`` ``(T, n, 3)`` [mm] in the body frame that is the world at
    frame 0: ``R_f R_0'``, ``t_f - R_f R_0' t_0`` and ``R_0 b + t_0``, which leave the same
    residual. The alternation anchors its last body at frame 0 but fits the last poses to it,
    so frame 0's pose is the identity only as far as the body had stopped changing, which a
    fit stopped by its iteration limit need not have."""
    first_rotation, first_translation = rotation[:, :1], translation[:, :1]
    anchored = rotation @ np.swapaxes(first_rotation, -1, -2)
    moved = translation - (anchored @ first_translation[..., None])[..., 0]
    placed = body @ np.swapaxes(first_rotation[:, 0], -1, -2) + first_translation
    return anchored, moved, placed
