"""How far the noise in two segments' poses pulls a joint centre: errors in variables.

A joint centre from two segments (SCoRE, the analytic centre, the Gauss–Markov fits) is fixed
by the relative rotations: a point ``a_p`` in the proximal segment and ``a_d`` in the distal
one, offsets from each cluster's centroid in its body frame, with
``R_p a_p + t_p = R_d a_d + t_d`` in every frame. Stacked over the ``N`` frames this is the
least-squares problem ``A x = b`` of :mod:`jointbench.numerics.joint_system`, whose normal
matrix ``M = [[N I, -S], [-S', N I]]`` (``S = sum_k Q_k``, ``Q_k = R_p' R_d`` the relative
rotation) has, on nearly hinged motion, one eigenvalue that only the rotation off the hinge
keeps from zero: along the hinge axis in both frames.

The rotations are noisy: to first order ``R_k = R0_k exp([e_k]x)`` with ``e_k`` of covariance
``Sigma = s^2 K^-1`` in the body frame, the pose covariance the support verdict tests the
rotation against (:mod:`jointbench.estimators.support`, "two segments"). Each segment's
``s^2`` is its own rigid-body residual, as the verdict takes it: the noisier segment's poses
are the noisier ones. The noise is taken to be the same in every direction of the world,
which the residuals of three or four markers cannot tell apart from the geometry of their
cluster (a camera's larger noise along its depth is a limit the README measures). Frame 0's
poses are the identity by construction (the body frame is the world's there), which moves
frame 0's error into every other frame's pose: a rotation of the body frames shared by all
frames, which moves no centre. Relative to it frame 0 is as noisy as the others, and every
frame counts.

Noise in a regressor is not noise in an answer: ``E[exp([e]x)] = I + G`` with
``G = (Sigma - tr(Sigma) I) / 2``, so the noise shrinks the mean relative rotation towards no
rotation at all, ``E[Q_k] = Q0_k + G_p Q0_k + Q0_k G_d``, and with it the eigenvalue that
fixes the centre along the hinge. To second order in the noise, with the true joint at
``x = (a_p, a_d)``,

    ``E[A' b] = E[M] x + B x``,   ``B = [[N G_p, S G_d], [S' G_p, N G_d]]``

(the centroids' noise is independent of the rotations' and adds nothing): the least-squares
answer ``M^-1 A' b`` is attenuated, and ``(M + B)^-1 A' b`` is not. An answer ``x^``
therefore lies ``(M + B)^-1 B x^`` from where the poses, their noise accounted for, put the
joint: for SCoRE, whose answer is the midpoint of its two points, nearly its distance from
that corrected centre; for any other answer the same attenuation read at it. Every ``G`` is
negative (semi)definite, so the answer is pulled towards the clusters' centroids by a part
of its distance from them that grows as the rotation off the hinge shrinks towards the
rotations' noise, and that no SD describes (the Gauss–Markov covariance, first order, does
not contain it). It is the classical attenuation of a regression on noisy regressors (Fuller
1987), which :mod:`jointbench.estimators.centre_precision` corrects in the one-segment
centre's information for the same cause. The corrected centre itself is no better an answer:
its variance grows without bound as the noise's part does.

How much the noise took: along the least determined direction ``v`` of the noise-free
information (the symmetric part of ``M + B``), the ratio of the noise's information to it,
``share = -v' B v / v' (M + B) v``: the answer keeps ``1 / (1 + share)`` of the joint's offset
from the markers along ``v``. Where that information is not positive, the noise is as large as
the rotation that fixes the centre along ``v`` and has taken all of it (the share is ``inf``).
The expansion is second order: where the noise takes most of the rotation off the hinge
(nearly hinged motion, or few frames) the pull overstates the mean error.
``tests/test_pose_noise.py`` compares the pull with SCoRE's mean error over noise draws.

Scatter of a linear least-squares centre. The noise also scatters an answer about where it
pulls it; to first order the analytic centre (paper C's eq. 9) and SCoRE are linear in the
noise, and their covariance follows from the model of paper C's frame-0 extension
(:mod:`jointbench.estimators.hjc`, "Frame 0"): the joint's point in each segment's body frame,
as that frame is placed at frame 0, is the true centre ``c`` plus an error ``delta_a`` of
covariance ``A_a`` (the frame-0 fit's error at the joint, :func:`point_covariance`, times that
segment's own rigid-body residual variance ``s_a^2``), and each later frame's pose places it
with an independent error of the same covariance. With ``Q_t = R_p(t)' R_d(t)`` the relative
rotations of frames ``t >= 1``, ``S = sum_t Q_t`` and ``n`` those frames:

* the analytic centre's error is ``N^-1 sum_t [(I - Q_t') (delta_p + e_pt) + (I - Q_t)
  (delta_d + e_dt)]`` with ``N = sum_t (2 I - Q_t - Q_t')``: the frame-0 errors enter every
  frame alike, through ``D_p = n I - S'`` and ``D_d = n I - S``, and dominate the later frames'
  on a long trial (:func:`analytic_covariance`);
* SCoRE's answer, the midpoint ``(c_p + c_d) / 2`` of its two points (frame 0 included, whose
  poses are the identity), has error ``P (x^ - x) + (delta_p + delta_d) / 2`` with ``[P_p,
  P_d] = [I, I] M^-1 / 2`` and ``M`` its normal matrix: frame ``t`` adds ``(P_p - P_d Q_t')
  e_pt - (P_p Q_t - P_d) e_dt``, frame 0 ``(I/2 - E) delta_p + (I/2 + E) delta_d`` with ``E =
  P_p - P_d`` (:func:`score_covariance`).

Every sum over the frames is one of ``S`` and ``sum_t Q_t' A Q_t`` or ``sum_t Q_t A Q_t'``,
which the second moments ``sum_t vec(Q_t) vec(Q_t)'`` (9 x 9) give for any ``A``. What it does not
hold: the pull above (second order), noise larger along one direction than across it, and
markers that move on their segment. How much of the information the analytic centre's
covariance is first order in is the noise's own: :func:`analytic_noise_share`; how much of
its error is second order in the frame-0 poses' errors, which turn every relative rotation as
they place the joint: :func:`analytic_anchor_covariance`.
``tests/test_joint_centre_scatter.py`` holds the covariances to the answers' scatter over noise
draws.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from jointbench.numerics.compiled import kernel, kernel_array
from jointbench.numerics.joint_system import normal_matrix
from jointbench.numerics.rank import RCOND
from jointbench.numerics.reuse import remembered
from jointbench.numerics.small import skew9

if TYPE_CHECKING:
    from jointbench.estimators.segment_poses import SegmentPoses

__all__ = [
    "NoisyPoses",
    "PoseNoise",
    "analytic_anchor_covariance",
    "analytic_anchor_share",
    "analytic_covariance",
    "analytic_noise_share",
    "anchor_bias_mm",
    "centre_covariance",
    "lever_factors",
    "point_covariance",
    "point_covariance_into",
    "pose_noise",
    "pull_mm",
    "score_covariance",
]


@dataclass(frozen=True, eq=False)
class PoseNoise:
    """What the noise in one trial's two segment poses does to a least-squares joint centre:
    ``operator`` ``(6, 6)``, ``(M + B)^-1 B``, maps an answer's offsets from the proximal and
    distal clusters' centroids ``(a_p, a_d)`` [mm] (body frames, which are the world's at
    frame 0) to how far the noise pulled those points [mm] (``inf`` where ``share`` is);
    ``centroids`` ``(2, 3)`` [mm] those centroids; ``share`` the ratio of the noise's
    information to the noise-free information along the least determined direction (module
    docstring). Equal to another with the same numbers, so that verdicts carrying one compare
    as values."""

    operator: np.ndarray
    centroids: np.ndarray
    share: float

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, PoseNoise):
            return NotImplemented
        return (
            np.array_equal(self.operator, other.operator)
            and np.array_equal(self.centroids, other.centroids)
            and self.share == other.share
        )


class NoisyPoses(NamedTuple):
    """One segment's poses in ``T`` trials, as the pull reads them: ``rotation``
    ``(T, N, 3, 3)``, the body-fixed markers ``body`` ``(T, n, 3)`` [mm], the inverse of their
    centred inertia ``inertia_inv`` ``(T, 3, 3)`` [mm^-2] and the rigid-body residual per
    coordinate ``variance`` ``(T,)`` [mm^2]."""

    rotation: np.ndarray
    body: np.ndarray
    inertia_inv: np.ndarray
    variance: np.ndarray


def pose_noise(proximal: NoisyPoses, distal: NoisyPoses) -> list[PoseNoise]:
    """Per trial, the :class:`PoseNoise` of the ``proximal`` and ``distal`` segments' poses
    (module docstring: ``M``, ``B`` and the share)."""
    operator, centroids, share = _pose_noise_numbers(
        *(
            kernel_array(array)
            for poses in (proximal, distal)
            for array in (poses.rotation, poses.body, poses.inertia_inv, poses.variance)
        )
    )
    return [
        PoseNoise(operator[t], centroids[t], float(share[t]))
        for t in range(proximal.rotation.shape[0])
    ]


@kernel
def _pose_noise_numbers(
    rotation_p: np.ndarray,
    body_p: np.ndarray,
    inertia_inv_p: np.ndarray,
    variance_p: np.ndarray,
    rotation_d: np.ndarray,
    body_d: np.ndarray,
    inertia_inv_d: np.ndarray,
    variance_d: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per trial of two segments' :class:`NoisyPoses` (proximal ``_p``, distal ``_d``: the
    rotations ``(T, N, 3, 3)``, body-fixed markers ``(T, n, 3)`` [mm], inverse inertias
    ``(T, 3, 3)`` [mm^-2] and residual variances ``(T,)`` [mm^2]), the numbers of their
    :class:`PoseNoise`: ``(M + B)^-1 B`` ``(T, 6, 6)`` (``inf`` where the share is), the
    clusters' centroids ``(T, 2, 3)`` [mm] and the share ``(T,)`` (module docstring). A compiled
    kernel: a one-trial check would otherwise pay NumPy's overhead on a dozen small arrays."""
    n_trials, n_frames = rotation_p.shape[:2]
    # sum_k R_p(k)' R_d(k), the relative rotations summed over the frames.
    relative_sum = np.zeros((n_trials, 3, 3))
    for t in range(n_trials):
        for f in range(n_frames):
            for i in range(3):
                for j in range(3):
                    value = 0.0
                    for k in range(3):
                        value += rotation_p[t, f, k, i] * rotation_d[t, f, k, j]
                    relative_sum[t, i, j] += value
    normal = normal_matrix(relative_sum, n_frames)
    operator = np.full((n_trials, 6, 6), np.inf)
    centroids = np.empty((n_trials, 2, 3))
    share = np.full(n_trials, np.inf)
    attenuation = np.empty((6, 6))
    for t in range(n_trials):
        g_p = _shrinkage(variance_p[t], inertia_inv_p[t])
        g_d = _shrinkage(variance_d[t], inertia_inv_d[t])
        relative = relative_sum[t]
        attenuation[:3, :3] = n_frames * g_p
        attenuation[:3, 3:] = relative @ g_d
        attenuation[3:, :3] = relative.T @ g_p
        attenuation[3:, 3:] = n_frames * g_d
        corrected = normal[t] + attenuation
        # M + B is not symmetric; the information along a direction v is v' (M + B) v, which
        # only its symmetric part carries.
        values, vectors = np.linalg.eigh((corrected + corrected.T) / 2.0)
        least, direction = values[0], vectors[:, 0]
        # No noise-free information left along v: the noise took it all, and no share or pull
        # is finite (nor is M + B safely solvable there).
        if least > 0.0:
            share[t] = -(direction @ attenuation @ direction) / least
            operator[t] = np.linalg.solve(corrected, attenuation)
        for segment, body in enumerate((body_p[t], body_d[t])):
            for i in range(3):
                centroids[t, segment, i] = body[:, i].sum() / body.shape[0]
    return operator, centroids, share


