"""Per-trial diagnostics that need the ground truth, by (study, method).

Each function takes the estimator's arguments for all trials of a condition (each segment
``(n_trials, ...)``), the results (``None`` where the estimator returned none) and the truth,
and returns extra columns for each trial's row (an empty mapping where there was no result).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from jointbench.estimators.registry import many
from jointbench.estimators.sphere import FMINSEARCH_OPTIONS, geometric_cost

__all__ = ["DIAGNOSTICS", "is_local_minimum"]

# Two searches found the same minimum when their f1 differ by less than this margin: fminsearch
# stops once the simplex's f1 values agree to TolFun (absolute, mm^2), so final values of one
# minimum can differ by a few TolFun; ten times TolFun, or 1e-6 relative for large f1.
_SAME_MINIMUM_ATOL = 10.0 * FMINSEARCH_OPTIONS["fatol"]
_SAME_MINIMUM_RTOL = 1e-6


def is_local_minimum(arguments, results: Sequence, truth: Mapping) -> list[dict[str, object]]:
    """Claim A7 (paper A §5.1.1), made operational: IS "returned a local minimum" when IS
    restarted from the true centre reaches a lower geometric cost f1 than IS from the LS centre.

    Columns: ``local_minimum`` (bool) and ``f1_gap`` = f1(IS from LS) − f1(IS from truth) [mm²].
    The restarts of all trials run as one batch (the same searches as one at a time).
    """
    (markers,) = arguments
    restarts = many("center", "IS", checked=False)(
        markers, start=np.asarray(truth["center"], dtype=float)
    )
    rows: list[dict[str, object]] = []
    for data, result, from_truth in zip(markers, results, restarts, strict=True):
        if result is None:
            rows.append({})
            continue
        if isinstance(from_truth, Exception):
            raise from_truth
        own = geometric_cost(data, result.center)
        best = geometric_cost(data, from_truth.center)
        rows.append(
            {
                "local_minimum": bool(
                    own - best > max(_SAME_MINIMUM_ATOL, _SAME_MINIMUM_RTOL * best)
                ),
                "f1_gap": float(own - best),
            }
        )
    return rows


DIAGNOSTICS: dict[tuple[str, str], Callable] = {("cmc", "IS"): is_local_minimum}
