"""Recordings read on an assumption, or told the wrong thing: a C3D that states no point unit
(read as mm, and said so), a rate of NaN, frames zero-filled past a capture's end, a TRC whose
fields are separated by spaces, a frame hidden in a long C3D's last block, a scale that zeroes
every coordinate; and files whose header disagrees with their rows, each refused naming it."""

from __future__ import annotations

import struct
import warnings

import ezc3d
import numpy as np
import pytest
from test_cli import run
from test_io_hostile_files import SHANK, THIGH, _refusal
from test_io_recordings import write_c3d
from test_io_units import fit_knee, knee_legs, write_trc  # noqa: F401 (a fixture)
from test_user_recordings import write_long_csv

from jointbench.io import read, readers
from jointbench.io.units import UNIT_TO_MM

NO_UNIT = "the unit the file is read in (it states no unit; read as mm)"


def _read_quietly(path):
    """``read(path)``, failing on any warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        return read(path)


def _markers(n_frames=20, n_markers=3, seed=0):
    return np.random.default_rng(seed).uniform(10.0, 100.0, size=(n_frames, n_markers, 3))


def _c3d_without_units(path, labels, markers, units_value=None):
    """A C3D of ``markers`` whose POINT group has no ``UNITS`` (ezc3d writes one, so it is
    renamed ``UNITZ`` in the file), or, with ``units_value`` (two characters), one that
    writes that."""
    content = bytearray(write_c3d(path, labels, markers).read_bytes())
    name = content.index(b"\x01UNITS") + 1
    if units_value is None:
        content[name : name + 5] = b"UNITZ"
    else:
        value = content.index(b"mm", name)
        content[value : value + 2] = units_value
    path.write_bytes(bytes(content))
    return path


@pytest.mark.parametrize("units_value", [None, b"  "], ids=["no-units", "blank-units"])
def test_a_c3d_that_states_no_unit_is_read_as_mm_and_says_so(tmp_path, units_value):
    """Read as if it stated 'mm' (ezc3d adds the parameter it lacks); a blank one was refused
    as the unknown unit ''."""
    markers = _markers()
    path = _c3d_without_units(tmp_path / "trial.c3d", "ABC", markers, units_value)
    with pytest.warns(UserWarning) as caught:
        recording = read(path)
    assert [str(w.message) for w in caught] == [
        f"{path}: the file states no point unit (POINT:UNITS); its coordinates are read as mm"
    ]
    assert recording.units == ""
    np.testing.assert_allclose(recording.markers, markers, rtol=1e-6)


def test_metres_in_a_c3d_that_states_no_unit_are_not_said_to_be_under_mm(tmp_path, request):
    labels, markers = request.getfixturevalue("knee_legs")
    path = _c3d_without_units(tmp_path / "knee.c3d", labels, markers / 1000.0)
    with pytest.warns(UserWarning, match="states no point unit"):
        recording = read(path)
    with pytest.raises(ValueError) as error:
        fit_knee(recording)
    message = str(error.value)
    assert f"The coordinates are not in {NO_UNIT}: its numbers look like " in message
    assert "or metres read as millimetres (a cluster 341 mm across)" in message
    assert "states ('mm'" not in message


def test_metres_in_a_csv_are_not_said_to_be_under_a_unit_the_file_states(tmp_path, request):
    """A CSV states no unit: it is read as mm, the format's."""
    labels, markers = request.getfixturevalue("knee_legs")
    recording = _read_quietly(write_long_csv(tmp_path / "knee.csv", labels, markers / 1000.0))
    assert recording.units == ""
    with pytest.raises(ValueError) as error:
        fit_knee(recording)
    assert f"The coordinates are not in {NO_UNIT}" in str(error.value)


def test_a_trc_whose_units_field_is_empty_is_refused_naming_it(tmp_path):
    path = write_trc(tmp_path / "trial.trc", "ABC", _markers(), units="")
    assert _refusal(path) == (
        f"{path}: line 3, field Units: empty; a TRC file states its point unit there (mm, cm or m)"
    )


def test_inspect_says_the_rate_was_not_stated(tmp_path, capsys):
    # A CSV states no rate: the summary said "unknown" where the unit beside it says
    # "no unit stated", a word without its noun.
    path = tmp_path / "trial.csv"
    rows = [f"{frame},{label},{x + frame},{y},20.5" for frame in (1, 2) for label, x, y in _CORNERS]
    path.write_text("frame,marker,x,y,z\n" + "\n".join(rows) + "\n")
    code, out, _ = run(capsys, "inspect", str(path))
    assert code == 0
    assert "(numbered 1 to 2 as in the file), no rate stated, 3 markers" in out, out