@kernel
def _shrinkage(variance: float, inertia_inv: np.ndarray) -> np.ndarray:
    """``G = (Sigma - tr(Sigma) I) / 2`` ``(3, 3)`` [rad^2] with ``Sigma = s^2 K^-1`` the
    covariance of a pose's rotation in the body frame (module docstring), from the residual
    ``variance`` ``s^2`` [mm^2] and ``inertia_inv`` ``K^-1`` ``(3, 3)`` [mm^-2]. A compiled
    kernel."""
    sigma = variance * inertia_inv
    return (sigma - np.trace(sigma) * np.eye(3)) / 2.0


def pull_mm(noise: PoseNoise, centre: np.ndarray) -> np.ndarray:
    """How far ``(3,)`` [mm] the noise in the poses pulled a joint centre answered at
    ``centre`` ``(3,)`` [mm] (body frames shared at frame 0): the mean of the pulls of its
    proximal and distal points, the world position at frame 0 of the two. ``inf`` where
    ``noise``'s share is."""
    if np.isinf(noise.share):
        return np.full(3, np.inf)
    offsets = (centre - noise.centroids).reshape(6)
    pulled = noise.operator @ offsets
    return (pulled[:3] + pulled[3:]) / 2.0


@kernel
def lever_factors(body: np.ndarray) -> tuple:
    """Centroid ``m`` ``(3,)`` [mm], inverse "inertia" ``K^-1`` ``(3, 3)`` [mm^-2] and count
    ``n`` of body-fixed markers ``body`` ``(n, 3)`` [mm], ``K = sum_i (|u_i|^2 I - u_i u_i')``
    with ``u_i`` the markers about ``m``. A compiled kernel."""
    n = body.shape[0]
    mean = np.zeros(3)
    for p in range(n):
        mean += body[p]
    mean /= n
    inertia = np.zeros((3, 3))
    for p in range(n):
        u = body[p] - mean
        square = u[0] * u[0] + u[1] * u[1] + u[2] * u[2]
        for i in range(3):
            inertia[i, i] += square
            for j in range(3):
                inertia[i, j] -= u[i] * u[j]
    return mean, np.linalg.inv(inertia), n


