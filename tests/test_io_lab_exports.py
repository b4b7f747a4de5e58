"""What lab exporters write that a reader must not take at its word: warnings that name the
line that called the reader (not the reader's own), and a C3D whose ``POINT:SCALE`` and
header disagree on how its coordinates are stored."""

from __future__ import annotations

import struct
import warnings

import numpy as np
import pytest
from test_io_recordings import DIST, KNEE, PROX, rig_recording, swapped, write_c3d
from test_io_units import write
from test_io_unstated_and_padded import _c3d_without_units

import jointbench
from jointbench.io import Recording, fit, prepare, read_c3d


def _markers(n_frames=20, n_markers=3, seed=0):
    """Markers ``(n_frames, n_markers, 3)`` [mm] about a metre from the lab's origin, each
    moving up to 160 mm a frame: far from it for any motion of theirs."""
    return np.random.default_rng(seed).uniform(1000.0, 1090.0, size=(n_frames, n_markers, 3))


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


def _integers_under_a_negative_scale(path):
    """A C3D of three markers, 20 frames, whose frames are 16-bit integers (1 mm a step, padded
    to the 512-byte block) under the POINT:SCALE of -1 ezc3d writes, which says floats."""
    markers = np.round(_markers())
    content = write_c3d(path, "ABC", markers).read_bytes()
    start = (struct.unpack("<H", content[16:18])[0] - 1) * 512
    assert struct.unpack("<f", content[12:16])[0] == -1.0
    words = np.zeros((20, 3, 4), "<i2")
    words[..., :3] = markers
    frames = words.tobytes()
    path.write_bytes(content[:start] + frames + bytes(-len(frames) % 512))
    return path


def test_a_c3d_of_integers_under_a_negative_scale_is_not_only_said_cut_short(tmp_path):
    """It was refused as cut short only, to be copied again: a copy is as short."""
    path = _integers_under_a_negative_scale(tmp_path / "integers.c3d")
    assert _refusal(path) == (
        f"{path}: truncated C3D file: its header promises frames 1 to 20 (20 frames) of 3 points "
        "and 0 analog samples each (2496 bytes), but the file has 2048 bytes: 10 complete "
        "frames; copy the file again from where it was recorded, or export it again; or, as "
        "the file ends where its frames end as 16-bit integers (or at the end of that 512-byte "
        "block), they are integers under a POINT:SCALE of -1 that says floats: export the "
        "trial again (its POINT:SCALE positive, for integers)"
    )


def test_the_knee_trial_reads_as_before():
    markers = jointbench.read(KNEE).markers
    assert np.isfinite(markers).all()
    assert markers[0, 0].tolist() == [575.7947998046875, 604.501953125, 1678.9611816406250]


# --- a marker at exactly (0, 0, 0) -------------------------------------------------------------


def _through_the_origin(n_frames=20):
    """Three markers ``(n_frames, 3, 3)`` [mm]: A passes through the lab's origin at row 10,
    0.5 mm a frame along each axis (exactly (0, 0, 0) there), B and C far from it."""
    markers = _markers(n_frames)
    markers[:, 0] = 0.5 * (np.arange(n_frames) - 10.0)[:, None]
    return markers


@pytest.mark.parametrize("suffix", [".c3d", ".trc", ".csv"])
def test_a_marker_at_the_origin_between_samples_far_from_it_is_a_gap_named(tmp_path, suffix):
    """It was read as missing without a word (the fit then leaves out its frames unsaid)."""
    markers = _markers()
    markers[[4, 5, 6, 12], 1] = 0.0
    path = write(tmp_path / f"trial{suffix}", "ABC", markers, "mm")
    first = 0 if suffix == ".csv" else 1
    caught = _caught(jointbench.read, path)
    assert [str(w.message) for w in caught] == [
        f"{path}: 4 samples at exactly (0, 0, 0) are read as missing, as gaps a writer stored as "
        "zeros (the C3D format's coordinates of an invalid point), not positions at the lab's "
        "origin: the marker's nearest sample before or after each lies farther from the origin "
        "than the marker moves in a frame nearby (or it has none): B at frames "
        f"{first + 4} to {first + 6} and {first + 12}"
    ]
    assert caught[0].filename == __file__
    recording = jointbench.read(path)
    assert np.isnan(recording.markers[[4, 5, 6, 12], 1]).all()
    assert np.isfinite(np.delete(recording.markers, [4, 5, 6, 12], axis=0)).all()


