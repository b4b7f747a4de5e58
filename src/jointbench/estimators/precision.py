"""How precisely an axis method's own cost determines its answer, added to a user's checked call.

A search reports the minimum of its cost; whether the data make that minimum a sharp one is a
separate question. On a short arc the radial cost of paper B can be nearly flat across tens of
degrees, and its minimum is then wherever the noise puts it, although the rotation itself is
resolved (the support verdict, :mod:`jointbench.estimators.support`, judges the data, not the
method). After the self-check the registry (:func:`jointbench.estimators.registry.get`) calls
the method's ``precision_many(results, markers, verdicts=...)`` (with the trials' support
verdicts, whose rigid-body noise a cost's residuals are held to), which writes into each
result:

* ``diagnostics["axis_sd_deg"]``: the standard deviation of the answer's direction implied by
  the method's cost and the data [deg], reported as ``sqrt(var_1 + var_2)`` over the two
  angles of the direction in its tangent plane: the RMS angle between the answer and the axis
  that noise of the size the cost's residuals show would give. ``inf`` where the cost does not
  rise in every direction from the answer, or has no more residuals than parameters;
* a warning in ``status`` when it is above :data:`MAX_AXIS_SD_DEG`
  (:func:`jointbench.estimators.results.with_warnings`; ``converged`` is left as the method set
  it).

For a least-squares cost ``f`` (a sum of ``n_residuals`` squared residuals with ``n_params``
parameters fitted), the covariance of the parameters at the minimum is ``2 s^2 H^-1``, ``H``
the Hessian of ``f`` and ``s^2 = f / (n_residuals - n_params)`` the residual variance; the
direction's block of it is the direction's covariance with the other parameters free
(:func:`direction_sd_deg`). The direction is parameterised by its tangent angles ``a``,
``n(a) = (n + E a) / |n + E a|`` with ``E`` an orthonormal basis normal to ``n``
(:func:`tangent_basis`). ``H`` is the cost's exact Hessian, not Gauss–Newton's ``2 J' J``: at
the minimum of an errors-in-variables cost such as the planar one, ``J' J`` also holds the
noise's own share, which would pass for signal on a short arc (the method's module derives
its costs' Hessians). SARA, a closed form, states its SD from its eigen-problem instead: the
perturbation of its null vector by the eigenvalue gap (:mod:`jointbench.estimators.twosegment`).

Where the answer is not the cost's minimum over all these parameters (the radial and combined
searches hold the axis's point ``m`` at the NM centre where their costs would move it), the
Newton step ``-H^-1 g`` (``g`` the gradient) is how far the answer lies from that minimum: its
direction's part is added to the SD in quadrature, as a bias, and ``s^2`` is taken at that
minimum, ``(f - g' H^-1 g / 2) / dof``.

When the first-order SD is a statement of precision at all: both closed-form axes are
eigenvectors, planar's the smallest of the scatter ``S`` and SARA's the null vector of its
normal matrix ``M``, and noise perturbs such a matrix twice over. Its cross term with the signal
moves the eigenvector by ``N(0, s^2 / gap)`` per tangent direction, ``gap`` the eigenvalue gap
above the answer's: that is what the SD states. Its square, the noise's own share, adds
``s^4 n / gap^2`` over ``n`` samples (the second term of the variance of an errors-in-variables
estimator, Fuller 1987), and ``s^2 n`` is the answer's own eigenvalue, the noise's share of
the matrix ``lambda_0``: the planar SD leaves out a factor ``1 + lambda_0 / gap`` of the
variance (SARA's, weighting by ``lambda_j / gap^2``, carries it), and where the gap is not
above that share the neglected term is the larger one and the eigenvector
is no longer a small perturbation of the axis (Davis–Kahan: its angle is bounded only by the
perturbation's size over the gap, here not below 1). On a 2 degree arc (4 markers about 100 mm
from the axis, 0.5 mm, 50 frames, 200 seeds) the planar RMS error over the SD rose with
``lambda_0 / gap`` as ``sqrt(1 + lambda_0 / gap)`` below 1 (1.02 at 0-0.1, 1.35 at 0.5-1; 1.3%
of answers more than 3 SDs off) and beyond it as the error left the linearisation (1.85 at 1-2,
2.99 at 2-5; 12-43% more than 3 SDs off, answers 55-67 degrees off with SDs of 8 degrees).
Where the noise's share reaches the gap the result says the precision is not determined
(:func:`annotate_validity`); the SD is kept as computed. For SARA the share is not the same in
every direction: a pose's rotation noise is ``s^2 K^-1`` (Pennec & Thirion 1997, ``K`` the
cluster's inertia), largest about the cluster's long axis, and a thin cluster's noise about it
can match the hinge's rotation. The share compared is then the largest over the tangent
directions, and the noise's anisotropy has a mean effect besides: it pulls the null vector by
``lambda_0 |E' K^-1 n| / (q(n) gap)`` (:func:`jointbench.estimators.twosegment._sara_validity`),
a bias the SD, a statement of the scatter about it, leaves out; where it is above the SD the
neglected term is again the larger. On the same 5 degree hinges 3.4% of SARA's answers passed
as determined were more than 4 SDs off with the share alone, none with the pull; on the
calibration hinges of ``tests/test_axis_sd.py`` (one cluster, 200 seeds) the mean tilt of the
answers matched the pull stated (2.76 against 2.62 degrees at 10 degrees and 1 mm, 0.33
against 0.30 at 30 degrees and 1 mm, 5.9 against 5.5 at 2 degrees and 0.3 mm).

Frames repeated exactly carry no new noise; counting them would shrink the SD as the square root
of the repetition. The SD is therefore taken from the distinct frames (:func:`distinct_frames`).

What the SD does not see: a second minimum as sharp as the answer's. With the NM centre far
along a short arc's axis, the radial cost's cylinders about a line through it nearly normal to
the true axis fit the arcs as closely as the true cylinders (a marker's distance from such a
line varies over a 30 degree arc by tenths of a millimetre), and in a share of noisy
pure hinges (7% at 30 degrees and 0.3 mm, 35% at 1 mm, over 40 seeds) the radial search ends
there, 65-90 degrees off, at a cost below the true axis's even with the axis's position free,
and curved as sharply as it. The SD is a statement of the cost's local curvature and cannot
tell that minimum from the true one. In the same trials the planar and combined answers stay
within about 2 degrees of the axis.

The self-check sees it instead: its restart from the planar eigenvector ends at the true
axis's minimum, and where that and the answer are two minima more than
:data:`AMBIGUOUS_APART_DEG` apart (the answer replaced by the restart's, or kept), the method
compares them (:func:`ambiguity`, :func:`annotate_ambiguity`). Two separate minima are two
non-nested fits of the same residuals, not one fit and its neighbour, so the chi-square
difference of a confidence region (``s^2`` times a quantile for the direction's two
parameters) is not their noise: between the true axis and the second minimum of those hinges
the profiled costs differed by up to 7 times ``s^2 chi2_2(1 - 1e-3)``, either way round. The
difference ``D = sum_i d_i`` of the two fits' squared residuals ``d_i`` sample by sample has the
standard error ``sqrt(n var(d))`` over the ``n`` samples (Vuong 1989, the test of two non-nested
models that fit equally well); the other minimum is not told apart from the answer when
``D`` is below the one-sided normal quantile at
:data:`jointbench.estimators.support.ROTATION_ALPHA` times it. On those hinges the true
axis's ``D`` was at most 2.0 standard errors above the second minimum's (0.3 and 1 mm noise,
40 seeds each), below the quantile 3.09.

What neither sees: a minimum of the radial cost that the data prefer, but not on the
hinge's axis. On a short arc (5-10 degrees) the radial cost can fall well below its value at
the true axis tens of degrees away, sharp enough for an SD under :data:`MAX_AXIS_SD_DEG`:
a family of cylinders about a tilted axis fits the noise on nearly straight arcs. Its
restart from the planar eigenvector descends into the same valley, so there is no second
minimum either. The planar cost has no such valley, and on a hinge both are estimates of its
one axis, so the radial answer is compared with the planar eigenvector (the closed-form
planar answer the result carries): their angle over ``sqrt(sd^2 + sd_planar^2)`` is a
Hausman-type test of "both find the same axis", conservative since the two share the
markers' noise and their difference varies less than the sum. Beyond the one-sided normal
quantile at :data:`jointbench.estimators.support.ROTATION_ALPHA` the radial cost is said not
to determine the axis (:func:`annotate_agreement`);
``tests/test_axis_sd_validity.py`` counts what it catches and what it passes.

What none of these sees: an answer whose own cost is sharp and agrees with itself, but which
is not the motion's axis. Paper B's planar cost, on a near-hinge whose abduction is a fraction
of its flexion, finds the direction the markers move least along, and on short arcs that can
be tens of degrees from the flexion axis with an SD of a few (knee, 5 degrees of flexion, AA 0.3
times it, 1 mm: answers about 75 degrees off with SDs under 3). The registry therefore compares
every checked axis answer, whatever its method, with a reference taken from the data alone:
the principal axis of the segment's rotations about their mean pose, with its own SD from the
pose noise (:class:`jointbench.estimators.support.MotionAxis`). That axis is the joint's own
only for a hinge: abduction coupled to flexion, or the knee's screw-home rotation, tilt it from
the flexion axis an accurate method finds by up to about 20 degrees. So an answer is said not
to be the motion's axis (:func:`annotate_motion_axis`) only beyond
:data:`MOTION_AXIS_BAND_DEG` from it, significantly in the reference's SD (the one-sided
normal quantile at :data:`jointbench.estimators.support.ROTATION_ALPHA`): another axis, not a
compromise of this motion's. The answer's own stated SD does not narrow the band, since a
method could state any; it can widen only a hinge's (below). Where the reference is not
determined (the noise's share of the rotations' scatter reaches its eigen-gap, its SD is above
:data:`MAX_AXIS_SD_DEG`, or a pose's rotation SD is above :data:`MAX_REFERENCE_POSE_SD_DEG`,
where the first-order pose noise behind both understates a thin cluster's) nothing is
compared, and the result says why. Where the
support verdict finds no rotation about a second axis (its off-axis test passes at
:data:`jointbench.estimators.support.ROTATION_ALPHA`), nothing couples to the flexion to tilt
the principal axis, which is then the hinge's own, and the band is the narrower
:data:`MISFIT_BAND_DEG`. A cluster that translates along its hinge's axis with the angle (a
plate sliding on its segment, a screw motion) needs it: each marker's arc then lies nearly in
a plane tilted from the axis, which the planar and combined costs fit to a sharp minimum
far from the axis in their own SDs, while the rotations are about the axis alone. An answer
whose own stated SD reaches beyond that band is held to :data:`_TOLD_APART_Z` of that SD
instead (:func:`_hinge_band_deg`), no wider than the band of any motion: a radial answer on a
short arc under heavy noise, stating several degrees, lies that far off as its own scatter,
not as another axis's answer.
``tests/test_axis_motion_check.py`` holds the cases it catches and those it passes.

What every SD above rests on: markers that read the segment's rotation to first order. A
method reads the rotation through the markers, the trajectory costs through each marker's arc,
whose radius is its distance ``r`` from the axis, SARA through the poses and translations they
give, and a marker with noise ``s`` per coordinate reads a frame's rotation to ``s / r``. A
marker's arc is a circle whose centre and normal are the axis, so one marker that reads the
rotation to first order can fix the axis line; where ``s / r`` is above
:data:`MAX_REFERENCE_POSE_SD_DEG`, the bound on a frame's rotation noise beyond which it is
not first order, for every marker, none can, and the costs' residuals about a line that near
the markers are not linear in their noise. ``r`` is read from the data alone, not from the
answer's line, which a wrong answer places where it lies and so would vouch for itself: a
marker's lever, how far it travels over how much the poses say the segment turns, both net of
their noise (:class:`jointbench.estimators.support.MotionAxis`, ``arc_rotation_sd_deg``).
Where the marker with the longest lever reads a frame's rotation worse than that bound, the
result says its precision is not determined, whatever the method
(:func:`annotate_motion_axis`). Two markers were asked for first (the line as the meet of the
planes through each marker normal to its travel), which took ``ok`` from correct answers of
clusters with one long lever and the rest on the axis (markers on a knee's joint line and one
on the ankle). The same bound on the pose noise about the answer's axis, from the cluster's
inertia, called compact plates far from a hinge undetermined although each marker's arc about
it has a long lever. Where the poses' rotation is itself mostly noise (a cluster a few
millimetres across against a millimetre of noise) it reads larger than the motion and the
levers shorter: the rule then errs towards saying not determined.

For the same reason the radial and combined costs' SD counts only the markers that read the
rotation within that bound (:func:`first_order_markers`): the SD is the cost's curvature over
its residuals' noise, which holds where each residual is linear in its marker's noise, and a
marker's distance from a line 3 mm away, under 1 mm of noise, is mostly the noise's own length;
its planar residuals are linear but its scatter is noise, whose fluctuations the combined cost
would count as curvature. One marker's arc fixes one circle, and on a short arc fixes the
axis's direction only through its sagitta, so the markers kept may not fix the direction while
the others make the SD read a few degrees: two markers 3 mm from a hinge's axis and one 100 mm
from it, on 10-30 degree arcs (``benchmarks/blind_spots.py``), left radial and combined answers
``ok`` up to 85 degrees off with SDs under 10. So where some markers are left out,
``diagnostics["axis_sd_deg"]`` is the SD the answer's cost implies on the others alone, and
above :data:`MAX_AXIS_SD_DEG` the precision is said not to be determined
(:func:`annotate_first_order`); where all are kept the SD is as before, and where none is, the
rule above says so. The planar method is held to its own check of the noise's share of its
scatter (:func:`annotate_validity`), SARA to the pose checks. A lever is read from a marker's
travel net of the noise's mean; a marker a few millimetres from the axis travels less than the
noise's own scatter, so its lever can read long by chance and the marker be kept (one of the
benchmark's answers, 77 degrees off, kept two 3 mm markers reading 4.7 degrees a frame). A
margin of the noise's scatter at 0.001 closed it but dropped, at random, a marker 16 mm from
the axis under 1 mm of noise (3.6 degrees a frame) and with it the radial SD's calibration.
``tests/test_axis_motion_check.py`` holds the near-axis case, the compact
plate, the joint-line markers and the one far marker.

What the band lets through: motion the cost does not model. A hinge with an independent wobble
about another axis of a tenth of its arc (0.5 mm noise) leaves the planar and combined answers
up to 30 degrees off with SDs of one or two, inside the band: the SD counts the wobble's share
of the residuals as independent noise, where it moves every marker of a frame together and
changes slowly over the frames. Whether the markers move as the cost's model says is a test of
its residuals against the rigid-body noise, which does not depend on any axis (:func:`misfit`):
their variance at the cost's minimum, ``f / dof``, over the support verdict's ``s^2`` is
F-distributed where they are the noise alone, both degrees of freedom scaled by ``2 / (2 +
kurtosis)`` for heavy-tailed noise (the kurtosis read off the residuals, misfit and all: a
misfit in a few frames widens its own test's spread). How far such a misfit moves the answer the
data cannot say: a misfit ``r`` moves the parameters by ``-(J'J)^-1 J' r``, and the part of
``r`` that does so, in the span of ``J``, is the part the fit absorbs and leaves no residual of.
What is measured is the rest, the excess ``e = f - dof s^2``; a misfit of that size along the
least determined direction would tilt the answer by ``sqrt(e lambda)``, ``lambda`` the largest
eigenvalue of the direction's block of ``(J'J)^-1 = (H / 2)^-1``: a scale, not a bound. A
structured misfit can be absorbed far beyond it (a wobble about the axis normal to both the
hinge and the markers' direction from it: 20 degrees off with a scale of 5), and one unlike
the wobble far below it (paper B's coupled abduction: scales of 30 to 40 degrees, answers
within 5). Where the test rejects and the
scale is above :data:`MAX_AXIS_SD_DEG`, the cost is said not to vouch for its answer
(:func:`unsupported_by_its_cost`), and the principal axis, which a wobble about a fixed hinge
tilts little (its eigen-gap is the rotations' own spread, where the planar cost's is the arcs'
sagitta), is held to a narrower band, :data:`MISFIT_BAND_DEG`; where that axis is not
determined, the answer is said to be checked by nothing. A slow random drift of the wobble tilts
the principal axis too, and a marker sliding on its segment moves the rigid-body residual with
it, so neither is seen; a reference segment's pose noise, carried into its frame with the
moving markers, moves the whole cluster as a wobble does and is read as misfit too.
``tests/test_axis_misfit.py`` and ``benchmarks/axis_misfit.py`` count what it catches and what
it passes.

Everything above judges the direction. An answer's ``point`` is a statement of its own: on a
3 degree hinge with 1 mm noise, ``ok`` answers of paper B's costs lay up to 280 mm from the axis,
their directions within a few degrees. A method that states the point's precision writes
``diagnostics["axis_point_covariance_mm2"]`` ``(3, 3)`` [mm^2], the covariance of the point
across the axis (where along the axis it lies does not matter), and
``diagnostics["axis_point_sd_mm"]``, its SD along the least determined direction across the
axis, and where that is above :data:`MAX_AXIS_POINT_SD_MM` the status says the point is not
determined (:func:`annotate_point`). The direction's own statements are left as they are: a
short arc can fix the direction and leave the line's place open. From a least-squares cost in
the line's tilt and shift, :func:`point_covariance` carries the tilt's uncertainty to the
point by its height along the axis, with the cost's Newton step as a bias (paper B's costs:
:mod:`jointbench.estimators.axis`); SARA states its point from its normal matrix, with the
pull of its rotations' noise as the bias (:mod:`jointbench.estimators.twosegment`).

That covariance is first order, as the direction's SD is, and fails where the planar SD does,
in the errors-in-variables regime. The exact Hessian ``H`` of a least-squares cost is its
Gauss–Newton part ``G = 2 sum grad(r) grad(r)'`` less the residuals' own term ``N = -2 sum r
d2r``. Where the residuals are noise, ``N`` is the noise's: for the planar cost ``N = 2 (n' S n)
I``, and ``lambda_0 / gap`` above is the largest eigenvalue of ``H^-1 N``. Read off the
residuals, though, ``N`` also holds whatever motion the cost does not model (paper B's coupled
abduction, whose misfit made that share 2-20 on its hinge grid while the answers' points lay
within a millimetre of the axis). So the share is read from the stated noise instead: the
expected value of ``N`` under the support verdict's rigid-body noise ``s^2``, which to second
order in the noise is ``-2 s^2 sum grad_v(r) . grad_v(d2r)``, each residual's derivative in its
marker's coordinates times its second derivative's (for the planar residuals ``2 s^2 P (N - 1)
I``, the planar share with ``lambda_0`` read as the noise's ``s^2 P (N - 1)``; the radial
residuals' is derived in :mod:`jointbench.estimators.axis`), against the curvature the cost's
model then leaves, ``G - E[N]`` (``E[H]`` under that model; ``H`` itself also takes the
misfit's term out). Where the largest eigenvalue of ``(G - E[N])^-1 E[N]`` (:func:`noise_share`)
is not below 1, in any combination of the parameters, the noise's own term is the larger, the
expansion the covariance rests on does not hold, and :func:`annotate_point` says the point is
not determined. It is read for the combined answer, whose line is the combined cost's own
minimum; the planar and radial answers' points are read at the planar eigenvector's line,
whose eigen-problem the planar check holds to the same share.

The simulated studies call the registered functions without this check, as they do without the
self-check, so their results are the papers' methods alone.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from jointbench.estimators.results import (
    MAX_AXIS_POINT_SD_MM,
    MAX_AXIS_SD_DEG,
    MAX_DIRECTION_OFF_DEG,
    PRECISION_NOT_DETERMINED,
    stated_axis_sd,
    with_warnings,
)
from jointbench.estimators.support import ROTATION_ALPHA, MotionAxis
from jointbench.numerics.compiled import kernel, kernel_array
from jointbench.numerics.small import tangent_basis_into
from jointbench.numerics.special import f_survival

__all__ = [
    "AMBIGUOUS_APART_DEG",
    "MAX_AXIS_POINT_SD_MM",
    "MAX_AXIS_SD_DEG",
    "MAX_DIRECTION_OFF_DEG",
    "MAX_REFERENCE_POSE_SD_DEG",
    "MISFIT_BAND_DEG",
    "MOTION_AXIS_BAND_DEG",
    "CostAt",
    "Misfit",
    "ambiguity",
    "annotate",
    "annotate_agreement",
    "annotate_ambiguity",
    "annotate_first_order",
    "annotate_misfit",
    "annotate_motion_axis",
    "annotate_point",
    "annotate_travel",
    "annotate_validity",
    "cost_at",
    "direction_sd_deg",
    "distinct_frames",
    "first_order_markers",
    "line_angle_deg",
    "misfit",
    "noise_share",
    "point_covariance",
    "rigid_dof",
    "smaller_eigenvalue",
    "stated_axis_sd",
    "tangent_basis",
    "unsupported_by_its_cost",
]

#: Two minima of an axis cost this far apart [deg] are two answers, not one answer's scatter:
#: three times the largest SD the precision check passes as determined
#: (:data:`MAX_AXIS_SD_DEG`), and below the 65-90 degrees the radial cost's second minimum lies
#: from the true axis (module docstring).
AMBIGUOUS_APART_DEG = 30.0

#: An answer significantly further than this [deg] from the principal axis of the segment's
#: rotations is not the motion's axis (:func:`annotate_motion_axis`): two axes this far apart
#: are two answers (:data:`AMBIGUOUS_APART_DEG`). A joint's own axis need not be the principal
#: axis of its rotations: abduction coupled to flexion (paper B's in phase, at a ratio of 0.3)
#: or the knee's screw-home rotation tilt the latter by up to about 20 degrees from the
#: flexion axis an accurate method finds, which a narrower band would warn about.
MOTION_AXIS_BAND_DEG = AMBIGUOUS_APART_DEG

#: ... or further than this [deg], where the answer's own cost cannot vouch for it
#: (:func:`unsupported_by_its_cost`): the markers leave the cost's model of a fixed axis by
#: more than their noise, enough to tilt its answer beyond :data:`MAX_AXIS_SD_DEG`; or where
#: the support verdict finds no rotation about a second axis, so that no coupling tilts the
#: principal axis from the joint's (module docstring). The
#: principal axis is the estimate such motion tilts least: its eigen-gap is the rotations' own
#: spread, where a planar cost's is the arcs' sagitta. Paper B's tighter accuracy band
#: (claim B2).
MISFIT_BAND_DEG = 5.0

#: The motion's axis is compared only where no pose's rotation SD is above this [deg]: beyond
#: it (a thin or nearly collinear cluster) the first-order pose noise ``s^2 K^-1`` understates
#: the rotation noise about the cluster's weak axis, and the principal axis can lie along
#: that axis with a small stated SD. An answer's precision is not determined where no marker
#: reads a frame's rotation through its arc within it (module docstring).
MAX_REFERENCE_POSE_SD_DEG = 5.0

# The one-sided normal quantile that a cost difference must exceed, in standard errors, to be
# told from noise (module docstring).
_TOLD_APART_Z = statistics.NormalDist().inv_cdf(1.0 - ROTATION_ALPHA)


def tangent_basis(direction: np.ndarray) -> np.ndarray:
    """An orthonormal basis ``(3, 2)`` of the plane normal to the unit ``direction`` (3,)
    (:func:`jointbench.numerics.small.tangent_basis_into`)."""
    basis = np.empty((3, 2))
    tangent_basis_into(kernel_array(direction), basis)
    return basis


def _cross(a: list[float], b: list[float]) -> np.ndarray:
    """``a x b`` ``(3,)`` of two vectors given as 3 floats, each component ``a_i b_j - a_j b_i``
    as ``np.cross`` computes it (so equal to it bit for bit), without the cost of its
    broadcasting, which was most of a checked axis call's statement of precision on a short
    trial."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return np.array((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0))