def point_covariance(point: np.ndarray, body: np.ndarray) -> np.ndarray:
    """``A(c) / s^2``: covariance, per unit marker variance, of the world position of the body
    point ``c`` ``(3,)`` [mm] predicted by an LS pose fit of the markers ``body`` ``(n, 3)``
    [mm] in the frame where the pose is the identity (``R A R'`` for any other pose ``R``)."""
    mean, inertia_inv, n = lever_factors(np.asarray(body, dtype=float))
    point = np.asarray(point, dtype=float).reshape(3)
    covariance = np.empty((3, 3))
    point_covariance_into(point, mean, inertia_inv, n, covariance)
    return covariance


@kernel
def point_covariance_into(
    point: np.ndarray, mean: np.ndarray, inertia_inv: np.ndarray, n: int, out: np.ndarray
) -> None:
    """``A(c) / s^2 = [c - m]x K^-1 [c - m]x' + I / n`` (:func:`point_covariance`) of one point
    ``c`` ``(3,)`` [mm] of a segment with lever factors (:func:`lever_factors`) ``mean`` ``(3,)``
    and ``inertia_inv`` ``(3, 3)`` and ``n`` markers, written into ``out`` ``(3, 3)``. A compiled
    kernel."""
    lever = np.zeros((3, 3))
    v = point - mean
    lever[0, 1], lever[0, 2], lever[1, 2] = -v[2], v[1], -v[0]
    lever[1, 0], lever[2, 0], lever[2, 1] = v[2], -v[1], v[0]
    for i in range(3):
        for j in range(3):
            value = 1.0 / n if i == j else 0.0
            for k in range(3):
                for m in range(3):
                    value += lever[i, k] * inertia_inv[k, m] * lever[j, m]
            out[i, j] = value


