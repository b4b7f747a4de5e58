"""An option's value is held to what the method declares before the fit, in every public call.

The config check refuses an estimator option outside its declaration (:mod:`jointbench.declared`)
before a run; a public fit call (``fit_center``, ``fit_axis``, ``fit_joint_center``,
``jointbench.fit``, a prepared recording's fit) and a study's estimate refuse the same values,
before fitting, with a ``ValueError`` naming the method, the option, the value and what is
declared: a count of ``10.5`` is not truncated, nor a tolerance of ``-1`` searched with.
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest
from rigs import two_segments
from test_bootstrap import hip_trial
from test_cli import sphere_markers
from test_programming_errors import CONDITION, _prepared, _trials

import jointbench as jb
from jointbench.configuration import config as study_config
from jointbench.declared import Positive
from jointbench.estimators import registry, sphere
from jointbench.estimators.batching import ProgrammingError
from jointbench.estimators.results import CenterResult
from jointbench.running import run

CONFIG = Path(__file__).resolve().parents[1] / "config" / "config.yaml"
NAME = "declares-its-options"


def _center(method, **options):
    return jb.fit_center(sphere_markers()[0], method, **options)


def _axis(method, **options):
    return jb.fit_axis(two_segments(relative="hinge", proximal_moves=False)[1], method, **options)


def _joint_center(method, **options):
    return jb.fit_joint_center(*two_segments(), method, **options)


def _recording(method, **options):
    recording, _ = hip_trial(0, 120)
    return jb.fit(recording, "center", "D1,D2,D3", "P1,P2,P3", method=method, **options)


def _prepared_fit(method, **options):
    return _prepared().fit(method, **options)


def _estimate(method, **options):
    return run.estimate("cmc", method, _trials(), CONDITION, options)


#: (call, study whose config may set the option, method, option, value) per case: values that
#: do not crash the method, so only a check before the fit refuses them.
WRONG = {
    "a fractional count": (_center, "cmc", "BC", "max_iterations", 10.5),
    "no iterations": (_center, "cmc", "BC", "max_iterations", 0),
    "a whole float for a count": (_center, "cmc", "BC", "max_iterations", 100.0),
    "a negative tolerance": (_center, "cmc", "BC", "tol_x", -1.0),
    "an axis's fractional count": (_axis, "hinge", "planar", "max_iter", 3.5),
    "a joint centre's fractional count": (
        _joint_center,
        "hip",
        "gauss-markov",
        "max_iterations",
        10.5,
    ),
    "a recording's fractional count": (_recording, "cmc", "BC", "max_iterations", 10.5),
    "a prepared recording's tolerance": (_prepared_fit, "cmc", "BC", "tol_x", -1.0),
    "a study's estimate": (_estimate, "cmc", "BC", "max_iterations", 10.5),
}


@pytest.fixture(scope="module")
def config():
    return study_config.load_config(CONFIG)


def _config_refusal(config, study: str, method: str, option: str, value) -> str:
    """What the config check says of ``option: value`` for ``method``, after its key path."""
    changed = copy.deepcopy(config)
    changed["studies"][study]["options"] = {method: {option: value}}
    with pytest.raises(ValueError) as raised:
        study_config.check_config(changed)
    return str(raised.value).split(f"options.{method}.", 1)[1]


@pytest.mark.parametrize("case", sorted(WRONG))
def test_a_value_the_config_check_refuses_is_refused_by_the_call(config, case):
    call, study, method, option, value = WRONG[case]
    reason = _config_refusal(config, study, method, option, value)
    with pytest.raises(ValueError) as raised:
        call(method, **{option: value})
    assert not isinstance(raised.value, ProgrammingError)
    message = str(raised.value)
    assert f"option {reason} (as {method} declares it)" in message, message


def test_a_right_option_gives_the_fit_it_gave():
    markers = sphere_markers()[0]
    fitted = jb.fit_center(markers, "BC", max_iterations=50)
    bare = sphere.fit_bc(markers, max_iterations=50)
    np.testing.assert_array_equal(fitted.center, bare.center)
    assert fitted.iterations == bare.iterations


@pytest.fixture
def registered():
    """Register a centre method for one test; unregistered after it."""
    names = []

    def register(fn):
        registry.register("center", NAME, min_frames=4)(fn)
        names.append(NAME)
        return fn

    yield register
    for name in names:
        registry.unregister("center", name)


def test_a_method_taking_any_option_is_not_checked(registered):
    given = []

    @registered
    def loose(markers: np.ndarray, **options: object) -> CenterResult:
        given.append(options)
        return sphere.fit_ls(markers)

    assert _center(NAME, max_iterations=10.5, tol_x=-1.0).converged
    assert given == [{"max_iterations": 10.5, "tol_x": -1.0}]


def test_an_extensions_declared_option_is_checked_before_its_fit(registered):
    given = []

    @registered
    def scaled(markers: np.ndarray, *, scale: Positive = 1.0, label=None) -> CenterResult:
        given.append(scale)
        return sphere.fit_ls(markers)

    with pytest.raises(ValueError) as raised:
        _center(NAME, scale=-1.0)
    message = str(raised.value)
    assert f"option scale: must be a number > 0, got -1.0 (as {NAME} declares it)" in message
    assert not given  # refused before the fit
    assert _center(NAME, scale=2.0, label=[1, "undeclared"]).converged
    assert given == [2.0]


def test_a_zero_tolerance_of_the_axis_search_is_the_tightest_not_a_refusal(config):
    """The simplex never stops below 10 ulp, so 0 is a meaningful request: the public call and
    the config check both take it."""
    rng = np.random.default_rng(3)
    local = np.array([[20.0, 5.0, 0.0], [25.0, -5.0, 10.0], [30.0, 0.0, -10.0]])
    turns = [
        np.array([[np.cos(a), np.sin(a), 0.0], [-np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
        for a in np.linspace(0.0, 1.5, 40)
    ]
    markers = np.stack([local @ turn for turn in turns]) + rng.normal(scale=0.01, size=(40, 3, 3))
    result = jb.fit_axis(markers, method="planar", xatol=0.0, fatol=0.0)
    assert abs(abs(result.direction[2]) - 1.0) < 1e-3
    changed = copy.deepcopy(config)
    changed["studies"]["hinge"]["options"] = {"planar": {"xatol": 0.0, "fatol": 0.0}}
    study_config.check_config(changed)