def direction_sd_deg(at: CostAt) -> float:
    """The SD of a direction [deg] from a least-squares cost ``at`` the answer
    (:func:`cost_at`), the direction's two tangent angles [rad] first among its parameters,
    the others (positions, in any unit) free (module docstring). ``inf`` when the residuals
    have no degrees of freedom or ``H`` is not positive definite (the cost does not rise in
    every direction from the answer)."""
    if at.inverse is None or at.dof < 1:
        return math.inf
    step = -at.inverse @ at.gradient
    covariance = 2.0 * (at.least / at.dof) * at.inverse
    variance = float(covariance[:2, :2].trace()) + float(step[:2] @ step[:2])
    return math.degrees(math.sqrt(max(variance, 0.0)))


def point_covariance(at: CostAt, direction: np.ndarray, height: float) -> np.ndarray:
    """The covariance ``(3, 3)`` [mm^2] of the point at ``height`` [mm] along a line through
    the markers, across the line (rank 2, in the plane normal to the unit ``direction`` (3,)),
    from a least-squares cost ``at`` the line (:func:`cost_at`) whose parameters are the
    line's tangent angles ``a`` [rad] in the basis ``E`` of :func:`tangent_basis` and its
    shift ``b`` [mm] along ``E`` at the foot of the markers' centroid, about which it tilts.

    The line's point at ``height`` ``h`` moves by ``E (b + h a)``: the covariance is
    ``E J (2 s^2 H^-1) J' E'`` with ``J = [h I, I]`` ``(2, 4)``, the direction's uncertainty
    carried to the point by its lever ``h``; the Newton step ``-H^-1 g``, how far the cost's
    minimum lies from the line, is added as a bias ``E J step (E J step)'``, as
    :func:`direction_sd_deg` adds its direction's part.
    ``inf`` throughout where ``H`` is not positive definite or the residuals have no degrees
    of freedom."""
    if at.inverse is None or at.dof < 1:
        return np.full((3, 3), math.inf)
    identity = np.eye(2)
    lever = np.hstack([height * identity, identity])
    step = lever @ (-at.inverse @ at.gradient)
    across = 2.0 * (at.least / at.dof) * (lever @ at.inverse @ lever.T) + np.outer(step, step)
    basis = tangent_basis(direction)
    return basis @ across @ basis.T


