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
  centre: ``g' F^-1 g / s^2`` is chi-square with 3 degrees of freedom there (Rao's score test),
  and ``|F_s^-1 g|`` (``center_step_mm``) estimates how far the answer is from it.

A warning is added when the data cannot support the answer this way: the SD above
:data:`MAX_CENTER_SD_MM`, or not a statement of precision (both only where the support
verdict has not already refused the data), or the score test rejecting at
:data:`jointbench.estimators.support.ROTATION_ALPHA` with the common centre more than
:data:`MIN_REJECTED_STEP_MM` away (a method's own documented bias of a few millimetres is a
property of the method, not a failure to find the centre). The noise ``s^2`` is the support
verdict's rigid-body residual, which does not depend on the answer.
Frames repeated exactly carry no new noise and are counted once
(:func:`jointbench.estimators.precision.distinct_frames`). ``converged`` and the answer are
left as the method set them; the simulated studies call the methods without this check.
"""

from __future__ import annotations

import math

import numpy as np

from jointbench.estimators.precision import distinct_frames
from jointbench.estimators.results import with_warnings
from jointbench.estimators.support import ROTATION_ALPHA, Support
from jointbench.numerics.compiled import kernel, kernel_array
from jointbench.numerics.small import symmetric_eigen_into

__all__ = [
    "MAX_CENTER_SD_MM",
    "MAX_SD_NOISE_SHARE",
    "MIN_REJECTED_STEP_MM",
    "annotate_many",
    "centre_statistics",
]

#: A centre whose SD along its least determined direction is above this [mm] is "not
#: determined" by the data: paper A's errors on its hardest conditions are of this order, so
#: an answer this uncertain cannot be told from a failed one.
MAX_CENTER_SD_MM = 10.0

#: Where the directions' noise is this share or more of their spread along the least
#: determined direction, the first-order SD is not a statement of precision: the variance it
#: leaves out grows as ``1 + share`` (module docstring), so at this share the SD understates the
#: scatter by a tenth, and beyond it the answers' errors grow heavy tails
#: (``tests/test_centre_precision.py`` counts them on both sides).
MAX_SD_NOISE_SHARE = 0.2

#: The score test's rejection is reported only when the spheres' common centre is at least this
#: far [mm] from the answer: half of :data:`MAX_CENTER_SD_MM`, well above the few millimetres
#: of bias paper A documents for its methods on small caps.
MIN_REJECTED_STEP_MM = 5.0

# A marker within this many noise SDs of the answer (a virtual marker at the joint, say) has a
# direction from it that is noise, and is left out.
_NEAR_SDS = 3.0

# Columns of centre_statistics' rows.
_SD, _CHI2, _STEP, _REPEATS, _SHARE = 0, 1, 2, 3, 4


@kernel
def centre_statistics(
    markers: np.ndarray, centres: np.ndarray, variances: np.ndarray
) -> np.ndarray:
    """Per trial ``(SD [mm], score chi-square, step [mm], repeats)`` ``(T, 4)`` of the answers
    ``centres`` ``(T, 3)`` [mm] to the markers ``(T, N, n, 3)`` [mm], with noise
    ``variances`` ``(T,)`` [mm^2] per coordinate (module docstring); ``inf`` SD and step where
    the corrected information is not positive definite. ``repeats`` is 1 where two frames of
    the trial may be equal (their numbers then count that frame twice), else 0. One pass over
    the samples per marker: ``F_p = sum u u' - N m m'`` and ``g_p = sum d u - N r m`` with
    ``m`` the mean direction and ``r`` the mean distance. A compiled kernel."""
    n_trials, n_frames, n_markers, _ = markers.shape
    out = np.empty((n_trials, 5))
    noisy = np.empty((3, 3))
    info = np.empty((3, 3))
    signal = np.empty((3, 3))
    score = np.empty(3)
    sum_u, sum_du, sum_uu = np.empty(3), np.empty(3), np.empty((3, 3))
    values, vectors, work = np.empty(3), np.empty((3, 3)), np.empty((3, 3))
    keys = np.empty(n_frames)
    for t in range(n_trials):
        info[:] = 0.0
        signal[:] = 0.0
        noisy[:] = 0.0
        score[:] = 0.0
        keys[:] = 0.0
        s2 = variances[t]
        for p in range(n_markers):
            sum_u[:] = 0.0
            sum_du[:] = 0.0
            sum_uu[:] = 0.0
            sum_d = 0.0
            wx, wy, wz = (
                math.sqrt(3.0 * p + 2.0),
                math.sqrt(3.0 * p + 3.0),
                math.sqrt(3.0 * p + 4.0),
            )
            for k in range(n_frames):
                x = markers[t, k, p, 0] - centres[t, 0]
                y = markers[t, k, p, 1] - centres[t, 1]
                z = markers[t, k, p, 2] - centres[t, 2]
                # Equal frames have equal keys (weights that no two coordinates share).
                keys[k] += wx * x + wy * y + wz * z
                d = math.sqrt(x * x + y * y + z * z)
                inverse = 1.0 / d if d > 0.0 else 0.0
                u0, u1, u2 = x * inverse, y * inverse, z * inverse
                sum_d += d
                sum_u[0] += u0
                sum_u[1] += u1
                sum_u[2] += u2
                sum_du[0] += x
                sum_du[1] += y
                sum_du[2] += z
                sum_uu[0, 0] += u0 * u0
                sum_uu[0, 1] += u0 * u1
                sum_uu[0, 2] += u0 * u2
                sum_uu[1, 1] += u1 * u1
                sum_uu[1, 2] += u1 * u2
                sum_uu[2, 2] += u2 * u2
            radius = sum_d / n_frames
            if not radius * radius > _NEAR_SDS**2 * s2:
                continue  # its direction from the answer is noise: no information on it
            norm2 = 0.0
            for i in range(3):
                score[i] += sum_du[i] - radius * sum_u[i]
                norm2 += sum_u[i] ** 2
            # The tangential noise of the directions, about the marker's mean direction.
            noise = (n_frames - 1) * s2 / radius**2
            for i in range(3):
                for j in range(i, 3):
                    moment = sum_uu[i, j] - sum_u[i] * sum_u[j] / n_frames
                    tangential = (1.0 if i == j else 0.0) - sum_u[i] * sum_u[j] / norm2
                    info[i, j] += moment
                    signal[i, j] += moment - noise * tangential
                    noisy[i, j] += noise * tangential
        keys.sort()
        out[t, _REPEATS] = 0.0
        for k in range(n_frames - 1):
            if not keys[k + 1] != keys[k]:
                out[t, _REPEATS] = 1.0
        out[t, _CHI2] = _quadratic_inverse(info, score, values, vectors, work) / s2
        symmetric_eigen_into(signal, values, vectors, work)
        if not values[0] > 1e-12 * abs(values[2]):
            out[t, _SD] = np.inf
            out[t, _STEP] = np.inf
            out[t, _SHARE] = np.inf
            continue
        share = 0.0
        for i in range(3):
            for j in range(3):
                share += vectors[i, 0] * _upper(noisy, i, j) * vectors[j, 0]
        out[t, _SHARE] = share / values[0]
        out[t, _SD] = math.sqrt(s2 / values[0])
        step2 = 0.0
        for i in range(3):
            along = 0.0
            for j in range(3):
                along += vectors[j, i] * score[j]
            step2 += (along / values[i]) ** 2
        out[t, _STEP] = math.sqrt(step2)
    return out


@kernel
def _upper(matrix: np.ndarray, i: int, j: int) -> float:
    """Entry ``(i, j)`` of the symmetric ``matrix`` of which only the upper triangle is
    written. A compiled kernel."""
    return matrix[i, j] if i <= j else matrix[j, i]


@kernel
def _quadratic_inverse(
    matrix: np.ndarray, vector: np.ndarray, values: np.ndarray, vectors: np.ndarray, work
) -> float:
    """``v' M^-1 v`` of the symmetric ``matrix`` ``M`` ``(3, 3)`` and ``vector`` ``v`` ``(3,)``,
    ``inf`` where ``M`` is singular to rounding, with ``values``, ``vectors``, ``work`` as
    scratch. A compiled kernel."""
    symmetric_eigen_into(matrix, values, vectors, work)
    if not values[0] > 1e-12 * abs(values[2]):
        return np.inf
    total = 0.0
    for i in range(3):
        along = 0.0
        for j in range(3):
            along += vectors[j, i] * vector[j]
        total += along * along / values[i]
    return total


def _chi2_3_sf(x: float) -> float:
    """The upper tail of the chi-square distribution with 3 degrees of freedom at ``x``, in
    closed form (a SciPy call costs more than the rest of the check)."""
    if not x >= 0.0:
        return math.nan
    if math.isinf(x):
        return 0.0
    return math.erfc(math.sqrt(x / 2.0)) + math.sqrt(2.0 * x / math.pi) * math.exp(-x / 2.0)


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
    step, p = numbers["center_step_mm"], numbers["center_score_p_value"]
    warnings = []
    if supported and not sd <= MAX_CENTER_SD_MM:
        size = "is unbounded" if math.isinf(sd) else f"is {sd:.3g} mm"
        warnings.append(
            f"centre not determined by the data: its SD along the least determined direction "
            f"{size} (above {MAX_CENTER_SD_MM:g} mm, from the rigid-body residual of "
            f"{residual_mm:.3g} mm)"
        )
    elif supported and not share < MAX_SD_NOISE_SHARE:
        warnings.append(
            f"centre's precision not determined by the data: along its least determined "
            f"direction the noise is {100 * share:.0f}% of the spread of the markers' "
            f"directions from it (below {100 * MAX_SD_NOISE_SHARE:g}% its SD of {sd:.3g} mm "
            "would hold)"
        )
    if p < ROTATION_ALPHA and step > MIN_REJECTED_STEP_MM and math.isfinite(step):
        warnings.append(
            f"the answer is not the markers' common centre of rotation: the spheres they move "
            f"on are centred {step:.3g} mm from it (score test chi^2 = "
            f"{numbers['center_score_chi2']:.3g}, p = {p:.2g})"
        )
    return tuple(warnings)


def annotate_many(results: list, markers: np.ndarray, verdicts: list[Support]) -> list:
    """``results`` of the trials of ``markers`` ``(T, N, n, 3)`` [mm] (centre results, in the
    reference frame) with their precision and score test (module docstring), given each
    trial's support verdict ``verdicts``: ``diagnostics["center_sd_mm"]``,
    ``["center_sd_noise_share"]``, ``["center_score_chi2"]``, ``["center_score_p_value"]``,
    ``["center_step_mm"]`` and warnings. A result without a finite centre, or whose data the
    verdict did not assess (no rigid-body residual), is returned with
    ``["center_precision_not_checked"]`` saying why."""
    annotated = list(results)
    checked, centres, residuals = [], [], []
    for t, (result, verdict) in enumerate(zip(results, verdicts, strict=True)):
        centre = result.center.tolist()
        reason = None
        if not verdict.diagnostics.get("assessed", False):
            reason = "the support verdict did not assess the data (no rigid-body residual)"
        elif not all(map(math.isfinite, centre)):
            reason = "the answer is not finite"
        if reason is not None:
            annotated[t] = with_warnings(result, (), {"center_precision_not_checked": reason})
            continue
        checked.append(t)
        centres.append(centre)
        residuals.append(verdict.diagnostics["rigid_residual_mm"])
    if not checked:
        return annotated
    if len(checked) < len(results):
        markers = markers[checked]
    variances = np.array(residuals) ** 2 / 3.0
    rows = _statistics(markers, np.array(centres), variances)
    for t, residual_mm, (sd, chi2, step, _, share) in zip(checked, residuals, rows, strict=True):
        numbers = {
            "center_sd_mm": sd,
            "center_sd_noise_share": share,
            "center_score_chi2": chi2,
            "center_score_p_value": _chi2_3_sf(chi2),
            "center_step_mm": step,
        }
        warnings = _warnings(numbers, residual_mm, not verdicts[t].warnings)
        annotated[t] = with_warnings(results[t], warnings, numbers)
    return annotated
