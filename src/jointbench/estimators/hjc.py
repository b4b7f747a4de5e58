"""Hip joint centre with uncertainty: paper C (Stoddart et al. 1999), and an extension.

Two segments (0 = proximal, 1 = distal) carry >= 3 markers each, measured in the world frame.
Notation of paper C: the pose ``f_a(t) = {R_a(t), d_a(t)}`` maps body-fixed coordinates to the
world, ``y = R_a x + d_a`` (eq. 1); both body frames coincide with the world at ``t = 0``, so the
ball joint has one body-fixed position ``c`` in both (eq. 2): ``0 = f0(t) c - f1(t) c``.

Steps (one function per registered method below):

1. Poses (§5): :func:`jointbench.numerics.poses.rigid_poses` for each segment -- SVD fits
   alternating with the re-estimated body-fixed coordinates of eq. 5, body frame = world at
   frame 0.
2. Analytic centre (§6, eq. 9), minimising ``sum_t |f0(t) c - f1(t) c|^2`` (eq. 6): with
   ``M_t = R0(t) - R1(t)`` and ``y_t = d1(t) - d0(t)``,
   ``c = [sum_t M_t' M_t]^-1 sum_t M_t' y_t`` (eq. 9 multiplied out: ``M' M = 2I - R0'R1 - R1'R0``).
3. Pose covariance (Pennec & Thirion 1997). Marker noise is isotropic with per-coordinate
   variance ``s^2``. The pose is perturbed as ``R -> exp([w]x) R``, ``d -> d + tau`` (a
   rotation vector ``w`` of the error, in the world frame), so the marker Jacobian is
   ``J_i = [-[R x_i]x, I3]`` and ``W_f = s^2 (sum_i J_i' J_i)^-1`` (6x6).
4. Constraint ``h_t(x_t, c) = R0 c + d0 - R1 c - d1`` (eq. 11) with ``x_t`` the two poses (12
   numbers). Jacobians (eqs. 13–14): ``M_t = dh/dc = R0 - R1`` and
   ``dh/dx_t = [-[R0 c]x, I3, [R1 c]x, -I3]`` (paper: ``[dR0/dr0 c, I3, -dR1/dr1 c, -I3]``; in
   this parameterisation ``d(R c)/dw = -[R c]x``). Pseudo-measurement (eq. 18):
   ``y_t = -h(x_t, c_hat) + M_t c_hat = d1(t) - d0(t)`` -- eq. 15; because ``h`` is linear in
   ``c`` it does not depend on the linearisation point, only ``W_y,t`` does.
   ``W_y,t = dh/dx W_x,t dh/dx'`` (eq. 20, ``W_x,t`` block-diagonal, eq. 12). Multiplied out,
   each segment contributes the covariance of the world position of a body point ``c``
   predicted from that segment's pose fit::

       W_y,t = sum_a R_a(t) A_a(c) R_a(t)',
       A_a(c) = s^2 ( [c - m_a]x K_a^-1 [c - m_a]x' + I3 / n_a ),

   with ``m_a`` the centroid of the segment's ``n_a`` body-fixed marker coordinates and
   ``K_a = sum_i (|u_i|^2 I3 - u_i u_i')``, ``u_i = x_i - m_a`` (the cluster's "inertia"):
   the translation of the centroid and the rotation decouple, so ``W_f`` never needs forming.
5. Gauss–Markov (eqs. 22–23): ``c = [sum M' W^-1 M]^-1 sum M' W^-1 y``,
   ``W_c = [sum M' W^-1 M]^-1``; ``W_y`` depends on ``c`` through the lever arm ``c - m_a``,
   so the solution is iterated from the analytic centre until ``c`` moves less than
   ``tol_mm`` (default 1e-6 mm, far below any predicted uncertainty); after
   ``max_iterations`` the result has ``converged=False``. Frame 0 is left out: its poses are
   the identity by construction and ``M_0 = 0``.

Noise convention. ``noise_mm`` is ``sqrt(tr W_y)`` of the marker covariance ``W_y``: the RMS
length of a 3-D marker error, paper C's "1.7 mm" and the ``sd_mm`` of
:func:`jointbench.simulate.noise.isotropic_noise`. Paper C writes the isotropic variance as
"sigma^2 = Tr(W_y)"; used as a per-coordinate variance that would overstate ``W_c`` three
times. Here the per-coordinate variance is ``s^2 = noise_mm^2 / 3``, which is what
``W_f = s^2 (sum J'J)^-1`` needs. Without ``noise_mm``, ``s^2`` is the pooled residual variance
of the two segments' rigid-body fits: ``s^2 = (RSS_0 + RSS_1) / (dof_0 + dof_1)`` with
``dof = 3 n N - 6 N - 3 n + 6 = 3 (n - 2)(N - 1)`` per segment (``3 n N`` coordinates, ``6 N``
pose parameters, ``3 n`` body coordinates, 6 gauge freedoms removed by pinning the body frame to
frame 0), unbiased to first order for any isotropic noise.

Frame 0 (an extension, method ``gauss-markov-frame0``). Paper C treats ``f_a(0) = I`` as exact.
With noisy markers it is not: each segment's body frame is placed by *its own* frame-0 fit,
whose rotation error (~0.01 rad for 1.7 mm noise on a 150 mm cluster) moves a point 500 mm away
by several mm, independently for the two segments. So (i) the two body frames do not coincide
at frame 0, the single ``c`` of eq. 2 does not exist, and the paper's estimate is biased by a
few mm; (ii) every relative pose shares that frame-0 error, so the errors of ``y_t`` are
correlated across ``t`` and ``W_c`` is far too small for the centre's position in the true
world at frame 0 (its true error does not fall below the frame-0 error however many frames are
used). ``gauss-markov-frame0`` applies the same Gauss–Markov theorem with these errors in the
measurement model: unknowns ``c`` (world at frame 0), ``c0``, ``c1`` (the centre in each
segment's frame as placed at frame 0); data ``R0 c0 - R1 c1 = d1 - d0`` for ``t >= 1`` with
covariance ``W_y,t`` as above; and the frame-0 placement errors as pseudo-measurements
``c0 - c = 0`` and ``c1 - c = 0`` with covariances ``A_0(c0)``, ``A_1(c1)`` (the frame-0 fit's
error at the joint). This is the generalised least-squares solution with the full,
correlated ``W_y``; its ``W_c`` covers the true centre. Paper C's own answer has the same
frame-0 errors in its data: with ``H = sum_t M_t' W_t^-1 M_t`` its information and ``F_a =
sum_t M_t' W_t^-1 R_a(t)``, its error is ``H^-1 [sum_t M_t' W_t^-1 (R_0 e_0t - R_1 e_1t) +
F_0 delta_0 - F_1 delta_1]``, so its covariance is ``s^2 (H^-1 + H^-1 (F_0 A_0 F_0' + F_1 A_1
F_1') H^-1)``, ``W_c`` plus what the frame-0 errors add: ``gauss-markov`` states it in
``diagnostics["center_covariance_mm2"]`` and keeps the paper's ``W_c`` as its covariance.
The frame-0 extension's diagnostics carry ``c0`` and its covariance, the centre relative to
the proximal markers (what a pelvis frame built from them needs), which is not limited by the
frame-0 error.

Model test. Both fits' chi^2 ``sum_t r_t' W_y,t^-1 r_t / s^2`` (plus, for the frame-0
extension, its two pseudo-measurements) has ``dof = 3 (N - 1) - 3`` degrees of freedom: when
the model holds (one centre fixed in both segments, marker noise of variance ``s^2`` per
coordinate, and for ``gauss-markov`` exact frame-0 poses) it is chi^2(dof) distributed with
``s^2`` given, and ``chi2 / dof`` is F(dof, dof_r) with ``s^2`` from the rigid-body residuals
(``dof_r`` theirs; the residuals are orthogonal to the pose errors the chi^2 is built from).
Far from the truth an answer comes with a chi^2 far above its dof: a joint that is no ball
joint (the centre moves in a segment), skin markers that slide, frame-0 poses with errors
paper C ignores. Far below, it says that less noise reaches the centre than the model
assumes: markers that move on their segment (skin) leave more rigid-body residual than pose
error, or a given ``noise_mm`` is larger than the data's. So the checked call
(:func:`jointbench.estimators.registry.get`, on the poses it fitted) tests the chi^2
two-sided at :data:`jointbench.estimators.support.ROTATION_ALPHA` and, when it is rejected,
warns that the model does not fit the data: the centre may be off and ``W_c`` does not
describe its error (``converged`` and the answer stay as fitted). For ``gauss-markov-frame0``,
whose SD is read from that ``W_c``, the warning adds that the precision is not determined.
``gauss-markov``'s SD is read from ``W_c`` with the frame-0 poses' errors added, the
frame-0 extension's model, not its own: a rejection of exact frame-0 poses leaves that SD
(where the model holds but for them its error is about that SD), and the checked call holds it
to the frame-0 extension's test on the same poses with the same noise (given or estimated), as
SCoRE's and the analytic centre's (:func:`_fixed_centre_test`); that test gives its verdict,
its own only where that one is not made (:func:`_paper_c_check`). Its own chi^2 is no test of
the model its SD is of: with frame-0 errors ``delta = (delta_0, delta_1)`` of covariance ``A =
diag(A_0, A_1)`` and ``G_t = [R_0(t), -R_1(t)]``, every frame's residual carries ``G_t delta``,
so its expectation is ``dof + tr(A (sum_t G_t' W_t^-1 G_t - F' H^-1 F)) / s^2`` (``F = [F_0,
-F_1]``), where ``R_a A_a R_a'`` sums to ``W_t``: near ``2 dof`` on a long trial, whatever
``N``, from six terms. On a ball joint with frame 0 as noisy as the rest (200 frames, 0.5 mm,
swing 20 deg, 60 trials) its ``chi2 / dof`` averaged 1.9 (median 1.5) and it rejected 82 % of
the trials at 1 %; with exact frame-0 markers 1.02 and 2 %, and the frame-0 extension's 1.02
and 2 % on both.

The noise need not be Gaussian: paper A's isotropic errors (a normal magnitude along a
uniform direction, :func:`jointbench.simulate.noise.isotropic_noise`) have a per-coordinate
excess kurtosis ``kappa = 2.4``, and a quadratic form ``e' X e`` of such errors varies more
than chi^2 says. For spherically symmetric noise the fourth cumulants of one marker's error
are ``(kappa / 3) s^4 (d_ij d_kl + d_ik d_jl + d_il d_jk)``, so ``Var(e' X e) = 2 s^4 tr(X^2) +
(kappa / 3) s^4 sum_i [tr(X_ii)^2 + 2 tr(X_ii^2)]`` over the markers' 3x3 blocks ``X_ii``. For the
chi^2 the blocks are ``B_ai' R_a' W_t^-1 R_a B_ai`` per frame, segment and marker, with
``B_ai`` the gain from marker ``i``'s error to the error of the centre its segment's pose
places (:func:`_marker_gains`); their sum over frames, against the Gaussian ``2 * 3 (N - 1)``,
is the inflation ``g`` of the chi^2's variance. Satterthwaite's scaling matches mean and
variance: ``chi2 ~ g chi^2(dof / g)``; in the F form the numerator's dof are ``dof / g`` and
the denominator's ``dof_r / g_r`` likewise. ``kappa`` is estimated from the same rigid-fit
residuals ``r = (I - H) e``, by the method of moments: ``E sum |r_i|^4 = s^4 (G + kappa F)`` with
``G`` and ``F`` from the blocks of ``I - H`` (:func:`_residual_moments`), and clipped at 0 (light
tails make the test conservative) and at :data:`MAX_NOISE_KURTOSIS` (heavier tails are glitches,
which the test must see rather than absorb). Diagnostics: ``chi2_p``, ``noise_kurtosis`` (the
estimate), ``chi2_inflation`` (``g``); NaN when the residuals are at rounding level (noise-free
data: nothing to test against). On trials of the two-segment test rig in which each model holds
(``tests/test_gauss_markov_fit.py``, 30 frames, 1500 trials per case) 10 of 12000 were rejected
(0-2 per 1500, Gaussian or isotropic errors, noise given or estimated); without the inflation the
chi^2's variance under the isotropic errors was 1.55 times its assumed ``2 dof``. On paper C's rig
and the skin-marker study none of 2640 trials in which the model holds was warned, and 88 % of the
answers more than 4 Mahalanobis SD or 10 mm off were (21 % before, by the support verdict). What
the test cannot see: an error that moves the centre the same way in both segments, such as the part
of the frame-0 pose errors common to the two segments, or skin motion that moves a cluster rigidly
with the joint angles (it passes for another centre).

Pooled noise. The model pools one noise for both segments in every frame, frame 0 included,
and two tests of the rigid-body residuals ask whether the data have it before the model test is
read (:func:`_fixed_centre_test`): the segments' residual variances against each other (an F
test, :func:`_unequal_noise`; where they differ, the model test is not made) and frame 0's
residuals against those a fit of the other frames leaves (:func:`_frame0_noise`; where they
lie above, a warning), for frame-0 markers off by more than the noise move the body frames
frame 0 places, which neither the model test (an error common to both segments moves the
centre alike in both) nor the variance ratio (one frame among hundreds) sees. Both allow for
the noise's kurtosis as the model test does (Satterthwaite, each residual sum of squares' dof
divided by its inflation ``1 + kappa G / (6 dof)`` per frame), ``kappa`` read from the frames
after frame 0, each segment's fourth moments over its own variance (:func:`_rest_kurtosis`), so
that neither error reads as heavy tails. Blind to the kurtosis, the variance ratio said equal
noise of paper A's law differs many times more often than its level; allowing for it, at about
its level (``tests/test_gauss_markov_fit.py``). Frame 0's test, one frame's residual with few
dof, keeps a tail heavier than its level under that law, most on a few frames, from which the
kurtosis mostly reads 0 (the README gives the rates measured).

Degenerate motion. Before anything is solved, the analytic normal matrix ``sum M'M`` must have
rank 3: an eigenvalue below ``1e-12`` of the largest (relative rotation off the main axis below
~1e-6 rad) means rotation about a single axis, and a largest eigenvalue below ``1e-16 N``
(relative rotation below ~1e-8 rad) means none; both raise ``ValueError``. Anything above is
solved: a large predicted covariance from a valid but poorly conditioned fit (paper C: 1872 mm
at Nt = 4) is an honest answer, not an error.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from jointbench.declared import Count, NonNegative
from jointbench.estimators.batching import isolated, one_trial
from jointbench.estimators.pose_noise import (
    analytic_anchor_covariance,
    analytic_anchor_share,
    analytic_covariance,
    analytic_noise_share,
    anchor_bias_mm,
    centre_covariance,
    lever_factors,
    point_covariance,
    point_covariance_into,
)
from jointbench.estimators.registry import register, register_many
from jointbench.estimators.results import (
    PRECISION_NOT_DETERMINED,
    JointCenterResult,
    with_warnings,
)
from jointbench.estimators.segment_poses import (
    POSE_MIN_FRAMES,
    SegmentPoses,
    precision_on_poses,
)
from jointbench.estimators.support import ROTATION_ALPHA, ROUNDING
from jointbench.estimators.twosegment import (
    PoseStack,
    batched,
    batched_all,
    each_trial,
    fit_score,
    score_scattered,
    trial_outcomes,
)
from jointbench.numerics.compiled import kernel, kernel_array
from jointbench.numerics.poses import rigid_fit
from jointbench.numerics.rank import RCOND, negligible
from jointbench.numerics.small import (
    add_block3,
    add_upper3,
    add_vector3,
    identity_less9,
    inverse3_entries,
    inverse3_into,
    rotated3_into,
    rotated9_upper,
    rows9,
    skew9,
    solve_into,
    symmetric9,
    symmetric_applied9,
    symmetric_eigen,
    symmetric_times9,
    transposed9,
    transposed_applied9,
    transposed_times9,
)
from jointbench.numerics.special import scipy_special

__all__ = [
    "MAX_NOISE_KURTOSIS",
    "align_to_markers",
    "fit_analytic",
    "fit_gauss_markov",
    "fit_gauss_markov_frame0",
    "point_covariance",
]

#: The model test takes the noise's excess kurtosis, read off the rigid-fit residuals, as at
#: most this: a Student t's on 5 degrees of freedom, heavier-tailed than any marker noise
#: model the studies use (paper A's isotropic errors: 2.4). Beyond it the tails are glitches
#: (a marker lost for a frame, a swapped label), which the test must see, not absorb: a
#: thousandth of the samples off by 30 mm would otherwise inflate the chi^2's variance
#: twenty-fold and hide a centre that slides by 10 mm.
MAX_NOISE_KURTOSIS = 6.0

# "No relative rotation": largest eigenvalue of sum M'M below this times the number of frames.
_NO_ROTATION = 1e-16
# The Gauss–Markov fits' defaults: at most this many re-linearisations, stopping when the
# centre moves no more than this [mm].
_FIT_ITERATIONS = 100
_FIT_TOL_MM = 1e-6


def _as_noise(noise_mm: float | None) -> float | None:
    if noise_mm is None:
        return None
    value = float(noise_mm)
    if not np.isfinite(value) or value < 0:
        raise ValueError(f"noise_mm must be a finite number >= 0, got {noise_mm!r}")
    return value


def _per_coordinate_variance(
    noise_mm: float | None, prox: SegmentPoses, dist: SegmentPoses
) -> tuple[float, float, str]:
    """``(s^2 [mm^2], noise_mm = sqrt(3 s^2), source)`` -- see the module docstring."""
    if noise_mm is not None:
        # A product, not a power: a noise whose square overflows gives an infinite variance
        # (which the model test then reads), not OverflowError.
        return noise_mm * noise_mm / 3.0, noise_mm, "given"
    variance = _pooled_variance((prox, dist))
    return variance, float(np.sqrt(3.0 * variance)), "rigid-body residuals"


def _largest_coordinate(segments: tuple[SegmentPoses, ...]) -> float:
    """The largest |coordinate| [mm] of the segments' markers, the scale of their rounding."""
    # From the extremes, without an array of absolute values.
    return max(max(float(p.markers.max()), -float(p.markers.min())) for p in segments)