def annotate_point(result, covariance: np.ndarray, share: float = math.nan):
    """``result`` with ``diagnostics["axis_point_covariance_mm2"]``, the ``covariance``
    ``(3, 3)`` [mm^2] of its point across the axis (:func:`point_covariance`), and
    ``diagnostics["axis_point_sd_mm"]``, the point's SD along its least determined direction
    across the axis [mm] (the root of the covariance's largest eigenvalue); above
    :data:`MAX_AXIS_POINT_SD_MM`, a warning that the point is not determined. ``share``, where
    the covariance was read from a cost whose own minimum the answer's line is, is that cost's
    :func:`noise_share` under the stated noise (``diagnostics["axis_point_noise_share"]``);
    where it is not below 1 the noise's own term, which the first-order covariance leaves out,
    is the larger, and the point is said not to be determined either (module docstring). NaN:
    not read. The direction's statements are left as they are: a short arc can fix the axis's
    direction and leave where it lies open. ``converged`` is left as the method set it."""
    covariance = np.asarray(covariance, dtype=float)
    finite = np.isfinite(covariance).all()
    sd_mm = math.sqrt(max(float(np.linalg.eigvalsh(covariance)[-1]), 0.0)) if finite else math.inf
    warnings = ()
    # NaN fails the comparison and is warned about: it tells nothing either.
    if not sd_mm <= MAX_AXIS_POINT_SD_MM:
        said = "is unbounded" if math.isinf(sd_mm) else f"is {sd_mm:.1f} mm"
        warnings = (
            f"point not determined: its SD across the axis {said} (above "
            f"{MAX_AXIS_POINT_SD_MM:g} mm), so the line may lie anywhere that far from the point "
            "given, whatever its direction's SD",
        )
    elif share >= 1.0:
        said = "takes all of" if math.isinf(share) else f"is {share:.2g} times what is left of"
        warnings = (
            f"point not determined: under the stated noise the noise's own term {said} the "
            f"curvature its SD across the axis ({sd_mm:.1f} mm) is read from (a share not below "
            "1), so the SD leaves out the larger part of the error",
        )
    diagnostics = {"axis_point_sd_mm": sd_mm, "axis_point_covariance_mm2": covariance.tolist()}
    if not math.isnan(share):
        diagnostics["axis_point_noise_share"] = share
    return with_warnings(result, warnings, diagnostics)


