"""The study layer: seeds, conditions, dataset files, failure capture, schema checks."""

from __future__ import annotations

import logging
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pyarrow as pa
import pytest

from jointbench.configuration import config as study_config
from jointbench.configuration.seeds import trial_seed
from jointbench.estimators import registry
from jointbench.estimators.results import CenterResult
from jointbench.resultfiles.parquet import read_dataset, write_dataset
from jointbench.resultfiles.schema import check_estimates
from jointbench.running import run
from jointbench.running.collected import scored_estimates
from jointbench.running.run import estimate, simulate_condition
from jointbench.simulate import Trials

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def config():
    return study_config.load_config(ROOT / "config" / "config.yaml")


def test_seed_depends_only_on_study_condition_trial():
    a = trial_seed(1, "cmc", {"marker_set": "M", "rom_deg": 5}, 3)
    assert a == trial_seed(1, "cmc", {"rom_deg": 5, "marker_set": "M"}, 3)
    assert a != trial_seed(1, "cmc", {"marker_set": "M", "rom_deg": 5}, 4)
    assert a != trial_seed(1, "cmc", {"marker_set": "H", "rom_deg": 5}, 3)
    assert a != trial_seed(2, "cmc", {"marker_set": "M", "rom_deg": 5}, 3)


def test_condition_ids_round_trip(config):
    for study in study_config.study_names(config):
        for condition in study_config.conditions(config, study):
            identifier = study_config.condition_id(condition)
            assert study_config.parse_condition_id(config, study, identifier) == condition


def test_unknown_condition_is_a_clear_error(config):
    with pytest.raises(ValueError, match="not a condition of study 'cmc'"):
        study_config.parse_condition_id(config, "cmc", "marker_set-X__rom_deg-5__noise_mm-1.0")


def test_config_schema_rejects_bad_config(config):
    bad = {**config, "studies": {"cmc": {**config["studies"]["cmc"], "trials": 0}}}
    with pytest.raises(ValueError, match="trials"):
        study_config.validate_config(bad)
    with pytest.raises(ValueError, match="unknown_study"):
        study_config.validate_config({**config, "studies": {"unknown_study": {}}})


def test_one_trial_regenerates_alone(config):
    """Trial k is the same whether simulated among 30 or on its own."""
    condition = study_config.conditions(config, "cmc")[0]
    full = simulate_condition(config, "cmc", condition)
    small = {**config, "studies": {"cmc": {**config["studies"]["cmc"], "trials": 2}}}
    alone = simulate_condition(small, "cmc", condition)
    np.testing.assert_array_equal(full.segments["moving"][:2], alone.segments["moving"])


def test_dataset_round_trip(tmp_path):
    rng = np.random.default_rng(0)
    trials = Trials(
        segments={
            "proximal": rng.normal(size=(2, 5, 3, 3)),
            "distal": rng.normal(size=(2, 5, 4, 3)),
        },
        truth={"center": [1.0, 2.0, 3.0]},
        parameters={"note": "test"},
    )
    path = tmp_path / "d.parquet"
    write_dataset(path, trials, study="hip", condition={"n_frames": 5})
    back, metadata = read_dataset(path)
    for name, markers in trials.segments.items():
        np.testing.assert_array_equal(back.segments[name], markers)
    assert metadata["condition"] == {"n_frames": 5}
    assert back.truth == trials.truth


@pytest.fixture
def flaky_estimator():
    """A throwaway estimator that fails on odd trials (a numerical ``ValueError``) and reports
    non-convergence on the others."""
    calls = {"n": 0}

    def flaky(markers):
        calls["n"] += 1
        if calls["n"] % 2 == 0:
            raise ValueError("boom")
        return CenterResult(
            center=markers.mean(axis=(0, 1)),
            converged=False,
            iterations=7,
            status="max iterations",
            method="flaky",
        )

    registry.register("center", "flaky")(flaky)
    yield "flaky"
    registry.unregister("center", "flaky")


