"""Recordings from files: readers, gaps, segments and technical frames, artefacts, frame order."""

from __future__ import annotations

from pathlib import Path

import ezc3d
import numpy as np
import pandas as pd
import pytest
from rigs import DISTAL, HINGE, JOINT, PROXIMAL, two_segments

import jointbench
from jointbench.geometry import angle_between_lines_deg
from jointbench.io import Recording, prepare, read
from jointbench.io.segments import technical_frame

KNEE = Path(__file__).resolve().parents[1] / "data" / "functional-trials" / "right_knee.c3d"
THIGH = "RTHI1,RTHI2,RTHI3,RGT"
SHANK = "RLEG1,RLEG2,RLEG3,RATT,RLM,RSPH"
PROX = ["P1", "P2", "P3"]
DIST = ["D1", "D2", "D3"]


def write_c3d(path, labels, markers, *, units="mm", rate=100.0, residuals=None, added=()):
    """Markers ``(n_frames, n, 3)`` in ``units`` (NaN stays NaN) to a C3D file via ezc3d, with
    the parameters ``added`` (``(group, name, value)`` each) besides its own."""
    c3d = ezc3d.c3d()
    for group, name, value in added:
        c3d.add_parameter(group, name, value)
    c3d["parameters"]["POINT"]["RATE"]["value"] = [rate]
    c3d["parameters"]["POINT"]["LABELS"]["value"] = list(labels)
    c3d["parameters"]["POINT"]["UNITS"]["value"] = [units]
    points = np.ones((4, len(labels), markers.shape[0]))
    points[:3] = np.transpose(markers, (2, 1, 0))
    c3d["data"]["points"] = points
    if residuals is not None:
        c3d["data"]["meta_points"] = {
            "residuals": np.transpose(residuals)[None],
            "camera_masks": np.zeros((7, len(labels), markers.shape[0]), dtype=bool),
        }
    c3d.write(str(path))
    return path


def in_frame(point, layout, direction=False):
    """A world-at-frame-0 point (or direction) in the technical frame of ``layout`` (n, 3)."""
    frame = technical_frame(layout, tuple(PROX), "rig")
    if direction:
        return frame[:3, :3].T @ point
    return frame[:3, :3].T @ (point - frame[:3, 3])


def rig_recording(n_frames=200, relative="ball", artefact_mm=0.0):
    """The two-segment rig, optionally with smooth marker artefact of ``artefact_mm``."""
    proximal, distal = two_segments(n_frames, relative=relative)
    markers = np.concatenate([proximal, distal], axis=1)
    if artefact_mm:
        rng = np.random.default_rng(7)
        t = np.linspace(0.0, 4.0, n_frames)[:, None, None]
        frequency = rng.uniform(0.3, 1.5, size=(1, 6, 3))
        phase = rng.uniform(0, 2 * np.pi, size=(1, 6, 3))
        markers = markers + artefact_mm * np.sin(2 * np.pi * frequency * t + phase)
    return Recording(tuple(PROX + DIST), markers, 100.0, "rig.c3d")


def reversed_recording(recording):
    return Recording(recording.labels, recording.markers[::-1], recording.rate_hz, "reversed")


# --- reading --------------------------------------------------------------------------------


def test_c3d_labels_rate_and_units_in_mm(tmp_path):
    recording = rig_recording(20)
    path = write_c3d(tmp_path / "rig.c3d", recording.labels, recording.markers / 1000.0, units="m")
    read_back = read(path)
    assert read_back.labels == recording.labels
    assert read_back.rate_hz == 100.0
    np.testing.assert_allclose(read_back.markers, recording.markers, atol=1e-3)  # float32 file


def test_gaps_stored_as_nan_zeros_or_negative_residuals_are_missing(tmp_path):
    markers = rig_recording(30).markers.copy()
    markers[3, 0] = np.nan
    markers[5, 1] = 0.0
    residuals = np.zeros(markers.shape[:2])
    residuals[7, 4] = -1.0
    path = write_c3d(tmp_path / "gaps.c3d", PROX + DIST, markers, residuals=residuals)
    recording = read(path)
    assert recording.gaps() == {"P1": 1, "P2": 1, "P3": 0, "D1": 0, "D2": 1, "D3": 0}
    assert np.isnan(recording.markers[[3, 5, 7], [0, 1, 4]]).all()