@kernel
def _turns(relative: tuple, a_p: np.ndarray, a_d: np.ndarray) -> tuple:
    """The sums over frames ``t >= 1`` that a linear centre's covariance reads (module
    docstring), of the relative rotations ``relative`` (:func:`_relative_rows`: ``(n, 9)``,
    each ``Q_t`` by rows, and their sum ``(9,)``) and the point covariances ``a_p``, ``a_d``
    ``(3, 3)`` [mm^2]: ``n``, ``S = sum_t Q_t`` ``(3, 3)``, ``sum_t Q_t' A_p Q_t`` and ``sum_t
    Q_t A_d Q_t'`` ``(3, 3)`` [mm^2], the last two read off the 9 x 9 second moments of the
    rotations, ``T[3 k + i, 3 l + j] = sum_t Q_t[k, i] Q_t[l, j]``. A compiled kernel."""
    rows, total = relative
    second = rows.T @ rows
    turned_p = np.zeros((3, 3))
    turned_d = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            for k in range(3):
                for m in range(3):
                    turned_p[i, j] += a_p[k, m] * second[3 * k + i, 3 * m + j]
                    turned_d[i, j] += a_d[k, m] * second[3 * i + k, 3 * j + m]
    return rows.shape[0], total.copy().reshape(3, 3), turned_p, turned_d


def _relative_rows(proximal: np.ndarray, distal: np.ndarray) -> tuple:
    """:func:`_relative_rows_of` the rotations ``proximal`` and ``distal`` ``(N, 3, 3)``, read
    only, and inside one checked call (:mod:`jointbench.numerics.reuse`) computed once for
    every check that reads them: the analytic centre's covariance, its anchor bias and its
    noise share each read the same pass over the frames."""
    return remembered("relative rotations", (proximal, distal), _read_only_relative_rows)


def _read_only_relative_rows(rotations: tuple[np.ndarray, np.ndarray]) -> tuple:
    """:func:`_relative_rows_of` the ``(proximal, distal)`` ``rotations``, as read-only
    arrays, which every check that reads them may share."""
    rows, total = _relative_rows_of(*rotations)
    rows.flags.writeable = False
    total.flags.writeable = False
    return rows, total


@kernel
def _relative_rows_of(proximal: np.ndarray, distal: np.ndarray) -> tuple:
    """The relative rotations ``Q_t = R_p(t)' R_d(t)`` of frames ``t >= 1`` of the rotations
    ``proximal`` and ``distal`` ``(N, 3, 3)``, each by rows, ``(N - 1, 9)``, and their sum
    ``(9,)``. A compiled kernel: NumPy's product of a stack of 3 x 3 matrices, and its sum over
    the frames, cost a checked call more than the sums that read them."""
    n_frames = proximal.shape[0]
    rows = np.empty((n_frames - 1, 9))
    total = np.zeros(9)
    for f in range(1, n_frames):
        for i in range(3):
            for j in range(3):
                value = 0.0
                for k in range(3):
                    value += proximal[f, k, i] * distal[f, k, j]
                rows[f - 1, 3 * i + j] = value
                total[3 * i + j] += value
    return rows, total


@kernel
def analytic_covariance(relative: tuple, a_p: np.ndarray, a_d: np.ndarray) -> np.ndarray:
    """The covariance ``(3, 3)`` [mm^2] of the analytic centre (paper C's eq. 9) on frames whose
    relative rotations ``Q_t = R_p' R_d`` of frames ``t >= 1`` are ``relative``
    (:func:`_relative_rows`), given the point covariances ``a_p``, ``a_d`` ``(3, 3)`` [mm^2]
    of the proximal and distal poses at the centre (module docstring, "Scatter"). A compiled
    kernel."""
    n, total, turned_p, turned_d = _turns(relative, a_p, a_d)
    identity = n * np.eye(3)
    d_p, d_d = identity - total.T, identity - total
    frames_p = n * a_p - total.T @ a_p - a_p @ total + turned_p
    frames_d = n * a_d - total @ a_d - a_d @ total.T + turned_d
    spread = d_p @ a_p @ d_p.T + frames_p + d_d @ a_d @ d_d.T + frames_d
    inverse = np.linalg.inv(d_p + d_d)
    return _symmetric(inverse @ spread @ inverse.T)


