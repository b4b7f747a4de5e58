"""Files a lab meets that are not what their name or header says: a binary file under a text
extension or a text file zero-filled past a cut, a Vicon Nexus export, a C3D of more or fewer
frames than its header and parameters count, one with no markers, a rate no recording has, a
TRC whose times leave its rate, labels written twice or mistyped, one frame to fit, and an
output path that cannot be written: each refused naming the file and what is wrong with it."""

from __future__ import annotations

import struct

import ezc3d
import numpy as np
import pytest
from test_cli import run
from test_io_recordings import KNEE, write_c3d

from jointbench.io import read

THIGH = "RTHI1,RTHI2,RTHI3,RGT"
SHANK = "RLEG1,RLEG2,RLEG3,RATT,RLM,RSPH"


def _refusal(path) -> str:
    """The message of the ``ValueError`` reading ``path`` raises."""
    with pytest.raises(ValueError) as error:
        read(path)
    return str(error.value)


@pytest.mark.parametrize(
    ("name", "content", "what"),
    [
        ("knee.csv", None, "CSV text: its first bytes are a C3D file's; name it .c3d"),
        ("knee.trc", None, "TRC text: its first bytes are a C3D file's; name it .c3d"),
        (
            "markers.csv",
            b"PK\x03\x04\x14\x00\x00\x00frame,marker,x,y,z\n",  # a zip, as .xlsx is
            "CSV text: byte 2 is 0x03, a control character no text holds (a spreadsheet, or "
            "another program's own format? export it as CSV)",
        ),
    ],
    ids=["c3d-as-csv", "c3d-as-trc", "zip-as-csv"],
)
def test_a_binary_file_under_a_text_extension_is_named_as_binary(tmp_path, name, content, what):
    """Read as text, a C3D's bytes (``content`` None: the knee trial's) were refused as "not
    UTF-8 text; save the file as UTF-8", a remedy no binary file takes."""
    path = tmp_path / name
    path.write_bytes(KNEE.read_bytes() if content is None else content)
    assert _refusal(path) == f"{path}: a binary file, not {what}"


@pytest.mark.parametrize("end", ["inside a line", "at a line's end"])
def test_a_text_file_ending_in_zero_bytes_is_refused_as_cut_short(tmp_path, end):
    """A file a crash or a full disk left short, its end filled with zero bytes, is no binary
    file: it was named one, and with the zeros after a line's end it would read as a shorter
    recording if they were dropped."""
    path = tmp_path / "markers.csv"
    text = b"frame,marker,x,y,z\n0,A,1,2,3\n1,A,2,3,4\n"
    cut = len(text) - (3 if end == "inside a line" else 0)
    path.write_bytes(text[:cut] + bytes(1000))
    line = 3 if end == "inside a line" else 4
    assert _refusal(path) == (
        f"{path}: the file ends in 1000 zero bytes, from byte {cut} (line {line}) on: it was cut "
        "short there and filled with zeros, as a crash or a full disk leaves a file"
    )


def test_a_utf16_text_file_is_refused_as_text_not_in_utf8(tmp_path):
    path = tmp_path / "markers.csv"
    path.write_text("frame,marker,x,y,z\n0,A,1,2,3\n", encoding="utf-16")
    with pytest.raises(ValueError, match="is not UTF-8 text; save the file as UTF-8"):
        read(path)


def test_text_with_tabs_and_line_ends_is_text(tmp_path):
    path = tmp_path / "markers.csv"
    path.write_bytes(b"frame,marker,x,y,z\r\n0,A,1,2,3\r\n\t\r\n")
    assert read(path).labels == ("A",)


@pytest.mark.parametrize(
    ("name", "content"),
    [
        ("markers.csv", b"frame,marker,x,y,z\r\n0,A,1,2,3\r\n1,A,1,2,4\r\n"),
        ("markers.csv", b"frame,marker,x,y,z\r\n0,A,1,2,3\r\n1,A,1,2,\r\n"),  # a gap
        (
            "markers.trc",
            b"PathFileType\t4\t(X/Y/Z)\tt.trc\r\nDataRate\tCameraRate\tNumFrames\tNumMarkers"
            b"\tUnits\r\n100\t100\t2\t1\tmm\r\nFrame#\tTime\tA\t\t\r\n\t\tX1\tY1\tZ1\r\n"
            b"1\t0\t1\t2\t3\r\n2\t0.01\t1\t2\t4\r\n",
        ),
    ],
    ids=["csv", "csv-gap", "trc"],
)
def test_a_dos_end_of_file_mark_ends_the_text(tmp_path, name, content):
    """A file some DOS programs end with 0x1a reads as the text before it, not as a last line
    cut short."""
    plain, marked = tmp_path / name, tmp_path / f"dos-{name}"
    plain.write_bytes(content)
    marked.write_bytes(content + b"\x1a")
    np.testing.assert_array_equal(read(marked).markers, read(plain).markers)


