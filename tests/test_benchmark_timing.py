"""How the estimator benchmark times its calls: every variant of a method (alone, checked,
public) is timed the same way, in the same time windows, after an untimed warm-up."""

import sys
import time
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from jointbench.estimators import support
from jointbench.numerics import compiled
from jointbench.numerics.compiled import kernel_array

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))

import check_stages
import estimators as bench


def _data(n_trials: int = 4) -> bench.DataSet:
    return bench.DataSet("center", "3 x 120", [(index,) for index in range(n_trials)])


def _recording(name: str, calls: list, *, first_call_seconds: float = 0.0):
    """A fit that records ``(name, trial)`` per call; its first call (the warm-up) sleeps."""

    def fit(trial):
        if first_call_seconds and not any(called == name for called, _ in calls):
            time.sleep(first_call_seconds)
        calls.append((name, trial))
        return SimpleNamespace(converged=True)

    return fit


def test_a_slow_warm_up_does_not_eat_the_timing_budget():
    # A first call that compiles kernels for longer than the budget must still leave the
    # variant its full number of timed calls, as every other method gets.
    calls: list = []
    fits = {"estimator": _recording("estimator", calls, first_call_seconds=0.3)}
    timed = bench.time_variants(fits, _data(), seconds=0.1, min_calls=2, max_calls=40)
    assert timed["estimator"].calls == 40


def test_variants_are_timed_in_alternating_blocks_on_the_same_trials():
    calls: list = []
    names = ("estimator", "checked", "public")
    fits = {name: _recording(name, calls) for name in names}
    timed = bench.time_variants(fits, _data(4), seconds=10.0, min_calls=2, max_calls=24)
    assert [timed[name].calls for name in names] == [24, 24, 24]
    timed_calls = calls[len(names) :]  # after one warm-up call each
    # Each variant's calls come in blocks of the data set's trials, and the blocks of all
    # variants alternate, so that a change of the machine's load falls on all of them alike.
    blocks = [timed_calls[start : start + 4] for start in range(0, len(timed_calls), 4)]
    order = [block[0][0] for block in blocks]
    assert all(len({name for name, _ in block}) == 1 for block in blocks)
    assert all([trial for _, trial in block] == [0, 1, 2, 3] for block in blocks)
    assert all(set(order[start : start + 3]) == set(names) for start in range(0, len(order), 3))
    assert order[:3] != order[3:6]  # the order rotates, so no variant always runs first


def test_a_failing_variant_is_reported_and_the_others_are_still_timed():
    calls: list = []

    def broken(trial):
        raise RuntimeError("cannot fit")

    fits = {"estimator": _recording("estimator", calls), "checked": broken}
    timed = bench.time_variants(fits, _data(), seconds=10.0, min_calls=2, max_calls=8)
    assert timed["estimator"].calls == 8
    assert timed["checked"].note == "error: RuntimeError: cannot fit"
    assert timed["checked"].seconds != timed["checked"].seconds  # NaN


def test_the_budget_bounds_a_slow_variant_but_never_below_min_calls():
    calls: list = []

    def slow(trial):
        time.sleep(0.02)
        return SimpleNamespace(converged=True)

    fits = {"estimator": _recording("estimator", calls), "slow": slow}
    timed = bench.time_variants(fits, _data(2), seconds=0.05, min_calls=3, max_calls=400)
    assert 3 <= timed["slow"].calls < 400
    assert timed["slow"].seconds == pytest.approx(0.02, rel=0.5)


def test_a_fit_that_does_not_converge_is_noted():
    def unconverged(trial):
        return SimpleNamespace(converged=False)

    timed = bench.time_variants({"estimator": unconverged}, _data(), 10.0, 2, 4)
    assert timed["estimator"].note == "some trials did not converge"