@kernel
def score_covariance(relative: tuple, a_p: np.ndarray, a_d: np.ndarray) -> np.ndarray:
    """The covariance ``(3, 3)`` [mm^2] of SCoRE's joint centre, the midpoint of its two points,
    on frames whose relative rotations of frames ``t >= 1`` are ``relative``
    (:func:`_relative_rows`; frame 0's is the identity), given the point covariances ``a_p``,
    ``a_d`` ``(3, 3)`` [mm^2] of the proximal and distal poses at SCoRE's point in each
    (module docstring, "Scatter"). A compiled kernel."""
    n, total, turned_p, turned_d = _turns(relative, a_p, a_d)
    # SCoRE's normal matrix is over all n + 1 frames, frame 0's relative rotation the identity.
    inverse = np.linalg.inv(normal_matrix((np.eye(3) + total).reshape(1, 3, 3), n + 1)[0])
    g_p = np.ascontiguousarray(0.5 * (inverse[:3, :3] + inverse[3:, :3]))
    g_d = np.ascontiguousarray(0.5 * (inverse[:3, 3:] + inverse[3:, 3:]))
    frames = (
        n * (g_p @ a_p @ g_p.T + g_d @ a_d @ g_d.T)
        - g_p @ (a_p @ total + total @ a_d) @ g_d.T
        - g_d @ (total.T @ a_p + a_d @ total.T) @ g_p.T
        + g_d @ turned_p @ g_d.T
        + g_p @ turned_d @ g_p.T
    )
    half, shift = 0.5 * np.eye(3), g_p - g_d
    frame0 = (half - shift) @ a_p @ (half - shift).T + (half + shift) @ a_d @ (half + shift).T
    return _symmetric(frames + frame0)


def anchor_bias_mm(proximal: SegmentPoses, distal: SegmentPoses, centre: np.ndarray) -> np.ndarray:
    """The mean ``(3,)`` [mm] of the analytic centre's error that the errors of the frame-0
    poses, which anchor both body frames, cause to second order, read at ``centre`` ``(3,)``
    [mm] on the fitted poses ``proximal`` and ``distal``.

    A frame-0 fit misplaces segment ``a``'s body frame by a rotation ``e_a`` (covariance
    ``Sigma_a = s_a^2 K_a^-1``) and so the joint in it by ``delta_a = [c - m_a]x e_a`` (plus the
    centroid's error). The analytic centre's error is exactly ``N^-1 (D_p delta_p + D_d
    delta_d)`` on the observed relative rotations ``Q_t`` (``D_p = n I - S'``, ``D_d = n I -
    S``, ``S = sum_t Q_t`` over frames ``t >= 1``, ``N = D_p + D_d``), and each ``Q_t`` carries
    the same errors, ``dQ_t = -[e_p]x Q_t + Q_t [e_d]x``: ``D`` and ``delta`` are correlated,
    and the error's mean is ``N^-1 (2 S' G_p (c - m_p) + 2 S G_d (c - m_d))`` with ``G_a =
    (Sigma_a - tr(Sigma_a) I) / 2``, the pose noise's shrinkage. On a small swing the
    frame-0 rotation errors turn every relative rotation by about as much as the motion does,
    and this mean is a bias of the order of the pull (:func:`pull_mm`, built on independent
    frames, which leaves it out). It is the first term of an expansion in those errors: where
    they are not small against the swing, the error's mean differs from it
    (``benchmarks/anchor_bias_frame0.py`` sets the two side by side on frame-0 errors alone)."""
    # S by the compiled pass over the frames: NumPy's einsum over them costs the check more.
    relative = _relative_rows(proximal.rotation, distal.rotation)[1].reshape(3, 3)
    n_frames = len(proximal.rotation) - 1
    terms = []
    for poses in (proximal, distal):
        mean, inertia_inv, _ = lever_factors(np.asarray(poses.body, dtype=float))
        terms.append(2.0 * _shrinkage(poses.variance, inertia_inv) @ (centre - mean))
    normal = 2.0 * n_frames * np.eye(3) - relative - relative.T
    return np.linalg.solve(normal, relative.T @ terms[0] + relative @ terms[1])


