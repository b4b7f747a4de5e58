"""A file's point unit against what its numbers make of a human body's markers: numbers in
another unit than the file states are refused naming the file, the unit it states, the markers,
their span and the unit the numbers look like; markers in their right unit, from a thumb's to
a knee's, are read and fitted in every reader."""

from __future__ import annotations

import re

import numpy as np
import pytest
from rigs import two_segments
from test_io_recordings import KNEE, write_c3d
from test_user_recordings import write_long_csv

import jointbench
from jointbench.cli import main
from jointbench.estimators.validation import MAX_JOINED_SPAN_MM, MAX_SPAN_MM
from jointbench.io import Recording, prepare, read
from jointbench.io.units import UNIT_TO_MM, to_mm, unit_hint
from jointbench.simulate import cmc, hinge

THIGH = "RTHI1,RTHI2,RTHI3,RGT"
SHANK = "RLEG1,RLEG2,RLEG3,RATT,RLM,RSPH"


def write_trc(path, labels, markers, *, units="mm", rate=100.0):
    """Markers ``(n_frames, n, 3)`` in ``units`` (NaN an empty field) to a TRC file."""
    rows = [
        f"PathFileType\t4\t(X/Y/Z)\t{path.name}",
        "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits",
        f"{rate:g}\t{rate:g}\t{len(markers)}\t{len(labels)}\t{units}",
        "Frame#\tTime\t" + "\t\t\t".join(labels),
        "\t\t" + "\t".join(f"X{i}\tY{i}\tZ{i}" for i in range(1, len(labels) + 1)),
    ]
    for frame, sample in enumerate(markers):
        values = ["" if np.isnan(v) else repr(float(v)) for v in sample.ravel()]
        rows.append(f"{frame + 1}\t{frame / rate:.4f}\t" + "\t".join(values))
    path.write_text("\n".join(rows) + "\n")
    return path


def write(path, labels, markers, units):
    """Markers ``(n_frames, n, 3)`` written in ``units`` (the numbers as given) by the writer
    of ``path``'s suffix; a CSV states no unit (it is mm)."""
    if path.suffix == ".c3d":
        return write_c3d(path, labels, markers, units=units)
    if path.suffix == ".trc":
        return write_trc(path, labels, markers, units=units)
    assert units == "mm", "a CSV states no unit"
    return write_long_csv(path, labels, markers)


@pytest.fixture(scope="module")
def knee_legs():
    """The knee trial's thigh and shank markers, frames 100 to 399: labels and ``(300, 10, 3)``
    [mm]."""
    knee = read(KNEE).frames("100:400")
    labels = tuple(f"{THIGH},{SHANK}".split(","))
    return labels, knee.select(labels)


def fit_knee(recording, method="NM"):
    return jointbench.fit(recording, "center", SHANK, THIGH, method=method, artefacts="exclude")


ONE_SEGMENT = "more than the markers of any one human body segment span (1500 mm)"
UNDER_A_MARKER = "less than a marker's own size (1 mm)"


@pytest.mark.parametrize(
    ("suffixes", "scale", "units", "span", "bound", "hint"),
    [
        # The shank reads 3.4 m across: no segment's markers span that; in mm, it is a shank.
        (
            ("c3d", "trc"),
            1.0,
            "cm",
            "3.41e+03",
            ONE_SEGMENT,
            "millimetres read as centimetres (a cluster 341 mm across)",
        ),
        # 34.1 read in metres is a shank's 341 mm in cm, or a thumb's 34.1 mm in mm: both named.
        (
            ("c3d", "trc"),
            0.1,
            "m",
            "3.41e+04",
            ONE_SEGMENT,
            "millimetres read as metres (a cluster 34.1 mm across) or centimetres read as "
            "metres (a cluster 341 mm across)",
        ),
        (
            ("c3d", "trc"),
            1.0,
            "m",
            "3.41e+05",
            ONE_SEGMENT,
            "millimetres read as metres (a cluster 341 mm across)",
        ),
        (
            ("c3d", "trc", "csv"),
            0.001,
            "mm",
            "0.341",
            UNDER_A_MARKER,
            "centimetres read as millimetres (a cluster 3.41 mm across) or metres read as "
            "millimetres (a cluster 341 mm across)",
        ),
    ],
    ids=["mm-under-cm", "cm-under-m", "mm-under-m", "m-under-mm"],
)
def test_numbers_in_another_unit_are_refused_naming_the_unit_they_look_like(
    tmp_path, knee_legs, suffixes, scale, units, span, bound, hint
):
    """The knee's thigh and shank written as ``scale`` times their millimetres under ``units``,
    by every reader that states that unit (a CSV, read as mm, states none): refused naming the
    file, the unit it states, the shank's markers and span (the moving markers, which tell the
    unit before the reference), and the units in which its numbers are a body's."""
    labels, markers = knee_legs
    for suffix in suffixes:
        path = write(tmp_path / f"knee.{suffix}", labels, markers * scale, units)
        with pytest.raises(ValueError) as error:
            fit_knee(read(path))
        # A CSV states no unit: it is read as mm, and not said to state it.
        stated = (
            "the unit the file is read in (it states no unit; read as mm)"
            if suffix == "csv"
            else f"the unit the file states ({units!r}, read as mm)"
        )
        assert str(error.value) == (
            f"{path}: markers RLEG1, RLEG2, RLEG3, RATT, RLM, RSPH lie {span} mm apart (the "
            f"farthest two, median over the frames), {bound}. The coordinates are not in "
            f"{stated}: its numbers look like {hint}; correct the file's unit (C3D POINT:UNITS, "
            "TRC Units; a CSV is in mm)"
        )


