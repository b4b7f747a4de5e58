"""A bug in a method reached through the public one-call API is named as one, not taken for
bad input.

``fit_center``, ``fit_axis`` and ``fit_joint_center`` apply the rule the estimate jobs apply
(:func:`jointbench.estimators.batching.numerical_failure`): a ``ValueError`` the method states
(its own ``raise``) and bad input reach the caller unchanged; any other exception raised inside
the method is a :class:`~jointbench.estimators.batching.ProgrammingError` naming the method and
the line where it went wrong.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rigs import two_segments
from test_cli import sphere_markers
from test_programming_errors import BUGS, UNSTATED, _stated

import jointbench as jb
from jointbench.estimators import registry
from jointbench.estimators.batching import ProgrammingError

NAME = "mistaken-public"

#: Per kind: the public call on noise-free data, and a registered method the newcomer defers to.
CALLS = {
    "center": (
        lambda method, **options: jb.fit_center(sphere_markers()[0], method, **options),
        "LS",
    ),
    "axis": (
        lambda method, **options: jb.fit_axis(
            two_segments(relative="hinge", proximal_moves=False)[1], method, **options
        ),
        "planar",
    ),
    "joint_center": (
        lambda method, **options: jb.fit_joint_center(*two_segments(), method, **options),
        "analytic",
    ),
}


@pytest.fixture
def registered():
    """Register, per kind, a method that runs ``body`` on its first array, then fits as the
    kind's working method does; unregistered after the test."""
    kinds = []

    def register(kind, body):
        deferred = registry.get(kind, CALLS[kind][1], checked=False)

        def mistaken(*arrays, **options):
            body(arrays[0])
            return deferred(*arrays, **options)

        registry.register(kind, NAME, min_frames=4)(mistaken)
        kinds.append(kind)

    yield register
    for kind in kinds:
        registry.unregister(kind, NAME)


@pytest.mark.parametrize("kind", sorted(CALLS))
@pytest.mark.parametrize("bug", ["broadcast", "type", "index", "np.stack", "math.sqrt"])
def test_a_bug_in_a_method_is_a_programming_error_naming_it(registered, kind, bug):
    registered(kind, {**BUGS, **UNSTATED}[bug])
    with pytest.raises(ProgrammingError) as raised:
        CALLS[kind][0](NAME)
    message = str(raised.value)
    assert "programming error" in message, message
    assert NAME in message, message
    assert f"{Path(__file__).with_name('test_programming_errors.py').name}:" in message, message


@pytest.mark.parametrize("kind", sorted(CALLS))
def test_a_bug_also_without_the_screen(registered, kind):
    registered(kind, BUGS["broadcast"])
    with pytest.raises(ProgrammingError, match=NAME):
        CALLS[kind][0](NAME, artefacts="ignore")


@pytest.mark.parametrize("kind", sorted(CALLS))
def test_a_refusal_the_method_states_is_the_callers_value_error(registered, kind):
    registered(kind, _stated)
    with pytest.raises(ValueError, match=r"^the markers span no sphere$") as raised:
        CALLS[kind][0](NAME)
    assert not isinstance(raised.value, ProgrammingError)


@pytest.mark.parametrize("kind", sorted(CALLS))
def test_an_option_the_method_does_not_take_is_still_a_type_error(kind):
    with pytest.raises(TypeError, match="bogus") as raised:
        CALLS[kind][0](CALLS[kind][1], bogus=1)
    assert not isinstance(raised.value, ProgrammingError)


def test_bad_input_is_still_a_value_error_naming_it():
    markers = sphere_markers()[0]
    markers[3, 1, 2] = np.nan
    with pytest.raises(ValueError, match="NaN") as raised:
        jb.fit_center(markers, "LS")
    assert not isinstance(raised.value, ProgrammingError)
