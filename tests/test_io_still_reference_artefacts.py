"""A still reference's artefacts: a bump, a ghost or a label swap in a few frames of a
treadmill stated fixed in the lab is screened as a moving cluster's is, before its stillness is
measured. With ``artefacts="exclude"`` those frames are left out and reported, and the rest is
bounded by a capture volume; by default the refusal names the marker (or the swapped pair) and
the frame, as for moving markers, not as motion of the reference in the lab."""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest
from test_io_recordings import KNEE, write_c3d
from test_io_units import LAB_FIXED, SHANK, TM, TREADMILL, with_treadmill, write

import jointbench
from jointbench.cli import main
from jointbench.estimators.validation import MAX_JOINED_SPAN_MM, MAX_SPAN_MM
from jointbench.io import Artefact, Recording, prepare, read
from jointbench.io import segments as segments_module

#: The treadmill's corners as markers placed by hand on its frame: a few mm off a rectangle
#: [mm]. Exchanging the labels of a long side's two markers, or of the other long side's, gives
#: a rectangle's shape the same distances, which tell the two apart only by that much (a
#: symmetric cluster's swap is ambiguous to a screen of its shape).
HAND_PLACED = TREADMILL + np.array(
    [[0.0, 0.0, 0.0], [4.0, -3.0, 1.0], [-2.0, 5.0, 0.0], [3.0, 2.0, -2.0]]
)


@pytest.fixture(scope="module")
def knee():
    """The knee trial's frames 100 to 399."""
    return read(KNEE).frames("100:400")


@pytest.fixture(scope="module")
def treadmill(knee):
    """The knee trial's frames 100 to 399 with a still treadmill TM1 to TM4 [mm]."""
    return with_treadmill(knee, HAND_PLACED)


def edited(recording, edit):
    """``recording`` with its markers changed by ``edit(markers, column_of)`` in place."""
    markers = recording.markers.copy()
    edit(markers, lambda label: recording.index(label)[0])
    return Recording(
        recording.labels,
        markers,
        recording.rate_hz,
        recording.source,
        recording.first_frame,
        recording.units,
    )


def bumped(recording, rows, label="TM1", by=(50.0, 0.0, 0.0)):
    """``recording`` with marker ``label`` displaced by ``by`` [mm] in the ``rows``."""

    def edit(markers, column):
        markers[rows, column(label)] += by

    return edited(recording, edit)


def lost(recording, row):
    """``recording`` with every marker missing in the ``row``."""

    def edit(markers, _):
        markers[row] = np.nan

    return edited(recording, edit)


def swapped(recording, rows, first="TM1", second="TM2"):
    """``recording`` with markers ``first`` and ``second`` exchanging labels in the ``rows``."""

    def edit(markers, column):
        a, b = column(first), column(second)
        markers[rows, a], markers[rows, b] = markers[rows, b].copy(), markers[rows, a].copy()

    return edited(recording, edit)