@pytest.mark.parametrize(
    ("suffix", "units", "scale"),
    [
        ("c3d", "mm", 1.0),
        ("c3d", "cm", 0.1),
        ("c3d", "m", 0.001),
        ("trc", "mm", 1.0),
        ("trc", "cm", 0.1),
        ("trc", "m", 0.001),
        ("csv", "mm", 1.0),
    ],
)
def test_the_knee_in_its_right_unit_is_fitted_in_every_reader(
    tmp_path, knee_legs, suffix, units, scale
):
    labels, markers = knee_legs
    path = write(tmp_path / f"knee.{suffix}", labels, markers * scale, units)
    recording = read(path)
    np.testing.assert_allclose(recording.select(labels), markers, rtol=1e-6, atol=1e-3)
    assert fit_knee(recording).result.converged


def thumb(units_mm: float = 1.0) -> tuple[tuple[str, ...], np.ndarray]:
    """The thumb CMC simulation's markers (paper A): the hand dorsum's H set still, the thumb
    metacarpal's M set circling 45 degrees about the CMC, 0.1 mm noise; labels and
    ``(n_frames, 6, 3)`` in a unit of ``units_mm`` mm."""
    protocol = cmc.CmcProtocol()
    moving = cmc.nominal_trajectory(protocol, "M", 45.0)
    still = cmc.marker_positions(protocol, "H") + np.asarray(protocol.center_mm)
    markers = np.concatenate([np.broadcast_to(still, moving.shape), moving], axis=1)
    markers = markers + np.random.default_rng(3).normal(scale=0.1, size=markers.shape)
    return ("H1", "H2", "H3", "M1", "M2", "M3"), markers / units_mm


@pytest.mark.parametrize(
    ("suffix", "units"),
    [
        ("c3d", "mm"),
        ("c3d", "cm"),
        ("c3d", "m"),
        ("trc", "mm"),
        ("trc", "cm"),
        ("trc", "m"),
        ("csv", "mm"),
    ],
)
def test_a_thumb_in_its_right_unit_is_fitted_in_every_reader(tmp_path, suffix, units):
    """The M set's triangle has sides of 11 to 18 mm: small, and a real cluster."""
    labels, markers = thumb(UNIT_TO_MM[units])
    path = write(tmp_path / f"thumb.{suffix}", labels, markers, units)
    fitted = jointbench.fit(read(path), "center", "M1,M2,M3", "H1,H2,H3", method="NM")
    assert fitted.result.converged
    centre = np.asarray(cmc.CmcProtocol().center_mm)
    assert np.linalg.norm(fitted.world()[0] - centre) < 2.0


@pytest.mark.parametrize("suffix", ["c3d", "trc", "csv"])
def test_an_index_finger_in_millimetres_is_fitted_in_every_reader(tmp_path, suffix):
    """The index MCP simulation's proximal phalanx markers (paper B), 16 to 19 mm apart, fitted
    as an axis in the lab."""
    protocol = hinge.HINGE_PROTOCOLS["mcp"]
    markers = hinge.nominal_markers({"fe_rom_deg": 60, "aa_ratio": 0.3}, protocol)
    markers = markers + np.array([100.0, 200.0, 300.0])
    markers += np.random.default_rng(4).normal(scale=0.1, size=markers.shape)
    path = write(tmp_path / f"mcp.{suffix}", protocol.marker_names, markers, "mm")
    fitted = jointbench.fit(read(path), "axis", "P1,P2,P3", method="planar")
    assert fitted.result.converged


