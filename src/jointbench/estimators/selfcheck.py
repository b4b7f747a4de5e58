"""Evidence that a search found the minimum it reports, added to a user's checked call.

A search-based estimator (a simplex from fixed starts, a fixed-point iteration) can stop where
its own cost is not least and still meet its stopping test. After such a fit the registry
(:func:`jointbench.estimators.registry.get`) calls the method's ``self_check``: each method
compares its cost with its cost at a few closed-form neighbours or with a restart from one,
which costs less than the fit itself. The outcome is written into the result:

* the answer holds: ``status`` is left as it is, ``diagnostics["self_check"]`` says what was
  compared;
* a neighbour or restart reached a cost lower by more than the search's own function
  tolerance: the search had stopped in a local minimum. The lower point, searched to the same
  tolerances, is returned, with ``status`` starting ``"restarted: "`` and naming both costs,
  so that a user never reads "ok" about a point that was not the least found;
* where the answer and the other minimum seen (the restart's, or the answer it replaced) are
  far apart and the data cannot tell their fits apart, a warning that the answer is ambiguous
  (the axis methods, :func:`jointbench.estimators.precision.annotate_ambiguity`);
* a check that fails without a better point to offer (a fixed point that is not one) sets
  ``converged=False`` and says so in ``status``.

A method whose check can judge many trials at once also gives its fit a
``self_check_many(results, markers, **options)``: the answers of the trials of ``markers``
``(T, N, P, 3)`` judged together (neighbours and updates of all trials in one pass, the axis
methods' restarts in one :func:`jointbench.numerics.simplex.lockstep`), each trial's outcome
the one ``self_check`` gives it alone.

The simulated studies call the registered functions without these checks (as the papers ran
their searches), so the published comparisons keep the papers' behaviour, local minima
included.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from jointbench.estimators.results import with_fields

__all__ = ["failed", "held", "lowest_neighbour", "restarted"]


def lowest_neighbour(
    result,
    neighbours: Mapping[str, np.ndarray],
    costs: np.ndarray,
    restart: Callable[[np.ndarray], object],
    *,
    tol_fun: float,
    cost_name: str,
    unit: str = "",
):
    """A search's answer judged against its cost at closed-form neighbouring points.

    ``neighbours`` maps a description ("the LS centre") to a point ``(3,)`` [mm], ``costs``
    ``(len(neighbours),)`` are the method's cost there. When none is below ``result.cost`` by
    more than ``tol_fun`` (the search's own function tolerance) the answer holds (:func:`held`);
    otherwise ``restart(point)`` searches again from the lowest one, and its answer replaces
    ``result`` (:func:`restarted`). ``cost_name`` and ``unit`` word the evidence.
    """
    names = list(neighbours)
    best = int(np.argmin(costs))
    if not costs[best] < result.cost - tol_fun:
        return held(
            result,
            f"{cost_name} at {', '.join(names)} is not below the answer's {result.cost:.6g}"
            f"{unit} by more than TolFun (least {float(costs[best]):.6g}{unit})",
        )
    better = restart(neighbours[names[best]])
    moved = float(np.linalg.norm(np.asarray(better.center) - np.asarray(result.center)))
    return restarted(
        result, better, names[best], f"{moved:.3g} mm from the first answer, which is replaced"
    )


def held(result, evidence: str):
    """``result`` with the evidence that its minimum held in ``diagnostics["self_check"]``."""
    return with_fields(result, diagnostics={**result.diagnostics, "self_check": evidence})


def restarted(result, better, source: str, moved: str):
    """``better`` (the lower minimum, reached from ``source``) in place of ``result``, its
    status saying so; ``moved`` describes how far the answer moved."""
    evidence = (
        f"the search stopped in a local minimum (cost {result.cost:.6g}); a restart from "
        f"{source} reached {better.cost:.6g}, {moved}"
    )
    status = f"restarted: {evidence}"
    if better.status != "ok":
        status = f"{status}; {better.status}"
    diagnostics = {
        **better.diagnostics,
        "self_check": evidence,
        "local_minimum_cost": result.cost,
    }
    return with_fields(better, status=status, diagnostics=diagnostics)


def failed(result, evidence: str):
    """``result`` marked as not converged because its self-check failed (``evidence``)."""
    status = f"self-check failed: {evidence}"
    if result.status != "ok":
        status = f"{result.status}; {status}"
    diagnostics = {**result.diagnostics, "self_check": evidence}
    return with_fields(result, converged=False, status=status, diagnostics=diagnostics)
