"""A bug in an estimator stops the job; only a trial's data defeating the fit make a failed row.

A trial fails (a row with its reason, and the run goes on) when the method states it: a
``ValueError`` raised by a ``raise`` statement of the method's own code (or by one of the
package's compiled kernels), or a ``LinAlgError`` or ``FloatingPointError`` of the data. Any
other exception is a mistake in the code and stops the job as a ``ProgrammingError`` naming the
study, the method, and the file and line in the method's code: a ``ValueError`` that Python or a
library raises (arrays that do not broadcast, ``np.stack`` of other shapes, a domain error of
``math.sqrt``), a ``TypeError``, an ``IndexError``. Recorded as a failed trial, a bug would be
ranked as the method's weakness on those data.
"""

from __future__ import annotations

import functools
import math
import types
from pathlib import Path

import numpy as np
import pytest
import scipy.optimize
from test_bootstrap import hip_trial
from test_cli import long_table, sphere_markers

from jointbench.cli import main
from jointbench.configuration.config import load_config
from jointbench.estimators import batching, registry, sphere
from jointbench.estimators.batching import ProgrammingError
from jointbench.estimators.results import CenterResult
from jointbench.io import prepare
from jointbench.numerics.compiled import kernel
from jointbench.papers import paper_sta
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


def _index(markers):
    return markers[0, 0, 7]


def _key(markers):
    return {}["radius"]


def _attribute(markers):
    return markers.centre


def _zero_division(markers):
    return 1 / 0


def _stacked(markers):
    return np.stack([markers[0], markers[0, :2]])


def _split(markers):
    return np.split(markers[0], 7)


def _solved(markers):
    return np.linalg.solve(markers[0, :2], np.ones(2))  # (2, 3): not square


def _minimised(markers):
    return scipy.optimize.minimize(lambda center: markers[0] - center, np.zeros(3))


def _square_root(markers):
    return math.sqrt(-1.0 - float(np.var(markers)))


def _arc_cosine(markers):
    return math.acos(1.0 + 1e-12)


def _integer(markers):
    return int(np.nan)


def _root(markers):
    return scipy.optimize.brentq(lambda x: x * x + 1.0, -1.0, 1.0)


def _stated(markers):
    raise ValueError("the markers span no sphere")


@kernel
def _refusing_kernel(value):
    if value < 1e300:
        raise ValueError("the kernel finds no sphere")
    return value


def _kernel_states(markers):
    return _refusing_kernel(1.0)


def _caught_and_stated(markers):
    try:
        return math.sqrt(-1.0)
    except ValueError as error:
        raise ValueError(f"no radius: {error}") from error


def _singular(markers):
    return np.linalg.inv(np.zeros((3, 3)))


def _overflow(markers):
    with np.errstate(over="raise"):
        return np.float64(1e308) * 10.0


BUGS = {
    "broadcast": _broadcast,
    "unpack": _unpack,
    "reshape": _reshape,
    "type": _type,
    "index": _index,
    "key": _key,
    "attribute": _attribute,
    "zero division": _zero_division,
    # A library's own raise statement about how it was called.
    "np.stack": _stacked,
    "np.split": _split,
    "np.linalg.solve": _solved,
    "minimize": _minimised,
}
#: Errors the data may cause inside a library or C code: the method must catch and state them.
UNSTATED = {
    "math.sqrt": _square_root,
    "math.acos": _arc_cosine,
    "int(nan)": _integer,
    "brentq": _root,
}
FAILURES = {
    "stated": _stated,
    "singular": _singular,
    "overflow": _overflow,
    "kernel": _kernel_states,
    "caught and stated": _caught_and_stated,
}


def _register(body):
    def mistaken(markers: np.ndarray) -> CenterResult:
        body(markers)
        return sphere.fit_ls(markers)

    registry.register("center", NAME, min_frames=4)(mistaken)


@pytest.fixture
def registered():
    yield _register
    registry.unregister("center", NAME)


def _assert_named(message: str, *names: str) -> None:
    """``message`` calls itself a programming error and names ``names`` and the line of this
    file where the method went wrong."""
    assert "programming error" in message, message
    assert all(name in message for name in names), message
    assert f"{Path(__file__).name}:" in message, message  # where the code went wrong


@pytest.mark.parametrize("bug", sorted(BUGS))
def test_a_bug_in_a_newcomer_stops_the_job_naming_it(registered, bug):
    registered(BUGS[bug])
    with pytest.raises(ProgrammingError) as raised:
        run.estimate("cmc", NAME, _trials(), CONDITION)
    _assert_named(str(raised.value), f"cmc {NAME}")