def plates(n_frames: int = 120) -> tuple[tuple[str, ...], np.ndarray]:
    """Two plates of three markers 95 mm across, 1 m apart across a ball joint (the two-segment
    rig's clusters drawn in to their centroids): labels and ``(n_frames, 6, 3)`` [mm]."""
    proximal, distal = two_segments(n_frames)
    drawn = [
        c.mean(axis=1, keepdims=True) + 0.5 * (c - c.mean(axis=1, keepdims=True))
        for c in (proximal, distal)
    ]
    return ("P1", "P2", "P3", "D1", "D2", "D3"), np.concatenate(drawn, axis=1)


def test_small_clusters_far_apart_under_centimetres_are_refused_as_two_segments(tmp_path):
    """Each plate reads 1 m across, which one segment's markers can span; the two read 10 m
    apart, which no two joined segments' can."""
    labels, markers = plates()
    path = write_c3d(tmp_path / "plates.c3d", labels, markers, units="cm")
    recording = read(path)
    assert MAX_SPAN_MM > 10 * np.ptp(markers[0, :3], axis=0).max()
    with pytest.raises(ValueError) as error:
        jointbench.fit(recording, "center", "D1,D2,D3", "P1,P2,P3", method="NM")
    message = str(error.value)
    assert message.startswith(f"{path}: markers P1, P2, P3, D1, D2, D3 lie 9.98e+03 mm apart"), (
        message
    )
    assert (
        f"more than the markers of two human body segments joined at a joint span "
        f"({MAX_JOINED_SPAN_MM:g} mm). The coordinates are not in the unit the file states "
        "('cm', read as mm): its numbers look like millimetres read as centimetres"
    ) in message


def test_the_plates_in_millimetres_are_fitted(tmp_path):
    labels, markers = plates()
    path = write_c3d(tmp_path / "plates.c3d", labels, markers, units="mm")
    assert jointbench.fit(
        read(path), "center", "D1,D2,D3", "P1,P2,P3", method="NM"
    ).result.converged


def test_two_moving_markers_in_another_unit_name_the_file(tmp_path, knee_legs):
    """Fewer than three moving markers are no segment, but their span is checked in the file's
    unit as a segment's is."""
    labels, markers = knee_legs
    path = write(tmp_path / "knee.c3d", labels, markers / 1000.0, "mm")
    with pytest.raises(ValueError, match=rf"^{path}: markers RLEG1, RLM lie 0\.122 mm apart"):
        jointbench.fit(read(path), "center", "RLEG1,RLM", method="LS")


def test_an_array_api_cluster_too_large_for_a_body_is_refused(knee_legs):
    """The array fits take millimetres: a thigh 3.2 m across is no segment's cluster either."""
    thigh = knee_legs[1][:, :4] * 10.0
    with pytest.raises(ValueError, match=r"markers lie 3\.17e\+03 mm apart .*\(1500 mm\)"):
        jointbench.fit_center(thigh, method="NM", artefacts="ignore")


def test_an_array_api_cluster_ten_times_a_segment_is_not_said_to_be_a_thousand(knee_legs):
    """A thigh's millimetres taken for centimetres (10 times, 3.2 m) is not named as taken for
    metres: the array fits state no unit, so either misreading, or more than one segment's
    markers, is named."""
    thigh = knee_legs[1][:, :4] * 10.0
    with pytest.raises(ValueError) as error:
        jointbench.fit_center(thigh, method="NM", artefacts="ignore")
    assert "millimetres read as metres?" not in str(error.value)
    assert (
        "(1500 mm): millimetres read as centimetres or metres, or the markers of more than "
        "one segment?"
    ) in str(error.value)


def test_a_unit_the_table_does_not_know_gives_no_hint():
    assert unit_hint(3170.0, "inch", MAX_SPAN_MM) == ""


def test_numbers_no_unit_makes_a_body_of_are_said_to_be_so():
    assert unit_hint(5e7, "mm", MAX_SPAN_MM) == (
        "in no unit of millimetres, centimetres, metres are its numbers a body's markers"
    )


def test_a_recording_built_in_memory_states_millimetres():
    knee = read(KNEE)
    recording = Recording(knee.labels, knee.markers * 10.0, knee.rate_hz, "trial")
    with pytest.raises(ValueError, match=r"states \('mm', read as mm\)"):
        fit_knee(recording)


