"""Marker arrays of every dtype: fitted as float64 where it holds the coordinates exactly,
refused by name where it cannot hold them (values beyond a narrow float's range, which it
stores as inf) or holds no numbers."""

from __future__ import annotations

import numpy as np
import pytest
from rigs import two_segments

from jointbench import api
from jointbench.estimators import registry
from jointbench.estimators.validation import check_input, check_input_many

N_FRAMES = 60


def _moving() -> np.ndarray:
    return two_segments(N_FRAMES, proximal_moves=False)[1]


def _overflowed(dtype: type, frame: int) -> np.ndarray:
    """The moving markers stored as ``dtype``, frame ``frame``'s marker 1 beyond its range."""
    markers = _moving().astype(dtype)
    with np.errstate(over="ignore"):
        markers[frame, 1, 2] = np.asarray(1e300).astype(dtype)  # inf in a narrow float
    return markers


@pytest.mark.parametrize("dtype", [np.float32, np.float16])
def test_values_beyond_a_narrow_float_are_named_as_such(dtype):
    name = np.dtype(dtype).name
    with pytest.raises(ValueError, match=f"markers is {name} and holds inf at marker 1, frame 7"):
        check_input("center", (_overflowed(dtype, 7),))
    with pytest.raises(ValueError, match=f"beyond the largest {name} holds"):
        api.fit_center(_overflowed(dtype, 7), "LS")


def test_a_narrow_float_in_a_batch_is_named_in_its_trial():
    markers = np.stack([_moving(), _moving()]).astype(np.float32)
    with np.errstate(over="ignore"):
        markers[1, 4, 0, 0] = np.float32(1e30) * np.float32(1e30)
    errors = check_input_many("center", (markers,), 2).errors
    assert errors[0] is None
    assert "float32 and holds inf at marker 0, frame 4" in str(errors[1])


def test_the_proximal_array_of_a_joint_centre_is_named():
    proximal, distal = two_segments(N_FRAMES)
    proximal = proximal.astype(np.float32)
    proximal[3, 2, 1] = np.inf
    with pytest.raises(ValueError, match="proximal is float32 and holds inf at marker 2, frame 3"):
        registry.get("joint_center", "SCoRE")(proximal, distal)


@pytest.mark.skipif(np.finfo(np.longdouble).max <= np.finfo(np.float64).max, reason="no wider")
def test_values_beyond_float64_in_a_wider_float_are_named():
    markers = _moving().astype(np.longdouble)
    markers[9, 0, 0] = np.longdouble(10.0) ** 400
    with pytest.raises(
        ValueError, match=r"1e\+400 mm at marker 0, frame 9.*beyond the largest float64"
    ):
        check_input("center", (markers,))
    markers[9, 0, 0] = np.inf  # a gap stored as inf, named as in float64
    with pytest.raises(ValueError, match="contains NaN or inf at marker 0, frame 9"):
        check_input("center", (markers,))


@pytest.mark.parametrize("dtype", [np.int16, np.int32, np.int64, np.uint16, np.float32])
def test_integer_and_narrow_float_markers_fit_as_their_float64_values(dtype):
    markers = np.round(_moving() + 1000.0).astype(dtype)  # positive, whole millimetres
    given = api.fit_center(markers, "LS", artefacts="ignore")
    exact = api.fit_center(markers.astype(np.float64), "LS", artefacts="ignore")
    np.testing.assert_array_equal(given.center, exact.center)
    assert given.status == exact.status


@pytest.mark.parametrize("values", [_moving().astype(object), np.array([["1", "2", "3"]] * 3)])
def test_arrays_of_no_numbers_are_refused_naming_their_dtype(values):
    with pytest.raises(ValueError, match=f"markers has dtype {values.dtype}"):
        check_input("center", (values,))
