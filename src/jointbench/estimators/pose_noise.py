"""How far the noise in two segments' poses pulls a joint centre: errors in variables.

A joint centre from two segments (SCoRE, the analytic centre, the Gauss–Markov fits) is fixed
by the relative rotations: a point ``a_p`` in the proximal segment and ``a_d`` in the distal
one, offsets from each cluster's centroid in its body frame, with
``R_p a_p + t_p = R_d a_d + t_d`` in every frame. Stacked over the ``N`` frames this is the
least-squares problem ``A x = b`` of :mod:`jointbench.estimators.twosegment`, whose normal
matrix ``M = [[N I, -S], [-S', N I]]`` (``S = sum_k Q_k``, ``Q_k = R_p' R_d`` the relative
rotation) has, on nearly hinged motion, one eigenvalue that only the rotation off the hinge
keeps from zero: along the hinge axis in both frames.

The rotations are noisy: to first order ``R_k = R0_k exp([e_k]x)`` with ``e_k`` of covariance
``Sigma = s^2 K^-1`` in the body frame (``K = sum_m (|u_m|^2 I - u_m u_m')`` the inertia of
the centred body-fixed markers ``u_m``, Pennec & Thirion's pose covariance, ``s^2`` the
rigid-body residual per coordinate). Each segment has its own ``s^2``, from its own
residuals: the noisier segment's poses are the noisier ones. The noise is taken to be the
same in every direction of the world, which the residuals of three or four markers cannot
tell apart from the geometry of their cluster (a camera's larger noise along its depth is a
limit the README measures). Frame 0's poses are the identity by construction (the body frame
is the world's there), which moves frame 0's error into every other frame's pose: a rotation
of the body frames shared by all frames, which moves no centre. Relative to it frame 0 is as
noisy as the others, and every frame counts.

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

__all__ = ["PoseNoise", "Segment", "bias_mm", "pose_noise"]


@dataclass(frozen=True, eq=False)
class PoseNoise:
    """What the noise in one trial's two segment poses does to a least-squares joint centre:
    ``operator`` ``(6, 6)``, ``(M + B)^-1 B``, maps an answer's offsets from the proximal and
    distal clusters' centroids ``(a_p, a_d)`` [mm] (body frames, which are the world's at
    frame 0) to how far the noise pulled it, ``(delta_p, delta_d)`` [mm] (``inf`` where
    ``share`` is); ``centroids`` ``(2, 3)`` [mm] those centroids; ``share`` the ratio of the
    noise's information to the noise-free information along the least determined direction
    (module docstring). Equal to another with the same numbers, so that verdicts carrying one
    compare as values."""

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


class Segment(NamedTuple):
    """One segment's poses in ``T`` trials, as the pull reads them: ``rotation``
    ``(T, N, 3, 3)``, the body-fixed markers ``body`` ``(T, n, 3)`` [mm], the inverse of their
    centred inertia ``inertia_inv`` ``(T, 3, 3)`` [mm^-2] and the rigid-body residual per
    coordinate ``variance`` ``(T,)`` [mm^2]."""

    rotation: np.ndarray
    body: np.ndarray
    inertia_inv: np.ndarray
    variance: np.ndarray


def _shrinkage(segment: Segment) -> np.ndarray:
    """``G = (Sigma - tr(Sigma) I) / 2`` ``(T, 3, 3)`` [rad^2] with ``Sigma = s^2 K^-1`` the
    covariance of a pose's rotation in the body frame (module docstring)."""
    sigma = segment.variance[:, None, None] * segment.inertia_inv
    trace = np.trace(sigma, axis1=1, axis2=2)
    return (sigma - trace[:, None, None] * np.eye(3)) / 2.0


def pose_noise(proximal: Segment, distal: Segment) -> list[PoseNoise]:
    """Per trial, the :class:`PoseNoise` of the ``proximal`` and ``distal`` segments' poses
    (module docstring: ``M``, ``B`` and the share)."""
    n_frames = proximal.rotation.shape[1]
    relative = np.einsum("tkji,tkjl->til", proximal.rotation, distal.rotation)
    relative_t = relative.transpose(0, 2, 1)
    g_p, g_d = _shrinkage(proximal), _shrinkage(distal)
    pull = np.block([[n_frames * g_p, relative @ g_d], [relative_t @ g_p, n_frames * g_d]])
    frames_eye = n_frames * np.broadcast_to(np.eye(3), relative.shape)
    normal = np.block([[frames_eye, -relative], [-relative_t, frames_eye]])
    corrected = normal + pull
    values, vectors = np.linalg.eigh((corrected + corrected.transpose(0, 2, 1)) / 2.0)
    least, direction = values[:, 0], vectors[:, :, 0]
    noise = -np.einsum("ti,tij,tj->t", direction, pull, direction)
    determined = least > 0.0
    share = np.full(least.shape, np.inf)
    share[determined] = noise[determined] / least[determined]
    operator = np.full_like(pull, np.inf)
    if determined.any():
        operator[determined] = np.linalg.solve(corrected[determined], pull[determined])
    centroids = np.stack([proximal.body.mean(axis=1), distal.body.mean(axis=1)], axis=1)
    return [
        PoseNoise(operator[t], centroids[t], float(share[t]))
        for t in range(proximal.rotation.shape[0])
    ]


def bias_mm(noise: PoseNoise, centre: np.ndarray) -> np.ndarray:
    """How far ``(3,)`` [mm] the noise in the poses pulled a joint centre answered at
    ``centre`` ``(3,)`` [mm] (body frames shared at frame 0): the mean of the proximal and
    distal parts, the world position at frame 0 of the two points. ``inf`` where ``noise``'s
    share is."""
    if np.isinf(noise.share):
        return np.full(3, np.inf)
    offsets = (centre - noise.centroids).reshape(6)
    delta = noise.operator @ offsets
    return (delta[:3] + delta[3:]) / 2.0
