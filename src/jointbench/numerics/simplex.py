"""Nelder–Mead exactly as MATLAB's ``fminsearch``: the one simplex search of jointbench.

The papers minimised their costs with ``fminsearch`` at its defaults (paper A §5, paper B §3),
so IS, MA and the axis searches all use :func:`nelder_mead_steps`, a re-implementation of its
coefficients, initial simplex and stopping rules (Lagarias et al. 1998). The search is written
as an ask/tell generator so that :func:`lockstep` can advance many independent searches (several
starts, several trials) together and evaluate all their pending points in one vectorised call.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Generator, Sequence
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

__all__ = [
    "FATOL",
    "FMINSEARCH_OPTIONS",
    "XATOL",
    "SimplexResult",
    "lockstep",
    "nelder_mead",
    "nelder_mead_steps",
    "stop_status",
]

# fminsearch defaults (MATLAB): TolX = TolFun = 1e-4, MaxIter = MaxFunEvals = 200 * n_params.
XATOL = 1e-4
FATOL = 1e-4

#: The defaults for the three unknowns of a centre of rotation (IS, MA).
FMINSEARCH_OPTIONS = MappingProxyType(
    {"xatol": XATOL, "fatol": FATOL, "max_iter": 600, "max_fev": 600}
)

Point = tuple[float, ...]


class SimplexResult(NamedTuple):
    """Outcome of one search: best vertex, its cost, whether the tolerances were met before
    either limit, and the iterations and cost evaluations used."""

    x: Point
    fun: float
    converged: bool
    iterations: int
    evaluations: int


NelderMeadSteps = Generator[list[Point], list[float], SimplexResult]


def _limits(n: int, max_iter: int | None, max_fev: int | None) -> tuple[int, int]:
    return (200 * n if max_iter is None else int(max_iter)), (
        200 * n if max_fev is None else int(max_fev)
    )


def nelder_mead_steps(
    x0: Sequence[float],
    *,
    xatol: float = XATOL,
    fatol: float = FATOL,
    max_iter: int | None = None,
    max_fev: int | None = None,
) -> NelderMeadSteps:
    """Nelder–Mead exactly as MATLAB's ``fminsearch``, as an ask/tell generator.

    The generator yields the list of points it needs evaluated and is sent back their costs;
    it returns (``StopIteration.value``) a :class:`SimplexResult`. Written over plain floats:
    the simplex is tiny and numpy's per-call overhead would dominate.

    Algorithm (Lagarias et al. 1998, as in ``fminsearch``): reflection 1, expansion 2,
    contraction 1/2, shrink 1/2. Initial simplex: ``x0`` and, for each coordinate, ``x0`` with
    that coordinate scaled by 1.05 (set to 0.00025 if it is zero). Vertices are kept sorted by
    cost (stable sort). Stops when both the largest cost difference to the best vertex is
    ``<= max(fatol, 10 eps(f_best))`` and the largest coordinate difference is
    ``<= max(xatol, 10 eps(max(x_best)))`` (converged), or when ``max_iter`` iterations or
    ``max_fev`` evaluations (default ``200 * len(x0)`` each) are used up (not converged). As in
    ``fminsearch``, the limits are checked between iterations: an iteration that has started
    finishes, so a shrink may take the evaluations past ``max_fev``.
    """
    start = [float(c) for c in x0]
    n = len(start)
    max_iter, max_fev = _limits(n, max_iter, max_fev)
    simplex = [tuple(start)]
    for j in range(n):
        y = list(start)
        y[j] = 1.05 * y[j] if y[j] != 0.0 else 0.00025
        simplex.append(tuple(y))
    values = list((yield simplex))
    order = sorted(range(n + 1), key=values.__getitem__)
    simplex = [simplex[i] for i in order]
    values = [values[i] for i in order]
    evaluations = n + 1
    iterations = 1
    while evaluations < max_fev and iterations < max_iter:
        best, f_best = simplex[0], values[0]
        # Sorted ascending, so the largest |f_best - f_j| is the last minus the first.
        f_spread = values[n] - f_best
        x_spread = max(abs(a - b) for x in simplex[1:] for a, b in zip(x, best, strict=True))
        if f_spread <= max(fatol, 10.0 * math.ulp(f_best)) and x_spread <= max(
            xatol, 10.0 * math.ulp(max(best))
        ):
            break
        worst, f_worst = simplex[n], values[n]
        bar = [sum(c) / n for c in zip(*simplex[:n], strict=True)]
        xr = tuple(2.0 * b - w for b, w in zip(bar, worst, strict=True))
        (fr,) = yield [xr]
        evaluations += 1
        shrink = False
        if fr < f_best:
            xe = tuple(3.0 * b - 2.0 * w for b, w in zip(bar, worst, strict=True))
            (fe,) = yield [xe]
            evaluations += 1
            new, f_new = (xe, fe) if fe < fr else (xr, fr)
        elif fr < values[n - 1]:
            new, f_new = xr, fr
        elif fr < f_worst:
            new = tuple(1.5 * b - 0.5 * w for b, w in zip(bar, worst, strict=True))
            (f_new,) = yield [new]
            evaluations += 1
            shrink = f_new > fr
        else:
            new = tuple(0.5 * b + 0.5 * w for b, w in zip(bar, worst, strict=True))
            (f_new,) = yield [new]
            evaluations += 1
            shrink = f_new >= f_worst
        if shrink:
            simplex = [best] + [
                tuple(b + 0.5 * (c - b) for b, c in zip(best, x, strict=True)) for x in simplex[1:]
            ]
            values = [f_best, *(yield simplex[1:])]
            evaluations += n
            order = sorted(range(n + 1), key=values.__getitem__)
            simplex = [simplex[i] for i in order]
            values = [values[i] for i in order]
        else:
            # The new vertex replaces the worst; a stable sort puts it after equal costs.
            del simplex[n], values[n]
            position = bisect.bisect_right(values, f_new)
            simplex.insert(position, new)
            values.insert(position, f_new)
        iterations += 1
    converged = evaluations < max_fev and iterations < max_iter
    return SimplexResult(simplex[0], values[0], converged, iterations, evaluations)


def nelder_mead(
    cost: Callable[..., float], x0: Sequence[float], **options: float | int | None
) -> SimplexResult:
    """Minimise ``cost(*x)`` from ``x0`` as ``fminsearch`` does (see :func:`nelder_mead_steps`)."""
    steps = nelder_mead_steps(x0, **options)
    points = next(steps)
    while True:
        try:
            points = steps.send([cost(*x) for x in points])
        except StopIteration as stop:
            return stop.value


def lockstep(
    batch_cost: Callable[[np.ndarray, np.ndarray], np.ndarray],
    starts: Sequence[Sequence[float]],
    **options: float | int | None,
) -> list[SimplexResult]:
    """Independent :func:`nelder_mead_steps` runs from ``starts``, advanced together.

    Each round gathers every running search's pending points and evaluates them with one call
    ``batch_cost(points, owners)``: ``points`` ``(k, n_params)``, ``owners`` ``(k,)`` the index
    into ``starts`` of the search each point belongs to; it returns the ``(k,)`` costs. Every
    search follows the path it would follow alone as long as ``batch_cost`` gives each point
    the cost a one-point call would.
    """
    runs = [nelder_mead_steps(x0, **options) for x0 in starts]
    pending = {i: next(run) for i, run in enumerate(runs)}
    results: list = [None] * len(runs)
    while pending:
        keys = list(pending)
        points = [x for i in keys for x in pending[i]]
        owners = [i for i in keys for _ in pending[i]]
        values = batch_cost(np.array(points), np.array(owners)).tolist()
        position = 0
        for i in keys:
            count = len(pending[i])
            try:
                pending[i] = runs[i].send(values[position : position + count])
            except StopIteration as stop:
                results[i] = stop.value
                del pending[i]
            position += count
    return results


def stop_status(result: SimplexResult, max_fev: int) -> str:
    """``"ok"`` for a converged search, else which of the limits it reached."""
    if result.converged:
        return "ok"
    if result.evaluations >= max_fev:
        return "Maximum number of function evaluations has been exceeded."
    return "Maximum number of iterations has been exceeded."
