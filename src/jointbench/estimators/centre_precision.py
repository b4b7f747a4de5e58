"""How precisely the markers determine a centre of rotation, and whether an answer is where they
put it: added to every checked centre call, whatever the method.

The support verdict (:mod:`jointbench.estimators.support`) judges whether the data rotate
enough to support a centre at all; it does not say how precisely they fix it, nor whether the
centre a method returned is the one they fix. A least-squares sphere fit on a 10 degree cap
with 1 mm noise passes the verdict and can still be tens of millimetres off, and nothing in a
status said so. Both questions have the same model behind them, the one every centre method
of paper A starts from: each marker ``p`` keeps a distance ``r_p`` from the centre ``c``
(concentric spheres), up to noise of variance ``s^2`` per coordinate.

At an answer ``c``, with ``u_kp`` the unit vector from ``c`` to marker ``p`` in frame ``k``,
``e_kp = |x_kp - c| - r_p`` the radial residual and ``r_p`` the mean distance (the radii
profiled out):

* The information the data hold on ``c`` is ``F = sum_p sum_k (u_kp - mean_k u_kp)
  (u_kp - mean_k u_kp)'`` over ``s^2`` (Gauss–Newton, the radial residual's variance being
  ``s^2``). The directions are themselves noisy: about ``s^2 / r_p^2`` per tangential
  coordinate, which adds ``(N - 1) (s^2 / r_p^2) (I - m m')`` (``m`` the marker's mean
  direction) to the scatter of a cluster that does not move. On a small cap that share is of
  the order of the signal and would pass for precision; it is subtracted (the
  errors-in-variables correction, Fuller 1987), giving ``F_s``. ``center_sd_mm`` is
  ``s / sqrt(lambda_min(F_s))``, the SD along the least determined direction; ``inf`` where
  ``F_s`` is not positive definite (a hinge, which fixes no centre along its axis, or a cap
  within the noise).
* That correction is first order too. The share of the noise in the information along the
  least determined direction ``v``, ``v' (F - F_s) v / v' F_s v`` (``center_sd_noise_share``),
  is the relative size of the variance the SD leaves out (as for an axis,
  :mod:`jointbench.estimators.precision`: a factor ``1 + share``), and the answers' errors
  grow heavier tails than any factor of the SD as it rises. Where it reaches
  :data:`MAX_SD_NOISE_SHARE` the SD is reported but said not to hold.
* The score ``g = sum_kp e_kp (u_kp - mean_k u_kp)`` is ``-F_s delta`` to first order for an
  answer ``delta`` from the spheres' common centre, and has covariance ``s^2 F`` at that
  centre: ``g' F^-1 g / s^2`` is chi-square with 3 degrees of freedom there (Rao's score test,
  ``center_score_chi2``). ``|F_s^-1 g|`` estimates how far the answer is from that centre, to
  first order only: from an answer among the markers (their centroid, say) it can read a few
  millimetres where the centre is twenty away. ``center_step_mm`` is instead the distance to
  where Gauss–Newton iterations from the answer end, if the spheres fit better there (the
  iterations leave out a marker within three noise SDs of where they are, whose radial
  residual is not smooth there, and so do the fits compared there and about the answer: the
  distance of a marker within its noise of a point is that noise's length, whose spread is not
  the radial noise's and moves by more than the step's whole gain as the point moves). The
  comparison reads the sum of squares of the last step's markers, the one the iterations
  lowered; where a marker left out at one iterate and let back in at the next keeps them from
  settling (cycling between two sets' centres, to end at one no better than the answer), a
  marker left out from then on stays out, so that they settle on one set.
* The score test does not judge a method's answer: its chi-square holds for an answer fixed
  before the data are seen, and of one fitted to them it measures, to first order, the
  distance to the spheres' centre in the answer's SDs, rejecting at about four of them. The
  SD states the scatter of that centre about the truth; an answer ``m`` of its SDs from it
  (``center_step_sds``, the step's Mahalanobis length under the covariance the SD is from)
  has an error whose mean square along the step is ``1 + m^2`` times the SD's. With four
  markers 500 mm from the centre on a 10 degree swing and 0.5 mm noise
  (``benchmarks/blind_spots.py``), the LS sphere fit lies two to four of its SDs from the
  spheres' centre, which the score test passes: 18 of 60 of its answers read ``ok`` up to
  18.5 mm off with SDs of at most 4.6 mm, and none does now (:data:`MAX_STEP_SDS`).
* A step that significant (the score test rejecting, or :data:`MAX_STEP_SDS` or more) but no
  longer than :data:`MIN_REJECTED_STEP_MM`, which no warning reports, is the answer's bias
  about the spheres' centre: it is stated (``center_step_bias_mm``, the answer less that
  centre) and its outer product added to the covariance the SD is read from, so that the SD
  of an ``ok`` answer is of its error (mean square: scatter and bias), not of that centre's
  scatter alone. On a near hinge (40 degrees of flexion, 2 to 8 about a normal axis, 0.5 mm
  noise, ``tests/test_near_hinge_centre.py``) SCoRE read ``ok`` up to 7.4 mm off with an SD
  of 1.05 mm, 54 of 100 answers at 4 degrees beyond three of their SDs, and MA up to 19 SDs
  off; with the bias, over 100 seeds per case, no ``ok`` answer of theirs is, nor of LS's
  on small caps (5 to 20 degrees, 0.5 and 1 mm), and their share beyond one SD (0.31 to
  0.52) is about that of IS (0.32 to 0.45), which ends at the spheres' centre and is
  unchanged (``benchmarks/centre_stated_sd.py``). Three ``ok`` NM and BC answers of 5
  degree caps, 6.6 to 16 mm off, now read not determined: their SD with the step exceeds
  :data:`MAX_CENTER_SD_MM`.
* Lack of fit: the radial residuals' sum of squares over ``s^2``, on ``P (N - 1)`` degrees of
  freedom, is what the noise alone leaves about the spheres' centre; its ratio to them
  (``center_fit_ratio``) is tested one-sided against the ratio's spread, which counts the
  noise's kurtosis (paper A's isotropic errors have heavy tails) and the noise estimate's own
  uncertainty (``center_fit_p_value``). Unlike the score it is not local: an answer far from
  the centre leaves residuals the noise cannot explain wherever it lies. The excess over the
  noise is what an answer at least ``center_offset_mm`` from the centre leaves (the offset
  along the best determined direction that explains it).

A marker whose directions from the answer do not spread significantly beyond their noise (a
virtual marker at the joint, or one within the noise of the answer) carries nothing on it and
is left out of all of these. One that does but lies within three noise SDs of the answer (a
virtual marker at the joint, placed where an earlier estimate put it) has directions so noisy
(``s / r`` of a third or more) that the first-order correction, whose left-out terms are of
relative size ``s^2 / r^2``, misjudges their noise; where other markers lie beyond, the SD and
the noise share are those of the markers beyond, since with it a centre the others fix well
read as undetermined. The score test, the lack of fit about the answer and the first-order step
keep it (the Gauss–Newton iterations and the fits they compare do not, above), and a marker
further out is kept in everything: a marker near an answer far from the centre is what they
must see (on paper A's grid, leaving out markers within ten noise SDs passed five answers more
than 10 mm off as ``ok``).

A warning is added when the data cannot support the answer this way: the SD above
:data:`MAX_CENTER_SD_MM`, or not a statement of precision (the noise share above, or the
lack of fit rejecting even about the spheres' own centre: where Gauss–Newton iterations from
the answer end, or the answer where the score test passes it; both only where the support
verdict has not already refused the data), or the score test or the lack of fit rejecting at
:data:`jointbench.estimators.support.ROTATION_ALPHA`, or the answer lying :data:`MAX_STEP_SDS`
of its SDs or more from the common centre where that SD holds, with the answer more than
:data:`MIN_REJECTED_STEP_MM` from that centre (a method's own documented bias of a few
millimetres is a property of the method, not a failure to find the centre); that warning
says the precision is not determined, the SD stating the scatter of the common centre and the
answer's error adding the step to it. IS minimises the
radial residuals and ends at the spheres' centre (of every marker's: beside a virtual marker at
the joint, whose distance is its noise's length, a fraction of a millimetre from the other
markers' centre, a step stated as its bias where significant); NM's and BC's algebraic fits
ended within 3.6 and 4.7 mm of it on paper A's conditions and
``tests/test_centre_precision.py``'s caps; LS's algebraic fit, MA and SCoRE need not come near
it. The noise ``s^2``
is the support verdict's rigid-body residual, which does not depend on the answer; it is one
level for every marker, so a marker much noisier than the others biases a geometric fit by more
than the SD, a statement of scatter, says. Markers that move on their segment (skin, a
plate sliding on it) can keep their shape, so that the rigid-body residual sees only the
noise, while their distances from any centre change: the spheres then fit worse than that
noise about every centre, the SD from it understates the answer's error many times over
(``tests/test_centre_precision.py``'s sliding plate), and only a resampling of the frames (a
bootstrap) states it. A slide linear in the rotation vector ``w`` as ``d x w`` is, to first
order, the motion about a centre ``d`` away, and no fit can tell it from one
(``benchmarks/lab_conditions.py``'s ``slide``). Frames
repeated exactly carry no new noise and are counted once
(:func:`jointbench.estimators.precision.distinct_frames`). ``converged`` and the answer are
left as the method set them; the simulated studies call the methods without this check.
"""