@pytest.mark.parametrize("suffix", [".c3d", ".trc", ".csv"])
def test_a_marker_passing_through_the_origin_is_kept(tmp_path, suffix):
    """Its samples on either side lie one frame's motion from the origin: it was read as a gap."""
    markers = _through_the_origin()
    path = write(tmp_path / f"trial{suffix}", "ABC", markers, "mm")
    assert _caught(jointbench.read, path) == []
    recording = jointbench.read(path)
    assert recording.markers[10, 0].tolist() == [0.0, 0.0, 0.0]
    assert np.isfinite(recording.markers).all()
    # A part of it keeps the sample too, whatever the part holds of the marker's motion.
    assert recording.frames(slice(10, 11)).markers[0, 0].tolist() == [0.0, 0.0, 0.0]


def test_a_marker_that_stops_at_the_origin_at_a_c3ds_end_is_kept(tmp_path):
    """A one-marker C3D whose marker moves to the origin and stays: it was read as frames
    zero-filled past the capture's end."""
    markers = _through_the_origin()[:, :1]
    markers[10:] = 0.0
    path = write_c3d(tmp_path / "stops.c3d", "A", markers)
    assert _caught(jointbench.read, path) == []
    assert (jointbench.read(path).markers[10:] == 0.0).all()


def test_a_marker_of_one_at_the_origin_at_a_c3ds_end_is_a_gap_named(tmp_path):
    """Far from the origin before: a writer's gap, named by its marker (with more markers it
    would be frames zero-filled past the capture's end)."""
    markers = _markers(n_markers=1)
    markers[15:] = 0.0
    path = write_c3d(tmp_path / "gap.c3d", "A", markers)
    (warning,) = _caught(jointbench.read, path)
    assert str(warning.message).endswith(
        "marker moves in a frame nearby (or it has none): A at frames 16 to 20"
    )


def _trc_warning(tmp_path, zeroed):
    """The TRC file of :func:`_markers` with the samples ``zeroed`` (an index) at (0, 0, 0), and
    the one warning reading it gives."""
    markers = _markers()
    markers[zeroed] = 0.0
    path = write(tmp_path / "trial.trc", "ABC", markers, "mm")
    (warning,) = _caught(jointbench.read, path)
    return path, str(warning.message)


def test_a_marker_never_away_from_the_origin_is_a_gap_named(tmp_path):
    """A marker a writer never saw (a labelled template's): nothing puts it at the origin."""
    path, message = _trc_warning(tmp_path, (slice(None), 2))
    assert message == (
        f"{path}: 20 samples at exactly (0, 0, 0) are read as missing, as gaps a writer stored "
        "as zeros (the C3D format's coordinates of an invalid point), not positions at the "
        "lab's origin: the marker's nearest sample before or after each lies farther from the "
        "origin than the marker moves in a frame nearby (or it has none): C at every frame "
        "(never away from the origin)"
    )
    assert np.isnan(jointbench.read(path).markers[:, 2]).all()


def test_every_marker_zero_filled_at_a_trcs_end_is_named_as_padding(tmp_path):
    """As in a C3D: a capture stopped early and padded, whatever the format."""
    path, message = _trc_warning(tmp_path, slice(15, None))
    assert message == (
        f"{path}: frames 16 to 20 (the last 5) hold every marker at exactly (0, 0, 0): frames "
        "zero-filled past the capture's end (a capture stopped early and padded, or a file cut "
        "and padded), not gaps a recording writes; they are read as missing"
    )


def test_arrays_given_a_recording_follow_the_rule_and_one_gap_is_named_so():
    markers = _markers(n_markers=2)
    markers[3, 0] = 0.0
    caught = _caught(lambda array: Recording(("A", "B"), array), markers)
    assert [str(w.message) for w in caught] == [
        "<memory>: 1 sample at exactly (0, 0, 0) is read as missing, as a gap a writer stored "
        "as zeros (the C3D format's coordinates of an invalid point), not a position at the "
        "lab's origin: the marker's nearest sample before or after it lies farther from the "
        "origin than the marker moves in a frame nearby (or it has none): A at frame 3"
    ]
    assert caught[0].filename == __file__