@kernel
def rigid_dof(n_markers: int, n_frames: int) -> int:
    """The degrees of freedom of the rigid-body residual of ``n_markers`` markers over
    ``n_frames`` frames: ``3 n`` coordinates less a pose's 6 per frame, less the shape's own
    (at least 3 per frame). A compiled kernel."""
    return max(3 * n_markers - 6, 3) * (n_frames - 1)


class Misfit(NamedTuple):
    """How far a least-squares axis cost's residuals at its minimum exceed the rigid-body
    noise, and the tilt an excess of that size can give the answer (:func:`misfit`)."""

    ratio: float  # the residuals' variance over the noise's
    p_value: float  # one-sided, of "the residuals are the noise alone"
    tilt_scale_deg: float  # [deg]: not a bound (module docstring)


def misfit(at: CostAt, noise_variance: float, noise_dof: int) -> Misfit | None:
    """A least-squares cost's lack of fit against the rigid-body noise, and the tilt a misfit of
    its size can give the answer (module docstring): the cost ``at`` the answer against the
    noise ``noise_variance`` [mm^2] per coordinate on ``noise_dof`` degrees of freedom.

    The ratio of the residuals' variance at the cost's minimum to the noise's is F-distributed
    where the residuals are the noise alone; both degrees of freedom are scaled by
    ``2 / (2 + kurtosis)`` (Satterthwaite's), the excess kurtosis read off the residuals and
    floored at a normal one's, so that heavy-tailed noise is not taken for misfit. The tilt
    scale is ``sqrt(e lambda)``: ``e`` the cost at its minimum less the noise's share
    ``dof s^2``, ``lambda`` the largest eigenvalue of the direction's block of ``(H / 2)^-1``.
    ``None`` where ``H`` is not positive definite (the cost has no minimum to measure at) or
    the residuals have no degrees of freedom."""
    if at.inverse is None or at.dof < 1:
        return None
    inverse, least = at.inverse, at.least
    variance = least / at.dof
    if noise_variance > 0.0:
        ratio = variance / noise_variance
    else:  # noise-free data: any residual at all is a misfit
        ratio = math.inf if variance > 0.0 else math.nan
    kurtosis = at.n_residuals * at.fourths / at.cost**2 - 3.0 if at.cost > 0.0 else 0.0
    shrink = 2.0 / (2.0 + max(kurtosis, 0.0))
    p_value = f_survival(at.dof * shrink, noise_dof * shrink, ratio)
    excess = max(least - at.dof * noise_variance, 0.0)
    reach = max(float(np.linalg.eigvalsh(2.0 * inverse[:2, :2])[-1]), 0.0)
    return Misfit(ratio, p_value, math.degrees(math.sqrt(excess * reach)))