from __future__ import annotations

import math
import statistics

import numpy as np

from jointbench.estimators.pose_noise import PoseNoise, pull_mm
from jointbench.estimators.precision import distinct_frames, rigid_dof
from jointbench.estimators.results import (
    MAX_CENTER_SD_MM,
    PRECISION_NOT_DETERMINED,
    stated_center_sd,
    with_warnings,
)
from jointbench.estimators.support import ROTATION_ALPHA, ROUNDING, Support
from jointbench.numerics.compiled import kernel, kernel_array
from jointbench.numerics.magnitudes import largest_magnitude
from jointbench.numerics.small import add_outer, symmetric_eigen_into, symmetric_into

__all__ = [
    "MAX_CENTER_SD_MM",
    "MAX_POSE_NOISE_PULL_MM",
    "MAX_POSE_NOISE_SHARE",
    "MAX_SD_NOISE_SHARE",
    "MAX_STEP_SDS",
    "MIN_POSE_NOISE_PULL_MM",
    "MIN_REJECTED_STEP_MM",
    "annotate_joint_centres",
    "annotate_many",
    "centre_statistics",
    "pull_bound_mm",
    "stated_center_sd",
    "stated_covariance",
]

#: Where the directions' noise is this share or more of their spread along the least
#: determined direction, the first-order SD is not a statement of precision: the variance it
#: leaves out grows as ``1 + share`` (module docstring), so at this share the SD understates the
#: scatter by a tenth, and beyond it the answers' errors grow heavy tails
#: (``tests/test_centre_precision.py`` counts them on both sides). The analytic joint centre's
#: SD is held to the same share of the poses' noise in the information its relative rotations
#: hold (:func:`jointbench.estimators.pose_noise.analytic_noise_share`).
MAX_SD_NOISE_SHARE = 0.2

#: Where the part of the analytic joint centre's variance that is second order in its frame-0
#: poses' errors is this share or more of the first-order part along some direction
#: (:func:`jointbench.estimators.pose_noise.analytic_anchor_share`), the first order no longer
#: leads the error and its SD does not describe it: equal parts. Not
#: :data:`MAX_SD_NOISE_SHARE`: that bounds a variance the SD leaves out, while this part is
#: one the SD holds on average, read on the observed rotations, which carry the draw's own
#: frame-0 errors (:func:`~jointbench.estimators.pose_noise.analytic_anchor_covariance`); it
#: says how far from linear in the noise the error is, and the answers' tails grow with it
#: (``benchmarks/joint_centre_stated_sd.py``, the README's paragraph on this SD).
MAX_ANCHOR_SHARE = 1.0

#: The score test's or the lack of fit's rejection, or a step of :data:`MAX_STEP_SDS`, is
#: reported only when the spheres' common centre is at least this far [mm] from the answer:
#: half of :data:`MAX_CENTER_SD_MM`, well above the few millimetres of bias paper A documents
#: for its methods on small caps. A shorter step that significant is that bias, stated as
#: such and held in the SD (:func:`annotate_many`), not a warning.
MIN_REJECTED_STEP_MM = 5.0

#: An answer this many of its SDs (Mahalanobis, under the covariance its SD is from) or more
#: from the spheres' common centre is not described by its SD: the SD states that centre's
#: scatter, and the answer's error is that scatter plus the step, whose mean square along the
#: step is ``1 + m^2`` times the variance the SD states (``m`` the step in SDs). The directions'
#: noise may leave a share of :data:`MAX_SD_NOISE_SHARE` of the variance out; so may the step:
#: ``m^2`` at that share, the SD understating the error by a tenth. Reported with
#: :data:`MIN_REJECTED_STEP_MM`, which an SD under :data:`MAX_CENTER_SD_MM` makes the larger
#: bound, and only where the SD holds (no other warning on the data or the precision): where
#: it does not, the spheres' centre is not fixed either. The score test is not this bound: it
#: rejects at about four SDs (module docstring).
MAX_STEP_SDS = math.sqrt(MAX_SD_NOISE_SHARE)

#: A joint centre whose poses' noise has this ratio, or more, to the noise-free information
#: along the centre's least determined direction (:mod:`jointbench.estimators.pose_noise`) is
#: not where the motion puts the joint: the answer keeps ``1 / (1 + ratio)`` of the joint's
#: offset from the markers along that direction, at most five sixths here, tens of
#: millimetres short where the joint lies a few hundred from its markers. The share alone
#: says so, whatever the pull read at the answer: the noise has moved the answer itself, and
#: one it moved close to the markers reads a small pull however far the joint is.
MAX_POSE_NOISE_SHARE = 0.2

#: ... or whose answer the noise pulled this far [mm] or more, where the share is smaller: a
#: pull of a few millimetres is of the order of the scatter of answers on the studies'
#: conditions and of their methods' own biases, which paper A documents for centres on
#: small caps; this is half the :data:`MAX_CENTER_SD_MM` beyond which a centre counts as not
#: determined.
MAX_POSE_NOISE_PULL_MM = 5.0

#: ... or this far [mm] or more where that is also :data:`MAX_STEP_SDS` of the answer's SD
#: (:func:`pull_bound_mm`): a pull under :data:`MAX_POSE_NOISE_PULL_MM` is still a bias beside
#: the scatter a smaller SD states. A smaller pull is not reported: the SD shrinks with the
#: frames and the pull does not, so on a long trial the small pulls of well-spread motion
#: (``tests/test_pose_noise.py``'s two-axis swings) would outgrow any SD while moving no
#: answer by more than this.
MIN_POSE_NOISE_PULL_MM = 2.0

# Columns of centre_statistics' rows.
_SD, _CHI2, _STEP, _REPEATS, _SHARE, _FIT_RATIO, _FIT_Z, _OFFSET = range(8)
# The step towards the spheres' centre [mm]: to where Gauss-Newton iterations end, or the first
# order's (F_s^-1 g; F^-1 g where F_s is not definite).
_TOWARDS = slice(8, 11)
# The lack of fit's ratio and z about the spheres' centre: where Gauss-Newton iterations from
# the answer end if the spheres fit better there (over the markers clear of it), else about
# the answer.
_SPHERES_RATIO, _SPHERES_Z = 11, 12
# The step in the answer's SDs (Mahalanobis).
_STEP_SDS = 13
# The p-values of the score test, of the lack of fit and of the lack of fit about the spheres'
# centre.
_SCORE_P, _FIT_P, _SPHERES_P = 14, 15, 16
# The covariance (3, 3) [mm^2] the SD is from, row after row: the spheres' centre's scatter.
_COVARIANCE = slice(17, 26)
# 1 where the noise is rounding (_noise_free), else 0.
_ROUNDING_NOISE = 26
# The SD [mm] of that covariance with the step's outer product added (_biased_sd).
_BIASED_SD = 27
_WIDTH = 28

# The one-sided normal quantile at ROTATION_ALPHA: what a marker's spread of directions must
# exceed their noise by, in standard errors, for the marker to count.
_Z_ALPHA = statistics.NormalDist().inv_cdf(1.0 - ROTATION_ALPHA)

# Within this many noise SDs of the answer a marker's directions are noisy beyond the
# first-order correction's reach (module docstring).
_CLEAR_RADIUS = 3.0

# Gauss–Newton iterations from an answer towards the spheres' centre.
_REFINE_ITERATIONS = 20
# ... until they move it less than this share of its distance from the answer, or of its SD
# where that is larger: the step in SDs is then known to this share of an SD.
_REFINED_TO = 1e-3


