"""Paths by which an answer from poses whose fit stopped short can still read as converged.

Paper C §5's alternation of SVD poses and body-fixed coordinates can stop at its iteration
limit; a pose-based method's result must then say so (``converged=False``, a status naming
the pose fit), whichever way the poses reached it: fitted in the call, read back from the
poses file the pipeline's pose-based estimators share, or refitted by a recording's bootstrap.
"""

from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq
import pytest
from test_support_sweep import TRIALS as SWEEP

import jointbench
from jointbench.estimators.registry import get, many
from jointbench.estimators.segment_poses import trial_poses
from jointbench.io.recording import Recording
from jointbench.numerics.poses import fit_rigid_poses
from jointbench.resultfiles.parquet import read_poses, write_poses_blocks
from jointbench.simulate.hip_sta import thigh_in_pelvis_frame

TWO_SEGMENTS = [arrays for kind, arrays in SWEEP if kind == "joint_center"]


def _stopped_far(min_change_mm: float) -> list[tuple[np.ndarray, np.ndarray]]:
    """Two-segment sweep trials whose proximal pose fit stopped with its last change of the
    body-fixed coordinates at least ``min_change_mm`` [mm]: clearly not converged."""
    return [
        arrays
        for arrays in TWO_SEGMENTS
        if float(fit_rigid_poses(arrays[0]).change_mm) >= min_change_mm
    ]


@pytest.fixture(scope="module")
def stopped() -> tuple[np.ndarray, np.ndarray]:
    found = _stopped_far(1e-3)
    assert found
    return found[0]


def test_poses_read_back_from_a_poses_file_keep_how_their_fit_ended(stopped, tmp_path):
    """The pipeline fits a study's poses once into a poses file when two or more pose-based
    methods share them (the hip studies' four), and its estimate jobs read them back: the
    answer from them must read as the same call on the markers alone does."""
    proximal, distal = stopped
    segments = {"proximal": proximal[None], "distal": distal[None]}
    fitted = trial_poses(segments, min_frames=3)
    assert fitted[0]["proximal"].converged is False
    path = tmp_path / "poses.parquet"
    write_poses_blocks(path, [fitted], shapes={k: v.shape for k, v in segments.items()})
    stored = read_poses(path, 0, segments)
    for method in ("SCoRE", "analytic", "gauss-markov-frame0"):
        fit = many("joint_center", method, checked=False)
        (alone,) = fit(proximal[None], distal[None])
        (shared,) = fit(proximal[None], distal[None], poses=stored)
        assert not alone.converged
        assert (shared.converged, shared.status) == (alone.converged, alone.status), method


def test_ma_says_when_its_poses_did_not_converge(stopped):
    """MA fits the moving segment's poses by the same alternation (its step 1), so its answer
    on poses whose fit stopped with millimetres still to go must read as SCoRE's does on
    them: ``converged=False``, naming the pose fit."""
    score = get("center", "SCoRE")(stopped[0])
    assert not score.converged and "pose fit stopped" in score.status
    result = get("center", "MA")(stopped[0])
    assert not result.converged, result.status
    assert "pose fit stopped" in result.status


def test_a_bootstrap_on_poses_that_do_not_converge_names_the_pose_fit():
    """A recording whose pose fit stops short: with ``n_bootstrap`` the user gets either the
    fit, saying its poses did not converge, or a refusal naming that cause, not one blaming
    too few frames or too little motion."""
    proximal, _ = _stopped_far(1e-7)[0]
    labels = tuple(f"M{k}" for k in range(proximal.shape[1]))
    recording = Recording(labels=labels, markers=proximal.copy(), rate_hz=100.0, source="trial")
    plain = jointbench.fit(recording, "center", list(labels), method="SCoRE")
    assert not plain.result.converged
    try:
        fitted = jointbench.fit(recording, "center", list(labels), method="SCoRE", n_bootstrap=20)
    except ValueError as error:
        assert "pose fit" in str(error), str(error)
    else:
        assert not fitted.result.converged


def test_a_poses_file_that_does_not_say_how_its_fits_ended_is_refused(stopped, tmp_path):
    proximal, distal = stopped
    segments = {"proximal": proximal[None], "distal": distal[None]}
    path = tmp_path / "poses.parquet"
    write_poses_blocks(
        path,
        [trial_poses(segments, min_frames=3)],
        shapes={k: v.shape for k, v in segments.items()},
    )
    table = pq.read_table(path)
    pq.write_table(table.drop_columns(["distal/iterations"]), path)
    with pytest.raises(ValueError, match="has no column 'distal/iterations': it does not say"):
        read_poses(path, 0, segments)


def test_the_simulated_pelvis_frame_refuses_pelvis_poses_that_did_not_converge(stopped):
    proximal, distal = stopped
    with pytest.raises(ValueError, match="hip_sta trial 0: the proximal markers' pose fit stopped"):
        thigh_in_pelvis_frame(proximal[None], distal[None])
    settled = _settled_trial()
    assert thigh_in_pelvis_frame(settled[0][None], settled[1][None]).shape == settled[1][None].shape


def _settled_trial() -> tuple[np.ndarray, np.ndarray]:
    return next(arrays for arrays in TWO_SEGMENTS if fit_rigid_poses(arrays[0]).converged)
