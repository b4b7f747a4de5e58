"""Whether marker data can support a joint centre or axis at all: one check for every estimator.

An estimator answers the question it is asked even when the data cannot: a static cluster
with noise, or markers that are not one rigid body, still yield a confident-looking centre.
This module judges the data, not the answer, by three tests on the moving cluster (three or
more non-collinear markers), each first order in the noise:

* Rigidity. The rigid-body residual per degree of freedom, ``s^2`` [mm^2], is the noise a rigid
  body would have; the markers' scatter about each frame's centroid per degree of freedom,
  ``v = sum |x - mean x|^2 / (3 (n - 1) N)``, is what the cluster's shape must explain. For a
  rigid body with noise, ``s^2 / v = s^2 / (s^2 + r^2)`` with ``r^2`` the shape's own spread per
  coordinate: the noise's share of the scatter. When it reaches :data:`MAX_NONRIGID_SHARE` the
  noise is more than ``1 / sqrt(3)`` of the shape it would be fitted to, so there is no shape to
  speak of and the markers are reported as not one rigid body.
* Range of motion. The rotation of the moving segment relative to the reference (the identity
  for one-segment data; the proximal segment's pose for two-segment data) against what noise
  alone produces: F-distributed when the segment does not rotate. A rotation not significant
  at the level :data:`ROTATION_ALPHA` is too small to support a centre or axis: whatever an
  estimator returns is fitted to noise.
* A second axis. For a centre (:data:`CENTRE_KINDS`) the rotation must also span a second
  axis, since rotation about one axis leaves the centre undetermined along it; tested the same
  way against "a hinge plus noise".
* One axis. For an axis, the same test resolving rotation about a second axis is not enough to
  refuse one (paper B studies hinges with a smaller AA rotation on top), but when
  :data:`MAX_OFF_AXIS_SHARE` of the rotation or more is about axes other than its principal one
  no single axis describes the motion, and whatever axis a method returns is a compromise that
  depends on its cost. The share is measured on the rotations themselves, which holds at any
  range and wherever the markers sit: the rotation vectors about their mean pose, less their
  noise, split between the principal axis and the others by their scatter's eigenvalues
  (the rotations carry the shape of the frame nearest the markers' mean positions, which no
  order of the frames changes, onto each frame's; a recording of more than
  ``_SHARE_FRAMES`` frames is sampled at evenly spaced frames in the order given).
  The principal axis itself, with its SD from the rotations' noise, is the motion's own axis
  (:class:`MotionAxis`), which the verdict on one segment carries for the registry to compare
  every axis answer with (:func:`jointbench.estimators.precision.annotate_motion_axis`),
  with how far the segment travels along that axis as it turns (:class:`Travel`: a hinge's
  does not), which the costs whose model excludes it are held to
  (:func:`jointbench.estimators.precision.annotate_travel`).
* Independent frames. Every test above, and every SD or covariance a method states, counts
  each frame's noise as new. The markers' pair distances, which the rigid motion leaves alone,
  then vary independently from frame to frame, and the mean of ``L`` consecutive frames'
  deviations (``d``, from each pair's mean, in the frames' order) varies as ``1 / L`` of one
  frame's. The ratio of the two, ``V_L = L var(block means) / var(d)`` pooled over the pairs,
  is then near 1 at every ``L``; over ``B`` blocks of noise of one variance, ``(B - 1) V_L``
  is about chi-square with ``B - 1`` degrees of freedom for one pair, and pooled over pairs
  spreads less. Errors shared over ``m`` frames raise it towards the correlation time
  ``tau``, the factor by which the mean's variance exceeds independent frames'. It is taken at
  ``L = 2, 4, 8, ...`` while at least :data:`MIN_BLOCKS` blocks remain, each against its
  chi-square quantile (Wilson and Hilferty's, with Satterthwaite's degrees of freedom, fewer
  where a few blocks carry the noise) at :data:`ROTATION_ALPHA` shared among the lengths.
  Where some ``V_L`` is resolved and at least :data:`MIN_VARIANCE_RATIO`, the frames are
  reported as not independent, holding about ``N / tau`` independent ones (``tau`` summed
  from the distances' autocorrelations, :func:`_independent_frames`): frames interpolated,
  filtered or resampled, and markers moving on the skin or sliding on their segment, share
  their errors from frame to frame, and a slow drift too small to correlate neighbouring
  frames still moves the means of long blocks. The lag-1 autocorrelation is reported beside
  it. This one test reads the frames' order, being about their sequence: shuffled frames hide
  it. Of two segments, the one further from independent frames is reported; markers that give
  no pose are read the same way (the moving ones). What it cannot see: a single marker, and
  errors every marker of a segment shares (a rigid wobble, or a smoothed reference segment's
  pose carried into the moving markers' coordinates), which keep the distances; nor
  noise-free data. Below ``4 MIN_BLOCKS`` frames (:data:`MIN_TESTED_FRAMES`) no ratio can
  reach its quantile, and the test is not made; above, few blocks leave it little power: over
  32 frames the ratios must reach 2.7 over 16 blocks of 2 frames or 3.8 over 8 of 4, above
  the 1.9 and 3.4 of noise keeping 0.87 of itself from frame to frame (``tau`` 14). Wherever
  the test does not find the frames not independent, too few to test or not, the lag-1
  autocorrelation is read too, and where it is not clearly below
  :data:`DEPENDENT_CORRELATION` the verdict says so (:class:`Untested`).

Noise-free data (a residual at rounding level, :data:`ROUNDING`) leave nothing to test
against: a rotation above 1e-8 rad RMS is resolved, and rotation about a second axis is when
its sum of squares is above ``1e-12`` of the main rotation's.

One segment (``center``, ``axis``: markers in the reference frame) needs no pose, and is
judged from sums over the frames, in one compiled call: a pass over the markers that keeps
each frame's centred markers and marker-pair differences, one over the centred markers about
their mean positions, and one over the differences per set of distances (the cluster's own,
then its projections on the two candidate hinge planes below):

* ``s^2`` from the inter-marker distances, which a rigid body keeps in any pose: to first order
  the rigid fit's residual is ``sum_k dd_k' G+ dd_k`` over the frames' distance deviations
  ``dd_k`` from their means, with ``G = J J'`` and ``J`` the distances' Jacobian at the mean
  shape (its entries follow from the mean distances by the law of cosines; a second time
  from the mean squared distances less their noise, ``6 s^2`` per pair, once ``s^2`` is
  known). ``G``'s rank, ``3 n - 6`` for a non-degenerate cluster, sets the degrees of freedom,
  ``rank (N - 1)``. A mode weaker than :data:`_FLEX` of the strongest, or whose first-order
  signal is under 3 times the second-order one noise adds to a flex (``s^2 / d``, ``d`` the
  RMS distance), is a flex of a (nearly) flat or collinear cluster, which moves no distance to
  first order, and is not counted.
* Rotation: the scatter of the centred markers about their mean positions is the rotation's
  sum of squares plus the rigid residual, so their difference, with
  ``(3 (n - 1) - rank)(N - 1)`` degrees of freedom, is tested against ``s^2``. Its RMS angle is
  the one that displaces the markers as much, ``(2/3) sum |u|^2`` being the inertia about an
  axis averaged over axes.
* A second axis: about a hinge axis ``h`` every marker moves in a plane normal to ``h`` and the
  cluster's projection on that plane is a rigid plane figure, at any range of motion. The
  markers' motion along ``h`` plus the projection's distance residual (as above, in 2-D),
  less the cluster's own residual, is what a hinge about ``h`` leaves unexplained, with
  ``(n - 1 + rank_2D - rank)(N - 1)`` degrees of freedom (2 (N - 1) for a non-degenerate
  cluster). It is taken about two candidate axes: the direction the markers move least along
  (exact for a hinge of any range, poor for a small one) and the principal axis of the
  rotations from the markers' mean positions (each frame's centred markers averaged over the
  frames), linearised and whitened by their noise (good for a small rotation); the hinge gets
  the candidate that explains the data better. The mean positions are the shape at the mean
  pose to first order, with a noise of ``s^2 / N``; a single frame as the reference (the
  first, say) would bring its own noise and its place in the motion into the axis, so that
  reordering the frames could change the verdict. Every sum above is over the frames, so the
  verdict does not depend on their order. A projection that keeps no plane
  figure (the rigidity share above, in 2-D) is no hinge's. Taking the better of two axes makes
  the test conservative; ``tests/test_support_calibration.py`` measures its rates on pure
  hinges and static clusters.

Two segments (``joint_center``: both clusters in the world) are judged from their rigid-body
poses, those of :func:`jointbench.estimators.segment_poses.trial_poses` that the pose-based
estimators fit (a checked call fits them once, for the estimator and the verdict; a trial
whose poses cannot be fitted is judged without them; poses whose fit stopped before
converging are judged as they are, and the estimator's result says they stopped):
``s^2 = RSS / (3 (n - 2)(N - 1))`` pooled over the clusters; with
``w_k`` the distal segment's rotation vector relative to the proximal one about their mean and
``S`` its noise covariance (``s_c^2 K^-1`` with ``K = sum_i (|u_i|^2 I - u_i u_i')`` the inertia
of the centred body-fixed markers, Pennec & Thirion's pose covariance, and ``s_c^2`` the
cluster's own residual per coordinate, plus the proximal cluster's term mapped into the distal
frame: a compact cluster is no noisier for a noisier neighbour, nor that one less noisy),
``sum_k w_k' S^-1 w_k / (3 (N - 1))``, with ``S`` read as a multiple of the pooled ``s^2``, is
about F-distributed with ``(3 (N - 1), dof)`` degrees of freedom when the segment does not
rotate (where one segment's noise dominates ``S``, its own degrees of freedom, fewer, are the
truer denominator's).
Rotation about a second axis is what a hinge leaves unexplained, tested the same way with
``(2 (N - 2), dof)``: the least ``sum_k r_k' S_k^-1 r_k`` over an axis ``h``, an offset and an
angle per frame, ``r_k = w_k - c - theta_k h`` (:func:`_hinge_residual`). ``S`` holds at the
mean pose only: frame ``k``'s noise ``S_k`` has the proximal cluster's term turned by that
frame's own relative rotation, and both terms carried through the logarithm's Jacobian at
``w_k`` (:func:`_frame_noise_into`), which turns them by half the frame's angle about the axis,
each the other way. With ``S`` alone for every frame (the two smaller eigenvalues of the
whitened scatter), pure hinges of three-marker clusters (far from isotropic inertia) swung 30
degrees passed as rotating about two axes in 29 of 100 trials of 300 frames and 42 of 100 of
1200 at the level of a thousandth (``tests/test_support_off_axis_level.py``). Yet ``S_k`` is
evaluated at the noisy ``w_k``: where the noise turns the frames more than the motion does
(nearly collinear clusters, poses uncertain by 10 degrees or more about their line, a small
swing) that leaks the noise about a cluster's line into the directions it fixes, and ``S``
is the truer. The hinge is read against whichever leaves it less, which makes the test
conservative where both hold (on those pure hinges ``S_k`` always leaves less).

The verdict is a list of warnings; :func:`annotate` writes them into a result's ``status`` and
its numbers into ``diagnostics["support_..."]``. It never changes ``converged``, which keeps the
meaning each method's paper gives it (so a hard but legitimate condition, e.g. a small range
of motion with large noise, is warned about, not dropped from a study).
"""

from __future__ import annotations

import functools
import math
import operator
import statistics
from typing import NamedTuple

import numpy as np

from jointbench.estimators import noise_directions as by_direction
from jointbench.estimators.batching import check_poses
from jointbench.estimators.noise_directions import inverse_gram_into, row_length, trial_test_into
from jointbench.estimators.pose_noise import NoisyPoses, PoseNoise, pose_noise
from jointbench.estimators.results import PRECISION_NOT_DETERMINED, REFUSED, with_warnings
from jointbench.estimators.segment_poses import SegmentPoses, trial_poses
from jointbench.estimators.validation import ARRAY_NAMES, check_markers
from jointbench.geometry import rotation_vector
from jointbench.numerics.compiled import kernel, kernel_array
from jointbench.numerics.distances import distance_modes_into
from jointbench.numerics.magnitudes import largest_magnitude
from jointbench.numerics.poses import _horn_rotations, best_rotation
from jointbench.numerics.reuse import one_call, remembered
from jointbench.numerics.small import (
    inertia_into,
    rotated9_upper,
    rows9,
    symmetric_eigen_into,
    tangent_basis_into,
    transposed_times9,
)
from jointbench.numerics.special import f_survival, scipy_special
from jointbench.numerics.spheres import ls_system, solve_ls_system
from jointbench.screening import _pair_distances, _pair_distances_into

__all__ = [
    "CENTRE_KINDS",
    "DEPENDENT_CORRELATION",
    "MAX_DISTANCE_MARKERS",
    "MAX_NONRIGID_SHARE",
    "MAX_OFF_AXIS_SHARE",
    "MAX_POSE_SD_RAD",
    "MIN_BLOCKS",
    "MIN_JUDGED_FRAMES",
    "MIN_TESTED_FRAMES",
    "MIN_VARIANCE_RATIO",
    "ROTATION_ALPHA",
    "ROUNDING",
    "MotionAxis",
    "Support",
    "Travel",
    "Untested",
    "annotate",
    "assess",
    "assess_many",
]

#: A rotation the data cannot tell from noise at this significance level is "not resolved": a
#: recording that does not rotate is passed as rotating in one trial in a thousand.
ROTATION_ALPHA = 1e-3

#: Markers are not one rigid body when the rigid fit leaves this share of their scatter about
#: the centroid unexplained (noise above 1 / sqrt(3) of the shape's spread; module docstring).
MAX_NONRIGID_SHARE = 0.25

#: The kinds whose answer is a centre, which rotation about a single axis leaves undetermined.
CENTRE_KINDS = ("center", "joint_center")

#: An axis is not the motion's when this share of the rotation's sum of squares about the mean
#: pose, or more, is about axes other than its principal one (and that rotation is resolved):
#: the same quarter as :data:`MAX_NONRIGID_SHARE`, the part no single axis explains. Paper B's
#: motions (every FE angle with every AA angle, AA ``ratio`` times FE) leave
#: ``ratio^2 / (1 + ratio^2)`` off the FE axis, 0.2 at ratio 0.5 and 0.33 at 0.7; its Table 1
#: has the combined cost within 10 deg at 0.5 (FE 30 and 60 deg) and every cost 17 to 81 deg
#: off at 0.7.
MAX_OFF_AXIS_SHARE = 0.25

# The frames, evenly spaced, whose poses measure that share: a share of a smooth motion's
# rotation needs no more, and it keeps the pose fits of a long recording cheap.
_SHARE_FRAMES = 240

#: A rigid-body residual (RMS per coordinate) below this fraction of the largest coordinate is
#: rounding, not noise: the data are treated as noise-free. Rounding leaves ~1e-16 of the
#: coordinates; the pose fits and the sums above it amplify that by a few orders.
ROUNDING = 1e-12

#: A pose whose rotation about the cluster's weakest axis has a noise SD above this [rad], about
#: 29 degrees, is left to the noise: first-order error theory no longer describes it. Paper A's
#: smallest marker set (M) with its largest noise (2 mm) reaches 13 degrees and is a studied,
#: legitimate condition; three collinear markers with 0.3 mm noise reach 46 degrees.
MAX_POSE_SD_RAD = 0.5

#: The frames are "not independent" when the means of the markers' distances over blocks of
#: frames vary this many times as much as those of independent frames would (module
#: docstring), resolved at :data:`ROTATION_ALPHA`: an SD that counts every frame then
#: understates the scatter by ``sqrt(1.5) = 1.22`` times or more, above the 1.1 times
#: (``sqrt(1 + 0.2)``) that :data:`jointbench.estimators.centre_precision.MAX_SD_NOISE_SHARE`,
#: a noise share of 0.2, lets a first-order SD understate it.
MIN_VARIANCE_RATIO = 1.5

#: A block length is tested only where it leaves at least this many blocks: the variance of
#: fewer means is itself too uncertain (a chi-square of 7 degrees of freedom or fewer), so
#: fewer than twice as many frames are not read.
MIN_BLOCKS = 8

#: The fewest frames the verdict judges: its tests of a straight line and of a hinge have
#: ``2 (N - 2)`` degrees of freedom (module docstring; :func:`_without_poses`), none in two
#: frames, where random markers that are no rigid body were judged with no warning at all.
MIN_JUDGED_FRAMES = 3

#: The fewest frames whose independence the verdict can test: below four times its fewest
#: blocks no variance ratio can reach its quantile (module docstring, "independent frames").
MIN_TESTED_FRAMES = 4 * MIN_BLOCKS

#: The lag-1 autocorrelation ``r`` at which noise that keeps that share of itself from frame to
#: frame reaches :data:`MIN_VARIANCE_RATIO` (its correlation time ``(1 + r) / (1 - r)``): 0.2.
#: Where the block test does not find the frames not independent (too few to test, or the test
#: did not reject them) the verdict says so unless their lag-1 autocorrelation is clearly below
#: it (:class:`Untested`).
DEPENDENT_CORRELATION = (MIN_VARIANCE_RATIO - 1.0) / (MIN_VARIANCE_RATIO + 1.0)

# A lag-1 autocorrelation is "clearly below" DEPENDENT_CORRELATION when it is below it by this
# many of the SDs that independent frames give it: the one-sided normal quantile at 5 %. A
# short series' correlation reads low (by about (1 + 3 r) / N), so frames just at the bound are
# cleared more often than that: 1 to 20 in 100 trials of 22 frames (README).
_Z_CLEARED = statistics.NormalDist().inv_cdf(0.95)

# The one-sided normal quantiles at ROTATION_ALPHA shared among k = 1, 2, ... tests (Bonferroni):
# a recording tests one block length per doubling of its frames past 2 MIN_BLOCKS, so these
# serve up to 2^36 frames.
_Z_SHARED = np.array(
    [statistics.NormalDist().inv_cdf(1.0 - ROTATION_ALPHA / k) for k in range(1, 33)]
)

# In noise-free data, a rotation below this is rounding (a noise-free hinge leaves ~5e-10 rad).
_ROUNDING_ROTATION_RAD = 1e-8

#: The most markers of one segment whose pairwise distances the one-segment verdict compares.
#: Its distance Gram matrix has a row per pair, ``n (n - 1) / 2``, and its eigen-decomposition
#: costs about ``n^6``: 20 markers take under a second, 40 a minute, 120 (an array of 120
#: frames of 4 markers passed as ``(markers, frames, 3)``) hours. A larger cluster is judged as
#: one without a pose (:func:`_without_poses`), and its status says what was not tested.
MAX_DISTANCE_MARKERS = 20

_LABELS = {"markers": "markers", "proximal": "proximal markers", "distal": "distal markers"}


class Support(NamedTuple):
    """The verdict on a data set: ``warnings`` (empty when it supports an answer) and the
    numbers behind it (``diagnostics``: ``rigid_residual_mm`` the RMS 3-D residual of the
    rigid-body fits, ``nonrigid_share`` the larger ``s^2 / v`` of the clusters,
    ``rotation_rms_deg`` the RMS rotation about the mean relative pose [deg] (for one segment,
    the angle that displaces the markers as much),
    ``rotation_p_value`` the p-value of "the segment does not rotate", and
    ``off_axis_rotation_rms_deg`` and ``off_axis_p_value`` the same for rotation about all but
    the dominant axis); for one segment's markers judged for an axis from their poses,
    ``motion_axis``, the principal axis of the segment's rotations (:class:`MotionAxis`), else
    ``None``; and ``caveats``, warnings that qualify every number of the fit without saying
    the data cannot support an answer (frames that are not independent), which the status
    carries after the warnings and the checks of an answer's precision do not read as a
    refusal; for two segments' poses judged for a joint centre, ``pose_noise``, what their
    noise does to a least-squares centre (:class:`jointbench.estimators.pose_noise.PoseNoise`),
    which the registry holds every joint-centre answer to, else ``None``; and ``untested``,
    for a trial without the caveat (too few frames to test, or the test did not reject them)
    whose lag-1 autocorrelation is not clearly below :data:`DEPENDENT_CORRELATION`, that the
    frames' independence was not established (:class:`Untested`), else ``None``. The status
    carries it after the caveats, as one of them: a warning (the status is no longer ``ok``)
    that the other checks do not read as a refusal. For one segment's markers with a pose and
    noise above rounding, ``noise_directions``, whether their noise is the same in every
    direction (:class:`jointbench.estimators.noise_directions.NoiseDirections`), which
    :func:`annotate` holds the answer's stated SD to, else ``None``."""

    warnings: tuple[str, ...]
    diagnostics: dict
    motion_axis: MotionAxis | None = None
    caveats: tuple[str, ...] = ()
    pose_noise: PoseNoise | None = None
    untested: Untested | None = None
    noise_directions: by_direction.NoiseDirections | None = None