def test_a_unit_written_out_is_named_as_its_symbol_is():
    assert unit_hint(3.17e5, " Meters", MAX_SPAN_MM) == (
        "its numbers look like millimetres read as metres (a cluster 317 mm across)"
    )


#: Clusters of the knee trial: thorax, pelvis, right thigh, shank, foot, upper arm, forearm.
SEGMENTS = {
    "thorax": "C7,T10,SUP,STR,LA,RA",
    "pelvis": "LPSIS,RPSIS,LASIS,RASIS",
    "thigh": THIGH,
    "shank": SHANK,
    "foot": "RCAL,RMFH5,RMFH1,RTT2",
    "arm": "RAMR1,RARM2,RARM3",
    "forearm": "RFARM1,RFARM2,RFARM3,RUS,RRS",
}
#: The pairs a joint joins, reference first, and the first markers whose span is refused under
#: 'cm': the moving segment's, which tell the unit first, the reference's where the moving
#: segment (the upper arm, 95 mm) passes for one, and both together where the moving markers
#: are two (the wrist's, 71 mm) and the reference (the upper arm) passes.
JOINED = [
    ("pelvis", "thigh", "RTHI1, RTHI2, RTHI3, RGT lie 3.17e+03"),
    ("thigh", "shank", "RLEG1, RLEG2, RLEG3, RATT, RLM, RSPH lie 3.41e+03"),
    ("shank", "foot", "RCAL, RMFH5, RMFH1, RTT2 lie 2.33e+03"),
    ("thorax", "arm", "C7, T10, SUP, STR, LA, RA lie 3.36e+03"),
    ("arm", "forearm", "RFARM1, RFARM2, RFARM3, RUS, RRS lie 1.89e+03"),
    ("arm", "RUS,RRS", "RAMR1, RARM2, RARM3, RUS, RRS lie 3.83e+03"),
]


# The foot's markers leave its shape in 12 frames of the trial, which are left out with a warning.
@pytest.mark.filterwarnings("ignore:.*right_knee.c3d. left out 12 frames with artefacts")
@pytest.mark.parametrize(
    ("reference", "moving", "refused"), JOINED, ids=[f"{r}-{m}" for r, m, _ in JOINED]
)
def test_every_joint_of_the_knee_trial_under_centimetres_is_refused(reference, moving, refused):
    """Millimetres under 'cm': every segment of the trial but the upper arm spans more than
    one segment can, and the upper arm with the wrist's markers more than two joined can."""
    knee = read(KNEE)
    mm = prepare(
        knee, "center", SEGMENTS.get(moving, moving), SEGMENTS[reference], artefacts="exclude"
    )
    assert mm.usable.size > 0
    cm = Recording(
        knee.labels, knee.markers * 10.0, knee.rate_hz, knee.source, knee.first_frame, "cm"
    )
    with pytest.raises(ValueError) as error:
        prepare(
            cm, "center", SEGMENTS.get(moving, moving), SEGMENTS[reference], artefacts="exclude"
        )
    assert str(error.value).startswith(f"{KNEE}: markers {refused} mm apart"), str(error.value)
    assert (
        "states ('cm', read as mm): its numbers look like millimetres read as centimetres"
        in str(error.value)
    )


def test_a_whole_body_in_millimetres_is_refused_as_no_one_segment_not_as_a_unit():
    """Every marker of the knee trial (``jointbench fit``'s default moving ones) spans the body,
    1.66 m: in
    no unit a file can state is that one segment's cluster, so the unit, which is right, is not
    what the refusal blames; the markers chosen are."""
    knee = read(KNEE).frames("100:400")
    with pytest.raises(ValueError) as error:
        jointbench.fit(knee, "center", ",".join(knee.labels), method="NM")
    message = str(error.value)
    assert f"{KNEE}: markers HV, OCC" in message
    assert "lie 1.66e+03 mm apart" in message
    assert "not in the unit the file states" not in message
    assert "correct the file's unit" not in message
    assert message.endswith(
        "more than the markers of any one human body segment span (1500 mm), in the unit the "
        "file states ('mm', read as mm), and in no unit of millimetres, centimetres, metres "
        "are its numbers a body's markers: they are not the markers of one human body "
        "segment, or are in a unit no file states; choose one segment's markers (moving, "
        "reference; --moving, --reference)"
    )