def _answered(center):
    """A method answering ``center`` for every trial, whatever its shape."""

    def answering(markers: np.ndarray) -> CenterResult:
        return CenterResult(center=center, converged=True, iterations=1, status="ok", method=NAME)

    return answering


#: A centre is three coordinates: an answer of another shape is the method's bug, which no
#: score, rank or row can be made of.
WRONG_SHAPES = {
    "two coordinates": np.zeros(2),
    "four coordinates": np.zeros(4),
    "a row of three": np.zeros((1, 3)),
    "a number": 0.0,
}


@pytest.mark.parametrize("shape", sorted(WRONG_SHAPES))
def test_an_answer_of_the_wrong_shape_stops_the_job_naming_the_method(shape):
    registry.register("center", NAME, min_frames=4)(_answered(WRONG_SHAPES[shape]))
    try:
        with pytest.raises(ProgrammingError) as raised:
            run.estimate("cmc", NAME, _trials(), CONDITION)
    finally:
        registry.unregister("center", NAME)
    message = str(raised.value)
    assert "programming error" in message and f"cmc {NAME}" in message, message
    shown = np.shape(WRONG_SHAPES[shape])
    assert f"center of shape {shown}, not (3,)" in message, message


@pytest.mark.parametrize("unstated", sorted(UNSTATED))
def test_a_library_error_the_method_does_not_state_stops_the_job_saying_how_to_state_it(
    registered, unstated
):
    registered(UNSTATED[unstated])
    with pytest.raises(ProgrammingError) as raised:
        run.estimate("cmc", NAME, _trials(), CONDITION)
    _assert_named(str(raised.value), f"cmc {NAME}", "catch")


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


@pytest.mark.parametrize("body", [*BUGS.values(), *UNSTATED.values(), *FAILURES.values()])
def test_the_rule_itself(body):
    try:
        body(np.ones((5, 3, 3)))
    except Exception as error:
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


def _on_repeated_frames(bug):
    """An estimator body that runs ``bug`` only on resamples: block bootstrap resamples
    repeat frames, the main fit's frames are distinct."""

    def body(markers):
        if np.unique(markers[:, 0, 0]).size < len(markers):
            bug(markers)

    return body


@functools.cache
def _prepared():
    recording, _ = hip_trial(0, 120)
    return prepare(recording, "center", "D1,D2,D3", "P1,P2,P3")


@pytest.mark.parametrize("bug", ["reshape", "index", "key"])
def test_a_bug_in_the_bootstrap_refits_is_raised_not_blamed_on_the_frames(registered, bug):
    registered(_on_repeated_frames(BUGS[bug]))
    assert _prepared().fit(NAME).result.converged
    with pytest.raises(ProgrammingError) as raised:
        _prepared().fit(NAME, n_bootstrap=20, seed=0)
    _assert_named(str(raised.value), f"center {NAME}")


@pytest.mark.parametrize("bug", ["broadcast", "index"])
def test_a_bug_in_a_recordings_fit_names_the_method_and_the_line(registered, bug):
    registered(BUGS[bug])
    with pytest.raises(ProgrammingError) as raised:
        _prepared().fit(NAME)
    _assert_named(str(raised.value), f"center {NAME}")


def test_a_trial_the_data_defeat_is_still_a_recordings_error_to_read(registered):
    registered(_stated)
    with pytest.raises(ValueError, match=f"center {NAME}: the markers span no sphere"):
        _prepared().fit(NAME)


def test_fitting_every_method_stops_on_a_bug_not_reporting_it_as_did_not_run(
    registered, tmp_path, capsys
):
    registered(_broadcast)
    markers, _ = sphere_markers()
    long_table(markers).to_csv(tmp_path / "markers.csv", index=False)
    arguments = ["fit", str(tmp_path / "markers.csv"), "--format", "csv", "--method"]
    with pytest.raises(ProgrammingError) as raised:
        main([*arguments, "all"])
    assert "did not run" not in capsys.readouterr().err
    _assert_named(str(raised.value), f"center {NAME}")
    with pytest.raises(ProgrammingError) as raised:
        main([*arguments, NAME])
    _assert_named(str(raised.value), f"center {NAME}")


def test_a_bug_in_the_hip_sta_bootstrap_stops_it_naming_the_method(monkeypatch):
    def broken(kind, method, checked=True):
        return lambda proximal, distal: [_index(proximal)] * len(proximal)

    monkeypatch.setattr(registry, "many", broken)
    segments = {name: np.ones((1, 12, 3, 3)) for name in ("proximal", "distal")}
    with pytest.raises(ProgrammingError) as raised:
        paper_sta.bootstrap_covariances(types.SimpleNamespace(segments=segments), 1, 4)
    _assert_named(str(raised.value), paper_sta.BOOTSTRAP_METHOD)