@kernel
def centre_statistics(
    markers: np.ndarray, centres: np.ndarray, variances: np.ndarray
) -> np.ndarray:
    """Per trial ``(SD [mm], score chi-square, step [mm], repeats, noise share, lack-of-fit
    ratio, its z, offset [mm], step (3,) [mm], the lack of fit's ratio and z about the spheres'
    centre, step in SDs, and the p-values of the score test, of the lack of fit and of the lack
    of fit about the spheres' centre, the covariance (3, 3) [mm^2] the SD is from, row after
    row, whether the noise is rounding, and the SD [mm] with the step's outer product added to
    that covariance)`` ``(T, 28)`` of the answers ``centres`` ``(T, 3)`` [mm]
    to the markers ``(T, N, n, 3)`` [mm], with noise ``variances`` ``(T,)`` [mm^2] per
    coordinate (module docstring). The step is the one to where Gauss–Newton iterations from
    the answer end, where the spheres fit better there (:func:`_refine`), else the first-order
    step; in SDs, its Mahalanobis length under the covariance the SD is from
    (:func:`_in_sds`). ``repeats`` is 1 where two frames may be equal (the numbers then count
    that frame twice), else 0. A compiled kernel."""
    n_trials, n_frames, n_markers = markers.shape[:3]
    out = np.empty((n_trials, _WIDTH))
    scratch = _scratch_for(n_frames, n_markers)
    keys = np.empty(n_frames)
    slots = _table_for(n_frames)
    weights = np.sqrt(np.arange(2.0, 2.0 + 3 * n_markers))
    coordinates = np.empty((n_markers, 3, n_frames))
    biased = np.empty((3, 3))
    for t in range(n_trials):
        _transposed_into(markers[t], coordinates)
        mixed = _row_at(coordinates, centres[t], variances[t], out[t], scratch)
        out[t, _REPEATS] = _repeats(markers[t], weights, keys, slots)
        # Wherever the score test passes it too: a method's bias of a few of its SDs does.
        refined = _refine(coordinates, centres[t], variances[t], mixed, out[t], scratch)
        out[t, _STEP_SDS] = _in_sds(out[t, _TOWARDS], scratch[13], scratch[14], variances[t])
        _covariance_into(scratch[13], scratch[14], variances[t], out[t, _COVARIANCE])
        out[t, _BIASED_SD] = _biased_sd(out[t, _COVARIANCE], out[t, _TOWARDS], biased)
        if not refined and _definite(scratch[13]):
            # No centre the iterations reach fits the spheres better: the answer is theirs.
            out[t, _STEP_SDS] = 0.0
        out[t, _ROUNDING_NOISE] = _noise_free(markers[t], variances[t])
        if out[t, _ROUNDING_NOISE]:
            # Rounding measured against rounding: nothing for the spheres' fit to fail.
            out[t, _SPHERES_Z] = np.nan
        out[t, _SCORE_P] = _chi2_3_sf(out[t, _CHI2])
        out[t, _FIT_P] = _normal_sf(out[t, _FIT_Z])
        out[t, _SPHERES_P] = _normal_sf(out[t, _SPHERES_Z])
    return out


@kernel
def _noise_free(markers: np.ndarray, s2: float) -> bool:
    """Whether the noise ``s2`` [mm^2] per coordinate of the markers ``(N, n, 3)`` [mm] is
    rounding, as the support verdict judges it (:data:`ROUNDING` of the largest coordinate).
    A compiled kernel."""
    return s2 <= (ROUNDING * largest_magnitude(markers)) ** 2


@kernel
def _transposed_into(markers: np.ndarray, coordinates: np.ndarray) -> None:
    """The markers ``(N, n, 3)`` [mm] written into ``coordinates`` ``(n, 3, N)``: each
    marker's coordinates frame after frame, which the sums over its frames
    (:func:`_marker_sums`), run several times per trial, read contiguously. A compiled
    kernel."""
    for k in range(markers.shape[0]):
        for p in range(markers.shape[1]):
            for i in range(3):
                coordinates[p, i, k] = markers[k, p, i]


@kernel
def _scratch_for(n_frames: int, n_markers: int) -> tuple:
    """Scratch arrays of :func:`_sums_at` and its callers for ``n_frames`` frames of
    ``n_markers`` markers, allocated once per batch: ``(info, signal, noisy, score, values,
    vectors, work, distances, sum_u, sum_du, sum_uu, stated, stated_noise, sd_values,
    sd_vectors, offsets, iterate, move, there, kept)``, ``sd_values`` and ``sd_vectors`` the
    eigen-decomposition of the information the SD is stated from (:func:`_row_at`),
    ``iterate``, ``move`` and ``there`` :func:`_refine`'s, ``kept`` ``(4, n)`` 1 for each
    marker the last :func:`_sums_at` kept (else 0), then for each that :func:`_row_at`'s sums
    about the answer kept, then for each that :func:`_refine`'s iterations have not left out
    (the markers :func:`_sums_at` may keep), then for each clear of the answer they start
    from. The 3 x 3 matrices and the
    3-vectors are each one array's rows: an allocation costs a one-trial call more than the
    arithmetic of several of them. A compiled kernel."""
    matrices = np.empty((9, 3, 3))
    vectors = np.empty((7, 3))
    return (
        matrices[0],
        matrices[1],
        matrices[2],
        vectors[0],
        vectors[1],
        matrices[3],
        matrices[4],
        np.empty(n_frames),
        vectors[2],
        vectors[3],
        matrices[5],
        matrices[6],
        matrices[7],
        vectors[4],
        matrices[8],
        np.empty((6, n_frames)),
        vectors[5],
        vectors[6],
        np.empty(17),
        np.empty((4, n_markers)),
    )


@kernel
def _refine(
    coordinates: np.ndarray,
    answer: np.ndarray,
    s2: float,
    mixed: bool,
    row: np.ndarray,
    scratch: tuple,
) -> bool:
    """``row``'s step made the one from ``answer`` ``(3,)`` [mm] to where Gauss–Newton
    iterations on the spheres' radial residuals end (at most :data:`_REFINE_ITERATIONS` on one
    set of markers), where the spheres fit better there; returns whether they do. The
    first-order step is exact only near the centre, and an answer far from it (among the
    markers, say) can have a small one. Each iteration takes :func:`_row_at`'s step
    (:func:`_step_at`) without the rest of its numbers, and without the markers within
    :data:`_CLEAR_RADIUS` noise SDs of the iterate: the radial residual of one (a virtual
    marker at the joint) is not smooth there, and draws the iterations to it or throws them
    off. The fits compared, about the answer and where the iterations end
    (:func:`_fits_better`), are over the markers of the last step: the sum of squares whose
    least the iterations sought (their steps, corrected for the directions' noise or not,
    vanish only where its gradient does). A marker near that radius can be left out at one
    iterate and let back in at the next, and the iterations cycle between two points, each
    the least of the other set's sum (a marker 1 mm from the joint on a 30 degree cap:
    ``tests/test_centre_precision.py``), to end at one no better than the answer. Where they
    have not settled within :data:`_REFINE_ITERATIONS` and some step left a marker out, or the
    end leaves out a marker of the last step, a marker left out from then on stays out, so that
    they settle on one set (where no step left one out, they end at the last iterate); where
    they settle with every marker clear of each iterate, that set is the one clear of where
    they end, as the fits about a centre of rotation read it. A marker within the noise of the
    answer is left out of them all: the fit about the answer cannot read it (beside a marker
    2 mm from the joint, IS's answer can lie among its noise, drawn towards it, and
    iterations that let it back in where it is clear settle at another least of the five
    markers' sum, which fits worse than the answer). They
    start from ``row``'s
    first-order step, unless some markers lie that near the answer (``mixed``, as
    :func:`_row_at` returns it), whose step keeps them. ``coordinates`` ``(n, 3, N)`` [mm] are
    the markers' (:func:`_transposed_into`). The iterations overwrite ``scratch`` but for the
    SD's eigen-decomposition. A compiled kernel."""
    centre, move, there = scratch[16:19]
    kept_here, allowed, clear_of_answer = scratch[19][0], scratch[19][2], scratch[19][3]
    centre[:] = answer
    if not mixed:
        centre += row[_TOWARDS]
    nearest = _CLEAR_RADIUS * math.sqrt(s2)
    sd = row[_SD] if math.isfinite(row[_SD]) else 0.0
    n_markers, _, n_frames = coordinates.shape
    keeping_out, first, left_out = False, True, False
    squares, fourths, kept, steps = 0.0, 0.0, 0, 0
    clear_of_answer[:] = 1.0
    while True:
        if not keeping_out:
            allowed[:] = clear_of_answer
        _step_at(coordinates, centre, s2, nearest, allowed, move, scratch)
        if not (math.isfinite(move[0]) and math.isfinite(move[1]) and math.isfinite(move[2])):
            return False
        if mixed and first:
            # The first step is from the answer: a marker within the noise of it is left out of
            # the fit about it, and so of every sum the iterations compare with that fit.
            clear_of_answer[:] = kept_here
        first = False
        # ``allowed`` is now the step's markers, those whose sum it lowers.
        if _narrowed(allowed, kept_here):
            left_out = True
            if keeping_out:
                # The sum the iterations seek the least of has changed: they count afresh.
                steps = 0
        centre += move
        steps += 1
        distance = _length(centre[0] - answer[0], centre[1] - answer[1], centre[2] - answer[2])
        settled = _length(move[0], move[1], move[2]) <= _REFINED_TO * max(distance, sd)
        if settled or steps >= _REFINE_ITERATIONS:
            # The fit where they end is over the last step's markers.
            squares, fourths, kept, _ = _sums_at(
                coordinates, centre, s2, nearest, allowed, True, scratch
            )
            if not _narrowed(allowed, kept_here) and (settled or keeping_out or not left_out):
                break
            # Not settled where markers were left out at some steps, or the end leaves out one
            # of the last step's: from here on a marker left out stays out. Each is left out
            # once, so the iterations end.
            keeping_out = True
            steps = 0
    _lack_of_fit(there, squares, fourths, kept, n_frames, n_markers, s2)
    if not _fits_better(coordinates, answer, row, there, squares, scratch):
        return False
    row[_TOWARDS] = centre - answer
    row[_STEP] = _length(centre[0] - answer[0], centre[1] - answer[1], centre[2] - answer[2])
    row[_SPHERES_RATIO] = there[_FIT_RATIO]
    row[_SPHERES_Z] = there[_FIT_Z]
    return True