def fit_still(recording, artefacts="exclude", **options):
    """The shank's centre about the treadmill stated fixed in the lab, and the warnings."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fitted = jointbench.fit(
            recording, "center", SHANK, TM, method="NM", artefacts=artefacts, **LAB_FIXED, **options
        )
    return fitted, [str(w.message) for w in caught]


def refused_swap(recording, first, second):
    """The refusal of ``recording`` (by default), whose markers ``first`` and ``second``
    exchange labels in rows 150 to 159 (frames 250 to 259), checked to name that swap, the
    frames where the labels change and both sides; its message."""
    with pytest.raises(ValueError) as error:
        fit_still(recording, artefacts="refuse")
    message = str(error.value)
    assert message.startswith(
        f"treadmill.c3d: markers {first} and {second} exchange labels at frame 250 (2.50 s) and "
        "back at frame 260 (2.60 s); frames 100 to 249, 250 to 259, 260 to 399 are each "
        "labelled one consistent way"
    ), message
    return message


def assert_swap_left_out(recording, first, second):
    """Excluded, the swap of ``first`` and ``second`` in rows 150 to 159 of ``recording`` leaves
    out those ten frames, and the warning names the pair."""
    fitted, warned = fit_still(recording)
    assert {a.frame for a in fitted.excluded} == set(range(150, 160))
    assert f"left out 10 frames with artefacts: markers {first} and {second} exchange" in warned[0]


@pytest.mark.parametrize("row", [0, 150, 299], ids=["first", "middle", "last"])
def test_a_bump_in_one_frame_of_a_still_reference_is_left_out_and_reported(treadmill, row):
    """TM1 knocked 50 mm in one frame (the first, one in the middle, the last): that frame is
    left out, reported as TM1's artefact at its frame number, and the answer is the clean
    trial's but for that frame."""
    clean, _ = fit_still(treadmill)
    fitted, warned = fit_still(bumped(treadmill, [row]))
    frame = treadmill.first_frame + row
    assert frame not in fitted.frames_used
    assert len(fitted.frames_used) == len(clean.frames_used) - 1
    assert {a.frame for a in fitted.excluded} == {row}
    assert any(a.label == "TM1" for a in fitted.excluded)
    assert len(warned) == 1
    left_out = rf"left out 1 frames with artefacts: marker TM1 .* at frame {frame} "
    assert re.search(left_out, warned[0]), warned
    # The same as the frame missing altogether: the bump shapes nothing.
    gap, _ = fit_still(lost(treadmill, row))
    np.testing.assert_allclose(fitted.estimate(), gap.estimate(), rtol=0, atol=1e-9)


@pytest.mark.parametrize("row", [0, 150, 299], ids=["first", "middle", "last"])
def test_a_bump_in_one_frame_of_a_still_reference_is_refused_by_default_naming_it(treadmill, row):
    """Not excluded, the bump is refused as a moving cluster's is: naming the marker and the
    frame as an artefact, and the option that leaves it out, not as motion in the lab."""
    with pytest.raises(ValueError) as error:
        fit_still(bumped(treadmill, [row]), artefacts="refuse")
    message = str(error.value)
    frame = treadmill.first_frame + row
    assert message.startswith("treadmill.c3d: marker TM1 leaves its cluster's rigid shape by "), (
        message
    )
    assert f" mm at frame {frame} (" in message
    assert "pass artefacts='exclude' (--artefacts exclude)" in message
    assert "move in the lab" not in message


def test_two_bad_frames_of_a_still_reference_are_both_left_out(treadmill):
    """A bump of TM1 and a ghost of TM3 800 mm off, in two frames far apart."""
    recording = bumped(bumped(treadmill, [40]), [210], "TM3", (0.0, 800.0, 0.0))
    fitted, _ = fit_still(recording)
    assert {a.frame for a in fitted.excluded} == {40, 210}
    assert {40 + treadmill.first_frame, 210 + treadmill.first_frame}.isdisjoint(fitted.frames_used)


@pytest.mark.parametrize("artefacts", ["refuse", "exclude"])
@pytest.mark.parametrize("missing", [np.nan, 0.0], ids=["nan", "zeros"])
def test_a_marker_of_a_still_reference_lost_in_one_frame_is_a_gap(treadmill, missing, artefacts):
    """Lost as NaN or written as (0, 0, 0), a sample is a gap, not an artefact: the frame keeps
    its pose from the other three markers and nothing is excluded or refused."""

    def lose(markers, column):
        markers[150, column("TM2")] = missing

    fitted, warned = fit_still(edited(treadmill, lose), artefacts=artefacts)
    assert fitted.excluded == ()
    assert warned == []
    assert 150 + treadmill.first_frame in fitted.frames_used


@pytest.mark.parametrize(("first", "second"), [("TM1", "TM2"), ("TM2", "TM4")])
def test_a_swap_in_a_still_reference_is_refused_as_a_swap_naming_its_frames(
    treadmill, first, second
):
    """TM1 and TM2 (a long side of the treadmill) or TM2 and TM4 (a short one) exchange labels
    in frames 250 to 259: the refusal names the swap, the frames where the labels change and
    both sides, as for a moving cluster, not 2 m of motion in the lab."""
    message = refused_swap(swapped(treadmill, slice(150, 160), first, second), first, second)
    assert "keep one side with frames='100:250' or '250:260' or '260:400' (--frames)" in message
    assert "move in the lab" not in message