_CORNERS = [("A", 0.5, 0.5), ("B", 100.5, 0.5), ("C", 0.5, 100.5)]


def test_inspect_and_fit_say_the_unit_was_not_stated(tmp_path, capsys):
    path = _c3d_without_units(tmp_path / "trial.c3d", "ABC", _markers())
    code, out, err = run(capsys, "inspect", str(path))
    assert code == 0
    assert "3 markers, no unit stated (read as mm)" in out
    assert err == (
        f"jointbench: warning: {path}: the file states no point unit (POINT:UNITS); its "
        "coordinates are read as mm\n"
    )
    code, out, err = run(capsys, "inspect", str(path), "--format", "json")
    assert '"units_in_file": null' in out


def _c3d_rate_words(path, header=None, parameter=None):
    """A C3D of three markers at 100 Hz, its header's rate and its POINT:RATE parameter set."""
    content = bytearray(write_c3d(path, "ABC", _markers()).read_bytes())
    if parameter is not None:
        value = content.index(b"\x01RATE\t\x00\x04\x00") + 9
        content[value : value + 4] = struct.pack("<f", parameter)
    if header is not None:
        content[20:24] = struct.pack("<f", header)
    path.write_bytes(bytes(content))
    return path


@pytest.mark.parametrize("header", [None, np.nan], ids=["parameter", "both"])
def test_a_c3d_point_rate_of_nan_is_refused_naming_it(tmp_path, header):
    """ezc3d failed on it ("vector::_M_default_append"), reported as an unreadable file."""
    path = _c3d_rate_words(tmp_path / "rate.c3d", header=header, parameter=np.nan)
    assert _refusal(path) == f"{path}: POINT:RATE nan is not a frame rate (frames per second)"


def test_a_c3d_header_rate_of_nan_under_a_parameter_rate_reads_the_parameter(tmp_path):
    """ezc3d takes the rate from POINT:RATE, which other programs read too."""
    path = _c3d_rate_words(tmp_path / "rate.c3d", header=np.nan)
    assert _read_quietly(path).rate_hz == 100.0


ZERO_FILLED = (
    "frames 16 to 20 (the last 5) hold every marker at exactly (0, 0, 0): frames zero-filled "
    "past the capture's end (a capture stopped early and padded, or a file cut and padded), not "
    "gaps a recording writes; they are read as missing"
)


def _far_markers():
    """:func:`_markers` a metre from the lab's origin: their random jumps of up to 160 mm a
    frame reach the origin from 17 to 173 mm, where a marker at it would be kept."""
    return _markers() + 1000.0


def test_a_c3d_zero_filled_at_its_end_is_read_as_missing_and_says_so(tmp_path):
    markers = _far_markers()
    markers[15:] = 0.0
    path = write_c3d(tmp_path / "padded.c3d", "ABC", markers)
    with pytest.warns(UserWarning) as caught:
        recording = read(path)
    assert [str(w.message) for w in caught] == [f"{path}: {ZERO_FILLED}"]
    assert np.isnan(recording.markers[15:]).all()
    assert np.isfinite(recording.markers[:15]).all()


def _zero_filled_and_missing(path, missing_from):
    """A file (C3D or TRC, by ``path``'s suffix) of :func:`_far_markers` zero-filled from frame
    16 on, where C is missing from row ``missing_from`` on."""
    markers = _far_markers()
    markers[15:] = 0.0
    markers[missing_from:, 2] = np.nan
    writer = write_c3d if path.suffix == ".c3d" else write_trc
    return writer(path, "ABC", markers)


