"""No public function takes a keyword that skips its checks: a form that trusts its caller to
have checked the data is private, for the calls that just did (the registry's checked call,
the array API's screen), so a caller cannot hand unchecked data to it by a keyword."""

from __future__ import annotations

import importlib
import inspect
import pkgutil

import numpy as np
import pytest
from rigs import two_segments

import jointbench
from jointbench.estimators.segment_poses import trial_poses
from jointbench.screening import find_artefacts


def _public_functions():
    """Every function a module of the package exports (``__all__``), by its dotted name."""
    for info in pkgutil.walk_packages(jointbench.__path__, "jointbench."):
        module = importlib.import_module(info.name)
        for name in getattr(module, "__all__", ()):
            value = getattr(module, name)
            if inspect.isfunction(value):
                yield f"{info.name}.{name}", value


def test_no_public_function_takes_a_keyword_that_skips_a_check():
    trusting = [
        f"{where}({parameter})"
        for where, function in _public_functions()
        for parameter in inspect.signature(function).parameters
        if parameter.endswith("_checked")
    ]
    assert trusting == []


def _gapped(value: float) -> np.ndarray:
    """One trial ``(1, 60, 3, 3)`` [mm] of a segment, one sample ``value`` in frame 10."""
    _, distal = two_segments(60)
    distal[10, 1] = value
    return distal[None]


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_trial_poses_of_a_gap_or_inf_is_the_trials_error(value):
    (outcome,) = trial_poses({"markers": _gapped(value)}, min_frames=4)
    assert isinstance(outcome, ValueError)
    assert "contains NaN or inf at marker 1, frame 10" in str(outcome)
    with pytest.raises(TypeError):
        trial_poses({"markers": _gapped(value)}, min_frames=4, samples_checked=True)


@pytest.mark.parametrize("value", [np.inf, 1e300])
def test_find_artefacts_of_a_coordinate_beyond_float64s_sums_is_refused(value):
    markers = _gapped(value)[0]
    with pytest.raises(ValueError, match=r"marker b has a coordinate of .* at frame 10"):
        find_artefacts(markers, ("a", "b", "c"), "trial")
    with pytest.raises(TypeError):
        find_artefacts(markers, ("a", "b", "c"), "trial", magnitudes_checked=True)