@kernel
def _narrowed(allowed: np.ndarray, kept: np.ndarray) -> bool:
    """Whether some marker that ``allowed`` ``(n,)`` marks 1 is 0 in ``kept`` ``(n,)``, the
    markers :func:`_sums_at` kept at the last iterate; such markers are set to 0 in
    ``allowed``. A compiled kernel."""
    narrowed = False
    for p in range(allowed.shape[0]):
        if allowed[p] and not kept[p]:
            allowed[p] = 0.0
            narrowed = True
    return narrowed


@kernel
def _fits_better(
    coordinates: np.ndarray,
    answer: np.ndarray,
    row: np.ndarray,
    there: np.ndarray,
    squares: float,
    scratch: tuple,
) -> bool:
    """Whether the spheres fit better where :func:`_refine`'s iterations end than about
    ``answer`` ``(3,)`` [mm], given the lack of fit there (``there``, of :func:`_lack_of_fit`,
    and its sum of squares ``squares`` [mm^2]) over the markers :func:`_sums_at` kept there
    (``scratch``'s ``kept``, its first row) and ``row``'s about the answer over those it kept
    there (its second). Where the two are the same markers, the ratios compare; else the
    radial residuals' sums of squares over the markers kept where the iterations end, about
    either point. A marker within a few noise SDs of a point (a virtual marker at the joint)
    has no direction from it: its distance is the length of its noise, whose spread is not the
    radial noise's and changes by several times the whole gain of a step as the point moves by
    a fraction of that noise, and whether its directions spread beyond their noise flips with
    it (on a short cap, such a marker's sum of squares can rise over a step that lowers the
    other markers' lack of fit: ``tests/test_centre_precision.py``). ``coordinates`` ``(n, 3, N)``
    [mm] are the markers' (:func:`_transposed_into`). A compiled kernel."""
    kept, kept_at_answer = scratch[19][0], scratch[19][1]
    same = True
    for p in range(kept.shape[0]):
        same = same and kept[p] == kept_at_answer[p]
    if same:
        return there[_FIT_RATIO] < row[_FIT_RATIO]
    if not math.isfinite(there[_FIT_RATIO]):
        return False
    distances, sum_u, sum_du, sum_uu = scratch[7:11]
    offsets = scratch[15]
    about_answer = 0.0
    for p in range(kept.shape[0]):
        if not kept[p]:
            continue
        radius = _marker_sums(coordinates[p], answer, distances, offsets, sum_u, sum_du, sum_uu)
        for k in range(distances.shape[0]):
            about_answer += (distances[k] - radius) ** 2
    return squares < about_answer


@kernel
def _length(x: float, y: float, z: float) -> float:
    """The length of the vector ``(x, y, z)``. A compiled kernel."""
    return math.sqrt(x * x + y * y + z * z)


@kernel
def _in_sds(step: np.ndarray, values: np.ndarray, vectors: np.ndarray, s2: float) -> float:
    """The Mahalanobis length of ``step`` ``(3,)`` [mm] under the covariance ``s2 M^-1`` [mm^2],
    ``M`` given by its ascending eigenvalues ``values`` ``(3,)`` and ``vectors`` ``(3, 3)``: how
    many of the answer's SDs it spans along its own direction. NaN where ``M`` is not positive
    definite (no SD to count in). A compiled kernel."""
    if not _definite(values):
        return np.nan
    total = 0.0
    for i in range(3):
        along = 0.0
        for j in range(3):
            along += vectors[j, i] * step[j]
        total += values[i] * along * along
    return math.sqrt(total / s2)


@kernel
def _covariance_into(values: np.ndarray, vectors: np.ndarray, s2: float, out: np.ndarray) -> None:
    """The covariance ``s2 M^-1`` [mm^2] of the spheres' centre, ``M`` given by its ascending
    eigenvalues ``values`` ``(3,)`` and ``vectors`` ``(3, 3)``, into ``out`` ``(9,)`` row after
    row; ``inf`` where ``M`` is not positive definite (the SD is then ``inf`` too). A compiled
    kernel."""
    if not _definite(values):
        out[:] = np.inf
        return
    for i in range(3):
        for j in range(3):
            total = 0.0
            for k in range(3):
                total += vectors[i, k] * vectors[j, k] / values[k]
            out[3 * i + j] = s2 * total


@kernel
def _biased_sd(covariance: np.ndarray, step: np.ndarray, work: np.ndarray) -> float:
    """The SD [mm] along the least determined direction of ``covariance`` ``(9,)`` [mm^2] (row
    after row) with the outer product of ``step`` ``(3,)`` [mm] added, into ``work`` ``(3, 3)``:
    :func:`_largest_sd` of :func:`_with_bias`, the SD of an answer whose bias is the step, in
    the kernel that forms both, where NumPy's calls on a 3 x 3 matrix would cost a one-trial
    call more than the fit's checks of it. A compiled kernel."""
    for i in range(3):
        for j in range(3):
            work[i, j] = covariance[3 * i + j] + step[i] * step[j]
    largest = _largest_variance(work)
    return math.sqrt(largest) if largest >= 0.0 else math.nan


@kernel
def _sums_at(
    coordinates: np.ndarray,
    centre: np.ndarray,
    s2: float,
    nearest: float,
    allowed: np.ndarray,
    fit: bool,
    scratch: tuple,
) -> tuple:
    """The spheres' sums about the answer ``centre`` ``(3,)`` [mm] over the markers whose
    ``coordinates`` are ``(n, 3, N)`` [mm] (:func:`_transposed_into`) at a mean distance of
    ``nearest`` [mm] or more from it, among those ``allowed`` ``(n,)`` marks 1 (the others 0),
    with noise ``s2`` [mm^2] per coordinate, into ``scratch``
    (:func:`_scratch_for`): the information ``F``, its part ``F_s`` beyond the directions'
    noise and that noise's part ``F - F_s`` (upper triangles), the score ``g``, and the parts
    of ``F_s`` and ``F - F_s`` from the markers beyond :data:`_CLEAR_RADIUS` noise SDs; returns
    the radial residuals' sum of squares and of fourth powers (where ``fit`` asks for them,
    else 0), the markers kept (each marker's 1 if kept, else 0, into the first row of
    ``scratch``'s ``kept``), and whether only some of those lie that far. A marker whose
    directions from the answer do not spread beyond their noise (one at the answer, a virtual
    marker at the joint, say) carries nothing on it and is left out. A compiled kernel."""
    info, signal, noisy, score, _, _, _, distances, sum_u, sum_du, sum_uu = scratch[:11]
    stated, stated_noise = scratch[11:13]
    offsets = scratch[15]
    flags = scratch[19][0]
    n_markers, _, n_frames = coordinates.shape
    # Pure noise spreads a marker's directions over two tangential coordinates, N - 1 degrees
    # of freedom each: beyond this factor of that spread the marker has a signal.
    beyond_noise = 1.0 + _Z_ALPHA / math.sqrt(max(n_frames - 1, 1))
    info[:] = 0.0
    signal[:] = 0.0
    noisy[:] = 0.0
    score[:] = 0.0
    stated[:] = 0.0
    stated_noise[:] = 0.0
    squares, fourths, kept, clear = 0.0, 0.0, 0, 0
    for p in range(n_markers):
        flags[p] = 0.0
        if not allowed[p]:
            continue
        radius = _marker_sums(coordinates[p], centre, distances, offsets, sum_u, sum_du, sum_uu)
        if radius < nearest:
            continue
        noise = (n_frames - 1) * s2 / radius**2 if radius > 0.0 else np.inf
        spread = sum_uu[0, 0] + sum_uu[1, 1] + sum_uu[2, 2]
        norm2 = sum_u[0] ** 2 + sum_u[1] ** 2 + sum_u[2] ** 2
        if not spread - norm2 / n_frames > 2.0 * noise * beyond_noise:
            continue
        flags[p] = 1.0
        kept += 1
        far = radius >= _CLEAR_RADIUS * math.sqrt(s2)
        clear += far
        if fit:
            for k in range(n_frames):
                e2 = (distances[k] - radius) ** 2
                squares += e2
                fourths += e2 * e2
        for i in range(3):
            score[i] += sum_du[i] - radius * sum_u[i]
        for i in range(3):
            for j in range(i, 3):
                moment = sum_uu[i, j] - sum_u[i] * sum_u[j] / n_frames
                # The tangential noise of the directions, about the mean direction.
                tangential = (1.0 if i == j else 0.0) - sum_u[i] * sum_u[j] / norm2
                info[i, j] += moment
                signal[i, j] += moment - noise * tangential
                noisy[i, j] += noise * tangential
                if far:
                    stated[i, j] += moment - noise * tangential
                    stated_noise[i, j] += noise * tangential
    return squares, fourths, kept, 0 < clear < kept