@pytest.mark.parametrize("suffix", [".c3d", ".trc"])
@pytest.mark.parametrize(
    ("missing_from", "missing"), [(12, "C, missing there"), (17, "C (in 3 of them), missing there")]
)
def test_frames_zero_filled_where_a_marker_is_missing_are_said_once(
    tmp_path, suffix, missing_from, missing
):
    """C unseen from before the padding, or within it: the padding was warned marker by marker,
    as gaps of A and B (and C's zeros) a writer stored, not as frames past the capture's end."""
    path = _zero_filled_and_missing(tmp_path / f"padded{suffix}", missing_from)
    with pytest.warns(UserWarning) as caught:
        recording = read(path)
    assert [str(w.message) for w in caught] == [
        f"{path}: frames 16 to 20 (the last 5) hold every marker at exactly (0, 0, 0) but "
        f"{missing}: frames zero-filled past the capture's end (a capture stopped early and "
        "padded, or a file cut and padded), not gaps a recording writes; they are read as "
        "missing"
    ]
    assert np.isnan(recording.markers[15:]).all()


def test_frames_where_one_marker_is_at_the_origin_and_the_rest_missing_are_its_gaps(tmp_path):
    """Two or more markers at (0, 0, 0) in each frame make a padding: one alone is a gap of its
    own, named by its marker."""
    markers = _far_markers()
    markers[15:, 0] = 0.0
    markers[12:, 1:] = np.nan
    path = write_trc(tmp_path / "trial.trc", "ABC", markers)
    assert _warnings_reading(path) == [f"{path}: {_gaps_said(5, 'A at frames 16 to 20')}"]


def _warnings_reading(path):
    """The messages of the warnings :func:`read` gives reading ``path``."""
    with pytest.warns(UserWarning) as caught:
        read(path)
    return [str(w.message) for w in caught]


def _gaps_said(n_samples, named):
    """The warning of ``n_samples`` (two or more) samples at (0, 0, 0) read as a writer's gaps,
    naming each marker's frames (``named``), after the file's name."""
    return (
        f"{n_samples} samples at exactly (0, 0, 0) are read as missing, as gaps a writer stored "
        "as zeros (the C3D format's coordinates of an invalid point), not positions at the lab's "
        "origin: the marker's nearest sample before or after each lies farther from the origin "
        f"than the marker moves in a frame nearby (or it has none): {named}"
    )


def test_markers_never_seen_at_the_origin_where_the_rest_are_missing_are_no_padding(tmp_path):
    """D and E, a template's markers never seen, at (0, 0, 0) in every frame, and A to C missing
    from frame 16 on (the subject out of the volume): no marker seen in the trial stops at the
    origin, so those frames are no padding; they were said zero-filled past the capture's end,
    and D and E's zeros before them as gaps, where each is a marker never seen."""
    markers = np.concatenate([_far_markers(), np.zeros((20, 2, 3))], axis=1)
    markers[15:, :3] = np.nan
    path = write_trc(tmp_path / "trial.trc", "ABCDE", markers)
    never = "at every frame (never away from the origin)"
    assert _warnings_reading(path) == [f"{path}: {_gaps_said(40, f'D {never}; E {never}')}"]


def test_fit_prints_the_zero_filled_frames(tmp_path, capsys, request):
    labels, markers = request.getfixturevalue("knee_legs")
    markers = markers.copy()
    markers[290:] = 0.0
    path = write_c3d(tmp_path / "padded.c3d", labels, markers)
    code, _, err = run(capsys, "fit", "center", str(path), "--moving", SHANK, "--reference", THIGH)
    assert code == 0
    assert err.startswith(
        f"jointbench: warning: {path}: frames 291 to 300 (the last 10) hold every marker at "
        "exactly (0, 0, 0)"
    ), err


def test_gaps_a_residual_marks_read_as_before_without_a_word(tmp_path):
    """Gaps marked by a residual of -1 (a marker unseen, at the end too)."""
    markers = _markers()
    markers[15:] = 0.0
    residuals = np.zeros(markers.shape[:2])
    residuals[15:] = -1.0
    path = write_c3d(tmp_path / "gaps.c3d", "ABC", markers, residuals=residuals)
    recording = _read_quietly(path)
    assert np.isnan(recording.markers[15:]).all() and np.isfinite(recording.markers[:15]).all()


