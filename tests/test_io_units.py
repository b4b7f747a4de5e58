"""A file's point unit against what its numbers make of a human body's markers: numbers in
another unit than the file states are refused naming the file, the unit it states, the markers,
their span and the unit the numbers look like; markers in their right unit, from a thumb's to
a knee's, are read and fitted in every reader."""

from __future__ import annotations

import numpy as np
import pytest
from rigs import two_segments
from test_io_recordings import KNEE, write_c3d
from test_user_recordings import write_long_csv

import jointbench
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
        # The thigh reads 3.2 m across: no segment's markers span that; in mm, it is a thigh.
        (
            ("c3d", "trc"),
            1.0,
            "cm",
            "3.17e+03",
            ONE_SEGMENT,
            "millimetres read as centimetres (a cluster 317 mm across)",
        ),
        # 31.7 read in metres is a thigh's 317 mm in cm, or a thumb's 31.7 mm in mm: both named.
        (
            ("c3d", "trc"),
            0.1,
            "m",
            "3.17e+04",
            ONE_SEGMENT,
            "millimetres read as metres (a cluster 31.7 mm across) or centimetres read as "
            "metres (a cluster 317 mm across)",
        ),
        (
            ("c3d", "trc"),
            1.0,
            "m",
            "3.17e+05",
            ONE_SEGMENT,
            "millimetres read as metres (a cluster 317 mm across)",
        ),
        (
            ("c3d", "trc", "csv"),
            0.001,
            "mm",
            "0.317",
            UNDER_A_MARKER,
            "centimetres read as millimetres (a cluster 3.17 mm across) or metres read as "
            "millimetres (a cluster 317 mm across)",
        ),
    ],
    ids=["mm-under-cm", "cm-under-m", "mm-under-m", "m-under-mm"],
)
def test_numbers_in_another_unit_are_refused_naming_the_unit_they_look_like(
    tmp_path, knee_legs, suffixes, scale, units, span, bound, hint
):
    """The knee's thigh and shank written as ``scale`` times their millimetres under ``units``,
    by every reader that states that unit: refused naming the file, the unit it states, the
    thigh's markers and span, and the units in which its numbers are a body's."""
    labels, markers = knee_legs
    for suffix in suffixes:
        path = write(tmp_path / f"knee.{suffix}", labels, markers * scale, units)
        with pytest.raises(ValueError) as error:
            fit_knee(read(path))
        assert str(error.value) == (
            f"{path}: markers RTHI1, RTHI2, RTHI3, RGT lie {span} mm apart (the farthest two, "
            f"median over the frames), {bound}. The coordinates are not in the unit the file "
            f"states ({units!r}, read as mm): its numbers look like {hint}; correct the file's "
            "unit (C3D POINT:UNITS, TRC Units; a CSV is in mm)"
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
#: 'cm': the reference's, the moving segment's where the reference (the upper arm, 95 mm)
#: passes for one, and both together where the moving markers are two (the wrist's, 71 mm).
JOINED = [
    ("pelvis", "thigh", "LPSIS, RPSIS, LASIS, RASIS lie 2.59e+03"),
    ("thigh", "shank", "RTHI1, RTHI2, RTHI3, RGT lie 3.17e+03"),
    ("shank", "foot", "RLEG1, RLEG2, RLEG3, RATT, RLM, RSPH lie 3.41e+03"),
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


@pytest.mark.xfail(
    strict=True,
    reason=(
        "MAX_SPAN_MM bounds every cluster as a human body segment's, the reference's too: four "
        "markers on a treadmill's frame 2 m by 0.8 m in millimetres (2.15 m apart), fitted "
        "while the bound was 10 m, are refused as no segment's; telling a reference that "
        "stays still in the lab from a segment's cluster, and bounding it as such, is a "
        "change of the unit check's design"
    ),
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
    fitted = jointbench.fit(recording, "center", SHANK, "TM1,TM2,TM3,TM4", artefacts="exclude")
    assert np.isfinite(fitted.estimate()).all()


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
