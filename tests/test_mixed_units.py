"""Frames in another unit among millimetres: the size check judges each frame, not the median.

A recording in which some frames (a block, or scattered ones) hold metres and the rest
millimetres has a median size a body segment's; the checks must name those frames rather than
fit them, whichever public call receives them.
"""

from __future__ import annotations

import numpy as np
import pytest
from rigs import two_segments

from jointbench import api
from jointbench.estimators import registry
from jointbench.estimators.validation import (
    check_input,
    check_input_many,
    check_span,
    frames_off_scale,
)

N_FRAMES = 120
BLOCK = np.arange(40, 80)
SCATTERED = np.sort(np.random.default_rng(0).choice(N_FRAMES, 40, replace=False))


def _in_metres(markers: np.ndarray, frames: np.ndarray) -> np.ndarray:
    mixed = markers.copy()
    mixed[frames] /= 1000.0
    return mixed


def _arrays(kind: str, frames: np.ndarray) -> tuple[np.ndarray, ...]:
    if kind == "joint_center":
        return tuple(_in_metres(a, frames) for a in two_segments(N_FRAMES))
    relative = "hinge" if kind == "axis" else "ball"
    _, moving = two_segments(N_FRAMES, relative=relative, proximal_moves=False)
    return (_in_metres(moving, frames),)


CASES = [
    (kind, method, frames)
    for kind, method in (("center", "LS"), ("axis", "planar"), ("joint_center", "SCoRE"))
    for frames in (BLOCK, SCATTERED)
]
FIT = {"center": api.fit_center, "axis": api.fit_axis, "joint_center": api.fit_joint_center}


def _names_the_frames(error: pytest.ExceptionInfo, frames: np.ndarray) -> None:
    text = str(error.value)
    assert "another unit" in text
    assert f"frame {frames[0]} " in text
    assert f"{len(frames)} frames" in text


@pytest.mark.parametrize(("kind", "method", "frames"), CASES)
@pytest.mark.parametrize("artefacts", ["refuse", "warn", "ignore"])
def test_public_calls_name_the_frames_in_another_unit(kind, method, frames, artefacts):
    with pytest.raises(ValueError, match="another unit") as error:
        FIT[kind](*_arrays(kind, frames), method, artefacts=artefacts)
    _names_the_frames(error, frames)


@pytest.mark.parametrize(("kind", "method", "frames"), CASES)
def test_checked_registry_calls_name_the_frames(kind, method, frames):
    with pytest.raises(ValueError, match="another unit") as error:
        registry.get(kind, method)(*_arrays(kind, frames))
    _names_the_frames(error, frames)


@pytest.mark.parametrize(("kind", "method", "frames"), CASES)
def test_many_trials_name_the_trial_and_frames(kind, method, frames):
    clean = _arrays(kind, np.arange(0))
    mixed = _arrays(kind, frames)
    segments = tuple(np.stack([c, m]) for c, m in zip(clean, mixed, strict=True))
    errors = check_input_many(kind, segments, 2).errors
    assert errors[0] is None
    assert "another unit" in str(errors[1])
    results = registry.many(kind, method)(*segments)
    assert isinstance(results[1], ValueError)
    assert "another unit" in str(results[1])


def test_centimetres_among_millimetres_are_named():
    _, moving = two_segments(N_FRAMES, proximal_moves=False)
    mixed = moving.copy()
    mixed[BLOCK] /= 10.0
    with pytest.raises(ValueError, match="another unit"):
        check_input("center", (mixed,))


def test_a_cluster_that_changes_shape_by_tens_of_percent_passes():
    # Skin markers move on the bone by tens of percent of their distances, not by a unit.
    _, moving = two_segments(N_FRAMES, proximal_moves=False)
    stretched = moving.copy()
    centre = moving.mean(axis=1, keepdims=True)
    stretched[BLOCK] = centre[BLOCK] + 1.5 * (moving[BLOCK] - centre[BLOCK])
    check_input("center", (stretched,))