@pytest.mark.parametrize(
    ("gap", "count", "named"),
    [
        ("some-markers", 10, "A at frames 16 to 20; B at frames 16 to 20"),
        ("middle", 15, "A at frames 11 to 15; B at frames 11 to 15; C at frames 11 to 15"),
    ],
)
def test_gaps_stored_as_zeros_read_as_before_and_are_named(tmp_path, gap, count, named):
    """Zeros in some markers only, or zeros in every marker before frames that see them, are
    gaps, as they were, read without a word: the rule of every format now names them."""
    markers = _far_markers()
    if gap == "some-markers":
        markers[15:, :2] = 0.0
    else:
        markers[10:15] = 0.0
    path = write_c3d(tmp_path / "gaps.c3d", "ABC", markers)
    with pytest.warns(UserWarning) as caught:
        recording = read(path)
    assert [str(w.message) for w in caught] == [
        f"{path}: {count} samples at exactly (0, 0, 0) are read as missing, as gaps a writer "
        "stored as zeros (the C3D format's coordinates of an invalid point), not positions at "
        "the lab's origin: the marker's nearest sample before or after each lies farther from "
        f"the origin than the marker moves in a frame nearby (or it has none): {named}"
    ]
    assert np.isnan(recording.markers[..., 0]).sum() == (markers == 0.0).all(axis=-1).sum()


@pytest.mark.parametrize(
    ("line", "text", "refusal"),
    [
        (
            None,
            None,
            "line 2 is not tab-separated: a TRC file's fields are separated by tabs, and spaces "
            "cannot tell an empty field (a gap) from none, nor a label with a space in it; save "
            "the file with tabs",
        ),
        (
            6,
            "1 0.0000 10.0 20.0 30.0 40.0 50.0 60.0 70.0 80.0 90.0",
            "line 6 is not tab-separated: a TRC file's fields are separated by tabs, and spaces "
            "cannot tell an empty field (a gap) from none, nor a label with a space in it; save "
            "the file with tabs",
        ),
    ],
    ids=["whole-file", "one-row"],
)
def test_a_space_separated_trc_is_refused_as_not_tab_separated(tmp_path, line, text, refusal):
    """It was refused as having no 'Units' (the whole file), or a row of 1 field (one row)."""
    path = write_trc(tmp_path / "trial.trc", "ABC", _markers())
    lines = path.read_text().splitlines()
    if line is None:
        lines = [" ".join(row.split("\t")) for row in lines]
    else:
        lines[line - 1] = text
    path.write_text("\n".join(lines) + "\n")
    assert _refusal(path) == f"{path}: {refusal}"


def _long_c3d_unpadded(path, n_frames):
    """A C3D of ``n_frames`` frames of one marker (16 bytes a frame) as a writer that pads
    its last block no further than its end writes it: ezc3d's file without the whole block
    of zeros it adds where the frames end a block."""
    markers = np.random.default_rng(1).uniform(10.0, 100.0, size=(n_frames, 1, 3))
    content = write_c3d(path, ("A",), markers).read_bytes()
    assert content.endswith(bytes(512))
    path.write_bytes(content[:-512])
    return path


def test_a_frame_hidden_in_a_long_c3ds_last_block_is_refused(tmp_path):
    """Frame 65536 ends the block the 65535th ends in: it was read as padding, unseen."""
    path = _long_c3d_unpadded(tmp_path / "long.c3d", 65536)
    assert _refusal(path) == (
        f"{path}: the file holds 16 bytes past the 65535 frames read, room for 1 more frames "
        "of 1 points and 0 analog samples each (a C3D's header counts at most 65535 frames, and "
        "frames past those its header and POINT:FRAMES count are not read, whatever its "
        "POINT:LONG_FRAMES or TRIAL:ACTUAL_END_FIELD say): frames from 65536 on would be left "
        "out unread; export the trial as TRC, or in parts"
    )


def test_a_long_c3ds_zero_padding_is_no_frame(tmp_path):
    markers = np.random.default_rng(1).uniform(10.0, 100.0, size=(65535, 1, 3))
    path = write_c3d(tmp_path / "long.c3d", ("A",), markers)
    assert _read_quietly(path).n_frames == 65535


@pytest.mark.parametrize("scale", [0.0, np.nan])
def test_a_c3d_point_scale_of_0_or_nan_is_refused_naming_it(tmp_path, scale):
    """Every coordinate read as 0 (or NaN), and so every sample as a gap."""
    path = write_c3d(tmp_path / "scale.c3d", "ABC", _markers())
    content = bytearray(path.read_bytes())
    value = content.index(b"\x01SCALE") + 10
    content[value : value + 4] = struct.pack("<f", scale)
    path.write_bytes(bytes(content))
    assert _refusal(path) == (
        f"{path}: POINT:SCALE {scale:g} is no scale: a float file's is negative, an integer "
        "file's the size of its unit step (0 or NaN would make every coordinate 0 or NaN, and so "
        "every sample a gap)"
    )