def analytic_noise_share(proximal: SegmentPoses, distal: SegmentPoses) -> float:
    """The share of the poses' noise in the information the relative rotations of the fitted
    poses ``proximal`` and ``distal`` hold on the analytic centre (paper C's eq. 9), along its
    least determined direction: where it reaches
    :data:`jointbench.estimators.centre_precision.MAX_SD_NOISE_SHARE` the first-order SD
    (:func:`analytic_covariance`) does not hold. ``inf`` where the noise's part is all of
    that information.

    The method solves ``N c = sum_t M_t' y_t`` over the frames ``t >= 1``, ``M_t = R_p(t) -
    R_d(t)``, ``N = sum_t M_t' M_t = 2 n I - S - S'`` (``S = sum_t Q_t``, ``Q_t = R_p(t)'
    R_d(t)``): ``N`` is the information the relative rotations hold on the centre. Its error
    is ``N^-1 sum_t M_t' nu_t``, ``nu_t`` the errors of ``y_t`` at the true centre (the
    frame-0 placements and frame ``t``'s poses, module docstring, "Scatter"); the SD reads
    ``M_t`` on the observed rotations as if they were exact. Each observed relative pose
    carries the errors of two pose fits, frame ``t``'s and frame 0's, which anchors the body
    frame: ``R_a(t) = R0_a(t) E_a`` with ``E[E_a] = I + 2 G_a`` (``G_a`` the shrinkage of
    the module docstring, one per fit). As ``E_a' E_a = I``, ``N = sum_t (2 I - E_p' Q0_t
    E_d - E_d' Q0_t' E_p)``, and to second order in the noise

        ``E[N] = N0 + W``,   ``W = -2 (G_p S + S' G_p + S G_d + G_d S')``,

    positive semidefinite (each ``G_a`` is negative semidefinite where ``S`` is near ``n I``):
    the noise adds information of its own, which the first-order SD counts as the motion's.
    Writing ``M_t = M0_t + dM_t``, the error holds ``N^-1 sum_t dM_t' nu_t``, a product of two
    noises the linearisation leaves out; against the first-order ``N^-1 sum_t M0_t' nu_t``
    its variance is, for errors ``nu_t`` independent of ``dM_t``, ``W`` against ``N0``
    (errors in variables, as for a centre of rotation's directions,
    :mod:`jointbench.estimators.centre_precision`). So along the least determined direction
    ``v`` of ``N - W``, ``share = v' W v / v' (N - W) v`` is the variance the SD leaves out,
    a factor ``1 + share``. Here the errors are not independent of ``dM_t``: frame 0's
    rotation errors turn every relative rotation alike, and also place the joint in both body
    frames (:func:`anchor_bias_mm`), so as the share grows the answers' errors, products of
    the same noise, grow heavy tails that no factor of the SD holds
    (``benchmarks/joint_centre_stated_sd.py``). ``S`` is read on the observed rotations;
    ``S0`` in its place changes the share by a third order."""
    relative = _relative_rows(proximal.rotation, distal.rotation)[1].reshape(3, 3)
    shrinkages = [
        _shrinkage(poses.variance, lever_factors(np.asarray(poses.body, dtype=float))[1])
        for poses in (proximal, distal)
    ]
    return float(_information_share(relative, len(proximal.rotation) - 1, *shrinkages))


@kernel
def _information_share(
    relative: np.ndarray, n_frames: int, g_p: np.ndarray, g_d: np.ndarray
) -> float:
    """:func:`analytic_noise_share` from the sum ``S`` ``(3, 3)`` of the relative rotations of
    ``n_frames`` frames and the shrinkages ``G_p``, ``G_d`` ``(3, 3)`` [rad^2] of the two
    segments' poses (:func:`_shrinkage`). A compiled kernel."""
    normal = 2.0 * n_frames * np.eye(3) - relative - relative.T
    turned = g_p @ relative + relative @ g_d
    noise = -2.0 * (turned + turned.T)
    values, vectors = np.linalg.eigh(normal - noise)
    if not values[0] > 0.0:
        return np.inf
    direction = vectors[:, 0]
    return (direction @ noise @ direction) / values[0]


