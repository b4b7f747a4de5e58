"""Hard inputs to the file and array paths: truncated files, frames named as in the file, label
swaps as events, frame order in exclude mode, screening of arrays, and the CLI's answers."""

from __future__ import annotations

import json
import re

import numpy as np
import pandas as pd
import pytest
from rigs import JOINT, PROXIMAL
from test_cli import long_table, run, sphere_markers
from test_io_recordings import DIST, KNEE, PROX, in_frame, rig_recording, swapped, write_c3d

import jointbench
from jointbench.io import Recording, prepare, read

THIGH = "RTHI1,RTHI2,RTHI3,RGT,RLFE,RMFE"  # with the epicondyles, whose labels get swapped
SHANK = "RLEG1,RLEG2,RLEG3,RATT,RLM,RSPH"


# --- readers ----------------------------------------------------------------------------------


@pytest.mark.parametrize("cut", ["half", "1000 bytes"])
def test_truncated_c3d_is_refused_naming_what_the_header_promised(tmp_path, cut):
    content = KNEE.read_bytes()
    path = tmp_path / "cut.c3d"
    path.write_bytes(content[: len(content) // 2] if cut == "half" else content[:-1000])
    complete = 458 if cut == "half" else 921
    with pytest.raises(ValueError) as error:
        read(path)
    assert str(error.value).startswith(f"{path}: truncated C3D file")
    assert "promises frames 100 to 1021 (922 frames) of 73 points" in str(error.value)
    assert f"{complete} complete frames" in str(error.value)


@pytest.mark.parametrize("cut", [300, 1024, 9000, 1_000_000, 2_045_000])
def test_a_truncated_c3d_refusal_says_what_to_do(tmp_path, cut):
    """Every refusal of a C3D file cut short, inside its header, its parameters or its frames,
    ends saying how to go on: the part that is there is not read as the trial."""
    path = tmp_path / "cut.c3d"
    path.write_bytes(KNEE.read_bytes()[:cut])
    with pytest.raises(ValueError) as error:
        read(path)
    assert str(error.value).endswith(
        "; copy the file again from where it was recorded, or export it again"
    )


@pytest.mark.parametrize(
    ("cut", "where"),
    [
        (300, "its 512-byte header block"),
        (1024, "its parameters, before the frames its header places at byte 10240"),
        (9000, "its parameters, before the frames its header places at byte 10240"),
    ],
)
def test_a_c3d_file_cut_before_its_frames_is_refused_as_truncated(tmp_path, cut, where):
    """ezc3d's own message for these ("The format is not standard. If you want to ignore this
    error, set ignoreBadFormatting to true") named neither the cut nor a remedy."""
    path = tmp_path / "cut.c3d"
    path.write_bytes(KNEE.read_bytes()[:cut])
    with pytest.raises(ValueError) as error:
        read(path)
    assert str(error.value) == (
        f"{path}: truncated C3D file: it ends after {cut} bytes, inside {where}; copy the "
        "file again from where it was recorded, or export it again"
    )


def test_truncated_trc_is_refused(tmp_path):
    header = "PathFileType\t4\t(X/Y/Z)\tcut.trc\n"
    header += "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\n100\t100\t5\t1\tmm\n"
    header += "Frame#\tTime\tA\t\t\n\t\tX1\tY1\tZ1\n"
    rows = "".join(f"{18 + i}\t{i / 100}\t{i}.0\t1.0\t2.0\n" for i in range(3))
    path = tmp_path / "cut.trc"
    path.write_text(header + rows)
    with pytest.raises(ValueError, match="promises NumFrames 5 but the file has 3"):
        read(path)
    path.write_text(header.replace("\t5\t", "\t3\t") + rows)
    assert read(path).first_frame == 18


def _trc(tmp_path, frames: int = 4) -> tuple:
    """A TRC file of ``frames`` frames of markers A and B, B occluded in frame 1 (its fields
    empty, the row whole), as its text and the path it is written to."""
    text = "PathFileType\t4\t(X/Y/Z)\tcut.trc\n"
    text += f"DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\n100\t100\t{frames}\t2\tmm\n"
    text += "Frame#\tTime\tA\t\t\tB\t\t\n\t\tX1\tY1\tZ1\tX2\tY2\tZ2\n"
    for i in range(frames):
        b = "\t\t" if i == 1 else f"{i}.5\t1.5\t2.5"
        text += f"{i + 1}\t{i / 100}\t{i}.0\t1.0\t2.0\t{b}\n"
    return text, tmp_path / "cut.trc"


def _long_csv(tmp_path) -> tuple:
    """A long CSV of 3 frames of markers A and B, B's z in frame 1 empty (the row whole)."""
    rows = [
        f"{f},{m},{f}.5,1.5,{'' if (f, m) == (1, 'B') else '2.5'}" for f in range(3) for m in "AB"
    ]
    return "frame,marker,x,y,z\n" + "\n".join(rows) + "\n", tmp_path / "cut.csv"


_TRC_HEADER = "8 (Frame#, Time and X, Y, Z of 2 markers)"
_CSV_HEADER = "5 (frame, marker, x, y, z)"


@pytest.mark.parametrize(
    ("written", "start", "kept", "fields", "line", "header"),
    [
        (_trc, "4\t0.03\t", "4\t0.03\t3.0\t1.0\t2", 5, 9, _TRC_HEADER),
        (_trc, "4\t0.03\t", "4\t0.03\t3.0\t1.0\t2.0\t3.5", 6, 9, _TRC_HEADER),
        (_trc, "4\t0.03\t", "4", 1, 9, _TRC_HEADER),
        (_long_csv, "2,B,", "2,B,2.5,1.5", 4, 7, _CSV_HEADER),
        (_long_csv, "2,B,", "2,B,2.5", 3, 7, _CSV_HEADER),
        (_long_csv, "2,B,", "2,B", 2, 7, _CSV_HEADER),
        (_long_csv, "2,B,", "2", 1, 7, _CSV_HEADER),
    ],
    ids=["trc in A's z", "trc after B's x", "trc after Frame#", *("csv",) * 4],
)
def test_a_file_cut_inside_its_last_line_is_refused_naming_the_line(
    tmp_path, written, start, kept, fields, line, header
):
    """The cut line once read as a frame with gaps (a TRC's NumFrames counts it), or as a
    marker named by what was left of its label."""
    text, path = written(tmp_path)
    path.write_text(text[: text.index(start)] + kept)
    with pytest.raises(ValueError) as error:
        read(path)
    assert str(error.value) == (
        f"{path}: line {line} has {fields} fields, but the header has {header}; the file ends "
        "inside this line: it was cut short; a gap is an empty field, not a missing one"
    )


_SEPARATOR = {_trc: "\t", _long_csv: ","}


@pytest.mark.parametrize(
    ("written", "line", "name"), [(_trc, 9, "Z of B"), (_long_csv, 7, "z")], ids=["trc", "csv"]
)
def test_a_file_cut_right_after_a_separator_of_its_last_line_is_refused(
    tmp_path, written, line, name
):
    """The cut line keeps every field, its last one empty: it once read as a gap in the last
    sample."""
    text, path = written(tmp_path)
    body = text.rstrip("\n")
    path.write_text(body[: body.rfind(_SEPARATOR[written]) + 1])
    with pytest.raises(ValueError) as error:
        read(path)
    assert str(error.value) == (
        f"{path}: line {line} leaves its last field ({name}) empty, which other rows fill, and "
        "the file ends inside this line, right after a separator: it was cut short; if the "
        "field is a gap, end the line with a newline"
    )


def _three_decimals(text: str) -> str:
    """``text`` with every coordinate written to three decimals, as most exporters write them;
    a TRC row's ``Frame#`` and ``Time``, its first two fields, as they are."""
    lines = []
    for line in text.split("\n"):
        *kept, rest = line.split("\t", 2) if line.count("\t") >= 2 else [line]
        rest = re.sub(r"(?<![\d.])(\d+)\.(\d)(?![\d.])", r"\g<1>.\g<2>25", rest)
        lines.append("\t".join([*kept, rest]))
    return "\n".join(lines)


@pytest.mark.parametrize("kept", [4, 3, 2, 1], ids=["2.52", "2.5", "2.", "2"])
@pytest.mark.parametrize(
    ("written", "line", "name"), [(_trc, 9, "Z of B"), (_long_csv, 7, "z")], ids=["trc", "csv"]
)
def test_a_file_cut_inside_its_last_number_is_refused(tmp_path, written, line, name, kept):
    """The cut number once read as another value: 2.5 or 2 for the 2.525 written."""
    text, path = written(tmp_path)
    body = _three_decimals(text).rstrip("\n")
    assert body.endswith("2.525")
    path.write_text(body[: len(body) - 5 + kept])
    left = body[len(body) - 5 : len(body) - 5 + kept]
    with pytest.raises(ValueError) as error:
        read(path)
    assert str(error.value) == (
        f"{path}: line {line} ends its last field ({name}) with {left!r}, "
        f"{max(kept - 2, 0)} decimals where every other row writes 3, and the file ends inside "
        "this line: it was cut short inside a number; if the value is whole, end the line with "
        "a newline"
    )
    path.write_text(body[: len(body) - 5 + kept] + "\n")
    assert read(path).markers[-1, 1, 2] == float(left)


@pytest.mark.parametrize("written", [_trc, _long_csv], ids=["trc", "csv"])
def test_a_last_number_without_a_newline_reads_where_the_rows_write_any_decimals(tmp_path, written):
    """A writer that drops trailing zeros (``%g``) leaves no format to tell a cut by."""
    text, path = written(tmp_path)
    body = _three_decimals(text).rstrip("\n")
    varied = body.replace("2.525\n", "2.5\n", 1)  # the last field of an earlier row
    assert varied != body
    path.write_text(varied[:-2])
    assert read(path).markers[-1, 1, 2] == 2.5


@pytest.mark.parametrize("written", [_trc, _long_csv], ids=["trc", "csv"])
def test_a_whole_file_without_a_final_newline_reads(tmp_path, written):
    text, path = written(tmp_path)
    path.write_text(text)
    whole = read(path).markers
    path.write_text(text.rstrip("\n"))
    np.testing.assert_array_equal(read(path).markers, whole)


@pytest.mark.parametrize("written", [_trc, _long_csv], ids=["trc", "csv"])
def test_an_empty_last_field_of_the_last_line_is_a_gap_when_the_line_ends(tmp_path, written):
    text, path = written(tmp_path)
    body = text.rstrip("\n")
    path.write_text(body[: body.rfind(_SEPARATOR[written]) + 1] + "\n")
    recording = read(path)
    assert np.isnan(recording.markers[-1, 1, 2]) and recording.gaps()["B"] == 2


def test_a_trc_file_of_blank_lines_after_its_header_is_refused(tmp_path):
    text, path = _trc(tmp_path)
    path.write_text("".join(text.splitlines(keepends=True)[:5]) + "\n\n")
    with pytest.raises(ValueError, match="no frames: the TRC header is followed by blank lines"):
        read(path)


def _renumbered(text: str, first: str, start: int = 1) -> str:
    """``text`` of :func:`_trc` with its rows numbered from ``start``, the first row's number
    written as ``first``."""
    lines = text.splitlines(keepends=True)
    for i in range(5, len(lines)):
        number = first if i == 5 else str(start + i - 5)
        lines[i] = number + lines[i][lines[i].index("\t") :]
    return "".join(lines)


@pytest.mark.parametrize(
    ("first", "start"),
    [("-1", -1), ("\u0661", 1), ("+1", 1), ("1e0", 1), ("1_0", 10), ("0x1", 1), ("", 1)],
    ids=["negative", "arabic-indic digit", "plus sign", "exponent", "underscore", "hex", "empty"],
)
def test_a_frame_number_not_written_in_ascii_digits_is_refused_naming_the_line(
    tmp_path, first, start
):
    text, path = _trc(tmp_path)
    path.write_text(_renumbered(text, first, start), encoding="utf-8")
    with pytest.raises(ValueError) as error:
        read(path)
    assert str(error.value).startswith(
        f"{path}: line 6, field Frame#: {first!r} is not a frame number"
    ), error.value


@pytest.mark.parametrize("first", ["1", "1.0", " 1"])
def test_a_frame_number_of_ascii_digits_reads(tmp_path, first):
    """Digits, as some writers give them a ``.0`` or pad them with spaces."""
    text, path = _trc(tmp_path)
    path.write_text(_renumbered(text, first))
    assert read(path).first_frame == 1


def test_frame_zero_is_a_frame_number(tmp_path):
    text, path = _trc(tmp_path)
    path.write_text(_renumbered(text, "0", 0))
    assert read(path).first_frame == 0


@pytest.mark.parametrize("written", [_trc, _long_csv], ids=["trc", "csv"])
def test_an_empty_field_is_a_gap(tmp_path, written):
    text, path = written(tmp_path)
    path.write_text(text)
    recording = read(path)
    assert recording.gaps() == {"A": 0, "B": 1}
    assert np.isnan(recording.markers[1, 1]).all() and not np.isnan(recording.markers[2]).any()


@pytest.mark.parametrize(
    ("written", "row", "short", "line"),
    [
        (_trc, "3\t0.02\t2.0\t1.0\t2.0\t2.5\t1.5\t2.5\n", "3\t0.02\t2.0\n", 8),
        (_long_csv, "1,A,1.5,1.5,2.5\n", "1,A,1.5\n", 4),
    ],
    ids=["trc", "csv"],
)
def test_a_row_missing_fields_inside_the_file_is_refused(tmp_path, written, row, short, line):
    text, path = written(tmp_path)
    assert row in text
    path.write_text(text.replace(row, short))
    with pytest.raises(ValueError) as error:
        read(path)
    message = str(error.value)
    assert message.startswith(f"{path}: line {line} has 3 fields, but the header has")
    assert "cut short" not in message


def _with_trailing_separators(text: str, extra: str) -> str:
    """``text``, a long CSV, with ``extra`` after every data row (the header left as it is)."""
    header, *rows = text.splitlines()
    return "\n".join([header, *(row + extra for row in rows)]) + "\n"


@pytest.mark.parametrize("extra", [",", ",,"])
def test_csv_rows_ending_in_separators_the_header_lacks_read_as_the_header_says(tmp_path, extra):
    """Spreadsheets end each row with a separator; pandas once took the rows' first field for an
    index and read the marker names as frame numbers."""
    text, path = _long_csv(tmp_path)
    path.write_text(text)
    expected = read(path).markers
    path.write_text(_with_trailing_separators(text, extra))
    recording = read(path)
    assert recording.labels == ("A", "B") and recording.first_frame == 0
    np.testing.assert_array_equal(recording.markers, expected)


@pytest.mark.parametrize(("extra", "column", "text"), [(",7", 6, "7"), (",,0.5", 7, "0.5")])
def test_a_csv_value_past_the_headers_columns_is_refused_naming_line_and_column(
    tmp_path, extra, column, text
):
    """The values written past the named columns once shifted every column by one (decimal
    commas, say: ``1,5`` for 1.5) or were dropped unseen."""
    written, path = _long_csv(tmp_path)
    path.write_text(_with_trailing_separators(written, extra))
    with pytest.raises(ValueError) as error:
        read(path)
    assert str(error.value) == (
        f"{path}: line 2, column {column}: {text!r} lies past the header's 5 columns (frame, "
        "marker, x, y, z); name its column in the header, or remove it (a decimal comma "
        "splits a number in two: write 1.5, not 1,5)"
    )


def test_header_only_csv_is_one_line(tmp_path, capsys):
    path = tmp_path / "empty.csv"
    path.write_text("frame,marker,x,y,z\n")
    code, _, err = run(capsys, "inspect", str(path))
    assert (
        code == 2
        and err.strip() == f"jointbench: {path}: no samples: the file has a header but no data rows"
    )


def test_csv_frame_absent_for_every_marker_stays_a_frame_of_gaps(tmp_path):
    markers, center = sphere_markers()
    table = long_table(markers)
    table["frame"] += 18
    path = tmp_path / "hole.csv"
    table[table["frame"] != 40].to_csv(path, index=False)
    recording = read(path)
    assert recording.first_frame == 18 and recording.n_frames == 60
    assert np.isnan(recording.markers[22]).all() and not np.isnan(recording.markers[21]).any()
    fitted = prepare(recording, "center", ["0", "1", "2"]).fit("NM")
    assert fitted.n_gap_frames == 1 and 40 not in fitted.frames_used
    assert fitted.frames_used[0] == 18 and fitted.frames_used[-1] == 77
    np.testing.assert_allclose(fitted.result.center, center, atol=1e-6)


def test_messages_and_frame_ranges_use_the_files_frame_numbers(tmp_path):
    markers = swapped(rig_recording(), 150, "D1", "D2").markers
    table = long_table(markers)
    table["frame"] += 18
    table["marker"] = np.array(PROX + DIST)[table["marker"]]
    path = tmp_path / "swap.csv"
    table.to_csv(path, index=False)
    recording = read(path)
    with pytest.raises(ValueError, match="exchange labels at frame 168; frames 18 to 167, 168 to"):
        prepare(recording, "center", DIST, PROX)
    fitted = prepare(recording, "center", DIST, PROX, frames="18:168").fit("LS")
    assert (fitted.frames_used[0], fitted.frames_used[-1]) == (18, 167)
    with pytest.raises(ValueError, match="frames '0:100' do not fit the recording, frames 18 to"):
        recording.frames("0:100")


def test_inspect_shows_units_and_the_first_frame_number(capsys):
    code, out, _ = run(capsys, "inspect", str(KNEE), "--format", "json")
    summary = json.loads(out)
    assert code == 0 and summary["first_frame"] == 100 and summary["last_frame"] == 1021
    assert summary["units_in_file"] == "mm" and summary["units"] == "mm"
    code, out, _ = run(capsys, "inspect", str(KNEE))
    assert "922 frames (numbered 100 to 1021 as in the file)" in out and "units mm" in out


# --- label swaps ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def knee_swapped():
    """The knee trial with RLFE and RMFE exchanged from row 300 (frame 400) to the end: the
    swapped labelling holds two thirds of the frames."""
    knee = read(KNEE)
    markers = knee.markers.copy()
    i, j = knee.index(["RLFE", "RMFE"])
    markers[300:, [i, j]] = markers[300:, [j, i]]
    return Recording(knee.labels, markers, knee.rate_hz, knee.source, knee.first_frame)


def test_a_swap_held_by_most_frames_is_named_where_it_happens(knee_swapped):
    with pytest.raises(ValueError) as error:
        prepare(knee_swapped, "joint_center", SHANK, THIGH)
    message = str(error.value)
    assert "markers RLFE and RMFE exchange labels at frame 400 (4.00 s)" in message
    assert "frames 100 to 399, 400 to 1021" in message
    assert "frames='100:400' or '400:1022'" in message
    for side in ("100:400", "400:1022"):
        assert prepare(knee_swapped, "joint_center", SHANK, THIGH, frames=side).found == ()


def excluded(recording: Recording, order: np.ndarray, **kwargs) -> set[int]:
    """Rows of ``recording`` (in its own order) that exclude mode leaves out of a fit of the
    frames taken in ``order``."""
    shuffled = Recording(recording.labels, recording.markers[order], 100.0, "order")
    with pytest.warns(UserWarning, match="left out"):
        prepared = prepare(shuffled, artefacts="exclude", **kwargs)
    return set(order.tolist()) - set(order[prepared.usable].tolist())


def test_exclude_mode_leaves_out_the_same_frames_in_any_order():
    recording = swapped(rig_recording(artefact_mm=1.0), 130, "D1", "D3")
    frames = np.arange(recording.n_frames)
    orders = [frames, frames[::-1], np.random.default_rng(2).permutation(frames)]
    found = [excluded(recording, o, kind="center", moving=DIST, reference=PROX) for o in orders]
    assert found[0] == set(range(130, 200)) and found[1] == found[0] and found[2] == found[0]
    # A marker outside a cluster can only jump, which takes time order; reversed, the same
    # step leaves out the same two frames.
    markers = rig_recording(artefact_mm=1.0).markers.copy()
    markers[90:, 3] += np.array([0.0, 0.0, 119.0])
    loose = Recording(recording.labels, markers, 100.0, "loose")
    found = [excluded(loose, o, kind="center", moving=["D1"], reference=PROX) for o in orders[:2]]
    assert found[0] == found[1] == {89, 90}


# --- arrays -----------------------------------------------------------------------------------


def test_array_fits_screen_like_files():
    markers = swapped(rig_recording(artefact_mm=1.0), 150, "P1", "P2").markers
    proximal, distal = markers[:, :3], markers[:, 3:]
    message = r"^proximal\[:, 0\] and proximal\[:, 1\] exchange labels at frame 150"
    with pytest.raises(ValueError, match=message):
        jointbench.fit_joint_center(proximal, distal)
    with pytest.raises(ValueError, match=r"Fit one side \(proximal\[0:150\] or proximal\[150"):
        jointbench.fit_joint_center(proximal, distal, method="SCoRE")
    with pytest.warns(UserWarning, match=r"artefacts in the data: proximal\[:, 0\] and"):
        warned = jointbench.fit_joint_center(proximal, distal, artefacts="warn")
    ignored = jointbench.fit_joint_center(proximal, distal, artefacts="ignore")
    np.testing.assert_array_equal(warned.center, ignored.center)
    found = jointbench.screen(proximal, distal)
    assert [swap.labels for swap in found["proximal"].swaps] == [
        ("proximal[:, 0]", "proximal[:, 1]")
    ]
    assert found["distal"].artefacts == ()
    clean = rig_recording().markers
    assert jointbench.fit_joint_center(clean[:, :3], clean[:, 3:]).status == "ok"


@pytest.mark.parametrize("kind", ["center", "axis", "joint_center"])
def test_warned_artefacts_are_in_the_result_not_only_a_python_warning(kind):
    """A result read or saved without its Python warnings still says the data held artefacts."""
    markers = swapped(rig_recording(artefact_mm=1.0), 150, "P1", "P2").markers
    arrays = (markers[:, :3], markers[:, 3:]) if kind == "joint_center" else (markers[:, :3],)
    fit = {
        "center": jointbench.fit_center,
        "axis": jointbench.fit_axis,
        "joint_center": jointbench.fit_joint_center,
    }[kind]
    name = "proximal" if kind == "joint_center" else "markers"
    with pytest.warns(UserWarning, match="artefacts in the data") as caught:
        warned = fit(*arrays, artefacts="warn")
    said = str(caught[0].message)
    assert f"warning: {said}" in warned.status
    assert f"data: {name}[:, 0] and {name}[:, 1] exchange labels at frame 150" in warned.status
    found = warned.diagnostics["artefacts"]
    assert found and min(a["frame"] for a in found) == 150
    assert all(a["label"].startswith(f"{name}[:, ") for a in found)
    ignored = fit(*arrays, artefacts="ignore")
    assert "artefacts" not in ignored.status and "artefacts" not in ignored.diagnostics
    assert warned.converged == ignored.converged


def test_a_broken_frame_is_blamed_on_the_marker_that_leaves_the_shape_most():
    """One corrupt sample pulls the frame's pose fit, so every marker of the frame may cross the
    level: the message names the one that departs most, not the first column."""
    markers = prepare(rig_recording(artefact_mm=1.0), "center", DIST, PROX).arrays[0].copy()
    markers[-1, 2, 2] /= 10.0  # a cut last sample: 268 read as 26
    found = jointbench.screen(markers)["markers"].artefacts
    assert len({a.label for a in found if a.frame == len(markers) - 1}) > 1
    with pytest.raises(ValueError, match=r"^markers\[:, 2\] leaves its cluster"):
        jointbench.fit_center(markers, method="LS")


def test_array_fit_of_one_marker_refuses_its_jump():
    markers = rig_recording(artefact_mm=1.0)
    moving = prepare(markers, "center", DIST, PROX).arrays[0][:, :1].copy()
    moving[90:] += np.array([0.0, 0.0, 119.0])
    with pytest.raises(ValueError, match=r"^markers\[:, 0\] jumps 11\d\.\d mm at frame 90"):
        jointbench.fit_center(moving, method="LS")
    with pytest.raises(ValueError, match="artefacts must be one of refuse, warn, ignore"):
        jointbench.fit_center(moving, artefacts="exclude")


def test_knee_arrays_with_the_swap_are_refused(knee_swapped):
    thigh, shank = knee_swapped.select(THIGH), knee_swapped.select(SHANK)
    with pytest.raises(ValueError, match=r"^proximal\[.* exchange labels at frame 300"):
        jointbench.fit_joint_center(thigh, shank, method="SCoRE")


# --- the command line -------------------------------------------------------------------------


def test_joint_center_json_says_which_point_and_gives_both(tmp_path, capsys):
    path = write_c3d(tmp_path / "rig.c3d", PROX + DIST, rig_recording(artefact_mm=2.0).markers)
    segments = ["--reference", ",".join(PROX), "--moving", ",".join(DIST), "--format", "json"]
    code, out, _ = run(capsys, "fit", str(path), "--kind", "joint_center", "--method", "SCoRE",
                       *segments)  # fmt: skip
    (joint,) = json.loads(out)
    assert code == 0 and "anchor frame" in joint["center_is"]
    proximal, distal = np.array(joint["center_proximal_mm"]), np.array(joint["center_distal_mm"])
    np.testing.assert_allclose(joint["center_mm"], (proximal + distal) / 2, atol=1e-9)
    assert np.linalg.norm(proximal - distal) > 0.1  # two different points, both reported
    code, out, _ = run(capsys, "fit", str(path), "--kind", "center", "--method", "SCoRE", *segments)
    (center,) = json.loads(out)
    assert "fixed in the reference segment" in center["center_is"]
    np.testing.assert_allclose(center["center_mm"], in_frame(JOINT, PROXIMAL), atol=3.0)


def test_method_all_runs_what_can_run_and_says_why_the_rest_did_not(tmp_path, capsys):
    path = write_c3d(tmp_path / "rig.c3d", PROX + DIST, rig_recording(artefact_mm=1.0).markers)
    arguments = ["fit", str(path), "--reference", ",".join(PROX), "--moving", "D1"]
    code, out, err = run(capsys, *arguments, "--method", "all", "--format", "csv")
    table = pd.read_csv(pd.io.common.StringIO(out)).set_index("method")
    assert code == 0 and list(table.index) == list(jointbench.methods("center"))
    assert table.loc["MA", "status"].startswith("failed: markers has 1 markers")
    # One moving marker: NM answers, and says what it could not verify (no pose).
    assert table.loc["NM", "status"].startswith("warning: not verified") and "MA did not run" in err
    # No SD is stated (a failed method, or one marker: no centre's precision), and the flag
    # says so in every row.
    assert "sd_mm" not in table and table["sd_stated"].dtype == bool
    assert not table["sd_stated"].any()
    code, out, _ = run(capsys, *arguments, "--method", "all", "--frames", "1:4", "--format", "json")
    assert code == 2 and all(f["status"].startswith("failed") for f in json.loads(out))
    assert not any(f["sd_stated"] for f in json.loads(out))