def test_failures_become_rows_and_the_run_goes_on(config, flaky_estimator):
    condition = study_config.conditions(config, "cmc")[0]
    small = {**config, "studies": {"cmc": {**config["studies"]["cmc"], "trials": 4}}}
    trials = simulate_condition(small, "cmc", condition)
    frame = estimate("cmc", flaky_estimator, trials, condition)
    assert len(frame) == 4
    assert not frame["converged"].any()
    assert frame["status"].str.startswith("error: ValueError: boom").sum() == 2
    assert (frame["status"] == "max iterations").sum() == 2
    assert frame.loc[frame["status"].str.startswith("error"), "error_mm"].isna().all()


class _Clock:
    """A stand-in for ``time.perf_counter`` [s] that moves only when an estimator is charged."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


COMPILE_S = 100.0  # one-time cost of an estimator's first call in a process
FIT_S = 1.0  # cost of fitting one trial


@pytest.fixture(params=[False, True], ids=["one trial at a time", "batched"])
def compiling_estimator(request, monkeypatch):
    """A throwaway estimator whose first call costs ``COMPILE_S`` besides ``FIT_S`` per trial,
    on a clock that only its calls move (so the test times nothing real)."""
    clock = _Clock()
    monkeypatch.setattr(run, "time", SimpleNamespace(perf_counter=clock))
    calls = []

    def charge(n_trials: int) -> None:
        clock.now += FIT_S * n_trials + (0.0 if calls else COMPILE_S)
        calls.append(n_trials)

    def centroid(markers):
        return CenterResult(
            center=markers.mean(axis=(0, 1)),
            converged=True,
            iterations=1,
            status="ok",
            method="compiling",
        )

    def compiling(markers):
        charge(1)
        return centroid(markers)

    def batched(markers):
        charge(len(markers))
        return [centroid(trial) for trial in markers]

    registry.register("center", "compiling", many=batched if request.param else None)(compiling)
    yield "compiling"
    registry.unregister("center", "compiling")


def test_a_first_calls_one_time_costs_are_in_no_trials_seconds(config, compiling_estimator, caplog):
    """Numba's compilation on an estimator's first call in a job is timed apart (logged), not
    charged to the first condition's trials (paper A Table 2 compares their times)."""
    caplog.set_level(logging.INFO, logger="jointbench")
    small = {**config, "studies": {"cmc": {**config["studies"]["cmc"], "trials": 3}}}
    for condition in study_config.conditions(config, "cmc")[:2]:
        trials = simulate_condition(small, "cmc", condition)
        frame = estimate("cmc", compiling_estimator, trials, condition)
        assert frame["seconds"].tolist() == [FIT_S] * 3, condition
    assert f"warm-up fit of trial 0 in {COMPILE_S + FIT_S:.3f} s" in caplog.text


def test_schema_check_names_the_column():
    frame = pd.DataFrame(
        {
            "marker_set": ["M"],
            "rom_deg": [5],
            "noise_mm": [1.0],
            "trial": [0],
            "method": ["x"],
            "center_x": [0.0],
            "center_y": [0.0],
            "center_z": [0.0],
            "error_mm": [1.0],
            "converged": [True],
            "iterations": [1],
            "seconds": [0.1],
            "status": ["ok"],
        }
    )
    keys = ("marker_set", "rom_deg", "noise_mm")
    check_estimates(frame, kind="center", condition_keys=keys)
    with pytest.raises(ValueError, match="missing column 'center_z'"):
        check_estimates(frame.drop(columns="center_z"), kind="center", condition_keys=keys)
    # The error is the benchmark's to compute: a file may leave it out, not give it as text.
    check_estimates(frame.drop(columns="error_mm"), kind="center", condition_keys=keys)
    with pytest.raises(ValueError, match="column 'error_mm' must be numeric"):
        check_estimates(frame.assign(error_mm=["small"]), kind="center", condition_keys=keys)
    with pytest.raises(ValueError, match="column 'converged' must be boolean"):
        check_estimates(frame.assign(converged=["yes"]), kind="center", condition_keys=keys)
    with pytest.raises(ValueError, match="'method' must be 'NM'"):
        check_estimates(frame, kind="center", condition_keys=keys, method="NM")