@kernel
def _corrected_step(
    score: np.ndarray, values: np.ndarray, vectors: np.ndarray, towards: np.ndarray
) -> float:
    """The step ``F_s^-1 g`` towards the spheres' centre into ``towards`` ``(3,)`` [mm], given
    the score ``g`` ``(3,)`` [mm] and the eigen-decomposition ``values`` ``(3,)``, ``vectors``
    ``(3, 3)`` of ``F_s``; returns its length [mm]. Gauss–Newton's own step (``F^-1 g``) is
    shortened by the directions' noise as a regression on noisy regressors is. A compiled
    kernel."""
    towards[:] = 0.0
    for i in range(3):
        along = 0.0
        for j in range(3):
            along += vectors[j, i] * score[j]
        for j in range(3):
            towards[j] += vectors[j, i] * along / values[i]
    return _length(towards[0], towards[1], towards[2])


@kernel
def _step_at(
    coordinates: np.ndarray,
    centre: np.ndarray,
    s2: float,
    nearest: float,
    allowed: np.ndarray,
    towards: np.ndarray,
    scratch: tuple,
) -> None:
    """:func:`_row_at`'s step towards the spheres' centre from ``centre`` ``(3,)`` [mm] alone,
    over the markers ``nearest`` [mm] or more from it among those ``allowed`` ``(n,)`` marks
    (:func:`_sums_at`, whose ``coordinates`` ``(n, 3, N)``), into ``towards`` ``(3,)``:
    ``F_s^-1 g``, or ``F^-1 g`` where ``F_s`` is not positive definite (NaN where neither is).
    A compiled kernel."""
    info, signal, _, score, values, vectors, work = scratch[:7]
    # The lack of fit is not wanted here: its sums are skipped.
    _sums_at(coordinates, centre, s2, nearest, allowed, False, scratch)
    symmetric_eigen_into(signal, values, vectors, work)
    if _definite(values):
        _corrected_step(score, values, vectors, towards)
    else:
        _solved(info, score, towards, values, vectors, work)


@kernel
def _row_at(
    coordinates: np.ndarray, centre: np.ndarray, s2: float, row: np.ndarray, scratch: tuple
) -> bool:
    """:func:`centre_statistics`'s first-order numbers of the answer ``centre`` ``(3,)`` [mm] to
    the markers whose ``coordinates`` are ``(n, 3, N)`` [mm] (:func:`_transposed_into`) with
    noise ``s2`` [mm^2] per coordinate (:func:`_sums_at`), into ``row`` ``(28,)`` but for
    ``repeats``, the step in SDs, the p-values, the covariance, the noise's rounding and the SD
    with the step; ``inf`` SD, step and share where the corrected information is not positive
    definite. Leaves the eigen-decomposition of the information the SD is from in ``scratch``
    (:func:`_scratch_for`); returns whether that is from only some of the markers (those clear
    of the answer, module docstring). A compiled kernel."""
    n_markers, _, n_frames = coordinates.shape
    info, signal, noisy, score, values, vectors, work = scratch[:7]
    # Every marker may be kept about the answer.
    kept_markers = scratch[19]
    kept_markers[2, :] = 1.0
    squares, fourths, kept, mixed = _sums_at(
        coordinates, centre, s2, 0.0, kept_markers[2], True, scratch
    )
    # The markers kept about the answer, for the fits :func:`_refine` compares.
    for p in range(n_markers):
        kept_markers[1, p] = kept_markers[0, p]
    row[_CHI2] = _solved(info, score, row[_TOWARDS], values, vectors, work) / s2
    _lack_of_fit(row, squares, fourths, kept, n_frames, n_markers, s2)
    row[_SPHERES_RATIO] = row[_FIT_RATIO]
    row[_SPHERES_Z] = row[_FIT_Z]
    symmetric_eigen_into(signal, values, vectors, work)
    largest = values[2] if values[2] > 0.0 else np.nan
    row[_OFFSET] = math.sqrt(max(squares - kept * (n_frames - 1) * s2, 0.0) / largest)
    if not _definite(values):
        row[_STEP] = np.inf
    else:
        row[_STEP] = _corrected_step(score, values, vectors, row[_TOWARDS])
    if mixed:
        # The statement of precision from the markers clear of the answer, where some are
        # (module docstring): the score, the lack of fit and the first-order step keep every
        # marker.
        signal, noisy = scratch[11:13]
        symmetric_eigen_into(signal, values, vectors, work)
    sd_values, sd_vectors = scratch[13:15]
    sd_values[:] = values
    sd_vectors[:] = vectors
    if not _definite(values):
        row[_SD] = np.inf
        row[_SHARE] = np.inf
        return mixed
    share = 0.0
    for i in range(3):
        for j in range(3):
            share += vectors[i, 0] * _upper(noisy, i, j) * vectors[j, 0]
    row[_SHARE] = share / values[0]
    row[_SD] = math.sqrt(s2 / values[0])
    return mixed


@kernel
def _marker_sums(
    track: np.ndarray,
    centre: np.ndarray,
    distances: np.ndarray,
    offsets: np.ndarray,
    sum_u: np.ndarray,
    sum_du: np.ndarray,
    sum_uu: np.ndarray,
) -> float:
    """One marker's sums over its ``track`` ``(3, N)`` [mm] (its coordinates, each over the
    frames) about ``centre`` ``(3,)``: its ``distances`` ``(N,)``, the sums of its unit
    directions ``u``, of ``d u`` and of ``u u'`` (both triangles); returns its mean distance
    ``r``. ``F_p = sum u u' - N m m'`` and ``g_p = sum d u - N r m`` follow, ``m`` the mean
    direction. ``offsets`` ``(6, N)`` is scratch (the offsets from ``centre`` and the unit
    directions). A compiled kernel."""
    xs, ys, zs = track[0], track[1], track[2]
    n_frames = xs.shape[0]
    cx, cy, cz = centre[0], centre[1], centre[2]
    # The offsets, distances and directions, most of the cost (square roots, divisions), in a
    # loop without a sum: the compiler runs it on several frames at once, which a sum, kept in
    # its order, would forbid.
    for k in range(n_frames):
        x = xs[k] - cx
        y = ys[k] - cy
        z = zs[k] - cz
        d = math.sqrt(x * x + y * y + z * z)
        distances[k] = d
        inverse = 1.0 / d if d > 0.0 else 0.0
        offsets[0, k], offsets[1, k], offsets[2, k] = x, y, z
        offsets[3, k], offsets[4, k], offsets[5, k] = x * inverse, y * inverse, z * inverse
    # Sums kept in locals, not in the arrays, so that the compiler keeps them in registers, all
    # thirteen in one loop: their chains of additions, each waiting on its last, then run side
    # by side (this function a tenth faster on 120 frames than with two loops of seven and six
    # sums). Each is still taken frame after frame, to the same bits.
    sum_d = 0.0
    su0 = su1 = su2 = 0.0
    sd0 = sd1 = sd2 = 0.0
    outer = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    for k in range(n_frames):
        sum_d += distances[k]
        su0 += offsets[3, k]
        su1 += offsets[4, k]
        su2 += offsets[5, k]
        sd0 += offsets[0, k]
        sd1 += offsets[1, k]
        sd2 += offsets[2, k]
        outer = add_outer(outer, offsets[3, k], offsets[4, k], offsets[5, k])
    sum_u[0], sum_u[1], sum_u[2] = su0, su1, su2
    sum_du[0], sum_du[1], sum_du[2] = sd0, sd1, sd2
    symmetric_into(outer, sum_uu)
    return sum_d / n_frames


@kernel
def _table_for(n_frames: int) -> np.ndarray:
    """The hash table of :func:`_repeats` for ``n_frames`` frames (scratch, allocated once per
    batch): a power of two of at least ``2 N`` entries, so that a lookup stays short and always
    meets an empty entry. A compiled kernel."""
    size = 2
    while size < 2 * n_frames:
        size *= 2
    return np.empty(size, dtype=np.int64)


@kernel
def _repeats(
    markers: np.ndarray, weights: np.ndarray, keys: np.ndarray, slots: np.ndarray
) -> float:
    """1 where two frames of ``markers`` ``(N, n, 3)`` may be equal, else 0: equal frames have
    equal keys ``(N,)`` (scratch), sums of the coordinates with the ``weights`` ``(3 n,)``, of
    which no two of a frame's coordinates share one. Each key is looked up among the earlier
    ones in a hash table, ``slots`` (:func:`_table_for`): a pass over the frames where sorting
    the keys cost several. A compiled kernel."""
    n_frames, n_markers, _ = markers.shape
    for k in range(n_frames):
        key = 0.0
        for p in range(n_markers):
            for i in range(3):
                key += weights[3 * p + i] * markers[k, p, i]
        keys[k] = key
    # The keys all formed before the lookups: each lookup then waits on no key just stored.
    # The sums start at +0.0 and so are never -0.0: equal keys have equal bits.
    bits = keys.view(np.int64)
    mask = slots.shape[0] - 1
    slots[:] = -1
    for k in range(n_frames):
        # The exponent's and the mantissa's upper bits folded onto the lower: keys of round
        # numbers differ there only.
        slot = (bits[k] ^ (bits[k] >> 17) ^ (bits[k] >> 34) ^ (bits[k] >> 51)) & mask
        while slots[slot] >= 0:
            if keys[slots[slot]] == keys[k]:
                return 1.0
            slot = (slot + 1) & mask
        slots[slot] = k
    return 0.0


