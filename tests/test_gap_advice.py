"""The advice of the input checks fits what they found: a NaN is already a marked gap, a sample
at (0, 0, 0) may be a gap stored as zeros, a masked value is a gap the fit cannot read."""

from __future__ import annotations

import numpy as np
import pytest

import jointbench

CENTRE = np.array([20.0, -25.0, -30.0])


def _arc() -> np.ndarray:
    """Noise-free markers ``(60, 3, 3)`` [mm] of a cluster turning about CENTRE."""
    t = np.linspace(0.0, 1.5, 60)
    angles = np.stack([0.5 * np.cos(t), 0.5 * np.sin(t)], -1)
    body = np.array([[40.0, 10.0, 5.0], [10.0, 50.0, -10.0], [-5.0, 15.0, 60.0]])
    cos, sin = np.cos(angles), np.sin(angles)
    x = body[None, :, 0] * cos[:, :1] - body[None, :, 1] * sin[:, :1]
    y = body[None, :, 0] * sin[:, :1] + body[None, :, 1] * cos[:, :1]
    z = body[None, :, 2] + 20.0 * sin[:, 1:]
    return CENTRE + np.stack([x, y, z], -1)


def _message(markers) -> str:
    with pytest.raises(ValueError) as error:
        jointbench.fit_center(markers, method="LS")
    return str(error.value)


@pytest.mark.parametrize("value", [np.nan, np.inf])
def test_a_nan_gap_is_not_told_to_be_marked_as_nan(value):
    markers = _arc()
    markers[7, 1] = value
    message = _message(markers)
    assert "contains NaN or inf at marker 1, frame 7" in message
    assert "mark gaps as NaN" not in message
    assert "drop those frames" in message and "jointbench.io.Recording" in message


def test_a_sample_at_the_origin_is_named_as_a_possible_gap():
    markers = _arc()
    markers[7, 1] = 0.0
    message = _message(markers)
    assert "at exactly (0, 0, 0) at marker 1, frame 7" in message
    assert "some C3D readers store gaps as zeros" in message
    assert "jointbench.io.Recording" in message and "reads (0, 0, 0) as a gap" in message
    # A Recording keeps a sample its marker's own motion reaches the origin by: the advice
    # does not say it reads every one as a gap.
    assert "unless its marker moves through the origin" in message


def test_a_masked_gap_is_not_told_to_be_marked_as_nan():
    markers = np.ma.masked_array(_arc(), mask=False)
    markers[7, 1] = np.ma.masked
    message = _message(markers)
    assert "masked values (first at marker 1, frame 7" in message
    assert "mark gaps as NaN" not in message and "drop those frames" in message