def _pair_with_a_gap_filled() -> np.ndarray:
    """Two markers 10 mm apart on a segment turning 180 degrees about a centre 400 mm away
    ``(N_FRAMES, 2, 3)`` [mm], one of them filled in by a straight line over frames 30 to 89,
    as software fills a gap: the chord cuts the arc, up to ~120 mm from the marker."""
    angles = np.deg2rad(np.linspace(-90.0, 90.0, N_FRAMES))
    arm = np.array([[0.0, -400.0], [0.0, -410.0]])  # (2 markers, y/z) [mm]
    cos, sin = np.cos(angles)[:, None], np.sin(angles)[:, None]
    markers = np.zeros((N_FRAMES, 2, 3))
    markers[:, :, 0] = 30.0 * np.sin(3.0 * angles)[:, None]
    markers[:, :, 1] = cos * arm[:, 0] - sin * arm[:, 1]
    markers[:, :, 2] = sin * arm[:, 0] + cos * arm[:, 1]
    markers += np.array([150.0, 250.0, 900.0])
    gap = np.arange(30, 90)
    start, stop = gap[0] - 1, gap[-1] + 1
    weights = np.linspace(0.0, 1.0, stop - start + 1)[1:-1, None]
    markers[gap, 1] = (1.0 - weights) * markers[start, 1] + weights * markers[stop, 1]
    return markers


def test_a_pair_with_one_marker_astray_is_no_unit():
    # With two markers the one distance is every distance: a marker gap-filled, or a ghost
    # marker for some frames, changes it as a unit would. Three markers keep a distance.
    markers = _pair_with_a_gap_filled()
    distances = np.linalg.norm(markers[:, 0] - markers[:, 1], axis=1)
    assert distances.max() > 10.0 * np.median(distances)  # astray by more than a unit's gap
    check_input("center", (markers,))


def test_a_marker_astray_in_a_cluster_is_no_unit():
    # A ghost taken for one marker for some frames moves that marker's distances tenfold, but
    # the other markers keep theirs: not a unit, whose frames change every distance.
    _, moving = two_segments(N_FRAMES, proximal_moves=False)
    ghost = moving.copy()
    ghost[BLOCK, 0] = moving[BLOCK, 1] + 20.0 * (moving[BLOCK, 0] - moving[BLOCK, 1])
    near = moving.copy()
    near[BLOCK, 0] = moving[BLOCK, 1] + 0.01 * (moving[BLOCK, 0] - moving[BLOCK, 1])
    for astray in (ghost, near):
        check_input("center", (astray,))


def test_half_the_frames_in_metres_name_the_others_size():
    # With half the frames in each unit, the median over all of them lies between the two
    # sizes, no frame's: the error gives the size of the frames on the cluster's scale.
    _, moving = two_segments(N_FRAMES, proximal_moves=False)
    mixed = _in_metres(moving, np.arange(0, N_FRAMES, 2))
    span = np.median(np.linalg.norm(moving[:, :, None] - moving[:, None], axis=-1).max((1, 2)))
    with pytest.raises(ValueError, match="another unit") as error:
        check_input("center", (mixed,))
    assert f"lie {span:.3g} mm apart" in str(error.value)


def _cluster_of_four() -> np.ndarray:
    """Four markers ``(N_FRAMES, 4, 3)`` [mm] of a segment turning about JOINT: DISTAL and its
    centroid lifted 40 mm off their plane."""
    _, moving = two_segments(N_FRAMES, proximal_moves=False)
    normal = np.cross(moving[:, 1] - moving[:, 0], moving[:, 2] - moving[:, 0])
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    fourth = moving.mean(axis=1) + 40.0 * normal
    return np.concatenate([moving, fourth[:, None]], axis=1)


def test_frames_in_metres_with_a_gap_are_judged_by_the_markers_they_show():
    # A marker missing in the metre frames, and a frame that shows none: the frames are
    # named by what they show, against the same markers in the other frames.
    markers = _in_metres(_cluster_of_four(), BLOCK)
    markers[BLOCK, 3] = np.nan
    markers[5] = np.nan
    with pytest.raises(ValueError, match="another unit") as error:
        check_span(markers)
    text = str(error.value)
    assert f"frame {BLOCK[0]} " in text
    assert "nan" not in text
    assert f"markers shown at frame {BLOCK[0]} " in text
    off, typical, spans = frames_off_scale(markers)
    assert off.tolist() == BLOCK.tolist()
    shown = markers[BLOCK[0], :3]
    assert spans[BLOCK[0]] == pytest.approx(np.linalg.norm(shown[:, None] - shown, axis=-1).max())
    assert typical[BLOCK[0]] == pytest.approx(1000.0 * spans[BLOCK[0]], rel=0.01)


