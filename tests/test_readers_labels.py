"""Marker labels as the file writes them, and malformed TRC and CSV files refused naming the
file, the line and the field: never read as other markers, never a traceback from the CLI."""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.cli import main
from jointbench.io import read

_TRC_TOP = "PathFileType\t4\t(X/Y/Z)\tt.trc\nDataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\n"


def _trc(tmp_path, names: str, n_markers: int, num_markers: str = "", rate: str = "100") -> str:
    """A TRC file at ``tmp_path / "t.trc"`` of 4 frames of ``n_markers`` markers, labelled by
    the tab-separated cells ``names`` (line 4 after ``Frame#  Time``); marker ``k`` (0-based)
    sits at ``100 k + frame, 100 k + 1, 100 k + 2``. ``num_markers``: the header's
    ``NumMarkers`` (empty: absent)."""
    keys = "DataRate\tCameraRate\tNumFrames\tUnits" + ("\tNumMarkers" if num_markers else "")
    values = f"{rate}\t100\t4\tmm" + (f"\t{num_markers}" if num_markers else "")
    text = _TRC_TOP.splitlines()[0] + f"\n{keys}\n{values}\n"
    text += f"Frame#\tTime\t{names}\n\t\t"
    text += "\t".join(f"X{k + 1}\tY{k + 1}\tZ{k + 1}" for k in range(n_markers)) + "\n"
    for i in range(4):
        fields = [f"{100 * k + i}.0\t{100 * k + 1}.0\t{100 * k + 2}.0" for k in range(n_markers)]
        text += f"{i + 1}\t{i / 100}\t" + "\t".join(fields) + "\n"
    path = tmp_path / "t.trc"
    path.write_text(text)
    return str(path)


def _refused(path: str, *parts: str) -> str:
    """The message of the ``ValueError`` reading ``path`` raises, checked to name the file and
    each of ``parts``."""
    with pytest.raises(ValueError) as error:
        read(path)
    message = str(error.value)
    assert message.startswith(f"{path}: "), message
    for part in parts:
        assert part in message, message
    return message


# --- TRC labels sit at fixed columns ----------------------------------------------------------


@pytest.mark.parametrize("num_markers", ["", "2", "3"], ids=["absent", "2", "3"])
def test_a_trc_marker_without_a_label_is_refused_not_read_as_the_next(tmp_path, num_markers):
    path = _trc(tmp_path, "A\t\t\t\t\t\tC\t\t", 3, num_markers)
    _refused(path, "line 4", "column 6", "marker 2")


def test_a_trc_label_off_its_three_column_boundary_is_refused(tmp_path):
    path = _trc(tmp_path, "A\t\t\t\tB\t\t", 2)
    _refused(path, "line 4", "column 7", "'B'")


def test_a_trc_row_with_coordinates_beyond_its_labels_is_refused(tmp_path):
    """A third marker's data (and line 5's X3 Y3 Z3) with two labels: the rows are not cut."""
    path = _trc(tmp_path, "A\t\t\tB\t\t", 3)
    _refused(path, "line 5", "column 9", "marker 3")
    lines = open(path).read().splitlines()
    lines[4] = "\t\tX1\tY1\tZ1\tX2\tY2\tZ2"
    open(path, "w").write("\n".join(lines) + "\n")
    _refused(path, "line 6", "column 9", "marker 3")


def test_trailing_empty_fields_of_a_trc_file_read(tmp_path):
    path = _trc(tmp_path, "A\t\t\tB\t\t\t\t", 2)
    lines = open(path).read().splitlines()
    open(path, "w").write("\n".join(line + "\t\t" for line in lines) + "\n")
    recording = read(path)
    assert recording.labels == ("A", "B")
    np.testing.assert_array_equal(recording.select("B")[0, 0], [100.0, 101.0, 102.0])