#: A treadmill's frame, 2 m by 0.8 m, in the knee trial's lab [mm]: its four corners.
TREADMILL = np.array(
    [[-500.0, -300.0, 0.0], [1500.0, -300.0, 0.0], [-500.0, 500.0, 0.0], [1500.0, 500.0, 0.0]]
)
TM = "TM1,TM2,TM3,TM4"
#: The user's statement that the reference is fixed in the lab, which alone lets a still one be
#: bounded by a capture volume.
LAB_FIXED = {"lab_fixed_reference": True}


def with_treadmill(knee, corners=TREADMILL, *, noise_mm=0.3, scale=1.0, units="mm", moves=0.0):
    """The ``knee`` recording with the ``corners`` ``(4, 3)`` [mm] as markers TM1 to TM4, seen
    with ``noise_mm`` of noise and displaced by ``moves`` (``(n_frames, 1, 3)`` [mm], or 0),
    every marker written as ``scale`` times its millimetres under ``units``."""
    rng = np.random.default_rng(0)
    still = corners + moves + rng.normal(scale=noise_mm, size=(len(knee.markers), 4, 3))
    return Recording(
        (*knee.labels, *TM.split(",")),
        np.concatenate([knee.markers, still], axis=1) * scale,
        knee.rate_hz,
        "treadmill.c3d",
        knee.first_frame,
        units,
    )


def test_a_treadmill_fixed_reference_in_millimetres_is_fitted():
    knee = read(KNEE).frames("100:400")
    corners = np.array([[-500.0, -300.0, 0.0], [1500.0, -300.0, 0.0], [-500.0, 500.0, 0.0]])
    corners = np.vstack([corners, [1500.0, 500.0, 0.0]])
    still = corners + np.random.default_rng(0).normal(scale=0.3, size=(len(knee.markers), 4, 3))
    recording = Recording(
        (*knee.labels, "TM1", "TM2", "TM3", "TM4"),
        np.concatenate([knee.markers, still], axis=1),
        knee.rate_hz,
        "treadmill.c3d",
        knee.first_frame,
        "mm",
    )
    fitted = jointbench.fit(
        recording, "center", SHANK, "TM1,TM2,TM3,TM4", artefacts="exclude", **LAB_FIXED
    )
    assert np.isfinite(fitted.estimate()).all()


@pytest.mark.parametrize(("units", "code"), [("mm", 0), ("cm", 2)])
def test_jointbench_fit_takes_a_treadmill_reference_from_a_file(tmp_path, capsys, units, code):
    """The command line passes the reference as the recordings API does: in millimetres the
    treadmill is fitted; under 'cm' the shank tells the unit."""
    recording = with_treadmill(read(KNEE).frames("100:400"))
    path = write_c3d(tmp_path / "treadmill.c3d", recording.labels, recording.markers, units=units)
    argv = ["fit", "center", str(path), "--moving", SHANK, "--reference", TM, "--method", "NM"]
    argv += ["--lab-fixed-reference"]
    assert main([*argv, "--artefacts", "exclude", "--format", "csv"]) == code
    _, err = capsys.readouterr()
    if code:
        assert f"{path}: markers RLEG1, RLEG2, RLEG3, RATT, RLM, RSPH lie 3.41e+03 mm" in err


def test_an_axis_about_a_still_reference_is_fitted_and_a_joint_centre_is_not():
    """The treadmill is the frame of a centre or an axis; a joint centre's reference is the
    proximal body segment of the joint, bounded as one, and refused as a ValueError."""
    recording = with_treadmill(read(KNEE).frames("100:400"))
    fitted = jointbench.fit(
        recording, "axis", SHANK, TM, method="planar", artefacts="exclude", **LAB_FIXED
    )
    assert np.isfinite(fitted.estimate()).all()
    with pytest.raises(ValueError, match=rf"{re.escape(ONE_SEGMENT)}.*: they are not the markers "):
        jointbench.fit(recording, "joint_center", SHANK, TM, artefacts="exclude")


#: What the refusal of a still reference wider than a segment, not stated fixed in the lab, says.
NOT_STATED = (
    "and they stay still in the lab, the positions each marker holds within 5 mm of one "
    "another: a reference fixed in the lab is bounded by what one optical capture volume spans "
    "where it is stated so (lab_fixed_reference=True, --lab-fixed-reference)"
)


