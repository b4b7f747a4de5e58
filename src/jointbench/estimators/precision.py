"""How precisely an axis method's own cost determines its answer, added to a user's checked call.

A search reports the minimum of its cost; whether the data make that minimum a sharp one is a
separate question. On a short arc the radial cost of paper B can be nearly flat across tens of
degrees, and its minimum is then wherever the noise puts it, although the rotation itself is
resolved (the support verdict, :mod:`jointbench.estimators.support`, judges the data, not the
method). After the self-check the registry (:func:`jointbench.estimators.registry.get`) calls
the method's ``precision_many(results, markers)``, which writes into each result:

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

The simulated studies call the registered functions without this check, as they do without the
self-check, so their results are the papers' methods alone.
"""

from __future__ import annotations

import math
import statistics

import numpy as np

from jointbench.estimators.results import with_warnings
from jointbench.estimators.support import ROTATION_ALPHA

__all__ = [
    "AMBIGUOUS_APART_DEG",
    "MAX_AXIS_SD_DEG",
    "ambiguity",
    "annotate",
    "annotate_ambiguity",
    "direction_sd_deg",
    "distinct_frames",
    "tangent_basis",
]

#: An axis whose direction's SD is above this [deg] is "not determined" by the method's cost.
#: Paper B states its accuracy in bands of 5 and 10 degrees (claims B2, B3): an SD above the
#: looser band means the answer cannot be told within it.
MAX_AXIS_SD_DEG = 10.0

#: Two minima of an axis cost this far apart [deg] are two answers, not one answer's scatter:
#: three times the largest SD the precision check passes as determined
#: (:data:`MAX_AXIS_SD_DEG`), and below the 65-90 degrees the radial cost's second minimum lies
#: from the true axis (module docstring).
AMBIGUOUS_APART_DEG = 30.0

# The one-sided normal quantile that a cost difference must exceed, in standard errors, to be
# told from noise (module docstring).
_TOLD_APART_Z = statistics.NormalDist().inv_cdf(1.0 - ROTATION_ALPHA)


def tangent_basis(direction: np.ndarray) -> np.ndarray:
    """An orthonormal basis ``(3, 2)`` of the plane normal to the unit ``direction`` (3,)."""
    values = np.asarray(direction, dtype=float).tolist()
    # Crossed with the coordinate axis it is least aligned with, so the product is never small
    # (the first such axis, as np.argmin takes it).
    helper = [0.0, 0.0, 0.0]
    helper[min(range(3), key=lambda i: abs(values[i]))] = 1.0
    first = _cross(values, helper)
    # As np.linalg.norm takes a vector's length, without its checks.
    first /= math.sqrt(first.dot(first))
    basis = np.empty((3, 2))
    basis[:, 0] = first
    basis[:, 1] = _cross(values, first.tolist())
    return basis


def _cross(a: list[float], b: list[float]) -> np.ndarray:
    """``a x b`` ``(3,)`` of two vectors given as 3 floats, each component ``a_i b_j - a_j b_i``
    as ``np.cross`` computes it (so equal to it bit for bit), without the cost of its
    broadcasting, which was most of a checked axis call's statement of precision on a short
    trial."""
    a0, a1, a2 = a
    b0, b1, b2 = b
    return np.array((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0))


def direction_sd_deg(gradient: np.ndarray, hessian: np.ndarray, cost: float, dof: int) -> float:
    """The SD of a direction [deg] from a least-squares cost's ``gradient`` ``(k,)`` and
    ``hessian`` ``(k, k)`` at the answer, the direction's two tangent angles [rad] first, the
    other ``k - 2`` parameters (positions, in any unit) free; ``cost`` its value, ``dof`` its
    residuals less its fitted parameters (module docstring). ``inf`` when ``dof < 1`` or ``H``
    is not positive definite (the cost does not rise in every direction from the answer)."""
    # The arrays' own methods: np.all, np.diag and np.outer would cost a quarter of the rest.
    hessian, gradient = np.asarray(hessian, dtype=float), np.asarray(gradient, dtype=float)
    if dof < 1 or not np.isfinite(hessian).all() or not np.isfinite(gradient).all():
        return math.inf
    # Positive definiteness does not depend on the parameters' units; the Cholesky factor of
    # the matrix scaled to a unit diagonal tells it where an eigenvalue would be lost to them.
    diagonal = hessian.diagonal()
    if not (diagonal > 0.0).all():
        return math.inf
    scale = 1.0 / np.sqrt(diagonal)
    try:
        np.linalg.cholesky(hessian * (scale[:, None] * scale))
    except np.linalg.LinAlgError:
        return math.inf
    inverse = np.linalg.inv(hessian)
    step = -inverse @ gradient
    least = max(cost + 0.5 * float(gradient @ step), 0.0)
    covariance = 2.0 * (least / dof) * inverse
    variance = float(np.trace(covariance[:2, :2])) + float(step[:2] @ step[:2])
    return math.degrees(math.sqrt(max(variance, 0.0)))


def distinct_frames(markers: np.ndarray) -> np.ndarray:
    """The frames of ``markers`` ``(N, P, 3)`` that differ from every other, once each
    ``(N_distinct, P, 3)``: ``markers`` itself when no two frames are equal, else the distinct
    frames in lexicographic order (module docstring)."""
    flat = markers.reshape(len(markers), -1)
    # Equal frames have equal keys, so frames whose keys all differ are all distinct: the usual
    # case needs one sort of N numbers, not of N whole frames (several times the cost of the
    # rest of the statement on 5000 frames).
    keys = np.sort(flat @ np.sqrt(np.arange(2.0, 2.0 + flat.shape[1])))
    # Sorted keys all differ when no two neighbours are equal, as np.unique counts them: NaN
    # keys (an overflow), which sort last, count as one value.
    if not (keys[1:] == keys[:-1]).any() and not (len(keys) > 1 and math.isnan(keys[-2])):
        return markers
    distinct = np.unique(flat, axis=0)
    return distinct.reshape(len(distinct), *markers.shape[1:])


def annotate(result, sd_deg: float, cost_name: str):
    """``result`` with ``diagnostics["axis_sd_deg"]`` = ``sd_deg`` and, above
    :data:`MAX_AXIS_SD_DEG`, a warning that ``cost_name`` ("the radial cost") does not
    determine the axis; ``converged`` is left as the method set it."""
    warnings = ()
    if not sd_deg <= MAX_AXIS_SD_DEG:
        if math.isinf(sd_deg):
            why = "it does not rise in every direction from the answer, so its direction's SD"
            size = "is unbounded"
        else:
            why, size = "its direction's SD", f"is {sd_deg:.1f} deg"
        warnings = (
            f"axis not determined by {cost_name}: {why} {size} (above {MAX_AXIS_SD_DEG:g} deg)",
        )
    return with_warnings(result, warnings, {"axis_sd_deg": float(sd_deg)})


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