class CostAt(NamedTuple):
    """A least-squares axis cost at an answer, as :func:`direction_sd_deg` and :func:`misfit`
    read it (:func:`cost_at`)."""

    gradient: np.ndarray  # (k,): the direction's two tangent angles [rad] first
    hessian: np.ndarray  # (k, k)
    cost: float  # [mm^2]
    fourths: float  # the residuals' fourth powers summed [mm^4]
    n_residuals: int
    dof: int  # residuals less the centroids or radii they are taken from, less parameters
    inverse: np.ndarray | None  # (k, k) H^-1; None where H is not positive definite
    least: float  # the cost at the minimum a Newton step reaches [mm^2]; NaN without inverse
    # (k, k): H's Gauss-Newton part 2 sum grad(r) grad(r)', and the expected value of the rest,
    # the residuals' own term, under noise of unit variance per coordinate (noise_share); None
    # where the cost gave none.
    gauss_newton: np.ndarray | None = None
    unit_noise_term: np.ndarray | None = None


def cost_at(
    gradient: np.ndarray,
    hessian: np.ndarray,
    cost: float,
    fourths: float,
    n_residuals: int,
    dof: int,
    gauss_newton: np.ndarray | None = None,
    unit_noise_term: np.ndarray | None = None,
) -> CostAt:
    """The :class:`CostAt` of a least-squares cost with ``gradient`` ``g`` ``(k,)`` and
    ``hessian`` ``H`` ``(k, k)`` at the answer, its value ``cost`` [mm^2], its residuals'
    summed ``fourths`` powers [mm^4], their number ``n_residuals`` and its ``dof``: with
    ``H^-1`` and ``f - g' H^-1 g / 2``, the cost at the minimum a Newton step reaches (not below
    zero), where ``H`` is positive definite and both are finite; ``gauss_newton`` and
    ``unit_noise_term`` ``(k, k)``, where the caller has them, are ``H``'s Gauss–Newton part
    and the expected value of the residuals' own term under unit noise (:func:`noise_share`)."""
    # The arrays' own methods: np.all, np.diag and np.outer would cost a quarter of the rest.
    hessian, gradient = np.asarray(hessian, dtype=float), np.asarray(gradient, dtype=float)
    inverse = _positive_definite_inverse(hessian) if np.isfinite(gradient).all() else None
    least = math.nan
    if inverse is not None:
        least = max(cost - 0.5 * float(gradient @ inverse @ gradient), 0.0)
    return CostAt(
        gradient,
        hessian,
        cost,
        fourths,
        n_residuals,
        dof,
        inverse,
        least,
        gauss_newton,
        unit_noise_term,
    )


def noise_share(at: CostAt, noise_variance: float) -> float:
    """The noise's own share of a least-squares cost's curvature ``at`` an answer, under the
    stated noise ``noise_variance`` [mm^2] per coordinate (module docstring): the largest
    eigenvalue of ``(G - E[N])^-1 E[N]``, ``G`` the cost's Gauss–Newton Hessian and ``E[N] =
    noise_variance`` times its ``unit_noise_term``, the residuals' own term's expected value,
    in whichever combination of the parameters it is largest (unitless: the parameters' units
    cancel). For the planar cost alone at its eigenvector it is ``lambda_0 / (lambda_1 -
    lambda_0)`` with ``lambda_0 = s^2 P (N - 1)``: the planar eigen-problem's share
    (:func:`annotate_validity`), the answer's eigenvalue read as the stated noise's. ``inf``
    where ``G - E[N]`` is not positive definite (the noise's term takes all of the curvature in
    some combination); NaN where the cost gave no such terms or the noise is not stated
    (NaN)."""
    if at.gauss_newton is None or at.unit_noise_term is None or not noise_variance >= 0.0:
        return math.nan
    expected = noise_variance * at.unit_noise_term
    model = at.gauss_newton - expected
    if not (np.isfinite(model).all() and np.isfinite(expected).all()):
        return math.nan
    # The generalised eigenvalues of (E[N], G - E[N]), read from both scaled to G - E[N]'s unit
    # diagonal, where positive definiteness is judged (as _positive_definite_inverse does).
    diagonal = model.diagonal()
    if not (diagonal > 0.0).all():
        return math.inf
    scale = 1.0 / np.sqrt(diagonal)
    scaling = scale[:, None] * scale
    try:
        factor = np.linalg.cholesky(model * scaling)
    except np.linalg.LinAlgError:
        return math.inf
    share = np.linalg.solve(factor, expected * scaling)
    share = np.linalg.solve(factor, share.T)
    return float(np.linalg.eigvalsh(0.5 * (share + share.T))[-1])


def _positive_definite_inverse(hessian: np.ndarray) -> np.ndarray | None:
    """``hessian``'s inverse ``(k, k)``, or ``None`` where it is not finite or not positive
    definite."""
    if not np.isfinite(hessian).all():
        return None
    # Positive definiteness does not depend on the parameters' units; the Cholesky factor of
    # the matrix scaled to a unit diagonal tells it where an eigenvalue would be lost to them.
    diagonal = hessian.diagonal()
    if not (diagonal > 0.0).all():
        return None
    scale = 1.0 / np.sqrt(diagonal)
    try:
        np.linalg.cholesky(hessian * (scale[:, None] * scale))
    except np.linalg.LinAlgError:
        return None
    return np.linalg.inv(hessian)


def annotate_misfit(result, found: Misfit | None, why: str = ""):
    """``result`` with ``diagnostics["axis_misfit"]``, the numbers of ``found``
    (:func:`misfit`), or where nothing was measured (``None``) ``not_checked`` saying ``why``.
    Whether they leave the answer unsupported by its cost is read by
    :func:`annotate_motion_axis` (:func:`unsupported_by_its_cost`)."""
    if found is None:
        return with_warnings(result, (), {"axis_misfit": {"not_checked": why}})
    numbers = {key: float(value) for key, value in found._asdict().items()}
    return with_warnings(result, (), {"axis_misfit": numbers})


def _misfit_words(method: str, misfit: Mapping[str, float]) -> str:
    """What an answer's ``misfit`` (:func:`misfit`) says, in words, for a warning."""
    return (
        f"the markers leave the {method} cost's model of a fixed axis by more than their "
        f"rigid-body noise (its residuals' variance {misfit['ratio']:.3g} times that noise's, "
        f"p = {misfit['p_value']:.2g}: the whole cluster moves off the model, by a wobble or by "
        "a reference segment's pose noise carried into its frame; a misfit that size can tilt "
        f"its answer by {misfit['tilt_scale_deg']:.0f} deg)"
    )


def unsupported_by_its_cost(misfit: Mapping[str, float]) -> bool:
    """Whether an axis answer's ``misfit`` (``diagnostics["axis_misfit"]``, :func:`misfit`)
    says its cost cannot vouch for it: the residuals exceed the rigid-body noise at
    :data:`~jointbench.estimators.support.ROTATION_ALPHA`, by enough that a misfit of their
    size could tilt the answer beyond :data:`MAX_AXIS_SD_DEG`."""
    return misfit.get("p_value", 1.0) < ROTATION_ALPHA and (
        misfit.get("tilt_scale_deg", 0.0) > MAX_AXIS_SD_DEG
    )


