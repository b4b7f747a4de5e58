"""Nelder–Mead exactly as MATLAB's ``fminsearch``: the one simplex search of jointbench.

The papers minimised their costs with ``fminsearch`` at its defaults (paper A §5, paper B §3),
so IS, MA and the axis searches all use a re-implementation of its coefficients, initial simplex
and stopping rules (Lagarias et al. 1998), in two forms that take the same path: a scalar
ask/tell generator, :func:`nelder_mead_steps` (one search; the reference), and an array form,
:func:`nelder_mead_many`, which advances many independent searches (several starts, several
trials) together and evaluates all their pending points in one vectorised call.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Generator, Sequence
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

__all__ = [
    "ARRAY_FROM",
    "FATOL",
    "FMINSEARCH_OPTIONS",
    "XATOL",
    "SimplexResult",
    "SimplexRuns",
    "lockstep",
    "nelder_mead",
    "nelder_mead_many",
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


#: From this many searches on, :func:`lockstep` runs them as arrays (:func:`nelder_mead_many`);
#: below it, per-search Python steps cost less than the array bookkeeping (same paths either way).
ARRAY_FROM = 32


def lockstep(
    batch_cost: Callable[[np.ndarray, np.ndarray], np.ndarray],
    starts: Sequence[Sequence[float]] | np.ndarray,
    **options: float | int | None,
) -> list[SimplexResult]:
    """Independent :func:`nelder_mead_steps` runs from ``starts``, advanced together.

    Each round evaluates every running search's pending points with one call
    ``batch_cost(points, owners)``: ``points`` ``(k, n_params)``, ``owners`` ``(k,)`` the index
    into ``starts`` of the search each point belongs to; it returns the ``(k,)`` costs. Every
    search follows the path it would follow alone as long as ``batch_cost`` gives each point
    the cost a one-point call would. Many searches run as arrays (:func:`nelder_mead_many`; a
    search that meets a NaN cost is then run again alone), a few as Python steps.
    """
    if len(starts) < ARRAY_FROM:
        return _lockstep_steps(batch_cost, starts, range(len(starts)), **options)
    runs = nelder_mead_many(batch_cost, starts, **options)
    results = [runs.result(i) for i in range(len(runs.fun))]
    inexact = np.flatnonzero(~runs.exact).tolist()
    redone = _lockstep_steps(batch_cost, [starts[i] for i in inexact], inexact, **options)
    for i, result in zip(inexact, redone, strict=True):
        results[i] = result
    return results


def _lockstep_steps(batch_cost, starts, owners, **options) -> list[SimplexResult]:
    """:func:`lockstep` over :func:`nelder_mead_steps` generators; ``owners`` name the searches
    to ``batch_cost``."""
    owners = list(owners)
    runs = [nelder_mead_steps(x0, **options) for x0 in starts]
    pending = {i: next(run) for i, run in enumerate(runs)}
    results: list = [None] * len(runs)
    while pending:
        keys = list(pending)
        points = [x for i in keys for x in pending[i]]
        owner = [owners[i] for i in keys for _ in pending[i]]
        values = np.asarray(batch_cost(np.array(points), np.array(owner))).tolist()
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


class SimplexRuns(NamedTuple):
    """Outcomes of ``R`` searches as arrays: ``x`` ``(R, n)``, ``fun``, ``converged``,
    ``iterations``, ``evaluations`` ``(R,)``, and ``exact`` ``(R,)``: False where a search met a
    NaN cost, whose ordering the array form does not reproduce (see :func:`nelder_mead_many`)."""

    x: np.ndarray
    fun: np.ndarray
    converged: np.ndarray
    iterations: np.ndarray
    evaluations: np.ndarray
    exact: np.ndarray

    def result(self, run: int) -> SimplexResult:
        """Run ``run`` as the :class:`SimplexResult` of :func:`nelder_mead_steps`."""
        return SimplexResult(
            tuple(self.x[run].tolist()),
            float(self.fun[run]),
            bool(self.converged[run]),
            int(self.iterations[run]),
            int(self.evaluations[run]),
        )


def _tolerance(floor: float, value: np.ndarray) -> np.ndarray:
    """``max(floor, 10 ulp(value))`` element-wise, as the scalar search computes it."""
    with np.errstate(invalid="ignore"):
        ulp = np.where(np.isinf(value), np.inf, np.spacing(np.abs(value)))
    return np.fmax(floor, 10.0 * ulp)


def _insert_sorted(values: np.ndarray, new: np.ndarray) -> np.ndarray:
    """``bisect.bisect_right(values[r], new[r])`` for each row of ``values`` ``(R, m)``: the
    same binary search, so equal and unordered (NaN) costs land where the scalar search puts
    them."""
    low = np.zeros(len(new), dtype=int)
    high = np.full(len(new), values.shape[1])
    rows = np.arange(len(new))
    while np.any(low < high):
        searching = low < high
        middle = (low + high) // 2
        left = new < values[rows, np.minimum(middle, values.shape[1] - 1)]
        high = np.where(searching & left, middle, high)
        low = np.where(searching & ~left, middle + 1, low)
    return low


def nelder_mead_many(
    batch_cost: Callable[[np.ndarray, np.ndarray], np.ndarray],
    starts: np.ndarray | Sequence[Sequence[float]],
    *,
    xatol: float = XATOL,
    fatol: float = FATOL,
    max_iter: int | None = None,
    max_fev: int | None = None,
) -> SimplexRuns:
    """:func:`nelder_mead_steps` from each row of ``starts`` ``(R, n)``, as array operations.

    Every search takes the path the scalar search takes from the same start: the same
    vertices, the same order of operations in every formula, the same stable ordering and the
    same stopping rules, so ``x`` and ``fun`` are equal to the last bit when
    ``batch_cost(points, owners)`` gives each point (``points`` ``(k, n)``, ``owners`` ``(k,)``
    the row of ``starts`` it belongs to) the cost a one-point call gives. The searches advance
    together; a round evaluates the pending points of every running search in one call.
    A search that meets a NaN cost is marked ``exact=False``: Python orders NaN keys by the
    accidents of its sort, which arrays do not copy; run those alone with
    :func:`nelder_mead_steps` when the path matters.
    """
    starts = np.array(starts, dtype=float, ndmin=2)
    n_runs, n = starts.shape
    max_iter, max_fev = _limits(n, max_iter, max_fev)
    simplex = np.repeat(starts[:, None, :], n + 1, axis=1)
    for j in range(n):
        column = simplex[:, j + 1, j]
        simplex[:, j + 1, j] = np.where(column != 0.0, 1.05 * column, 0.00025)
    runs = np.arange(n_runs)
    values = np.asarray(
        batch_cost(simplex.reshape(-1, n), np.repeat(runs, n + 1)), dtype=float
    ).reshape(n_runs, n + 1)
    exact = ~np.isnan(values).any(axis=1)
    order = np.argsort(values, axis=1, kind="stable")
    simplex = np.take_along_axis(simplex, order[:, :, None], axis=1)
    values = np.take_along_axis(values, order, axis=1)
    evaluations = np.full(n_runs, n + 1)
    iterations = np.ones(n_runs, dtype=int)
    running = runs
    while True:
        running = running[(evaluations[running] < max_fev) & (iterations[running] < max_iter)]
        if running.size == 0:
            break
        vertices, costs = simplex[running], values[running]
        best, f_best = vertices[:, 0], costs[:, 0]
        with np.errstate(invalid="ignore"):
            f_spread = costs[:, n] - f_best
            x_spread = np.abs(vertices[:, 1:] - best[:, None]).max(axis=(1, 2))
            done = (f_spread <= _tolerance(fatol, f_best)) & (
                x_spread <= _tolerance(xatol, best.max(axis=1))
            )
        keep = ~done
        running, vertices, costs = running[keep], vertices[keep], costs[keep]
        if running.size == 0:
            break
        best, f_best = vertices[:, 0], costs[:, 0]
        worst, f_worst = vertices[:, n], costs[:, n]
        # sum() of the scalar search starts from 0 (so -0.0 becomes 0.0), then adds in order.
        bar = vertices[:, 0] + 0.0
        for j in range(1, n):
            bar = bar + vertices[:, j]
        bar = bar / n
        reflected = 2.0 * bar - worst
        f_reflected = np.asarray(batch_cost(reflected, running), dtype=float)
        evaluations[running] += 1
        with np.errstate(invalid="ignore"):
            expand = f_reflected < f_best
            accept = ~expand & (f_reflected < costs[:, n - 1])
            outside = ~expand & ~accept & (f_reflected < f_worst)
        inside = ~(expand | accept | outside)
        second = np.where(
            expand[:, None],
            3.0 * bar - 2.0 * worst,
            np.where(outside[:, None], 1.5 * bar - 0.5 * worst, 0.5 * bar + 0.5 * worst),
        )
        f_second = np.full(running.size, np.nan)
        probe = ~accept
        if probe.any():
            f_second[probe] = batch_cost(second[probe], running[probe])
            evaluations[running[probe]] += 1
        with np.errstate(invalid="ignore"):
            take_second = (expand & (f_second < f_reflected)) | outside | inside
            shrink = (outside & (f_second > f_reflected)) | (inside & (f_second >= f_worst))
        new = np.where(take_second[:, None], second, reflected)
        f_new = np.where(take_second, f_second, f_reflected)
        exact[running] &= ~np.isnan(f_reflected) & ~(probe & np.isnan(f_second))
        # The new vertex replaces the worst; a stable insertion puts it after equal costs.
        stay = ~shrink
        position = _insert_sorted(costs[stay, :n], f_new[stay])
        slots = np.arange(n + 1)
        before = slots[None, :] < position[:, None]
        at = slots[None, :] == position[:, None]
        shifted_v = np.concatenate([vertices[stay, :1], vertices[stay, :n]], axis=1)
        shifted_c = np.concatenate([costs[stay, :1], costs[stay, :n]], axis=1)
        vertices[stay] = np.where(
            before[:, :, None],
            vertices[stay],
            np.where(at[:, :, None], new[stay][:, None, :], shifted_v),
        )
        costs[stay] = np.where(before, costs[stay], np.where(at, f_new[stay][:, None], shifted_c))
        if shrink.any():
            shrunk = vertices[shrink]
            base = shrunk[:, :1]
            shrunk[:, 1:] = base + 0.5 * (shrunk[:, 1:] - base)
            owners = np.repeat(running[shrink], n)
            f_shrunk = np.asarray(batch_cost(shrunk[:, 1:].reshape(-1, n), owners), float)
            shrunk_costs = np.concatenate([costs[shrink, :1], f_shrunk.reshape(-1, n)], axis=1)
            evaluations[running[shrink]] += n
            exact[running[shrink]] &= ~np.isnan(f_shrunk).reshape(-1, n).any(axis=1)
            order = np.argsort(shrunk_costs, axis=1, kind="stable")
            vertices[shrink] = np.take_along_axis(shrunk, order[:, :, None], axis=1)
            costs[shrink] = np.take_along_axis(shrunk_costs, order, axis=1)
        simplex[running], values[running] = vertices, costs
        iterations[running] += 1
    converged = (evaluations < max_fev) & (iterations < max_iter)
    return SimplexRuns(simplex[:, 0], values[:, 0], converged, iterations, evaluations, exact)