@pytest.mark.parametrize(
    ("labels", "refused"),
    [
        (("", "", ""), "point 1 (of 3) has no label, an empty one (3 in all)"),
        (("A", "", "C"), "point 2 (of 3) has no label, an empty one (1 in all)"),
    ],
    ids=["all-empty", "one-empty"],
)
def test_a_c3d_point_without_a_label_is_refused_naming_it(tmp_path, labels, refused):
    """All empty, they were refused as markers 1 and 2 both labelled ''; one empty read as a
    marker named '', which no --moving can name."""
    path = write_c3d(tmp_path / "labels.c3d", labels, _markers())
    assert _refusal(path) == (
        f"{path}: POINT:LABELS: {refused}; every marker needs a label (relabel those points, "
        "or export the trial without unlabelled trajectories)"
    )


def test_a_c3d_of_more_points_than_labels_is_refused_naming_both(tmp_path):
    """ezc3d reads POINT:USED points a frame: refused as markers of another shape than the
    labels, naming neither parameter."""
    path = write_c3d(tmp_path / "used.c3d", "ABC", _markers())
    content = bytearray(path.read_bytes())
    value = content.index(b"\x01USED") + 9
    content[value : value + 2] = struct.pack("<h", 5)
    path.write_bytes(bytes(content))
    assert _refusal(path) == (
        f"{path}: POINT:USED counts 5 points, but POINT:LABELS (with LABELS2, LABELS3) names 3; "
        "every point needs a label"
    )


def _edited_trc(path, line, text):
    """A TRC of three markers over 20 frames with line ``line`` (1-based) replaced by
    ``text``."""
    lines = write_trc(path, "ABC", _markers()).read_text().splitlines()
    lines[line - 1] = text
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize(
    ("line", "text", "refused"),
    [
        (3, "100\t100\t25\t3\tmm", "the TRC header promises NumFrames 25 but the file has 20"),
        (3, "100\t100\t20\t4\tmm", "the TRC header promises NumMarkers 4 but the file has 3"),
        (3, "100\t100\t20\t3\tin", "unknown point unit 'in'; known: cm, m, mm"),
        (3, "nan\t100\t20\t3\tmm", "line 3, field DataRate: 'nan' is not a frame rate"),
        (7, "1\t0.0\t1\t2\t3\t4\t5\t6\t7\t8\t9", "line 7, field Frame#: frame 1 follows frame 1"),
    ],
    ids=["num-frames", "num-markers", "inches", "rate-nan", "frame-twice"],
)
def test_a_trc_header_its_rows_do_not_keep_is_refused(tmp_path, line, text, refused):
    path = _edited_trc(tmp_path / "trial.trc", line, text)
    assert _refusal(path).startswith(f"{path}: {refused}")


@pytest.mark.parametrize(
    ("rows", "refused"),
    [
        (
            ["frame,marker,x,y,z", ",,m,m,m", "0,A,1,2,3"],
            "line 2, field frame: '' is not a frame number",
        ),
        (
            ["frame,marker,x,y,z", "0,,A,1,2,3"],
            "line 2, column 6: '3' lies past the header's 5 columns",
        ),
        (
            [",frame,marker,x,y,z", "0,A,1,2,3"],
            "line 2 has 5 fields, but the header has 6",
        ),
        (
            ["frame,marker,x_m,y_m,z_m", "0,A,1,2,3"],
            "missing columns ['x', 'y', 'z']; the header names ['frame', 'marker', 'x_m',",
        ),
        (
            ["Frame,A,,,B,,", "mm,X,Y,Z,X,Y,Z", "0,1,2,3,4,5,6"],
            "missing columns ['frame', 'marker', 'x', 'y', 'z']; the header names ['Frame', 'A',",
        ),
    ],
    ids=["units-row", "row-shifted", "header-shifted", "units-in-names", "one-row-per-frame"],
)
def test_a_csv_of_another_layout_is_refused_naming_where(tmp_path, rows, refused):
    """A units row in metres, a label row shifted by one column either way, units in the
    column names, a wide layout with a units row: none is read as millimetres."""
    path = tmp_path / "trial.csv"
    path.write_text("\n".join(rows) + "\n")
    assert _refusal(path).startswith(f"{path}: {refused}")


