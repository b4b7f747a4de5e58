"""Per-trial diagnostics that need the ground truth, by (study, method).

Each function takes the estimator's arguments, its result and the truth, and returns extra
columns for that trial's row. They run only where the estimator returned a result.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from jointbench.estimators.sphere import FMINSEARCH_OPTIONS, fit_is, geometric_cost

__all__ = ["DIAGNOSTICS", "is_local_minimum"]

# Two searches found the same minimum when their f1 differ by less than this margin: fminsearch
# stops once the simplex's f1 values agree to TolFun (absolute, mm^2), so final values of one
# minimum can differ by a few TolFun; ten times TolFun, or 1e-6 relative for large f1.
_SAME_MINIMUM_ATOL = 10.0 * FMINSEARCH_OPTIONS["fatol"]
_SAME_MINIMUM_RTOL = 1e-6


def is_local_minimum(arguments, result, truth: Mapping) -> dict[str, object]:
    """Claim A7 (paper A §5.1.1), made operational: IS "returned a local minimum" when IS
    restarted from the true centre reaches a lower geometric cost f1 than IS from the LS centre.

    Columns: ``local_minimum`` (bool) and ``f1_gap`` = f1(IS from LS) − f1(IS from truth) [mm²].
    """
    (markers,) = arguments
    from_truth = fit_is(markers, start=np.asarray(truth["center"], dtype=float))
    own = geometric_cost(markers, result.center)
    best = geometric_cost(markers, from_truth.center)
    return {
        "local_minimum": bool(own - best > max(_SAME_MINIMUM_ATOL, _SAME_MINIMUM_RTOL * best)),
        "f1_gap": float(own - best),
    }


DIAGNOSTICS: dict[tuple[str, str], Callable] = {("cmc", "IS"): is_local_minimum}