def analytic_anchor_covariance(
    proximal: SegmentPoses, distal: SegmentPoses, centre: np.ndarray
) -> np.ndarray:
    """The covariance ``(3, 3)`` [mm^2] of the part of the analytic centre's error (paper C's
    eq. 9) that is second order in the errors of the frame-0 poses, which anchor both body
    frames, read at ``centre`` ``(3,)`` [mm] on the fitted poses ``proximal`` and ``distal``.

    Frame 0's fit of segment ``a`` misplaces its body frame by a rotation ``e_a`` about the
    markers' centroid ``m_a`` (covariance ``s_a^2 K_a^-1``, :func:`lever_factors`) and a shift
    ``tau_a`` of that centroid (covariance ``s_a^2 / n_a I``), all four independent: ``z =
    (e_p, tau_p, e_d, tau_d)`` ``(12,)``, Gaussian with block-diagonal covariance ``Sigma``.
    The joint then lies at ``c + delta_a`` in the body frame, ``delta_a = [c - m_a]x e_a -
    tau_a = J_a z``, and every later pose carries the rotation, ``R_a(t) = R0_a(t) exp([e_a]x)``,
    so that the sum of the relative rotations is ``S = exp(-[e_p]x) S0 exp([e_d]x)``, to first
    order ``dS = -[e_p]x S + S [e_d]x``. The method builds ``N = D_p + D_d`` (``D_p = n I -
    S'``, ``D_d = n I - S``, ``n`` the frames ``t >= 1``) and its answer's error is exactly
    ``N^-1 (D_p delta_p + D_d delta_d)`` (module docstring, "Scatter"; the later frames' own
    errors add to it independently). Differentiating it in ``S`` (``dD_p = -dS'``, ``dD_d =
    -dS``, ``dN = -(dS + dS')``) gives, beside the first order ``x1 = L z``, ``L = N^-1 (D_p
    J_p + D_d J_d)``, the second

        ``x2 = N^-1 [dS' (x1 - delta_p) + dS (x1 - delta_d)]``,

    with ``dS' u = -S' [u]x e_p + [S' u]x e_d`` and ``dS v = [S v]x e_p - S [v]x e_d``: each
    component a quadratic form ``z' H_i z``. Its mean ``tr(H_i Sigma)`` is the anchor's bias
    (:func:`anchor_bias_mm`, the same expansion's leading terms), its covariance ``2 tr(H_i
    Sigma H_j Sigma)`` (``H_i`` symmetrised; Isserlis' theorem), and it is uncorrelated with
    ``x1`` (odd moments of ``z`` vanish). Left out: the products of the anchor's rotation with
    the later frames' errors, which average over the frames, and the turn's own second order
    in ``delta_a``, ``[e_a]x^2 (c - m_a) / 2``, which enters through ``D_a`` alone, small where
    the swing is: 0.1-0.2 % of this covariance at 5-10 degrees, 1.5 % at 30, 13 % at 90 where
    it is a few thousandths of the first-order one (``tests/test_analytic_anchor_share.py``
    holds it to the method's own answer differentiated twice).

    Read on the noise-free rotations, the first-order covariance
    (:func:`analytic_covariance`) plus this one is the answers' scatter; the first order alone
    understates it five-fold at a 10 degree circumduction with 0.5 mm noise
    (``tests/test_analytic_anchor_share.py``). Read on the observed rotations, as a checked
    call must, the first-order covariance already holds it on average: the observed ``S``
    carries the draw's own ``e``, which turns every relative rotation (on a small swing
    ``D_d`` gains ``n [e_d - e_p]x``), so this covariance is not added to it (that would count
    it twice). What it measures is how far the answer's error is from linear in the noise:
    :func:`analytic_anchor_share`."""
    relative = _relative_rows(proximal.rotation, distal.rotation)[1].reshape(3, 3)
    factors = [lever_factors(np.asarray(poses.body, dtype=float)) for poses in (proximal, distal)]
    return _anchor_covariance(
        relative,
        len(proximal.rotation) - 1,
        np.asarray(centre, dtype=float),
        np.array([factor[0] for factor in factors]),
        np.array([factor[1] for factor in factors]),
        np.array([float(factor[2]) for factor in factors]),
        np.array([poses.variance for poses in (proximal, distal)]),
    )