def _rounding_variance(segments: tuple[SegmentPoses, ...]) -> float:
    """The per-coordinate variance [mm^2] at or below which the segments' rigid-body residuals
    are rounding, not noise: ``(ROUNDING * their largest |coordinate|)^2``."""
    return (ROUNDING * _largest_coordinate(segments)) ** 2


def _pooled_variance(segments: tuple[SegmentPoses, ...]) -> float:
    """``s^2`` [mm^2]: the segments' rigid-body residual sum of squares over its dof."""
    return sum(p.residual_ss for p in segments) / sum(p.dof for p in segments)


def _relative_system(prox, dist) -> tuple[np.ndarray, np.ndarray]:
    """``M_t = R0 - R1`` ``(..., N-1, 3, 3)`` and ``y_t = d1 - d0`` ``(..., N-1, 3)`` for
    ``t >= 1``, of one trial's poses (:class:`SegmentPoses`) or a stack's (:class:`PoseStack`)."""
    return prox.rotation[..., 1:, :, :] - dist.rotation[..., 1:, :, :], _translations(prox, dist)


def _translations(prox, dist) -> np.ndarray:
    """``y_t = d1 - d0`` ``(..., N-1, 3)`` [mm] of :func:`_relative_system`."""
    return dist.translation[..., 1:, :] - prox.translation[..., 1:, :]


def _analytic(prox, dist, what: str):
    """Eq. 9 for the trials of the poses ``prox``, ``dist`` (a :class:`PoseStack` each, or
    one trial's :class:`SegmentPoses` as a batch of one): centres ``c`` ``(T, 3)`` [mm],
    ``rcond`` ``(T,)`` and per trial ``None`` or the ``ValueError`` of degenerate motion (the
    centre of such a trial is not used)."""
    arrays = [
        array if array.ndim == dims else array[None]
        for array, dims in (
            (prox.rotation, 4),
            (dist.rotation, 4),
            (prox.translation, 3),
            (dist.translation, 3),
        )
    ]
    # C-contiguous as both kinds of poses hold them (read-only for one trial's): not copied.
    centres, values, rcond = _analytic_solution(*arrays)
    n_frames = arrays[0].shape[1]
    errors = [_motion_error(trial_values, n_frames, what) for trial_values in values]
    return centres, rcond, errors