def test_a_still_treadmill_not_stated_fixed_in_the_lab_is_bounded_as_a_segment_naming_the_option():
    """Without the user's word the treadmill's size is a segment's too large: refused as at
    5547d95, and the refusal says the markers are still and names the option."""
    recording = with_treadmill(read(KNEE).frames("100:400"))
    with pytest.raises(ValueError) as error:
        jointbench.fit(recording, "center", SHANK, TM, artefacts="exclude")
    message = str(error.value)
    assert message.startswith(
        f"treadmill.c3d: markers TM1, TM2, TM3, TM4 lie 2.15e+03 mm apart (the farthest two, "
        f"median over the frames), {ONE_SEGMENT}, {NOT_STATED}, in the unit the file states"
    ), message


def test_jointbench_fit_names_its_option_for_a_still_treadmill_not_stated_fixed(tmp_path, capsys):
    recording = with_treadmill(read(KNEE).frames("100:400"))
    path = write_c3d(tmp_path / "treadmill.c3d", recording.labels, recording.markers)
    argv = ["fit", "center", str(path), "--moving", SHANK, "--reference", TM, "--method", "NM"]
    assert main([*argv, "--artefacts", "exclude", "--format", "csv"]) == 2
    _, err = capsys.readouterr()
    assert f"{path}: markers TM1, TM2, TM3, TM4 lie 2.15e+03 mm apart" in err
    assert NOT_STATED in err


def test_a_still_reference_far_from_the_subject_not_stated_fixed_names_the_option():
    """A wand frame 300 mm across, 4 m from the treadmill's: a segment's size, but with the
    shank it spans more than two joined segments; the refusal names the option."""
    wand = TREADMILL * [0.15, 0.375, 0.0] + [4500.0, 0.0, 0.0]
    recording = with_treadmill(read(KNEE).frames("100:400"), wand)
    with pytest.raises(ValueError) as error:
        jointbench.fit(recording, "center", SHANK, TM, artefacts="exclude")
    message = str(error.value)
    assert message.startswith(
        f"treadmill.c3d: markers TM1, TM2, TM3, TM4, {SHANK.replace(',', ', ')} lie 3.95e+03 mm"
    ), message
    assert f"({MAX_JOINED_SPAN_MM:g} mm), {NOT_STATED}" in message, message


def test_a_wide_reference_that_moves_not_stated_fixed_is_refused_as_no_segment():
    """Not stated fixed, a wide reference that moves is refused as at 5547d95, without naming
    the option (it would not hold) or the motion (nothing claimed it still)."""
    knee = read(KNEE).frames("100:400")
    recording = with_treadmill(knee, moves=pelvis_sway(knee))
    with pytest.raises(ValueError) as error:
        jointbench.fit(recording, "center", SHANK, TM, artefacts="exclude")
    message = str(error.value)
    assert f"{ONE_SEGMENT}, in the unit the file states ('mm', read as mm)" in message, message
    assert "lab_fixed_reference" not in message


def test_a_joint_centre_takes_no_lab_fixed_reference():
    """A joint centre's reference is the proximal body segment of the joint, never the lab's."""
    recording = with_treadmill(read(KNEE).frames("100:400"))
    with pytest.raises(ValueError, match=r"^lab_fixed_reference \(--lab-fixed-reference\) is "):
        jointbench.fit(recording, "joint_center", SHANK, THIGH, artefacts="exclude", **LAB_FIXED)


@pytest.mark.parametrize(
    ("reference", "stated", "named"),
    [
        (None, True, "needs a reference"),
        (TM, "yes", "must be True or False, got 'yes'"),
        (TM, 1, "must be True or False, got 1"),
    ],
)
def test_a_lab_fixed_reference_needs_a_reference_and_a_bool(reference, stated, named):
    recording = with_treadmill(read(KNEE).frames("100:400"))
    with pytest.raises(
        ValueError, match=rf"^lab_fixed_reference \(--lab-fixed-reference\) {named}"
    ):
        jointbench.fit(
            recording, "center", SHANK, reference, artefacts="exclude", lab_fixed_reference=stated
        )


def test_a_small_reference_stated_fixed_that_moves_is_bounded_as_a_segment():
    """The statement widens a bound only: a thigh stated fixed in the lab moves, and being a
    segment's size, is fitted as one."""
    recording = with_treadmill(read(KNEE).frames("100:400"))
    fitted = jointbench.fit(recording, "center", SHANK, THIGH, artefacts="exclude", **LAB_FIXED)
    assert np.isfinite(fitted.estimate()).all()


