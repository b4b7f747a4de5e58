"""What lab exporters write that a reader must not take at its word: warnings that name the
line that called the reader (not the reader's own), and a C3D whose ``POINT:SCALE`` and
header disagree on how its coordinates are stored."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from test_io_recordings import write_c3d
from test_io_unstated_and_padded import _c3d_without_units

import jointbench
from jointbench.io import read_c3d


def _markers(n_frames=20, n_markers=3, seed=0):
    return np.random.default_rng(seed).uniform(10.0, 100.0, size=(n_frames, n_markers, 3))


def _caught(reader, path):
    """The warnings ``reader(path)`` gives, called from this line."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        reader(path)
    return caught


@pytest.mark.parametrize("reader", [jointbench.read, read_c3d], ids=["read", "read_c3d"])
def test_a_readers_warning_names_the_line_that_called_it(tmp_path, reader):
    """It named jointbench/io/readers.py, the line inside read() that called read_c3d()."""
    path = _c3d_without_units(tmp_path / "trial.c3d", "ABC", _markers())
    caught = _caught(reader, path)
    assert [str(w.message) for w in caught] == [
        f"{path}: the file states no point unit (POINT:UNITS); its coordinates are read as mm"
    ]
    assert caught[0].filename == __file__


def test_the_zero_filled_end_warning_names_the_line_that_called_the_reader(tmp_path):
    markers = _markers()
    markers[15:] = 0.0
    path = write_c3d(tmp_path / "padded.c3d", "ABC", markers)
    (warning,) = _caught(jointbench.read, path)
    assert "(the last 5) hold every marker at exactly (0, 0, 0)" in str(warning.message)
    assert warning.filename == __file__