def test_a_swap_over_half_a_still_reference_s_trial_is_named_as_a_swap(treadmill):
    """TM1 and TM2 exchanged from frame 240 to the end, 160 of the 300 frames: the frames
    before it break the shape most frames share. Their residuals of some 2 m are the swap's,
    not the rigid fit's noise, which would call the treadmill's markers collinear."""
    recording = swapped(treadmill, slice(140, None))
    with pytest.raises(ValueError) as error:
        fit_still(recording, artefacts="refuse")
    assert str(error.value).startswith(
        "treadmill.c3d: markers TM1 and TM2 exchange labels at frame 240 (2.40 s); "
    ), str(error.value)
    fitted, _ = fit_still(recording)
    np.testing.assert_array_equal(fitted.frames_used, np.arange(240, 400))


def test_a_swap_in_a_still_reference_is_left_out_when_excluded(treadmill):
    fitted, warned = fit_still(swapped(treadmill, slice(150, 160)))
    assert {a.frame for a in fitted.excluded} == set(range(150, 160))
    assert len(warned) == 1
    assert "left out 10 frames with artefacts: markers TM1 and TM2 exchange labels" in warned[0]


def test_a_swap_lasting_the_whole_trial_is_a_labelling_not_an_artefact(treadmill):
    """Swapped in every frame the labels are consistent: nothing to screen, and the answer is
    the same point in the lab, in the frame the labels as written define."""
    clean, _ = fit_still(treadmill)
    fitted, warned = fit_still(swapped(treadmill, slice(None)), artefacts="refuse")
    assert fitted.excluded == () and warned == []
    assert fitted.frame["x"] == "from TM1 towards TM2"
    np.testing.assert_allclose(
        np.nanmedian(fitted.world(), axis=0), np.nanmedian(clean.world(), axis=0), atol=1e-6
    )


def test_a_swap_between_a_reference_and_a_moving_marker_is_refused_and_left_out(treadmill):
    """TM1 and the shank's RLEG1 exchange labels in frames 200 to 204: each cluster breaks its
    shape there; refused naming the frame, left out when excluded."""
    recording = swapped(treadmill, slice(100, 105), "TM1", "RLEG1")
    with pytest.raises(ValueError, match=r"at frame 200 \(2\.00 s\).*pass artefacts='exclude'"):
        fit_still(recording, artefacts="refuse")
    fitted, _ = fit_still(recording)
    assert {a.frame for a in fitted.excluded} == set(range(100, 105))
    assert {a.label for a in fitted.excluded} >= {"TM1", "RLEG1"}


@pytest.mark.parametrize(
    ("artefacts", "code"), [("exclude", 0), ("refuse", 2)], ids=["exclude", "refuse"]
)
def test_jointbench_fit_screens_a_still_reference_from_a_c3d_file(
    tmp_path, capsys, treadmill, artefacts, code
):
    """The command line as the API: a bump of TM1 in row 150 (frame 151 of the file, which
    numbers its frames from 1), left out and warned of, or refused naming it."""
    recording = bumped(treadmill, [150])
    path = write_c3d(tmp_path / "treadmill.c3d", recording.labels, recording.markers)
    argv = ["fit", "center", str(path), "--moving", SHANK, "--reference", TM, "--method", "NM"]
    argv += ["--lab-fixed-reference", "--artefacts", artefacts, "--format", "json"]
    assert main(argv) == code
    out, err = capsys.readouterr()
    if code:
        assert f"{path}: marker TM1 leaves its cluster's rigid shape by " in err, err
        assert "mm at frame 151 (1.51 s)" in err
    else:
        assert "left out 1 frames with artefacts: marker TM1 " in err, err
        assert '"frame": 150' in out


def test_a_still_reference_with_a_bump_is_still_not_fitted_when_not_stated_fixed(treadmill):
    """The screen changes what is measured, not what is stated: unstated, the bumped
    treadmill is a segment too wide, naming the option."""
    with pytest.raises(ValueError, match=r"stated so \(lab_fixed_reference=True"):
        jointbench.fit(bumped(treadmill, [150]), "center", SHANK, TM, artefacts="exclude")