def test_a_still_reference_with_gaps_is_fitted_and_its_gaps_counted():
    """Gaps, as NaN or as (0, 0, 0), do not make markers move: frames where fewer than three
    of the treadmill's markers are seen are gaps of the fit."""
    knee = read(KNEE).frames("100:400")
    whole = jointbench.fit(
        with_treadmill(knee), "center", SHANK, TM, artefacts="exclude", **LAB_FIXED
    )
    recording = with_treadmill(knee)
    markers = recording.markers.copy()
    tm1, tm2, tm3 = recording.index("TM1,TM2,TM3")
    markers[10:21, tm1] = np.nan
    markers[15:31, tm2] = 0.0
    markers[200:260, tm3] = np.nan
    gappy = Recording(recording.labels, markers, knee.rate_hz, "treadmill.c3d", knee.first_frame)
    fitted = jointbench.fit(gappy, "center", SHANK, TM, artefacts="exclude", **LAB_FIXED)
    assert np.isfinite(fitted.estimate()).all()
    assert fitted.n_gap_frames == whole.n_gap_frames + 6  # frames 15 to 20: TM1 and TM2 unseen


def test_a_still_reference_across_the_lab_from_the_subject_is_fitted():
    """A wand frame 300 mm across on the floor 4 m from the treadmill's: with the shank it spans
    more than two joined segments can, and within one capture volume."""
    knee = read(KNEE).frames("100:400")
    wand = TREADMILL * [0.15, 0.375, 0.0] + [4500.0, 0.0, 0.0]
    recording = with_treadmill(knee, wand)
    joined = recording.select(f"{SHANK},{TM}")
    assert np.ptp(joined.reshape(-1, 3), axis=0).max() > MAX_JOINED_SPAN_MM
    fitted = jointbench.fit(recording, "center", SHANK, TM, artefacts="exclude", **LAB_FIXED)
    assert np.isfinite(fitted.estimate()).all()


@pytest.mark.parametrize(
    ("scale", "units", "span", "hint"),
    [
        (0.001, "mm", "0.341", "or metres read as millimetres (a cluster 341 mm across)"),
        (10.0, "cm", "3.41e+03", "millimetres read as centimetres (a cluster 341 mm across)"),
        (1000.0, "m", "3.41e+05", "millimetres read as metres (a cluster 341 mm across)"),
    ],
    ids=["m-under-mm", "mm-under-cm", "mm-under-m"],
)
def test_a_still_reference_in_another_unit_is_caught_from_the_moving_markers(
    scale, units, span, hint
):
    """The treadmill's size in another unit is a capture volume's (2 mm, 21 m) or no longer
    still (its noise read 1000 times): the shank, which moves, tells the unit, and is named."""
    recording = with_treadmill(read(KNEE).frames("100:400"), scale=scale, units=units)
    with pytest.raises(ValueError) as error:
        jointbench.fit(recording, "center", SHANK, TM, artefacts="exclude", **LAB_FIXED)
    message = str(error.value)
    assert message.startswith(
        f"treadmill.c3d: markers RLEG1, RLEG2, RLEG3, RATT, RLM, RSPH lie {span} mm apart"
    ), message
    assert f"{hint}; correct the file's unit" in message


def test_a_still_reference_in_centimetres_with_a_compact_moving_cluster_is_refused():
    """A wand frame 300 mm by 300 mm fixed in the lab, seen with 0.1 mm of noise, and a
    three-marker shank plate, in millimetres under 'cm': refused as a wrong unit."""
    wand = TREADMILL * [0.15, 0.375, 0.0] + [1500.0, 0.0, 0.0]
    recording = with_treadmill(
        read(KNEE).frames("100:400"), wand, noise_mm=0.1, scale=10.0, units="cm"
    )
    with pytest.raises(ValueError, match="correct the file's unit"):
        jointbench.fit(recording, "center", "RLEG1,RLEG2,RLEG3", TM, artefacts="exclude")


def test_a_still_reference_is_bounded_by_a_capture_volume():
    """A lab-defined "world" cluster, exact in every frame, in millimetres under 'm' with one
    moving marker, whose size tells no unit: 2 km is no capture volume's; 2 m or 21 m is, and
    both are named."""
    recording = with_treadmill(read(KNEE).frames("100:400"), noise_mm=0.0, scale=1000.0, units="m")
    with pytest.raises(ValueError) as error:
        jointbench.fit(recording, "center", "RATT", TM, artefacts="exclude", **LAB_FIXED)
    assert str(error.value) == (
        "treadmill.c3d: markers TM1, TM2, TM3, TM4 lie 2.15e+06 mm apart (the farthest two, "
        "median over the frames), more than the markers of one optical capture volume span "
        "(100000 mm). The coordinates are not in the unit the file states ('m', read as mm): "
        "its numbers look like millimetres read as metres (a cluster 2.15e+03 mm across) or "
        "centimetres read as metres (a cluster 2.15e+04 mm across); "
        "correct the file's unit (C3D POINT:UNITS, TRC Units; a CSV is in mm)"
    )