def _c3d_with_a_second_point_group(path, units):
    """A C3D of three markers in metres (stated 'm') whose POINT group is written twice: the
    first without ``UNITS`` (renamed ``UNITZ``), the second holding ``UNITS`` ``units``, as a
    program that appends a parameter under a group already written may write it. ezc3d reads
    the two as one POINT group."""
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = [100.0]
    c3d["parameters"]["POINT"]["LABELS"]["value"] = ["A", "B", "C"]
    c3d.add_parameter("ZZZZZ", "UNITS", [units])
    points = np.ones((4, 3, 20))
    points[:3] = np.transpose(_markers(), (2, 1, 0)) / 1000.0
    c3d["data"]["points"] = points
    c3d.write(str(path))
    content = bytearray(path.read_bytes())
    name = content.index(b"\x01UNITS") + 1
    content[name : name + 5] = b"UNITZ"
    group = content.index(b"ZZZZZ")
    content[group : group + 5] = b"POINT"
    path.write_bytes(bytes(content))
    assert ezc3d.c3d(str(path))["parameters"]["POINT"]["UNITS"]["value"] == [units]
    return path


@pytest.mark.parametrize("units", ["m", "mm"])
def test_a_unit_stated_in_a_point_group_written_twice_is_read(tmp_path, units):
    """The parameter walk looked in the first group of the name only: the file was said to
    state no unit, and its metres were read as millimetres."""
    path = _c3d_with_a_second_point_group(tmp_path / "twice.c3d", units)
    recording = _read_quietly(path)
    assert recording.units == units
    np.testing.assert_allclose(
        recording.markers, _markers() / 1000.0 * UNIT_TO_MM[units], rtol=1e-6
    )


def test_a_c3d_zero_filled_throughout_names_every_frame(tmp_path):
    path = write_c3d(tmp_path / "zeros.c3d", "ABC", np.zeros((20, 3, 3)))
    every = ZERO_FILLED.replace("frames 16 to 20 (the last 5)", "frames 1 to 20 (the last 20)")
    with pytest.warns(UserWarning) as caught:
        recording = read(path)
    assert [str(w.message) for w in caught] == [f"{path}: {every}"]
    assert np.isnan(recording.markers).all()


def test_a_parameter_section_that_counts_no_blocks_is_read_to_the_frames(tmp_path):
    """A writer that leaves the parameter section's block count 0: its parameters run to the
    block the header places the frames in, and the unit they state is read."""
    path = write_c3d(tmp_path / "m.c3d", "ABC", _markers() / 1000.0, units="m")
    content = bytearray(path.read_bytes())
    content[(content[0] - 1) * 512 + 2] = 0
    path.write_bytes(bytes(content))
    recording = _read_quietly(path)
    assert recording.units == "m"
    np.testing.assert_allclose(recording.markers, _markers(), rtol=1e-6)


@pytest.mark.parametrize("line", [3, 4])
def test_a_trc_header_line_of_spaces_is_refused_as_not_tab_separated(tmp_path, line):
    """Line 3 of spaces was refused as a header with no 'Units' while naming line 2's Units
    key, line 4 as naming no marker."""
    path = write_trc(tmp_path / "trial.trc", "ABC", _markers())
    lines = path.read_text().splitlines()
    lines[line - 1] = " ".join(lines[line - 1].split("\t"))
    path.write_text("\n".join(lines) + "\n")
    assert _refusal(path) == (
        f"{path}: line {line} is not tab-separated: a TRC file's fields are separated by tabs, "
        "and spaces cannot tell an empty field (a gap) from none, nor a label with a space in "
        "it; save the file with tabs"
    )


@pytest.mark.parametrize("units", ["m", "cm"])
def test_a_unit_other_than_mm_that_ezc3d_reads_is_the_files_own(tmp_path, monkeypatch, units):
    """ezc3d supplies only 'mm' for a file that states no unit: any other unit it reads came
    from the file, and is kept where the package's own walk of the parameters finds no
    ``POINT:UNITS`` (a layout it does not know), not replaced by 'mm' under a warning, which
    would read metres as millimetres."""
    path = write_c3d(tmp_path / "m.c3d", "ABC", _markers() / UNIT_TO_MM[units], units=units)
    monkeypatch.setattr(readers, "_c3d_parameter", lambda *args: None)
    recording = _read_quietly(path)
    assert recording.units == units
    np.testing.assert_allclose(recording.markers, _markers(), rtol=1e-6)
