"""The checked one-trial call's own path: built once per method, one compiled pass of the input
checks per marker array."""

from __future__ import annotations

import numpy as np
import pytest
from rigs import two_segments

import jointbench
from jointbench.estimators import registry, validation


@pytest.mark.parametrize("kind", registry.KINDS)
def test_the_checked_form_for_valid_input_is_built_once_per_method(kind):
    for name in jointbench.methods(kind):
        assert registry.get_for_valid(kind, name) is registry.get_for_valid(kind, name), name


@pytest.fixture
def kernel_calls(monkeypatch):
    """The number of calls of the input checks' kernel."""
    calls = []
    kernel = validation._first_failures

    def counting(*args):
        calls.append(args[0].shape)
        return kernel(*args)

    monkeypatch.setattr(validation, "_first_failures", counting)
    return calls


@pytest.mark.parametrize("kind", ["center", "axis", "joint_center"])
def test_the_one_trial_input_checks_make_one_compiled_pass_per_array(kind, kernel_calls):
    proximal, distal = two_segments(60)
    arrays = (proximal, distal) if kind == "joint_center" else (distal,)
    validation.check_input(kind, arrays)
    assert kernel_calls == [(1, *array.shape) for array in arrays]


def test_the_input_checks_of_a_batch_make_one_compiled_pass(kernel_calls):
    markers = np.stack([two_segments(60)[1]] * 5)
    checked = validation.check_input_many("center", (markers,), len(markers))
    assert checked.errors == [None] * 5
    assert kernel_calls == [markers.shape]


def test_the_fit_alone_still_checks_its_markers(kernel_calls):
    distal = two_segments(60)[1]
    registry.get("center", "LS", checked=False)(distal)
    assert len(kernel_calls) == 2  # check_markers, check_moves
    with pytest.raises(ValueError, match="NaN or inf at marker 0, frame 3"):
        registry.get("center", "LS", checked=False)(
            np.where(np.arange(60)[:, None, None] == 3, np.nan, distal)
        )


@pytest.mark.parametrize("method", ["LS", "NM", "BC", "IS"])
def test_the_checked_call_s_fit_does_not_repeat_the_input_checks(method, kernel_calls):
    """The package's own fit, handed the very arrays the checked call's input checks passed,
    makes no compiled pass of its own over them; called alone afterwards, it does again."""
    distal = two_segments(60)[1]
    registry.get("center", method)(distal)
    assert kernel_calls == [(1, *distal.shape)]
    kernel_calls.clear()
    registry.get("center", method, checked=False)(distal)
    assert len(kernel_calls) == 2  # check_markers, check_moves


@pytest.mark.parametrize("method", ["LS", "NM", "BC"])
def test_the_fit_for_valid_input_still_refuses_a_buffer_refilled_after_its_checks(method):
    """:func:`registry.get_for_valid` trusts its caller's input checks for its own stages, but
    nothing shows that the arrays it is handed are, as they are now, the ones that passed: a
    buffer checked once and refilled with a NaN is refused by the package's fit, by name, not
    fitted into a ``LinAlgError``."""
    distal = two_segments(60)[1]
    (buffer,) = validation.check_input("center", (distal.copy(),))
    buffer[5, 1, 2] = np.nan
    with pytest.raises(ValueError, match="NaN or inf at marker 1, frame 5"):
        registry.get_for_valid("center", method)((buffer,))


def test_the_public_fit_checks_its_arrays_once(kernel_calls):
    """The public fit hands the fit the very arrays its input checks returned
    (:func:`registry.get_for_passed`): one compiled pass over them in all."""
    distal = two_segments(60)[1]
    jointbench.fit_center(distal, method="LS")
    assert kernel_calls == [(1, *distal.shape)]


def test_an_estimator_writing_a_nan_into_its_checked_markers_is_refused_by_the_fit_it_calls():
    """A checked call's input checks hold for the markers as they were given: an estimator
    (one registered from outside, as README "Adding an estimator" shows) that writes a NaN
    into them and hands them to a built-in fit is refused by that fit's own checks, naming
    the sample, as a fit called alone is, not fitted on what it wrote."""
    from_sphere = registry.get("center", "NM", checked=False)

    def writes_its_markers(markers):
        markers[0, 0, 0] = np.nan  # as if one sample were an outlier
        return from_sphere(markers)

    registry.register("center", "writes-its-markers")(writes_its_markers)
    try:
        distal = two_segments(60)[1].copy()
        with pytest.raises(ValueError, match="NaN or inf at marker 0, frame 0"):
            registry.get("center", "writes-its-markers")(distal)
    finally:
        registry.unregister("center", "writes-its-markers")
