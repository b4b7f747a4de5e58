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