def counted(monkeypatch, name):
    """Calls of ``jointbench.io.segments.<name>``, as the list of their first arguments."""
    calls = []
    original = getattr(segments_module, name)

    def counting(*args, **kwargs):
        calls.append(args[0])
        return original(*args, **kwargs)

    monkeypatch.setattr(segments_module, name, counting)
    return calls


@pytest.mark.parametrize("kind", ["center", "joint_center"])
def test_prepare_bounds_each_cluster_once(monkeypatch, treadmill, kind):
    """One preparation measures each cluster's span once (the moving one, the reference, the
    two joined) and a reference's stillness in the lab once."""
    spans = counted(monkeypatch, "cluster_span")
    motions = counted(monkeypatch, "lab_motion")
    reference = TM if kind == "center" else "RTHI1,RTHI2,RTHI3,RGT"
    options = LAB_FIXED if kind == "center" else {}
    prepare(treadmill, kind, SHANK, reference, artefacts="exclude", **options)
    assert [markers.shape[1] for markers in spans] == [6, 4, 10]
    assert len(motions) == (1 if kind == "center" else 0)


def test_a_marker_seen_only_in_spoilt_frames_shows_no_stillness(treadmill):
    """TM4 seen only in frames 100 to 109, each spoilt by a bump of TM1: no frame shows TM4
    still, so the reference is not taken as still from the others' frames (all frames are
    measured, the bump among them) and is bounded as a segment, naming the bump."""

    def edit(markers, column):
        markers[10:, column("TM4")] = np.nan
        markers[:10, column("TM1")] += [50.0, 0.0, 0.0]

    recording = edited(treadmill, edit)
    spoilt = tuple(Artefact("rigidity", "TM1", row, 50.0, 5.0) for row in range(10))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        alone, joined = segments_module._reference_bounds(
            recording, tuple(TM.split(",")), spoilt, True
        )
    assert alone.largest_mm == MAX_SPAN_MM
    assert (
        "they move in the lab: TM1 lies 12.7 mm or more from its median position in frame 103 "
    ) in alone.why_not_lab
    assert joined.largest_mm == MAX_JOINED_SPAN_MM


#: Out of the treadmill's plane: its four markers tilt to take most of a corner's bump, which
#: leaves each a residual of a quarter of it, under the screen's level up to 20 mm.
OUT_OF_PLANE = (0.0, 0.0, 1.0)


@pytest.mark.parametrize("artefacts", ["refuse", "exclude"])
@pytest.mark.parametrize("row", [0, 150, 299], ids=["first", "middle", "last"])
@pytest.mark.parametrize("size", [5.0, 6.0, 7.0, 9.0])
def test_a_small_bump_in_one_frame_of_a_still_reference_is_not_motion(
    treadmill, size, row, artefacts
):
    """TM1 bumped 5 to 9 mm out of the treadmill's plane in one frame (the first, one in the
    middle, the last): under the screen's level, so no artefact, and over the 5 mm a still
    marker keeps to, but held by no second frame, so no motion either. The frame is kept, as
    any cluster's frame the screen does not flag, and the treadmill is bounded as fixed."""
    fitted, warned = fit_still(
        bumped(treadmill, [row], by=tuple(size * np.array(OUT_OF_PLANE))), artefacts
    )
    assert fitted.excluded == () and warned == []
    assert treadmill.first_frame + row in fitted.frames_used
    assert len(fitted.frames_used) == treadmill.n_frames


def test_a_small_bump_on_two_markers_in_one_frame_is_not_motion(treadmill):
    """TM1 and TM4, two opposite corners, bumped 6 mm in opposite directions in frame 250."""

    def edit(markers, column):
        markers[150, column("TM1")] += [0.0, 0.0, 6.0]
        markers[150, column("TM4")] += [0.0, 0.0, -6.0]

    fitted, warned = fit_still(edited(treadmill, edit), artefacts="refuse")
    assert fitted.excluded == () and warned == []
    assert 250 in fitted.frames_used


def moved(recording, by_row):
    """``recording`` with every treadmill marker displaced by ``by_row`` ``(n_frames, 3)``
    [mm]."""

    def edit(markers, column):
        markers[:, recording.index(TM)] += by_row[:, None, :]

    return edited(recording, edit)