def test_batched_variants_alternate_and_a_failing_one_does_not_hide_the_other(monkeypatch):
    calls: list = []

    def many(kind, name, *, checked):
        label = "checked" if checked else "estimator"

        def batched(markers, **options):
            calls.append((label, len(markers)))
            if checked and len(markers) > 2:
                raise RuntimeError("broken checks")
            return [SimpleNamespace(converged=True)] * len(markers)

        return batched

    monkeypatch.setattr(bench.registry, "many", many)
    monkeypatch.setattr(bench, "pose_segments", lambda batched: None)
    data = bench.DataSet("center", "3 x 120", [(bench.np.zeros((4, 3, 3)),) for _ in range(3)])
    timed = bench.time_batched("center", "LS", data, n_trials=6, repeats=4)
    assert calls[:2] == [("estimator", 2), ("checked", 2)]  # untimed first calls
    assert timed["checked"][1] == "error: RuntimeError: broken checks"
    assert timed["checked"][0] != timed["checked"][0]  # NaN
    assert timed["estimator"][1] == "" and timed["estimator"][0] >= 0
    assert [label for label, size in calls[2:]] == ["estimator", "checked"] + ["estimator"] * 3
    assert "from fitted poses" not in timed


def test_batched_variants_rotate_their_order(monkeypatch):
    calls: list = []

    def many(kind, name, *, checked):
        def batched(markers, **options):
            calls.append("checked" if checked else "estimator")
            return [SimpleNamespace(converged=True)] * len(markers)

        return batched

    monkeypatch.setattr(bench.registry, "many", many)
    monkeypatch.setattr(bench, "pose_segments", lambda batched: None)
    data = bench.DataSet("center", "3 x 120", [(bench.np.zeros((4, 3, 3)),) for _ in range(3)])
    bench.time_batched("center", "LS", data, n_trials=6, repeats=4)
    rounds = [calls[start : start + 2] for start in range(2, len(calls), 2)]
    assert rounds == [["estimator", "checked"], ["checked", "estimator"]] * 2


def test_the_check_stages_table_times_every_stage_of_each_method(capsys):
    # The stages are the checks' own functions: a renamed or moved one fails here, not in a
    # benchmark run that is rarely made.
    assert check_stages.main(["--methods", "LS", "NM", "--calls", "2"]) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| ")]
    assert rows[0].split(" | ")[1:-1] == [*check_stages.STAGES, "checked / estimator"]
    for method, row in zip(["LS", "NM"], rows[1:], strict=True):
        cells = row.strip("| ").split(" | ")
        assert cells[0] == method
        assert all(float(cell.rstrip("×")) > 0.0 for cell in cells[1:])


def test_the_joint_centre_stages_table_times_every_stage_of_each_method(capsys):
    # A checked joint-centre call's stages (input checks, the shared pose fit, the fit on those
    # poses, the verdict, the model test, the answers' checks) and the public call's screen,
    # each the checks' own function: a renamed or moved one fails here.
    argv = ["--kind", "joint_center", "--methods", "SCoRE", "gauss-markov", "--calls", "2"]
    assert check_stages.main(argv) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| ")]
    header = [*check_stages.JOINT_STAGES, "checked / estimator", "public / estimator"]
    assert rows[0].strip("| ").split(" | ")[1:] == header
    for method, row in zip(["SCoRE", "gauss-markov"], rows[1:], strict=True):
        cells = row.strip("| ").split(" | ")
        assert cells[0] == method
        assert all(float(cell.rstrip("×")) > 0.0 for cell in cells[1:])


def test_the_axis_stages_table_times_every_stage_of_each_method(capsys):
    # A checked one-segment axis call's stages (input checks, the verdict and its compiled
    # passes, the self-check, the statement of precision and its compiled passes, the answers'
    # checks) and the public call's screen, each the checks' own function: a renamed or moved
    # one fails here.
    argv = ["--kind", "axis", "--methods", "planar", "combined", "--calls", "2"]
    assert check_stages.main(argv) == 0
    rows = [line for line in capsys.readouterr().out.splitlines() if line.startswith("| ")]
    header = [*check_stages.AXIS_STAGES, "checked / estimator", "public / estimator"]
    assert rows[0].strip("| ").split(" | ")[1:] == [*header, "floor / estimator"]
    for method, row in zip(["planar", "combined"], rows[1:], strict=True):
        cells = row.strip("| ").split(" | ")
        assert cells[0] == method
        assert all(float(cell.rstrip("×")) > 0.0 for cell in cells[1:])