@kernel
def _analytic_solution(
    r0: np.ndarray, r1: np.ndarray, d0: np.ndarray, d1: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Eq. 9 solved per trial of the rotations ``r0``, ``r1`` ``(T, N, 3, 3)`` and translations
    ``d0``, ``d1`` ``(T, N, 3)`` [mm] (:func:`_analytic_sums`): the centres ``(T, 3)`` [mm],
    the normal matrices' ascending eigenvalues ``(T, 3)`` and ``rcond`` ``(T,)``, their
    smallest over their largest. The centre is
    :func:`~jointbench.estimators.twosegment.eigen_solution`'s, from LAPACK's eigenpairs as
    NumPy's ``eigh`` gives them: an eigenvalue negligible against the largest
    (:func:`jointbench.numerics.rank.negligible`) is left out, so that the unused centre of a
    trial of degenerate motion (:func:`_motion_error`) stays finite; without relative rotation
    every eigenvalue can be zero and ``rcond`` is NaN. A compiled kernel: NumPy's ``eigh``,
    solve and ``errstate`` on one 3 x 3 matrix cost a checked call several times the sums."""
    normal, rhs = _analytic_sums(r0, r1, d0, d1)
    n_trials = normal.shape[0]
    centres = np.zeros((n_trials, 3))
    values = np.empty((n_trials, 3))
    rcond = np.empty(n_trials)
    for trial in range(n_trials):
        trial_values, vectors = np.linalg.eigh(normal[trial])
        values[trial] = trial_values
        largest = trial_values[2]
        for j in range(3):
            kept = np.inf if abs(trial_values[j]) <= RCOND * largest else trial_values[j]
            projected = 0.0
            for i in range(3):
                projected += vectors[i, j] * rhs[trial, i]
            projected /= kept
            for i in range(3):
                centres[trial, i] += vectors[i, j] * projected
        rcond[trial] = trial_values[0] / largest
    return centres, values, rcond


@kernel
def _analytic_sums(
    r0: np.ndarray, r1: np.ndarray, d0: np.ndarray, d1: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 9's normal equations ``sum_t M_t' M_t`` ``(T, 3, 3)`` and ``sum_t M_t' y_t``
    ``(T, 3)`` [mm] over the frames ``t >= 1``, ``M_t = R0 - R1``, ``y_t = d1 - d0``, of the
    rotations ``r0``, ``r1`` ``(T, N, 3, 3)`` and translations ``d0``, ``d1`` ``(T, N, 3)``
    [mm], one pass over the frames that forms no ``M_t`` array: a matrix product of the
    stacked ``(3 (N - 1), 3)`` rows costs several times that pass. Each entry is summed from
    its own products, not as ``2 I - R0' R1 - R1' R0``, whose cancellation would lose the
    small eigenvalues that tell degenerate motion. A compiled kernel."""
    n_trials, n_frames = r0.shape[0], r0.shape[1]
    normal = np.zeros((n_trials, 3, 3))
    rhs = np.zeros((n_trials, 3))
    for trial in range(n_trials):
        # The sums in locals (the upper triangle), stored once per trial.
        n00 = n01 = n02 = n11 = n12 = n22 = 0.0
        b0 = b1 = b2 = 0.0
        for t in range(1, n_frames):
            for k in range(3):  # row k of M_t and of y_t
                m0 = r0[trial, t, k, 0] - r1[trial, t, k, 0]
                m1 = r0[trial, t, k, 1] - r1[trial, t, k, 1]
                m2 = r0[trial, t, k, 2] - r1[trial, t, k, 2]
                y = d1[trial, t, k] - d0[trial, t, k]
                n00 += m0 * m0
                n01 += m0 * m1
                n02 += m0 * m2
                n11 += m1 * m1
                n12 += m1 * m2
                n22 += m2 * m2
                b0 += m0 * y
                b1 += m1 * y
                b2 += m2 * y
        normal[trial, 0, 0], normal[trial, 0, 1], normal[trial, 0, 2] = n00, n01, n02
        normal[trial, 1, 0], normal[trial, 1, 1], normal[trial, 1, 2] = n01, n11, n12
        normal[trial, 2, 0], normal[trial, 2, 1], normal[trial, 2, 2] = n02, n12, n22
        rhs[trial, 0], rhs[trial, 1], rhs[trial, 2] = b0, b1, b2
    return normal, rhs


def _motion_error(values: np.ndarray, n_frames: int, what: str) -> ValueError | None:
    """The degenerate-motion error of a normal matrix with eigenvalues ``values`` (3,),
    ascending, or ``None``."""
    if values[-1] <= _NO_ROTATION * n_frames:
        return ValueError(
            f"{what}: degenerate motion: the segments do not rotate relative to each other"
        )
    if negligible(values[0], values[-1]):
        return ValueError(
            f"{what}: degenerate motion: the relative rotation is about a single axis (a "
            "hinge), so the centre is not determined along that axis"
        )
    return None


@register("joint_center", "analytic", min_frames=POSE_MIN_FRAMES, color="#fb9a99", marker="s")
def fit_analytic(
    proximal: np.ndarray, distal: np.ndarray, *, noise_mm: NonNegative | None = None
) -> JointCenterResult:
    """Paper C's analytic joint centre (§6, eq. 9).

    Parameters
    ----------
    proximal, distal : (n_frames >= 3, n_markers >= 3, 3) [mm], world frame, same frames.
    noise_mm : accepted for a uniform ``joint_center`` signature; unused.

    Returns
    -------
    JointCenterResult
        ``center`` ``(3,)`` [mm] in the body-fixed frame shared at frame 0 (the world at frame
        0); ``covariance`` ``None``; ``cost`` ``sum_t |f0(t) c - f1(t) c|^2`` [mm^2] (eq. 6);
        ``diagnostics["rcond"]`` the smallest over largest eigenvalue of ``sum M'M``.
    """
    return one_trial(_analytic_trials, proximal, distal, noise_mm=noise_mm)


def _analytic_result(prox: PoseStack, dist: PoseStack) -> list[JointCenterResult | ValueError]:
    centers, rcond, errors = _analytic(prox, dist, "analytic")
    m, y = _relative_system(prox, dist)
    residual = np.einsum("tfij,tj->tfi", m, centers) - y
    cost = np.sum(residual**2, axis=(1, 2))
    return trial_outcomes(
        errors,
        lambda trial: JointCenterResult(
            center=centers[trial],
            covariance=None,
            converged=True,
            iterations=0,
            status="ok",
            method="analytic",
            cost=float(cost[trial]),
            diagnostics={"rcond": float(rcond[trial])},
        ),
    )


@dataclass(frozen=True)
class _Prepared:
    """One trial's Gauss–Markov system before iterating (frames ``t >= 1``)."""

    y: np.ndarray  # (N-1, 3) [mm]
    r0: np.ndarray  # (N-1, 3, 3)
    r1: np.ndarray  # (N-1, 3, 3)
    means: np.ndarray  # (2, 3) [mm], the segments' lever factors (pose_noise.lever_factors)
    inertia_invs: np.ndarray  # (2, 3, 3) [mm^-2]
    counts: np.ndarray  # (2,), markers per segment
    analytic_center: np.ndarray  # (3,) [mm]
    variance: float  # s^2 [mm^2]
    diagnostics: dict
    proximal_body: np.ndarray  # (n, 3) [mm]


#: The analytic centre ``(3,)`` [mm] of one trial's poses and its ``rcond`` (:func:`_analytic`).
_Analytic = tuple[np.ndarray, float]


def _prepared(
    prox: SegmentPoses,
    dist: SegmentPoses,
    noise_mm,
    method: str,
    *,
    analytic: _Analytic | None = None,
) -> _Prepared:
    """The analytic start, the noise variance and the lever factors of one trial; the analytic
    step's ``ValueError`` on degenerate motion. ``analytic``: the analytic centre and its
    ``rcond`` where a fit to the same poses found them (eq. 9 gives the same numbers), so
    that it is not solved again."""
    if analytic is None:
        centers, rconds, errors = _analytic(prox, dist, method)
        if errors[0] is not None:
            raise errors[0]
        analytic = centers[0], float(rconds[0])
    y = _translations(prox, dist)
    analytic_center, rcond = analytic
    variance, noise_used, noise_source = _per_coordinate_variance(noise_mm, prox, dist)
    means, inertia_invs, counts = np.empty((2, 3)), np.empty((2, 3, 3)), np.empty(2, dtype=int)
    for segment, poses in enumerate((prox, dist)):
        means[segment], inertia_invs[segment], counts[segment] = lever_factors(poses.body)
    return _Prepared(
        y=kernel_array(y),
        # The poses' arrays are read-only and C-contiguous, as kernels take them: not copied.
        r0=prox.rotation[1:],
        r1=dist.rotation[1:],
        means=means,
        inertia_invs=inertia_invs,
        counts=counts,
        analytic_center=analytic_center,
        variance=variance,
        diagnostics={
            "noise_mm": noise_used,
            "noise_source": noise_source,
            "analytic_center": analytic_center.tolist(),
            "rcond": rcond,
        },
        proximal_body=prox.body,
    )


@dataclass(frozen=True)
class _Iterated:
    """Where paper C's re-linearisation left one trial (:func:`_relinearised`)."""

    state: np.ndarray  # (k,): c, or (c, c0, c1) [mm]
    information: np.ndarray  # (k, k), of the last iteration, unit variance
    iterations: int
    step: float  # [mm], the last correction
    singular: bool  # the last iteration's system was singular: no answer
    chi2: float  # at the final state, unit variance
    frame0_added: np.ndarray | None  # (3, 3), paper C's model only (_relinearised)


def _iterated(trial: _Prepared, *, frame0: bool, max_iterations: int, tol_mm: float):
    """Paper C's re-linearisation of one ``trial`` from its analytic centre
    (:func:`_relinearised`), for its own model or, ``frame0``, the frame-0 model.
    ``ValueError`` for ``max_iterations`` below 1: no iteration forms the weights that the
    chi^2 and the information are read at."""
    if int(max_iterations) < 1:
        raise ValueError(f"max_iterations must be >= 1, got {max_iterations!r}")
    k = 9 if frame0 else 3
    state = np.tile(trial.analytic_center, k // 3)
    information = np.full((k, k), np.nan)
    frame0_added = np.full((3, 3), np.nan)
    iterations, step, singular, chi2 = _relinearised(
        trial.r0,
        trial.r1,
        trial.y,
        trial.means,
        trial.inertia_invs,
        trial.counts,
        frame0,
        int(max_iterations),
        float(tol_mm),
        state,
        information,
        frame0_added,
    )
    return _Iterated(
        state=state,
        information=information,
        iterations=iterations,
        step=step,
        singular=singular,
        chi2=chi2,
        frame0_added=None if frame0 else frame0_added,
    )


@kernel
def _relinearised(
    r0: np.ndarray,
    r1: np.ndarray,
    y: np.ndarray,
    means: np.ndarray,
    inertia_invs: np.ndarray,
    counts: np.ndarray,
    frame0: bool,
    max_iterations: int,
    tol_mm: float,
    state: np.ndarray,
    information: np.ndarray,
    frame0_added: np.ndarray,
) -> tuple:
    """Paper C's re-linearisation of one trial (eqs. 11–23, module docstring) from ``state``
    ``(k,)`` [mm], iterated in place until the correction is at most ``tol_mm`` (each of the
    centre's three points at most, for the frame-0 model) or for ``max_iterations``.

    ``r0``, ``r1`` ``(N-1, 3, 3)`` and ``y = d1 - d0`` ``(N-1, 3)`` [mm] are the poses of the
    frames ``t >= 1``; ``means`` ``(2, 3)``, ``inertia_invs`` ``(2, 3, 3)`` and ``counts`` ``(2,)``
    the segments' lever factors (:func:`jointbench.estimators.pose_noise.lever_factors`).
    Paper C's model (``frame0`` false): unknown ``c`` (``k = 3``), rows ``M_t = R0 - R1``. The
    frame-0 model: unknowns ``(c, c0, c1)`` (``k = 9``), rows ``[R0, -R1]`` acting on ``(c0,
    c1)`` and the pseudo-measurements ``c0 - c = 0``, ``c1 - c = 0`` of covariances ``A_0(c0)``,
    ``A_1(c1)``. Each iteration weighs every frame by ``W_t^-1`` at the current state and
    accumulates the normal equations in one pass over the frames, each frame's terms in its
    proximal body frame (:func:`_frame_weights`, :func:`_frame_normal`); the correction is
    solved from the residuals, which keeps full precision when they are tiny (noise-free data)
    however large the coordinates.

    Writes the last iteration's ``information`` ``(k, k)`` (unit variance) and, for paper C's
    model, ``frame0_added`` ``(3, 3)``: ``F_0 A_0 F_0' + F_1 A_1 F_1'`` with ``F_a = sum_t M_t'
    W_t^-1 R_a(t)`` at the weights of the last iteration, what the frame-0 poses' errors add
    (module docstring, "Frame 0"). Returns ``(iterations, step [mm], singular, chi2)``:
    ``singular`` where a normal matrix had an exactly zero pivot (the trial stops there, with no
    answer), ``chi2`` ``sum_t r_t' W_t^-1 r_t`` (plus the frame-0 terms) at the final state with
    the last iteration's weights, unit variance. A compiled kernel."""
    k = state.shape[0]
    at_joint = np.empty((2, 3, 3))
    precisions = np.empty((2, 3, 3))
    gradient = np.empty(k)
    system = np.empty((k, k))
    correction = np.empty(k)
    gains = np.empty((2, 3, 3))
    relative, local = _proximal_frames(r0, r1, y)
    weights = np.empty((6, local.shape[0]))
    iterations, step = 0, np.inf
    for iteration in range(1, max_iterations + 1):
        iterations = iteration
        for a in range(2):
            # A_a at the centre as segment a places it: c, or c0 and c1.
            at = 3 + 3 * a if frame0 else 0
            point_covariance_into(
                state[at : at + 3], means[a], inertia_invs[a], counts[a], at_joint[a]
            )
        _frame_weights(relative, at_joint, weights)
        _frame_normal(relative, local, weights, state, frame0, system, gradient)
        if frame0:
            for a in range(2):
                if inverse3_into(at_joint[a], precisions[a]) == 0.0:
                    return iterations, step, True, np.nan
            _pseudo_measurements(precisions, state, system, gradient)
        information[:, :] = system
        if not solve_into(system, gradient, correction):
            return iterations, step, True, np.nan
        step = 0.0
        for point in range(k // 3):
            for i in range(3):
                state[3 * point + i] += correction[3 * point + i]
            length = np.sqrt(
                correction[3 * point] ** 2
                + correction[3 * point + 1] ** 2
                + correction[3 * point + 2] ** 2
            )
            # Not max(): it keeps the larger of a comparison with NaN false, so a NaN correction
            # would leave a step of 0 and read as converged.
            if length > step or math.isnan(length):
                step = length
        if not step > tol_mm:  # a NaN step stops too, unconverged
            break
    chi2 = _frame_chi2(relative, local, weights, state, frame0, gains)
    if frame0:
        for a in range(2):
            at = 3 + 3 * a
            for i in range(3):
                for j in range(3):
                    offsets = (state[at + i] - state[i]) * (state[at + j] - state[j])
                    chi2 += offsets * precisions[a, i, j]
    else:
        frame0_added[:, :] = 0.0
        for a in range(2):
            for i in range(3):
                for j in range(3):
                    for p in range(3):
                        for q in range(3):
                            added = gains[a, i, p] * at_joint[a, p, q] * gains[a, j, q]
                            frame0_added[i, j] += added
    return iterations, step, False, chi2


@kernel
def _proximal_frames(r0: np.ndarray, r1: np.ndarray, y: np.ndarray) -> tuple:
    """Each frame's relative rotation ``Q_t = R0' R1``, entry ``(i, j)`` of frame ``t`` at
    ``[3 i + j, t]`` of ``(9, N-1)``, and ``z_t = R0' y_t`` ``(N-1, 3)`` [mm]: the constraint
    in the proximal body frame, ``R0' h_t = c0 - Q_t c1 - z_t``, ``R0' W_t R0 = A_0 + Q_t A_1
    Q_t'``, so that ``B_t' W_t^-1 B_t`` and ``B_t' W_t^-1 e_t`` (:func:`_frame_normal`) need
    one ``3 x 3`` inverse and no product with ``R0``. Each entry over the frames is contiguous,
    so that the frames' weights (:func:`_frame_weights`) are formed several at once. A
    compiled kernel."""
    n_steps = y.shape[0]
    relative = np.empty((9, n_steps))
    local = np.empty((n_steps, 3))
    for t in range(n_steps):
        for i in range(3):
            for j in range(3):
                turned = r0[t, 0, i] * r1[t, 0, j] + r0[t, 1, i] * r1[t, 1, j]
                relative[3 * i + j, t] = turned + r0[t, 2, i] * r1[t, 2, j]
            local[t, i] = r0[t, 0, i] * y[t, 0] + r0[t, 1, i] * y[t, 1] + r0[t, 2, i] * y[t, 2]
    return relative, local


@kernel
def _frame_weights(relative: np.ndarray, at_joint: np.ndarray, weights: np.ndarray) -> None:
    """Each frame's weight in its proximal body frame, ``V_t = (R0' W_t R0)^-1 = (A_0 + Q_t
    A_1 Q_t')^-1`` (paper C's eq. 20 in that frame), of the relative rotations ``Q_t``
    ``relative`` ``(9, N-1)`` (:func:`_proximal_frames`) and the point covariances ``A_a``
    ``at_joint`` ``(2, 3, 3)``, its upper triangle ``(v00, v01, v02, v11, v12, v22)`` written
    into ``weights`` ``(6, N-1)``, entry by entry as ``relative``; the inverse from the
    cofactors, as :func:`jointbench.numerics.small.inverse3` forms it. Formed once per
    iteration, for its normal equations (:func:`_frame_normal`) and, after the last, the
    chi^2 (:func:`_frame_chi2`). A compiled kernel."""
    # The point covariances read into registers once: the frames' stores into ``weights``
    # could otherwise alias them. With them held, and every call inside the loop one that
    # compiles into it, the frames are formed several at once.
    a0, a1 = rows9(at_joint[0]), rows9(at_joint[1])
    for t in range(weights.shape[1]):
        q00, q01, q02, q11, q12, q22 = rotated9_upper(_frame_rotation(relative, t), a1)
        s00, s01, s02 = a0[0] + q00, a0[1] + q01, a0[2] + q02
        s11, s12, s22 = a0[4] + q11, a0[5] + q12, a0[8] + q22
        inverse = inverse3_entries(s00, s01, s02, s01, s11, s12, s02, s12, s22)
        weights[0, t], weights[1, t], weights[2, t] = inverse[0], inverse[1], inverse[2]
        weights[3, t], weights[4, t], weights[5, t] = inverse[4], inverse[5], inverse[8]


@kernel
def _frame_rotation(relative: np.ndarray, t: int) -> tuple:
    """Frame ``t``'s relative rotation of ``relative`` ``(9, N-1)`` (:func:`_proximal_frames`)
    as 9 numbers by rows. A compiled kernel."""
    return (
        relative[0, t],
        relative[1, t],
        relative[2, t],
        relative[3, t],
        relative[4, t],
        relative[5, t],
        relative[6, t],
        relative[7, t],
        relative[8, t],
    )


@kernel
def _frame_normal(
    relative: np.ndarray,
    local: np.ndarray,
    weights: np.ndarray,
    state: np.ndarray,
    frame0: bool,
    system: np.ndarray,
    gradient: np.ndarray,
) -> None:
    """The frames' part of one iteration's normal equations (:func:`_relinearised`), written
    into ``system`` ``(k, k)`` (both triangles; zero where the pseudo-measurements go) and
    ``gradient`` ``(k,)``: ``sum_t B_t' W_t^-1 B_t`` and ``sum_t B_t' W_t^-1 e_t`` with rows
    ``B_t`` (``M_t``, or ``[R0, -R1]`` for the frame-0 model) and residuals ``e_t = y_t - B_t
    x`` at the current unknowns ``x``, with the frames' ``weights`` ``(6, N-1)``
    (:func:`_frame_weights`). Each frame's terms are taken in its proximal body frame
    (:func:`_proximal_frames`: ``relative`` ``Q_t``, ``local`` ``z_t``): with ``V_t = (R0' W_t
    R0)^-1`` (:func:`_frame_weights`), ``B_t = R0 [I, -Q_t]`` (or ``R0 (I - Q_t)``) and
    ``R0' e_t = z_t - [I, -Q_t] x``, so ``B_t' W_t^-1 B_t = [I, -Q_t]' V_t [I, -Q_t]``. A
    compiled kernel."""
    system[:, :] = 0.0
    gradient[:] = 0.0
    # The unknowns read once (see _frame_weights): c0 and c1, or c for both.
    proximal = state[3:6].copy() if frame0 else state[0:3].copy()
    distal = state[6:9].copy() if frame0 else state[0:3].copy()
    for t in range(local.shape[0]):
        weight = _weight_at(weights, t)
        q = _frame_rotation(relative, t)
        residual = _local_residual(local[t], q, proximal, distal)
        if frame0:
            u = symmetric_times9(weight, q)  # V Q
            add_upper3(system, 3, 3, symmetric9(weight), 1.0)
            add_block3(system, 3, 6, u, -1.0)
            add_upper3(system, 6, 6, transposed_times9(q, u), 1.0)
            pulled = symmetric_applied9(weight, residual)
            add_vector3(gradient, 3, pulled, 1.0)
            add_vector3(gradient, 6, transposed_applied9(q, pulled), -1.0)
        else:
            m = identity_less9(q)
            u = symmetric_times9(weight, m)
            add_upper3(system, 0, 0, transposed_times9(m, u), 1.0)
            add_vector3(gradient, 0, transposed_applied9(u, residual), 1.0)
    first = 3 if frame0 else 0
    for i in range(first, system.shape[0]):
        for j in range(i + 1, system.shape[0]):
            system[j, i] = system[i, j]


@kernel
def _frame_chi2(
    relative: np.ndarray,
    local: np.ndarray,
    weights: np.ndarray,
    state: np.ndarray,
    frame0: bool,
    gains: np.ndarray,
) -> float:
    """``sum_t e_t' W_t^-1 e_t`` at the unknowns ``state``, with the frames' ``weights``
    ``(6, N-1)`` (:func:`_frame_weights`) and, for paper C's model, ``F_a = sum_t M_t' W_t^-1
    R_a(t)`` into ``gains`` ``(2, 3, 3)``: ``F_0 = sum_t (I - Q_t)' V_t``, ``F_1 = sum_t (I -
    Q_t)' V_t Q_t``. A compiled kernel."""
    chi2 = 0.0
    gains[:, :, :] = 0.0
    proximal = state[3:6].copy() if frame0 else state[0:3].copy()
    distal = state[6:9].copy() if frame0 else state[0:3].copy()
    for t in range(local.shape[0]):
        weight = _weight_at(weights, t)
        q = _frame_rotation(relative, t)
        residual = _local_residual(local[t], q, proximal, distal)
        if not frame0:
            u = symmetric_times9(weight, identity_less9(q))
            add_block3(gains[0], 0, 0, transposed9(u), 1.0)
            add_block3(gains[1], 0, 0, transposed_times9(u, q), 1.0)
        weighted = symmetric_applied9(weight, residual)
        chi2 += residual[0] * weighted[0] + residual[1] * weighted[1] + residual[2] * weighted[2]
    return chi2


@kernel
def _weight_at(weights: np.ndarray, t: int) -> tuple:
    """Frame ``t``'s weight of ``weights`` ``(6, N-1)`` (:func:`_frame_weights`) as its 6
    numbers. A compiled kernel."""
    return (
        weights[0, t],
        weights[1, t],
        weights[2, t],
        weights[3, t],
        weights[4, t],
        weights[5, t],
    )


@kernel
def _local_residual(z: np.ndarray, q: tuple, u: np.ndarray, v: np.ndarray) -> tuple:
    """``z - u + Q v`` ``(3,)`` for a 9-number ``Q`` and ``(3,)`` vectors: a frame's residual
    in its proximal body frame (:func:`_frame_normal`). A compiled kernel."""
    return (
        z[0] - u[0] + (q[0] * v[0] + q[1] * v[1] + q[2] * v[2]),
        z[1] - u[1] + (q[3] * v[0] + q[4] * v[1] + q[5] * v[2]),
        z[2] - u[2] + (q[6] * v[0] + q[7] * v[1] + q[8] * v[2]),
    )


@kernel
def _pseudo_measurements(
    precisions: np.ndarray, state: np.ndarray, system: np.ndarray, gradient: np.ndarray
) -> None:
    """The frame-0 model's pseudo-measurements ``c0 - c = 0`` and ``c1 - c = 0``, of
    precisions ``P_a = A_a^-1`` ``(2, 3, 3)``, added to its normal matrix ``system`` ``(9,
    9)`` and its ``gradient`` ``(9,)`` at ``state`` ``(c, c0, c1)``. A compiled kernel."""
    for a in range(2):
        at = 3 + 3 * a
        for i in range(3):
            pull = 0.0
            for j in range(3):
                p = precisions[a, i, j]
                system[i, j] += p
                system[i, at + j] -= p
                system[at + i, j] -= p
                system[at + i, at + j] += p
                pull += p * (state[at + j] - state[j])
            gradient[i] += pull
            gradient[at + i] -= pull


def _gauss_markov_results(
    poses: list[dict[str, SegmentPoses] | ValueError],
    *,
    noise_mm: float | None,
    frame0: bool,
    max_iterations: int,
    tol_mm: float,
    analytic: list[_Analytic | None] | None = None,
) -> list[JointCenterResult | ValueError]:
    """Paper C's Gauss–Markov fit of every trial's ``proximal`` and ``distal`` poses (a trial's
    ``ValueError`` is kept as its outcome), each trial iterated to its own convergence from its
    analytic centre: per trial in ``analytic`` where a fit to the same poses found it
    (:func:`_prepared`), else solved here."""
    method = "gauss-markov-frame0" if frame0 else "gauss-markov"
    noise_mm = _as_noise(noise_mm)
    starts = [None] * len(poses) if analytic is None else analytic
    outcomes = each_trial(
        [p if isinstance(p, ValueError) else (p, s) for p, s in zip(poses, starts, strict=True)],
        lambda given: _prepared(
            given[0]["proximal"], given[0]["distal"], noise_mm, method, analytic=given[1]
        ),
    )
    for index, outcome in enumerate(outcomes):
        if isinstance(outcome, _Prepared):
            done = _iterated(outcome, frame0=frame0, max_iterations=max_iterations, tol_mm=tol_mm)
            outcomes[index] = _result(outcome, done, method, tol_mm)
    return outcomes


def _result(trial: _Prepared, done: _Iterated, method: str, tol_mm) -> JointCenterResult:
    """One trial's result from its iteration (:func:`_iterated`)."""
    frame0 = done.frame0_added is None
    diagnostics = dict(trial.diagnostics)
    try:
        if done.singular:
            raise np.linalg.LinAlgError("Singular matrix")
        unit_covariance = np.linalg.inv(done.information)
        covariance_all = trial.variance * 0.5 * (unit_covariance + unit_covariance.T)
    except np.linalg.LinAlgError as error:
        return JointCenterResult(
            center=trial.analytic_center,
            covariance=None,
            converged=False,
            iterations=0,
            status=f"singular Gauss–Markov information matrix ({error})",
            method=method,
            diagnostics=diagnostics,
        )
    state = done.state
    covariance = covariance_all[:3, :3]
    if not frame0:
        # s^2 (H^-1 + H^-1 (F_0 A_0 F_0' + F_1 A_1 F_1') H^-1), H the information: W_c is
        # conditional on the frame-0 poses, whose errors every frame shares (module
        # docstring, "Frame 0").
        unit = unit_covariance + unit_covariance @ done.frame0_added @ unit_covariance
        diagnostics["center_covariance_mm2"] = (trial.variance * 0.5 * (unit + unit.T)).tolist()
    if frame0:
        diagnostics["proximal_body"] = trial.proximal_body.tolist()
        diagnostics["center_proximal"] = state[3:6].tolist()
        diagnostics["covariance_proximal"] = covariance_all[3:6, 3:6].tolist()
        diagnostics["center_distal"] = state[6:].tolist()
        diagnostics["covariance_distal"] = covariance_all[6:, 6:].tolist()
    dof = 3 * trial.y.shape[0] - 3
    chi2 = float(done.chi2) / trial.variance if trial.variance > 0 else float("nan")
    diagnostics["chi2"] = chi2
    diagnostics["chi2_dof"] = dof
    step, iterations = float(done.step), int(done.iterations)
    converged = bool(step <= tol_mm and np.all(np.isfinite(covariance)))
    status = (
        "ok"
        if converged
        else f"did not converge: the centre still moved {step:.3g} mm at iteration {iterations}"
    )
    return JointCenterResult(
        center=state[:3].copy(),
        covariance=covariance,
        converged=converged,
        iterations=iterations,
        status=status,
        method=method,
        cost=chi2,
        diagnostics=diagnostics,
    )


# The model test (module docstring, "Model test").


@kernel
def _marker_gains(points: np.ndarray, body: np.ndarray) -> np.ndarray:
    """``B_pi = I/n - [p - m]x K^-1 [u_i]x`` ``(P, n, 3, 3)`` for body points ``p`` ``(P, 3)``
    [mm]: the error of ``p`` as a least-squares pose fit of the markers ``body`` ``(n, 3)``
    [mm] places it, per unit error of marker ``i`` (``m``, ``u_i``, ``K`` as in ``A(c)``;
    ``sum_i B_pi B_pi' = A(p) / s^2``). At ``p = x_j`` it is the fit's hat matrix. A compiled
    kernel."""
    mean, inertia_inv, n = lever_factors(body)
    gains = np.empty((points.shape[0], n, 3, 3))
    for p in range(points.shape[0]):
        lever = skew9(points[p, 0] - mean[0], points[p, 1] - mean[1], points[p, 2] - mean[2])
        turned = _levered(lever, inertia_inv)
        for i in range(n):
            offset = skew9(body[i, 0] - mean[0], body[i, 1] - mean[1], body[i, 2] - mean[2])
            gain = _gain9(turned, offset, n)
            for k in range(9):
                gains[p, i, k // 3, k % 3] = gain[k]
    return gains


@kernel
def _levered(lever: tuple, inertia_inv: np.ndarray) -> tuple:
    """``[p - m]x K^-1`` (9 numbers) of the skew matrix ``lever`` (9 numbers) of a point about
    the centroid and the inverse inertia ``K^-1`` ``(3, 3)`` [mm^-2] (:func:`_marker_gains`).
    A compiled kernel."""
    return transposed_times9(transposed9(lever), rows9(inertia_inv))


@kernel
def _gain9(turned: tuple, offset: tuple, n: int) -> tuple:
    """``I/n - T [u_i]x`` (9 numbers): marker ``i``'s gain (:func:`_marker_gains`) from
    ``T = [p - m]x K^-1`` (:func:`_levered`) and ``offset = [u_i]x`` (9 numbers each), of
    ``n`` markers. A compiled kernel."""
    product = transposed_times9(transposed9(turned), offset)
    share = 1.0 / n
    return (
        share - product[0],
        0.0 - product[1],
        0.0 - product[2],
        0.0 - product[3],
        share - product[4],
        0.0 - product[5],
        0.0 - product[6],
        0.0 - product[7],
        share - product[8],
    )


@kernel
def _fourth_moment(x: tuple) -> float:
    """``tr(X)^2 + 2 tr(X X')`` of a 9-number block ``X`` (symmetric: ``tr(X^2)``): per unit
    ``s^4``, ``E (e' X e)^2`` for one marker's Gaussian error ``e``, and ``3 / kappa`` times
    what spherical noise of excess kurtosis ``kappa`` adds to it. A compiled kernel."""
    trace = x[0] + x[4] + x[8]
    squares = 0.0
    for k in range(9):
        squares += x[k] * x[k]
    return trace * trace + 2.0 * squares


@kernel
def _residual_moments(body: np.ndarray) -> tuple:
    """Per frame, ``(G, F)`` of ``E sum_i |r_i|^4 = s^4 (G + kappa F)`` over the residuals
    ``r_i`` ``(3,)`` of a rigid fit of the markers ``body`` ``(n, 3)`` [mm]; ``kappa G / 3`` is
    also what the kurtosis adds to the variance of the frame's residual sum of squares. With
    ``Q_ji = delta_ji I - B_ji`` the blocks of ``I - H`` (:func:`_marker_gains` at the
    markers), ``G = sum_i m(Q_ii)`` and ``F = sum_ji m(Q_ji' Q_ji) / 3``, ``m`` of
    :func:`_fourth_moment`. A compiled kernel.

    ``F``'s sum over the ``n^2`` pairs is taken in closed form, in time and memory linear in
    ``n``: the hat's blocks are ``B_ji = U_j U_i'`` with ``U_i = [I / sqrt(n), [u_i]x L]``
    ``(3, 6)`` and ``L L' = K^-1``, so with ``A_i = U_i' U_i`` ``(6, 6)`` a pair has
    ``tr(B' B) = tr(A_j A_i)`` and ``tr((B' B)^2) = tr(A_j A_i A_j A_i)``, and over all pairs
    these need only ``T = sum_i vec(A_i) vec(A_i)'`` ``(36, 36)`` (:func:`_pair_moments`). The
    pairs ``i = j`` take ``m(Q_ii' Q_ii)`` in place of ``m(B_ii' B_ii)``. Up to
    :data:`_PAIRED_MARKERS` markers the pairs are summed one by one (:func:`_paired_moments`),
    which costs less there."""
    n = body.shape[0]
    if n <= _PAIRED_MARKERS:
        return _paired_moments(body)
    mean, inertia_inv, _ = lever_factors(body)
    values, vectors = symmetric_eigen(inertia_inv)
    # L = V diag(sqrt(values)), L L' = K^-1, a square root rather than K^-1 itself: the
    # U_i's columns are then orthonormal over the markers (sum_i U_i' U_i = I), so every A_i
    # is bounded by 1 and the sums over the pairs cancel no more than their answer.
    root = np.empty((3, 3))
    for r in range(3):
        for c in range(3):
            root[r, c] = vectors[r, c] * math.sqrt(values[c])
    seconds = np.zeros((36, 36))
    basis = np.empty((3, 6))
    spread = np.empty(36)
    own, diagonal = 0.0, 0.0
    scale = 1.0 / math.sqrt(n)
    for i in range(n):
        offset = skew9(body[i, 0] - mean[0], body[i, 1] - mean[1], body[i, 2] - mean[2])
        for r in range(3):
            for c in range(3):
                basis[r, c] = scale if r == c else 0.0
                basis[r, 3 + c] = (
                    offset[3 * r] * root[0, c]
                    + offset[3 * r + 1] * root[1, c]
                    + offset[3 * r + 2] * root[2, c]
                )
        for p in range(6):
            for q in range(6):
                spread[6 * p + q] = (
                    basis[0, p] * basis[0, q]
                    + basis[1, p] * basis[1, q]
                    + basis[2, p] * basis[2, q]
                )
        for p in range(36):
            for q in range(p, 36):
                seconds[p, q] += spread[p] * spread[q]
        block = _gain9(_levered(offset, inertia_inv), offset, n)
        residual = identity_less9(block)
        own += _fourth_moment(residual)
        diagonal += _fourth_moment(transposed_times9(residual, residual))
        diagonal -= _fourth_moment(transposed_times9(block, block))
    return own, (_pair_moments(seconds) + diagonal) / 3.0


#: Markers up to which :func:`_residual_moments` sums the hat's pairs of blocks one by one:
#: ``n^2`` small products, fewer than the closed form's fixed ``36 x 36`` sums on a few
#: markers.
_PAIRED_MARKERS = 12


@kernel
def _paired_moments(body: np.ndarray) -> tuple:
    """:func:`_residual_moments` summed over the pairs of markers one by one, each block of
    the hat made where it is read (:func:`_gain9`). A compiled kernel."""
    n = body.shape[0]
    mean, inertia_inv, _ = lever_factors(body)
    own, shared = 0.0, 0.0
    for j in range(n):
        lever = skew9(body[j, 0] - mean[0], body[j, 1] - mean[1], body[j, 2] - mean[2])
        turned = _levered(lever, inertia_inv)
        for i in range(n):
            offset = skew9(body[i, 0] - mean[0], body[i, 1] - mean[1], body[i, 2] - mean[2])
            block = _gain9(turned, offset, n)
            delta = 1.0 if i == j else 0.0
            residual = (
                delta - block[0],
                -block[1],
                -block[2],
                -block[3],
                delta - block[4],
                -block[5],
                -block[6],
                -block[7],
                delta - block[8],
            )
            if i == j:
                own += _fourth_moment(residual)
            shared += _fourth_moment(transposed_times9(residual, residual))
    return own, shared / 3.0


@kernel
def _pair_moments(seconds: np.ndarray) -> float:
    """``sum_ji m(B_ji' B_ji)`` over all pairs of markers, ``i = j`` included, from the upper
    triangle of ``T = sum_i vec(A_i) vec(A_i)'`` ``(36, 36)`` (:func:`_residual_moments`; its
    lower triangle is filled here): ``sum_ji tr(A_j A_i)^2 = sum T[pq, rs]^2`` (``A``
    symmetric) and ``sum_ji tr(A_j A_i A_j A_i) = sum T[pq, rs] T[qr, sp]``. A compiled
    kernel."""
    for p in range(36):
        for q in range(p):
            seconds[p, q] = seconds[q, p]
    squares, chained = 0.0, 0.0
    for p in range(6):
        for q in range(6):
            for r in range(6):
                for s in range(6):
                    second = seconds[6 * p + q, 6 * r + s]
                    squares += second * second
                    chained += second * seconds[6 * q + r, 6 * s + p]
    return squares + 2.0 * chained


def _constraint_moments(rotations, bodies, points) -> float:
    """``sum_{t, a, i} tr(X)^2 + 2 tr(X^2)`` with ``X = B_ai' V_at B_ai``, ``V_at = R_a' W_t^-1
    R_a``, over the frames ``t >= 1``, both segments ``a`` and their markers ``i``: per unit
    ``s^4``, ``3 / kappa`` times what the noise's kurtosis adds to the variance of the
    Gauss–Markov chi^2. ``rotations`` ``R_a`` ``(N-1, 3, 3)``, ``bodies`` ``(n_a, 3)`` [mm] and
    ``points`` ``c_a`` ``(3,)`` [mm], the centre in each segment (:func:`_marker_gains`).

    ``V_at`` is the inverse of ``R_a' W_t R_a = A_a + R_ab A_b R_ab'`` with ``R_ab = R_a' R_b``
    the other segment's relative rotation. With ``C = B B'``, ``tr(X) = <V, C>`` and
    ``tr(X^2) = tr(V C V C)``, so the sum over frames needs only ``S = sum_t vec(V_t)
    vec(V_t)'`` (9 x 9, :func:`_local_weight_moments`): ``c' S c`` and ``sum S[jk, lm] C_kl
    C_mj``, not one product per frame and marker. On a long trial it is taken over
    :data:`_MOMENT_FRAMES` frames and scaled."""
    n_steps = len(rotations[0])
    chosen = _spread_frames(n_steps, _MOMENT_FRAMES)
    # Contiguous, but not copied where read-only (the poses' arrays, the shared frames).
    arrays = [np.ascontiguousarray(array, dtype=float) for array in (*rotations, *bodies)]
    points = np.stack([np.asarray(point, dtype=float) for point in points])
    return _constraint_moment_sum(*arrays, chosen, points) * n_steps / len(chosen)


@kernel
def _constraint_moment_sum(
    r0: np.ndarray,
    r1: np.ndarray,
    body0: np.ndarray,
    body1: np.ndarray,
    frames: np.ndarray,
    points: np.ndarray,
) -> float:
    """The sum of :func:`_constraint_moments` over the ``frames`` ``(k,)`` of the rotations
    ``R_a`` ``(N-1, 3, 3)``, for the segments' markers ``body0`` ``(n_0, 3)``, ``body1`` ``(n_1,
    3)`` [mm] and the centre in each, ``points`` ``(2, 3)`` [mm]: per segment and marker, with
    ``C = B B'`` and ``S`` of :func:`_local_weight_moments`, ``c' S c + 2 sum S[jk, lm] C_kl
    C_mj``. A compiled kernel."""
    covariances = np.empty((2, 3, 3))
    for a in range(2):
        body = body0 if a == 0 else body1
        mean, inertia_inv, n = lever_factors(body)
        point_covariance_into(points[a], mean, inertia_inv, n, covariances[a])
    seconds = _local_weight_moments(r0, r1, frames, covariances)
    total = 0.0
    for a in range(2):
        body = body0 if a == 0 else body1
        gains = _marker_gains(points[a : a + 1], body)[0]
        for i in range(body.shape[0]):
            gain = rows9(gains[i])
            spread = transposed_times9(transposed9(gain), transposed9(gain))  # B B'
            for p in range(9):
                for q in range(9):
                    total += spread[p] * seconds[a, p, q] * spread[q]
            for j in range(3):
                for k in range(3):
                    for m in range(3):
                        for o in range(3):
                            second = seconds[a, 3 * j + k, 3 * m + o]
                            total += 2.0 * second * spread[3 * k + m] * spread[3 * o + j]
    return total


@kernel
def _local_weight_moments(
    r0: np.ndarray, r1: np.ndarray, frames: np.ndarray, covariances: np.ndarray
) -> np.ndarray:
    """``S_a = sum_t vec(V_at) vec(V_at)'`` ``(2, 9, 9)`` over the ``frames`` ``(k,)`` of the
    rotations ``R_a`` ``(N-1, 3, 3)``, ``V_at = (A_a + R_ab A_b R_ab')^-1`` with ``A_a`` the
    point ``covariances`` ``(2, 3, 3)`` and ``R_ab = R_a' R_b`` (:func:`_constraint_moments`).
    A compiled kernel."""
    seconds = np.zeros((2, 9, 9))
    relative = np.empty((2, 3, 3))
    other = np.empty((3, 3))
    local = np.empty((3, 3))
    for t in frames:
        for i in range(3):
            for j in range(3):
                value = r0[t, 0, i] * r1[t, 0, j] + r0[t, 1, i] * r1[t, 1, j]
                value += r0[t, 2, i] * r1[t, 2, j]
                relative[0, i, j] = value
                relative[1, j, i] = value
        for a in range(2):
            rotated3_into(relative[a], covariances[1 - a], other)
            for i in range(3):
                for j in range(3):
                    other[i, j] += covariances[a, i, j]
            inverse3_into(other, local)
            # S is symmetric: its upper triangle summed, the lower copied after the frames
            # (each entry the same products in the same order, so the same bits).
            for p in range(9):
                for q in range(p, 9):
                    seconds[a, p, q] += local[p // 3, p % 3] * local[q // 3, q % 3]
    for a in range(2):
        for p in range(9):
            for q in range(p):
                seconds[a, p, q] = seconds[a, q, p]
    return seconds


#: Frames over which :func:`_constraint_moments` averages: its sum is one over the frames of a
#: function of the poses, which this many evenly spaced frames give to within 0.05 % on paper
#: C's rig and the skin-marker study (1200 and 600 frames) and 0.5 % with poses drawn at random
#: in every frame (``tests/test_gauss_markov_fit.py``), at a fifth of the cost on 1200 frames.
_MOMENT_FRAMES = 256


@functools.lru_cache(maxsize=64)
def _spread_frames(n_frames: int, most: int) -> np.ndarray:
    """At most ``most`` frame indices ``(k,)``, evenly spaced over ``n_frames``, first and last
    included; every frame when there are no more. Read-only: the same array serves every trial
    of that many frames."""
    frames = np.unique(np.linspace(0, n_frames - 1, min(n_frames, most)).round().astype(int))
    frames.flags.writeable = False
    return frames


def _noise_kurtosis(segments: tuple[SegmentPoses, ...], variance: float) -> tuple[float, float]:
    """``(kappa, G)``: the noise's per-coordinate excess kurtosis, by the method of moments
    from the segments' rigid-fit residuals of pooled variance ``variance`` [mm^2]
    (:func:`_residual_moments`), and ``G`` summed over the frames and segments."""
    fourth, gaussian, excess = 0.0, 0.0, 0.0
    for poses in segments:
        fourth += poses.residual_fourths
        g, f = _fit_moments(poses, len(poses.markers))
        gaussian += g
        excess += f
    return (fourth / variance**2 - gaussian) / excess, gaussian


def _fit_moments(poses: SegmentPoses, frames: int) -> tuple[float, float]:
    """``(G, F)`` of :func:`_residual_moments` for ``frames`` frames of the segment's rigid
    fit ``poses``: ``E sum |r_i|^4 = s^4 (G + kappa F)`` over those frames' residuals."""
    # The body-fixed coordinates, fitted to all N frames, shrink each frame's residuals by
    # about (N - 1) / N (the residual dof are (3 n - 6)(N - 1), not (3 n - 6) N): second
    # moments by its square, fourth cumulants by its fourth power.
    n_frames = len(poses.markers)
    shrink = (n_frames - 1) / n_frames
    g, f = _residual_moments(poses.body)
    return frames * shrink**2 * g, frames * shrink**4 * f


#: What a rejected model test says of the SD of an answer whose covariance assumes that model:
#: no statement of the answer's error, in either direction (a chi^2 above its dof: errors the
#: model leaves out; below: less noise reaching the centre than the covariance counts).
_SD_NOT_ITS_ERROR = f"so its SD does not describe its error: {PRECISION_NOT_DETERMINED}"


def _model_test(
    result: JointCenterResult, proximal: SegmentPoses, distal: SegmentPoses
) -> JointCenterResult:
    """``result`` of ``gauss-markov`` or ``gauss-markov-frame0`` with the test of its model
    on the poses ``proximal`` and ``distal`` it was fitted to
    (module docstring, "Model test"): ``chi2_p``, ``noise_kurtosis`` and ``chi2_inflation`` in
    its diagnostics (NaN where there is nothing to test), and below
    :data:`jointbench.estimators.support.ROTATION_ALPHA` a warning."""
    return with_warnings(result, *_model_verdict(result, proximal, distal))


def _paper_c_check(
    result: JointCenterResult, proximal: SegmentPoses, distal: SegmentPoses
) -> JointCenterResult:
    """``result`` of ``gauss-markov`` with the numbers of :func:`_model_test` (paper C's chi^2,
    of exact frame-0 poses) in its diagnostics, held to :func:`_fixed_centre_test`, the test of
    the model its stated SD is of (the frame-0 poses' errors added). Paper C's chi^2 carries
    each segment's frame-0 pose error in every frame: with frame 0 as noisy as the rest its mean
    is near twice its dof (module docstring, "Model test"), and its rejection says only that
    frame 0 has noise, which that SD holds. Its warning is given where the frame-0 extension's
    test was not made (its fit failed, or the segments' noise differs) or where the data allow
    no test of its own (a given noise of 0 beside noisy residuals)."""
    own, numbers = _model_verdict(result, proximal, distal)
    untested = all(math.isnan(value) for value in numbers.values())
    start = with_warnings(result, own if untested else (), numbers)
    held = _fixed_centre_test(start, proximal, distal, _gauss_markov_start(result))
    if not untested and "not_tested" in held.diagnostics["fixed_centre_test"]:
        return with_warnings(held, own, {})
    return held


def _frame0_model_test(
    result: JointCenterResult, proximal: SegmentPoses, distal: SegmentPoses
) -> JointCenterResult:
    """:func:`_model_test` of a ``gauss-markov-frame0`` ``result``, whose SD is read from the
    covariance of the model tested: a rejection says that SD does not describe its error."""
    return with_warnings(result, *_model_verdict(result, proximal, distal, _SD_NOT_ITS_ERROR))


def _model_verdict(
    result: JointCenterResult,
    proximal: SegmentPoses,
    distal: SegmentPoses,
    consequence: str | None = None,
    rounding: float | None = None,
) -> tuple[tuple[str, ...], dict]:
    """The test of :func:`_model_test` of the Gauss–Markov ``result`` on its poses: its
    warnings (none, or one where the test rejects, ending in ``consequence`` where given, what
    that says of the SD of the answer the test is made for) and its numbers (``chi2_p``,
    ``noise_kurtosis``, ``chi2_inflation``; NaN where there is nothing to test).
    ``rounding``: :func:`_rounding_variance` of the poses where the caller read it."""
    segments = (proximal, distal)
    untested = {"chi2_p": math.nan, "noise_kurtosis": math.nan, "chi2_inflation": math.nan}
    chi2, dof = result.diagnostics.get("chi2", math.nan), result.diagnostics.get("chi2_dof", 0)
    variance = _pooled_variance(segments)
    noisy = variance > (_rounding_variance(segments) if rounding is None else rounding)
    given = result.diagnostics["noise_mm"] if result.diagnostics["noise_source"] == "given" else 1
    if noisy and given * given == 0.0:
        # A noise of 0 (or one whose variance rounds to 0) makes the covariance 0 and the
        # chi^2 undefined: a confident answer.
        rms_mm = math.sqrt(3.0 * variance)
        warning = (
            f"noise_mm = {given:.3g} was given, but the rigid-body residuals show noise of "
            f"{rms_mm:.3g} mm "
            "RMS: the zero covariance does not describe the centre's error, its "
            f"{PRECISION_NOT_DETERMINED} (leave noise_mm out to estimate the noise from the data)"
        )
        return (warning,), untested
    if np.isnan(chi2) or dof < 1 or not noisy:
        # Noise-free data (rounding, not noise) or no chi^2: nothing to test against. An
        # infinite one (a given noise far below the data's) is tested, and rejects.
        return (), untested
    kurtosis, gaussian = _noise_kurtosis(segments, variance)
    excess = min(max(kurtosis, 0.0), MAX_NOISE_KURTOSIS) / 3.0
    n_steps = len(segments[0].markers) - 1
    frame0 = result.method == "gauss-markov-frame0"
    points = (
        (result.diagnostics["center_proximal"], result.diagnostics["center_distal"])
        if frame0
        else (result.center, result.center)
    )
    moments = _constraint_moments(
        tuple(p.rotation[1:] for p in segments), tuple(p.body for p in segments), points
    )
    inflation = 1.0 + excess * moments / (6.0 * n_steps)
    if result.diagnostics["noise_source"] == "given":
        residual = None
    else:
        residual_dof = sum(p.dof for p in segments)
        residual = (residual_dof, 1.0 + excess * gaussian / (2.0 * residual_dof))
    p_value, above, statistic = _model_p_value(chi2, dof, inflation, residual)
    warnings = ()
    if p_value < ROTATION_ALPHA:
        given = residual is None
        words = _model_warning(statistic, p_value, above, given, frame0, kurtosis)
        warnings = (words if consequence is None else f"{words}; {consequence}",)
    return warnings, {
        "chi2_p": p_value,
        "noise_kurtosis": float(kurtosis),
        "chi2_inflation": inflation,
    }


def _model_p_value(
    chi2: float, dof: int, inflation: float, residual: tuple[int, float] | None
) -> tuple[float, bool, str]:
    """``(p, above, statistic)``: the two-sided p-value of the Gauss–Markov ``chi2`` on ``dof``
    with its variance inflated ``inflation`` times (Satterthwaite: ``chi2 / g ~ chi^2(dof /
    g)``), whether it lies above its expectation, and how it reads. ``residual``: ``None`` for
    a given noise, else the rigid-body residuals' dof and inflation, for the F form
    ``(chi2 / dof) ~ F(dof / g, dof_r / g_r)``."""
    special = scipy_special()
    if residual is None:
        upper = float(special.chdtrc(dof / inflation, chi2 / inflation))
        lower = float(special.chdtr(dof / inflation, chi2 / inflation))
        return min(2.0 * min(upper, lower), 1.0), upper < lower, f"chi^2 = {chi2:.4g} on {dof} dof"
    residual_dof, residual_inflation = residual
    shape = (dof / inflation, residual_dof / residual_inflation, chi2 / dof)
    upper, lower = float(special.fdtrc(*shape)), float(special.fdtr(*shape))
    statistic = f"F = chi^2 / dof = {chi2 / dof:.4g} on ({dof}, {residual_dof}) dof"
    return min(2.0 * min(upper, lower), 1.0), upper < lower, statistic


def _model_warning(
    statistic: str, p_value: float, above: bool, given: bool, frame0: bool, kurtosis: float
) -> str:
    """The warning of a rejected model test, in plain words (:func:`_model_p_value`), adding
    glitches where the residuals' excess ``kurtosis`` is beyond :data:`MAX_NOISE_KURTOSIS`
    (an estimate that scatters widely on a few frames, so only as a possibility)."""
    words = (
        "the Gauss–Markov model does not fit the data (a joint centre fixed in both segments, "
        f"with the noise of the rigid-body fits): {statistic}, p = {p_value:.2g}, "
    )
    if above:
        words += (
            "above what the noise allows: the centre is not fixed in both segments, or the "
            "noise is not the same in every direction"
        )
        if not frame0:
            words += "; gauss-markov-frame0 also models the errors of the frame-0 poses"
    elif given:
        words += "below what the noise allows: noise_mm is larger than the data's noise"
    else:
        words += (
            "below what the noise allows: the rigid-body residuals hold more than the noise "
            "that reaches the centre (markers that move on their segment)"
        )
    if kurtosis > MAX_NOISE_KURTOSIS:
        words += (
            f"; the residuals' excess kurtosis of {kurtosis:.3g}, above {MAX_NOISE_KURTOSIS:g}, "
            "may also be glitches (a marker lost or swapped for a frame)"
        )
    return words


def _fixed_centre_test(
    result: JointCenterResult,
    proximal: SegmentPoses,
    distal: SegmentPoses,
    analytic: _Analytic | None = None,
) -> JointCenterResult:
    """``result``, a least-squares joint centre whose covariance has no model test of its own
    (SCoRE, the analytic centre; paper C's ``gauss-markov``, whose own test is of exact frame-0
    poses and whose SD adds their errors), held to the test of the model it shares with the
    Gauss–Markov fits, one centre fixed in both segments: ``gauss-markov-frame0`` fitted to the
    same poses
    ``proximal`` and ``distal``, with the noise given to ``result``'s fit where one was
    (:func:`_given_noise`), and its model tested (module docstring, "Model test"). That
    test asks whether the data allow any such centre with the rigid-body fits' noise; where it
    rejects, the covariance the answer states from its poses' noise does not describe its
    error (a thigh cluster that slides with the hip angles moves SCoRE's answer by
    centimetres while its SD stays near a millimetre), and a warning says so.
    ``diagnostics["fixed_centre_test"]`` holds the fit's ``chi2`` and ``chi2_dof`` and the
    test's numbers, or ``not_tested`` and why: the fit failed or did not converge, or the two
    segments' rigid-body residuals reject the one noise that model pools for them
    (:func:`_unequal_noise`), which the answer's own covariance does not assume. Frame 0's
    residuals are tested against the other frames' first (:func:`_frame0_noise`): where they
    lie above them, a warning says so (the body frames frame 0 places, and the answer in them,
    carry an error beyond the noise), whatever the rest; ``frame0_p`` holds that test's
    p-value. ``analytic``: the analytic centre of these poses and its ``rcond`` where
    ``result``'s fit found them, the fit's start (:func:`_prepared`)."""
    # Both the noise comparison and the model test ask the same poses where rounding ends: a
    # scan of every coordinate, read once.
    rounding = _rounding_variance((proximal, distal))
    noise = _segments_noise(proximal, distal, rounding)
    frame0_warnings, frame0_numbers = _frame0_noise(noise)
    unequal = _unequal_noise(noise)
    if unequal:
        found = {"fixed_centre_test": {"not_tested": unequal, **frame0_numbers}}
        return with_warnings(result, frame0_warnings, found)
    (fitted,) = _gauss_markov_results(
        [{"proximal": proximal, "distal": distal}],
        noise_mm=_given_noise(result),
        frame0=True,
        max_iterations=_FIT_ITERATIONS,
        tol_mm=_FIT_TOL_MM,
        analytic=[analytic],
    )
    if not (isinstance(fitted, JointCenterResult) and fitted.converged):
        why = str(fitted) if isinstance(fitted, ValueError) else fitted.status
        found = {"fixed_centre_test": {"not_tested": why, **frame0_numbers}}
        return with_warnings(result, frame0_warnings, found)
    shared = (
        "this answer's model is the same (gauss-markov-frame0's fit to the same poses tested "
        f"it), {_SD_NOT_ITS_ERROR}"
    )
    warnings, numbers = _model_verdict(fitted, proximal, distal, shared, rounding)
    tested = {key: fitted.diagnostics[key] for key in ("chi2", "chi2_dof")}
    found = {"fixed_centre_test": {**tested, **numbers, **frame0_numbers}}
    return with_warnings(result, (*frame0_warnings, *warnings), found)


def _given_noise(result: JointCenterResult) -> float | None:
    """The marker noise [mm] given to the fit of ``result``, which its SD is read from, or
    ``None`` where the noise was estimated from the rigid-body residuals (or the method takes
    none): the test the SD is held to is of the same noise."""
    if result.diagnostics.get("noise_source") != "given":
        return None
    return float(result.diagnostics["noise_mm"])


# The noise the fixed-centre model pools. Paper C: "The measurements will be noisy and we
# approximate the true unknown noise distribution by isotropic Gaussian noise n_i(t) with
# variance sigma^2 = Tr(W_y)": one noise for every marker of both segments in every frame,
# frame 0 included, where "the two body fixed coordinate systems coincide with the world
# coordinate system at t = 0". Two tests of the rigid-body residuals ask whether these data
# have it, neither of them Gaussian in the tails: paper A's errors ("The directions of the
# error vectors were uniformly distributed, and the magnitudes of the random errors were
# normally distributed") have an excess kurtosis of 2.4 per coordinate, which widens a
# residual variance's scatter (an F test blind to it said equal noise differs many times more
# often than its level) and most of all one frame's.


@dataclass(frozen=True)
class _SegmentNoise:
    """One segment's rigid-body residuals, frame 0's apart (:func:`_segment_noise`)."""

    dof: int  # of every frame's residuals, 3 (n - 2)(N - 1)
    variance: float  # residual_ss / dof [mm^2]
    n_frames: int
    frame0_ss: float  # frame 0's sum of squared residuals [mm^2]
    rest_variance: float  # the other frames' residual sum of squares over their dof [mm^2]
    rest_fourths: float  # the other frames' sum of |r_i|^4 [mm^4]
    gaussian: float  # G of one frame (:func:`_fit_moments`)
    excess: float  # F of one frame

    def inflation(self, kurtosis: float) -> float:
        """How many times a residual sum of squares of this segment varies more than its
        Gaussian ``2 dof s^4`` for noise of excess ``kurtosis`` (clipped): ``1 + kappa G /
        (6 dof)`` per frame (:func:`_residual_moments`), whatever the number of frames."""
        return 1.0 + kurtosis * self.n_frames * self.gaussian / (6.0 * self.dof)


def _segment_noise(poses: SegmentPoses) -> _SegmentNoise:
    """The residual numbers of one segment's rigid fit ``poses`` that its noise tests read."""
    residual = poses.markers[0] - poses.body @ poses.rotation[0].T - poses.translation[0]
    squares = np.einsum("ij,ij->i", residual, residual)
    frame0_ss, frame0_fourths = float(squares.sum()), float(squares @ squares)
    n_frames = len(poses.markers)
    # Each frame holds a share 1 / N of the dof: the residuals do not depend on the gauge that
    # pins the body frame to frame 0, so frame 0 is fitted as every other frame is.
    rest_dof = poses.dof * (n_frames - 1) / n_frames
    gaussian, excess = _fit_moments(poses, 1)
    return _SegmentNoise(
        dof=poses.dof,
        variance=poses.residual_ss / poses.dof,
        n_frames=n_frames,
        frame0_ss=frame0_ss,
        rest_variance=max(poses.residual_ss - frame0_ss, 0.0) / rest_dof,
        rest_fourths=max(poses.residual_fourths - frame0_fourths, 0.0),
        gaussian=gaussian,
        excess=excess,
    )


def _rest_kurtosis(segments: tuple[_SegmentNoise, ...], rounding: float) -> float:
    """The noise's excess kurtosis, clipped to ``[0, MAX_NOISE_KURTOSIS]``, by the method of
    moments of :func:`_noise_kurtosis` from the frames after frame 0 (an error of frame 0, the
    thing one test looks for, would read as heavy tails and hide itself), each segment's
    fourth moments over its own variance (a noise that differs between the segments, the
    other, would read as heavy tails too). Segments whose residuals are rounding (at or below
    ``rounding`` [mm^2]) have no law to read: 0 where no segment has."""
    fourth, gaussian, excess = 0.0, 0.0, 0.0
    for segment in segments:
        if segment.rest_variance > rounding:
            frames = segment.n_frames - 1
            fourth += segment.rest_fourths / segment.rest_variance**2
            gaussian += frames * segment.gaussian
            excess += frames * segment.excess
    if excess <= 0.0:
        return 0.0
    return min(max((fourth - gaussian) / excess, 0.0), MAX_NOISE_KURTOSIS)


def _segments_noise(
    proximal: SegmentPoses, distal: SegmentPoses, rounding: float
) -> tuple[tuple[_SegmentNoise, ...], float] | None:
    """The two segments' residual numbers (:func:`_segment_noise`) and the noise's kurtosis
    (:func:`_rest_kurtosis`), or ``None`` where there is no noise to test: residuals of
    rounding in both segments (noise-free data, as :func:`_model_verdict` judges them, at or
    below ``rounding``, their :func:`_rounding_variance` [mm^2]; their ratio is rounding over
    rounding), or none at all."""
    segments = tuple(_segment_noise(poses) for poses in (proximal, distal))
    variances = [segment.variance for segment in segments]
    if not (all(np.isfinite(variances)) and min(variances) > 0.0):
        return None
    if max(variances) <= rounding:
        return None
    return segments, _rest_kurtosis(segments, rounding)


def _unequal_noise_p(noise: tuple[tuple[_SegmentNoise, ...], float]) -> tuple[float, float]:
    """``(p, ratio)``: the proximal over distal residual variance and the two-sided p-value of
    the F test that they are equal, each segment's dof divided by its inflation under the
    noise's kurtosis (Satterthwaite, as the model test's; Layard's correction of the variance
    ratio's F test, with the kurtosis read from the residuals)."""
    segments, kurtosis = noise
    proximal, distal = segments
    ratio = proximal.variance / distal.variance
    shape = (
        proximal.dof / proximal.inflation(kurtosis),
        distal.dof / distal.inflation(kurtosis),
        ratio,
    )
    special = scipy_special()
    p_value = min(2.0 * min(float(special.fdtr(*shape)), float(special.fdtrc(*shape))), 1.0)
    return p_value, ratio


def _unequal_noise(noise: tuple[tuple[_SegmentNoise, ...], float] | None) -> str:
    """Why the Gauss–Markov model's one noise does not hold for two segments' poses (their
    :func:`_segments_noise`), or ``""`` where it may: their rigid-body residual variances
    differ at :data:`~jointbench.estimators.support.ROTATION_ALPHA` (:func:`_unequal_noise_p`).
    A noisy pelvis beside a clean thigh breaks the pooled noise, not the fixed centre; SCoRE's
    and the analytic centre's covariances read each segment's own."""
    if noise is None:
        return ""
    p_value, ratio = _unequal_noise_p(noise)
    if p_value >= ROTATION_ALPHA:
        return ""
    return (
        f"the segments' rigid-body noise differs (proximal over distal variance {ratio:.3g}, "
        f"p = {p_value:.2g}), where the Gauss–Markov model pools one noise for both"
    )


def _frame0_noise_p(
    noise: tuple[tuple[_SegmentNoise, ...], float],
) -> tuple[float, list, list]:
    """``(p, ratios, p_values)``: per segment, frame 0's residual per dof over the other
    frames' (:func:`_frame0_ratio`) and the upper tail of the F law of that ratio, its dof
    each divided by the segment's inflation under the noise's kurtosis (Satterthwaite; NaN
    where the segment has no test); and ``p``, the p-value that neither lies above its noise,
    the smaller of the tested segments' p-values times their number (Bonferroni).
    One frame's markers off by more than the noise (a marker's position misread, a cluster
    not yet settled when the recording starts) move the body frame that frame 0 places, and
    with it every centre stated in it."""
    segments, kurtosis = noise
    special = scipy_special()
    ratios, p_values = [], []
    for segment in segments:
        ratio, dofs = _frame0_ratio(segment)
        ratios.append(ratio)
        inflation = segment.inflation(kurtosis)
        p_values.append(
            math.nan
            if math.isnan(ratio)
            else float(special.fdtrc(dofs[0] / inflation, dofs[1] / inflation, ratio))
        )
    tested = [p for p in p_values if not math.isnan(p)]
    if not tested:
        return math.nan, ratios, p_values
    return min(len(tested) * min(tested), 1.0), ratios, p_values


def _frame0_ratio(segment: _SegmentNoise) -> tuple[float, tuple[float, float]]:
    """``(ratio, (dof_0, dof_rest))``: frame 0's residual per dof over that of a fit of the
    other frames alone, F-distributed on ``3 (n - 2)`` and ``3 (n - 2)(N - 2)`` dof for
    Gaussian noise (to first order); NaN where there are no other frames' dof (two frames) or
    residual. The body-fixed coordinates, fitted to every frame, take a share ``1 / N`` of
    frame 0's error away from its residual and pass a share ``1 / (N - 1)`` of it into the
    other frames': to first order frame 0's residual sum of squares ``q`` is ``(N - 1) / N``
    of that left by a fit of the others, which leave ``residual_ss - q N / (N - 1)``. Read off
    the one fit, frame 0's ratio to the others' would be bounded by ``(N - 1)^2`` (on four
    frames of three markers, no error of frame 0 however large could be told from noise),
    and, its two parts sharing frame 0's noise, would reject honest frames below its level."""
    per_frame = segment.dof / (segment.n_frames - 1)
    rest_dof = per_frame * (segment.n_frames - 2)
    left_out = segment.frame0_ss * segment.n_frames / (segment.n_frames - 1)
    rest = segment.variance * segment.dof - left_out
    if rest_dof <= 0.0 or not (rest > 0.0 or left_out > 0.0):
        return math.nan, (per_frame, rest_dof)
    # The others left with no residual (to rounding, by a frame 0 that holds it all): frame 0
    # infinitely off.
    ratio = left_out / per_frame / (rest / rest_dof) if rest > 0.0 else math.inf
    return ratio, (per_frame, rest_dof)


def _frame0_noise(noise: tuple[tuple[_SegmentNoise, ...], float] | None) -> tuple[tuple, dict]:
    """The test of frame 0's noise (:func:`_frame0_noise_p`) on two segments' poses (their
    :func:`_segments_noise`): a warning where it rejects at
    :data:`~jointbench.estimators.support.ROTATION_ALPHA`, and ``frame0_p`` (NaN where there
    is no noise to test)."""
    if noise is None:
        return (), {"frame0_p": math.nan}
    p_value, ratios, p_values = _frame0_noise_p(noise)
    if not p_value < ROTATION_ALPHA:
        return (), {"frame0_p": p_value}
    # The segment whose test rejects: a larger ratio on fewer dof may reject less surely.
    worst = int(np.nanargmin(p_values))
    warning = (
        f"frame 0's markers of the {('proximal', 'distal')[worst]} segment leave "
        f"{ratios[worst]:.3g} times the other frames' rigid-body residual (p = {p_value:.2g}): "
        "the frame-0 pose that places the body frames, and the centre in them, has an error "
        f"beyond the noise the model pools, {_SD_NOT_ITS_ERROR}"
    )
    return (warning,), {"frame0_p": p_value}


def _held_to_the_model(
    scattered: Callable, analytic_of: Callable[[JointCenterResult], _Analytic] | None = None
) -> Callable:
    """The one-trial check ``scattered(result, proximal, distal)`` (a method's covariance on
    its poses) followed by :func:`_fixed_centre_test`, given ``analytic_of(result)``, the
    analytic centre that the method's fit found on the same poses, where it finds one."""

    def check(result: JointCenterResult, proximal: SegmentPoses, distal: SegmentPoses):
        analytic = None if analytic_of is None else analytic_of(result)
        return _fixed_centre_test(scattered(result, proximal, distal), proximal, distal, analytic)

    return check


def _analytic_answer(result: JointCenterResult) -> _Analytic:
    """The analytic centre of an ``analytic`` ``result``: its answer and ``rcond``."""
    return result.center, result.diagnostics["rcond"]


def _gauss_markov_start(result: JointCenterResult) -> _Analytic:
    """The analytic centre a ``gauss-markov`` ``result`` started from and its ``rcond``."""
    return np.array(result.diagnostics["analytic_center"]), result.diagnostics["rcond"]


def _analytic_scattered(
    result: JointCenterResult, proximal: SegmentPoses, distal: SegmentPoses
) -> JointCenterResult:
    """The analytic ``result`` with the covariance of its centre on the poses it was fitted to
    (:func:`jointbench.estimators.pose_noise.analytic_covariance`),
    ``diagnostics["center_covariance_mm2"]``, the share of the poses' noise in the
    information that covariance is first order in
    (:func:`jointbench.estimators.pose_noise.analytic_noise_share`),
    ``["center_sd_noise_share"]``, the share of its variance that is second order in the
    errors of the frame-0 poses, which anchor both body frames
    (:func:`jointbench.estimators.pose_noise.analytic_anchor_share`),
    ``["center_sd_anchor_share"]``, and the mean error those errors cause to second order
    (:func:`jointbench.estimators.pose_noise.anchor_bias_mm`), ``["center_anchor_bias_mm"]``:
    on small swings of the order of the pull, which the checked call adds it to, as it holds
    the noise share to the centres' bound and the anchor share to its own
    (:func:`jointbench.estimators.centre_precision.annotate_joint_centres`;
    ``benchmarks/joint_centre_stated_sd.py`` prints them)."""
    covariance = centre_covariance(
        analytic_covariance, proximal, distal, (result.center, result.center)
    )
    # The frame-0 poses' second-order bias, which the pull of independent frames leaves out
    # and the checked call adds to it (centre_precision.annotate_joint_centres).
    bias = anchor_bias_mm(proximal, distal, result.center)
    anchor = analytic_anchor_covariance(proximal, distal, result.center)
    numbers = {
        "center_covariance_mm2": covariance.tolist(),
        "center_sd_noise_share": analytic_noise_share(proximal, distal),
        "center_sd_anchor_share": float(analytic_anchor_share(anchor, covariance)),
        "center_anchor_bias_mm": bias.tolist(),
    }
    return with_warnings(result, (), numbers)


def _gauss_markov(
    proximal, distal, *, noise_mm, frame0: bool, max_iterations: int, tol_mm: float
) -> JointCenterResult:
    return one_trial(
        _gauss_markov_trials[frame0],
        proximal,
        distal,
        noise_mm=noise_mm,
        max_iterations=max_iterations,
        tol_mm=tol_mm,
    )


def _check_gauss_markov_options(noise_mm, max_iterations, tol_mm) -> None:
    _as_noise(noise_mm)
    if int(max_iterations) < 1 or not tol_mm >= 0:
        raise ValueError("max_iterations must be >= 1 and tol_mm >= 0")


@register("joint_center", "gauss-markov", min_frames=POSE_MIN_FRAMES, color="#2166ac", marker="o")
def fit_gauss_markov(
    proximal: np.ndarray,
    distal: np.ndarray,
    *,
    noise_mm: NonNegative | None = None,
    max_iterations: Count = _FIT_ITERATIONS,
    tol_mm: NonNegative = _FIT_TOL_MM,
) -> JointCenterResult:
    """Paper C's Gauss–Markov joint centre with its predicted covariance (eqs. 11–23).

    Parameters
    ----------
    proximal, distal : (n_frames >= 3, n_markers >= 3, 3) [mm], world frame, same frames.
    noise_mm : ``sqrt(tr W_y)`` of the isotropic marker noise [mm] (RMS length of the 3-D
        error; per-coordinate variance ``noise_mm**2 / 3``). ``None``: estimated from the
        rigid-body fit residuals (module docstring).
    max_iterations, tol_mm : the re-linearisation stops when the centre moves ``<= tol_mm``.

    Returns
    -------
    JointCenterResult
        ``center`` ``(3,)`` [mm] in the body-fixed frame shared at frame 0; ``covariance``
        ``W_c`` ``(3, 3)`` [mm^2], conditional on the two segments' frame-0 poses as paper C
        assumes (see the module docstring, "Frame 0", for what it does not cover);
        ``cost`` the Gauss–Markov chi^2 ``sum_t r_t' W_y,t^-1 r_t``. ``diagnostics``:
        ``noise_mm`` used and its ``noise_source``, ``analytic_center``, ``rcond`` of the
        analytic normal matrix, ``chi2`` and ``chi2_dof`` (``3 (N - 1) - 3``; chi2/dof near 1
        when the noise model fits), ``center_covariance_mm2``, ``W_c`` with the frame-0 poses'
        errors added (module docstring, "Frame 0"), the covariance of the centre in the true
        world frame at frame 0 and the one its checked call holds the answer to. A checked
        call (:func:`jointbench.estimators.registry.get`, :func:`jointbench.fit_joint_center`)
        tests the model on them (module docstring, "Model test"): ``chi2_p``,
        ``noise_kurtosis``, ``chi2_inflation`` and, rejected, a warning.
    """
    return _gauss_markov(
        proximal,
        distal,
        noise_mm=noise_mm,
        frame0=False,
        max_iterations=max_iterations,
        tol_mm=tol_mm,
    )


@register(
    "joint_center", "gauss-markov-frame0", min_frames=POSE_MIN_FRAMES, color="#e6ab02", marker="D"
)
def fit_gauss_markov_frame0(
    proximal: np.ndarray,
    distal: np.ndarray,
    *,
    noise_mm: NonNegative | None = None,
    max_iterations: Count = _FIT_ITERATIONS,
    tol_mm: NonNegative = _FIT_TOL_MM,
) -> JointCenterResult:
    """Gauss–Markov joint centre whose covariance includes the frame-0 pose errors.

    Same inputs and outputs as :func:`fit_gauss_markov`; the model is paper C's plus the
    errors of the frame-0 poses that define the shared body frame (module docstring, "Frame
    0"), so ``covariance`` is the uncertainty of the centre in the true world frame at frame 0.
    ``diagnostics`` adds ``center_proximal`` / ``center_distal`` (the centre in each segment's
    frame as placed by its own frame-0 fit) and their covariances ``covariance_proximal`` /
    ``covariance_distal`` [mm^2], i.e. the uncertainty relative to that segment's markers, and
    ``proximal_body``, the estimated body-fixed proximal markers ``(n, 3)`` that place that
    frame: :func:`align_to_markers` moves ``center_proximal`` into any frame in which those
    markers are known (e.g. a pelvis frame, or a simulation's true marker layout).
    """
    return _gauss_markov(
        proximal,
        distal,
        noise_mm=noise_mm,
        frame0=True,
        max_iterations=max_iterations,
        tol_mm=tol_mm,
    )


def _batched_gauss_markov(frame0: bool):
    def finish_all(
        poses: list,
        *,
        noise_mm: float | None = None,
        max_iterations: int = _FIT_ITERATIONS,
        tol_mm: float = _FIT_TOL_MM,
    ) -> list[JointCenterResult | ValueError]:
        return _gauss_markov_results(
            poses,
            noise_mm=noise_mm,
            frame0=frame0,
            max_iterations=max_iterations,
            tol_mm=tol_mm,
        )

    run = batched_all(finish_all, ("proximal", "distal"))

    def checked(proximal, distal, *, poses=None, **options):
        # Bad options fail every trial, before its poses, as they do one trial at a time.
        try:
            _check_gauss_markov_options(
                options.get("noise_mm"),
                options.get("max_iterations", _FIT_ITERATIONS),
                options.get("tol_mm", _FIT_TOL_MM),
            )
        except ValueError as error:
            return [error] * len(proximal)
        return run(proximal, distal, poses=poses, **options)

    checked.pose_segments = run.pose_segments
    return isolated(checked)


def _analytic_finish(
    prox: PoseStack, dist: PoseStack, *, noise_mm: float | None = None
) -> list[JointCenterResult | ValueError]:
    del noise_mm
    return _analytic_result(prox, dist)


_analytic_trials = batched(_analytic_finish, ("proximal", "distal"))
_gauss_markov_trials = {frame0: _batched_gauss_markov(frame0) for frame0 in (False, True)}

register_many("joint_center", "analytic", _analytic_trials)
register_many("joint_center", "gauss-markov", _gauss_markov_trials[False])
register_many("joint_center", "gauss-markov-frame0", _gauss_markov_trials[True])
# SCoRE's covariance lives with SCoRE; the model test it is held to lives here.
fit_analytic.precision_many = precision_on_poses(
    _held_to_the_model(_analytic_scattered, _analytic_answer)
)
fit_score.precision_many = precision_on_poses(_held_to_the_model(score_scattered))
# Paper C's SD adds the frame-0 poses' errors, the model gauss-markov-frame0 tests: that test
# is its verdict, its own (exact frame-0 poses) only where that one is not made.
fit_gauss_markov.precision_many = precision_on_poses(_paper_c_check)
fit_gauss_markov_frame0.precision_many = precision_on_poses(_frame0_model_test)


def align_to_markers(
    point: np.ndarray,
    covariance: np.ndarray | None,
    markers_from: np.ndarray,
    markers_to: np.ndarray,
) -> tuple[np.ndarray, np.ndarray | None]:
    """Express a point given relative to a marker cluster in another frame of that cluster.

    ``point`` ``(3,)`` [mm] (and its ``covariance`` ``(3, 3)`` [mm^2] or ``None``) is known in
    the frame where the cluster's markers are ``markers_from`` ``(n, 3)``; the result is the
    same body point in the frame where they are ``markers_to`` ``(n, 3)``, via the
    least-squares rigid transform between the two (``R p + t``, ``R W R'``). With
    ``gauss-markov-frame0``'s ``center_proximal``, ``covariance_proximal`` and
    ``proximal_body``, this is the centre relative to the proximal markers, free of the
    frame-0 placement error.
    """
    markers_from = np.asarray(markers_from, dtype=float)
    markers_to = np.asarray(markers_to, dtype=float)
    if markers_from.shape != markers_to.shape or markers_from.ndim != 2:
        raise ValueError(
            f"markers_from and markers_to must both be (n, 3), got {markers_from.shape} "
            f"and {markers_to.shape}"
        )
    rotation, translation = rigid_fit(markers_from, markers_to[None])
    rotation, translation = rotation[0], translation[0]
    moved = rotation @ np.asarray(point, dtype=float) + translation
    if covariance is None:
        return moved, None
    return moved, rotation @ np.asarray(covariance, dtype=float) @ rotation.T