def test_trc_reader(tmp_path):
    recording = rig_recording(10)
    rows = [
        "PathFileType\t4\t(X/Y/Z)\trig.trc",
        "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits",
        "50\t50\t10\t6\tcm",
        "Frame#\tTime\t" + "\t\t\t".join(recording.labels),
        "\t\t" + "\t".join(f"X{i}\tY{i}\tZ{i}" for i in range(1, 7)),
    ]
    for frame, sample in enumerate(recording.markers / 10.0):
        values = [f"{v:.9f}" for v in sample.ravel()]
        if frame == 4:
            values[3:6] = ["", "", ""]  # P2 occluded
        rows.append(f"{frame + 1}\t{frame / 50:.3f}\t" + "\t".join(values))
    path = tmp_path / "rig.trc"
    path.write_text("\n".join(rows) + "\n")
    read_back = read(path)
    assert read_back.labels == recording.labels and read_back.rate_hz == 50.0
    assert read_back.gaps()["P2"] == 1
    expected = recording.markers.copy()
    expected[4, 1] = np.nan
    np.testing.assert_allclose(read_back.markers, expected, atol=1e-6)


def test_csv_missing_row_is_a_gap_and_a_duplicated_row_is_refused(tmp_path):
    markers = rig_recording(12).markers.copy()
    frame, marker = np.meshgrid(np.arange(12), np.arange(6), indexing="ij")
    table = pd.DataFrame({"frame": frame.ravel(), "marker": marker.ravel()})
    table[["x", "y", "z"]] = markers.reshape(-1, 3)
    path = tmp_path / "long.csv"
    table.drop(index=20).to_csv(path, index=False)  # frame 3, marker 2
    recording = read(path)
    assert recording.labels == ("0", "1", "2", "3", "4", "5")
    assert np.isnan(recording.markers[3, 2]).all()
    assert np.nansum(np.isnan(recording.markers[..., 0])) == 1
    pd.concat([table, table.iloc[[20]]]).to_csv(path, index=False)
    with pytest.raises(ValueError, match="frame 3, marker 2 has 2 rows"):
        read(path)


@pytest.mark.parametrize(
    ("name", "content", "message"),
    [
        ("absent.c3d", None, "no such file"),
        ("folder.c3d", "dir", "is a directory"),
        ("garbage.c3d", b"\xab\xcd not a c3d", "not a readable C3D file"),
        ("markers.xlsx", b"", "unknown file type '.xlsx'"),
    ],
)
def test_unreadable_files_are_named(tmp_path, name, content, message):
    path = tmp_path / name
    if content == "dir":
        path.mkdir()
    elif content is not None:
        path.write_bytes(content)
    with pytest.raises(ValueError, match=message) as error:
        read(path)
    assert name in str(error.value)


def test_unknown_label_lists_the_file_labels():
    with pytest.raises(ValueError, match=r"no marker labelled 'RASI'.*labels in the file: P1"):
        rig_recording(10).select("P1,RASI")


def test_a_label_written_with_another_case_spaces_or_a_subject_prefix_is_named():
    """Labels are matched as written; one that differs only so is shown as the file writes it,
    where the list of labels hides a trailing space."""
    markers = rig_recording(10).markers
    recording = Recording(("Sub01:P1", "p2", "P3 ", "D1", "D2", "D3"), markers, 100.0, "t.csv")
    with pytest.raises(ValueError) as error:
        recording.select("P1,P2,P3,D1")
    assert str(error.value).endswith(
        "; the file writes 'Sub01:P1' for 'P1', 'p2' for 'P2', 'P3 ' for 'P3' (labels are "
        "matched as written: case, spaces and a subject prefix count)"
    )


def test_a_label_with_no_near_match_has_no_suggestion():
    with pytest.raises(ValueError) as error:
        rig_recording(10).select("P1,RASI")
    assert "the file writes" not in str(error.value)


# --- known answers in the reference segment's technical frame -------------------------------


@pytest.mark.parametrize("method", jointbench.methods("joint_center"))
def test_joint_centre_recovered_in_the_reference_frame(method):
    fitted = prepare(rig_recording(), "joint_center", DIST, PROX).fit(method)
    np.testing.assert_allclose(fitted.result.center, in_frame(JOINT, PROXIMAL), atol=1e-8)
    assert fitted.frame["x"] == "from P1 towards P2"
    assert fitted.frame["segment"] == PROX


@pytest.mark.parametrize("method", ["LS", "NM", "SCoRE"])
def test_centre_of_the_moving_segment_recovered(method):
    fitted = prepare(rig_recording(), "center", DIST, PROX).fit(method)
    np.testing.assert_allclose(fitted.result.center, in_frame(JOINT, PROXIMAL), atol=1e-8)
    # The centre is fixed in the reference segment: its world trajectory is the joint's.
    world = fitted.world()
    _, distal = two_segments(200)
    np.testing.assert_allclose(
        np.linalg.norm(world[:, None] - distal, axis=-1),
        np.broadcast_to(np.linalg.norm(JOINT - DISTAL, axis=-1), (200, 3)),
        atol=1e-8,
    )