@kernel
def _lack_of_fit(
    row: np.ndarray,
    squares: float,
    fourths: float,
    kept: int,
    n_frames: int,
    n_markers: int,
    s2: float,
) -> None:
    """The lack of fit of the concentric spheres about an answer into ``row``: the radial
    residuals' sum of ``squares`` (and of ``fourths`` powers) over the ``kept`` markers'
    ``kept (N - 1)`` degrees of freedom, as a ratio to the rigid-body noise ``s2``, and its z:
    the ratio's spread counts the noise's kurtosis, read off the residuals (floored at a
    normal one's), and the noise estimate's own, from the rigid fit's ``(3 n - 6)(N - 1)``
    degrees of freedom. A compiled kernel."""
    dof = kept * (n_frames - 1)
    if dof < 1:
        row[_FIT_RATIO] = np.nan
        row[_FIT_Z] = np.nan
        return
    ratio = squares / (dof * s2)
    kurtosis = max(kept * n_frames * fourths / squares**2 - 3.0, 0.0) if squares > 0 else 0.0
    noise_dof = rigid_dof(n_markers, n_frames)
    row[_FIT_RATIO] = ratio
    row[_FIT_Z] = (ratio - 1.0) / math.sqrt((2.0 + kurtosis) * (1.0 / dof + 1.0 / noise_dof))


@kernel
def _definite(values: np.ndarray) -> bool:
    """Whether the ascending eigenvalues ``values`` ``(3,)`` are those of a positive definite
    matrix, to rounding: the smallest above 1e-12 of the largest. A compiled kernel."""
    return values[0] > 1e-12 * abs(values[2])


@kernel
def _upper(matrix: np.ndarray, i: int, j: int) -> float:
    """Entry ``(i, j)`` of the symmetric ``matrix`` of which only the upper triangle is
    written. A compiled kernel."""
    return matrix[i, j] if i <= j else matrix[j, i]


@kernel
def _solved(
    matrix: np.ndarray,
    vector: np.ndarray,
    solution: np.ndarray,
    values: np.ndarray,
    vectors: np.ndarray,
    work: np.ndarray,
) -> float:
    """``v' M^-1 v`` of the symmetric ``matrix`` ``M`` ``(3, 3)`` (upper triangle) and
    ``vector`` ``v`` ``(3,)``, with ``M^-1 v`` written into ``solution`` ``(3,)``; NaN where
    ``M`` is singular to rounding. ``values``, ``vectors``, ``work`` are scratch. A
    compiled kernel."""
    symmetric_eigen_into(matrix, values, vectors, work)
    if not _definite(values):
        solution[:] = np.nan
        return np.nan
    total = 0.0
    solution[:] = 0.0
    for i in range(3):
        along = 0.0
        for j in range(3):
            along += vectors[j, i] * vector[j]
        total += along * along / values[i]
        for j in range(3):
            solution[j] += vectors[j, i] * along / values[i]
    return total


@kernel
def _chi2_3_sf(x: float) -> float:
    """The upper tail of the chi-square distribution with 3 degrees of freedom at ``x``, in
    closed form (a SciPy call costs more than the rest of the check). A compiled kernel."""
    if not x >= 0.0:
        return math.nan
    if math.isinf(x):
        return 0.0
    # 2 x / pi as x / pi doubled: the same number, but 2 x overflows for x above half the
    # largest float, and inf times the exponential's 0 would make the tail NaN.
    return math.erfc(math.sqrt(x / 2.0)) + math.sqrt(x / math.pi * 2.0) * math.exp(-x / 2.0)


@kernel
def _normal_sf(z: float) -> float:
    """The upper tail of the standard normal distribution at ``z``. A compiled kernel."""
    return 0.5 * math.erfc(z / math.sqrt(2.0))


def _statistics(markers: np.ndarray, centres: np.ndarray, variances: np.ndarray) -> list:
    """:func:`centre_statistics` with each trial's repeated frames counted once, as lists."""
    rows = centre_statistics(kernel_array(markers), centres, variances).tolist()
    for t, row in enumerate(rows):
        if row[_REPEATS]:
            distinct = distinct_frames(markers[t])
            rows[t] = centre_statistics(
                kernel_array(distinct[None]), centres[t : t + 1], variances[t : t + 1]
            )[0].tolist()
    return rows


def _warnings(numbers: dict, residual_mm: float, supported: bool) -> tuple[str, ...]:
    """The warnings of one answer's ``numbers`` (the diagnostics of :func:`annotate_many`),
    the precision's only where the support verdict ``supported`` the data."""
    sd, share = numbers["center_sd_mm"], numbers["center_sd_noise_share"]
    warnings = []
    if supported and stated_center_sd(sd) is None:
        warnings.append(_undetermined(sd, f"the rigid-body residual of {residual_mm:.3g} mm"))
    elif supported and not share < MAX_SD_NOISE_SHARE:
        warnings.append(_noisy_sd(share, sd, "the spread of the markers' directions from it"))
    elif supported and numbers["center_spheres_fit_p_value"] < ROTATION_ALPHA:
        warnings.append(
            f"centre's {PRECISION_NOT_DETERMINED} by the data: even about their own centre the "
            f"spheres leave radial residuals {numbers['center_spheres_fit_ratio']:.3g} times "
            f"the rigid-body noise's variance (p = "
            f"{numbers['center_spheres_fit_p_value']:.2g}): the markers do not keep their "
            f"distances from any centre (skin, or markers moving on their segment), which an SD "
            f"of {sd:.3g} mm from that noise does not count; a bootstrap interval does"
        )
    reasons = []
    step, p = numbers["center_step_mm"], numbers["center_score_p_value"]
    # Only an SD that holds states the scatter of a centre the markers fix (a hinge's spheres,
    # say, have none): the score test alone speaks elsewhere.
    sds = numbers["center_step_sds"] if supported and not warnings else math.nan
    if MIN_REJECTED_STEP_MM < step < math.inf and _significant_step(p, sds):
        test = f"score test chi^2 = {numbers['center_score_chi2']:.3g}, p = {p:.2g}"
        reasons.append(
            f"the spheres they move on are centred {step:.3g} mm from it, {sds:.2g} of its SDs "
            f"({test}): an error beside the scatter its SD states"
            if math.isfinite(sds)
            else f"the spheres they move on are centred {step:.3g} mm from it ({test})"
        )
    offset, p_fit = numbers["center_offset_mm"], numbers["center_fit_p_value"]
    if p_fit < ROTATION_ALPHA and offset > MIN_REJECTED_STEP_MM:
        reasons.append(
            f"spheres about it leave radial residuals {numbers['center_fit_ratio']:.3g} times "
            f"the rigid-body noise's variance, as an answer {offset:.3g} mm or more from "
            f"their centre would (p = {p_fit:.2g})"
        )
    if reasons:
        # The SD states the scatter of the spheres' centre; this answer's error adds the step.
        warnings.append(
            "the answer is not the markers' common centre of rotation: "
            + "; and ".join(reasons)
            + f"; its SD, that centre's scatter, leaves the step out: {PRECISION_NOT_DETERMINED}"
        )
    return tuple(warnings)


def _significant_step(p: float, sds: float) -> bool:
    """Whether a step to the spheres' common centre is more than the SD may leave out: the
    score test rejects the answer (p-value ``p``) at :data:`ROTATION_ALPHA`, or the step is
    :data:`MAX_STEP_SDS` or more of the answer's SDs (``sds``, NaN where no SD holds)."""
    return p < ROTATION_ALPHA or sds >= MAX_STEP_SDS


def _step_bias(numbers: dict, row: list) -> list | None:
    """The bias ``(3,)`` [mm] of an answer whose precision holds, given its ``numbers`` (the
    diagnostics of :func:`annotate_many`) and its row of :func:`centre_statistics`: the
    answer's offset from the spheres' common centre where that step is significant
    (:func:`_significant_step`) but no more than :data:`MIN_REJECTED_STEP_MM`, which no
    warning reports; ``None`` elsewhere, where the iterations found no centre that the
    spheres fit better (the answer is then theirs, its step in SDs 0), and where the noise is
    rounding (a step of rounding in SDs of rounding)."""
    sds = numbers["center_step_sds"]
    if row[_ROUNDING_NOISE]:
        return None
    if not (0.0 < sds < math.inf and numbers["center_step_mm"] <= MIN_REJECTED_STEP_MM):
        return None
    if not _significant_step(numbers["center_score_p_value"], sds):
        return None
    return [-x for x in row[_TOWARDS]]


