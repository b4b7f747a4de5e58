"""The self-checks of the search-based estimators: the shared neighbour check (IS, MA) and
what each method's check costs."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from test_selfcheck_sweep import near_hinge_trial, sphere_trial

from jointbench.estimators import axis, registry, sphere
from jointbench.estimators.results import CenterResult, with_fields
from jointbench.estimators.selfcheck import failed, held, lowest_neighbour, restarted
from jointbench.numerics import poses


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


# What each check pays for, counted: the checks are cheap by construction, not by timing.


def _calls(monkeypatch, module, name: str) -> list:
    """The calls of ``module.name`` from now on, counted in the returned list."""
    calls, original = [], getattr(module, name)

    def counted(*args, **kwargs):
        calls.append(name)
        return original(*args, **kwargs)

    monkeypatch.setattr(module, name, counted)
    return calls


@pytest.mark.parametrize("method", ["planar", "radial", "combined"])
def test_the_axis_restart_skips_the_public_costs_checks(method, monkeypatch):
    """Every evaluation of the single restart would pay the public costs' argument checks."""
    markers = near_hinge_trial(0)
    fit = registry.get("axis", method, checked=False)
    result = fit(markers)
    for name in ("planar", "radial", "_radial"):
        monkeypatch.setattr(axis.AxisCosts, name, _refused)
    assert fit.self_check(result, markers).status == "ok"


def _refused(*args, **kwargs):
    raise AssertionError("the self-check's restart went through a public cost")


def test_the_planar_check_makes_no_radial_arrays():
    markers = near_hinge_trial(0)
    result = registry.get("axis", "planar", checked=False)(markers)
    costs = axis.AxisCosts(markers, np.asarray(result.point))
    costs.search_cost("planar", "angles")(np.zeros((2, 2)), np.zeros(2, dtype=np.intp))
    assert "_w" not in vars(costs)


def test_the_bc_check_is_one_compiled_pass(monkeypatch):
    markers = sphere_trial(1)
    fit = registry.get("center", "BC", checked=False)
    result = fit(markers)
    for name in ("ls_system", "solve_ls_system"):
        monkeypatch.setattr(sphere, name, _refused, raising=False)
    passes = _calls(monkeypatch, sphere, "_bc_steps")
    assert "self_check" in fit.self_check(result, markers).diagnostics
    assert passes == ["_bc_steps"]


def test_the_ma_check_fits_the_poses_once(monkeypatch):
    markers = sphere_trial(1)
    fit = registry.get("center", "MA", checked=False)
    result = fit(markers)
    fits = _calls(monkeypatch, poses, "fit_rigid_poses")
    fit.self_check(result, markers)
    assert len(fits) == 1


@pytest.mark.parametrize(
    ("kind", "method"),
    [
        ("center", "BC"),
        ("center", "MA"),
        ("axis", "planar"),
        ("axis", "radial"),
        ("axis", "combined"),
    ],
)
def test_a_many_trial_self_check_restarts_all_trials_in_one_search(kind, method, monkeypatch):
    """``self_check_many`` judges all trials in one pass; a raised cost forces every axis and
    MA trial to restart, and the restarts are searched together."""
    trials = [(sphere_trial if kind == "center" else near_hinge_trial)(seed) for seed in range(3)]
    fit = registry.get(kind, method, checked=False)
    results = [dataclasses.replace(fit(m), cost=fit(m).cost + 1.0) for m in trials]
    # The planar restarts are searched in one compiled call, the others through lockstep.
    searches = _calls(monkeypatch, axis, "_planar_restarts" if method == "planar" else "lockstep")
    checked = fit.self_check_many(results, np.stack(trials))
    searched_together = len(searches) == 1
    one_by_one = [fit.self_check(r, m) for r, m in zip(results, trials, strict=True)]
    assert [c.status for c in checked] == [c.status for c in one_by_one]
    if kind == "axis":
        assert searched_together
        assert all(c.status.startswith("restarted: ") for c in checked)


def test_the_outcome_is_written_without_building_the_result_again(monkeypatch):
    """Held, restarted and failed change status and diagnostics only: the arrays are kept as
    they are, not frozen again."""
    answer = _result([0.0, 0.0, 0.0], 1.0)
    built = _calls(monkeypatch, CenterResult, "__post_init__")
    outcomes = [held(answer, "x"), failed(answer, "y"), restarted(answer, answer, "z", "0 mm")]
    assert built == []
    assert [o.center is answer.center for o in outcomes] == [True] * 3
    assert outcomes[1].converged is False and outcomes[1].status == "self-check failed: y"
    assert held(answer, "x") == dataclasses.replace(
        answer, diagnostics={**answer.diagnostics, "self_check": "x"}
    )


def test_an_outcome_for_a_field_the_result_lacks_is_refused():
    with pytest.raises(ValueError, match="CenterResult has no field 'colour'"):
        with_fields(_result([0.0, 0.0, 0.0], 1.0), colour="red")
