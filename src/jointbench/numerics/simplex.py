"""Nelder–Mead exactly as MATLAB's ``fminsearch``: the one simplex search of jointbench.

The papers minimised their costs with ``fminsearch`` at its defaults (paper A §5, paper B §3),
so IS, MA and the axis searches all use a re-implementation of its coefficients, initial simplex
and stopping rules (Lagarias et al. 1998). There is one implementation, over a leading axis of
independent searches (several starts, several trials): :func:`lockstep` advances them together
and evaluates the pending points of all of them in one call of the cost; :func:`nelder_mead` is
that search on a batch of one. The bookkeeping of the simplices is a compiled kernel
(:mod:`jointbench.numerics.compiled`), so a single search pays no per-operation array overhead
and many searches no per-search Python loop; the cost stays a Python callable over a batch of
points. A cost that is itself a compiled kernel can drive the same searches from compiled code
(:func:`started`, :func:`advance`), without a round trip to Python per round: the searches
then take the paths :func:`lockstep` gives them with that cost.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from types import MappingProxyType
from typing import NamedTuple

import numpy as np

from jointbench.numerics.compiled import kernel, kernel_array

__all__ = [
    "FATOL",
    "FMINSEARCH_OPTIONS",
    "XATOL",
    "SimplexResult",
    "advance",
    "lockstep",
    "nelder_mead",
    "started",
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


def _limits(n: int, max_iter: int | None, max_fev: int | None) -> tuple[int, int]:
    return (200 * n if max_iter is None else int(max_iter)), (
        200 * n if max_fev is None else int(max_fev)
    )


def nelder_mead(
    cost: Callable[..., float], x0: Sequence[float], **options: float | int | None
) -> SimplexResult:
    """Minimise ``cost(*x)`` from ``x0`` as ``fminsearch`` does: :func:`lockstep` on a batch of
    one search."""
    (result,) = lockstep(
        lambda points, _owners: [cost(*x) for x in points.tolist()], [x0], **options
    )
    return result


def lockstep(
    batch_cost: Callable[[np.ndarray, np.ndarray], np.ndarray],
    starts: Sequence[Sequence[float]] | np.ndarray,
    *,
    xatol: float = XATOL,
    fatol: float = FATOL,
    max_iter: int | None = None,
    max_fev: int | None = None,
) -> list[SimplexResult]:
    """Nelder–Mead exactly as MATLAB's ``fminsearch`` from each row of ``starts`` ``(R, n)``,
    the ``R`` searches advanced together.

    Each round evaluates the pending points of every running search with one call
    ``batch_cost(points, owners)``: ``points`` ``(k, n)``, ``owners`` ``(k,)`` the row of
    ``starts`` each point belongs to, grouped by search in row order; it returns the ``(k,)``
    costs. A search's path depends on the costs of its own points only, so it is the path it
    takes alone as long as ``batch_cost`` gives each point the cost a one-point call gives.

    Algorithm (Lagarias et al. 1998, as in ``fminsearch``): reflection 1, expansion 2,
    contraction 1/2, shrink 1/2. Initial simplex: the start and, for each coordinate, the start
    with that coordinate scaled by 1.05 (set to 0.00025 if it is zero). Vertices are kept sorted
    by cost, ties in their previous order; a new vertex goes after the costs equal to its own.
    Stops when both the largest cost difference to the best vertex is
    ``<= max(fatol, 10 eps(f_best))`` and the largest coordinate difference is
    ``<= max(xatol, 10 eps(max(x_best)))`` (converged), or when ``max_iter`` iterations or
    ``max_fev`` evaluations (default ``200 * n`` each) are used up (not converged). As in
    ``fminsearch``, the limits are checked between iterations: an iteration that has started
    finishes, so a shrink may take the evaluations past ``max_fev``. NaN costs are ordered as
    Python's ``sorted`` and ``bisect`` order them (see :func:`advance`).

    Raises ``ValueError`` when ``batch_cost`` returns other than one cost per point.
    """
    searches = started(starts, xatol=xatol, fatol=fatol, max_iter=max_iter, max_fev=max_fev)
    count = searches.advance(np.empty(0))
    while count:
        points, owners = searches.points[:count].copy(), searches.owners[:count].copy()
        costs = kernel_array(np.asarray(batch_cost(points, owners), dtype=float))
        if costs.shape != (count,):
            raise ValueError(
                f"the simplex cost returned an array of shape {costs.shape} for {count} points; "
                f"expected ({count},)"
            )
        count = searches.advance(costs)
    return searches.results()


def started(
    starts: Sequence[Sequence[float]] | np.ndarray,
    *,
    xatol: float = XATOL,
    fatol: float = FATOL,
    max_iter: int | None = None,
    max_fev: int | None = None,
) -> _Searches:
    """The searches of :func:`lockstep` from each row of ``starts`` ``(R, n)``, not yet
    advanced: for a compiled cost, a kernel drives them with :func:`advance` as
    :func:`lockstep` does from Python, and :meth:`_Searches.results` reads their outcome."""
    starts = np.array(starts, dtype=float, ndmin=2)
    return _Searches.create(starts, _limits(starts.shape[1], max_iter, max_fev), (xatol, fatol))


def stop_status(result: SimplexResult, max_fev: int) -> str:
    """``"ok"`` for a converged search, else which of the limits it reached."""
    if result.converged:
        return "ok"
    if result.evaluations >= max_fev:
        return "Maximum number of function evaluations has been exceeded."
    return "Maximum number of iterations has been exceeded."


# What the costs a search is sent next belong to (its phase in :func:`advance`).
_START, _VERTICES, _REFLECTED, _EXPANDED, _OUTSIDE, _INSIDE, _SHRUNK, _DONE = range(8)


class _Searches(NamedTuple):
    """The state of ``R`` searches over ``n`` parameters, as the arrays :func:`advance` updates:
    ``phase`` ``(R,)``; ``simplex`` ``(R, n + 1, n)`` and ``values`` ``(R, n + 1)``, sorted by
    cost; ``moves`` ``(R, 3, n)``: centroid of the best ``n`` vertices, reflected point, probe
    (expansion or contraction); ``f_reflected`` ``(R,)``; ``counts`` ``(R, 2)``: iterations,
    evaluations; ``limits`` ``(2,)``: ``max_iter``, ``max_fev``; ``tolerances`` ``(2,)``:
    ``xatol``, ``fatol``; the points asked for, ``points`` ``(R (n + 1), n)`` and their
    ``owners``."""

    phase: np.ndarray
    simplex: np.ndarray
    values: np.ndarray
    moves: np.ndarray
    f_reflected: np.ndarray
    counts: np.ndarray
    limits: np.ndarray
    tolerances: np.ndarray
    points: np.ndarray
    owners: np.ndarray

    @classmethod
    def create(
        cls, starts: np.ndarray, limits: tuple[int, int], tolerances: tuple[float, float]
    ) -> _Searches:
        """Searches not yet started from ``starts`` ``(R, n)``."""
        n_runs, n = starts.shape
        return cls(
            phase=np.full(n_runs, _START, dtype=np.int64),
            simplex=np.repeat(starts[:, None, :], n + 1, axis=1),
            values=np.zeros((n_runs, n + 1)),
            moves=np.zeros((n_runs, 3, n)),
            f_reflected=np.zeros(n_runs),
            counts=np.zeros((n_runs, 2), dtype=np.int64),
            limits=np.array(limits, dtype=np.int64),
            tolerances=np.array(tolerances, dtype=float),
            points=np.zeros((n_runs * (n + 1), n)),
            owners=np.zeros(n_runs * (n + 1), dtype=np.int64),
        )

    def advance(self, costs: np.ndarray) -> int:
        """Send every running search the ``costs`` of the points it asked for last; returns the
        number of points asked for now (0 when all have stopped)."""
        return advance(*self, costs)

    def results(self) -> list[SimplexResult]:
        """Every search's :class:`SimplexResult`."""
        iterations, evaluations = self.counts.T
        converged = (evaluations < self.limits[1]) & (iterations < self.limits[0])
        return [
            SimplexResult(tuple(x), fun, ok, i, e)
            for x, fun, ok, i, e in zip(
                self.simplex[:, 0].tolist(),
                self.values[:, 0].tolist(),
                converged.tolist(),
                iterations.tolist(),
                evaluations.tolist(),
                strict=True,
            )
        ]


