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
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from jointbench.numerics.joint_system import normal_matrix

__all__ = ["NoisyPoses", "PoseNoise", "pose_noise", "pull_mm"]


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


def _shrinkage(poses: NoisyPoses) -> np.ndarray:
    """``G = (Sigma - tr(Sigma) I) / 2`` ``(T, 3, 3)`` [rad^2] with ``Sigma = s^2 K^-1`` the
    covariance of a pose's rotation in the body frame (module docstring)."""
    sigma = poses.variance[:, None, None] * poses.inertia_inv
    trace = np.trace(sigma, axis1=1, axis2=2)
    return (sigma - trace[:, None, None] * np.eye(3)) / 2.0


def pose_noise(proximal: NoisyPoses, distal: NoisyPoses) -> list[PoseNoise]:
    """Per trial, the :class:`PoseNoise` of the ``proximal`` and ``distal`` segments' poses
    (module docstring: ``M``, ``B`` and the share)."""
    n_frames = proximal.rotation.shape[1]
    relative_sum = np.einsum("tkji,tkjl->til", proximal.rotation, distal.rotation)
    g_p, g_d = _shrinkage(proximal), _shrinkage(distal)
    attenuation = np.block(
        [
            [n_frames * g_p, relative_sum @ g_d],
            [np.swapaxes(relative_sum, 1, 2) @ g_p, n_frames * g_d],
        ]
    )
    corrected = normal_matrix(relative_sum, n_frames) + attenuation
    # M + B is not symmetric; the information along a direction v is v' (M + B) v, which only
    # its symmetric part carries.
    values, vectors = np.linalg.eigh((corrected + np.swapaxes(corrected, 1, 2)) / 2.0)
    least, direction = values[:, 0], vectors[:, :, 0]
    noise_information = -np.einsum("ti,tij,tj->t", direction, attenuation, direction)
    # No noise-free information left along v: the noise took it all, and no share or pull is
    # finite (nor is M + B safely solvable there).
    determined = least > 0.0
    share = np.full(least.shape, np.inf)
    share[determined] = noise_information[determined] / least[determined]
    operator = np.full_like(attenuation, np.inf)
    if determined.any():
        operator[determined] = np.linalg.solve(corrected[determined], attenuation[determined])
    centroids = np.stack([proximal.body.mean(axis=1), distal.body.mean(axis=1)], axis=1)
    return [
        PoseNoise(operator[t], centroids[t], float(share[t]))
        for t in range(proximal.rotation.shape[0])
    ]


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