class _Clusters(NamedTuple):
    """Rigid-body fits of one segment in each of ``T`` trials."""

    rotation: np.ndarray  # (T, N, 3, 3)
    inertia_inv: np.ndarray  # (T, 3, 3) [mm^-2]
    weakest_variance: np.ndarray  # (T,) largest eigenvalue of inertia_inv [mm^-2]
    body: np.ndarray  # (T, n, 3) body-fixed markers [mm]
    residual_ss: np.ndarray  # (T,) [mm^2]
    largest: np.ndarray  # (T,) largest absolute coordinate [mm]
    dof: int
    nonrigid_share: np.ndarray  # (T,) s^2 / v, see the module docstring

    @property
    def variance(self) -> np.ndarray:
        """``(T,)`` the rigid-body residual per coordinate, ``s^2`` [mm^2]."""
        return self.residual_ss / self.dof


def _poses_defined(markers: np.ndarray) -> bool:
    """Whether every trial's clusters ``(T, N, n, 3)`` can define a pose (3 non-collinear
    markers at frame 0, two frames or more)."""
    _, n_frames, n_markers, _ = markers.shape
    if n_markers < 3 or n_frames < 2:
        return False
    return bool(_first_frame_spread(kernel_array(markers)).all())


@kernel
def _centred_into(points: np.ndarray, centred: np.ndarray) -> None:
    """``points`` ``(n, 3)`` less their centroid, written into ``centred`` ``(n, 3)``. A
    compiled kernel."""
    n_points = points.shape[0]
    for i in range(3):
        mean = 0.0
        for m in range(n_points):
            mean += points[m, i]
        mean /= n_points
        for m in range(n_points):
            centred[m, i] = points[m, i] - mean


@kernel
def _first_frame_spread(markers: np.ndarray) -> np.ndarray:
    """Per trial of ``markers`` ``(T, N, n, 3)``: whether the centred frame-0 cluster's second
    singular value exceeds 1e-6 of its first (not collinear). A compiled kernel."""
    n_trials, _, n_markers, _ = markers.shape
    spread = np.empty(n_trials, dtype=np.bool_)
    centred = np.empty((n_markers, 3))
    for t in range(n_trials):
        _centred_into(markers[t, 0], centred)
        # Without the (n, n) left singular vectors a full SVD would make of many markers.
        singular = np.linalg.svd(centred, False)[1]
        spread[t] = singular[1] > 1e-6 * singular[0]
    return spread


