"""A recording with frames in another unit among millimetres: its markers' check names the
file's frames and the unit it states, before the artefact screen can read those frames as a
broken shape (refused) or leave them out as artefacts (fitted)."""

from __future__ import annotations

import numpy as np
import pytest
from rigs import two_segments

from jointbench.io.fit import fit
from jointbench.io.recording import Recording

LABELS = ("P1", "P2", "P3", "D1", "D2", "D3")


def _recording(frames: np.ndarray, *, gap_row: int | None = None) -> Recording:
    proximal, distal = two_segments(120)
    markers = np.concatenate([proximal, distal], axis=1)
    markers[frames] /= 1000.0
    if gap_row is not None:
        markers[gap_row, 4] = np.nan
    return Recording(LABELS, markers, rate_hz=100.0, first_frame=1, source="trial.csv")


@pytest.mark.parametrize("kind", ["center", "joint_center"])
@pytest.mark.parametrize("artefacts", ["refuse", "exclude"])
def test_a_block_in_metres_is_named_by_the_files_frames(kind, artefacts):
    recording = _recording(np.arange(40, 80), gap_row=10)
    method = "SCoRE" if kind == "joint_center" else "LS"
    with pytest.raises(ValueError, match="another unit") as error:
        fit(recording, kind, "D1,D2,D3", "P1,P2,P3", method=method, artefacts=artefacts)
    text = str(error.value)
    assert text.startswith("trial.csv: markers ")
    assert "frame 41 (0.41 s)" in text
    assert "40 frames in all, frames 41 to 80" in text
    assert "'mm'" in text


def test_scattered_frames_in_metres_are_named():
    rows = np.array([3, 17, 18, 19, 64, 100])
    with pytest.raises(ValueError, match="6 frames in all, frames 4, 18 to 20, 65, 101"):
        fit(_recording(rows), "center", "D1,D2,D3", "P1,P2,P3", method="LS")


def _four_markers(frames: np.ndarray, gap: np.ndarray, *, units: str = "mm") -> Recording:
    """A segment of four markers D1 to D4 turning about the joint ``(120, 4, 3)`` [mm], its
    ``frames`` divided by 1000 and D4 missing in ``gap``, of a file that states ``units``
    (``""``: none)."""
    _, distal = two_segments(120, proximal_moves=False)
    normal = np.cross(distal[:, 1] - distal[:, 0], distal[:, 2] - distal[:, 0])
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    markers = np.concatenate([distal, (distal.mean(axis=1) + 40.0 * normal)[:, None]], axis=1)
    markers[frames] /= 1000.0
    markers[gap, 3] = np.nan
    return Recording(
        ("D1", "D2", "D3", "D4"),
        markers,
        rate_hz=100.0,
        first_frame=1,
        source="trial.csv",
        units=units,
    )


@pytest.mark.parametrize("artefacts", ["refuse", "exclude"])
def test_frames_in_metres_with_a_marker_missing_are_named(artefacts):
    # D4 missing in every frame in metres: those frames are judged by D1 to D3 against the
    # same three markers in the others.
    block = np.arange(40, 80)
    recording = _four_markers(block, block)
    with pytest.raises(ValueError, match="another unit") as error:
        fit(recording, "center", "D1,D2,D3,D4", method="LS", artefacts=artefacts)
    text = str(error.value)
    assert "40 frames in all, frames 41 to 80" in text
    assert "markers shown at frame 41 (0.41 s)" in text


@pytest.mark.parametrize(
    ("metres", "smaller"), [(np.arange(40, 80), True), (np.r_[0:40, 80:120], False)]
)
def test_the_refusal_says_which_frames_are_in_the_files_unit(metres, smaller):
    # A minority in metres among millimetres, or in millimetres among metres: the frames named
    # are the minority either way, and the refusal says which group is in the file's unit.
    recording = _four_markers(metres, np.arange(0))
    with pytest.raises(ValueError, match="another unit") as error:
        fit(recording, "center", "D1,D2,D3,D4", method="LS")
    text = str(error.value)
    assert "40 frames in all, frames 41 to 80" in text
    if smaller:
        assert "the rest are a body segment's size in the file's 'mm'" in text
    else:
        assert "those frames are a body segment's size in the file's 'mm'" in text
    assert "among the file's" not in text


def test_the_refusal_of_a_file_that_states_no_unit_names_the_unit_it_is_read_in():
    # A CSV states no unit: its frames are not said to be in a unit "the file's ''".
    recording = _four_markers(np.arange(40, 80), np.arange(0), units="")
    with pytest.raises(ValueError, match="another unit") as error:
        fit(recording, "center", "D1,D2,D3,D4", method="LS")
    text = str(error.value)
    assert (
        "the rest are a body segment's size in mm, which the file is read in (it states no unit)"
        in text
    )
    assert "the file's ''" not in text