@pytest.mark.parametrize("column, value", [("seconds", -0.5), ("iterations", -3)])
def test_a_negative_time_or_iteration_count_is_refused_naming_the_trial(column, value):
    """A file cannot claim less than no time or no work: the extended ranking shows each
    method's mean time per trial beside its error."""
    row = dict(marker_set="M", rom_deg=5, noise_mm=1.0, method="NM", center_x=0.0, center_y=0.0)
    row |= dict(center_z=0.0, converged=True, iterations=0, seconds=0.0, status="ok")
    frame = pd.DataFrame([{**row, "trial": 0}, {**row, "trial": 1, column: value}])
    truth = {"center": [0.0, 0.0, 0.0]}
    unmeasured = frame.assign(seconds=np.nan, iterations=0)
    scored = scored_estimates(unmeasured, kind="center", truth=truth, source="x")
    assert (scored["error_mm"] == 0).all()
    message = f"x: trial 1: column '{column}' is {value!r}, below 0 (1 such rows)"
    with pytest.raises(ValueError, match=re.escape(message)):
        scored_estimates(frame, kind="center", truth=truth, source="x")


def test_check_estimates_reads_arrow_tables_and_names_a_column_of_mixed_values():
    keys = ("marker_set", "rom_deg", "noise_mm")
    row = dict(marker_set="M", rom_deg=5, noise_mm=1.0, trial=0, method="NM", center_x=0.0)
    row |= dict(center_y=0.0, center_z=0.0, error_mm=1.0, converged=True, iterations=1)
    row |= dict(seconds=0.1, status="ok")
    table = pa.table({name: [value] for name, value in row.items()})
    check_estimates(table, kind="center", condition_keys=keys, method="NM")
    with pytest.raises(ValueError, match="column 'iterations' must be integer, got double"):
        check_estimates(
            table.set_column(10, "iterations", pa.array([1.0])), kind="center", condition_keys=keys
        )
    mixed = pd.DataFrame([row, {**row, "status": 3}])
    with pytest.raises(ValueError, match="estimates: column 'status' mixes types"):
        check_estimates(mixed, kind="center", condition_keys=keys)
    unreadable = pd.DataFrame([{**row, "status": 1 + 2j}])
    with pytest.raises(ValueError, match="column 'status'"):
        check_estimates(unreadable, kind="center", condition_keys=keys)
    missing_trial = table.set_column(3, "trial", pa.array([None], pa.int64()))
    with pytest.raises(ValueError, match="column 'trial' has missing values"):
        check_estimates(missing_trial, kind="center", condition_keys=keys)


def test_an_estimates_file_without_a_convergence_verdict_is_refused_naming_the_trial():
    """A row whose ``converged`` is missing claims neither success nor failure; a file an
    estimator writes as parquet is held to that as an estimates CSV is."""
    keys = ("marker_set", "rom_deg", "noise_mm")
    row = dict(marker_set="M", rom_deg=5, noise_mm=1.0, method="LS-P", center_x=0.0)
    row |= dict(center_y=0.0, center_z=0.0, iterations=1, seconds=0.1, status="ok")
    frame = pd.DataFrame([{**row, "trial": 0, "converged": True}, {**row, "trial": 1}])
    message = "x: column 'converged' is empty in the row of trial 1 (1 such rows)"
    with pytest.raises(ValueError, match=re.escape(message)):
        check_estimates(frame, kind="center", condition_keys=keys, source="x")
    unanswered = frame.assign(converged=None)
    with pytest.raises(ValueError, match=re.escape(message.replace("1 (1", "0 (2"))):
        check_estimates(unanswered, kind="center", condition_keys=keys, source="x")