@kernel
def advance(
    phase: np.ndarray,
    simplex: np.ndarray,
    values: np.ndarray,
    moves: np.ndarray,
    f_reflected: np.ndarray,
    counts: np.ndarray,
    limits: np.ndarray,
    tolerances: np.ndarray,
    points: np.ndarray,
    owners: np.ndarray,
    costs: np.ndarray,
) -> int:
    """One round of every running search (arrays of :class:`_Searches`): each takes the
    ``costs`` ``(k,)`` of the points it asked for last (in ``owners`` order), moves on, and
    writes the points it needs next into ``points``, ``owners``; returns their number. A
    compiled kernel (:mod:`jointbench.numerics.compiled`).

    Every formula keeps the order of operations of the plain-float search it replaced, and
    orders costs as Python does, NaN included: sorting as ``list.sort`` does a short list
    (CPython 3.11: the natural run from the start, reversed if strictly descending, then binary
    insertion) and inserting a new vertex as ``bisect.bisect_right``; maxima as ``max()``
    takes them (the first, replaced only by a strictly greater one).
    """
    n_runs, m, n = simplex.shape
    max_iter, max_fev = limits[0], limits[1]
    xatol, fatol = tolerances[0], tolerances[1]
    order = np.empty(m, dtype=np.int64)
    keys = np.empty(m)
    vertex = np.empty(n)
    read = 0
    asked = 0
    for r in range(n_runs):
        state = phase[r]
        if state == _DONE:
            continue
        if state == _START:
            for j in range(n):
                y = simplex[r, j + 1, j]
                simplex[r, j + 1, j] = 1.05 * y if y != 0.0 else 0.00025
            for i in range(m):
                points[asked] = simplex[r, i]
                owners[asked] = r
                asked += 1
            phase[r] = _VERTICES
            continue
        # The iteration ends by sorting the simplex (``sort``) or by the vertex
        # ``moves[r, slot]`` of cost ``f_new`` replacing the worst (``slot`` 1 or 2).
        sort = False
        slot = -1
        f_new = 0.0
        if state == _VERTICES or state == _SHRUNK:
            first = 0 if state == _VERTICES else 1
            for i in range(first, m):
                values[r, i] = costs[read]
                read += 1
            counts[r, 1] += m - first
            if state == _VERTICES:
                counts[r, 0] = 0
            sort = True
        elif state == _REFLECTED:
            fr = costs[read]
            read += 1
            counts[r, 1] += 1
            f_reflected[r] = fr
            if fr < values[r, 0]:
                phase[r] = _EXPANDED
            elif fr < values[r, n - 1]:
                slot, f_new = 1, fr
            elif fr < values[r, n]:
                phase[r] = _OUTSIDE
            else:
                phase[r] = _INSIDE
            if slot < 0:
                for j in range(n):
                    b, w = moves[r, 0, j], simplex[r, n, j]
                    if phase[r] == _EXPANDED:
                        moves[r, 2, j] = 3.0 * b - 2.0 * w
                    elif phase[r] == _OUTSIDE:
                        moves[r, 2, j] = 1.5 * b - 0.5 * w
                    else:
                        moves[r, 2, j] = 0.5 * b + 0.5 * w
                points[asked] = moves[r, 2]
                owners[asked] = r
                asked += 1
                continue
        else:
            f_probe = costs[read]
            read += 1
            counts[r, 1] += 1
            fr = f_reflected[r]
            if state == _EXPANDED:
                slot, f_new = (2, f_probe) if f_probe < fr else (1, fr)
            elif (state == _OUTSIDE and not f_probe > fr) or (
                state == _INSIDE and not f_probe >= values[r, n]
            ):
                slot, f_new = 2, f_probe
            else:
                for i in range(1, m):
                    for j in range(n):
                        b = simplex[r, 0, j]
                        simplex[r, i, j] = b + 0.5 * (simplex[r, i, j] - b)
                    points[asked] = simplex[r, i]
                    owners[asked] = r
                    asked += 1
                phase[r] = _SHRUNK
                continue
        if sort:
            for i in range(m):
                order[i] = i
                keys[i] = values[r, i]
            run = 2 if m > 1 else 1
            if m > 1 and keys[1] < keys[0]:
                while run < m and keys[run] < keys[run - 1]:
                    run += 1
                for i in range(run // 2):
                    keys[i], keys[run - 1 - i] = keys[run - 1 - i], keys[i]
                    order[i], order[run - 1 - i] = order[run - 1 - i], order[i]
            else:
                while run < m and not keys[run] < keys[run - 1]:
                    run += 1
            for start in range(run, m):
                pivot, index = keys[start], order[start]
                low, high = 0, start
                while low < high:
                    middle = low + ((high - low) >> 1)
                    if pivot < keys[middle]:
                        high = middle
                    else:
                        low = middle + 1
                for i in range(start, low, -1):
                    keys[i], order[i] = keys[i - 1], order[i - 1]
                keys[low], order[low] = pivot, index
            shuffled = simplex[r].copy()
            for i in range(m):
                values[r, i] = keys[i]
                simplex[r, i] = shuffled[order[i]]
        else:
            vertex[:] = moves[r, slot]
            low, high = 0, n
            while low < high:
                middle = (low + high) // 2
                if f_new < values[r, middle]:
                    high = middle
                else:
                    low = middle + 1
            for i in range(n, low, -1):
                values[r, i] = values[r, i - 1]
                simplex[r, i] = simplex[r, i - 1]
            values[r, low] = f_new
            simplex[r, low] = vertex
        counts[r, 0] += 1
        # The next iteration, if the limits and the tolerances leave one.
        if not (counts[r, 1] < max_fev and counts[r, 0] < max_iter):
            phase[r] = _DONE
            continue
        f_best = values[r, 0]
        f_spread = values[r, n] - f_best
        x_spread = abs(simplex[r, 1, 0] - simplex[r, 0, 0])
        x_top = simplex[r, 0, 0]
        for i in range(1, m):
            for j in range(n):
                d = abs(simplex[r, i, j] - simplex[r, 0, j])
                if d > x_spread:
                    x_spread = d
        for j in range(1, n):
            if simplex[r, 0, j] > x_top:
                x_top = simplex[r, 0, j]
        f_tolerance, x_tolerance = fatol, xatol
        for k in range(2):
            # math.ulp of f_best (k = 0) and of the best vertex's largest coordinate (k = 1).
            size = abs(f_best if k == 0 else x_top)
            if math.isnan(size) or math.isinf(size):
                ulp = size
            elif size == 0.0:
                ulp = math.ldexp(1.0, -1074)
            else:
                ulp = math.ldexp(1.0, max(math.frexp(size)[1] - 53, -1074))
            if k == 0 and 10.0 * ulp > f_tolerance:
                f_tolerance = 10.0 * ulp
            if k == 1 and 10.0 * ulp > x_tolerance:
                x_tolerance = 10.0 * ulp
        if f_spread <= f_tolerance and x_spread <= x_tolerance:
            phase[r] = _DONE
            continue
        # sum() of plain floats starts from 0 (so -0.0 becomes 0.0), then adds in order.
        for j in range(n):
            total = 0.0
            for i in range(n):
                total += simplex[r, i, j]
            moves[r, 0, j] = total / n
            moves[r, 1, j] = 2.0 * moves[r, 0, j] - simplex[r, n, j]
        points[asked] = moves[r, 1]
        owners[asked] = r
        asked += 1
        phase[r] = _REFLECTED
    return asked