def pelvis_sway(knee):
    """The pelvis's (the ASISs' midpoint's) displacement from its median ``(n_frames, 1, 3)``
    [mm]: markers on a harness or a frame the subject carries move so."""
    pelvis = knee.select("LASIS,RASIS").mean(axis=1, keepdims=True)
    return pelvis - np.median(pelvis, axis=0)


def test_a_wide_reference_that_moves_with_the_subject_is_bounded_as_a_segment():
    knee = read(KNEE).frames("100:400")
    recording = with_treadmill(knee, moves=pelvis_sway(knee))
    with pytest.raises(ValueError) as error:
        jointbench.fit(recording, "center", SHANK, TM, artefacts="exclude", **LAB_FIXED)
    message = str(error.value)
    assert message.startswith("treadmill.c3d: markers TM1, TM2, TM3, TM4 lie 2.15e+03 mm apart")
    assert re.search(
        r"more than the markers of any one human body segment span \(1500 mm\), and they move "
        r"in the lab: TM\d holds positions \d+(\.\d+)? mm apart, at frame \d+ \(\S+ s\) and at "
        r"frame \d+ \(\S+ s\), "
        r"more than the 5 mm a reference fixed in the lab stays within",
        message,
    ), message
    assert message.endswith(
        "they are not the markers of one human body segment, or are in a "
        "unit no file states; choose one segment's markers (moving, reference; --moving, "
        "--reference)"
    )


def test_lab_markers_with_a_body_marker_among_them_are_bounded_as_a_segment():
    """The head's vertex named among three of the treadmill's markers: it moves, and is named."""
    recording = with_treadmill(read(KNEE).frames("100:400"))
    moves = r"and they move in the lab: HV holds positions \d+(\.\d+)? mm apart"
    with pytest.raises(ValueError, match=moves):
        jointbench.fit(
            recording, "center", SHANK, "TM1,TM2,TM3,HV", artefacts="exclude", **LAB_FIXED
        )


def test_a_reference_of_two_still_markers_is_no_segment():
    recording = with_treadmill(read(KNEE).frames("100:400"))
    with pytest.raises(ValueError, match=r"a segment needs at least three markers, got \['TM1'"):
        jointbench.fit(recording, "center", SHANK, "TM1,TM2", artefacts="exclude", **LAB_FIXED)


def test_a_still_reference_bumped_once_is_refused_naming_the_bump_and_fitted_without_it():
    """Knocked 20 mm along the belt in ten frames and back: refused as no still reference,
    naming a marker and a frame of the bump; over the frames before it, fitted."""
    knee = read(KNEE).frames("100:400")
    bump = np.zeros((len(knee.markers), 1, 3))
    bump[150:160] = [20.0, 0.0, 0.0]
    recording = with_treadmill(knee, moves=bump)
    with pytest.raises(ValueError) as error:
        jointbench.fit(recording, "center", SHANK, TM, artefacts="exclude", **LAB_FIXED)
    found = re.search(
        r"TM\d lies (\d+(?:\.\d+)?) mm or more from its median position in frame (\d+)",
        str(error.value),
    )
    assert found, str(error.value)
    assert 18.0 < float(found[1]) < 22.0
    assert 250 <= int(found[2]) < 260
    before = jointbench.fit(
        recording, "center", SHANK, TM, frames="100:250", artefacts="exclude", **LAB_FIXED
    )
    assert np.isfinite(before.estimate()).all()


@pytest.mark.parametrize(
    ("spelled", "size_mm"),
    [
        ("Millimetres", 1.0),
        ("millimeter", 1.0),
        ("centimeters", 10.0),
        ("Centimetre", 10.0),
        ("metres", 1000.0),
        ("Meter", 1000.0),
    ],
)
def test_a_unit_spelled_out_in_either_spelling_is_read_as_its_symbol(spelled, size_mm):
    """Files state units spelled out as well as by symbol, in British and American spelling,
    singular or plural: each is the unit its symbol is."""
    assert to_mm(spelled, "trial.trc") == size_mm


def test_a_unit_no_spelling_names_is_refused_naming_the_file_and_the_known_units():
    with pytest.raises(ValueError, match=r"trial\.trc: unknown point unit 'inches'; known: "):
        to_mm("inches", "trial.trc")