def drift(n_frames, total_mm):
    """A slow drift along x, 0 to ``total_mm`` over the ``n_frames`` ``(n_frames, 3)``."""
    return np.linspace(0.0, total_mm, n_frames)[:, None] * [1.0, 0.0, 0.0]


def step(n_frames, at, by):
    """A step of ``by`` ``(3,)`` [mm] at row ``at``, held to the end ``(n_frames, 3)``."""
    return (np.arange(n_frames) >= at)[:, None] * np.asarray(by, float)


def slide_tm1(recording):
    """TM1 sliding 8 mm along y over rows 100 to 150 and staying there."""

    def edit(markers, column):
        markers[:, column("TM1")] += np.clip((np.arange(len(markers)) - 100) / 50, 0, 1)[
            :, None
        ] * [0.0, 8.0, 0.0]

    return edited(recording, edit)


@pytest.mark.parametrize(
    ("motion", "where"),
    [
        (
            lambda r: moved(r, drift(r.n_frames, 10.0)),
            "TM2 holds positions 9.53 mm apart, at frame 110 (1.10 s) and at frame 389 (3.89 s)",
        ),
        (
            lambda r: moved(r, step(r.n_frames, 100, (0.0, 0.0, 6.0))),
            "TM2 holds positions 6.4 mm apart, at frame 139 (1.39 s) and at frame 338 (3.38 s)",
        ),
        (
            slide_tm1,
            "TM1 holds positions 8.26 mm apart, at frame 123 (1.23 s) and at frame 333 (3.33 s)",
        ),
    ],
    ids=["drift-10mm", "step-6mm-held", "one-marker-slides-8mm"],
)
def test_a_still_reference_that_moves_is_still_refused_as_moving(treadmill, motion, where):
    """Motion held over frames is motion, whichever marker shows it: a 10 mm drift of the whole
    treadmill, a 6 mm step held for the last two thirds of the trial, TM1 sliding 8 mm and
    staying: bounded as a segment, naming the marker, how far apart its held positions lie and
    a frame of each, before and after the step or the slide, the drift's two ends, with
    artefacts excluded too."""
    with pytest.raises(ValueError) as error:
        fit_still(motion(treadmill))
    message = str(error.value)
    assert "and they move in the lab: " in message, message
    assert where in message, message


#: How a refusal names a marker's held positions that lie too far apart: the marker, how far
#: apart [mm] and the two frames, in time order.
HELD_APART = re.compile(
    r"and they move in the lab: (TM\d) holds positions ([\d.]+) mm apart, at frame (\d+) "
    r"\(\S+ s\) and at frame (\d+) \(\S+ s\)"
)


def held_apart(message):
    """The marker, the distance [mm] and the two frames a refusal names as held apart."""
    found = HELD_APART.search(message)
    assert found, message
    return found[1], float(found[2]), int(found[3]), int(found[4])


def one_marker_step(recording, at, by, label="TM1"):
    """``recording`` with marker ``label`` displaced by ``by`` ``(3,)`` [mm] from row ``at`` to
    the end."""

    def edit(markers, column):
        markers[at:, column(label)] += by

    return edited(recording, edit)


@pytest.mark.parametrize("at", [150, 100, 200], ids=["middle", "one-third", "two-thirds"])
def test_a_still_reference_stepping_6mm_is_refused_naming_frames_either_side(treadmill, at):
    """The whole treadmill steps 6 mm along the belt at row 150 (the middle: every marker then
    lies about 3 mm from its median, the median between the two halves), 100 or 200, and stays
    there: it moved 6 mm in the lab, and so would the fitted centre. Refused as moving, naming
    a marker, how far apart its positions before and after lie, and a frame on either side of
    the step (not two frames of the shorter side, whose distance from the median said it)."""
    with pytest.raises(ValueError) as error:
        fit_still(moved(treadmill, step(treadmill.n_frames, at, (6.0, 0.0, 0.0))))
    _, apart, before, after = held_apart(str(error.value))
    assert 5.5 < apart < 7.0
    assert before < treadmill.first_frame + at <= after