def smaller_eigenvalue(matrix: np.ndarray) -> float:
    """The smaller eigenvalue of a symmetric ``(2, 2)`` ``matrix``: the smaller root of its
    characteristic polynomial, without the cost of a general eigen-solver."""
    (a, b), (_, d) = np.asarray(matrix, dtype=float).tolist()
    return 0.5 * (a + d) - math.hypot(0.5 * (a - d), b)


def distinct_frames(markers: np.ndarray) -> np.ndarray:
    """The frames of ``markers`` ``(N, P, 3)`` that differ from every other, once each
    ``(N_distinct, P, 3)``: ``markers`` itself when no two frames are equal, else the distinct
    frames in lexicographic order (module docstring). Frames are equal when every coordinate
    is, as ``np.unique`` compares them (``-0.0`` equals ``0.0``)."""
    flat = markers.reshape(len(markers), -1)
    if _rows_all_differ(kernel_array(flat)):
        return markers
    distinct = np.unique(flat, axis=0)
    return distinct.reshape(len(distinct), *markers.shape[1:])


@kernel
def _rows_all_differ(rows: np.ndarray) -> bool:
    """Whether no two of ``rows`` ``(N, K)`` are equal coordinate by coordinate (``==``). A
    compiled kernel: each row is hashed once into an open-addressed table and compared only
    with the rows of its own hash, where a sort of whole rows, or of one number per row, costs
    several times the rest of a statement of precision on a long trial. The hash is of each
    coordinate's bits with ``-0.0`` read as ``0.0``, so equal rows hash alike."""
    n_rows, width = rows.shape
    size = 2
    while size < 2 * n_rows:
        size *= 2
    table = np.full(size, -1, dtype=np.int64)
    bits = rows.view(np.uint64)
    negative_zero = np.uint64(1) << np.uint64(63)
    # A multiplier per coordinate: the products are independent, where one running product
    # would chain a multiplication's latency through every coordinate.
    factors = np.empty(width, dtype=np.uint64)
    for j in range(width):
        factors[j] = np.uint64(0x9E3779B97F4A7C15) * np.uint64(2 * j + 1)
    for r in range(n_rows):
        mixed = np.uint64(0)
        for j in range(width):
            b = bits[r, j]
            if b == negative_zero:
                b = np.uint64(0)
            mixed += b * factors[j]
        mixed ^= mixed >> np.uint64(29)
        mixed *= np.uint64(0xBF58476D1CE4E5B9)
        slot = np.int64((mixed >> np.uint64(32)) & np.uint64(size - 1))
        while table[slot] >= 0:
            other = table[slot]
            same = True
            for j in range(width):
                if not rows[r, j] == rows[other, j]:
                    same = False
                    break
            if same:
                return False
            slot = (slot + 1) & (size - 1)
        table[slot] = r
    return True


def _sd_is(sd_deg: float) -> str:
    """An axis direction's SD [deg] in a warning's words: ``"is 17.2 deg"``; beyond
    :data:`MAX_DIRECTION_OFF_DEG`, infinite or NaN without its number, which would read as a
    precision."""
    if math.isnan(sd_deg):
        return "is not a number"
    if math.isinf(sd_deg):
        return "is unbounded"
    if sd_deg > MAX_DIRECTION_OFF_DEG:
        return f"is over {MAX_DIRECTION_OFF_DEG:g} deg, more than a direction can be off"
    return f"is {sd_deg:.1f} deg"


def annotate(result, sd_deg: float, cost_name: str):
    """``result`` with ``diagnostics["axis_sd_deg"]`` = ``sd_deg`` and, above
    :data:`MAX_AXIS_SD_DEG`, a warning that ``cost_name`` ("the radial cost") does not
    determine the axis; ``converged`` is left as the method set it."""
    warnings = ()
    if stated_axis_sd(sd_deg) is None:
        why = "its direction's SD"
        if math.isinf(sd_deg):
            why = f"it does not rise in every direction from the answer, so {why}"
        warnings = (
            f"axis not determined by {cost_name}: {why} {_sd_is(sd_deg)} (above "
            f"{MAX_AXIS_SD_DEG:g} deg)",
        )
    return with_warnings(result, warnings, {"axis_sd_deg": float(sd_deg)})


def first_order_markers(reference: MotionAxis | None) -> np.ndarray | None:
    """Which markers ``(n,)`` read a frame's rotation through their arcs within
    :data:`MAX_REFERENCE_POSE_SD_DEG` (``reference.marker_arc_sd_deg``, levers read from the
    data alone; module docstring); ``None`` where the data gave no pose."""
    if reference is None:
        return None
    # NaN fails the comparison: a marker whose lever is not read reads nothing.
    return np.asarray(reference.marker_arc_sd_deg, dtype=float) <= MAX_REFERENCE_POSE_SD_DEG


def annotate_first_order(result, sd_deg: float, first_order: np.ndarray):
    """``result`` (:func:`annotate`'s) with ``diagnostics["axis_sd_deg"]`` = ``sd_deg``, the
    direction's SD [deg] that the answer's cost implies on the markers ``first_order`` ``(n,)``
    marks as reading the rotation to first order (:func:`first_order_markers`), and
    ``diagnostics["first_order_markers"]``: ``markers``, their indices, and
    ``all_markers_axis_sd_deg``, the SD stated from every marker, which counts the others'
    residuals as first order in their noise where they are not (module docstring). Above
    :data:`MAX_AXIS_SD_DEG`, and where that SD was not, a warning that the precision is not
    determined. ``converged`` is left as the method set it."""
    kept = np.flatnonzero(first_order)
    all_markers_sd_deg = result.diagnostics["axis_sd_deg"]
    warnings = ()
    if stated_axis_sd(all_markers_sd_deg) is not None and stated_axis_sd(sd_deg) is None:
        warnings = (
            f"{PRECISION_NOT_DETERMINED}: only {kept.size} of {first_order.size} markers travel "
            "far enough for the rotation the poses show to read it within "
            f"{MAX_REFERENCE_POSE_SD_DEG:g} deg a frame, and on their own the direction's SD "
            f"{_sd_is(sd_deg)} (above {MAX_AXIS_SD_DEG:g} deg): the others lie too near "
            "the axis for their residuals to be first order in their noise, so they do not "
            f"make it the {all_markers_sd_deg:.1f} deg stated from every marker",
        )
    record = {"markers": kept.tolist(), "all_markers_axis_sd_deg": float(all_markers_sd_deg)}
    return with_warnings(
        result, warnings, {"axis_sd_deg": float(sd_deg), "first_order_markers": record}
    )


def annotate_validity(
    result, noise_share: float, gap: float, problem_name: str, *, bias_deg: float | None = None
):
    """``result`` with ``diagnostics["axis_sd_noise_share"]``, the noise's share of the
    eigen-problem ``noise_share`` over its eigenvalue ``gap`` above the answer's (both in the
    matrix's unit; ``inf`` for a gap that is not positive), ``diagnostics["axis_bias_deg"]``
    where ``bias_deg`` is given (the pull [deg] of a noise that is not isotropic, which the SD
    does not include), and, where that share reaches the gap or the pull is above the SD, a
    warning that the precision is not determined: the first-order SD in
    ``diagnostics["axis_sd_deg"]`` is then not a statement of precision (module docstring).
    No such warning where the SD has already been warned about (:func:`annotate`).
    ``problem_name`` names the eigen-problem ("the planar cost's scatter"); ``converged`` is
    left as the method set it."""
    ratio = noise_share / gap if gap > 0.0 else math.inf
    sd_deg = result.diagnostics.get("axis_sd_deg", math.inf)
    diagnostics = {"axis_sd_noise_share": float(ratio)}
    if bias_deg is not None:
        diagnostics["axis_bias_deg"] = float(bias_deg)
    warnings = ()
    # NaN fails the comparisons and is warned about: it tells nothing either.
    if stated_axis_sd(sd_deg) is not None:
        if not ratio < 1.0:
            warnings = (
                f"{PRECISION_NOT_DETERMINED}: the eigen-gap of {problem_name} ({gap:.3g}) is "
                f"within the noise's own share of it ({noise_share:.3g}), so its direction's "
                f"first-order SD ({sd_deg:.1f} deg) is not a statement of precision",
            )
        elif bias_deg is not None and not bias_deg <= sd_deg:
            warnings = (
                f"{PRECISION_NOT_DETERMINED}: the noise's anisotropic share of {problem_name} "
                f"pulls the axis by up to {bias_deg:.1f} deg, more than its direction's "
                f"first-order SD ({sd_deg:.1f} deg), which does not include it",
            )
    return with_warnings(result, warnings, diagnostics)