def test_a_gap_in_the_frames_of_the_typical_size_is_no_change_of_unit():
    # The farthest marker missing: the others lie closer together than the whole cluster, as
    # they do in every frame; compared with the same markers elsewhere, no frame is off.
    markers = _cluster_of_four()
    markers[BLOCK, 3] = np.nan
    markers[10:20, 0] = np.nan
    assert frames_off_scale(markers)[0].size == 0
    check_span(markers)


#: The other frames than BLOCK, most of them.
OUTSIDE_BLOCK = np.setdiff1d(np.arange(N_FRAMES), BLOCK)


@pytest.mark.parametrize(("metres", "smaller"), [(BLOCK, True), (OUTSIDE_BLOCK, False)])
def test_the_refusal_says_how_the_frames_differ_and_which_are_millimetres(metres, smaller):
    # Most frames in millimetres and some in metres, or most in metres and some in
    # millimetres: the refusal names the fewer, BLOCK, says how they differ from the rest and
    # which group is a body segment's size in millimetres.
    _, moving = two_segments(N_FRAMES, proximal_moves=False)
    with pytest.raises(ValueError, match="another unit") as error:
        check_input("center", (_in_metres(moving, metres),))
    text = str(error.value)
    assert f"{BLOCK.size} frames in all, frames {BLOCK[0]} to {BLOCK[-1]}" in text
    if smaller:
        assert "those frames are 1000 times smaller than the rest:" in text
        assert "the rest are a body segment's size in millimetres" in text
    else:
        assert "those frames are 1000 times larger than the rest:" in text
        assert "those frames are a body segment's size in millimetres" in text
    assert "among millimetres" not in text


def test_a_refusal_with_a_gap_gives_the_first_frames_size_and_the_typical_one_of_the_rest():
    # The first frame off the scale in centimetres, the others in metres, a marker missing in
    # all of them, noisy markers: the refusal's sizes are the first frame's and the median
    # over the frames on the scale that show the same markers, not over every frame.
    markers = _cluster_of_four() + np.random.default_rng(1).normal(scale=0.3, size=(N_FRAMES, 4, 3))
    markers = _in_metres(markers, BLOCK[1:])
    markers[BLOCK[0]] /= 10.0
    markers[BLOCK, 3] = np.nan
    off, typical, spans = frames_off_scale(markers)
    assert off.tolist() == BLOCK.tolist()
    shown = markers[:, :3]
    sizes = np.linalg.norm(shown[:, :, None] - shown[:, None], axis=-1).max(axis=(1, 2))
    on_scale = np.setdiff1d(np.arange(N_FRAMES), BLOCK)
    assert typical[BLOCK[0]] == pytest.approx(np.median(sizes[on_scale]), rel=1e-12)
    with pytest.raises(ValueError, match="another unit") as error:
        check_span(markers)
    assert f"but {spans[BLOCK[0]]:.3g} mm at frame {BLOCK[0]} " in str(error.value)
    assert f"lie {typical[BLOCK[0]]:.3g} mm apart" in str(error.value)


#: Three markers of a plate, two of them 10 mm apart and the third 50 mm from both [mm].
_CLOSE_PAIR = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [5.0, 50.0, 0.0]])


@pytest.mark.parametrize("gap", [False, True])
def test_a_marker_astray_from_the_closest_pair_is_no_change_of_unit(gap):
    # A ghost 500 mm away for one of the two close markers in one frame: that frame's largest
    # and smallest distances both grow more than ten times, but the other two markers keep
    # theirs, as in no frame in another unit; with a fourth marker missing there, the three
    # shown are judged alike. The artefact screen's to find, no unit to refuse.
    _, moving = two_segments(N_FRAMES, proximal_moves=False)
    markers = _cluster_of_four()
    markers[:, :3] = moving[:, :1] + _CLOSE_PAIR
    markers[50, 0] += [500.0, 0.0, 0.0]
    if gap:
        markers[40:60, 3] = np.nan
    assert frames_off_scale(markers)[0].size == 0
    check_span(markers)
    if not gap:
        check_input("center", (markers,))


def test_a_single_frame_in_another_unit_is_one_frame():
    _, moving = two_segments(N_FRAMES, proximal_moves=False)
    with pytest.raises(ValueError, match="another unit") as error:
        check_input("center", (_in_metres(moving, np.array([57])),))
    text = str(error.value)
    assert "(1 frame in all, frame 57, each with" in text
    assert "that frame is 1000 times smaller than the rest:" in text