@kernel
def _cross_matrix(v: np.ndarray) -> np.ndarray:
    """``[v]x`` ``(3, 3)`` of ``v`` ``(3,)`` (:func:`jointbench.numerics.small.skew9`). A
    compiled kernel."""
    entries = skew9(v[0], v[1], v[2])
    matrix = np.empty((3, 3))
    for k in range(9):
        matrix[k // 3, k % 3] = entries[k]
    return matrix


@kernel
def _anchor_covariance(
    relative: np.ndarray,
    n_frames: int,
    centre: np.ndarray,
    means: np.ndarray,
    inertia_invs: np.ndarray,
    counts: np.ndarray,
    variances: np.ndarray,
) -> np.ndarray:
    """:func:`analytic_anchor_covariance` ``(3, 3)`` [mm^2] from the sum ``S`` ``(3, 3)`` of
    the relative rotations of ``n_frames`` frames ``t >= 1``, the ``centre`` ``(3,)`` [mm] and
    per segment (proximal, distal) its markers' centroid ``means`` ``(2, 3)`` [mm], inverse
    inertia ``inertia_invs`` ``(2, 3, 3)`` [mm^-2], marker ``counts`` ``(2,)`` and residual
    ``variances`` ``(2,)`` [mm^2]. A compiled kernel."""
    identity = np.eye(3)
    d_p = n_frames * identity - relative.T
    d_d = n_frames * identity - relative
    inverse = np.linalg.inv(d_p + d_d)
    sigma = np.zeros((12, 12))
    gains = np.zeros((2, 3, 12))
    for a in range(2):
        start = 6 * a
        sigma[start : start + 3, start : start + 3] = variances[a] * inertia_invs[a]
        gains[a, :, start : start + 3] = _cross_matrix(centre - means[a])
        for i in range(3):
            sigma[start + 3 + i, start + 3 + i] = variances[a] / counts[a]
            gains[a, i, start + 3 + i] = -1.0
    first = inverse @ (d_p @ gains[0] + d_d @ gains[1])
    # Column k of each: u = x1 - delta_p, v = x1 - delta_d and their turned S v, S' u, per
    # unit of z_k; the blocks of H_i in e_p's and e_d's columns are N^-1 times
    # [S v]x - S' [u]x and [S' u]x - S [v]x, formed for every k and turned by N^-1 at once
    # (one product, where one per k costs the check more than the arithmetic).
    off_p = first - gains[0]
    off_d = first - gains[1]
    turned_d = relative @ off_d
    turned_p = relative.T @ off_p
    blocks = np.empty((3, 72))
    for k in range(12):
        cross_sv = skew9(turned_d[0, k], turned_d[1, k], turned_d[2, k])
        cross_su = skew9(turned_p[0, k], turned_p[1, k], turned_p[2, k])
        cross_u = skew9(off_p[0, k], off_p[1, k], off_p[2, k])
        cross_v = skew9(off_d[0, k], off_d[1, k], off_d[2, k])
        for a in range(3):
            for b in range(3):
                proximal = cross_sv[3 * a + b]
                distal = cross_su[3 * a + b]
                for c in range(3):
                    proximal -= relative[c, a] * cross_u[3 * c + b]
                    distal -= relative[a, c] * cross_v[3 * c + b]
                blocks[a, 6 * k + b] = proximal
                blocks[a, 6 * k + 3 + b] = distal
    turned = inverse @ blocks
    quadratic = np.zeros((3, 12, 12))
    for i in range(3):
        for k in range(12):
            for b in range(3):
                quadratic[i, k, b] = turned[i, 6 * k + b]
                quadratic[i, k, 6 + b] = turned[i, 6 * k + 3 + b]
    weighted = np.empty((3, 12, 12))
    for i in range(3):
        weighted[i] = 0.5 * (quadratic[i] + quadratic[i].T) @ sigma
    covariance = np.empty((3, 3))
    for i in range(3):
        for j in range(3):
            covariance[i, j] = 2.0 * np.sum(weighted[i] * weighted[j].T)
    return _symmetric(covariance)


@kernel
def analytic_anchor_share(anchor: np.ndarray, covariance: np.ndarray) -> float:
    """The share of the analytic centre's variance that is second order in its frame-0 poses'
    errors: the largest ratio, over directions, of ``anchor`` ``(3, 3)`` [mm^2]
    (:func:`analytic_anchor_covariance`) to the first-order ``covariance`` ``(3, 3)`` [mm^2]
    (:func:`analytic_covariance`), both on the same poses. Where it reaches
    :data:`jointbench.estimators.centre_precision.MAX_ANCHOR_SHARE` the answer's error is
    not linear in the noise: the first-order SD read on the observed rotations holds its
    variance only through the draw's own anchor error, and the errors, products of that
    noise, have heavy tails. Directions in which ``covariance``'s variance is negligible
    against its largest (:data:`jointbench.numerics.rank.RCOND`) are left out: there both
    are rounding (noise-free poses on a nearly hinged motion). ``0`` where neither has a
    variance, ``inf`` where only the anchor's has. A compiled kernel."""
    values, vectors = np.linalg.eigh(covariance)
    largest = values[-1]
    if not largest > 0.0:
        return 0.0 if np.abs(anchor).max() == 0.0 else np.inf
    kept = 0
    scaled = np.zeros((3, 3))
    for j in range(3):
        if values[j] > RCOND * largest:
            scaled[:, kept] = vectors[:, j] / np.sqrt(values[j])
            kept += 1
    basis = np.ascontiguousarray(scaled[:, :kept])
    return np.linalg.eigvalsh(basis.T @ anchor @ basis)[-1]


def centre_covariance(
    formula: Callable[[tuple, np.ndarray, np.ndarray], np.ndarray],
    proximal: SegmentPoses,
    distal: SegmentPoses,
    points: tuple,
) -> np.ndarray:
    """The covariance ``(3, 3)`` [mm^2] that ``formula`` (:func:`analytic_covariance` or
    :func:`score_covariance`) gives a centre answered on the poses ``proximal`` and ``distal``,
    whose point in each segment is ``points`` (two ``(3,)`` [mm], body frames): each segment's
    point covariance scaled by its own rigid-body residual variance, as the pull takes it."""
    relative = _relative_rows(proximal.rotation, distal.rotation)
    a_p, a_d = (
        poses.variance * point_covariance(point, poses.body)
        for poses, point in zip((proximal, distal), points, strict=True)
    )
    return formula(relative, a_p, a_d)


@kernel
def _symmetric(matrix: np.ndarray) -> np.ndarray:
    """The symmetric part of ``matrix`` ``(3, 3)``: a covariance rounded in its products. A
    compiled kernel."""
    return 0.5 * (matrix + matrix.T)
