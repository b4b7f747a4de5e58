"""The one simplex search against the plain-float search it replaced, frozen below as the reference.

``lockstep`` (many searches advanced together) and ``nelder_mead`` (a batch of one) must take the
reference's path to the last bit: the same best vertex and cost, iterations, evaluations and
convergence flag, on smooth costs, plateaus (ties, where the stable ordering decides the path),
walls of infinite cost, NaN costs (ordered as Python's ``sorted`` and ``bisect`` order them) and
at both limits.
"""

from __future__ import annotations

import bisect
import math

import numpy as np
import pytest

from jointbench.numerics import simplex


def _reference_steps(x0, *, xatol=1e-4, fatol=1e-4, max_iter=None, max_fev=None):
    """The ask/tell generator that was jointbench's one-search Nelder–Mead, kept unchanged as the
    specification: yields the points it needs, is sent their costs, returns the result tuple."""
    start = [float(c) for c in x0]
    n = len(start)
    max_iter = 200 * n if max_iter is None else int(max_iter)
    max_fev = 200 * n if max_fev is None else int(max_fev)
    points = [tuple(start)]
    for j in range(n):
        y = list(start)
        y[j] = 1.05 * y[j] if y[j] != 0.0 else 0.00025
        points.append(tuple(y))
    values = list((yield points))
    order = sorted(range(n + 1), key=values.__getitem__)
    points = [points[i] for i in order]
    values = [values[i] for i in order]
    evaluations = n + 1
    iterations = 1
    while evaluations < max_fev and iterations < max_iter:
        best, f_best = points[0], values[0]
        f_spread = values[n] - f_best
        x_spread = max(abs(a - b) for x in points[1:] for a, b in zip(x, best, strict=True))
        if f_spread <= max(fatol, 10.0 * math.ulp(f_best)) and x_spread <= max(
            xatol, 10.0 * math.ulp(max(best))
        ):
            break
        worst, f_worst = points[n], values[n]
        bar = [sum(c) / n for c in zip(*points[:n], strict=True)]
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
            points = [best] + [
                tuple(b + 0.5 * (c - b) for b, c in zip(best, x, strict=True)) for x in points[1:]
            ]
            values = [f_best, *(yield points[1:])]
            evaluations += n
            order = sorted(range(n + 1), key=values.__getitem__)
            points = [points[i] for i in order]
            values = [values[i] for i in order]
        else:
            del points[n], values[n]
            position = bisect.bisect_right(values, f_new)
            points.insert(position, new)
            values.insert(position, f_new)
        iterations += 1
    converged = evaluations < max_fev and iterations < max_iter
    return points[0], values[0], converged, iterations, evaluations


def _reference(cost, x0, **options):
    """The reference search from ``x0`` alone, ``cost`` taking rows ``(k, n)``."""
    steps = _reference_steps(x0, **options)
    points = next(steps)
    while True:
        try:
            points = steps.send(cost(np.array(points)).tolist())
        except StopIteration as stop:
            return stop.value


def _rosenbrock_rows(points: np.ndarray) -> np.ndarray:
    a, b, c = points[:, 0], points[:, 1], points[:, 2]
    return (1 - a) ** 2 + 100 * (b - a * a) ** 2 + (c - 0.5) ** 2


COSTS = {
    "smooth": _rosenbrock_rows,
    "plateaus": lambda p: np.floor(2.0 * np.abs(p).sum(axis=1)),
    "wall": lambda p: np.where(p[:, 0] > 1.5, np.inf, _rosenbrock_rows(p)),
    "nan": lambda p: np.where(p[:, 0] < -0.3, np.nan, _rosenbrock_rows(p)),
    # NaN among tied costs: Python's sort and bisect order them by the accidents of their
    # comparisons, which the search must copy.
    "nan plateaus": lambda p: np.where(
        p[:, 1] > 0.8, np.nan, np.floor(3.0 * np.abs(p).sum(axis=1))
    ),
}
LIMITS = {
    "defaults": {},
    "max_iter": {"max_iter": 7},
    "max_fev": {"max_fev": 20},
    "tight": {"xatol": 1e-9, "fatol": 1e-9},
}


def _starts(n_searches: int) -> np.ndarray:
    starts = np.random.default_rng(7).normal(size=(n_searches, 3))
    starts[0] = 0.0  # the 0.00025 initial step
    starts[1] = -0.0
    starts[2, 1] = 0.0
    return starts


def _same(result: simplex.SimplexResult, reference: tuple) -> bool:
    """Equal to the last bit, NaN and the sign of zero included (``repr`` of a float round-trips
    exactly)."""
    return repr(tuple(result)) == repr(tuple(reference))


@pytest.mark.parametrize("limits", list(LIMITS.values()), ids=list(LIMITS))
@pytest.mark.parametrize("name", list(COSTS))
def test_searches_together_take_the_reference_path_to_the_last_bit(name, limits):
    cost = COSTS[name]
    starts = _starts(64)
    together = simplex.lockstep(lambda points, _owners: cost(points), starts, **limits)
    mismatched = [
        i
        for i, (x0, result) in enumerate(zip(starts, together, strict=True))
        if not _same(result, _reference(cost, x0, **limits))
    ]
    assert mismatched == []


@pytest.mark.parametrize("name", list(COSTS))
def test_one_search_takes_the_reference_path_to_the_last_bit(name):
    cost = COSTS[name]
    for x0 in _starts(12):
        alone = simplex.nelder_mead(lambda *x: float(cost(np.array([x]))[0]), x0)
        assert _same(alone, _reference(cost, x0))


def test_every_point_is_evaluated_once_also_when_costs_are_nan():
    """One path for every search: none is run a second time, NaN costs or not."""
    cost = COSTS["nan"]
    evaluated = []

    def counted(points, _owners):
        evaluated.append(len(points))
        return cost(points)

    results = simplex.lockstep(counted, _starts(64))
    assert sum(evaluated) == sum(result.evaluations for result in results)


def test_a_cost_that_does_not_return_one_value_per_point_is_refused():
    with pytest.raises(ValueError, match=r"shape \(1,\) for 4 points"):
        simplex.lockstep(lambda points, _owners: np.zeros(1), [(1.0, 2.0, 3.0)])


def test_the_compiled_bookkeeping_runs_its_python_source(monkeypatch):
    """The kernel's Python source is its specification: run as written, it takes the same
    paths."""
    cost = COSTS["nan plateaus"]
    starts = _starts(6)
    compiled = simplex.lockstep(lambda points, _owners: cost(points), starts)
    monkeypatch.setattr(simplex, "advance", simplex.advance.__wrapped__)
    as_written = simplex.lockstep(lambda points, _owners: cost(points), starts)
    assert repr(as_written) == repr(compiled)