def _long_c3d(path, n_frames, added=()):
    """A C3D of ``n_frames`` > 65535 frames of eight markers (128 bytes a frame, so that the
    frames end a 512-byte block), as ezc3d writes it: its header and ``POINT:FRAMES`` stop at
    65535, and no ``TRIAL`` group counts the rest unless ``added`` (:func:`write_c3d`)."""
    rng = np.random.default_rng(3)
    markers = rng.uniform(10.0, 100.0, size=(n_frames, 8, 3))
    return write_c3d(path, tuple("ABCDEFGH"), markers, added=added)


@pytest.mark.parametrize(
    "added",
    [(), [("TRIAL", "ACTUAL_START_FIELD", [1, 0]), ("TRIAL", "ACTUAL_END_FIELD", [4464, 1])]],
    ids=["counted-by-none", "counted-by-trial"],
)
def test_a_c3d_of_more_frames_than_were_read_is_refused(tmp_path, added):
    """ezc3d read its first 65535 frames and nothing said that 4465 more were left unread; it
    reads no more where the file's TRIAL group counts all 70000, which the refusal does not
    deny."""
    path = _long_c3d(tmp_path / "long.c3d", 70000, added)
    refusal = (
        f"{path}: the file holds 572032 bytes past the 65535 frames read, room for 4465 to 4469 "
        "more frames of 8 points and 0 analog samples each (a C3D's header counts at most 65535 "
        "frames, and frames past those its header and POINT:FRAMES count are not read, whatever "
        "its POINT:LONG_FRAMES or TRIAL:ACTUAL_END_FIELD say): frames from 65536 on would be "
        "left out unread; export the trial as TRC, or in parts"
    )
    assert _refusal(path) == refusal


def test_a_c3d_of_65535_frames_reads(tmp_path):
    path = _long_c3d(tmp_path / "long.c3d", 65535)
    assert read(path).n_frames == 65535