def test_hinge_axis_recovered_in_the_reference_frame():
    fitted = prepare(rig_recording(relative="hinge"), "axis", DIST, PROX).fit("SARA")
    direction = in_frame(HINGE, PROXIMAL, direction=True)
    assert angle_between_lines_deg(fitted.result.direction, direction) < 1e-7
    offset = fitted.result.point - in_frame(JOINT, PROXIMAL)
    np.testing.assert_allclose(np.cross(offset, direction), 0.0, atol=1e-7)


# --- gaps, artefacts ------------------------------------------------------------------------


@pytest.mark.parametrize("stored_as", [np.nan, 0.0])
def test_gaps_are_left_out_and_counted(tmp_path, stored_as):
    markers = rig_recording().markers.copy()
    markers[10:15, 4] = stored_as  # moving marker D2
    markers[40, 0] = stored_as  # reference marker P1: two markers cannot pose the segment
    from_file = prepare(
        read(write_c3d(tmp_path / "g.c3d", PROX + DIST, markers)), "center", DIST, PROX
    )
    in_memory = prepare(Recording(PROX + DIST, markers, 100.0), "center", DIST, PROX)
    for prepared in (from_file, in_memory):
        fitted = prepared.fit("NM")
        assert fitted.n_gap_frames == 6
        assert not {10, 11, 12, 13, 14, 40} & set(fitted.frames_used - fitted.first_frame)
    # A C3D file holds float32 (~1e-4 mm here); the float64 recording gives the exact centre.
    truth = in_frame(JOINT, PROXIMAL)
    np.testing.assert_allclose(from_file.fit("NM").result.center, truth, atol=1e-3)
    np.testing.assert_allclose(in_memory.fit("NM").result.center, truth, atol=1e-8)


def test_too_few_frames_left_by_gaps_say_how_many_the_gaps_took():
    """The method's own refusal counts the frames it was given, not the file's: "markers has 3
    frames" of a 200-frame trial read as a mistake until the gaps were counted."""
    markers = rig_recording().markers.copy()
    markers[3:, 4] = np.nan  # moving marker D2, seen in the first three frames only
    with pytest.raises(ValueError) as error:
        prepare(Recording(PROX + DIST, markers, 100.0, "g.c3d"), "axis", DIST, PROX).fit()
    assert str(error.value).endswith(
        "markers has 3 frames; this method needs at least 4 (3 of the 200 frames read enter "
        "the fit: 197 lack a marker it needs)"
    )


def test_a_marker_never_seen_is_named(tmp_path):
    markers = rig_recording().markers.copy()
    markers[:, 4] = 0.0
    recording = read(write_c3d(tmp_path / "dropped.c3d", PROX + DIST, markers))
    with pytest.raises(ValueError, match=r"dropped.c3d: marker D2 is never visible"):
        prepare(recording, "joint_center", DIST, PROX)


def test_a_marker_never_seen_is_named_with_what_to_do(tmp_path):
    """The refusal of a marker seen in none of the frames read says how to go on: fit the
    segment without it, or read frames where it is seen."""
    markers = rig_recording().markers.copy()
    markers[:, 4] = np.nan
    recording = read(write_c3d(tmp_path / "dropped.c3d", PROX + DIST, markers))
    with pytest.raises(ValueError) as error:
        prepare(recording, "joint_center", DIST, PROX)
    assert str(error.value).endswith(
        "leave it out of the segment's markers (moving, reference; --moving, --reference), or "
        "read frames where it is seen (frames; --frames)"
    )


def test_estimator_errors_name_the_file_and_method():
    proximal, distal = two_segments(100, relative="hinge")
    recording = Recording(
        tuple(PROX + DIST), np.concatenate([proximal, distal], 1), 100.0, "hinge.c3d"
    )
    with pytest.raises(ValueError, match=r"hinge.c3d: joint_center SCoRE: .*degenerate motion"):
        prepare(recording, "joint_center", DIST, PROX).fit("SCoRE")


def swapped(recording, frame, first, second):
    markers = recording.markers.copy()
    i, j = recording.index([first, second])
    markers[frame:, [i, j]] = markers[frame:, [j, i]]
    return Recording(recording.labels, markers, recording.rate_hz, recording.source)


@pytest.mark.parametrize("segment", ["P", "D"])
def test_label_swap_is_refused_naming_marker_and_frame(segment):
    recording = swapped(rig_recording(), 150, f"{segment}1", f"{segment}2")
    message = rf"markers {segment}1 and {segment}2 exchange labels at frame 150 \(1\.50 s\)"
    with pytest.raises(ValueError, match=message):
        prepare(recording, "joint_center", DIST, PROX)