@pytest.mark.parametrize("call", ["prepare", "fit"])
def test_the_artefact_warning_names_the_line_that_called_prepare_or_fit(call):
    """Called as prepare(), it named the line above the caller's (pytest's own)."""
    recording = swapped(rig_recording(), 150, "D1", "D3")
    function = {"prepare": prepare, "fit": fit}[call]
    options = {"method": "SCoRE"} if call == "fit" else {}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        function(recording, "joint_center", DIST, PROX, artefacts="exclude", **options)
    (warning,) = [w for w in caught if "left out 50 frames with artefacts" in str(w.message)]
    assert warning.filename == __file__


@pytest.mark.parametrize("spike", [3, 11], ids=["elsewhere", "next-to-the-gap"])
def test_a_gap_at_the_origin_is_not_kept_for_an_artefacts_jump(tmp_path, spike):
    """One sample of B 2 m off (a ghost labelled B), elsewhere in the trial or just before B's
    gap of zeros: its jump of 2 m a frame was taken as B's motion, which reaches the origin
    from anywhere, and the gap was kept as three samples at the lab's origin, without a word."""
    markers = _markers()
    markers[spike, 1] += 2000.0
    markers[12:15, 1] = 0.0
    path = write(tmp_path / "trial.trc", "ABC", markers, "mm")
    (warning,) = _caught(jointbench.read, path)
    assert str(warning.message).endswith(
        "marker moves in a frame nearby (or it has none): B at frames 13 to 15"
    )
    assert np.isnan(jointbench.read(path).markers[12:15, 1]).all()


def _cluster_through_the_origin(n_frames=120):
    """Three markers ``(n_frames, 3, 3)`` [mm] of a segment swinging about a centre 300 mm off,
    shifted so that A is at exactly (0, 0, 0) at row 60: A passes through the lab's origin."""
    angle = np.linspace(-0.6, 0.6, n_frames)[:, None]
    tilt = 0.4 * np.cos(np.linspace(0.0, 2 * np.pi, n_frames))[:, None]
    local = np.array([[300.0, 0.0, 0.0], [300.0, 40.0, 0.0], [300.0, 0.0, 40.0]])
    x, y, z = local[:, 0], local[:, 1], local[:, 2]
    swung = np.stack(
        [
            np.cos(angle) * x - np.sin(angle) * y,
            np.sin(angle) * x + np.cos(angle) * y,
            z + tilt * x,
        ],
        axis=-1,
    )
    return swung - swung[60, 0]


def test_a_sample_kept_at_the_origin_is_refused_by_a_fit_saying_what_to_do():
    """The estimators' input checks refuse every sample at exactly (0, 0, 0) as a possible gap:
    a fit without a reference refused A's at frame 60, kept by the Recording, with the advice
    to fit a Recording, which it was."""
    recording = Recording(("A", "B", "C"), _cluster_through_the_origin(), 100.0, "wand.trc")
    assert recording.markers[60, 0].tolist() == [0.0, 0.0, 0.0]
    with pytest.raises(ValueError) as error:
        fit(recording, "center", "A,B,C")
    assert str(error.value) == (
        "wand.trc: A is at exactly (0, 0, 0) at frame 60 (0.60 s), read as a position (its "
        "samples on either side lie within its motion of the lab's origin), which the fits "
        "refuse as a possible gap stored as zeros: name a --reference segment (reference=), in "
        "whose frame the markers are fitted, or fit frames without it (frames='0:60' or "
        "'61:120')"
    )
    # Frames without it are fitted.
    assert fit(recording, "center", "A,B,C", frames="61:120").frames_used[0] == 61


def test_a_marker_with_many_gaps_at_the_origin_names_three_runs_and_counts_the_rest():
    markers = _markers(n_frames=30, n_markers=2)
    markers[[2, 3, 8, 14, 20, 26], 0] = 0.0
    (warning,) = _caught(lambda array: Recording(("A", "B"), array), markers)
    assert str(warning.message).endswith(
        "marker moves in a frame nearby (or it has none): A at frames 2 to 3, 8, 14 and 2 more runs"
    )


