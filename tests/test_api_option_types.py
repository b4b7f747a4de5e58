"""An option of the wrong type is the caller's mistake, named as such, not the method's bug.

A public fit call (``fit_center``, ``fit_axis``, ``fit_joint_center``, a recording's fit) and
the estimate of a study hold an option the method declares (:mod:`jointbench.declared`) to its
annotation before the fit: a value that is not what the method declares is a ``ValueError``
naming the option, the value, what the method declares and the method, as the config check
names it before a run (tests/test_api_option_values.py: values that would not crash it). An
option that fits its annotation and still makes the method fail stays the method's
:class:`~jointbench.estimators.batching.ProgrammingError`.
"""

from __future__ import annotations

import numpy as np
import pytest
from rigs import two_segments
from test_cli import sphere_markers
from test_programming_errors import CONDITION, _prepared, _trials

import jointbench as jb
from jointbench.estimators import registry, sphere
from jointbench.estimators.batching import ProgrammingError
from jointbench.estimators.results import CenterResult
from jointbench.running import run

NAME = "mistaken-with-options"

#: (call, method, option, value, what the method declares for the option) per case.
WRONG = {
    "text for a count": (
        lambda method, **options: jb.fit_center(sphere_markers()[0], method, **options),
        "BC",
        "max_iterations",
        "ten",
        "an integer >= 1",
    ),
    "a list for a number": (
        lambda method, **options: jb.fit_center(sphere_markers()[0], method, **options),
        "BC",
        "tol_x",
        [1e-4, 1e-3],
        "a number > 0",
    ),
    "an axis count": (
        lambda method, **options: jb.fit_axis(
            two_segments(relative="hinge", proximal_moves=False)[1], method, **options
        ),
        "planar",
        "max_iter",
        "ten",
        "an integer >= 1 or null",
    ),
    "a joint centre's noise": (
        lambda method, **options: jb.fit_joint_center(*two_segments(), method, **options),
        "gauss-markov",
        "noise_mm",
        [1.0],
        "a number >= 0 or null",
    ),
}


def _assert_callers(raised: pytest.ExceptionInfo, method: str, option: str, value, words: str):
    assert not isinstance(raised.value, ProgrammingError)
    message = str(raised.value)
    for part in (method, option, repr(value), words, "declares"):
        assert part in message, message
    assert "programming error" not in message, message


@pytest.mark.parametrize("case", sorted(WRONG))
def test_an_option_of_the_wrong_type_is_the_callers_value_error(case):
    call, method, option, value, words = WRONG[case]
    with pytest.raises(ValueError) as raised:
        call(method, **{option: value})
    _assert_callers(raised, method, option, value, words)


def test_a_recordings_fit_names_the_option_too():
    with pytest.raises(ValueError) as raised:
        _prepared().fit("BC", max_iterations="ten")
    _assert_callers(raised, "center BC", "max_iterations", "ten", "an integer >= 1")


def test_a_studys_estimate_names_the_option_too():
    # The batched path: the many-trial form returns the failure per trial, or raises it.
    for option, value in (("max_iterations", "ten"), ("tol_x", [1e-4, 1e-3])):
        with pytest.raises(ValueError) as raised:
            run.estimate("cmc", "BC", _trials(), CONDITION, {option: value})
        _assert_callers(raised, "cmc BC", option, value, "")


@pytest.fixture
def scaled():
    """A method declaring ``scale: float`` that a bug of its own breaks for any scale."""

    def mistaken(markers: np.ndarray, *, scale: float = 1.0) -> CenterResult:
        markers[0, :2] + markers[0, :3] * scale
        return sphere.fit_ls(markers)

    registry.register("center", NAME, min_frames=4)(mistaken)
    yield
    registry.unregister("center", NAME)


def test_an_option_that_fits_its_declaration_leaves_a_bug_the_methods(scaled):
    with pytest.raises(ProgrammingError, match=f"center method {NAME}: ValueError: .*broadcast"):
        jb.fit_center(sphere_markers()[0], NAME, scale=2.0)


def test_a_right_option_still_fits():
    assert jb.fit_center(sphere_markers()[0], "BC", max_iterations=50).converged
