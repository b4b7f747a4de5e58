"""The registry's checked forms hold an option's value to what the method declares, as the
public calls do (tests/test_api_option_values.py, tests/test_api_option_types.py).

``registry.get(kind, name)`` and ``registry.many(kind, name)`` (``checked=True``, the default)
refuse, before the fit, an option that is not what the method declares for it, with the
message of a public call; the unchecked forms (``checked=False``) pass it to the method, as the
studies' estimate jobs use them after the config check. Every public call checks its options
once, whichever form it fits with.
"""

from __future__ import annotations

import numpy as np
import pytest
from rigs import two_segments
from test_cli import sphere_markers
from test_programming_errors import _prepared

import jointbench as jb
from jointbench.declared import Positive
from jointbench.estimators import registry, sphere
from jointbench.estimators.batching import ProgrammingError
from jointbench.estimators.results import CenterResult

NAME = "declares-a-scale"


def _arrays(kind: str) -> tuple[np.ndarray, ...]:
    """One trial's marker arrays of a ``kind`` fit."""
    if kind == "center":
        return (sphere_markers()[0],)
    if kind == "axis":
        return (two_segments(relative="hinge", proximal_moves=False)[1],)
    return two_segments()


def _public(kind: str, method: str, **options):
    call = {"center": jb.fit_center, "axis": jb.fit_axis, "joint_center": jb.fit_joint_center}
    return call[kind](*_arrays(kind), method, **options)


def _one(kind: str, method: str, **options):
    return registry.get(kind, method)(*_arrays(kind), **options)


def _many(kind: str, method: str, **options):
    return registry.many(kind, method)(*(np.stack([a, a]) for a in _arrays(kind)), **options)


#: The checked forms of the registry.
FORMS = {"get": _one, "many": _many}

#: (kind, method, option, value) per case: values the public calls refuse, both those that do
#: not crash the method (only a check before the fit refuses them) and those that do.
WRONG = {
    "a fractional count": ("center", "BC", "max_iterations", 10.5),
    "no iterations": ("center", "BC", "max_iterations", 0),
    "a whole float for a count": ("center", "BC", "max_iterations", 100.0),
    "a negative tolerance": ("center", "BC", "tol_x", -1.0),
    "text for a count": ("center", "BC", "max_iterations", "ten"),
    "a list for a number": ("center", "BC", "tol_x", [1e-4, 1e-3]),
    "an axis's fractional count": ("axis", "planar", "max_iter", 3.5),
    "an axis's text count": ("axis", "planar", "max_iter", "ten"),
    "a joint centre's fractional count": ("joint_center", "gauss-markov", "max_iterations", 10.5),
    "a joint centre's noise": ("joint_center", "gauss-markov", "noise_mm", [1.0]),
    "a joint centre's negative noise": ("joint_center", "gauss-markov", "noise_mm", -1.0),
}


def _refusal(call, *args, **options) -> ValueError:
    with pytest.raises(ValueError) as raised:
        call(*args, **options)
    assert not isinstance(raised.value, ProgrammingError), raised.value
    return raised.value


@pytest.mark.parametrize("case", sorted(WRONG))
@pytest.mark.parametrize("form", sorted(FORMS))
def test_a_checked_form_refuses_what_the_public_call_refuses(form, case):
    kind, method, option, value = WRONG[case]
    expected = str(_refusal(_public, kind, method, **{option: value}))
    assert f"(as {method} declares it)" in expected
    assert str(_refusal(FORMS[form], kind, method, **{option: value})) == expected


@pytest.mark.parametrize("form", sorted(FORMS))
def test_a_checked_form_refuses_before_the_fit(form, monkeypatch):
    fitted = []
    entry = registry._entry("center", "BC")

    def counting(fit):
        def fitting(*args, **options):
            fitted.append(options)
            return fit(*args, **options)

        return fitting

    monkeypatch.setattr(entry, "many", counting(entry.many))
    # The one-trial forms' stages, the fit first (the checked form runs them in the scope its
    # input checks share).
    monkeypatch.setattr(registry, "_stages", counting(registry._stages))
    _refusal(FORMS[form], "center", "BC", max_iterations=10.5)
    assert fitted == []
    FORMS[form]("center", "BC", max_iterations=10)
    assert fitted  # the counting reaches the fit


@pytest.mark.parametrize("case", ["a fractional count", "a negative tolerance"])
def test_the_unchecked_forms_pass_the_value_to_the_method(case):
    """The estimate jobs' forms: their options passed the config check."""
    kind, method, option, value = WRONG[case]
    markers = _arrays(kind)[0]
    assert registry.get(kind, method, checked=False)(markers, **{option: value}) is not None
    (outcome,) = registry.many(kind, method, checked=False)(markers[None], **{option: value})
    assert not isinstance(outcome, Exception), outcome


@pytest.mark.parametrize("form", sorted(FORMS))
def test_a_right_option_gives_the_fit_it_gave(form):
    markers = sphere_markers()[0]
    bare = sphere.fit_bc(markers, max_iterations=50)
    found = FORMS[form]("center", "BC", max_iterations=50)
    for fitted in found if isinstance(found, list) else [found]:
        np.testing.assert_array_equal(fitted.center, bare.center)
        assert fitted.iterations == bare.iterations


@pytest.fixture
def scaled():
    """A centre method without a many-trial form of its own, declaring ``scale``; the scales
    its fits were given."""
    given = []

    def fit(markers: np.ndarray, *, scale: Positive = 1.0, label=None) -> CenterResult:
        given.append(scale)
        return sphere.fit_ls(markers)

    registry.register("center", NAME, min_frames=4)(fit)
    yield given
    registry.unregister("center", NAME)


@pytest.mark.parametrize("form", sorted(FORMS))
def test_a_method_without_a_many_trial_form_is_checked_once_before_any_trial(form, scaled):
    with pytest.raises(ValueError) as raised:
        FORMS[form]("center", NAME, scale=-1.0)
    assert str(raised.value) == (
        f"center method {NAME}: option scale: must be a number > 0, got -1.0 "
        f"(as {NAME} declares it)"
    )
    assert scaled == []
    FORMS[form]("center", NAME, scale=2.0, label=[1, "undeclared"])
    assert set(scaled) == {2.0}


#: Every call that checks options, and its options: a list, whose check is never remembered.
CALLS = {
    "get": lambda: _one("center", NAME, scale=2.0, label=[1]),
    "many": lambda: _many("center", NAME, scale=2.0, label=[1]),
    "fit_center": lambda: _public("center", NAME, scale=2.0, label=[1]),
    "a prepared recording's fit": lambda: _prepared().fit(NAME, scale=2.0, label=[1]),
}


@pytest.mark.parametrize("call", sorted(CALLS))
def test_a_call_checks_its_options_once(call, scaled, monkeypatch):
    checked = []
    refusal = registry._refusal

    def counting(fn, n_arrays, option, value):
        checked.append(option)
        return refusal(fn, n_arrays, option, value)

    monkeypatch.setattr(registry, "_refusal", counting)
    CALLS[call]()
    assert checked.count("label") == 1, checked
    assert scaled  # it fitted


@pytest.mark.parametrize("form", sorted(FORMS))
def test_a_call_without_options_checks_none(form, monkeypatch):
    monkeypatch.setattr(registry, "check_options", None)
    monkeypatch.setattr(registry, "_refusal", None)
    monkeypatch.setattr(registry, "_scalar_fits", None)
    FORMS[form]("center", "LS")
