"""A bug in an estimator stops the job; only a trial's data defeating the fit make a failed row.

An estimate job records a trial whose fit raises a numerical failure (a ``ValueError`` the
method raises about the data, a ``LinAlgError``, a ``FloatingPointError``) as a failed row and
goes on. A ``ValueError`` that Python or NumPy raise inside an expression (arrays that do not
broadcast, an unpacking of the wrong length, a reshape to the wrong size) is a mistake in the
method's code, like a ``TypeError``: recorded as a failed trial, it would be ranked as the
method's weakness on those data.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest
from test_bootstrap import hip_trial

from jointbench.configuration.config import load_config
from jointbench.estimators import batching, registry, sphere
from jointbench.estimators.batching import ProgrammingError
from jointbench.estimators.results import CenterResult
from jointbench.io import prepare
from jointbench.running import run

CONFIG = Path(__file__).resolve().parents[1] / "config" / "config.yaml"
CONDITION = {"marker_set": "M", "rom_deg": 5, "noise_mm": 2.0}
NAME = "mistaken"


@functools.cache
def _trials():
    config = load_config(CONFIG)
    config["studies"]["cmc"]["trials"] = 3
    return run.simulate_condition(config, "cmc", CONDITION)


def _broadcast(markers):
    return markers[0, :2] + markers[0, :3]


def _unpack(markers):
    first, second = markers.shape
    return first + second


def _reshape(markers):
    return markers.reshape(7, -1)


def _type(markers):
    return markers + "mm"


def _stated(markers):
    raise ValueError("the markers span no sphere")


def _singular(markers):
    return np.linalg.inv(np.zeros((3, 3)))


def _overflow(markers):
    with np.errstate(over="raise"):
        return np.float64(1e308) * 10.0


BUGS = {"broadcast": _broadcast, "unpack": _unpack, "reshape": _reshape, "type": _type}
FAILURES = {"stated": _stated, "singular": _singular, "overflow": _overflow}


def _register(body):
    def mistaken(markers: np.ndarray) -> CenterResult:
        body(markers)
        return sphere.fit_ls(markers)

    registry.register("center", NAME, min_frames=4)(mistaken)


@pytest.fixture
def registered():
    yield _register
    registry.unregister("center", NAME)


@pytest.mark.parametrize("bug", sorted(BUGS))
def test_a_bug_in_a_newcomer_stops_the_job_naming_it(registered, bug):
    registered(BUGS[bug])
    with pytest.raises((ProgrammingError, TypeError)) as raised:
        run.estimate("cmc", NAME, _trials(), CONDITION)
    if bug != "type":
        message = str(raised.value)
        assert "programming error" in message, message
        assert NAME in message and "cmc" in message, message
        assert Path(__file__).name in message, message  # where the code went wrong


@pytest.mark.parametrize("failure", sorted(FAILURES))
def test_a_trial_the_data_defeat_is_a_failed_row(registered, failure):
    registered(FAILURES[failure])
    table = run.estimate("cmc", NAME, _trials(), CONDITION)
    assert len(table) == 3
    assert not table["converged"].any()
    assert table["status"].str.startswith("error: ").all()


def test_a_bug_in_a_batched_form_stops_the_job(monkeypatch):
    # The batch fails, each trial is retried alone and fails again: still a bug, not three
    # failed trials.
    def broken(data):
        return data[:, :2] + data[:, :3]

    monkeypatch.setattr(sphere, "_ls_fits", broken)
    with pytest.raises(ProgrammingError, match=r"cmc LS: .*broadcast.*programming error"):
        run.estimate("cmc", "LS", _trials(), CONDITION)


@pytest.mark.parametrize("checked", [False, True])
def test_the_many_trial_form_returns_a_bug_as_the_trials_outcome_for_the_job_to_raise(
    registered, checked
):
    # Returned, not raised: in a checked call the input checks may yet replace it with their
    # own error (bad input can defeat a method's first NumPy call before they run).
    registered(_broadcast)
    outcomes = registry.many("center", NAME, checked=checked)(_trials().segments["moving"])
    assert all(not batching.numerical_failure(outcome) for outcome in outcomes)
    with pytest.raises(batching.ProgrammingError, match=r"a job: ValueError: .*broadcast"):
        with batching.mistakes_named("a job"):
            batching.failed_trial(outcomes[0])


@pytest.mark.parametrize("body", [*BUGS.values(), *FAILURES.values()])
def test_the_rule_itself(body):
    try:
        body(np.ones((5, 3, 3)))
    except (ValueError, FloatingPointError, TypeError) as error:
        expected = body in FAILURES.values()
        assert batching.numerical_failure(error) is expected
    else:
        raise AssertionError("the example did not raise")


def test_a_failure_raised_again_keeps_its_kind():
    try:
        try:
            _stated(None)
        except ValueError as error:
            raise error from None
    except ValueError as again:
        assert batching.numerical_failure(again)
    try:
        try:
            _broadcast(np.ones((5, 3, 3)))
        except ValueError as error:
            raise ValueError("in trial 3") from error
    except ValueError as wrapped:
        # Wrapped by a raise statement: the wrapper's own, deliberate.
        assert batching.numerical_failure(wrapped)


def _fails_on_repeated_frames(markers):
    # A mistake only resamples meet: block bootstrap resamples repeat frames.
    if np.unique(markers[:, 0, 0]).size < len(markers):
        markers.reshape(7, -1)


def test_a_bug_in_the_bootstrap_refits_is_raised_not_blamed_on_the_frames(registered):
    registered(_fails_on_repeated_frames)
    recording, _ = hip_trial(0, 120)
    prepared = prepare(recording, "center", "D1,D2,D3", "P1,P2,P3")
    assert prepared.fit(NAME).result.converged  # the main fit's frames are distinct
    with pytest.raises(ProgrammingError, match="reshape"):
        prepared.fit(NAME, n_bootstrap=20, seed=0)
