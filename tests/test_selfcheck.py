"""The neighbour self-check shared by the simplex-based centre estimators (IS, MA)."""

from __future__ import annotations

import numpy as np

from jointbench.estimators.results import CenterResult
from jointbench.estimators.selfcheck import lowest_neighbour


def _result(center, cost: float) -> CenterResult:
    return CenterResult(
        center=np.asarray(center, float),
        radii=None,
        converged=True,
        iterations=5,
        status="ok",
        method="IS",
        cost=cost,
    )


NEIGHBOURS = {
    "the LS centre": np.array([1.0, 0.0, 0.0]),
    "the NM centre": np.array([0.0, 2.0, 0.0]),
}


def test_an_answer_no_neighbour_beats_by_more_than_tol_fun_holds_without_a_restart():
    answer = _result([0.0, 0.0, 0.0], 1.0)

    def restart(point):
        raise AssertionError("no restart expected")

    checked = lowest_neighbour(
        answer, NEIGHBOURS, np.array([1.5, 1.0 - 0.5e-4]), restart, tol_fun=1e-4, cost_name="f1"
    )
    assert checked.status == "ok" and checked.center.tolist() == [0.0, 0.0, 0.0]
    assert checked.diagnostics["self_check"].startswith("f1 at the LS centre, the NM centre")


def test_a_lower_neighbour_restarts_from_that_neighbour_and_replaces_the_answer():
    answer = _result([0.0, 0.0, 0.0], 1.0)
    starts = []

    def restart(point):
        starts.append(point.tolist())
        return _result([0.0, 3.0, 4.0], 0.25)

    checked = lowest_neighbour(
        answer, NEIGHBOURS, np.array([0.9, 0.5]), restart, tol_fun=1e-4, cost_name="f1"
    )
    assert starts == [[0.0, 2.0, 0.0]]
    assert checked.center.tolist() == [0.0, 3.0, 4.0] and checked.cost == 0.25
    assert checked.status.startswith("restarted: ") and "the NM centre" in checked.status
    assert "5 mm from the first answer" in checked.diagnostics["self_check"]
    assert checked.diagnostics["local_minimum_cost"] == 1.0
