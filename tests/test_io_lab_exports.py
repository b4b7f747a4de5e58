"""What lab exporters write that a reader must not take at its word: warnings that name the
line that called the reader (not the reader's own), and a C3D whose ``POINT:SCALE`` and
header disagree on how its coordinates are stored."""

from __future__ import annotations

import struct
import warnings

import numpy as np
import pytest
from test_io_recordings import KNEE, write_c3d
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


#: Where the knee trial writes its header's scale (words 7-8) and its POINT:SCALE's value.
_HEADER_SCALE = slice(12, 16)
_PARAMETER_SCALE = slice(774, 778)


def _knee_scaled(tmp_path, header=None, parameter=None):
    """A copy of the knee trial (float coordinates, both scales -0.0525) with its header's scale
    and its POINT:SCALE set."""
    content = bytearray(KNEE.read_bytes())
    for where, value in ((_HEADER_SCALE, header), (_PARAMETER_SCALE, parameter)):
        assert struct.unpack("<f", content[where])[0] == pytest.approx(-0.05248538)
        if value is not None:
            content[where] = struct.pack("<f", value)
    path = tmp_path / "knee.c3d"
    path.write_bytes(bytes(content))
    return path


def _refusal(path):
    with pytest.raises(ValueError) as error:
        jointbench.read(path)
    return str(error.value)


FLOATS = (
    "the file's 2046464 bytes hold its 922 frames of its 73 points' coordinates as 32-bit floats"
)


def test_a_c3d_whose_positive_scale_misstates_its_float_frames_is_refused(tmp_path):
    """ezc3d read the floats as integers: numbers of another size, without a word."""
    path = _knee_scaled(tmp_path, header=0.0525, parameter=0.0525)
    assert _refusal(path) == (
        f"{path}: POINT:SCALE 0.0525 and its header's scale say its coordinates are 16-bit "
        f"integers (a positive scale), but {FLOATS}, as a negative scale says: read as "
        "integers, every coordinate would be another number; export the trial again (its "
        "POINT:SCALE negative, for floats)"
    )


@pytest.mark.parametrize(
    ("header", "parameter", "says"),
    [
        (
            None,
            0.0525,
            "POINT:SCALE 0.0525 says its coordinates are 16-bit integers (a positive scale), "
            "its header's scale -0.0525 says 32-bit floats (a negative one)",
        ),
        (
            0.0525,
            None,
            "POINT:SCALE -0.0525 says its coordinates are 32-bit floats (a negative scale), "
            "its header's scale 0.0525 says 16-bit integers (a positive one)",
        ),
    ],
    ids=["parameter", "header"],
)
def test_a_c3d_whose_two_scales_disagree_is_refused(tmp_path, header, parameter, says):
    """ezc3d read the first as integers, the second as floats in its first frame and integers
    after it, without a word."""
    path = _knee_scaled(tmp_path, header, parameter)
    assert _refusal(path) == (
        f"{path}: {says}: a file that disagrees with itself, which ezc3d reads as integers in "
        f"all or some of its frames; {FLOATS}, and those read as integers would be other numbers; "
        "export the trial again (both scales negative, for floats)"
    )


def test_the_knee_trial_reads_as_before():
    markers = jointbench.read(KNEE).markers
    assert np.isfinite(markers).all()
    assert markers[0, 0].tolist() == [575.7947998046875, 604.501953125, 1678.9611816406250]