@kernel
def _scatter_and_largest(
    markers: np.ndarray, body: np.ndarray, inertia_inv: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per trial of ``markers`` ``(T, N, n, 3)`` [mm] with body-fixed coordinates ``body``
    ``(T, n, 3)`` [mm]: writes the inverse of the centred body's inertia
    ``K = sum_m (|u_m|^2 I - u_m u_m')`` into ``inertia_inv`` ``(T, 3, 3)`` [mm^-2]; returns the
    markers' scatter about each frame's centroid [mm^2], the largest eigenvalue of ``K^-1``
    [mm^-2] and the largest absolute coordinate [mm], ``(T,)`` each. A compiled kernel."""
    n_trials, n_frames, n_markers, _ = markers.shape
    scatter = np.empty(n_trials)
    weakest = np.empty(n_trials)
    largest = np.empty(n_trials)
    centred = np.empty((n_markers, 3))
    tensor = np.empty((3, 3))
    for t in range(n_trials):
        # The sums in locals, not in the arrays: a store per marker costs the pass its speed.
        trial_scatter = 0.0
        trial_largest = 0.0
        for f in range(n_frames):
            for i in range(3):
                mean = 0.0
                for m in range(n_markers):
                    mean += markers[t, f, m, i]
                    trial_largest = max(trial_largest, abs(markers[t, f, m, i]))
                mean /= n_markers
                for m in range(n_markers):
                    trial_scatter += (markers[t, f, m, i] - mean) ** 2
        scatter[t] = trial_scatter
        largest[t] = trial_largest
        for i in range(3):
            mean = 0.0
            for m in range(n_markers):
                mean += body[t, m, i]
            mean /= n_markers
            for m in range(n_markers):
                centred[m, i] = body[t, m, i] - mean
        inertia_into(centred, tensor)
        inertia_inv[t] = np.linalg.inv(tensor)
        weakest[t] = np.linalg.eigvalsh(inertia_inv[t])[2]
    return scatter, weakest, largest


def _clusters(markers: np.ndarray, poses: list[SegmentPoses]) -> _Clusters:
    """The rigid-body fits of one segment's markers ``(T, N, n, 3)`` [mm] in ``T`` trials from
    their poses ``poses`` (one :class:`SegmentPoses` per trial, fitted to those markers)."""
    _, n_frames, n_markers, _ = markers.shape
    rotation = np.stack([pose.rotation for pose in poses])
    body = np.stack([pose.body for pose in poses])
    residual_ss = np.array([pose.residual_ss for pose in poses])
    inertia_inv = np.empty((len(poses), 3, 3))
    scatter, weakest, largest = _scatter_and_largest(
        kernel_array(markers), kernel_array(body), inertia_inv
    )
    dof = 3 * (n_markers - 2) * (n_frames - 1)
    return _Clusters(
        rotation=rotation,
        inertia_inv=inertia_inv,
        weakest_variance=weakest,
        body=body,
        residual_ss=residual_ss,
        largest=largest,
        dof=dof,
        nonrigid_share=(residual_ss / dof) / (scatter / (3 * (n_markers - 1) * n_frames)),
    )


#: The columns of :func:`_one_segment_numbers`, per trial: the rigid residual per coordinate
#: [mm^2], the non-rigid share, the pose's SD about the weakest axis [rad], 1.0 for a collinear
#: mean shape and the residual's degrees of freedom; then per test (any rotation; off the hinge
#: about each candidate axis) the RMS rotation [rad], the F ratio and its numerator's degrees
#: of freedom; the frame nearest the markers' mean positions (the motion axis's reference);
#: and how the frames depend on each other (:func:`_frame_dependence`: the lag-1
#: autocorrelation, the variance ratio furthest beyond independent frames', its block length
#: [frames] and that excess).
_ONE_SEGMENT_COLUMNS = (
    "variance",
    "nonrigid_share",
    "weakest_pose_sd_rad",
    "collinear",
    "residual_dof",
    "rotation_rms_rad",
    "rotation_f",
    "rotation_dof",
    "least_moving_rms_rad",
    "least_moving_f",
    "least_moving_dof",
    "rotation_axis_rms_rad",
    "rotation_axis_f",
    "rotation_axis_dof",
    "central_frame",
    "frame_correlation",
    "variance_ratio",
    "variance_ratio_block",
    "variance_ratio_excess",
)
# The column of the frame whose centred markers are nearest their mean positions.
_CENTRAL_FRAME = _ONE_SEGMENT_COLUMNS.index("central_frame")
# The first column of each test's (RMS [rad], F ratio, its numerator's degrees of freedom):
# any rotation, and off the hinge about each candidate axis.
_ROTATION_TEST = _ONE_SEGMENT_COLUMNS.index("rotation_rms_rad")
_LEAST_MOVING_TEST = _ONE_SEGMENT_COLUMNS.index("least_moving_rms_rad")
_ROTATION_AXIS_TEST = _ONE_SEGMENT_COLUMNS.index("rotation_axis_rms_rad")
# The columns of the residual's degrees of freedom and of the frames' dependence's excess.
_RESIDUAL_DOF = _ONE_SEGMENT_COLUMNS.index("residual_dof")
_EXCESS = _ONE_SEGMENT_COLUMNS.index("variance_ratio_excess")
# The columns of the frames' dependence (:func:`_frame_dependence`).
_DEPENDENCE = slice(
    _ONE_SEGMENT_COLUMNS.index("frame_correlation"),
    _ONE_SEGMENT_COLUMNS.index("variance_ratio_excess") + 1,
)

#: The columns of :func:`_frame_numbers` per trial, which :func:`_one_segment_numbers` ends with.
_FRAME_COLUMNS = 5

# A mode of a distance Gram matrix this much weaker than the strongest is a flex of a (nearly)
# flat or collinear cluster, which moves no distance to first order: it is not counted as shape.
_FLEX = 1e-2


@kernel
def _one_segment_numbers(markers: np.ndarray, flex: float) -> np.ndarray:
    """The numbers of the one-segment verdict (module docstring) for ``markers``
    ``(T, N, n >= 3, 3)`` [mm]: per trial the columns of :data:`_ONE_SEGMENT_COLUMNS`, from
    one pass over the frames' markers, which keeps each frame's centred markers and
    marker-pair differences, one over the centred markers about their mean positions, and
    one over the differences per set of distances (the cluster's, then its two projections).
    Modes of a distance Gram matrix weaker than ``flex`` times its
    strongest are flexes, not shape. After those columns, the test of whether the markers'
    noise is the same in every direction
    (:func:`jointbench.estimators.noise_directions.trial_test_into`), from the first pass's
    centred markers, differences and distances and the cluster's own distance modes, where the
    residual is above rounding and the frames are not found dependent (else its first column
    is NaN and its frames' blocks are the caller's to choose). Last, the trial's row of
    :func:`_frame_numbers`, which the lag-1 statement reads (:class:`Untested`), from the
    cluster's own distances' dependence and scatter, which the pass forms anyway: one dispatch
    for the whole verdict. A compiled kernel."""
    n_trials, n_frames, n_markers, _ = markers.shape
    n_pairs = n_markers * (n_markers - 1) // 2
    n_columns = len(_ONE_SEGMENT_COLUMNS)
    at_frames = n_columns + row_length(n_markers)
    out = np.zeros((n_trials, at_frames + _FRAME_COLUMNS))
    inverse_gram = np.empty((n_pairs, n_pairs))
    pair_a = np.empty(n_pairs, dtype=np.int64)
    pair_b = np.empty(n_pairs, dtype=np.int64)
    p = 0
    for a in range(n_markers):
        for b in range(a + 1, n_markers):
            pair_a[p] = a
            pair_b[p] = b
            p += 1
    # Work arrays, reused by every trial.
    differences = np.empty((n_pairs, 3, n_frames))
    # The distances per frame, and a row of ones (_distance_moments).
    lengths = np.ones((n_pairs + 1, n_frames))
    n_terms = n_pairs + n_pairs * (n_pairs + 1) // 2
    left = np.full(4 * ((n_terms + 3) // 4), n_pairs)
    right = np.full(left.shape[0], n_pairs)
    k = n_pairs
    for p in range(n_pairs):
        left[p] = p
        for q in range(p, n_pairs):
            left[k] = p
            right[k] = q
            k += 1
    terms = (left, right, np.empty(left.shape[0]))
    # Work arrays of one shape share an allocation, taken apart by their first index: a few
    # allocations in place of some thirty, a measurable share of a one-trial call. (The BLAS
    # products' operands below keep allocations of their own.)
    by_pair = np.empty((9, n_pairs))
    pair_squares = np.empty((7, n_pairs, n_pairs))
    # Each frame's centred markers, and after them their mean positions.
    by_frame = np.empty((n_frames + 1, n_markers, 3))
    marker_squares = np.empty((4, n_markers, n_markers))
    per_marker = np.empty((2, n_markers))
    small = np.empty((3, 3))
    small_squares = np.empty((2, 3, 3))
    # Three sets of distances: the cluster's own (set 0), and those of its projections on the
    # planes normal to the two candidate hinge axes (sets 1 and 2).
    planes = np.empty((3, 2, 3))
    first_d = by_pair[0:3]
    sum_d = by_pair[3]
    scatter_d = pair_squares[0:3]
    mean_sq = by_pair[4:7]
    residual = small[0]
    rank = small[1]
    off_axis = small[2]
    flat = np.zeros(2, dtype=np.bool_)
    positions = by_frame[:n_frames]
    mean_c = by_frame[n_frames]
    pooled = small_squares[0]
    vectors3 = small_squares[1]
    inverse = np.empty((3, 3))
    root = np.empty((3, 3))
    outer_w = np.empty((3, 3))
    whitened = np.empty((3, 3))
    axes = np.empty((2, 3))
    values3 = np.empty(3)
    principal = np.empty(3)
    work3 = np.empty((3, 3))
    mean_d = by_pair[7]
    squared = marker_squares[0]
    row_sums = per_marker[0]
    gram = marker_squares[1]
    mu = per_marker[1]
    vectors_n = marker_squares[2]
    work_n = marker_squares[3]
    scratch = (
        squared,
        pair_squares[6],
        pair_squares[3],
        by_pair[8],
        pair_squares[4],
        pair_squares[5],
    )
    for t in range(n_trials):
        trial = markers[t]
        # Scalar sums: the pooled scatter of the displacements e about the mean positions, and
        # the linearised rotations w and their outer products (upper triangles). Both e and w
        # sum to zero over the frames, so these are their scatters about their means.
        e00 = e01 = e02 = e11 = e12 = e22 = 0.0
        w00 = w01 = w02 = w11 = w12 = w22 = 0.0
        largest = 0.0
        mean_c[:] = 0.0
        # First pass: each frame's centred markers, their sum over the frames, and their pair
        # differences.
        for f in range(n_frames):
            centred = positions[f]
            for i in range(3):
                total = 0.0
                for m in range(n_markers):
                    total += trial[f, m, i]
                mean = total / n_markers
                for m in range(n_markers):
                    centred[m, i] = trial[f, m, i] - mean
                    mean_c[m, i] += centred[m, i]
                    largest = max(largest, abs(trial[f, m, i]))
            # The pairs by their markers, not through pair_a and pair_b: two loads less per
            # difference, in the loop that costs the most.
            p = 0
            for a in range(n_markers):
                for b in range(a + 1, n_markers):
                    differences[p, 0, f] = centred[a, 0] - centred[b, 0]
                    differences[p, 1, f] = centred[a, 1] - centred[b, 1]
                    differences[p, 2, f] = centred[a, 2] - centred[b, 2]
                    p += 1
        # The reference of the linearised rotations: the markers' mean positions, the shape
        # at the mean pose to first order, which no frame's noise or place in the motion (nor
        # the frames' order) decides. Its inertia sum |u|^2 I - sum u u', inverse and square
        # root give the rotations and their noise.
        for m in range(n_markers):
            for i in range(3):
                mean_c[m, i] /= n_frames
        inertia_into(mean_c, work3)
        _inverse_and_root(work3, inverse, root, (values3, vectors3, whitened))
        # Second pass: the markers' displacements e from their mean positions, the rotations
        # about those, linearised, and the frame nearest those positions (the first of equals).
        nearest = np.inf
        for f in range(n_frames):
            moment0 = 0.0
            moment1 = 0.0
            moment2 = 0.0
            distance = 0.0
            for m in range(n_markers):
                e0 = positions[f, m, 0] - mean_c[m, 0]
                e1 = positions[f, m, 1] - mean_c[m, 1]
                e2 = positions[f, m, 2] - mean_c[m, 2]
                distance += e0 * e0 + e1 * e1 + e2 * e2
                e00 += e0 * e0
                e01 += e0 * e1
                e02 += e0 * e2
                e11 += e1 * e1
                e12 += e1 * e2
                e22 += e2 * e2
                moment0 += mean_c[m, 1] * e2 - mean_c[m, 2] * e1
                moment1 += mean_c[m, 2] * e0 - mean_c[m, 0] * e2
                moment2 += mean_c[m, 0] * e1 - mean_c[m, 1] * e0
            if distance < nearest:
                nearest = distance
                out[t, _CENTRAL_FRAME] = f
            w0 = inverse[0, 0] * moment0 + inverse[0, 1] * moment1 + inverse[0, 2] * moment2
            w1 = inverse[1, 0] * moment0 + inverse[1, 1] * moment1 + inverse[1, 2] * moment2
            w2 = inverse[2, 0] * moment0 + inverse[2, 1] * moment1 + inverse[2, 2] * moment2
            w00 += w0 * w0
            w01 += w0 * w1
            w02 += w0 * w2
            w11 += w1 * w1
            w12 += w1 * w2
            w22 += w2 * w2
        pooled[0, 0], pooled[0, 1], pooled[0, 2] = e00, e01, e02
        pooled[1, 1], pooled[1, 2], pooled[2, 2] = e11, e12, e22
        outer_w[0, 0], outer_w[0, 1], outer_w[0, 2] = w00, w01, w02
        outer_w[1, 1], outer_w[1, 2], outer_w[2, 2] = w11, w12, w22
        # The cluster's own distances.
        for p in range(n_pairs):
            dx, dy, dz = differences[p, 0], differences[p, 1], differences[p, 2]
            for f in range(n_frames):
                lengths[p, f] = np.sqrt(dx[f] * dx[f] + dy[f] * dy[f] + dz[f] * dz[f])
        _frame_dependence(lengths, n_pairs, largest, out[t, _DEPENDENCE])
        _distance_moments(lengths, first_d[0], sum_d, scatter_d[0], mean_sq[0], terms)
        # The trial's row of _frame_numbers from these distances' own numbers: their
        # dependence, and the SD of their lag-1 autocorrelation from their scatter.
        out[t, at_frames : at_frames + 4] = out[t, _DEPENDENCE]
        out[t, at_frames + 4] = _read_correlation_sd(
            out[t, at_frames], _scatter_correlation_sd(scatter_d[0], n_frames)
        )
        # The cluster's own distance residual, from its mean distances and again from its mean
        # squared distances less their noise (6 s^2 per pair), and the residual per degree of
        # freedom each gives.
        variance = 0.0
        for corrected in (False, True):
            for p in range(n_pairs):
                if corrected:
                    mean_d[p] = np.sqrt(max(mean_sq[0, p] - 6.0 * variance, 0.0))
                else:
                    mean_d[p] = first_d[0, p] + sum_d[p] / n_frames
            residual[0], rank[0] = _shape_residual(
                mean_d, scatter_d[0], corrected, variance, flex, pair_a, pair_b, scratch
            )
            variance = residual[0] / max(rank[0] * (n_frames - 1), 1)
        # The noise's directions, while the cluster's own distances and modes are at hand.
        noise = out[t, n_columns:]
        noise[0] = noise[2] = np.nan
        noise[3] = 1.0
        if variance > (ROUNDING * largest) ** 2 and not out[t, _EXCESS] >= 1.0:
            inverse_gram_into(scratch[3], scratch[4], int(rank[0]), inverse_gram)
            trial_test_into(
                positions,
                differences,
                lengths[:n_pairs],
                first_d[0],
                sum_d,
                scatter_d[0],
                inverse_gram,
                scratch[1],
                1,
                noise,
            )
        # The mean shape's principal moments by classical scaling of the mean squared
        # distances less their noise (6 s^2 per pair).
        for p in range(n_pairs):
            squared[pair_a[p], pair_b[p]] = mean_sq[0, p] - 6.0 * variance
            squared[pair_b[p], pair_a[p]] = mean_sq[0, p] - 6.0 * variance
        for a in range(n_markers):
            squared[a, a] = 0.0
        total = 0.0
        for a in range(n_markers):
            row = 0.0
            for b in range(n_markers):
                total += squared[a, b]
                row += squared[a, b]
            row_sums[a] = row
        for a in range(n_markers):
            for b in range(n_markers):
                gram[a, b] = -0.5 * (
                    squared[a, b] - (row_sums[a] + row_sums[b]) / n_markers + total / n_markers**2
                )
        symmetric_eigen_into(gram, mu, vectors_n, work_n)
        top = max(mu[n_markers - 1], 0.0)
        second = max(mu[n_markers - 2], 0.0)
        third = max(mu[n_markers - 3], 0.0)
        for i in range(3):
            for j in range(i + 1, 3):
                pooled[j, i] = pooled[i, j]
                outer_w[j, i] = outer_w[i, j]
        motion = pooled[0, 0] + pooled[1, 1] + pooled[2, 2]
        spread = top + second + third
        collinear = second <= 1e-12 * top
        # Candidate hinge axes: the direction the markers move least along (exact for a
        # hinge of any range), and the principal axis of the rotations from the mean
        # positions, linearised and whitened by their noise (the better estimate of a small
        # one).
        symmetric_eigen_into(pooled, values3, vectors3, work3)
        for i in range(3):
            axes[0, i] = vectors3[i, 0]
        # The whitened scatter root outer_w root, and its principal axis carried back by
        # inverse root, in loops: a BLAS call costs more than these 3 x 3 products.
        for i in range(3):
            for j in range(3):
                work3[i, j] = root[i, 0] * outer_w[0, j] + root[i, 1] * outer_w[1, j]
                work3[i, j] += root[i, 2] * outer_w[2, j]
        for i in range(3):
            for j in range(3):
                whitened[i, j] = work3[i, 0] * root[0, j] + work3[i, 1] * root[1, j]
                whitened[i, j] += work3[i, 2] * root[2, j]
        symmetric_eigen_into(whitened, values3, vectors3, work3)
        for i in range(3):
            principal[i] = vectors3[i, 2]
        for i in range(3):
            values3[i] = root[i, 0] * principal[0] + root[i, 1] * principal[1]
            values3[i] += root[i, 2] * principal[2]
        for i in range(3):
            axes[1, i] = inverse[i, 0] * values3[0] + inverse[i, 1] * values3[1]
            axes[1, i] += inverse[i, 2] * values3[2]
        for c in range(2):
            off_axis[c] = _hinge_plane(axes[c], pooled, planes[c + 1])
        # Third pass: the distances of the projections on the candidate hinges' planes.
        for s in range(1, 3):
            u0, u1, u2 = planes[s, 0, 0], planes[s, 0, 1], planes[s, 0, 2]
            v0, v1, v2 = planes[s, 1, 0], planes[s, 1, 1], planes[s, 1, 2]
            for p in range(n_pairs):
                dx, dy, dz = differences[p, 0], differences[p, 1], differences[p, 2]
                for f in range(n_frames):
                    along_u = u0 * dx[f] + u1 * dy[f] + u2 * dz[f]
                    along_v = v0 * dx[f] + v1 * dy[f] + v2 * dz[f]
                    lengths[p, f] = np.sqrt(along_u * along_u + along_v * along_v)
            _distance_moments(lengths, first_d[s], sum_d, scatter_d[s], mean_sq[s], terms)
            # The projection's mean distances less their noise (4 s^2 per pair in 2-D).
            for p in range(n_pairs):
                mean_d[p] = np.sqrt(max(mean_sq[s, p] - 4.0 * variance, 0.0))
            residual[s], rank[s] = _shape_residual(
                mean_d, scatter_d[s], True, variance, flex, pair_a, pair_b, scratch
            )
            # A projection that keeps no plane figure (its residual is the share of its
            # scatter that makes markers "not one rigid body") is no hinge's: the first-order
            # residual would not measure its departure from one.
            scatter_2d = 0.0
            for p in range(n_pairs):
                scatter_2d += mean_sq[s, p]
            per_dof = residual[s] / max(rank[s] * (n_frames - 1), 1)
            spread_2d = scatter_2d / n_markers / (2 * (n_markers - 1))
            flat[s - 1] = per_dof >= MAX_NONRIGID_SHARE * spread_2d
        # The tests' statistics (module docstring, "one segment"), each as the F ratio and
        # its numerator's degrees of freedom, for the caller's F survival function. Noise-free
        # data are judged against rounding instead (the ratio would compare rounding with
        # rounding): a ratio of inf for resolved, 0 for not; no degree of freedom left: 0.
        n_steps = n_frames - 1
        exact = variance <= (ROUNDING * largest) ** 2
        rotation_ss = max(motion - residual[0], 0.0)
        # Marker displacement over (2/3) sum |u|^2, the inertia about an axis averaged over
        # axes: the RMS angle that moves the markers as much, to first order.
        displacement = n_frames * 2.0 / 3.0 * spread
        out[t, 0] = variance
        # The markers' scatter about each frame's centroid: about their mean positions, and
        # those about the centroid.
        centroid_sq = motion
        for m in range(n_markers):
            centroid_sq += n_frames * (mean_c[m, 0] ** 2 + mean_c[m, 1] ** 2 + mean_c[m, 2] ** 2)
        out[t, 1] = variance / (centroid_sq / (3 * (n_markers - 1) * n_frames))
        out[t, 2] = np.sqrt(variance / (second + third)) if second + third > 0.0 else np.inf
        out[t, 3] = collinear
        out[t, 4] = max(rank[0] * n_steps, 1.0)
        for test in range(3):
            if test == 0:
                tested_ss = rotation_ss
                dof = (3 * (n_markers - 1) - rank[0]) * n_steps
                rounding = rotation_ss <= _ROUNDING_ROTATION_RAD**2 * displacement
            else:
                # Off the hinge about candidate c: motion along the axis, plus the
                # projection's departure from a rigid plane figure, less the cluster's own
                # residual.
                tested_ss = max(off_axis[test - 1] + (residual[test] - residual[0]), 0.0)
                dof = (n_markers - 1 + rank[test] - rank[0]) * n_steps
                rounding = tested_ss <= 1e-12 * rotation_ss
            column = 5 + 3 * test
            out[t, column] = np.sqrt(tested_ss / displacement)
            if dof <= 0:
                out[t, column + 1] = 0.0
            elif test > 0 and flat[test - 1]:
                out[t, column + 1] = np.inf
            elif exact:
                out[t, column + 1] = 0.0 if rounding else np.inf
            else:
                out[t, column + 1] = tested_ss / dof / variance
            out[t, column + 2] = max(dof, 1.0)
    return out


@kernel
def _inverse_and_root(
    matrix: np.ndarray, inverse: np.ndarray, root: np.ndarray, scratch: tuple[np.ndarray, ...]
) -> None:
    """The pseudo-inverse and the square root of the symmetric positive semi-definite
    ``matrix`` ``(3, 3)``, into ``inverse`` and ``root`` ``(3, 3)``, from its eigen-decomposition
    (modes at or below 1e-12 of the strongest left out); ``scratch`` holds work arrays ``(3,)``,
    ``(3, 3)`` and ``(3, 3)``. A compiled kernel."""
    values, vectors, work = scratch
    symmetric_eigen_into(matrix, values, vectors, work)
    for i in range(3):
        for j in range(3):
            inverse[i, j] = 0.0
            root[i, j] = 0.0
            for k in range(3):
                if values[k] > 1e-12 * values[2]:
                    inverse[i, j] += vectors[i, k] * vectors[j, k] / values[k]
                    root[i, j] += vectors[i, k] * vectors[j, k] * np.sqrt(values[k])


@kernel
def _frame_dependence(lengths: np.ndarray, n_pairs: int, largest: float, out: np.ndarray) -> None:
    """How the distances ``lengths[:n_pairs]`` ``(P, N)`` [mm] depend on each other from frame
    to frame (module docstring, "independent frames"), into ``out`` ``(4,)``: their lag-1
    autocorrelation pooled over the pairs, ``sum_p sum_k d_pk d_p(k+1) / sum_p sum_k d_pk^2``
    (``d`` the deviations from each pair's mean); the variance ratio ``V_L`` that is furthest
    beyond what independent frames allow, and its block length ``L`` [frames]; and that
    excess, ``V_L`` over the larger of its chi-square quantile and
    :data:`MIN_VARIANCE_RATIO` (at least 1 where the frames are not independent; 0 where no
    block length is tested). The quantile's degrees of freedom are Satterthwaite's,
    ``(sum_b W_b)^2 / sum_b W_b^2 - 1`` with ``W_b`` block ``b``'s sum of squared deviations
    over the pairs: ``B - 1`` where the noise keeps one variance, fewer where a few blocks
    carry it (a burst of noise on one marker), whose variance ratio then spreads the wider.
    All NaN where the distances are rounding (a variance per pair within twice the
    :data:`ROUNDING` of the ``largest`` coordinate [mm] squared, what noise of that size per
    coordinate would give), whose pattern says nothing of the noise. A compiled kernel."""
    n_frames = lengths.shape[1]
    pooled = _pooled_dependence(n_frames)
    for p in range(n_pairs):
        _pool_pair(lengths[p], pooled)
    _dependence_of(pooled, n_pairs, largest, out)


@kernel
def _pooled_dependence(
    n_frames: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The empty sums :func:`_pool_pair` adds each pair's distances over ``n_frames`` frames
    to: per block length ``L`` (:func:`_block_levels`) the block sums' sum of squares about
    their mean ``(levels,)``; a work row ``(N,)``; per frame the
    pairs' squared deviations ``(N,)``, whose block sums are the ``W_b``; and the lagged
    products and the squares ``(2,)``. A compiled kernel."""
    n_levels = _block_levels(n_frames)
    return np.zeros(max(n_levels, 1)), np.empty(n_frames), np.zeros(n_frames), np.zeros(2)


@kernel
def _block_levels(n_frames: int) -> int:
    """How many block lengths ``L = 2, 4, ...`` over ``n_frames`` frames leave
    :data:`MIN_BLOCKS` blocks or more. A compiled kernel."""
    n_levels = 0
    while n_frames >> (n_levels + 1) >= MIN_BLOCKS:
        n_levels += 1
    return n_levels


@kernel
def _pool_pair(
    lengths: np.ndarray, pooled: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
) -> None:
    """Add one pair's distances ``lengths`` ``(N,)`` [mm] to the ``pooled`` sums of
    :func:`_pooled_dependence` (:func:`_frame_dependence`): the pairs are pooled one after the
    other in one order, so that the sums are the same numbers whether the distances were
    kept or each pair's were made in turn. A compiled kernel."""
    level_squares, sums, weights, totals = pooled
    n_frames = lengths.shape[0]
    n_levels = _block_levels(n_frames)
    mean = 0.0
    for f in range(n_frames):
        mean += lengths[f]
    mean /= n_frames
    # The totals carried in scalars through the loop (the arrays written beside them would
    # keep them in memory), each sum the same as added in place.
    lagged, squares = totals[0], totals[1]
    previous = lengths[0] - mean
    squares += previous * previous
    sums[0] = previous
    weights[0] += previous * previous
    for f in range(1, n_frames):
        current = lengths[f] - mean
        lagged += previous * current
        squares += current * current
        sums[f] = current
        weights[f] += current * current
        previous = current
    totals[0], totals[1] = lagged, squares
    # Each level's block sums are the sums of the last level's pairs of blocks (a frame
    # left over at the end of a level is left out of the longer blocks).
    count = n_frames
    for level in range(n_levels):
        count //= 2
        total = 0.0
        for b in range(count):
            sums[b] = sums[2 * b] + sums[2 * b + 1]
            total += sums[b]
        centre = total / count
        for b in range(count):
            level_squares[level] += (sums[b] - centre) ** 2


@kernel
def _dependence_of(
    pooled: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    n_pairs: int,
    largest: float,
    out: np.ndarray,
) -> None:
    """:func:`_frame_dependence`'s numbers ``(4,)`` into ``out`` from the ``pooled`` sums of
    ``n_pairs`` pairs' distances (:func:`_pool_pair`), ``largest`` the largest coordinate
    [mm]. A compiled kernel."""
    level_squares, _, weights, totals = pooled
    lagged, squares = totals[0], totals[1]
    n_frames = weights.shape[0]
    n_levels = _block_levels(n_frames)
    if squares <= 2.0 * (ROUNDING * largest) ** 2 * n_pairs * (n_frames - 1):
        out[:] = np.nan
        return
    out[0] = lagged / squares
    out[1] = out[2] = np.nan
    out[3] = 0.0
    z = _Z_SHARED[min(n_levels, _Z_SHARED.shape[0]) - 1] if n_levels else 0.0
    per_frame = squares / (n_frames - 1)
    count = n_frames
    for level in range(n_levels):
        length = 2 << level
        count //= 2
        n_blocks = count
        # V_L = L var(block means) / var(d) = var(block sums) / (L var(d)).
        ratio = level_squares[level] / (n_blocks - 1) / (length * per_frame)
        total = 0.0
        total_squares = 0.0
        for b in range(n_blocks):
            weights[b] = weights[2 * b] + weights[2 * b + 1]
            total += weights[b]
            total_squares += weights[b] ** 2
        dof = max(total * total / total_squares - 1.0, 1.0) if total_squares > 0.0 else 1.0
        # Wilson and Hilferty's chi-square quantile, per degree of freedom.
        spread = 2.0 / (9.0 * dof)
        quantile = (1.0 - spread + z * math.sqrt(spread)) ** 3
        excess = ratio / max(quantile, MIN_VARIANCE_RATIO)
        # The first length's numbers stand until another's excess is larger, so that a trial
        # whose ratios all fall short still reports one.
        if excess > out[3] or level == 0:
            out[1], out[2], out[3] = ratio, length, excess


@kernel
def _frame_numbers(markers: np.ndarray) -> np.ndarray:
    """Per trial of one segment's markers ``(T, N, n, 3)`` [mm], how its marker-pair distances
    depend on each other from frame to frame (:func:`_frame_dependence`: the first four) and
    the SD of their pooled lag-1 autocorrelation for independent frames
    (:func:`_correlation_sd`), what :class:`Untested` reads beside the first, ``(T, 5)``: the
    distances computed once for all (:func:`_trial_frame_numbers_into`). A compiled kernel."""
    out = np.empty((markers.shape[0], _FRAME_COLUMNS))
    for t in range(markers.shape[0]):
        _trial_frame_numbers_into(markers[t], out[t])
    return out


@kernel
def _trial_frame_numbers_into(markers: np.ndarray, out: np.ndarray) -> None:
    """One trial's row of :func:`_frame_numbers` for its markers ``(N, n, 3)`` [mm], into
    ``out`` ``(5,)``: from its distances kept ``(P, N)`` where the pairs are no more than the
    frames, else from each pair's in turn (:func:`_streamed_frame_numbers_into`). A compiled
    kernel."""
    n_markers = markers.shape[1]
    if n_markers * (n_markers - 1) // 2 > markers.shape[0]:
        _streamed_frame_numbers_into(markers, out)
        return
    distances = _dependence_into(markers, out[:4])
    out[4] = _read_correlation_sd(out[0], _correlation_sd(distances))


@kernel
def _streamed_frame_numbers_into(markers: np.ndarray, out: np.ndarray) -> None:
    """:func:`_trial_frame_numbers_into` of markers ``(N, n, 3)`` [mm] with more pairs ``P``
    than frames, into ``out`` ``(5,)``, each pair's distances ``(N,)`` made, pooled
    (:func:`_pool_pair`) and added to the deviations' Gram matrix over the frames ``(N, N)``
    in turn: the same sums in the same order as from the distances kept, without their
    ``(P, N)`` array, gigabytes for thousands of markers (a recording passed as
    ``(markers, frames, 3)``). The Gram matrix has the trace and the Frobenius norm of the
    ``(P, P)`` scatter (``D D'`` and ``D' D`` share both), all that
    :func:`_scatter_correlation_sd` reads. A compiled kernel."""
    n_frames, n_markers = markers.shape[0], markers.shape[1]
    pooled = _pooled_dependence(n_frames)
    # Its upper triangle, all that _scatter_correlation_sd reads.
    gram = np.zeros((n_frames, n_frames))
    lengths = np.empty(n_frames)
    for a in range(n_markers):
        for b in range(a + 1, n_markers):
            _pair_distances_into(markers, a, b, lengths)
            _pool_pair(lengths, pooled)
            _deviations_in_place(lengths)
            for f in range(n_frames):
                for g in range(f, n_frames):
                    gram[f, g] += lengths[f] * lengths[g]
    _dependence_of(pooled, n_markers * (n_markers - 1) // 2, largest_magnitude(markers), out[:4])
    out[4] = _read_correlation_sd(out[0], _scatter_correlation_sd(gram, n_frames))


@kernel
def _read_correlation_sd(correlation: float, sd: float) -> float:
    """The SD of the lag-1 ``correlation`` of a row of :func:`_frame_numbers`: ``sd``, NaN
    where the correlation is (distances at rounding level, whose scatter is rounding too and
    which no statement reads). A compiled kernel."""
    return sd if not np.isnan(correlation) else np.nan


def _segment_frame_numbers(markers: np.ndarray) -> np.ndarray:
    """:func:`_frame_numbers` of one segment's markers ``(T, N, n, 3)`` [mm], read-only: in one
    verdict (:func:`assess_many`) computed once for the block test and the lag-1 statement,
    which both read them (:func:`jointbench.numerics.reuse.remembered`)."""
    return remembered("frame numbers", markers, _read_only_frame_numbers)


def _read_only_frame_numbers(markers: np.ndarray) -> np.ndarray:
    """:func:`_frame_numbers` of ``markers`` ``(T, N, n, 3)`` [mm], as an array no reader can
    write to."""
    numbers = _frame_numbers(kernel_array(markers))
    numbers.flags.writeable = False
    return numbers


@kernel
def _dependence_into(markers: np.ndarray, out: np.ndarray) -> np.ndarray:
    """:func:`_frame_dependence` of one trial's markers ``(N, n, 3)`` [mm] into ``out``
    ``(4,)``; returns their pair distances ``(P, N)`` [mm]. A compiled kernel."""
    lengths = _pair_distances(markers)
    _frame_dependence(lengths, lengths.shape[0], largest_magnitude(markers), out)
    return lengths


@kernel
def _distance_moments(
    lengths: np.ndarray,
    first: np.ndarray,
    total: np.ndarray,
    scatter: np.ndarray,
    mean_sq: np.ndarray,
    terms: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> None:
    """The moments of the distances ``lengths[:P]`` ``(P, N)`` [mm] over the frames: their values
    at frame 0 ``first`` ``(P,)`` [mm], the sum ``total`` ``(P,)`` [mm] of their deviations from
    those, the deviations' scatter about their mean ``scatter`` ``(P, P)`` [mm^2] and the mean
    squared distances ``mean_sq`` ``(P,)`` [mm^2], each sum taken frame by frame.

    The distances are replaced by their deviations; ``lengths[P]`` holds ones. ``terms`` holds
    the rows ``left`` and ``right`` ``(K,)`` whose products are summed (``K`` a multiple of 4:
    the ``P`` totals as products with the ones, then the upper scatter row by row, then
    padding) and their sums ``(K,)``: four sums at a time, side by side, each in frame order.
    A compiled kernel."""
    left, right, sums = terms
    n_pairs = first.shape[0]
    n_frames = lengths.shape[1]
    for p in range(n_pairs):
        first[p] = lengths[p, 0]
        for f in range(n_frames):
            lengths[p, f] -= first[p]
    for k in range(0, left.shape[0], 4):
        a0, a1, a2, a3 = (
            lengths[left[k]],
            lengths[left[k + 1]],
            lengths[left[k + 2]],
            lengths[left[k + 3]],
        )
        b0, b1, b2, b3 = (
            lengths[right[k]],
            lengths[right[k + 1]],
            lengths[right[k + 2]],
            lengths[right[k + 3]],
        )
        sum0 = sum1 = sum2 = sum3 = 0.0
        for f in range(n_frames):
            sum0 += a0[f] * b0[f]
            sum1 += a1[f] * b1[f]
            sum2 += a2[f] * b2[f]
            sum3 += a3[f] * b3[f]
        sums[k], sums[k + 1], sums[k + 2], sums[k + 3] = sum0, sum1, sum2, sum3
    k = n_pairs
    for p in range(n_pairs):
        total[p] = sums[p]
        for q in range(p, n_pairs):
            scatter[p, q] = sums[k]
            k += 1
    # The mean squared distance is the squared mean plus the scatter about it, neither of
    # which depends on the frame the deviations are taken from (frame 0 is only a shift that
    # keeps the sums small).
    for p in range(n_pairs):
        mean_sq[p] = (first[p] + total[p] / n_frames) ** 2
        mean_sq[p] += (scatter[p, p] - total[p] ** 2 / n_frames) / n_frames
        for q in range(p, n_pairs):
            value = scatter[p, q] - total[p] * total[q] / n_frames
            scatter[p, q] = value
            scatter[q, p] = value


@kernel
def _shape_residual(
    mean_d: np.ndarray,
    scatter: np.ndarray,
    corrected: bool,
    variance: float,
    flex: float,
    pair_a: np.ndarray,
    pair_b: np.ndarray,
    scratch: tuple[np.ndarray, ...],
) -> tuple[float, int]:
    """The distances' residual from a rigid figure to first order and its rank (module
    docstring, "one segment"): ``sum_k dd_k' G+ dd_k`` [mm^2] from the deviations' scatter
    ``scatter`` ``(P, P)`` [mm^2], with ``G = J J'`` and ``J`` the Jacobian of the distances
    between markers ``pair_a`` and ``pair_b`` ``(P,)`` at the mean figure, whose entries the
    mean distances ``mean_d`` ``(P,)`` [mm] give by the law of cosines. A mode counts as shape
    where it is above ``flex`` of the strongest and, for mean distances ``corrected`` for the
    noise ``variance`` [mm^2], where its first-order signal is 3 times the second-order one,
    ``s^2 / d`` (``d`` the RMS distance), which noise adds to a flex
    (:func:`jointbench.numerics.distances.distance_modes_into`, whose work arrays ``scratch``
    holds). A compiled kernel."""
    strength, modes = scratch[3], scratch[4]
    n_pairs = mean_d.shape[0]
    weakest_mode = distance_modes_into(mean_d, corrected, variance, flex, pair_a, pair_b, scratch)
    residual = 0.0
    rank = 0
    for k in range(n_pairs):
        if strength[k] > weakest_mode:
            rank += 1
            value = 0.0
            for p in range(n_pairs):
                for q in range(n_pairs):
                    value += modes[p, k] * scatter[p, q] * modes[q, k]
            residual += value / strength[k]
    return residual, rank


@kernel
def _hinge_plane(axis: np.ndarray, pooled: np.ndarray, plane: np.ndarray) -> float:
    """An orthonormal basis ``plane`` ``(2, 3)`` of the plane normal to ``axis`` ``(3,)``, and
    the markers' motion along the axis, ``h' pooled h`` [mm^2] with ``h`` its unit vector and
    ``pooled`` ``(3, 3)`` their scatter about their mean displacements. A compiled kernel."""
    norm = max(np.sqrt(axis[0] ** 2 + axis[1] ** 2 + axis[2] ** 2), 1e-300)
    h0, h1, h2 = axis[0] / norm, axis[1] / norm, axis[2] / norm
    # The first normal from the coordinate axis least along h.
    k = 0
    if abs(h1) < abs(h0):
        k = 1
    if abs(h2) < abs((h0, h1)[k]):
        k = 2
    hk = (h0, h1, h2)[k]
    n0 = (1.0 if k == 0 else 0.0) - hk * h0
    n1 = (1.0 if k == 1 else 0.0) - hk * h1
    n2 = (1.0 if k == 2 else 0.0) - hk * h2
    length = np.sqrt(n0**2 + n1**2 + n2**2)
    n0, n1, n2 = n0 / length, n1 / length, n2 / length
    plane[0, 0], plane[0, 1], plane[0, 2] = n0, n1, n2
    plane[1, 0] = h1 * n2 - h2 * n1
    plane[1, 1] = h2 * n0 - h0 * n2
    plane[1, 2] = h0 * n1 - h1 * n0
    h = (h0, h1, h2)
    along = 0.0
    for i in range(3):
        for j in range(3):
            along += h[i] * pooled[i, j] * h[j]
    return along


# The coefficient of t^10 in the series of the logarithm's Jacobian (:func:`_frame_noise_into`).
_B12 = 691.0 / 1307674368000.0

# The Gauss-Newton steps of the hinge fit (:func:`_hinge_residual`) past which its residual is
# taken as it stands. Where the test's answer can turn on it the residual is noise, and each step
# brings it about a thousand times closer to its least: from the principal axis one step leaves
# a pure hinge's within 1e-2 of a chi-square unit, two leave that of a second rotation of 30 %
# of the flexion (12 times its noise) within 0.02. A circumduction, far from any hinge, settles
# slowly, but its residual stays hundreds of times its noise. A small swing of nearly collinear
# clusters settles slowly too, where the mean pose's noise is the truer and is read instead
# (:func:`_rotation_spreads`).
_HINGE_STEPS = 3


@kernel
def _frame_noise_into(
    columns: np.ndarray, moving_noise: np.ndarray, reference_noise: np.ndarray, noise: np.ndarray
) -> None:
    """The noise covariance per unit variance [mm^-2] of each rotation vector ``w_k`` of the
    relative rotations about their mean pose ``M`` (``M' relative_k = exp([w_k])``), given by
    coordinate over the frames, ``columns`` ``(3, N)`` [rad]: its upper triangle written into
    ``noise`` ``(6, N)`` in the order of :func:`rotated9_upper`, ``(s00, s01, s02, s11, s12,
    s22)``, each entry over the frames contiguous (as :func:`_hinge_terms_into` reads them). A
    compiled kernel.

    The moving segment's pose noise, ``moving_noise`` ``(3, 3)`` in its own frame, enters
    ``exp([w_k])`` on the right and reaches ``w_k`` through the logarithm's right Jacobian,
    ``J_r^-1(w) = I + [w]/2 + b [w]^2`` (``b = (1 - (t/2) cot(t/2)) / t^2``, ``t = |w|``). The
    reference segment's, ``reference_noise`` ``(3, 3)`` carried to the mean pose
    (``M' K_ref^-1 M``), enters it turned back by the frame's own rotation, ``exp(-[w_k])``,
    which with the right Jacobian makes the left one, ``J_l^-1(w) = I - [w]/2 + b [w]^2``. The
    mean pose's covariance taken for every frame is off by a turn of half the frame's angle
    about the axis, each segment's the other way: with clusters of unequal inertia across the
    axis (three markers), a wide hinge over many frames resolves that."""
    # The covariances read into registers once, and each frame's Jacobians kept in registers:
    # in arrays, every frame's stores into ``noise`` could alias them and would have them read
    # again. Each frame's b first, in a loop of its own (its branch and tangent would keep the
    # frames of the sandwiches from being formed several at once).
    moving, reference = rows9(moving_noise), rows9(reference_noise)
    n_frames = columns.shape[1]
    scales = np.empty(n_frames)
    for f in range(n_frames):
        w0, w1, w2 = columns[0, f], columns[1, f], columns[2, f]
        squared = w0 * w0 + w1 * w1 + w2 * w2
        if squared < 0.25:
            # b's series in t^2 (from the Bernoulli numbers), within 1e-13 of it below half a
            # radian, where the closed form cancels and the tangent costs as much as the rest.
            b = 1.0 / 12.0 + squared * (
                1.0 / 720.0
                + squared
                * (
                    1.0 / 30240.0
                    + squared * (1.0 / 1209600.0 + squared * (1.0 / 47900160.0 + squared * _B12))
                )
            )
        else:
            angle = np.sqrt(squared)
            b = (1.0 - 0.5 * angle / np.tan(0.5 * angle)) / squared
        scales[f] = b
    for f in range(n_frames):
        w0, w1, w2 = columns[0, f], columns[1, f], columns[2, f]
        squared = w0 * w0 + w1 * w1 + w2 * w2
        b = scales[f]
        # I + b [w]^2, with [w]^2 = w w' - |w|^2 I, then the halves of [w] either way.
        diagonal = 1.0 - b * squared
        s00, s11, s22 = b * w0 * w0 + diagonal, b * w1 * w1 + diagonal, b * w2 * w2 + diagonal
        s01, s02, s10 = b * w0 * w1, b * w0 * w2, b * w1 * w0
        s12, s20, s21 = b * w1 * w2, b * w2 * w0, b * w2 * w1
        half0, half1, half2 = 0.5 * w0, 0.5 * w1, 0.5 * w2
        right = (
            s00, s01 - half2, s02 + half1,
            s10 + half2, s11, s12 - half0,
            s20 - half1, s21 + half0, s22,
        )  # fmt: skip
        left = (
            s00, s01 + half2, s02 - half1,
            s10 - half2, s11, s12 + half0,
            s20 + half1, s21 - half0, s22,
        )  # fmt: skip
        on_right = rotated9_upper(right, moving)
        on_left = rotated9_upper(left, reference)
        for e in range(6):
            noise[e, f] = on_right[e] + on_left[e]


@kernel
def _hinge_residual(columns: np.ndarray, noise: np.ndarray) -> float:
    """What rotation about a single axis leaves unexplained of the rotation vectors ``w_k``,
    given by coordinate over the frames, ``columns`` ``(3, N)`` [rad], each frame against its
    own noise, ``noise`` ``(6, N)`` per unit variance [mm^-2] (:func:`_frame_noise_into`): the
    least ``sum_k (w_k - c - theta_k h)' S_k^-1 (w_k - c - theta_k h)`` [mm^2] over an axis
    ``h``, an offset ``c`` and an angle ``theta_k`` per frame, which is about the variance times
    a chi-square of ``2 (N - 2)`` degrees of freedom where the rotation is about one axis. NaN
    where a frame's noise is not positive definite across the axis. A compiled kernel.

    The angles drop out in closed form: with ``U`` ``(3, 2)`` a basis normal to ``h``, frame
    ``k`` leaves ``y' G^-1 y``, ``y = U' (w_k - c)`` and ``G = U' S_k U``. The axis and the
    offset normal to it are Gauss-Newton's, from the principal axis of the vectors' scatter and
    their mean, for at most :data:`_HINGE_STEPS` steps and until a step would take off less
    than 1e-6 of the residual; the least residual met is returned. Each step's pass over the
    frames forms their terms first, several frames at once (:func:`_hinge_terms_into`), then
    sums them frame by frame, in the order one loop would."""
    n_frames = columns.shape[1]
    offset = np.zeros(3)
    for f in range(n_frames):
        for i in range(3):
            offset[i] += columns[i, f] / n_frames
    scatter = np.zeros((3, 3))
    for f in range(n_frames):
        for i in range(3):
            for j in range(3):
                scatter[i, j] += (columns[i, f] - offset[i]) * (columns[j, f] - offset[j])
    values = np.empty(3)
    axes = np.empty((3, 3))
    symmetric_eigen_into(scatter, values, axes, np.empty((3, 3)))
    axis = axes[:, 2].copy()
    basis = np.empty((3, 2))
    terms = np.empty((7, n_frames))
    best = np.inf
    for step in range(_HINGE_STEPS + 1):
        tangent_basis_into(axis, basis)
        u0 = (basis[0, 0], basis[1, 0], basis[2, 0])
        u1 = (basis[0, 1], basis[1, 1], basis[2, 1])
        h = (axis[0], axis[1], axis[2])
        # u' S v for the pairs (u0, u0), (u0, u1), (u1, u1), (h, u0), (h, u1) of U's columns
        # and the axis, as sums over S's upper triangle.
        weights = (
            _upper_weights(u0, u0),
            _upper_weights(u0, u1),
            _upper_weights(u1, u1),
            _upper_weights(h, u0),
            _upper_weights(h, u1),
        )
        positive = _hinge_terms_into(columns, noise, offset, u0, u1, h, weights, terms)
        residual = 0.0
        for f in range(n_frames):
            residual += terms[5, f]
        if not positive:
            return np.nan
        best = min(best, residual)
        if step == _HINGE_STEPS:
            break
        # The normal equations of a step in the offset and the axis (two coordinates each,
        # along U), the angles eliminated: 2 x 2 symmetric blocks [[P, Q], [Q, R]], the sums
        # over the frames of G^-1 times 1, theta_k and theta_k^2, and right-hand sides gc, ga.
        p00 = p01 = p11 = q00 = q01 = q11 = r00 = r01 = r11 = 0.0
        gc0 = gc1 = ga0 = ga1 = 0.0
        for f in range(n_frames):
            i00, i01, i11 = terms[0, f], terms[1, f], terms[2, f]
            z0, z1, theta = terms[3, f], terms[4, f], terms[6, f]
            p00, p01, p11 = p00 + i00, p01 + i01, p11 + i11
            q00, q01, q11 = q00 + theta * i00, q01 + theta * i01, q11 + theta * i11
            t2 = theta * theta
            r00, r01, r11 = r00 + t2 * i00, r01 + t2 * i01, r11 + t2 * i11
            gc0, gc1 = gc0 + z0, gc1 + z1
            ga0, ga1 = ga0 + theta * z0, ga1 + theta * z1
        # The offset eliminated (Schur complement of P), the axis's step, then the offset's.
        det = p00 * p11 - p01 * p01
        v00, v01, v11 = p11 / det, -p01 / det, p00 / det
        m00, m01 = q00 * v00 + q01 * v01, q00 * v01 + q01 * v11
        m10, m11 = q01 * v00 + q11 * v01, q01 * v01 + q11 * v11
        s00 = r00 - m00 * q00 - m01 * q01
        s01 = r01 - m00 * q01 - m01 * q11
        s11 = r11 - m10 * q01 - m11 * q11
        e0, e1 = ga0 - m00 * gc0 - m01 * gc1, ga1 - m10 * gc0 - m11 * gc1
        det = s00 * s11 - s01 * s01
        if not det > 0.0:
            break  # no rotation along the axis to place it by
        turn0, turn1 = (s11 * e0 - s01 * e1) / det, (s00 * e1 - s01 * e0) / det
        e0, e1 = gc0 - q00 * turn0 - q01 * turn1, gc1 - q01 * turn0 - q11 * turn1
        shift0, shift1 = v00 * e0 + v01 * e1, v01 * e0 + v11 * e1
        if not shift0 * gc0 + shift1 * gc1 + turn0 * ga0 + turn1 * ga1 > 1e-6 * residual:
            break
        for i in range(3):
            offset[i] += basis[i, 0] * shift0 + basis[i, 1] * shift1
            axis[i] += basis[i, 0] * turn0 + basis[i, 1] * turn1
        axis /= np.sqrt(axis[0] ** 2 + axis[1] ** 2 + axis[2] ** 2)
    return best


@kernel
def _upper_weights(u: tuple, v: tuple) -> tuple:
    """The weights of a symmetric ``S``'s upper triangle ``(s00, s01, s02, s11, s12, s22)`` (as
    :func:`_frame_noise_into` stores it) in ``u' S v`` for the vectors ``u``, ``v`` (3 numbers
    each). A compiled kernel."""
    return (
        u[0] * v[0],
        u[0] * v[1] + u[1] * v[0],
        u[0] * v[2] + u[2] * v[0],
        u[1] * v[1],
        u[1] * v[2] + u[2] * v[1],
        u[2] * v[2],
    )


@kernel
def _hinge_terms_into(
    columns: np.ndarray,
    noise: np.ndarray,
    offset: np.ndarray,
    u0: tuple,
    u1: tuple,
    h: tuple,
    weights: tuple,
    terms: np.ndarray,
) -> bool:
    """Each frame's terms of one step of :func:`_hinge_residual`, written into ``terms``
    ``(7, N)``: its ``G^-1`` (``i00``, ``i01``, ``i11``), ``z = G^-1 y`` (two), ``y' G^-1 y`` and
    its best angle ``theta``, for the rotation vectors ``columns`` ``(3, N)`` [rad] about
    ``offset`` ``(3,)``, their noise ``noise`` ``(6, N)`` (:func:`_frame_noise_into`), the
    basis ``U`` of columns ``u0``, ``u1`` normal to the axis ``h`` (3 numbers each) and the
    ``weights`` (five of :func:`_upper_weights`: the pairs of :func:`_hinge_residual`).
    Whether every frame's ``G`` is positive definite. A compiled kernel: no frame's terms wait
    on another's, so with each term over the frames contiguous several frames are formed at
    once; the sums over them, in frame order, are the caller's."""
    o0, o1, o2 = offset[0], offset[1], offset[2]
    w0, w1, w2, w3, w4 = weights
    positive = True
    for f in range(columns.shape[1]):
        a0 = columns[0, f] - o0
        a1 = columns[1, f] - o1
        a2 = columns[2, f] - o2
        y0 = u0[0] * a0 + u0[1] * a1 + u0[2] * a2
        y1 = u1[0] * a0 + u1[1] * a1 + u1[2] * a2
        along = h[0] * a0 + h[1] * a1 + h[2] * a2
        g00 = g01 = g11 = h0 = h1 = 0.0
        for e in range(6):
            entry = noise[e, f]
            g00 += w0[e] * entry
            g01 += w1[e] * entry
            g11 += w2[e] * entry
            h0 += w3[e] * entry
            h1 += w4[e] * entry
        det = g00 * g11 - g01 * g01
        positive = positive & (g00 > 0.0) & (det > 0.0)
        # One division, not three: the frame's inverse is most of its arithmetic.
        scale = 1.0 / det
        i00, i01, i11 = g11 * scale, -g01 * scale, g00 * scale
        z0 = i00 * y0 + i01 * y1
        z1 = i01 * y0 + i11 * y1
        terms[0, f], terms[1, f], terms[2, f] = i00, i01, i11
        terms[3, f], terms[4, f] = z0, z1
        terms[5, f] = y0 * z0 + y1 * z1
        # The frame's best angle: its rotation along h less what the noise off the axis
        # shares with the noise along it.
        terms[6, f] = along - h0 * z0 - h1 * z1
    return positive


class _Rotation(NamedTuple):
    rms_rad: np.ndarray  # (T,) RMS rotation about the mean relative pose
    p_any: np.ndarray  # (T,) p-value of "the segment does not rotate"
    second_rms_rad: np.ndarray  # (T,) RMS rotation about all but the dominant axis
    p_second: np.ndarray  # (T,) p-value of "it rotates about one axis only"


@kernel
def _rotation_spreads(
    moving: np.ndarray,
    moving_inertia_inv: np.ndarray,
    reference: np.ndarray,
    reference_inertia_inv: np.ndarray,
    variance: np.ndarray,
    tested: bool = True,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, bool]:
    """The rotations ``moving`` ``(T, N, 3, 3)`` relative to ``reference`` (the same shape,
    or no frames for the identity) about their mean, against their noise. A compiled kernel.

    Per trial: the mean rotation ``M`` is the rotation nearest (Frobenius) the mean of the
    relative rotations (Kabsch's SVD); ``w_k`` the rotation vector of ``M' relative_k``, as
    :func:`jointbench.geometry.rotation_vector` gives it away from pi, centred over the
    frames; the noise covariance per unit variance at the mean pose is ``moving_inertia_inv``
    plus, with a reference, ``M' reference_inertia_inv M`` (``(T, 3, 3)`` each). Returns the
    ascending eigenvalues of ``sum_k w_k w_k'`` [rad^2], ``(T, 3)``; the rotation tests' sums,
    ``(T, 2)``: the sum ``sum_k z_k' z_k`` of the vectors whitened by that covariance
    (``z_k = L' w_k``, ``L L'`` its inverse), and what a hinge leaves of them, the lesser of
    the two smaller eigenvalues of ``sum_k z_k z_k'`` and the residual against each frame's
    own noise (:func:`_hinge_residual`); the eigenvalues of the rotation's own
    scatter, ``sum_k w_k w_k'`` less its noise ``(N - 1) variance C`` (``variance`` ``(T,)``
    [mm^2], ``C`` the covariance per unit variance), ``(T, 3)``; that scatter itself
    ``(T, 3, 3)`` [rad^2] and ``M`` ``(T, 3, 3)``; and whether some rotation is within 1e-4 of
    pi, where that rotation vector does not hold. Without ``tested`` the first two, which
    only the rotation tests read, are left NaN.
    """
    n_trials, n_frames, _, _ = moving.shape
    with_reference = reference.shape[1] > 0
    raw = np.empty((n_trials, 3))
    sums = np.empty((n_trials, 2))
    rotation_only = np.empty((n_trials, 3))
    own = np.empty((n_trials, 3, 3))
    means = np.empty((n_trials, 3, 3))
    relative = np.empty((n_frames, 3, 3))
    vectors = np.empty((n_frames, 3))
    gram = np.empty((3, 3))
    mean = np.empty((3, 3))
    centre = np.empty(3)
    noise = np.empty((6, n_frames))
    reference_noise = np.zeros((3, 3))
    near_pi = False
    for t in range(n_trials):
        mean[:] = 0.0
        for f in range(n_frames):
            for i in range(3):
                for j in range(3):
                    if with_reference:
                        value = 0.0
                        for k in range(3):
                            value += reference[t, f, k, i] * moving[t, f, k, j]
                    else:
                        value = moving[t, f, i, j]
                    relative[f, i, j] = value
                    mean[i, j] += value
        u, _, vt = np.linalg.svd(mean / n_frames)
        if np.linalg.det(u) * np.linalg.det(vt) < 0.0:
            u[:, 2] = -u[:, 2]
        nearest = u @ vt
        means[t] = nearest
        if with_reference:
            reference_noise = nearest.T @ reference_inertia_inv[t] @ nearest
        covariance = moving_inertia_inv[t] + reference_noise
        centre[:] = 0.0
        # M read into registers once, and each frame's M' relative in registers: in arrays,
        # every frame's stores could alias M and would have it read again.
        nearest9 = rows9(nearest)
        for f in range(n_frames):
            d = transposed_times9(nearest9, rows9(relative[f]))
            cos_theta = min(max((d[0] + d[4] + d[8] - 1.0) / 2.0, -1.0), 1.0)
            theta = np.arccos(cos_theta)
            turned = theta > np.pi - 1e-4
            near_pi = near_pi or turned
            if theta < 1e-6:
                scale = 0.5 + theta**2 / 12.0
            elif turned:
                scale = theta / (2.0 * np.sin(theta))
            else:
                # sin(arccos c) as sqrt((1 - c)(1 + c)), both factors exact where either is
                # small: a root costs a fraction of a sine. Near pi, whose vectors are taken
                # again another way, the sine keeps them finite.
                scale = theta / (2.0 * np.sqrt((1.0 - cos_theta) * (1.0 + cos_theta)))
            vectors[f, 0] = scale * (d[7] - d[5])
            vectors[f, 1] = scale * (d[2] - d[6])
            vectors[f, 2] = scale * (d[3] - d[1])
            for i in range(3):
                centre[i] += vectors[f, i]
        for i in range(3):
            centre[i] /= n_frames
        gram[:] = 0.0
        for f in range(n_frames):
            for i in range(3):
                for j in range(3):
                    gram[i, j] += (vectors[f, i] - centre[i]) * (vectors[f, j] - centre[j])
        own[t] = gram - (n_frames - 1) * variance[t] * covariance
        rotation_only[t] = np.maximum(np.linalg.eigvalsh(own[t]), 0.0)
        if not tested:
            raw[t] = sums[t] = np.nan
            continue
        # L = V diag(mu)^-1/2 from the covariance's own eigenvectors, not the Cholesky factor
        # of its inverse: with nearly collinear markers the covariance's inverse is rounding
        # in one direction and need not come out positive definite.
        mu, basis = np.linalg.eigh(covariance)
        whitening = basis / np.sqrt(mu)
        white = whitening.T @ gram @ whitening
        raw[t] = np.maximum(np.linalg.eigvalsh(gram), 0.0)
        white_values = np.maximum(np.linalg.eigvalsh(white), 0.0)
        sums[t, 0] = white_values.sum()
        sums[t, 1] = _hinge_left(
            white_values[0] + white_values[1],
            vectors,
            moving_inertia_inv[t],
            reference_noise,
            noise,
        )
    return raw, sums, rotation_only, own, means, near_pi


@kernel
def _hinge_left(
    at_mean_pose: float,
    vectors: np.ndarray,
    moving_noise: np.ndarray,
    reference_noise: np.ndarray,
    noise: np.ndarray,
) -> float:
    """What a hinge leaves unexplained of the rotation vectors ``vectors`` ``(N, 3)`` [rad]
    [mm^2 per unit variance]: read against each frame's own noise (:func:`_frame_noise_into`
    of ``moving_noise`` and ``reference_noise`` ``(3, 3)``, into the scratch ``noise``
    ``(6, N)``; :func:`_hinge_residual`) or, ``at_mean_pose``, against the mean pose's,
    whichever leaves it less. Each frame's holds where its rotation is well above its noise
    (a wide hinge), the mean pose's where the noise turns the frames more than the motion does
    (the plug-in Jacobian of a nearly collinear cluster's frame, turned by its noise, leaks
    the noise about its line into the directions it fixes). The mean pose's where each frame's
    is NaN (a frame's noise not positive definite). A compiled kernel."""
    # Each coordinate over the frames contiguous, as the frames' passes read them.
    columns = np.ascontiguousarray(vectors.T)
    _frame_noise_into(columns, moving_noise, reference_noise, noise)
    per_frame = _hinge_residual(columns, noise)
    if not per_frame < at_mean_pose:  # NaN compares false: the mean pose's then
        return at_mean_pose
    return per_frame


def _spreads_near_pi(
    relative: np.ndarray,
    moving_noise: np.ndarray,
    reference_noise: np.ndarray | None,
    variance: np.ndarray,
) -> tuple[np.ndarray, ...]:
    """:func:`_rotation_spreads` ``(raw, sums, rotation_only, own, mean)`` of the relative
    rotations ``relative`` ``(T, N, 3, 3)`` whose noise covariance per unit variance is
    ``moving_noise`` ``(T, 3, 3)`` [mm^-2] in the moving segment's frame and
    ``reference_noise`` (the same shape, or ``None``) in the reference segment's, and their
    residual ``variance`` ``(T,)`` [mm^2], through :func:`jointbench.geometry.rotation_vector`,
    which holds near pi too."""
    n_trials, n_frames = relative.shape[:2]
    mean = best_rotation(relative.mean(axis=1))
    at_mean = np.zeros_like(moving_noise)
    if reference_noise is not None:
        at_mean = np.swapaxes(mean, -1, -2) @ reference_noise @ mean
    covariance = moving_noise + at_mean
    vectors = rotation_vector(np.swapaxes(mean, -1, -2)[:, None] @ relative)
    deviation = vectors - vectors.mean(axis=1, keepdims=True)
    mu, basis = np.linalg.eigh(covariance)
    whitened = deviation @ (basis / np.sqrt(mu)[:, None, :])
    gram = np.swapaxes(deviation, 1, 2) @ deviation
    white = np.swapaxes(whitened, 1, 2) @ whitened
    own = gram - (n_frames - 1) * variance[:, None, None] * covariance
    raw, white, values = (
        np.maximum(np.linalg.eigvalsh(matrix), 0.0) for matrix in (gram, white, own)
    )
    sums = np.empty((n_trials, 2))
    sums[:, 0] = white.sum(axis=1)
    noise = np.empty((6, n_frames))
    for t in range(n_trials):
        sums[t, 1] = _hinge_left(
            white[t, 0] + white[t, 1],
            kernel_array(vectors[t]),
            kernel_array(moving_noise[t]),
            kernel_array(at_mean[t]),
            noise,
        )
    return raw, sums, values, own, mean


def _spreads(
    moving: np.ndarray,
    moving_inertia_inv: np.ndarray,
    reference: _Clusters | None,
    variance: np.ndarray,
) -> tuple[np.ndarray, ...]:
    """:func:`_rotation_spreads` ``(raw, sums, rotation_only, own, mean)`` of the rotations
    ``moving`` ``(T, N, 3, 3)`` with inverse inertia ``moving_inertia_inv`` ``(T, 3, 3)``
    [mm^-2], relative to ``reference``'s (or the identity), and their residual ``variance``
    ``(T,)`` [mm^2]; near pi through :func:`_spreads_near_pi`."""
    if reference is None:
        no_frames = np.empty((moving.shape[0], 0, 3, 3))
        arguments = (moving, moving_inertia_inv, no_frames, moving_inertia_inv)
    else:
        arguments = (moving, moving_inertia_inv, reference.rotation, reference.inertia_inv)
    *spreads, near_pi = _rotation_spreads(*arguments, variance)
    if not near_pi:
        return tuple(spreads)
    if reference is None:
        return _spreads_near_pi(moving, moving_inertia_inv, None, variance)
    relative = np.swapaxes(reference.rotation, -1, -2) @ moving
    return _spreads_near_pi(relative, moving_inertia_inv, reference.inertia_inv, variance)


class _AxisShare(NamedTuple):
    share: np.ndarray  # (T,) share of the rotation's sum of squares off its principal axis
    principal_rms_rad: np.ndarray  # (T,) RMS rotation about the principal axis
    off_rms_rad: np.ndarray  # (T,) RMS rotation about the two other axes


def _frame_step(n_frames: int) -> int:
    """The step between the frames, evenly spaced, that sample ``n_frames`` with at most
    :data:`_SHARE_FRAMES`."""
    return -(-n_frames // _SHARE_FRAMES)


@kernel
def _onto_central_frame(
    markers: np.ndarray, step: int, central: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """For every ``step``-th frame of ``markers`` ``(T, N, n, 3)`` [mm], the cross-covariance
    ``(T, F, 3, 3)`` [mm^2] of its centred markers with those ``u`` of the trial's central
    frame ``central`` ``(T,)`` (an index; :func:`_one_segment_numbers` gives the frame nearest
    the markers' mean positions: a rigid shape near the mean pose, and the same frame in any
    order of the frames), whose best rotation carries the central frame's shape onto that
    frame's (:func:`_cross_into`); and the inverse of ``u``'s inertia
    ``sum_m (|u_m|^2 I - u_m u_m')`` ``(T, 3, 3)`` [mm^-2], the covariance per unit variance
    of those rotations' noise. A compiled kernel."""
    n_trials, n_frames, n_markers, _ = markers.shape
    cross = np.empty((n_trials, (n_frames + step - 1) // step, 3, 3))
    inertia_inv = np.empty((n_trials, 3, 3))
    shape = np.empty((n_markers, 3))
    tensor = np.empty((3, 3))
    for t in range(n_trials):
        _centred_into(markers[t, int(central[t])], shape)
        _cross_into(markers[t], step, shape, cross[t])
        inertia_into(shape, tensor)
        inertia_inv[t] = np.linalg.inv(tensor)
    return cross, inertia_inv


@kernel
def _cross_into(markers: np.ndarray, step: int, shape: np.ndarray, cross: np.ndarray) -> None:
    """For every ``step``-th frame of ``markers`` ``(N, n, 3)`` [mm], the cross-covariance
    ``sum_m c_m u_m'`` [mm^2] of its centred markers ``c`` with the centred ``shape`` ``u``
    ``(n, 3)`` [mm], into ``cross`` ``(F, 3, 3)``. A compiled kernel."""
    n_markers = markers.shape[1]
    centred = np.empty((n_markers, 3))
    for s in range(cross.shape[0]):
        _centred_into(markers[s * step], centred)
        for i in range(3):
            for j in range(3):
                value = 0.0
                for m in range(n_markers):
                    value += centred[m, i] * shape[m, j]
                cross[s, i, j] = value


class _OneSegmentRotations(NamedTuple):
    """The rotations of one segment's sampled frames about their mean pose, per trial."""

    values: np.ndarray  # (T, 3) ascending eigenvalues of ``own`` (negative ones clipped) [rad^2]
    own: np.ndarray  # (T, 3, 3) their rotation vectors' scatter less its noise [rad^2]
    mean: np.ndarray  # (T, 3, 3) the mean pose M
    noise: np.ndarray  # (T, 3, 3) each rotation vector's noise covariance s^2 K^-1 [rad^2]
    n_frames: int  # the frames sampled
    rotations: np.ndarray  # (T, F, 3, 3) the sampled frames' rotations from the central one


def _one_segment_rotations(
    markers: np.ndarray, variance: np.ndarray, central: np.ndarray
) -> _OneSegmentRotations:
    """The rotations that carry the ``central`` frame's (``(T,)``, :func:`_onto_central_frame`)
    centred shape of one segment's markers ``(T, N, n, 3)`` [mm] in the reference frame onto
    each sampled frame's
    (:func:`_frame_step`, :func:`_onto_central_frame`), about their mean pose: their rotation
    vectors, which hold at any angle (unlike the one-segment pass's linearised rotations),
    less their noise (:func:`_rotation_spreads`); ``variance`` ``(T,)`` [mm^2] is the rigid
    residual per coordinate. The whole way, for the trials :func:`_sampled_axis_numbers`
    leaves to it.

    The central frame's noise is common to every rotation and, to first order, turns them
    all alike, which leaves their scatter's eigenvalues and the axis in the markers' frame as
    they are; beyond first order (a thin cluster) it is not, so the shape is chosen by a
    rule the frames' order does not change. Taken from frame 0 instead, the share off the
    principal axis of a thin cluster of the support sweep (0.02 without noise) came out
    anywhere from 0.005 to 0.26 as the frames were reordered. The markers' mean shape (each
    frame carried back by its pose and averaged) gave the same shares on the sweep's axis
    trials and a motion axis closer by 4 degrees (median, mostly thin clusters), at a second
    pose fit per frame: a third more for the verdict on an axis."""
    cross, inertia_inv = _onto_central_frame(
        kernel_array(markers), _frame_step(markers.shape[1]), central
    )
    rotations = best_rotation(cross)
    _, _, values, own, mean = _spreads(rotations, inertia_inv, None, variance)
    noise = variance[:, None, None] * inertia_inv
    return _OneSegmentRotations(values, own, mean, noise, rotations.shape[1], rotations)


def _one_segment_axes(
    markers: np.ndarray,
    variance: np.ndarray,
    central: np.ndarray,
    independent: np.ndarray | None = None,
) -> tuple[list[MotionAxis], _AxisShare]:
    """The :class:`MotionAxis` of each trial of one segment's markers ``(T, N, n, 3)`` [mm] in
    the reference frame, and how much of its rotation is about that axis
    (:func:`_axis_numbers`), from the rotations of :func:`_one_segment_rotations`;
    ``variance`` ``(T,)`` [mm^2] is the rigid residual per coordinate, ``central`` ``(T,)``
    the frame the rotations start from (:func:`_onto_central_frame`) and ``independent``
    ``(T,)`` about how many independent frames each holds (``inf``, or ``None`` for every
    trial, where the verdict did not find them otherwise), which the travel along the axis
    reads (:class:`Travel`). One compiled call
    (:func:`_sampled_axis_numbers`) where every sampled frame's rotation is Horn's and none is
    near pi from the mean pose; otherwise the rotations' own way, through the SVD and
    :func:`jointbench.geometry.rotation_vector`, which give the same numbers where both hold."""
    variance = kernel_array(variance)
    central = kernel_array(central)
    step = _frame_step(markers.shape[1])
    fused, rotations, *numbers = _sampled_axis_numbers(
        kernel_array(markers), step, variance, central
    )
    if not fused:
        found = _one_segment_rotations(markers, variance, central)
        rotations = found.rotations
        numbers = _axis_numbers(found.values, found.own, found.mean, found.noise, found.n_frames)
    directions, sd_deg, noise_share, pose_sd_deg, *shares = numbers
    axis_share = _AxisShare(*shares)
    arc_sd_deg = _arc_rotation_sd_deg(
        kernel_array(markers), variance, axis_share.principal_rms_rad, axis_share.off_rms_rad
    )
    if independent is None:
        independent = np.full(len(markers), np.inf)
    travels = _travels(
        _travel_numbers(kernel_array(markers), step, kernel_array(rotations), directions),
        independent,
    )
    axes = [
        MotionAxis(direction, sd, share, pose_sd, arc_sd, travel)
        for direction, sd, share, pose_sd, arc_sd, travel in zip(
            directions,
            sd_deg.tolist(),
            noise_share.tolist(),
            pose_sd_deg.tolist(),
            arc_sd_deg,
            travels,
            strict=True,
        )
    ]
    return axes, axis_share


class Travel(NamedTuple):
    """How far a segment moves along its motion axis as it turns about it: a hinge's segment
    does not, and every model of a fixed axis whose markers circle it excludes it (paper B
    \u00a72: "each marker trajectory is a circular path on a plane orthogonal to the AoR"). A
    marker plate sliding on its segment, or a joint with travel, moves it ``per_rad_mm``
    [mm/rad] along the axis: each marker's arc is a helix, which a plane tilted from the axis
    fits. Read from the rigid displacements between the sampled frames, not from the markers'
    positions along the axis, which rotation about a second axis moves too: the displacement
    from one frame to another along that displacement's own rotation axis (its screw
    translation, the same about whatever point it is taken), which a rotation about any fixed
    point leaves zero (a coupled or screw-home knee turns about one). The frames sorted by
    their angle about the motion axis, the first half is paired with the second, each frame in
    one pair: the pairs' displacements are independent, and the shape the rotations start from
    cancels out of each. For a pair turning by ``w`` [rad] and moving the centroid by ``d``
    [mm], ``w . d = p |w|^2`` with ``p`` the travel per radian; ``p`` is its weighted mean,
    ``sum w . d / sum |w|^2``, and ``sd_mm`` [mm/rad] its SD from the pairs' own scatter about
    it (noise, and whatever the model leaves out), over ``dof`` degrees of freedom; where the
    frames are not independent, as if only ``independent`` of them were. ``arc_rad`` is the
    range of the sampled frames' angles about the axis [rad]."""

    per_rad_mm: float
    sd_mm: float
    dof: float
    arc_rad: float

    @property
    def over_arc_mm(self) -> float:
        """The travel along the axis over the arc [mm]."""
        return self.per_rad_mm * self.arc_rad

    @property
    def p_value(self) -> float:
        """The two-sided p-value of "the segment does not travel along its axis" (a t test on
        ``dof`` degrees of freedom, as the F ratio on ``(1, dof)``); NaN without a test."""
        if not (self.dof >= 1.0 and self.sd_mm > 0.0):
            return math.nan
        return f_survival(1.0, self.dof, (self.per_rad_mm / self.sd_mm) ** 2)


def _travels(numbers: np.ndarray, independent: np.ndarray) -> list[Travel]:
    """A :class:`Travel` per row of :func:`_travel_numbers` ``numbers`` ``(T, 5)``, the pairs
    counted as no more than half of the ``independent`` frames ``(T,)`` (each pair takes two):
    where the frames share their errors, so do the pairs, and their mean's variance grows by
    as much as their count is cut."""
    travels = []
    for (per_rad, scatter, weight, n_pairs, arc), count in zip(
        numbers.tolist(), independent.tolist(), strict=True
    ):
        effective = min(n_pairs, count / 2.0)
        if n_pairs < 2 or not weight > 0.0 or effective < 2.0:
            travels.append(Travel(per_rad, math.nan, math.nan, arc))
            continue
        variance = scatter / weight**2 * n_pairs / (n_pairs - 1.0) * n_pairs / effective
        travels.append(Travel(per_rad, math.sqrt(variance), effective - 1.0, arc))
    return travels


@kernel
def _travel_numbers(
    markers: np.ndarray, step: int, rotations: np.ndarray, directions: np.ndarray
) -> np.ndarray:
    """Per trial of one segment's markers ``(T, N, n, 3)`` [mm] sampled every ``step``
    frames, with those frames' ``rotations`` ``(T, F, 3, 3)`` from one shape and the motion
    axes ``directions`` ``(T, 3)``: per trial ``(T, 5)`` the travel along the axis per radian
    ``p`` [mm/rad], the pairs' squared residuals about it ``sum (w . d - p |w|^2)^2``
    [mm^2 rad^2], their weight ``sum |w|^2`` [rad^2], the number of pairs and the arc [rad]
    (:class:`Travel`). A compiled kernel."""
    n_trials, n_sampled = rotations.shape[0], rotations.shape[1]
    n_markers = markers.shape[2]
    out = np.zeros((n_trials, 5))
    centroids = np.empty((n_sampled, 3))
    angles = np.empty(n_sampled)
    vector = np.empty(3)
    relative = np.empty((3, 3))
    half = n_sampled // 2
    dots = np.empty(half)
    squares = np.empty(half)
    for t in range(n_trials):
        for s in range(n_sampled):
            for i in range(3):
                total = 0.0
                for m in range(n_markers):
                    total += markers[t, s * step, m, i]
                centroids[s, i] = total / n_markers
            _rotation_vector_into(rotations[t, s], vector)
            angles[s] = (
                vector[0] * directions[t, 0]
                + vector[1] * directions[t, 1]
                + vector[2] * directions[t, 2]
            )
        order = np.argsort(angles, kind="mergesort")
        weight = 0.0
        moved = 0.0
        for j in range(half):
            a = order[j]
            b = order[n_sampled - half + j]
            # The rotation from frame a to frame b, R_b R_a'.
            for i in range(3):
                for k in range(3):
                    value = 0.0
                    for q in range(3):
                        value += rotations[t, b, i, q] * rotations[t, a, k, q]
                    relative[i, k] = value
            _rotation_vector_into(relative, vector)
            dot = 0.0
            square = 0.0
            for i in range(3):
                dot += vector[i] * (centroids[b, i] - centroids[a, i])
                square += vector[i] * vector[i]
            dots[j] = dot
            squares[j] = square
            moved += dot
            weight += square
        per_rad = moved / weight if weight > 0.0 else np.nan
        scatter = 0.0
        for j in range(half):
            scatter += (dots[j] - per_rad * squares[j]) ** 2
        out[t, 0] = per_rad
        out[t, 1] = scatter
        out[t, 2] = weight
        out[t, 3] = half
        out[t, 4] = angles[order[n_sampled - 1]] - angles[order[0]] if n_sampled else 0.0
    return out


@kernel
def _rotation_vector_into(matrix: np.ndarray, vector: np.ndarray) -> None:
    """The rotation vector [rad] of a rotation ``matrix`` ``(3, 3)`` into ``vector`` ``(3,)``:
    its angle from the trace and the axial part together (``atan2``), which hold to rounding
    at any angle short of pi, where the axis is left to the axial part's noise. A compiled
    kernel."""
    a0 = 0.5 * (matrix[2, 1] - matrix[1, 2])
    a1 = 0.5 * (matrix[0, 2] - matrix[2, 0])
    a2 = 0.5 * (matrix[1, 0] - matrix[0, 1])
    sine = np.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
    angle = np.arctan2(sine, 0.5 * (matrix[0, 0] + matrix[1, 1] + matrix[2, 2] - 1.0))
    # angle / sin(angle), 1 to rounding below 1e-8 rad.
    scale = angle / sine if sine > 1e-12 else 1.0
    vector[0] = scale * a0
    vector[1] = scale * a1
    vector[2] = scale * a2


@kernel
def _arc_rotation_sd_deg(
    markers: np.ndarray, variance: np.ndarray, principal_rms: np.ndarray, off_rms: np.ndarray
) -> np.ndarray:
    """Per trial and marker, the SD [deg] of one frame's rotation as the marker's arc reads
    it, from one segment's markers ``(T, N, n, 3)`` [mm] alone (:class:`MotionAxis`):
    ``s / L``, ``s^2`` the rigid residual ``variance`` ``(T,)`` [mm^2] and the marker's lever
    ``L`` its travel (its positions' RMS distance from their mean, net of the noise's
    ``3 s^2 (N - 1) / N`` in the square) over the rotation the poses measure (the RMS rotation
    about the principal axis and the two others, ``principal_rms`` and ``off_rms`` ``(T,)``
    [rad], net of their noise): ``(T, n)``, ``inf`` where a marker's travel is within its
    noise. A compiled kernel."""
    n_trials, n_frames, n_markers, _ = markers.shape
    sd_deg = np.empty((n_trials, n_markers))
    for t in range(n_trials):
        noise = 3.0 * variance[t] * (n_frames - 1) / n_frames
        rotation_sq = principal_rms[t] ** 2 + off_rms[t] ** 2
        for i in range(n_markers):
            # The three coordinates' means side by side, each summed in frame order: one
            # sum's additions wait for each other, the coordinates' do not.
            mean0 = mean1 = mean2 = 0.0
            for k in range(n_frames):
                mean0 += markers[t, k, i, 0]
                mean1 += markers[t, k, i, 1]
                mean2 += markers[t, k, i, 2]
            mean0 /= n_frames
            mean1 /= n_frames
            mean2 /= n_frames
            # Likewise the squares, per coordinate, added up after.
            squares0 = squares1 = squares2 = 0.0
            for k in range(n_frames):
                squares0 += (markers[t, k, i, 0] - mean0) ** 2
                squares1 += (markers[t, k, i, 1] - mean1) ** 2
                squares2 += (markers[t, k, i, 2] - mean2) ** 2
            travel = (squares0 + squares1 + squares2) / n_frames - noise
            # L^2 = travel / rotation_sq, so s / L = s * rotation / sqrt(travel).
            if travel <= 0.0:
                sd_deg[t, i] = np.inf
            else:
                sd_deg[t, i] = np.degrees(np.sqrt(variance[t] * rotation_sq / travel))
    return sd_deg


@kernel
def _sampled_axis_numbers(
    markers: np.ndarray, step: int, variance: np.ndarray, central: np.ndarray
) -> tuple:
    """:func:`_axis_numbers` of the rotations of :func:`_one_segment_rotations` of ``markers``
    ``(T, N, n, 3)`` [mm], sampled every ``step`` frames from the ``central`` frames ``(T,)``,
    with the rigid residual ``variance`` ``(T,)`` [mm^2], preceded by whether they hold and
    the sampled frames' rotations ``(T, F, 3, 3)``: ``False`` (and empty arrays) where
    Horn's method leaves a sampled frame's rotation to the SVD or one is within 1e-4 of pi
    from the mean pose
    (:func:`jointbench.numerics.poses.best_rotation`, :func:`_spreads`), which the caller then
    takes the whole way. A compiled kernel: the same kernels in one call, where
    the glue between them cost a one-trial check as much as their work."""
    cross, inertia_inv = _onto_central_frame(markers, step, central)
    n_trials, n_sampled = cross.shape[0], cross.shape[1]
    flat = cross.reshape((n_trials * n_sampled, 3, 3))
    rotation = np.empty_like(flat)
    unsettled = np.empty(flat.shape[0], dtype=np.bool_)
    _horn_rotations(flat, np.full(flat.shape[0], np.inf), rotation, unsettled)
    empty = np.empty(0)
    no_rotations = np.empty((0, 0, 3, 3))
    if unsettled.any():
        return False, no_rotations, np.empty((0, 3)), empty, empty, empty, empty, empty, empty
    no_frames = np.empty((n_trials, 0, 3, 3))
    sampled = rotation.reshape((n_trials, n_sampled, 3, 3))
    _, _, values, own, mean, near_pi = _rotation_spreads(
        sampled,
        inertia_inv,
        no_frames,
        inertia_inv,
        variance,
        False,
    )
    if near_pi:
        return False, no_rotations, np.empty((0, 3)), empty, empty, empty, empty, empty, empty
    noise = np.empty_like(inertia_inv)
    for t in range(n_trials):
        noise[t] = variance[t] * inertia_inv[t]
    directions, sd_deg, share, pose_sd_deg, off_share, principal, off = _axis_numbers(
        values, own, mean, noise, n_sampled
    )
    return True, sampled, directions, sd_deg, share, pose_sd_deg, off_share, principal, off


@kernel
def _axis_numbers(
    values: np.ndarray, own: np.ndarray, mean: np.ndarray, noise: np.ndarray, n_frames: int
) -> tuple:
    """Per trial, from the eigenvalues ``values`` ``(T, 3)`` [rad^2] of the rotations' own
    scatter ``own``, their mean pose ``mean`` and each one's noise ``noise`` ``(T, 3, 3)``
    over ``n_frames`` (:class:`_OneSegmentRotations`): the :class:`MotionAxis` numbers of
    :func:`_motion_axis_numbers` (axes ``(T, 3)``, their SDs [deg], noise shares), the largest
    SD [deg] of one pose's rotation (the noise's largest eigenvalue), and the three columns of
    :class:`_AxisShare`: the share of the rotation's sum of squares off the principal axis
    and the RMS rotations [rad] about it and about the two others, ``(T,)`` each. A compiled
    kernel."""
    directions, sd_deg, share = _motion_axis_numbers(own, mean, noise, n_frames)
    n_trials = values.shape[0]
    pose_sd_deg = np.empty(n_trials)
    off_share = np.empty(n_trials)
    principal = np.empty(n_trials)
    off_rms = np.empty(n_trials)
    for t in range(n_trials):
        pose_sd_deg[t] = np.degrees(np.sqrt(np.linalg.eigvalsh(noise[t])[2]))
        off = values[t, 0] + values[t, 1]
        total = off + values[t, 2]
        off_share[t] = off / total if total > 0.0 else 0.0
        principal[t] = np.sqrt(values[t, 2] / n_frames)
        off_rms[t] = np.sqrt(off / n_frames)
    return directions, sd_deg, share, pose_sd_deg, off_share, principal, off_rms


class MotionAxis(NamedTuple):
    """The principal axis of one segment's rotations about their mean pose
    (:func:`_one_segment_axes`), the motion's own axis, which any answer of an axis method can be
    compared with: ``direction`` the unit axis ``(3,)`` in the markers' frame, ``sd_deg`` its
    first-order SD [deg] and ``noise_share`` the larger, over the two directions normal to it,
    of the rotation noise's share of the rotations' scatter over its eigen-gap (from 1 up, the
    axis is not determined by the motion) and ``pose_sd_deg`` the largest SD of one pose's
    rotation [deg], about the cluster's weakest axis (where it is large, a thin cluster's, the
    first-order noise model behind the other two does not hold), and ``marker_arc_sd_deg``
    ``(n,)`` the SD [deg] of one frame's rotation as each marker's arc reads it: ``s / L``, a
    marker's lever ``L`` how far it travels against how much the poses say the segment turns,
    both net of their noise (:func:`_arc_rotation_sd_deg`); ``arc_rotation_sd_deg``, the
    smallest, is the marker's with the longest lever. A marker at a distance ``r`` from the
    axis travels ``r`` times the rotation, so ``L`` is that distance read from the data,
    whatever line an answer claims
    (:func:`jointbench.estimators.precision.annotate_motion_axis`); ``travel``, how far the
    segment moves along the axis as it turns (:class:`Travel`), where the verdict read it."""

    direction: np.ndarray
    sd_deg: float
    noise_share: float
    pose_sd_deg: float
    marker_arc_sd_deg: np.ndarray
    travel: Travel | None = None

    @property
    def arc_rotation_sd_deg(self) -> float:
        """The SD [deg] of one frame's rotation as the marker with the longest lever reads it
        (``inf`` for no marker)."""
        return float(np.min(self.marker_arc_sd_deg, initial=np.inf))


@kernel
def _motion_axis_numbers(
    own: np.ndarray, mean: np.ndarray, noise: np.ndarray, n_frames: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The :class:`MotionAxis` numbers from the rotations' own scatter ``own``, mean pose
    ``mean`` and per-frame noise ``noise`` ``(T, 3, 3)`` each over ``n_frames``
    (:func:`_one_segment_rotations`): the axes ``(T, 3)``, their SDs [deg] and noise shares
    ``(T,)``. A compiled kernel: a one-trial check pays microseconds, not the tens that small
    array operations cost.

    The rotation vectors ``w_k`` of ``M' R_k`` about the mean pose ``M`` each carry noise of
    covariance ``S = s^2 K^-1`` (the module docstring's pose covariance), so their scatter less
    the noise's, ``A = sum_k w_k w_k' - (F - 1) S``, is the rotation's own; its principal
    eigenvector ``h`` (eigenvalue ``l``), carried into the markers' frame by ``M``, is the
    axis. Noise moves ``h`` towards each other eigenvector ``e_j`` (eigenvalue ``l_j``) by
    ``e_j' dA h / (l - l_j)``, whose variance over the cross terms of the signal and the noise
    and the noise's own square is ``l_j S_hh + l S_jj + (F - 1)(S_jj S_hh + S_jh^2)``:
    ``sd_deg`` is the root of the two directions' sum. ``noise_share`` is
    ``(F - 1) S_jj / (l - l_j)``, the larger of the two: where the noise's own share reaches
    the gap the eigenvector is no longer a small perturbation of the axis (as for the planar
    scatter, :mod:`jointbench.estimators.precision`). On paper B's hinges (1 mm, 40 seeds a
    condition) the axes' RMS error matched the median SD stated within a factor of 1.3
    wherever the share was below 1."""
    n_trials = own.shape[0]
    directions = np.empty((n_trials, 3))
    sd_deg = np.empty(n_trials)
    share = np.empty(n_trials)
    for t in range(n_trials):
        values, vectors = np.linalg.eigh(own[t])
        # The noise in the scatter's eigenbasis: S_jj, S_hh and S_jh, h the last eigenvector.
        basis_noise = vectors.T @ noise[t] @ vectors
        top = max(values[2], 0.0)
        along = basis_noise[2, 2]
        variance = 0.0
        largest = 0.0
        for j in range(2):
            gap = top - max(values[j], 0.0)
            normal = basis_noise[j, j]
            # A gap that is not positive leaves the eigenvector anywhere in its plane.
            if gap <= 0.0:
                variance = np.inf
                largest = np.inf
                continue
            moved = max(values[j], 0.0) * along + top * normal
            moved += (n_frames - 1) * (normal * along + basis_noise[j, 2] ** 2)
            variance += moved / gap**2
            largest = max(largest, (n_frames - 1) * normal / gap)
        sd_deg[t] = np.degrees(np.sqrt(variance))
        share[t] = largest
        directions[t] = mean[t] @ vectors[:, 2]
    return directions, sd_deg, share


@kernel
def _rotation_ratios(
    raw: np.ndarray,
    sums: np.ndarray,
    variance: np.ndarray,
    exact: np.ndarray,
    n_frames: int,
    any_dof: int,
    off_axis: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What :func:`_rotation_test` reads of :func:`_spreads`' ``raw`` ``(T, 3)`` [rad^2] and
    ``sums`` ``(T, 2)`` over ``n_frames``: the RMS rotation and the RMS
    rotation about all but the dominant axis [rad], ``(T,)`` each, and the two tests' F ratios
    ``(2, T)``, each sum over its degrees of freedom (``any_dof``; ``off_axis``, at least 1)
    over the noise, ``variance`` ``(T,)`` [mm^2], or 1 where ``exact`` ``(T,)`` (rounding
    only). Each number from the same operations in the same order as NumPy's forms of them, so
    the same bits. A compiled kernel: a dozen NumPy operations on arrays of one trial cost a
    checked call tens of microseconds."""
    n_trials = raw.shape[0]
    off_dof = max(off_axis, 1)
    rms = np.empty(n_trials)
    second = np.empty(n_trials)
    ratios = np.empty((2, n_trials))
    for t in range(n_trials):
        lesser = raw[t, 0] + raw[t, 1]
        rms[t] = np.sqrt((lesser + raw[t, 2]) / n_frames)
        second[t] = np.sqrt(lesser / n_frames)
        noise = 1.0 if exact[t] else variance[t]
        ratios[0, t] = sums[t, 0] / any_dof / noise
        ratios[1, t] = sums[t, 1] / off_dof / noise
    return rms, second, ratios


def _rotation_test(
    moving: _Clusters,
    reference: _Clusters | None,
    variance: np.ndarray,
    dof: int,
    exact: np.ndarray,
) -> _Rotation:
    """The rotation of ``moving`` relative to ``reference`` (or the identity) against noise,
    per trial; ``variance`` ``(T,)`` [mm^2], ``exact`` ``(T,)`` where it is rounding only."""
    # The eigenvalues of the Gram matrix of the rotation vectors about the mean pose
    # (ascending, rounding's negative zeros clipped), and per unit variance (under "no
    # rotation" each coordinate of each frame is noise of variance s^2) their whitened sum of
    # squares and what a hinge leaves of them.
    raw, sums, *_ = _spreads(moving.rotation, moving.inertia_inv, reference, variance)
    n_frames = moving.rotation.shape[1]
    # fdtrc(d1, d2, x) is the F survival function (scipy.stats would import far more).
    fdtrc = scipy_special().fdtrc
    any_dof = 3 * (n_frames - 1)
    # A hinge fits each frame's angle, its axis and the offset normal to it: two frames are
    # always on one, and leave nothing to test.
    off_axis = 2 * (n_frames - 2)
    rms, second, ratios = _rotation_ratios(
        kernel_array(raw),
        kernel_array(sums),
        kernel_array(variance),
        kernel_array(exact, np.bool_),
        n_frames,
        any_dof,
        off_axis,
    )
    # Both tests in one call: "any rotation" (3 (N - 1) degrees of freedom) and "rotation
    # about a second axis" (2 (N - 2)).
    p_any, p_second = fdtrc(np.array([[any_dof], [max(off_axis, 1)]]), dof, ratios)
    if off_axis <= 0:
        p_second = np.ones_like(p_second)
    # Noise-free data: a rotation above rounding is resolved, and rotation about other axes is
    # judged against the main one (the F-test would compare rounding with rounding).
    if exact.any():
        p_any = np.where(exact, (rms <= _ROUNDING_ROTATION_RAD).astype(float), p_any)
        p_second = np.where(exact, (raw[:, 1] <= 1e-12 * raw[:, 2]).astype(float), p_second)
    return _Rotation(rms, p_any, second, p_second)


def assess_many(
    kind: str, arrays: tuple[np.ndarray, ...], *, poses: list | None = None
) -> list[Support]:
    """:func:`assess` for ``T`` trials at once: ``arrays`` as there with a leading trial axis,
    ``(T, N, n, 3)`` each, and ``poses`` one entry per trial as there; one :class:`Support`
    per trial."""
    _check_judged_frames(kind, arrays)
    if len(arrays) == 1:
        # One segment's pass gives the block test and the lag-1 statement their numbers
        # (_one_segment): its stages share nothing through a scope, and none is opened.
        return _judged_untested(kind, arrays, poses)
    # The numbers the verdict's stages share (_segment_frame_numbers) are kept for this verdict
    # alone: the scope of the checked call around it also holds the fit, where an estimator's
    # own code may judge trial after trial refilled into one array.
    with one_call():
        return _judged_untested(kind, arrays, poses)


def _judged_untested(
    kind: str, arrays: tuple[np.ndarray, ...], poses: list | None
) -> list[Support]:
    """:func:`assess_many` after its check of the frames: the verdicts of :func:`_judged`,
    each with what the frames' lag-1 autocorrelation says where the block test does not."""
    verdicts, frame_numbers = _judged(kind, arrays, poses)
    flags = [not verdict.caveats for verdict in verdicts]
    untested = _untested(ARRAY_NAMES[kind], arrays, flags, frame_numbers)
    return [
        verdict if found is None else verdict._replace(untested=found)
        for verdict, found in zip(verdicts, untested, strict=True)
    ]


def _check_judged_frames(kind: str, arrays: tuple[np.ndarray, ...]) -> None:
    """Raise ``ValueError`` naming the first of ``arrays`` ``(T, N, n, 3)`` (named by
    :data:`ARRAY_NAMES` for ``kind``) with fewer than :data:`MIN_JUDGED_FRAMES` frames."""
    for name, array in zip(ARRAY_NAMES[kind], arrays, strict=True):
        if array.shape[1] < MIN_JUDGED_FRAMES:
            raise ValueError(
                f"{name} has {array.shape[1]} frames; the support verdict needs at least "
                f"{MIN_JUDGED_FRAMES} (its tests of a straight line and of a hinge have "
                "2 (frames - 2) degrees of freedom)"
            )


def _judged(
    kind: str, arrays: tuple[np.ndarray, ...], poses: list | None
) -> tuple[list[Support], np.ndarray | None]:
    """The verdicts of :func:`assess_many` but for what the frames' lag-1 autocorrelation
    says where the block test does not (:class:`Untested`), and the one segment's
    :func:`_frame_numbers` ``(T, 5)`` where the verdict's pass computed them (else ``None``)."""
    n_trials = arrays[0].shape[0]
    # Every array has MIN_JUDGED_FRAMES frames or more: _check_judged_frames refused the rest.
    if len(arrays) == 1 and arrays[0].shape[2] >= 3:
        n_markers = arrays[0].shape[2]
        if n_markers > MAX_DISTANCE_MARKERS:
            reason = (
                f"{n_markers} markers, more than the {MAX_DISTANCE_MARKERS} whose pairwise "
                "distances the rigidity test compares"
            )
            # One pass over the pairs (thousands of markers have millions) for every trial's
            # verdict and its lag-1 statement alike.
            numbers = _frame_numbers(kernel_array(arrays[0]))
            return [
                _without_poses((trial,), reason, has_pose=True, frame_numbers=row)
                for trial, row in zip(arrays[0], numbers, strict=True)
            ], numbers
        return _one_segment(kind, arrays[0])
    if len(arrays) > 1:
        check_poses(arrays, poses, ARRAY_NAMES[kind])
    if not all(_poses_defined(array) for array in arrays):
        if n_trials > 1:
            each = [
                assess(
                    kind,
                    tuple(array[t] for array in arrays),
                    poses=None if poses is None else poses[t],
                )
                for t in range(n_trials)
            ]
            return each, None
        one = tuple(array[0] for array in arrays)
        return [_without_poses(one, "no 3 non-collinear markers")], None
    if poses is None:
        poses = _fitted_poses(kind, arrays)
    verdicts: list = [None] * n_trials
    fitted = []
    for t, trial in enumerate(poses):
        if isinstance(trial, Exception):
            one = tuple(array[t] for array in arrays)
            verdicts[t] = _without_poses(one, f"the pose fit failed ({trial})")
        else:
            fitted.append(t)
    if fitted:
        if len(fitted) < n_trials:
            arrays = tuple(array[fitted] for array in arrays)
        judged = _two_segments(kind, arrays, [poses[t] for t in fitted])
        for t, verdict in zip(fitted, judged, strict=True):
            verdicts[t] = verdict
    return verdicts, None


def _fitted_poses(kind: str, arrays: tuple[np.ndarray, ...]) -> list:
    """Per trial of ``arrays`` ``(T, N, n, 3)`` each, the poses of every segment (a dict by
    the names of :data:`jointbench.estimators.validation.ARRAY_NAMES`), or the ``ValueError``
    of a trial whose poses cannot be fitted; all trials in one call."""
    return trial_poses(dict(zip(ARRAY_NAMES[kind], arrays, strict=True)), min_frames=2)


def _one_segment(kind: str, markers: np.ndarray) -> tuple[list[Support], np.ndarray]:
    """The verdicts on one segment's markers ``(T, N, n >= 3, 3)`` in the reference frame, from
    one compiled call (module docstring, "one segment"), and for an axis the rotations of the
    trials that rotate about more than one axis (:func:`_one_segment_axes`); and the
    markers' :func:`_frame_numbers` ``(T, 5)``, which that call gives too."""
    numbers = _one_segment_numbers(kernel_array(markers), _FLEX)
    rows = numbers[:, : len(_ONE_SEGMENT_COLUMNS)].tolist()
    # Per trial in one pass (a checked one-trial call pays for every pass over the trials):
    # why it has no pose, its tests, and where it has a pose, how independent its frames are.
    no_pose: list[str | None] = []
    tests: list[tuple[float, float, float, float]] = []
    frames: dict[int, _Frames] = {}
    for t, row in enumerate(rows):
        reason = _no_pose_reason(row)
        no_pose.append(reason)
        p_any = _p_value(row, _ROTATION_TEST)
        p_least = _p_value(row, _LEAST_MOVING_TEST)
        p_axis = _p_value(row, _ROTATION_AXIS_TEST)
        # The hinge is given the candidate axis that explains the data better.
        hinge, p_hinge = (
            (_ROTATION_AXIS_TEST, p_axis) if p_axis > p_least else (_LEAST_MOVING_TEST, p_least)
        )
        tests.append((row[_ROTATION_TEST], p_any, row[hinge], p_hinge))
        if reason is None:
            frames[t] = _segment_frames(row[_DEPENDENCE], "markers", markers[t])
    # For an axis: the motion's own axis of every trial with a pose, and where rotation off
    # the main axis is resolved, how much of the rotation it is (a centre needs neither).
    shares: dict[int, tuple[float, ...]] = {}
    axes: dict[int, MotionAxis] = {}
    posed = list(frames)
    if kind not in CENTRE_KINDS and posed:
        # Every trial has a pose, as a rule: its markers are not copied.
        found_axes, found = _one_segment_axes(
            markers if len(posed) == len(markers) else markers[posed],
            numbers[posed, 0],
            numbers[posed, _CENTRAL_FRAME],
            np.array([frames[t].independent if frames[t].dependent() else np.inf for t in posed]),
        )
        axes = dict(zip(posed, found_axes, strict=True))
        by_trial = zip(posed, zip(*(column.tolist() for column in found), strict=True), strict=True)
        shares = {t: share for t, share in by_trial if tests[t][3] < ROTATION_ALPHA}
    by_noise = _noise_directions(markers, numbers, frames)
    return [
        _without_poses((markers[t],), no_pose[t])
        if no_pose[t] is not None
        else _verdict(
            kind,
            ("markers",),
            [(row[1], math.sqrt(3.0 * row[0]))],
            row[0],
            tests[t],
            shares.get(t),
            axes.get(t),
            frames=frames[t],
            noise_directions=by_noise.get(t),
        )
        for t, row in enumerate(rows)
    ], numbers[:, -_FRAME_COLUMNS:]


def _p_value(row: list[float], column: int) -> float:
    """The p-value of the test of a trial's :func:`_one_segment_numbers` ``row`` whose columns
    start at ``column`` (one of :data:`_ROTATION_TEST`, :data:`_LEAST_MOVING_TEST`,
    :data:`_ROTATION_AXIS_TEST`): the F survival of its ratio on its numerator's degrees of
    freedom over the residual's."""
    return f_survival(row[column + 2], row[_RESIDUAL_DOF], row[column + 1])


def _noise_directions(
    markers: np.ndarray, numbers: np.ndarray, frames: dict[int, _Frames]
) -> dict[int, by_direction.NoiseDirections]:
    """Per trial of one segment's markers ``(T, N, n >= 3, 3)`` [mm] that has a pose
    (``frames``, by trial), whether their noise is the same in every direction
    (:mod:`jointbench.estimators.noise_directions`): from the verdict's pass ``numbers``
    (:func:`_one_segment_numbers`) where the frames are independent, else over blocks of about
    as many frames as one independent frame spans, by a pass of its own."""
    posed = list(frames)
    if not posed:
        return {}
    every = len(posed) == len(markers)
    found = numbers[:, len(_ONE_SEGMENT_COLUMNS) : -_FRAME_COLUMNS]
    if not every:
        found = found[posed]
    dependent = [i for i, t in enumerate(posed) if frames[t].dependent()]
    if dependent:
        chosen = [posed[i] for i in dependent]
        blocks = np.array([_frames_per_independent(frames[t]) for t in chosen])
        ranks = np.rint(numbers[chosen, _RESIDUAL_DOF] / (markers.shape[1] - 1))
        found[dependent] = by_direction.sphericity_numbers(
            markers[chosen], numbers[chosen, 0], ranks, blocks, _FLEX, ROUNDING
        )
    found = by_direction.judged(
        markers if every else markers[posed], found, _noise_critical_ratio, f_survival
    )
    return dict(zip(posed, found, strict=True))


@functools.cache
def _noise_critical_ratio(dof: int) -> float:
    """The F ratio on ``(5, dof)`` degrees of freedom beyond which the noise-direction test
    rejects (:data:`jointbench.estimators.noise_directions.NOISE_DIRECTION_ALPHA`), held per
    ``dof``: the F quantile once per recording length, not per checked call."""
    return float(scipy_special().fdtri(5.0, dof, 1.0 - by_direction.NOISE_DIRECTION_ALPHA))


def _frames_per_independent(frames: _Frames) -> int:
    """About how many consecutive frames one independent frame spans: 1 unless the frames
    are not independent (:class:`_Frames`)."""
    if not frames.dependent():
        return 1
    return max(1, round(frames.n_frames / frames.independent))


def _no_pose_reason(row: list[float]) -> str | None:
    """Why a trial's :func:`_one_segment_numbers` ``row`` gives no pose, or ``None``."""
    _, share, weakest, collinear = row[:4]
    if collinear:
        return "no 3 non-collinear markers"
    if weakest > MAX_POSE_SD_RAD and share < MAX_NONRIGID_SHARE:
        return (
            "nearly collinear markers (their pose is determined to "
            f"{math.degrees(weakest):.2g} deg about their line)"
        )
    return None


def _two_segments(kind: str, arrays: tuple[np.ndarray, ...], poses: list[dict]) -> list[Support]:
    """The verdicts on two segments' markers ``(T, N, n >= 3, 3)`` each, in the world frame,
    from their rigid-body poses ``poses`` (per trial, a :class:`SegmentPoses` by segment name;
    module docstring, "two segments")."""
    n_trials = arrays[0].shape[0]
    names = ARRAY_NAMES[kind]
    clusters = [
        _clusters(array, [trial[name] for trial in poses])
        for name, array in zip(names, arrays, strict=True)
    ]
    # functools.reduce, not sum or np.maximum.reduce: one cluster needs no arithmetic, and these
    # small array operations are most of the verdict's cost outside the compiled passes.
    dof = sum(cluster.dof for cluster in clusters)
    variance = functools.reduce(operator.add, [cluster.residual_ss for cluster in clusters]) / dof
    largest = functools.reduce(np.maximum, [cluster.largest for cluster in clusters])
    exact = variance <= (ROUNDING * largest) ** 2
    frames = _segments_frames(names, arrays)
    # The F-tests divide by the pooled s^2, but each segment's poses carry their own noise:
    # charged with the pooled s^2, a compact cluster beside a noisier one reads far noisier than
    # it is and the noisier one less noisy, and a pure hinge then passes as rotating about a
    # second axis.
    weighted = [_with_own_noise(cluster, variance) for cluster in clusters]
    reference = weighted[0] if kind == "joint_center" else None
    rotation = _rotation_test(weighted[-1], reference, variance, dof, exact)
    # A rotation about the cluster's weakest axis worse determined than this (noise s over the
    # markers' spread about that axis) leaves the pose to the noise (nearly collinear markers):
    # the first-order tests above do not hold, and the data are judged without poses.
    weakest = np.sqrt(
        functools.reduce(np.maximum, [c.weakest_variance for c in weighted]) * variance
    )
    noise = _centre_pose_noise(clusters) if kind == "joint_center" else None
    return [
        _without_poses(
            tuple(array[t] for array in arrays),
            f"nearly collinear markers (their pose is determined to {np.degrees(weakest[t]):.2g}"
            " deg about their line)",
        )
        # Markers that keep no shape are reported as such (_verdict), collinear or not.
        if weakest[t] > MAX_POSE_SD_RAD
        and all(cluster.nonrigid_share[t] < MAX_NONRIGID_SHARE for cluster in clusters)
        else _verdict(
            kind,
            names,
            [(c.nonrigid_share[t], np.sqrt(3.0 * c.variance[t])) for c in clusters],
            float(variance[t]),
            (
                rotation.rms_rad[t],
                rotation.p_any[t],
                rotation.second_rms_rad[t],
                rotation.p_second[t],
            ),
            frames=frames[t],
            pose_noise=None if noise is None else noise[t],
        )
        for t in range(n_trials)
    ]


def _with_own_noise(cluster: _Clusters, pooled: np.ndarray) -> _Clusters:
    """``cluster`` with its inverse inertia (and its largest eigenvalue) scaled by its own
    rigid-body residual over the ``pooled`` one ``(T,)`` [mm^2], so that ``pooled`` times it is
    the covariance ``s^2 K^-1`` of its poses' rotations with its own ``s^2``; unscaled where
    the pooled residual is zero."""
    inertia_inv, weakest_variance = _scaled_to_own_noise(
        kernel_array(cluster.variance),
        kernel_array(pooled),
        cluster.inertia_inv,
        cluster.weakest_variance,
    )
    return cluster._replace(inertia_inv=inertia_inv, weakest_variance=weakest_variance)


@kernel
def _scaled_to_own_noise(
    own: np.ndarray,
    pooled: np.ndarray,
    inertia_inv: np.ndarray,
    weakest_variance: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_with_own_noise`'s ``inertia_inv`` ``(T, 3, 3)`` [mm^-2] and
    ``weakest_variance`` ``(T,)`` [mm^-2], each times the weight ``own / pooled`` per trial
    (a cluster's own residual variance, :attr:`_Clusters.variance`, over the pooled one,
    ``(T,)`` [mm^2] each; 1 where ``pooled`` is not positive), as new arrays: the same
    operations as NumPy's, so the same bits. A compiled kernel: NumPy's half dozen operations
    on one trial's arrays cost a checked call tens of microseconds."""
    scaled = np.empty_like(inertia_inv)
    weakest = np.empty_like(weakest_variance)
    for t in range(pooled.shape[0]):
        weight = own[t] / pooled[t] if pooled[t] > 0.0 else 1.0
        for i in range(3):
            for j in range(3):
                scaled[t, i, j] = inertia_inv[t, i, j] * weight
        weakest[t] = weakest_variance[t] * weight
    return scaled, weakest


def _centre_pose_noise(clusters: list[_Clusters]) -> list[PoseNoise]:
    """Per trial, what the noise in the proximal and distal ``clusters``' poses, each at its own
    residual, does to a least-squares joint centre
    (:func:`jointbench.estimators.pose_noise.pose_noise`)."""
    return pose_noise(
        *(NoisyPoses(c.rotation, c.body, c.inertia_inv, c.variance) for c in clusters)
    )


class _Frames(NamedTuple):
    """How the frames of a trial depend on each other (:func:`_frame_dependence`), read from
    the pair distances of the segment ``name``
    (:data:`jointbench.estimators.validation.ARRAY_NAMES`): their lag-1 autocorrelation, the
    variance ratio furthest beyond what independent frames allow, its block length [frames]
    and that excess (NaN where the distances are rounding); over how many frames; and where
    the frames are not independent, about how many independent ones they hold."""

    correlation: float
    ratio: float
    block: float
    excess: float
    n_frames: int
    name: str
    independent: float = math.nan

    def dependent(self) -> bool:
        """Whether some block length's variance ratio is resolved and reaches
        :data:`MIN_VARIANCE_RATIO`."""
        return self.excess >= 1.0

    def caveats(self) -> tuple[str, ...]:
        """The verdict's caveat where the frames are not independent, else none."""
        if not self.dependent():
            return ()
        return (
            f"the frames are not independent: the means of the {_LABELS[self.name]}' distances "
            "over blocks of "
            f"{self.block:.0f} frames vary {self.ratio:.3g} times as much as independent frames' "
            f"would (lag-1 autocorrelation {self.correlation:.2f}), as filtered, interpolated or "
            "resampled frames, markers moving on the skin and slow drifts make them: every "
            f"p-value and SD of this fit counts {self.n_frames} independent frames where there "
            f"are about {_count(self.independent)}, so its SD understates the error by a "
            "factor those counts do not give (an answer fitted to the motion's smooth course "
            f"is no mean of the frames): {PRECISION_NOT_DETERMINED} (a recording's "
            "moving-block bootstrap, n_bootstrap or --bootstrap, over blocks of three times "
            "the frames one of those spans or more understates the scatter far less)",
        )

    def numbers(self) -> dict[str, float]:
        """The verdict's numbers: the lag-1 autocorrelation and the variance ratio with its
        block length where they were read, and where the frames are not independent, about
        how many independent ones they hold."""
        if math.isnan(self.correlation):
            return {}
        numbers = {"frame_correlation": self.correlation}
        if not math.isnan(self.ratio):
            numbers["frame_variance_ratio"] = self.ratio
            numbers["frame_variance_ratio_block"] = self.block
        if self.dependent():
            numbers["independent_frames"] = self.independent
        return numbers


def _count(value: float) -> str:
    """``value`` as a count in prose: whole above 10, two figures below."""
    return f"{value:.0f}" if value >= 10.0 else f"{value:.2g}"


def _segment_frames(dependence: list[float], name: str, markers: np.ndarray) -> _Frames:
    """The :class:`_Frames` of the segment ``name`` whose markers ``(N, n, 3)`` [mm] have the
    pair distances' ``dependence`` (the four numbers of :func:`_frame_dependence`), counting
    their independent frames where they are not independent (:func:`_independent_frames`;
    only then, at a cost a one-trial check would otherwise pay)."""
    correlation, ratio, block, excess = dependence
    n_frames = markers.shape[0]
    if not excess >= 1.0:
        return _Frames(correlation, ratio, block, excess, n_frames, name)
    independent = _independent_frames(_pair_distances(markers).T)
    return _Frames(correlation, ratio, block, excess, n_frames, name, independent)


def _independent_frames(distances: np.ndarray) -> float:
    """About how many independent frames the ``distances`` ``(N, K)`` [mm] (K of them per
    frame) hold: ``N / tau``, ``tau = 1 + 2 sum_k rho_k`` their integrated autocorrelation time
    (``rho_k`` pooled over the ``K`` as :func:`_frame_dependence` pools ``rho_1``), summed by
    Geyer's initial monotone sequence: the lags' pairs ``rho_2m + rho_2m+1`` while they are
    positive, each at most the one before. ``N / tau`` independent frames of the same variance
    have the mean's variance that these do: noise that keeps a share ``r`` of itself from frame
    to frame gives ``tau = (1 + r) / (1 - r)``, and noisy frames interpolated linearly ``m``
    times about ``1.5 m`` (the interpolated frames vary less than the noise they come from)."""
    deviations = distances - distances.mean(axis=0)
    n_frames = deviations.shape[0]
    spectrum = np.fft.rfft(deviations, n=2 * n_frames, axis=0)
    covariance = np.fft.irfft(spectrum * spectrum.conj(), n=2 * n_frames, axis=0)[:n_frames]
    pooled = covariance.sum(axis=1)
    correlation = pooled / pooled[0]
    pairs = correlation[: n_frames - n_frames % 2].reshape(-1, 2).sum(axis=1)
    ends = np.flatnonzero(pairs <= 0.0)
    pairs = np.minimum.accumulate(pairs[: ends[0] if ends.size else pairs.size])
    tau = max(2.0 * float(pairs.sum()) - 1.0, 1.0)
    return n_frames / tau


def _segments_frames(names: tuple[str, ...], arrays: tuple[np.ndarray, ...]) -> list[_Frames]:
    """Per trial of the segments' markers ``arrays`` ``(T, N, n, 3)`` each (named ``names``),
    the :class:`_Frames` of the segment whose frames are the further from independent (the
    larger excess of :func:`_frame_dependence`), of those whose distances are not rounding."""
    dependence = [_segment_frame_numbers(array) for array in arrays]
    frames = []
    for t in range(arrays[0].shape[0]):
        readable = [k for k in range(len(arrays)) if math.isfinite(dependence[k][t, 0])]
        worst = (
            max(readable, key=lambda segment: dependence[segment][t, 3])
            if readable
            else len(arrays) - 1
        )
        frames.append(
            _segment_frames(dependence[worst][t, :4].tolist(), names[worst], arrays[worst][t])
        )
    return frames


class Untested(NamedTuple):
    """Frames whose independence the verdict did not establish: too few to test
    (:data:`MIN_TESTED_FRAMES`) or tested without the block test rejecting it, whose pair
    distances' lag-1 autocorrelation (pooled as :func:`_frame_dependence` pools it), read from
    the segment ``name``, is not clearly below :data:`DEPENDENT_CORRELATION`: at or above
    ``bound``, that correlation less :data:`_Z_CLEARED` of the SDs ``n_frames`` independent
    frames would give it (:func:`_correlation_sd`). Every SD and p-value of the fit counts each
    frame as independent, and a short stretch of a recording, whose consecutive frames share
    their skin motion and their filter's smoothing, seldom is (22 frames of the knee trial:
    0.87; 32: 0.92, where the block test did not reject them).

    One rule at every length, the lag-1 statement wherever the block test gives no caveat,
    rather than a length below which it applies: where the block test is weak (tens of
    frames; at 120 frames it names noise keeping half of itself from frame to frame in a
    fraction of trials) the statement is what flags correlated frames, and where it is strong
    the statement costs independent frames little. Their correlation scatters about 0 by
    ``sd``, about ``1 / sqrt(P N)`` for ``P`` pairs of their own noise, so the bound
    ``0.2 - 1.64 sd`` stands ``0.2 / sd - 1.64`` of those SDs above it, a margin that grows
    as ``sqrt(N)``: of 100 trials of independent noise on four markers, 12 to 29 read the
    statement at 32 frames, at most 1 at 120 and none at 500 (README). Independent frames
    (simulated, resampled) are cleared where their correlation can show it: most 22-frame
    trials of six-marker clusters, fewer of three, whose correlation spreads more.
    Noise-free distances have no correlation to read, and are not named; fewer frames than
    the test needs whose segments have one marker each have none either, and are
    (``correlation`` and ``bound`` NaN: nothing clears them)."""

    name: str
    n_frames: int
    correlation: float
    bound: float

    @property
    def tested(self) -> bool:
        """Whether the block test was made (and did not reject the frames' independence)."""
        return self.n_frames >= MIN_TESTED_FRAMES

    @property
    def dependent(self) -> bool:
        """Whether the correlation shows the frames not independent by the caveat's own
        measure: at or above :data:`DEPENDENT_CORRELATION`, where an SD counting every frame
        understates the scatter by ``sqrt(MIN_VARIANCE_RATIO)`` or more, and resolved from 0
        at :data:`ROTATION_ALPHA`, the block test's level (by the SDs independent frames give
        it, ``(DEPENDENT_CORRELATION - bound) / _Z_CLEARED``). False where no correlation was
        read (NaN)."""
        sd = (DEPENDENT_CORRELATION - self.bound) / _Z_CLEARED
        return self.correlation >= DEPENDENT_CORRELATION and self.correlation > _Z_SHARED[0] * sd

    def words(self) -> str:
        """The status's words."""
        found = (
            "the frames' dependence test did not reject their independence over "
            f"{self.n_frames} frames, but"
            if self.tested
            else f"the frames' independence was not tested: the test needs {MIN_TESTED_FRAMES} "
            f"frames and this fit has {self.n_frames};"
        )
        if math.isnan(self.correlation):
            read = (
                "no segment has two markers, whose distance's lag-1 autocorrelation could "
                "clear them"
            )
        else:
            read = (
                f"the lag-1 autocorrelation of the {_LABELS[self.name]}' distances, "
                f"{self.correlation:.2f}, is not clearly below {DEPENDENT_CORRELATION:.2g} "
                f"(below {self.bound:.2f}, {_Z_CLEARED:.3g} of its SDs for independent frames "
                "under it), at which an SD that counts every frame as independent understates "
                f"the scatter by {math.sqrt(MIN_VARIANCE_RATIO):.3g} times"
            )
        said = (
            f"{found} {read}: its SDs and p-values count each frame as independent, which "
            "consecutive frames of a recording seldom are: fit a longer stretch"
        )
        if not self.dependent:
            return said
        return (
            f"{said}; that correlation, over {_Z_SHARED[0]:.3g} of those SDs above 0, shows "
            f"the frames not independent: {PRECISION_NOT_DETERMINED}"
        )

    def numbers(self) -> dict[str, float]:
        """The diagnostics: the frames fitted, under ``frames_independence_untested`` where
        they were too few to test and ``frames_independence_unconfirmed`` where the test did
        not reject them, and the bound their correlation did not clear."""
        key = "unconfirmed" if self.tested else "untested"
        return {
            f"frames_independence_{key}": self.n_frames,
            "frames_independence_bound": self.bound,
        }


def _untested(
    names: tuple[str, ...],
    arrays: tuple[np.ndarray, ...],
    unflagged: list[bool],
    frame_numbers: np.ndarray | None = None,
) -> list[Untested | None]:
    """Per trial of the segments' markers ``arrays`` ``(T, N, n, 3)`` each (named ``names``),
    the :class:`Untested` of the segment whose lag-1 autocorrelation is the furthest above its
    bound, where the trial is ``unflagged`` (its verdict carries no caveat of frames that are not
    independent); ``None`` where it is not, or no segment's correlation is at or above its
    bound (or noise-free distances leave none to read). Where no segment has two markers (or
    there are fewer than two frames), no correlation can clear the frames: below
    :data:`MIN_TESTED_FRAMES` frames an :class:`Untested` whose ``correlation`` and ``bound``
    are NaN; from them on ``None``, the block test having had no distances either (a single
    marker's blind spot, which the README names). ``frame_numbers``: one segment's
    :func:`_frame_numbers` ``(T, 5)`` where the verdict's pass already computed them."""
    n_trials, n_frames = arrays[0].shape[:2]
    found: list[Untested | None] = [None] * n_trials
    trials = [t for t, flag in enumerate(unflagged) if flag]
    if not trials:
        return found
    read = []
    for name, array in zip(names, arrays, strict=True):
        if array.shape[2] >= 2 and n_frames >= 2:  # a pair's distance over two frames at least
            part = slice(None) if len(trials) == n_trials else trials
            if frame_numbers is not None:
                numbers = frame_numbers[part]
            elif len(arrays) > 1:
                # The block test's numbers of every trial (_segments_frames), found again.
                numbers = _segment_frame_numbers(array)[part]
            else:
                # One segment judged without its pass (_without_poses) reads a pass of its
                # own: the trials the caveat closed, most of a long correlated recording's,
                # are not passed over here.
                numbers = _frame_numbers(kernel_array(array[part]))
            read.append((name, numbers.tolist()))
    if not read:
        if n_frames < MIN_TESTED_FRAMES:
            for t in trials:
                found[t] = Untested(names[0], n_frames, math.nan, math.nan)
        return found
    for row, t in enumerate(trials):
        worst = None
        for name, numbers in read:
            correlation, sd = numbers[row][0], numbers[row][4]
            if not math.isfinite(correlation):
                continue
            bound = DEPENDENT_CORRELATION - _Z_CLEARED * sd
            if correlation >= bound and (
                worst is None or correlation - bound > worst.correlation - worst.bound
            ):
                worst = Untested(name, n_frames, correlation, bound)
        found[t] = worst
    return found


@kernel
def _correlation_sd(distances: np.ndarray) -> float:
    """The SD of the lag-1 autocorrelation pooled over the pair ``distances`` ``(P, N)`` [mm]
    (:func:`_frame_dependence`) that ``N`` independent frames of their covariance give it
    (:func:`_scatter_correlation_sd`), from their scatter ``(P, P)``: for no more pairs than
    frames (:func:`_trial_frame_numbers_into`; more are read by
    :func:`_streamed_frame_numbers_into`). The distances are made their deviations from their
    means, in place. A compiled kernel: every checked fit reads it, where NumPy's calls on
    these small arrays cost tens of microseconds."""
    n_pairs, n_frames = distances.shape
    deviations = distances
    for p in range(n_pairs):
        _deviations_in_place(deviations[p])
    scatter = np.empty((n_pairs, n_pairs))
    for p in range(n_pairs):
        for q in range(p, n_pairs):
            product = 0.0
            for f in range(n_frames):
                product += deviations[p, f] * deviations[q, f]
            scatter[p, q] = scatter[q, p] = product
    return _scatter_correlation_sd(scatter, n_frames)


@kernel
def _deviations_in_place(values: np.ndarray) -> None:
    """``values`` ``(N,)`` made their deviations from their mean, in place. A compiled
    kernel."""
    n = values.shape[0]
    mean = 0.0
    for f in range(n):
        mean += values[f]
    mean /= n
    for f in range(n):
        values[f] -= mean


@kernel
def _scatter_correlation_sd(scatter: np.ndarray, n_frames: int) -> float:
    """The SD of the lag-1 autocorrelation pooled over pair distances (:func:`_frame_dependence`)
    whose deviations from their means over ``n_frames`` frames have the ``scatter`` ``(P, P)``
    [mm^2], ``N C`` for their covariance ``C``, that ``N`` independent frames give it:
    ``sqrt(N - 1) |C|_F / (N tr C)`` (NaN where every deviation is zero). The pooled products
    of neighbouring frames' deviations sum ``N - 1`` terms of variance ``|C|_F^2`` (pairs that
    share a marker share its noise), over the pooled squares, ``N tr C``: ``1 / sqrt(N)`` for
    one pair, ``1 / sqrt(P N)`` for ``P`` pairs of their own noise each. Only the upper
    triangle is read, and only the trace and the Frobenius norm: the deviations' Gram matrix
    over the frames ``(N, N)`` serves as well (:func:`_correlation_sd`). A compiled kernel."""
    n_pairs = scatter.shape[0]
    trace = 0.0
    frobenius = 0.0
    for p in range(n_pairs):
        trace += scatter[p, p]
        for q in range(p, n_pairs):
            # C is symmetric: an entry off the diagonal stands twice in |C|_F^2.
            frobenius += (1.0 if p == q else 2.0) * scatter[p, q] * scatter[p, q]
    # Both sums are of products over the frames, N times C's entries: their ratio holds.
    return np.sqrt((n_frames - 1) * frobenius) / (n_frames * trace) if trace > 0.0 else np.nan


def _without_poses(
    arrays: tuple[np.ndarray, ...],
    reason: str,
    *,
    has_pose: bool = False,
    frame_numbers: np.ndarray | None = None,
) -> Support:
    """The verdict on one trial whose markers give no rigid-body pose (``reason``): fewer
    than three markers, or collinear ones; or (``has_pose``) whose markers the rigidity test
    cannot take (``reason`` says why). What the positions alone can show is tested on the
    moving markers ``arrays[-1]`` ``(N, P, 3)``, fitted with the concentric spheres every centre
    and axis model implies (a marker turning about an axis moves on a sphere about any of its
    points; LS, closed form); ``frame_numbers``, their row of :func:`_frame_numbers` ``(5,)``
    where the caller has it (else computed here):

    * the sphere fit's residual share of the markers' scatter about their mean positions, as
      the rigidity share of the module docstring (a cloud has no sphere to fit);
    * whether the trajectories are arcs at all: with ``RSS_line`` the scatter off each marker's
      best straight line (2 coordinates per sample, ``2 P (N - 2)`` degrees of freedom) and
      ``s^2`` the sphere residual per degree of freedom (``N P - 3 - P``),
      ``(RSS_line / (2 P (N - 2))) / s^2`` is F-distributed near 1 when every marker moves on a
      line (no rotation), and large for an arc resolved above the noise.

    Rigidity between markers, and rotation about more than one axis, are not tested here: the
    status always says so.
    """
    markers = arrays[-1]
    n_frames, n_markers, _ = markers.shape
    offsets = markers - markers[0, 0]
    sphere = np.linalg.norm(offsets - solve_ls_system(*ls_system(offsets)), axis=-1)
    rss_sphere = float(np.sum((sphere - sphere.mean(axis=0)) ** 2))
    centred = markers - markers.mean(axis=0)
    scatter = np.einsum("kpi,kpj->pij", centred, centred)
    rss_line = float(np.maximum(np.linalg.eigvalsh(scatter)[:, :2], 0.0).sum())
    total_ss = float(np.sum(centred * centred))
    # Markers that do not move have no scatter for a fit to leave unexplained.
    share = rss_sphere / total_ss if total_ss > 0.0 else 0.0
    sphere_dof = n_frames * n_markers - 3 - n_markers
    line_dof = 2 * n_markers * (n_frames - 2)
    rounding = (ROUNDING * float(np.abs(markers).max())) ** 2 * n_frames * n_markers
    # Three frames or more (assess_many refuses fewer): the line test has 2 P (N - 2) > 0.
    if sphere_dof < 1:
        p_line = math.nan  # a sphere passes through every sample: no residual to test against
    elif rss_sphere <= rounding:
        p_line = float(rss_line <= rounding)
    else:
        p_line = f_survival(line_dof, sphere_dof, (rss_line / line_dof) / (rss_sphere / sphere_dof))
    residual_mm = float(np.sqrt(rss_sphere / max(sphere_dof, 1)))
    # Pair distances hold whatever the motion; a single marker's hold nothing to read.
    if frame_numbers is None:
        (frame_numbers,) = _frame_numbers(kernel_array(markers[None]))
    name = "distal" if len(arrays) > 1 else "markers"
    frames = _segment_frames(frame_numbers[:4].tolist(), name, markers)
    why = reason if has_pose else f"{reason}, so no rigid-body pose"
    warnings = [
        f"not verified: {why}: whether the markers are one rigid body and rotate about more "
        "than one axis was not tested"
    ]
    if sphere_dof < 1:
        warnings.append(
            f"whether the trajectories are arcs was not tested: spheres pass through every "
            f"sample of {n_frames} frames of {n_markers} markers, leaving no residual"
        )
    elif share >= MAX_NONRIGID_SHARE:
        warnings.append(
            f"the markers do not move on concentric spheres: the sphere fit leaves "
            f"{100 * share:.0f}% of their scatter about their mean positions unexplained"
        )
    elif p_line >= ROTATION_ALPHA:
        warnings.append(
            "range of motion too small to support an answer: the trajectories are straight "
            f"lines within the sphere fit's residual of {residual_mm:.3g} mm (p = {p_line:.2g})"
        )
    return Support(
        tuple(warnings),
        {
            "assessed": False,
            "reason": reason,
            "sphere_residual_share": share,
            "sphere_residual_mm": residual_mm,
            "straight_line_p_value": p_line,
            **frames.numbers(),
        },
        caveats=frames.caveats(),
    )


def _verdict(
    kind,
    names,
    rigidity,
    variance,
    tests,
    axis_share=None,
    motion_axis=None,
    *,
    frames,
    pose_noise=None,
    noise_directions=None,
) -> Support:
    """One trial's warnings and numbers: ``rigidity`` holds per array of ``names`` its non-rigid
    share and RMS 3-D residual [mm], ``variance`` is the pooled residual per coordinate
    [mm^2] and ``tests`` the RMS rotation [rad] and p-value of any rotation, then of rotation
    off the main axis; ``axis_share``, for an axis whose rotation off the main axis is
    resolved, an :class:`_AxisShare` row (share, RMS rotation about the principal axis and
    about the others [rad]); ``motion_axis`` the :class:`MotionAxis` the verdict carries;
    ``frames`` how independent the frames are (:class:`_Frames`); ``pose_noise`` the
    :class:`PoseNoise` it carries for a joint centre, ``noise_directions`` the
    :class:`~jointbench.estimators.noise_directions.NoiseDirections` for one segment."""
    residual_mm = math.sqrt(3.0 * variance)
    rms_rad, p_any, second_rms_rad, p_second = map(float, tests)
    rms_deg, second_rms_deg = math.degrees(rms_rad), math.degrees(second_rms_rad)
    warnings = [
        f"the {_LABELS[name]} are not one rigid body: the best rigid-body fit leaves "
        f"{100 * share:.0f}% of their scatter about their centroid "
        f"unexplained (residual {residual:.3g} mm)"
        for name, (share, residual) in zip(names, rigidity, strict=True)
        if share >= MAX_NONRIGID_SHARE
    ]
    # A rotation test on markers that keep no shape would only restate that.
    if not warnings and p_any >= ROTATION_ALPHA:
        warnings.append(
            f"range of motion too small to support an answer: a rotation of "
            f"{rms_deg:.3g} deg RMS is not resolved above the "
            f"rigid-body residual of {residual_mm:.3g} mm (p = {p_any:.2g})"
        )
    elif not warnings and kind in CENTRE_KINDS and p_second >= ROTATION_ALPHA:
        warnings.append(
            f"rotation about a single axis: the centre is not determined along it (rotation "
            f"about other axes, {second_rms_deg:.3g} deg RMS, is not "
            f"resolved above the rigid-body residual of {residual_mm:.3g} mm, "
            f"p = {p_second:.2g})"
        )
    elif not warnings and axis_share is not None and axis_share[0] >= MAX_OFF_AXIS_SHARE:
        share, principal_rad, off_rad = axis_share
        warnings.append(
            f"rotation about more than one axis: {100 * share:.0f}% of the rotation is about "
            f"axes other than its principal one ({math.degrees(off_rad):.3g} deg RMS against "
            f"{math.degrees(principal_rad):.3g} deg about it, p = {p_second:.2g}); an axis "
            "fitted to it is a compromise the motion does not define"
        )
    numbers = {
        "assessed": True,
        "rigid_residual_mm": residual_mm,
        # The pairs compare by their shares first: the largest share's pair, without a
        # generator per verdict.
        "nonrigid_share": float(max(rigidity)[0]),
        "rotation_rms_deg": rms_deg,
        "rotation_p_value": p_any,
        "off_axis_rotation_rms_deg": second_rms_deg,
        "off_axis_p_value": p_second,
        **frames.numbers(),
    }
    if axis_share is not None:
        numbers["off_principal_axis_share"] = float(axis_share[0])
    return Support(
        tuple(warnings),
        numbers,
        motion_axis,
        frames.caveats(),
        pose_noise,
        noise_directions=noise_directions,
    )


def assess(
    kind: str, arrays: tuple[np.ndarray, ...], *, poses: dict | Exception | None = None
) -> Support:
    """Judge whether the marker ``arrays`` of an estimator ``kind`` support an answer.

    ``arrays`` is ``(markers,)`` for ``center``/``axis`` (reference frame) and
    ``(proximal, distal)`` for ``joint_center`` (world frame); see the module docstring. Each
    is refused with a ``ValueError`` naming it, the marker and the frame where it is not a
    ``(frames, markers, 3)`` array of finite samples within float64's sums
    (:func:`jointbench.estimators.validation.check_markers`), or has fewer than
    :data:`MIN_JUDGED_FRAMES` frames.
    Data with fewer than three non-collinear markers per segment give no rigid-body fit and
    are not assessed (``diagnostics["assessed"]`` is False); nor is one segment of more than
    :data:`MAX_DISTANCE_MARKERS` markers. ``poses``: the two segments'
    poses (:func:`jointbench.estimators.segment_poses.trial_poses`, one trial's entry) an
    estimator already fitted to these arrays, or the ``ValueError`` it met fitting them
    (anything else is refused with a ``ValueError``); ``None`` fits them here. One segment
    needs none.
    """
    names = ARRAY_NAMES[kind]
    if len(arrays) != len(names):
        raise ValueError(
            f"{kind} data are {len(names)} marker arrays ({', '.join(names)}), got {len(arrays)}"
        )
    checked = tuple(
        check_markers(array, name=name) for array, name in zip(arrays, names, strict=True)
    )
    stacked = tuple(array[None] for array in checked)
    return assess_many(kind, stacked, poses=None if poses is None else [poses])[0]


def annotate(result, support: Support):
    """``result`` with the support warnings, then its caveats or, where it has none, what the
    frames' lag-1 autocorrelation says (:class:`Untested`), appended to its ``status``, and the
    numbers in its ``diagnostics`` under ``support_<name>`` (the lag-1 statement's under their
    own names), and under :data:`~jointbench.estimators.results.REFUSED` whether the verdict
    refused the data; ``converged`` is left as the method set it."""
    numbers = {f"support_{key}": value for key, value in support.diagnostics.items()}
    numbers[REFUSED] = bool(support.warnings)
    words = support.warnings + support.caveats
    if support.untested is not None:
        words += (support.untested.words(),)
        numbers.update(support.untested.numbers())
    if support.noise_directions is not None:
        warning, found = by_direction.statement(result, support.noise_directions)
        words += warning
        numbers.update(found)
    return with_warnings(result, words, numbers)
