"""Inputs that cannot lie: estimator failures, estimates files checked against their datasets,
corrupt intermediate files named."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from jointbench.estimators import registry
from jointbench.study import config as study_config
from jointbench.study.run import estimate, simulate_condition

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def config():
    small = study_config.load_config(ROOT / "config" / "config.yaml")
    small["studies"]["cmc"]["trials"] = 2
    return small


@pytest.fixture(scope="module")
def cmc_trials(config):
    condition = study_config.conditions(config, "cmc")[0]
    return condition, simulate_condition(config, "cmc", condition)


@pytest.fixture
def raising_estimator():
    """Register a centre estimator raising the given exception; yields a setter of it."""
    raised = {}

    def fails(markers):
        raise raised["error"]

    registry.register("center", "raises")(fails)
    yield lambda error: raised.__setitem__("error", error) or "raises"
    del registry._REGISTRY["center"]["raises"]


@pytest.mark.parametrize(
    "error",
    [
        ValueError("markers do not move"),
        np.linalg.LinAlgError("Singular matrix"),
        FloatingPointError("overflow encountered"),
    ],
    ids=lambda e: type(e).__name__,
)
def test_numerical_failure_becomes_a_failed_row(cmc_trials, raising_estimator, error):
    condition, trials = cmc_trials
    frame = estimate("cmc", raising_estimator(error), trials, condition)
    assert len(frame) == 2 and not frame["converged"].any()
    assert frame["status"].str.startswith(f"error: {type(error).__name__}: ").all()
    assert frame["error_mm"].isna().all()


@pytest.mark.parametrize(
    "error",
    [TypeError("fits() got an unexpected keyword argument"), KeyError("x"), AttributeError("y")],
    ids=lambda e: type(e).__name__,
)
def test_programming_error_stops_the_run(cmc_trials, raising_estimator, error):
    condition, trials = cmc_trials
    with pytest.raises(type(error)):
        estimate("cmc", raising_estimator(error), trials, condition)


def test_an_option_the_estimator_does_not_take_stops_the_run(cmc_trials):
    condition, trials = cmc_trials
    with pytest.raises(TypeError, match="tolerance"):
        estimate("cmc", "NM", trials, condition, {"tolerance": 1e-3})