def test_label_swap_excluded_on_request_leaves_a_clean_answer():
    recording = swapped(rig_recording(), 150, "D1", "D3")
    with pytest.warns(UserWarning, match="left out 50 frames with artefacts"):
        prepared = prepare(recording, "joint_center", DIST, PROX, artefacts="exclude")
    fitted = prepared.fit("SCoRE")
    assert fitted.frames_used.max() == 149 and len(fitted.excluded) >= 50
    np.testing.assert_allclose(fitted.result.center, in_frame(JOINT, PROXIMAL), atol=1e-8)


def test_marker_falling_off_is_refused():
    recording = rig_recording()
    markers = recording.markers.copy()
    markers[120:, 3] += np.linspace(0.0, 40.0, 80)[:, None] * np.array([0.0, 0.0, -1.0])
    fallen = Recording(recording.labels, markers, 100.0, "rig.c3d")
    with pytest.raises(ValueError, match=r"rig.c3d: marker D1 leaves its cluster's rigid shape"):
        prepare(fallen, "center", DIST, PROX)


def test_jump_of_a_loose_marker_is_refused():
    recording = rig_recording()
    markers = recording.markers.copy()
    markers[90:, 3] += np.array([0.0, 0.0, 119.0])
    jumped = Recording(recording.labels, markers, 100.0, "rig.c3d")
    with pytest.raises(ValueError, match=r"marker D1 jumps 11[89]\.\d mm at frame 90"):
        prepare(jumped, "center", ["D1"], PROX)


def test_frame_range_and_file_frame_numbers_in_messages():
    recording = swapped(rig_recording(), 150, "D1", "D2")
    fitted = prepare(recording, "center", DIST, PROX, frames="20:140").fit("LS")
    assert fitted.frames_used[0] == 20 and fitted.frames_used[-1] == 139
    with pytest.raises(ValueError, match="at frame 150"):
        prepare(recording, "center", DIST, PROX, frames="100:")


# --- frame order ----------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kind", "methods"),
    [
        ("joint_center", jointbench.methods("joint_center")),
        ("axis", jointbench.methods("axis")),
        ("center", ("LS", "NM", "BC", "SCoRE")),
    ],
)
def test_answers_do_not_depend_on_frame_order(kind, methods):
    recording = rig_recording(artefact_mm=3.0)
    shuffled = np.random.default_rng(1).permutation(recording.n_frames)
    orders = [
        recording,
        reversed_recording(recording),
        Recording(recording.labels, recording.markers[shuffled], 100.0, "shuffled"),
    ]
    for method in methods:
        fits = [prepare(r, kind, DIST, PROX).fit(method).estimate() for r in orders]
        for other in fits[1:]:
            if kind == "axis":
                assert angle_between_lines_deg(fits[0][:3], other[:3]) < 1e-6
                gap = other[3:] - fits[0][3:]
                np.testing.assert_allclose(np.cross(gap, fits[0][:3]), 0.0, atol=1e-6)
            else:
                np.testing.assert_allclose(other, fits[0], atol=1e-6)


def test_frame_order_moves_the_plain_two_segment_fit():
    """What the recording path protects against: the same frames in another order."""
    markers = rig_recording(artefact_mm=3.0).markers
    forward = jointbench.fit_joint_center(markers[:, :3], markers[:, 3:], method="analytic")
    backward = jointbench.fit_joint_center(markers[::-1, :3], markers[::-1, 3:], method="analytic")
    assert np.linalg.norm(forward.center - backward.center) > 1.0


# --- the real knee trial --------------------------------------------------------------------


@pytest.fixture(scope="module")
def knee():
    assert KNEE.is_file(), f"{KNEE} is part of the repository"
    return read(KNEE)


def test_knee_file_as_read(knee):
    assert knee.n_frames == 922 and knee.rate_hz == 100.0 and len(knee.labels) == 73
    assert all(knee.gaps()[label] == 0 for label in [*THIGH.split(","), *SHANK.split(",")])


def test_knee_axis_methods_agree_with_the_epicondyles_and_ignore_frame_order(knee):
    forward = prepare(knee, "axis", SHANK, THIGH)
    backward = prepare(reversed_recording(knee), "axis", SHANK, THIGH)
    epicondyles = forward.reference.local(knee.select("RLFE,RMFE")).mean(axis=0)
    line = epicondyles[1] - epicondyles[0]
    directions = []
    for method in jointbench.methods("axis"):
        fitted, again = forward.fit(method), backward.fit(method)
        assert fitted.result.converged, method
        assert angle_between_lines_deg(fitted.result.direction, line) < 15.0, method
        assert angle_between_lines_deg(fitted.result.direction, again.result.direction) < 1e-6
        directions.append(fitted.result.direction)
    spread = max(angle_between_lines_deg(a, b) for a in directions for b in directions)
    assert spread < 5.0