def test_a_trc_file_whose_data_start_on_line_5_is_refused(tmp_path):
    """Without the X1 Y1 Z1 line, the first frame once read as those names and was lost, where
    no NumFrames counts the frames."""
    lines = open(_trc(tmp_path, "A\t\t\tB\t\t", 2)).read().splitlines()
    lines[2] = "100\t100\t\tmm"
    path = tmp_path / "t.trc"
    path.write_text("\n".join(lines[:4] + lines[5:]) + "\n")
    assert _refused(str(path)) == (
        f"{path}: line 5 holds frame 1, where a TRC file names each marker's X, Y and Z (its "
        "Frame# and Time fields empty); read as those names, the frame would be lost"
    )


def test_a_trc_file_naming_no_marker_is_refused(tmp_path):
    _refused(_trc(tmp_path, "\t\t", 1), "line 4", "no marker")


@pytest.mark.parametrize("rate", ["abc", "0", "-100"])
def test_a_trc_data_rate_that_is_no_number_is_refused(tmp_path, rate):
    """0 and -100 once were refused without the line and the field."""
    _refused(_trc(tmp_path, "A\t\t", 1, rate=rate), "line 3", "DataRate", repr(rate))


def test_a_number_written_with_a_decimal_comma_is_named_as_such(tmp_path):
    path = _trc(tmp_path, "A\t\t", 1)
    lines = open(path).read().splitlines()
    fields = lines[5].split("\t")
    lines[5] = "\t".join([*fields[:2], "0,5", *fields[3:]])
    open(path, "w").write("\n".join(lines) + "\n")
    assert _refused(path).endswith("'0,5' is not a number (a decimal comma? write 0.5)")


def test_a_trc_frame_number_that_is_no_number_names_the_line(tmp_path):
    path = _trc(tmp_path, "A\t\t", 1)
    text = open(path).read().replace("\n3\t0.02\t", "\nx\t0.02\t")
    open(path, "w").write(text)
    _refused(path, "line 8", "Frame#", "'x'")


@pytest.mark.parametrize("frame", ["1.5", "nan", "inf"])
def test_a_trc_frame_number_that_is_no_whole_number_names_the_line(tmp_path, frame):
    """Frame numbers 1.5, 2.5 ... were truncated to 1, 2 ... and read as consecutive frames."""
    path = _trc(tmp_path, "A\t\t", 1)
    lines = open(path).read().splitlines()
    for i in range(5, 9):  # the data lines 6 to 9: frames 1.5 (or nan, inf), 2.5, 3.5, 4.5
        lines[i] = f"{frame if i == 5 else i - 3.5}\t" + lines[i].split("\t", 1)[1]
    open(path, "w").write("\n".join(lines) + "\n")
    _refused(path, "line 6", "Frame#", f"'{frame}'", "whole number")


def test_a_trc_frame_number_written_with_a_zero_fraction_reads(tmp_path):
    path = _trc(tmp_path, "A\t\t", 1)
    text = open(path).read().replace("\n1\t0.0\t", "\n1.0\t0.0\t")
    open(path, "w").write(text.replace("\n2\t0.01\t", "\n2.0\t0.01\t"))
    assert read(path).select("A").shape[0] == 4


@pytest.mark.parametrize(
    ("old", "new", "line", "after", "previous"),
    [
        ("\n3\t0.02\t", "\n2\t0.02\t", 8, "frame 2 follows frame 2", 7),
        ("\n4\t0.03\t", "\n1\t0.03\t", 9, "frame 1 follows frame 3", 8),
        ("\n3\t0.02\t", "\n\n \n2\t0.02\t", 10, "frame 2 follows frame 2", 7),
    ],
    ids=["repeated", "backwards", "after blank lines"],
)
def test_a_trc_frame_out_of_order_names_its_line_and_the_line_before(
    tmp_path, old, new, line, after, previous
):
    """The line is the file's (blank lines counted), so a frame written twice is found by it."""
    path = _trc(tmp_path, "A\t\t", 1)
    text = open(path).read()
    assert old in text
    open(path, "w").write(text.replace(old, new))
    message = _refused(path, f"line {line}, field Frame#: {after} (line {previous})")
    assert message.endswith("a TRC file's frames must be consecutive"), message