def test_a_recordings_markers_and_a_parts_are_read_only_and_shared():
    """A part is a view of the recording's markers, not a copy, and neither can be written."""
    recording = Recording(("A", "B", "C"), _through_the_origin())
    part = recording.frames("5:15")
    assert np.shares_memory(part.markers, recording.markers)
    for markers in (recording.markers, part.markers):
        with pytest.raises(ValueError, match="read-only"):
            markers[0, 0, 0] = 1.0


def _integers_under_a_positive_scale(path, n_frames):
    """A C3D of one marker, ``n_frames``, whose frames are 16-bit integers under a POINT:SCALE
    of 0.1 in its parameter and its header (a file as integer writers make it), the marker
    moving 0.1 mm a frame along x from 100 mm."""
    x = 100.0 + 0.1 * (np.arange(n_frames) % 1000)
    markers = np.stack([x, np.full(n_frames, 200.0), np.full(n_frames, 300.0)], -1)[:, None]
    content = bytearray(write_c3d(path, "A", markers).read_bytes())
    start = (struct.unpack("<H", content[16:18])[0] - 1) * 512
    scale = content.find(b"SCALE", content.find(b"POINT", 512)) + 9  # name, offset, type, dims
    for where in (slice(12, 16), slice(scale, scale + 4)):
        assert struct.unpack("<f", content[where])[0] == -1.0
        content[where] = struct.pack("<f", 0.1)
    words = np.zeros((n_frames, 1, 4), "<i2")
    words[..., :3] = np.round(markers / 0.1)
    frames = words.tobytes()
    path.write_bytes(bytes(content[:start]) + frames + bytes(-len(frames) % 512))
    return path


def test_an_integer_c3d_is_read_as_written(tmp_path):
    path = _integers_under_a_positive_scale(tmp_path / "integers.c3d", 300)
    markers = jointbench.read(path).markers
    assert np.allclose(markers[[0, 299], 0], [[100.0, 200.0, 300.0], [129.9, 200.0, 300.0]])


def test_an_integer_c3d_of_twice_the_frames_a_header_counts_is_refused_as_long(tmp_path):
    """Its frames past the 65535 its header counts, as many bytes again, were taken for the
    second half of frames of floats: refused as floats under a positive scale, to be exported
    again with a negative one, which it is not."""
    path = _integers_under_a_positive_scale(tmp_path / "long.c3d", 140_000)
    assert _refusal(path).startswith(
        f"{path}: the file holds 595976 bytes past the 65535 frames read, room for "
    )


def test_a_gap_of_a_marker_passing_over_the_origin_is_read_as_a_gap():
    """A moves 40 mm a frame along x, 60 mm above the lab's origin (a foot marker swinging over
    a floor origin), its sample at x = 0 a gap stored as zeros: the samples on either side lie
    72 mm from the origin, farther than it moves in a frame, though within two frames' motion."""
    markers = _markers(n_markers=2)
    markers[:, 0] = np.stack([40.0 * (np.arange(20) - 10.0), np.zeros(20), np.full(20, 60.0)], -1)
    markers[10, 0] = 0.0
    (warning,) = _caught(lambda array: Recording(("A", "B"), array), markers)
    assert str(warning.message).endswith(
        "marker moves in a frame nearby (or it has none): A at frame 10"
    )


def test_a_gap_at_the_origin_between_missing_samples_is_read_as_a_gap():
    """B unseen (NaN) for 20 frames, then one frame at (0, 0, 0), then unseen for 20 more: its
    steps of up to 156 mm a frame times the 21 frames to its samples reached the origin from
    1.8 m, and the sample was kept at the lab's origin, without a word; frames unseen say
    nothing of where a marker went."""
    markers = _markers(n_frames=60)
    markers[10:30, 1] = np.nan
    markers[30, 1] = 0.0
    markers[31:51, 1] = np.nan
    (warning,) = _caught(lambda array: Recording(("A", "B", "C"), array), markers)
    assert str(warning.message).endswith("(or it has none): B at frame 30")