class _TickingClock:
    """A clock that advances ``step`` seconds each time it is read."""

    def __init__(self, step: float):
        self.step, self.now, self.reads = step, 0.0, 0

    def __call__(self) -> float:
        self.reads += 1
        self.now += self.step
        return self.now


def test_each_call_is_timed_by_the_clock_given(monkeypatch):
    # --clock cpu reads the process's CPU time: every timing, one trial and many, must come from
    # the clock handed in, not from a wall clock read beside it.
    clock = _TickingClock(0.25)
    fits = {name: _recording(name, []) for name in ("estimator", "checked")}
    timed = bench.time_variants(fits, _data(), seconds=10.0, min_calls=2, max_calls=4, clock=clock)
    assert {variant.seconds for variant in timed.values()} == {0.25}
    assert clock.reads == 2 * 2 * 4

    def many(kind, name, *, checked):
        return lambda markers, **options: [SimpleNamespace(converged=True)] * len(markers)

    monkeypatch.setattr(bench.registry, "many", many)
    monkeypatch.setattr(bench, "pose_segments", lambda batched: None)
    data = bench.DataSet("center", "3 x 120", [(bench.np.zeros((4, 3, 3)),) for _ in range(3)])
    batched = bench.time_batched("center", "LS", data, n_trials=5, repeats=3, clock=clock)
    assert {seconds for seconds, _ in batched.values()} == {0.25 / 5}


def test_the_clocks_are_functions_of_time_the_baseline_worker_can_read_by_name():
    assert bench.CLOCKS["wall"] == "perf_counter"
    for name in bench.CLOCKS.values():
        assert callable(getattr(time, name))


def test_the_check_stages_are_timed_by_the_clock_given():
    # --clock cpu reads the process's CPU time, which other processes' load does not lengthen:
    # every stage's time must come from the clock handed in, not from a wall clock beside it.
    clock = _TickingClock(0.25)
    calls = {"estimator": lambda i: None, "checked": lambda i: None}
    median = check_stages.time_stages(calls, n_trials=4, rounds=3, clock=clock)
    assert median == {"estimator": 0.25 / 4, "checked": 0.25 / 4}
    assert clock.reads == 2 * 2 * 3


def test_the_check_stages_clocks_are_the_estimator_benchmarks(capsys):
    assert check_stages.CLOCKS is bench.CLOCKS
    assert check_stages.main(["--methods", "LS", "--calls", "2", "--clock", "cpu"]) == 0
    assert "process CPU" in capsys.readouterr().out
    with pytest.raises(SystemExit):
        check_stages.main(["--methods", "LS", "--calls", "2", "--clock", "sundial"])


def test_the_verdict_kernels_stage_makes_the_verdicts_compiled_calls(monkeypatch):
    # The floor adds the verdict's compiled work alone: a kernel call the verdict does not
    # make (the lag-1 numbers, which its one-segment call now gives) would raise the floor.
    (trial,) = bench.center_data(np.random.default_rng(0), 1).trials[0]
    stacked = kernel_array(trial[None])
    called: list[str] = []
    call = compiled._Kernel.__call__
    monkeypatch.setattr(
        compiled._Kernel,
        "__call__",
        lambda self, *a: called.append(self.__name__) or call(self, *a),
    )
    support.assess_many("center", (stacked,))
    verdicts = called.copy()
    called.clear()
    check_stages._verdict_kernels(stacked)
    assert called == verdicts == ["_one_segment_numbers"]