def test_a_trc_frame_count_that_is_no_count_is_not_checked(tmp_path):
    path = _trc(tmp_path, "A\t\t", 1, num_markers="1\u00b2")
    assert read(path).labels == ("A",)


def test_a_trc_file_not_in_utf8_is_refused_naming_line_and_byte(tmp_path):
    path = _trc(tmp_path, "G\u00fcn\u00f6u\t\t", 1)
    text = open(path, encoding="utf-8").read()
    open(path, "wb").write(text.encode("latin-1"))
    message = _refused(path, "line 4", "byte 0xfc", "UTF-8")
    assert "\ufffd" not in message


def test_a_utf8_trc_label_reads_as_written(tmp_path):
    path = _trc(tmp_path, "G\u00fcn\u00f6u\t\t", 1)
    assert read(path).labels == ("G\u00fcn\u00f6u",)


# --- CSV labels are text as written -----------------------------------------------------------


def _csv(tmp_path, markers: list[str], frames: list[str] | None = None) -> str:
    """A long CSV at ``tmp_path / "t.csv"``, one row per marker written as ``markers`` (in
    ``frames``, all frame 0 when ``None``), marker ``k`` at ``(k, k + 1, k + 2)``."""
    frames = frames or ["0"] * len(markers)
    rows = [
        f"{f},{m},{k},{k + 1},{k + 2}" for k, (f, m) in enumerate(zip(frames, markers, strict=True))
    ]
    path = tmp_path / "t.csv"
    path.write_text("frame,marker,x,y,z\n" + "\n".join(rows) + "\n")
    return str(path)


@pytest.mark.parametrize(
    "markers",
    [
        ["01", "02"],
        ["1.5", "2"],
        ["01", "1"],
        ["NA", "B"],
        ["null", "NaN", "None"],
        ["--1", "2"],
        ["\u00b2", "2"],
    ],
    ids=["01", "1.5", "01 and 1", "NA", "null", "--1", "superscript 2"],
)
def test_csv_labels_are_the_text_the_file_writes(tmp_path, markers):
    recording = read(_csv(tmp_path, markers))
    assert sorted(recording.labels) == sorted(markers)
    for k, marker in enumerate(markers):
        np.testing.assert_array_equal(recording.select(marker)[0, 0], [k, k + 1, k + 2])


def test_csv_labels_written_as_integers_sort_by_value(tmp_path):
    assert read(_csv(tmp_path, ["10", "2", "B", "01", "-3"])).labels == ("-3", "01", "2", "10", "B")


def test_an_empty_csv_label_is_refused_naming_the_line(tmp_path):
    path = _csv(tmp_path, ["A", "B", "", "C"])
    _refused(path, "line 4", "marker", "empty")


def test_a_csv_frame_number_beyond_any_recording_is_refused_naming_the_line(tmp_path):
    for frame in ("1e20", "100000000000000000000"):
        path = _csv(tmp_path, ["A", "A", "A"], ["0", frame, "2"])
        _refused(path, "line 3", "frame", repr(frame))
        # blank lines are no rows, and the line is the file's
        text = open(path).read()
        open(path, "w").write("\n" + text.replace("\n", "\n\n  \n", 1))
        _refused(path, "line 6", "frame", repr(frame))


@pytest.mark.parametrize(
    "frame",
    ["+1", "-0", "-1", "1e0", "1E2", "1_0", "\u0661", "\uff11", "0x1", "1.5", "NA", ""],
    ids=[
        "plus sign",
        "minus zero",
        "negative",
        "exponent",
        "capital exponent",
        "underscore",
        "arabic-indic digit",
        "fullwidth digit",
        "hex",
        "fraction",
        "NA",
        "empty",
    ],
)
def test_a_csv_frame_number_not_written_in_ascii_digits_is_refused_as_in_a_trc(tmp_path, frame):
    """The rule and the words of a TRC's Frame#: pandas reads ``+1``, ``1e0`` and ``1_0`` as
    numbers, and would take ``-0`` for frame 0."""
    path = _csv(tmp_path, ["A", "A", "A"], ["0", frame, "2"])
    message = _refused(path)
    assert message == (
        f"{path}: line 3, field frame: {frame!r} is not a frame number (a whole number >= 0 in "
        "ASCII digits)"
    )