def test_a_still_reference_drifting_9mm_is_refused_naming_its_ends(treadmill):
    """A slow drift of 9 mm over the trial leaves every marker within 4.5 mm of its median, and
    moves the treadmill 9 mm in the lab: refused, naming frames near either end."""
    with pytest.raises(ValueError) as error:
        fit_still(moved(treadmill, drift(treadmill.n_frames, 9.0)))
    _, apart, first, last = held_apart(str(error.value))
    assert 8.0 < apart < 9.5
    assert first < treadmill.first_frame + 50
    assert last >= treadmill.first_frame + treadmill.n_frames - 50


@pytest.mark.parametrize("by", [(6.0, 0.0, 0.0), (0.0, 6.0, 0.0), (0.0, 0.0, 6.0)])
def test_one_marker_of_a_still_reference_stepping_6mm_is_refused_naming_it(treadmill, by):
    """TM1 alone steps 6 mm (along x, y, z) at the middle row and stays: under the screen's
    level (the pose takes part of it), so no artefact, but a marker that moved 6 mm in the lab
    and pulls the fitted pose with it. Refused naming TM1 and a frame either side."""
    with pytest.raises(ValueError) as error:
        fit_still(one_marker_step(treadmill, 150, by))
    label, apart, before, after = held_apart(str(error.value))
    assert label == "TM1"
    assert 5.5 < apart < 7.0
    assert before < treadmill.first_frame + 150 <= after


@pytest.mark.parametrize("artefacts", ["refuse", "exclude"])
@pytest.mark.parametrize("rows", [[150, 151], [0, 1], [298, 299]], ids=["middle", "first", "last"])
def test_a_small_bump_held_two_frames_is_not_motion(treadmill, rows, artefacts):
    """TM1 bumped 6 mm out of the treadmill's plane in two consecutive frames and back: under
    the screen's level, so no artefact, and a bump, not a position the marker holds: the
    frames are kept and the treadmill is bounded as fixed, as for a one-frame bump."""
    fitted, warned = fit_still(bumped(treadmill, rows, by=(0.0, 0.0, 6.0)), artefacts)
    assert fitted.excluded == () and warned == []
    assert len(fitted.frames_used) == treadmill.n_frames