def ambiguity(answer_squares: np.ndarray, other_squares: np.ndarray) -> tuple[float, float]:
    """How much worse another minimum fits than the answer: ``(D, se)``, ``D`` the sum of the
    differences ``d = other_squares - answer_squares`` of the two fits' squared residuals
    (any equal shapes, one entry per sample) and ``se = sqrt(n var(d))`` its standard error
    over the ``n`` samples (module docstring) [the residuals' unit squared]."""
    differences = np.ravel(other_squares) - np.ravel(answer_squares)
    return float(differences.sum()), math.sqrt(differences.size * float(differences.var()))


def annotate_ambiguity(result, other: dict, difference: float, se: float, cost_name: str):
    """``result`` with ``diagnostics["other_minimum"]`` = ``other`` (the other minimum's
    ``direction``, ``cost`` and ``angle_deg``, plus ``difference`` and ``se`` of
    :func:`ambiguity`) and, where the difference is within the noise (below
    ``_TOLD_APART_Z`` times ``se``), a warning that ``cost_name`` ("the radial cost") leaves
    the direction ambiguous; ``converged`` is left as the method set it."""
    warnings = ()
    if not difference > _TOLD_APART_Z * se:
        warnings = (
            f"{cost_name} has another minimum {other['angle_deg']:.0f} deg away whose cost "
            f"is within the noise of this one's ({other['cost']:.6g} against {result.cost:.6g}, "
            f"{difference / se if se > 0.0 else 0.0:.2f} standard errors of the difference, "
            f"not above {_TOLD_APART_Z:.2f} at {ROTATION_ALPHA:g}): the direction is ambiguous",
        )
    record = {**other, "difference": difference, "se": se}
    return with_warnings(result, warnings, {"other_minimum": record})


def line_angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    """The angle [deg] between the lines along ``a`` and ``b`` (3,), of any non-zero length:
    ``atan2(|a x b|, |a . b|)``, exact at small angles, in a few float operations where
    :func:`jointbench.geometry.angle_between_lines_deg` costs a tenth of a millisecond."""
    a_values = np.asarray(a, dtype=float).tolist()
    b_values = np.asarray(b, dtype=float).tolist()
    cross = _cross(a_values, b_values)
    dot = sum(x * y for x, y in zip(a_values, b_values, strict=True))
    return math.degrees(math.atan2(math.sqrt(float(cross @ cross)), abs(dot)))


def annotate_agreement(
    result, other_direction: np.ndarray, other_sd_deg: float, cost_name: str, other_name: str
):
    """``result`` with ``diagnostics["cross_check"]``: ``direction``, another cost's answer
    ``other_direction`` (3,) for the same axis; ``other_sd_deg``, its first-order SD [deg];
    ``angle_deg``, the angle between the two answers [deg]; and ``z``, that angle over
    ``sqrt(sd^2 + other_sd^2)`` (``sd`` the result's ``axis_sd_deg``). Where the SD is stated
    as determined (:func:`annotate`) and ``z`` is above ``_TOLD_APART_Z``, a warning that
    ``cost_name`` ("the radial cost") does not determine the direction: its answer and
    ``other_name``'s ("the planar cost's eigenvector"), two estimates of one hinge's axis, are
    further apart than their SDs allow (module docstring). ``converged`` is left as the method
    set it."""
    angle_deg = line_angle_deg(result.direction, other_direction)
    sd_deg = result.diagnostics.get("axis_sd_deg", math.inf)
    scale = math.hypot(sd_deg, other_sd_deg)
    z = angle_deg / scale if scale > 0.0 else math.inf
    warnings = ()
    # NaN fails the comparisons and is warned about: it tells nothing either.
    if stated_axis_sd(sd_deg) is not None and not z <= _TOLD_APART_Z:
        warnings = (
            f"axis not determined by {cost_name}: its answer lies {angle_deg:.0f} deg from "
            f"{other_name}, {z:.2f} times their first-order SDs combined ({sd_deg:.1f} and "
            f"{other_sd_deg:.1f} deg), above {_TOLD_APART_Z:.2f} at {ROTATION_ALPHA:g}; on a "
            "hinge both find its axis",
        )
    record = {
        "direction": np.asarray(other_direction, dtype=float).tolist(),
        "other_sd_deg": float(other_sd_deg),
        "angle_deg": angle_deg,
        "z": float(z),
    }
    return with_warnings(result, warnings, {"cross_check": record})


def _hinge_band_deg(answer_sd_deg: float) -> float:
    """The band [deg] about the principal axis of a hinge's rotations (the support verdict finds
    no rotation about a second axis) for an answer that states an SD of ``answer_sd_deg``
    [deg]: :data:`MISFIT_BAND_DEG`, or :data:`_TOLD_APART_Z` of that SD where these reach
    further, up to :data:`MOTION_AXIS_BAND_DEG`. That axis is the hinge's, so an answer that
    states a small SD and lies beyond the narrow band is not this motion's; one that states a
    large SD (a radial answer on a short arc under heavy noise) lies that far off as its own
    scatter (README: the hinge band's measured false alarms). No SD (NaN) is held to
    :data:`MISFIT_BAND_DEG`; the widest band is the one any motion's answer is held to, so a
    method stating a large SD escapes nothing it did not before."""
    if not answer_sd_deg > MISFIT_BAND_DEG / _TOLD_APART_Z:
        return MISFIT_BAND_DEG
    return min(_TOLD_APART_Z * answer_sd_deg, MOTION_AXIS_BAND_DEG)