def annotate_many(results: list, markers: np.ndarray, verdicts: list[Support]) -> list:
    """``results`` of the trials of ``markers`` ``(T, N, n, 3)`` [mm] (centre results, in the
    reference frame) with their precision and score test (module docstring), given each
    trial's support verdict ``verdicts``: ``diagnostics["center_sd_mm"]``,
    ``["center_sd_noise_share"]``, ``["center_score_chi2"]``, ``["center_score_p_value"]``,
    ``["center_step_mm"]`` and warnings; where the answer is a significant step of at most
    :data:`MIN_REJECTED_STEP_MM` from the spheres' centre and nothing else is warned of, that
    step as the answer's bias ``["center_step_bias_mm"]`` ``(3,)`` [mm], the answer less that
    centre, and ``["center_sd_mm"]`` read from the covariance with its outer product added
    (the SD of the answer's error, scatter and bias; above :data:`MAX_CENTER_SD_MM` the
    warning that the data do not determine the centre). A result without a finite centre, or
    whose data the verdict did not assess (no rigid-body residual), is returned with
    ``["center_precision_not_checked"]`` saying why."""
    annotated = list(results)
    checked, centres, residuals, variances = [], [], [], []
    for t, (result, verdict) in enumerate(zip(results, verdicts, strict=True)):
        centre = result.center.tolist()
        if not all(map(math.isfinite, centre)):
            reason = "the answer is not finite"
            # A method that says it converged on it is contradicted; a failure says so itself.
            warnings = (f"{reason}: no centre was found",) if result.converged else ()
            notes = {"center_precision_not_checked": reason}
            annotated[t] = with_warnings(result, warnings, notes)
            continue
        if not verdict.diagnostics.get("assessed", False):
            reason = "the support verdict did not assess the data (no rigid-body residual)"
            annotated[t] = with_warnings(result, (), {"center_precision_not_checked": reason})
            continue
        residual = verdict.diagnostics["rigid_residual_mm"]
        checked.append(t)
        centres.append(centre)
        residuals.append(residual)
        variances.append(residual * residual / 3.0)
    if not checked:
        return annotated
    if len(checked) < len(results):
        markers = markers[checked]
    # Arrays from the numbers, not NumPy operations on a few elements.
    rows = _statistics(markers, np.array(centres), np.array(variances))
    for t, residual_mm, row in zip(checked, residuals, rows, strict=True):
        numbers = {
            "center_sd_mm": row[_SD],
            "center_sd_noise_share": row[_SHARE],
            "center_score_chi2": row[_CHI2],
            "center_score_p_value": row[_SCORE_P],
            "center_step_mm": row[_STEP],
            "center_step_sds": row[_STEP_SDS],
            "center_fit_ratio": row[_FIT_RATIO],
            "center_fit_p_value": row[_FIT_P],
            "center_offset_mm": row[_OFFSET],
            "center_spheres_fit_ratio": row[_SPHERES_RATIO],
            "center_spheres_fit_p_value": row[_SPHERES_P],
        }
        warnings = _warnings(numbers, residual_mm, not verdicts[t].warnings)
        bias = None if verdicts[t].warnings or warnings else _step_bias(numbers, row)
        if bias is not None:
            # The SD states the spheres' centre's scatter; the answer's error adds the step.
            numbers["center_step_bias_mm"] = bias
            numbers["center_sd_mm"] = row[_BIASED_SD]
            if stated_center_sd(numbers["center_sd_mm"]) is None:
                source = f"the rigid-body residual of {residual_mm:.3g} mm and the step"
                warnings = (_undetermined(numbers["center_sd_mm"], source),)
        annotated[t] = with_warnings(results[t], warnings, numbers)
    return annotated


def annotate_joint_centres(results: list, verdicts: list[Support]) -> list:
    """Joint-centre ``results`` with their precision and what the noise in their two segments'
    poses does to a least-squares centre (:mod:`jointbench.estimators.pose_noise`), given each
    trial's support verdict ``verdicts``.

    * ``diagnostics["center_sd_mm"]``, the SD along the least determined direction of the
      covariance the result states of its answer's scatter (:func:`stated_covariance`), and
      above :data:`MAX_CENTER_SD_MM` the warning that the data do not determine the centre,
      as for a centre of rotation; below it, where the result states the share of the poses'
      noise in the information that SD is first order in (``["center_sd_noise_share"]``, the
      analytic centre's, :func:`jointbench.estimators.pose_noise.analytic_noise_share`) and
      that reaches :data:`MAX_SD_NOISE_SHARE`, the warning that the SD does not hold, as for a
      centre of rotation's directions, and the same where the share of its variance second
      order in its frame-0 poses' errors (``["center_sd_anchor_share"]``,
      :func:`jointbench.estimators.pose_noise.analytic_anchor_share`) reaches
      :data:`MAX_ANCHOR_SHARE`;
    * ``["center_pose_noise_share"]``, the ratio of the noise's information to the noise-free
      information along the least determined direction, and ``["center_pose_noise_pull_mm"]``,
      how far the noise pulled the answer (both ``inf`` where the noise is as large as the
      rotation that fixes the centre), with the analytic centre's bias from its anchoring
      frame-0 poses added where the result states one (``["center_anchor_bias_mm"]``,
      :func:`jointbench.estimators.pose_noise.anchor_bias_mm`), and where the ratio reaches
      :data:`MAX_POSE_NOISE_SHARE` or the pull :func:`pull_bound_mm` of the SD a warning;
    * ``["center_pose_noise_bias_mm"]``, that pull as a vector ``(3,)`` [mm] where it is within
      its bound and the SD is positive and finite: a bias of the answer that the scatter's
      covariance leaves out, added to it as its outer product, so that the SD reported, and
      :func:`stated_covariance`, are of the answer's error about the truth (mean square), not
      of its scatter about where the noise pulled it. The pull's bound is held to the
      scatter's SD, as its constants say; :data:`MAX_CENTER_SD_MM` and the words of the SD's
      warnings to the SD reported, so that no answer reads ``ok`` with an SD every output
      prints as none, nor quotes another SD than it states. Where the pull reaches its bound
      the warning says
      the SD is no statement of the precision, and the pull, an expansion to second order
      that overstates the mean error where the noise takes most of the rotation off a hinge
      (:mod:`jointbench.estimators.pose_noise`), is not added. On small swings SCoRE's answers
      lie a good part of their scatter's SD along the pull, which the scatter's SD alone does
      not hold (``benchmarks/joint_centre_stated_sd.py`` counts them beyond 3 SDs;
      ``tests/test_pose_noise_pull_stated.py``).

    No warning is added where the verdict has already refused the data. A result without a
    finite centre is returned as it is; one that states no covariance gets no SD, and one
    whose verdict carries no pose noise (no poses, or markers too nearly collinear for their
    noise model) no pull."""
    annotated = list(results)
    for t, (result, verdict) in enumerate(zip(results, verdicts, strict=True)):
        if not np.isfinite(result.center).all():
            continue
        numbers, pulled_words = {}, []
        covariance, sd = None, None
        stated = stated_covariance(result)
        if stated is not None:
            covariance, source = stated
            sd = _largest_sd(covariance)
        noise = verdict.pose_noise
        if noise is not None:
            pulled = _pulled(noise, result)
            pull = float(np.linalg.norm(pulled))
            numbers["center_pose_noise_share"] = noise.share
            numbers["center_pose_noise_pull_mm"] = pull
            if noise.share >= MAX_POSE_NOISE_SHARE or pull >= pull_bound_mm(sd):
                pulled_words.append(_pulled_by_pose_noise(noise.share, pull, sd))
            elif sd is not None and 0.0 < sd < math.inf:
                # Within its bound the pull is a bias the SD can hold: the SD states the
                # answer's error about the truth, not its scatter about where it was pulled.
                numbers["center_pose_noise_bias_mm"] = pulled.tolist()
                sd = _largest_sd(_with_bias(covariance, pulled))
        # The SD stated, the pull's outer product in it, is the one the words quote and hold
        # to MAX_CENTER_SD_MM: an answer reads no SD that an output would print as none.
        warnings = [] if covariance is None else _sd_warnings(result, sd, source)
        warnings += pulled_words
        if sd is not None:
            numbers["center_sd_mm"] = sd
        if numbers:
            kept = () if verdict.warnings else tuple(warnings)
            annotated[t] = with_warnings(result, kept, numbers)
    return annotated


def _sd_warnings(result, sd: float, source: str) -> list[str]:
    """The warning (none, or one) that a joint centre ``result`` stating the SD ``sd`` [mm]
    along its least determined direction, from the noise ``source`` names, gets for that SD:
    that the data do not determine the centre (:func:`stated_center_sd`), or that the SD does
    not hold where the noise's share (``diagnostics["center_sd_noise_share"]``) or the frame-0
    poses' (``["center_sd_anchor_share"]``) reaches its bound."""
    share = result.diagnostics.get("center_sd_noise_share", 0.0)
    anchored = result.diagnostics.get("center_sd_anchor_share", 0.0)
    if stated_center_sd(sd) is None:
        return [_undetermined(sd, source)]
    if not share < MAX_SD_NOISE_SHARE:
        held = "the information the relative rotations of the poses hold on it"
        return [_noisy_sd(share, sd, held)]
    if not anchored < MAX_ANCHOR_SHARE:
        return [_anchored_sd(anchored, sd)]
    return []