@pytest.mark.parametrize("suffix", [".c3d", ".trc"])
def test_jointbench_fit_refuses_a_still_reference_that_stepped(tmp_path, capsys, treadmill, suffix):
    """The command line as the API, from a C3D (frames numbered from 1) and a TRC file: the
    treadmill stepping 6 mm at row 150 is refused, naming a frame either side of the step."""
    recording = moved(treadmill, step(treadmill.n_frames, 150, (0.0, 6.0, 0.0)))
    path = write(tmp_path / f"treadmill{suffix}", recording.labels, recording.markers, "mm")
    argv = ["fit", "center", str(path), "--moving", SHANK, "--reference", TM, "--method", "NM"]
    argv += ["--lab-fixed-reference", "--artefacts", "exclude", "--format", "json"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"{path}: " in err, err
    _, apart, before, after = held_apart(err)
    assert 5.5 < apart < 7.0
    # Row 150 is frame 151 of a C3D file, which numbers its frames from 1, and of a TRC file.
    assert before < 151 <= after


#: The left foot's markers in the knee trial, on which the subject stands: a real cluster
#: still in the lab, with the capture's own noise and the foot's small sway.
STANDING_FOOT = "LCAL,LFT3,LTT2,LMFH1,LHMH5"


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize(("noise_mm", "n_frames"), [(1.0, 3000), (2.0, 300)])
def test_still_markers_with_1_or_2mm_of_noise_do_not_move(seed, noise_mm, n_frames):
    """Four markers fixed in the lab seen with 1 mm of noise on each axis (more than an
    optical system's) over 3000 frames, or 2 mm over 300: held still, whatever the noise's
    extremes."""
    rng = np.random.default_rng(seed)
    markers = TREADMILL + rng.normal(scale=noise_mm, size=(n_frames, 4, 3))
    assert segments_module.lab_motion(markers)[0] <= segments_module.LAB_FIXED_MM


@pytest.mark.parametrize("at", [307, 461, 614], ids=["one-third", "middle", "two-thirds"])
def test_a_real_still_cluster_is_still_and_moves_when_stepped_6mm(at):
    """The standing foot over the whole knee trial is still; stepped 6 mm along x at a third,
    the middle or two thirds of the trial and staying there, it moved, and the rows named lie
    on either side of the step."""
    foot = read(KNEE).select(STANDING_FOOT)
    assert segments_module.lab_motion(foot)[0] <= segments_module.LAB_FIXED_MM
    stepped = foot + step(len(foot), at, (6.0, 0.0, 0.0))[:, None, :]
    moved_mm, _, before, after = segments_module.lab_motion(stepped)
    assert 5.5 < moved_mm < 7.0
    assert before < at <= after


def every_third_frame(n_frames, by):
    """A displacement of ``by`` ``(3,)`` [mm] in every third row, none in the others
    ``(n_frames, 3)``: a mount that vibrates."""
    return (np.arange(n_frames) % 3 == 0)[:, None] * np.asarray(by, float)


@pytest.mark.parametrize("size", [6.0, 20.0])
def test_a_reference_moving_together_in_every_third_frame_is_refused_as_moving(treadmill, size):
    """The whole treadmill displaced 6 or 20 mm in every third frame, a hundred times in the
    trial: no sample of a marker is held in the next, but every marker moves with the others,
    which keeps the cluster's shape, so the screen cannot see it as a marker's bump. Motion the
    capture followed, refused as it was before stillness was held over two samples."""
    with pytest.raises(ValueError) as error:
        fit_still(moved(treadmill, every_third_frame(treadmill.n_frames, (size, 0.0, 0.0))))
    message = str(error.value)
    assert "and they move in the lab: " in message, message
    held = r"TM\d lies [\d.]+ mm or more from its median position in frame \d+ \("
    assert re.search(held, message), message


@pytest.mark.parametrize("suffix", [".c3d", ".trc", ".csv"])
def test_jointbench_fit_keeps_a_still_reference_bumped_in_one_frame(
    tmp_path, capsys, treadmill, suffix
):
    """The command line as the API, from each reader: TM1 bumped 6 mm out of the treadmill's
    plane in row 150 is neither an artefact nor motion, and the fit uses every frame."""
    recording = bumped(treadmill, [150], by=(0.0, 0.0, 6.0))
    path = write(tmp_path / f"treadmill{suffix}", recording.labels, recording.markers, "mm")
    argv = ["fit", "center", str(path), "--moving", SHANK, "--reference", TM, "--method", "NM"]
    argv += ["--lab-fixed-reference", "--format", "json"]
    assert main(argv) == 0, capsys.readouterr().err
    out, err = capsys.readouterr()
    assert '"n_frames_used": 300' in out
    assert "left out" not in err


#: A square wand frame 800 mm on a side, TM1 and TM4 (and TM2 and TM3) at opposite corners
#: [mm].
SQUARE = np.array(
    [[-400.0, -300.0, 0.0], [400.0, -300.0, 0.0], [-400.0, 500.0, 0.0], [400.0, 500.0, 0.0]]
)


@pytest.mark.parametrize(
    ("corners", "first", "second"),
    [
        (TREADMILL, "TM1", "TM2"),
        (TREADMILL, "TM3", "TM4"),
        (TREADMILL, "TM1", "TM3"),
        (TREADMILL, "TM1", "TM4"),
        (TREADMILL, "TM2", "TM3"),
        (SQUARE, "TM1", "TM2"),
        (SQUARE, "TM2", "TM4"),
        (HAND_PLACED, "TM1", "TM4"),
    ],
    ids=[
        "rectangle-long-side",
        "rectangle-other-long-side",
        "rectangle-short-side",
        "rectangle-diagonal",
        "rectangle-other-diagonal",
        "square-side",
        "square-other-side",
        "hand-placed-diagonal",
    ],
)
def test_a_swap_in_a_symmetric_still_reference_names_the_pair_that_swapped(
    knee, corners, first, second
):
    """A rectangle's (or a square's) symmetry fits its shape alike with the swapped pair
    exchanged or with the pair it maps that one to (TM1 and TM2, or TM3 and TM4: the 180 deg turn
    about the axis between them). The frames around the swap tell them apart, as the swapped
    pair's markers step back where they were and the other pair's would turn the frame over:
    one swap, of the pair that swapped, from its first frame to its last."""
    recording = swapped(with_treadmill(knee, corners), slice(150, 160), first, second)
    message = refused_swap(recording, first, second)
    assert message.count("exchange labels") == 1, message
    assert_swap_left_out(recording, first, second)


def test_a_swap_the_frames_around_cannot_place_names_both_pairs_a_symmetry_fits(knee):
    """TM1 and TM2 of the rectangle exchanged in frames 250 to 259, the treadmill unseen in the
    three frames on either side: its symmetry fits TM3 and TM4 exchanged alike, and no frame
    next to the swap tells which pair it was. The message says so, naming both, rather than
    one with confidence."""

    def unseen(markers, column):
        for label in TM.split(","):
            markers[147:150, column(label)] = np.nan
            markers[160:163, column(label)] = np.nan

    recording = edited(swapped(with_treadmill(knee, TREADMILL), slice(150, 160)), unseen)
    with pytest.raises(ValueError) as error:
        fit_still(recording, artefacts="refuse")
    message = str(error.value)
    assert message.startswith(
        "treadmill.c3d: markers TM1 and TM2, or TM3 and TM4 (the cluster's symmetry fits either "
        "pair alike, and the frames next to the swap do not tell which), exchange labels at "
        "frame 250 (2.50 s) and back at frame 260 (2.60 s)"
    ), message
    assert message.count("exchange labels") == 1, message


#: An isosceles triangle (TM1 and TM2 its base, TM3 its apex) with TM4 on its axis, in its
#: plane [mm]: exchanging TM1 and TM2 keeps its shape (the plate turned 180 deg about its axis).
ISOSCELES = np.array(
    [[-400.0, -300.0, 0.0], [400.0, -300.0, 0.0], [0.0, 500.0, 0.0], [0.0, 100.0, 0.0]]
)


@pytest.mark.parametrize(
    ("corners", "first", "second"),
    [(SQUARE, "TM1", "TM4"), (SQUARE, "TM2", "TM3"), (ISOSCELES, "TM1", "TM2")],
    ids=["square-diagonal", "square-other-diagonal", "isosceles-base"],
)
def test_a_swap_that_keeps_a_still_reference_s_shape_is_found_over_all_its_frames(
    knee, corners, first, second
):
    """A square's diagonal (the square turned 180 deg about the other diagonal) or an isosceles
    triangle's base, exchanged in frames 250 to 259: the shape is the same, so only time order
    shows the swap, as both markers jump where the labels change and back. Named as a swap of
    those two from its first frame to its last, and every frame of it left out when excluded,
    not only the two steps: the frames between carry the reference turned over, and would move
    the answer by metres."""
    recording = swapped(with_treadmill(knee, corners), slice(150, 160), first, second)
    refused_swap(recording, first, second)
    assert_swap_left_out(recording, first, second)


@pytest.mark.parametrize("suffix", [".c3d", ".trc", ".csv"])
def test_jointbench_fit_names_the_pair_that_swapped_in_a_rectangle(tmp_path, capsys, knee, suffix):
    """The command line as the API, from each reader: TM1 and TM2 of the perfect rectangle
    exchanged in rows 150 to 159 are refused as one swap of those two, and left out, all ten
    frames, when excluded."""
    recording = swapped(with_treadmill(knee, TREADMILL), slice(150, 160))
    path = write(tmp_path / f"treadmill{suffix}", recording.labels, recording.markers, "mm")
    argv = ["fit", "center", str(path), "--moving", SHANK, "--reference", TM, "--method", "NM"]
    argv += ["--lab-fixed-reference", "--format", "json"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    named = r": markers TM1 and TM2 exchange labels at frame \d+ (\(\S+ s\) )?and back at frame "
    assert re.search(named, err), err
    assert err.count("exchange labels") == 1, err
    assert main([*argv, "--artefacts", "exclude"]) == 0
    out, err = capsys.readouterr()
    assert '"n_frames_used": 290' in out
    assert "left out 10 frames with artefacts: markers TM1 and TM2 exchange labels" in err, err