def annotate_motion_axis(
    result,
    reference: MotionAxis | None,
    unavailable: str = "",
    off_axis_p_value: float = math.nan,
):
    """``result`` with ``diagnostics["motion_axis_check"]``: the answer compared with the
    principal axis of the segment's rotations ``reference``
    (:class:`jointbench.estimators.support.MotionAxis`, taken from the data alone by the
    support verdict; module docstring). It records ``principal_axis`` (3,),
    ``principal_axis_sd_deg``, ``principal_axis_noise_share`` and ``pose_sd_deg``, and
    ``angle_deg``, the angle between the answer and that axis [deg], and ``z``, how far the
    angle is beyond its band in the reference's SDs (``band_deg``: :data:`MOTION_AXIS_BAND_DEG`,
    or :data:`MISFIT_BAND_DEG` where the answer's cost cannot vouch for it, or where
    ``off_axis_p_value``, the support verdict's p-value of rotation about a second axis, is not
    below :data:`~jointbench.estimators.support.ROTATION_ALPHA`: a hinge, whose principal axis
    is its own, the band widened to the answer's own stated SD's reach,
    :func:`_hinge_band_deg`; NaN, not tested, keeps the wide band). Where ``z`` is above
    ``_TOLD_APART_Z``, a warning that the answer is not the motion's axis. The answer's own
    stated SD never narrows the band (the question is whether it is an axis of this motion at
    all, and a method could state any SD); it widens only a hinge's, at most to the band of
    any motion. Where the reference is not determined (its noise share not
    below 1, its SD above :data:`MAX_AXIS_SD_DEG`, a pose's SD above
    :data:`MAX_REFERENCE_POSE_SD_DEG`), or is ``None`` (the data gave no pose: ``unavailable``
    says why), nothing is compared and ``not_checked`` says why. Where a reference is given
    and the answer is finite, ``arc_rotation_sd_deg`` is the SD of a frame's rotation as the
    marker with the longest lever reads it through its arc; above
    :data:`MAX_REFERENCE_POSE_SD_DEG`, a warning that the precision is not determined (module
    docstring), unless the answer is already said to be checked by nothing. ``converged`` and
    the answer are left as the method set them."""
    if reference is None:
        why = f"no principal axis of the segment's rotations: {unavailable or 'no pose'}"
        return with_warnings(result, (), {"motion_axis_check": {"not_checked": why}})
    record = {
        "principal_axis": np.asarray(reference.direction, dtype=float).tolist(),
        "principal_axis_sd_deg": float(reference.sd_deg),
        "principal_axis_noise_share": float(reference.noise_share),
        "pose_sd_deg": float(reference.pose_sd_deg),
    }
    undetermined = "the principal axis of the segment's rotations is not determined"
    # NaN fails the comparisons and leaves the reference undetermined: it tells nothing.
    if not reference.noise_share < 1.0:
        record["not_checked"] = (
            f"{undetermined}: the noise's share of their scatter is "
            f"{reference.noise_share:.3g} of its eigen-gap (not below 1)"
        )
    elif stated_axis_sd(reference.sd_deg) is None:
        record["not_checked"] = (
            f"{undetermined}: its SD {_sd_is(reference.sd_deg)} (above {MAX_AXIS_SD_DEG:g} deg)"
        )
    elif not reference.pose_sd_deg <= MAX_REFERENCE_POSE_SD_DEG:
        record["not_checked"] = (
            f"{undetermined}: a pose's rotation SD is {reference.pose_sd_deg:.1f} deg about the "
            f"cluster's weakest axis (above {MAX_REFERENCE_POSE_SD_DEG:g} deg), where its noise "
            "is not first order"
        )
    warnings = ()
    misfit = result.diagnostics.get("axis_misfit", {})
    unsupported = unsupported_by_its_cost(misfit)
    if not np.isfinite(result.direction).all():
        record["not_checked"] = "the answer is not finite"
        # A method that says it converged on it is contradicted; a failure says so itself.
        warnings = ("the answer is not finite: no axis was found",) if result.converged else ()
    elif "not_checked" in record and unsupported:
        # Neither the answer's own cost nor the reference vouches for it.
        warnings = (
            f"axis not determined: {_misfit_words(result.method, misfit)}, and "
            f"{record['not_checked']}, so nothing checks the answer",
        )
    else:
        arc_sd_deg = float(reference.arc_rotation_sd_deg)
        record["arc_rotation_sd_deg"] = arc_sd_deg
        # NaN fails the comparison and is warned about: it tells nothing either.
        if not arc_sd_deg <= MAX_REFERENCE_POSE_SD_DEG:
            warnings = (
                f"{PRECISION_NOT_DETERMINED}: no marker travels far enough for the rotation "
                f"the poses show to read it within {MAX_REFERENCE_POSE_SD_DEG:g} deg a frame "
                f"(the one with the longest lever reads it to {arc_sd_deg:.1f} deg): they lie "
                "too near the axis for their noise to be first order, so no SD stated of an "
                "axis holds, whatever line the answer claims",
            )
    if "not_checked" in record:
        return with_warnings(result, warnings, {"motion_axis_check": record})
    # NaN fails the comparison: an untested motion may turn about a second axis.
    hinge = off_axis_p_value >= ROTATION_ALPHA and not unsupported
    answer_sd_deg = result.diagnostics.get("axis_sd_deg", math.nan)
    if unsupported:
        band = MISFIT_BAND_DEG
    elif hinge:
        band = _hinge_band_deg(answer_sd_deg)
    else:
        band = MOTION_AXIS_BAND_DEG
    angle_deg = line_angle_deg(result.direction, reference.direction)
    beyond = angle_deg - band
    z = beyond / reference.sd_deg if reference.sd_deg > 0.0 else math.copysign(math.inf, beyond)
    record.update({"angle_deg": angle_deg, "z": float(z), "band_deg": band})
    if z > _TOLD_APART_Z:
        why = ""
        if unsupported:
            why = (
                f"; {band:g} deg, not {MOTION_AXIS_BAND_DEG:g}, since "
                f"{_misfit_words(result.method, misfit)}"
            )
        elif hinge and band < MOTION_AXIS_BAND_DEG:
            why = (
                f"; {band:.3g} deg, not {MOTION_AXIS_BAND_DEG:g}, since the segment turns about "
                f"no second axis (p = {off_axis_p_value:.2g}): the principal axis of a hinge's "
                "rotations is its axis"
            )
            if band > MISFIT_BAND_DEG:
                why += (
                    f", widened to {_TOLD_APART_Z:.2f} times the answer's own SD of "
                    f"{answer_sd_deg:.2g} deg"
                )
        warnings = (
            f"axis not the motion's: the answer lies {angle_deg:.0f} deg from the principal "
            f"axis of the segment's rotations, beyond {band:.3g} deg by {z:.2f} times that "
            f"axis's SD of {reference.sd_deg:.2g} deg (above {_TOLD_APART_Z:.2f} at "
            f"{ROTATION_ALPHA:g}){why}",
        )
    return with_warnings(result, warnings, {"motion_axis_check": record})


def annotate_travel(result, reference: MotionAxis | None, cost_name: str):
    """``result`` of a cost whose model is a fixed axis the markers circle (paper B's planar,
    radial and combined costs: the radial one's point is the concentric spheres' centre) with
    ``diagnostics["axis_travel"]``, how far the segment moves along the motion axis of its
    support verdict ``reference`` as it turns (:class:`jointbench.estimators.support.Travel`):
    ``over_arc_mm`` over the arc of ``arc_deg``, ``per_10_deg_mm``, its SD ``sd_per_10_deg_mm``,
    ``dof`` and ``p_value``; and where that p-value is below
    :data:`~jointbench.estimators.support.ROTATION_ALPHA`, a warning naming it: each marker's
    arc is then a helix, which those costs fit with a plane or a centre tilted from the axis
    by many of their own SDs (``tests/test_axis_travel.py``). SARA's direction comes from the
    rotations alone, which travel leaves alone, so it is not held to this.
    Nothing is recorded where the verdict read no travel."""
    travel = None if reference is None else reference.travel
    if travel is None:
        return result
    per_10_deg = math.radians(10.0)
    p_value = travel.p_value
    record = {
        "over_arc_mm": float(travel.over_arc_mm),
        "arc_deg": math.degrees(travel.arc_rad),
        "per_10_deg_mm": travel.per_rad_mm * per_10_deg,
        "sd_per_10_deg_mm": travel.sd_mm * per_10_deg,
        "dof": float(travel.dof),
        "p_value": p_value,
    }
    warnings = ()
    # NaN (no test) fails the comparison: nothing is said of a travel that was not tested.
    if p_value < ROTATION_ALPHA:
        warnings = (
            f"axis not determined by {cost_name}: the segment travels "
            f"{travel.over_arc_mm:.2g} mm along the axis over the arc of "
            f"{record['arc_deg']:.0f} deg ({record['per_10_deg_mm']:.2g} mm per 10 deg, "
            f"p = {p_value:.2g}), which the cost's model of markers circling a fixed axis "
            "excludes: a helix's plane or centre tilts the answer",
        )
    return with_warnings(result, warnings, {"axis_travel": record})