def stated_covariance(result) -> tuple[np.ndarray, str] | None:
    """The covariance ``(3, 3)`` [mm^2] a joint-centre ``result`` states of its centre's
    error, and where its scatter's part comes from: ``diagnostics["center_covariance_mm2"]``
    where the method states one there (SCoRE's and the analytic centre's from each segment's
    pose noise, paper C's Gauss–Markov fit's with the frame-0 poses' errors, which its own
    covariance is conditional on), else its own covariance (``gauss-markov-frame0``'s);
    ``None`` for neither. The pull of the poses' noise, where the checked call states it
    (``["center_pose_noise_bias_mm"]``, :func:`annotate_joint_centres`), is added as its
    outer product: the SD is read from the sum."""
    added = result.diagnostics.get("center_covariance_mm2")
    if added is not None:
        source = (
            "the noise of both segments' poses"
            if result.covariance is None
            else "its method's covariance with the frame-0 poses' errors added"
        )
        scatter = np.asarray(added, dtype=float)
    elif result.covariance is not None:
        scatter = np.asarray(result.covariance, dtype=float)
        source = "the covariance its method states"
    else:
        return None
    return _with_bias(scatter, result.diagnostics.get("center_pose_noise_bias_mm")), source


def _with_bias(scatter: np.ndarray, bias: np.ndarray | list | None) -> np.ndarray:
    """The mean square ``(3, 3)`` [mm^2] of an error whose covariance about its mean is
    ``scatter`` ``(3, 3)`` [mm^2] and whose mean is ``bias`` ``(3,)`` [mm] (``None``: none)."""
    if bias is None:
        return scatter
    mean = np.asarray(bias, dtype=float)
    return scatter + np.outer(mean, mean)


def _pulled(noise: PoseNoise, result) -> np.ndarray:
    """How far ``(3,)`` [mm] the noise in the poses ``noise`` pulled the joint centre of
    ``result`` (:func:`jointbench.estimators.pose_noise.pull_mm`), with the analytic
    centre's bias from its anchoring frame-0 poses where the result states one, a product of
    the same noise that the pull, built on independent frames, leaves out."""
    pulled = pull_mm(noise, np.asarray(result.center))
    anchor = result.diagnostics.get("center_anchor_bias_mm")
    if anchor is not None:
        pulled = pulled + np.asarray(anchor)
    return pulled


def _largest_sd(covariance: np.ndarray) -> float:
    """The SD [mm] along the least determined direction of ``covariance`` ``(3, 3)`` [mm^2]:
    ``inf`` where it is not finite, NaN where no direction has a positive variance (no
    covariance of an answer with noise)."""
    largest = _largest_variance(kernel_array(covariance))
    return math.sqrt(largest) if largest >= 0.0 else math.nan


@kernel
def _largest_variance(covariance: np.ndarray) -> float:
    """The largest eigenvalue [mm^2] of ``covariance`` ``(3, 3)`` [mm^2] (its lower triangle,
    as NumPy's ``eigvalsh`` reads it, by the same LAPACK routine), ``inf`` where an
    entry is not finite. A compiled kernel: NumPy's ``eigvalsh`` of one 3 x 3 matrix costs a
    checked call tens of microseconds."""
    for i in range(covariance.shape[0]):
        for j in range(covariance.shape[1]):
            if not np.isfinite(covariance[i, j]):
                return np.inf
    return np.linalg.eigvalsh(covariance)[-1]


def _undetermined(sd: float, source: str) -> str:
    """The warning for a centre whose SD along its least determined direction is ``sd`` [mm],
    above :data:`MAX_CENTER_SD_MM`, from the noise ``source`` names."""
    if math.isnan(sd):
        size = "is not a number"
    else:
        size = "is unbounded" if math.isinf(sd) else f"is {sd:.3g} mm"
    return (
        f"centre not determined by the data: its SD along the least determined direction "
        f"{size} (above {MAX_CENTER_SD_MM:g} mm, from {source})"
    )


def _noisy_sd(share: float, sd: float, held: str) -> str:
    """The warning for a centre whose SD ``sd`` [mm] is first order in an information of
    which the noise is the share ``share``, :data:`MAX_SD_NOISE_SHARE` or more, along the
    least determined direction; ``held`` names that information."""
    return (
        f"centre's {PRECISION_NOT_DETERMINED} by the data: along its least determined "
        f"direction the noise is {100 * share:.0f}% of {held} (below "
        f"{100 * MAX_SD_NOISE_SHARE:g}% its SD of {sd:.3g} mm would hold)"
    )


def _anchored_sd(share: float, sd: float) -> str:
    """The warning for a joint centre whose variance is the share ``share``,
    :data:`MAX_ANCHOR_SHARE` or more, second order in the errors of the frame-0 poses that
    anchor both body frames (:func:`jointbench.estimators.pose_noise.analytic_anchor_share`)
    against its first-order SD ``sd`` [mm], and what lowers that share: the rotations
    that errors of the frame-0 poses add are a larger part of a smaller swing's, and the
    second-order part grows with the noise's square against the first's."""
    return (
        f"centre's {PRECISION_NOT_DETERMINED} by the data: the errors of the frame-0 poses, "
        "which place the joint in both segments and turn every relative rotation, make its "
        f"error a product of noises whose second-order variance is {100 * share:.0f}% of the "
        f"first-order one in some direction (below {100 * MAX_ANCHOR_SHARE:g}% its SD of "
        f"{sd:.3g} mm would hold; a wider swing or less marker noise lowers it)"
    )


def pull_bound_mm(sd: float | None) -> float:
    """The least pull [mm] of the noise in the poses (:mod:`jointbench.estimators.pose_noise`)
    that leaves a joint centre's SD ``sd`` [mm] (along its least determined direction, or
    ``None`` where the method states none) no statement of its precision:
    :data:`MAX_STEP_SDS` of that SD, but at least :data:`MIN_POSE_NOISE_PULL_MM`, and
    :data:`MAX_POSE_NOISE_PULL_MM` where that is less or no finite SD is stated. The pull is a
    bias the SD (its scatter's) does not hold, as a centre's step is, and is held to the SD as
    the step is (:data:`MAX_STEP_SDS` says why); the floor and the cap say theirs.
    ``benchmarks/joint_centre_degenerate.py`` counts, on nearly hinged trials, the answers
    that read ``ok`` and how far off they are."""
    if sd is None or not math.isfinite(sd):
        return MAX_POSE_NOISE_PULL_MM
    return min(MAX_POSE_NOISE_PULL_MM, max(MIN_POSE_NOISE_PULL_MM, MAX_STEP_SDS * sd))


def _pulled_by_pose_noise(share: float, pull: float, sd: float | None) -> str:
    """The warning for a joint centre whose poses' noise has the ratio ``share`` to the
    noise-free information along its least determined direction and pulled it ``pull``
    [mm], the answer stating an SD ``sd`` [mm] (``None`` for none). The pull is a bias the
    answer's SD (its scatter's) does not contain: a pull of :data:`MAX_POSE_NOISE_PULL_MM`,
    half :data:`MAX_CENTER_SD_MM`, is over :data:`MAX_STEP_SDS` of any SD that holds, a
    smaller one over that of a smaller SD (:func:`pull_bound_mm`), and at
    :data:`MAX_POSE_NOISE_SHARE` the answer keeps at most five sixths of the joint's offset
    from the markers, so that SD is no statement of the answer's precision."""
    words = (
        f"{PRECISION_NOT_DETERMINED}: the noise in the poses pulls a least-squares joint centre "
        "towards the markers"
    )
    if math.isinf(share):
        return (
            f"{words} by more than the data can bound: it is as large as the rotation off the "
            "main axis that fixes the joint centre"
        )
    kept = (
        f"it keeps {100 / (1 + share):.0f}% of the joint's offset from them along its least "
        "determined direction"
    )
    if share >= MAX_POSE_NOISE_SHARE:
        return (
            f"{words}: {kept}, too little rotation off the main axis for that noise (the pull "
            f"read at this answer, {pull:.3g} mm, understates it where the noise has moved "
            "the answer itself)"
        )
    if pull < MAX_POSE_NOISE_PULL_MM:
        # Only the SD makes so small a pull count: the words say so, and a larger one's stay.
        times = pull / sd if sd > 0.0 else math.inf
        held = f"{times:.2g} of its SD of {sd:.3g} mm, a bias beside the scatter it states"
        kept = f"{held}; {kept}"
    return (
        f"{words}, about {pull:.3g} mm here ({kept}): too little rotation off the main axis "
        "for that noise"
    )