def test_a_c3d_of_65535_frames_or_more_cut_short_is_refused(tmp_path):
    """Its header's last frame, 65535, is the most a header counts, and was taken to promise
    nothing: the file cut in half read as its first 32762 frames."""
    path = _long_c3d(tmp_path / "long.c3d", 65535)
    content = path.read_bytes()
    path.write_bytes(content[: len(content) // 2])
    assert _refusal(path) == (
        f"{path}: truncated C3D file: its header promises frames 1 to 65535 or more (65535 "
        "frames or more) of 8 points and 0 analog samples each (8390016 bytes or more), but the "
        "file has 4195072 bytes: 32762 complete frames; copy the file again from where it was "
        "recorded, or export it again"
    )


def test_a_c3d_without_markers_is_named_as_such_by_fit(tmp_path, capsys):
    """An analog-only C3D (force plates, EMG): fit answered "no marker labels given", as if the
    command had named none."""
    c3d = ezc3d.c3d()
    c3d["parameters"]["POINT"]["RATE"]["value"] = [100.0]
    c3d["parameters"]["ANALOG"]["RATE"]["value"] = [1000.0]
    c3d["parameters"]["ANALOG"]["LABELS"]["value"] = ["Fx", "Fy"]
    c3d["data"]["points"] = np.ones((4, 0, 50))
    c3d["data"]["analogs"] = np.random.default_rng(0).random((1, 2, 500))
    path = tmp_path / "forces.c3d"
    c3d.write(str(path))
    assert read(path).labels == ()
    code, _, err = run(capsys, "fit", str(path))
    assert code == 2
    assert err == (
        f"jointbench: {path}: the file holds no markers (no 3D points: only analog channels?); "
        "a fit needs marker trajectories\n"
    )


@pytest.mark.parametrize("where", ["missing folder", "folder"])
def test_a_world_output_that_cannot_be_written_is_refused_before_the_fit(tmp_path, capsys, where):
    """The path was tried after the fit: the fit's time was lost, and its table with it, to
    "Cannot save file into a non-existent directory", which named no option."""
    world = tmp_path / "absent" / "world.csv" if where == "missing folder" else tmp_path
    missing = tmp_path / "absent.c3d"  # read after the output is checked: never reached
    code, out, err = run(capsys, "fit", str(missing), "--world", str(world))
    assert (code, out) == (2, "")
    reason = (
        f"its folder {tmp_path / 'absent'} does not exist"
        if where == "missing folder"
        else "it is a folder"
    )
    assert err == f"jointbench: --world {world}: cannot be written: {reason}\n"


def test_a_world_output_in_an_existing_folder_is_written(tmp_path, capsys):
    world = tmp_path / "world.csv"
    code, _, _ = run(
        capsys, "fit", str(KNEE), "--reference", THIGH, "--moving", SHANK, "--world", str(world)
    )
    assert code == 0
    assert world.read_text().startswith("frame,method,x_mm,y_mm,z_mm\n100,NM,")


def _timed_trc(path, times, rate="100"):
    """A TRC of one marker at ``DataRate`` ``rate``, its frames 1, 2, ... written at ``times``
    [s] (their text as given)."""
    text = "PathFileType\t4\t(X/Y/Z)\tt.trc\nDataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\n"
    text += f"{rate}\t{rate}\t{len(times)}\t1\tmm\nFrame#\tTime\tA\t\t\n\t\tX1\tY1\tZ1\n"
    text += "".join(f"{i + 1}\t{t}\t{i}.5\t1.5\t2.5\n" for i, t in enumerate(times))
    path.write_text(text)
    return path


def test_trc_frames_not_at_the_headers_rate_are_refused_naming_the_line(tmp_path):
    """Two recordings joined, the second at 200 Hz under the first's 100 Hz, read as one of
    100 Hz: their Time column, which said otherwise, was not read."""
    times = [f"{i / 100:.3f}" for i in range(50)] + [f"{0.49 + i / 200:.3f}" for i in range(1, 51)]
    path = _timed_trc(tmp_path / "joined.trc", times)
    assert _refusal(path) == (
        f"{path}: line 57, field Time: 0.500 s, where frame 52 falls at 0.51 s at the header's "
        "DataRate of 100 Hz (frame 1 at 0.000 s, line 6): the frames are not at that rate; a "
        "wrong DataRate, or recordings of different rates joined?"
    )


@pytest.mark.parametrize(
    ("first", "refused"),
    [
        ("0.00000", r"line 9, field Time: 0.03000 s, where frame 4 falls"),
        ("", r"line 10, field Time: 0.04000 s, where frame 5 falls"),  # frame 2 at 0.01 s
    ],
    ids=["timed", "first-time-empty"],
)
def test_a_trc_data_rate_its_times_do_not_keep_is_refused(tmp_path, first, refused):
    """Times are counted from the first row that writes one, which need not be the first."""
    times = [first, *(f"{i / 100:.5f}" for i in range(1, 10))]
    path = _timed_trc(tmp_path / "rate.trc", times, rate="120")
    with pytest.raises(ValueError, match=refused):
        read(path)


@pytest.mark.parametrize(
    ("times", "rate"),
    [
        ([f"{0.25 + i / 2000:.3f}" for i in range(40)], "2000"),  # rounded to 1 ms
        ([f"{i / 100:g}" for i in range(40)], "100"),  # %g: 0, 0.01, ..., 0.39
        ([f"{i / 120:.6e}" for i in range(40)], "120"),  # exponent form
        (["", *(f"{i / 100}" for i in range(1, 40))], "100"),  # a time not written
        ([f"{i / 100:.2f}" for i in range(40)], ""),  # no DataRate: no rate to keep
        (["0"] * 40, "100"),  # a writer that leaves the column unfilled
        (["0.000"] * 40, "100"),
    ],
    ids=["rounded", "%g", "exponent", "empty", "no rate", "unfilled", "unfilled-decimals"],
)
def test_trc_times_at_the_headers_rate_as_written_read(tmp_path, times, rate):
    assert read(_timed_trc(tmp_path / "t.trc", times, rate)).n_frames == 40


@pytest.mark.parametrize(
    ("asked", "close"),
    [
        ("RTH1,RLEG1", "close to 'RTH1': 'RTHI1'"),
        ("RGTR,RTIB1", "close to 'RGTR': 'RGT'; close to 'RTIB1': 'RTHI1'"),
    ],
)
def test_a_label_missing_from_the_file_is_shown_its_close_matches(asked, close):
    """A mistyped label was answered with the file's 73 labels to search by eye."""
    with pytest.raises(ValueError) as error:
        read(KNEE).select(asked)
    assert str(error.value).endswith(f"RLEG1, RLEG2, RLEG3; {close}")


def test_a_label_with_no_close_match_is_shown_none():
    with pytest.raises(ValueError) as error:
        read(KNEE).select("RKNE")
    assert str(error.value).endswith("RLEG1, RLEG2, RLEG3")


def test_a_world_output_onto_the_recording_read_is_refused(tmp_path, capsys):
    """The recording was overwritten by the trajectory written after the fit."""
    path = tmp_path / "knee.c3d"
    path.write_bytes(KNEE.read_bytes())
    world = tmp_path / "." / "knee.c3d"
    code, out, err = run(
        capsys, "fit", str(path), "--reference", THIGH, "--moving", SHANK, "--world", str(world)
    )
    assert (code, out) == (2, "")
    assert err == f"jointbench: --world {world}: cannot be written: it is the recording read\n"
    assert path.read_bytes() == KNEE.read_bytes()


@pytest.mark.parametrize("first", ["Trajectories\n", "Trajectories,,,,,,,\r\n"])
def test_a_vicon_nexus_csv_export_is_named_as_such(tmp_path, first):
    """pandas' "Error tokenizing data. C error: Expected 1 fields in line 3, saw 8" was all a
    lab's commonest CSV was answered with; Nexus on Windows ends its lines with CR LF, and some
    exports fill the first line with the separators of the rows below."""
    path = tmp_path / "trial.csv"
    path.write_bytes(
        first.encode() + b"100\n,,Sub01:A,,,Sub01:B,,\nFrame,Sub Frame,X,Y,Z,X,Y,Z\n"
        b",,mm,mm,mm,mm,mm,mm\n1,0,1.5,2.5,3.5,4.5,5.5,6.5\n"
    )
    assert _refusal(path) == (
        f"{path}: line 1, 'Trajectories': a Vicon Nexus CSV export (sections of one row per "
        "frame, three columns per marker), not the CSV jointbench reads (one row per frame and "
        "marker: frame, marker, x, y, z); export the trial as C3D or TRC"
    )


def test_a_csv_of_one_row_per_frame_is_shown_the_layout_read(tmp_path):
    path = tmp_path / "wide.csv"
    path.write_text("frame,A_x,A_y,A_z\n0,1.5,2.5,3.5\n")
    assert _refusal(path) == (
        f"{path}: missing columns ['marker', 'x', 'y', 'z']; the header names ['frame', 'A_x', "
        "'A_y', 'A_z']; jointbench reads one row per frame and marker: frame, marker, x, y, z "
        "[mm]"
    )


def test_a_label_written_twice_is_refused_naming_both_markers(tmp_path):
    """Two trajectories under one label were refused as "marker label 'X' appears twice",
    naming neither marker. (Empty labels, which some writers leave on unlabelled
    trajectories, are refused as points without a label, before they are compared.)"""
    markers = np.random.default_rng(0).uniform(10.0, 100.0, size=(20, 4, 3))
    path = write_c3d(tmp_path / "twice.c3d", ["A", "X", "X", "B"], markers)
    assert _refusal(path) == (
        f"{path}: markers 2 and 3 (of 4) are both labelled 'X'; each marker needs a label of its "
        "own (relabel them, or export the trial without unlabelled trajectories)"
    )


@pytest.mark.parametrize("kind", ["center", "axis"])
def test_one_frame_to_fit_is_refused_as_one_frame(capsys, kind):
    """A range of one frame was refused as markers that "do not move: every marker stays at
    one point in every frame", of markers the trial shows moving."""
    code, _, err = run(
        capsys, "fit", str(KNEE), "--kind", kind, "--reference", THIGH, "--moving", SHANK,
        "--frames", "500:501",
    )  # fmt: skip
    assert code == 2
    assert err.endswith(": markers has 1 frame: no motion to fit a centre or an axis to\n")


def _c3d_at_rate(path, rate):
    """A C3D of three markers whose ``POINT:RATE`` and header rate are ``rate`` [Hz] (0 or
    negative: ezc3d writes none such, so both floats are set in the file)."""
    markers = np.random.default_rng(0).uniform(10.0, 100.0, size=(20, 3, 3))
    content = bytearray(write_c3d(path, ("A", "B", "C"), markers).read_bytes())
    # A parameter: its group (POINT is 1), its name, the offset to the next (2 bytes), its
    # type (4: float), its dimensions (0: a scalar) and then its value.
    value = content.index(b"\x01RATE\t\x00\x04\x00") + 9
    content[value : value + 4] = struct.pack("<f", rate)
    content[20:24] = struct.pack("<f", rate)  # the header's 11th and 12th words
    path.write_bytes(bytes(content))
    return path


def test_a_c3d_frame_rate_of_0_is_no_rate_stated(tmp_path):
    assert read(_c3d_at_rate(tmp_path / "rate.c3d", 0.0)).rate_hz is None


@pytest.mark.parametrize(("rate", "written"), [(-100.0, "-100"), (np.inf, "inf")])
def test_a_negative_or_infinite_c3d_frame_rate_is_refused_naming_it(tmp_path, rate, written):
    """It was read as a rate not stated, as 0 is; an infinite one was refused as the
    recording's rate, not naming the file's POINT:RATE."""
    path = _c3d_at_rate(tmp_path / "rate.c3d", rate)
    assert _refusal(path) == f"{path}: POINT:RATE {written} is not a frame rate (frames per second)"