def test_a_csv_header_repeated_among_the_rows_is_named_as_such(tmp_path):
    """Two exports joined end to end repeat the header: it once read as a frame number that is
    no number, which left the reader to find out why."""
    path = _csv(tmp_path, ["A", "A", "A"], ["0", "1", "2"])
    lines = open(path).read().splitlines(keepends=True)
    open(path, "w").write("".join(lines[:3] + lines[:1] + lines[3:]))
    assert _refused(path) == (
        f"{path}: line 4 repeats the header (frame,marker,x,y,z): files joined end to end? "
        "Remove the line, and read each recording from a file of its own"
    )


@pytest.mark.parametrize("frame", ["1", "1.0", "1.", " 1", "01"])
def test_a_csv_frame_number_of_ascii_digits_reads(tmp_path, frame):
    recording = read(_csv(tmp_path, ["A", "A", "A"], ["0", frame, "2"]))
    assert recording.first_frame == 0 and recording.n_frames == 3
    np.testing.assert_array_equal(recording.select("A")[1, 0], [1, 2, 3])


def test_a_csv_frame_written_twice_in_two_ways_is_one_frame_given_twice(tmp_path):
    _refused(_csv(tmp_path, ["A", "A"], ["1", "1.0"]), "frame 1, marker A has 2 rows")


def test_a_csv_file_not_in_utf8_is_refused_naming_line_and_byte(tmp_path):
    path = _csv(tmp_path, ["A", "G\u00fcn\u00f6u"])
    text = open(path, encoding="utf-8").read()
    open(path, "wb").write(text.encode("latin-1"))
    _refused(path, "line 3", "byte 0xfc", "UTF-8")


# --- the CLI: one line and exit code 2 --------------------------------------------------------


def _one_line_exit_2(capsys, *argv: str) -> str:
    code = main(list(argv))
    _, err = capsys.readouterr()
    assert code == 2 and "Traceback" not in err and err.count("\n") == 1, err
    return err


@pytest.mark.parametrize(
    "write",
    [
        lambda tmp_path: _csv(tmp_path, ["NA", ""]),
        lambda tmp_path: _csv(tmp_path, ["A", "A"], ["0", "1e20"]),
        lambda tmp_path: _trc(tmp_path, "A\t\t\t\t\t\tC\t\t", 3),
        lambda tmp_path: _trc(tmp_path, "A\t\t", 1, rate="abc"),
        lambda tmp_path: _trc(tmp_path, "\t\t", 1),
        lambda tmp_path: _csv(tmp_path, ["A", "B,7"]),
    ],
    ids=[
        "csv empty label",
        "csv frame 1e20",
        "trc unlabelled",
        "trc rate",
        "trc no labels",
        "csv extra field",
    ],
)
def test_inspect_and_fit_refuse_a_malformed_file_in_one_line(tmp_path, capsys, write):
    path = write(tmp_path)
    assert _one_line_exit_2(capsys, "inspect", path).startswith(f"jointbench: {path}: ")
    err = _one_line_exit_2(capsys, "fit", path, "--moving", "A")
    assert err.startswith(f"jointbench: {path}: ")


def test_fit_takes_a_csv_label_written_with_a_leading_zero(tmp_path, capsys):
    path = _csv(tmp_path, ["01", "02"])
    err = _one_line_exit_2(capsys, "fit", path, "--moving", "1")
    assert "no marker labelled '1'; labels in the file: 01, 02" in err
