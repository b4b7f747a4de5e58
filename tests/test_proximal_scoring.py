"""A joint centre scored relative to the proximal markers, in the estimate jobs and at collect."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from jointbench.configuration import config as study_config
from jointbench.geometry import rotation_matrix
from jointbench.resultfiles.parquet import write_dataset, write_table
from jointbench.resultfiles.schema import check_estimates
from jointbench.running.collected import collect
from jointbench.running.run import estimate, simulate_condition
from jointbench.running.scoring import CHI2_3DOF_95, PROXIMAL_COLUMNS, score_columns
from jointbench.simulate import PROXIMAL_TRUTH

ROOT = Path(__file__).resolve().parents[1]

TRUE_MARKERS = np.array([[0.0, 0.0, 500.0], [150.0, 0.0, 520.0], [40.0, 170.0, 480.0]])
TRUE_CENTER = np.array([10.0, -20.0, 0.0])
TRUTH = {"center": TRUE_CENTER.tolist(), PROXIMAL_TRUTH: TRUE_MARKERS.tolist()}


def _placed(points, rotvec, shift):
    """``points`` ``(..., 3)`` moved by the rigid motion ``rotation_matrix(rotvec)``, ``shift``."""
    return np.asarray(points) @ rotation_matrix(np.asarray(rotvec)).T + np.asarray(shift)


# Two trials whose frames a noisy frame-0 fit placed 0.6° and 1.1° off and a few mm aside.
PLACEMENTS = [((0.01, 0.0, 0.0), (1.0, 2.0, 0.0)), ((0.0, -0.02, 0.005), (0.0, -3.0, 1.5))]
RECORDED = np.stack([_placed(TRUE_MARKERS, r, t) for r, t in PLACEMENTS])


def _rows(centres, covariance_mm2=0.04):
    centres = np.asarray(centres, dtype=float)
    return {
        "center_x": centres[:, 0],
        "center_y": centres[:, 1],
        "center_z": centres[:, 2],
        **{name: np.full(len(centres), covariance_mm2) for name in ("cov_xx", "cov_yy", "cov_zz")},
        **{name: np.zeros(len(centres)) for name in ("cov_xy", "cov_xz", "cov_yz")},
    }


def test_the_placement_of_the_frame_drops_out_relative_to_the_proximal_markers():
    """The true centre in each trial's misplaced frame is off by mm in the world, exact
    relative to the proximal markers, and inside its 0.2 mm ellipsoid there."""
    centres = [_placed(TRUE_CENTER, r, t) for r, t in PLACEMENTS]
    scores = score_columns("joint_center", _rows(centres), TRUTH, RECORDED)
    assert (scores["error_mm"] > 1.0).all()
    np.testing.assert_allclose(scores["error_proximal_mm"], 0.0, atol=1e-9)
    np.testing.assert_allclose(scores["sqrt_trace_cov_proximal_mm"], np.sqrt(0.12))
    assert (scores["mahalanobis_sq_proximal"] <= CHI2_3DOF_95).all()
    assert (scores["mahalanobis_sq"] > CHI2_3DOF_95).all()


def test_an_error_relative_to_the_markers_is_kept():
    """A centre 1 mm off relative to the markers is 1 mm off, however the frame was placed."""
    offset = np.array([0.0, 0.6, 0.8])
    centres = [_placed(TRUE_CENTER + offset, r, t) for r, t in PLACEMENTS]
    scores = score_columns("joint_center", _rows(centres), TRUTH, RECORDED)
    np.testing.assert_allclose(scores["error_proximal_mm"], 1.0, atol=1e-9)


def test_a_centre_given_relative_to_the_proximal_frame_is_the_one_scored():
    """A method's own centre relative to the proximal markers (its proximal columns) is
    scored there, its shared-frame centre in the world."""
    proximal = [_placed(TRUE_CENTER, r, t) for r, t in PLACEMENTS]
    rows = _rows(np.tile(TRUE_CENTER + 5.0, (2, 1)))
    for axis, name in enumerate(PROXIMAL_COLUMNS[:3]):
        rows[name] = np.array([p[axis] for p in proximal])
    for name in PROXIMAL_COLUMNS[3:]:
        rows[name] = np.full(2, 0.01 if name.endswith(("xx", "yy", "zz")) else 0.0)
    scores = score_columns("joint_center", rows, TRUTH, RECORDED)
    np.testing.assert_allclose(scores["error_mm"], 5.0 * np.sqrt(3))
    np.testing.assert_allclose(scores["error_proximal_mm"], 0.0, atol=1e-9)
    np.testing.assert_allclose(scores["sqrt_trace_cov_proximal_mm"], np.sqrt(0.03))


def test_without_proximal_markers_the_proximal_scores_are_nan():
    centres = [TRUE_CENTER, TRUE_CENTER]
    for truth, recorded in (({"center": TRUE_CENTER.tolist()}, RECORDED), (TRUTH, None)):
        scores = score_columns("joint_center", _rows(centres), truth, recorded)
        assert np.isnan(scores["error_proximal_mm"]).all()
        np.testing.assert_allclose(scores["error_mm"], 0.0)


@pytest.fixture(scope="module")
def hip_condition():
    config = study_config.load_config(ROOT / "config" / "config.yaml")
    config = {**config, "studies": {"hip": {**config["studies"]["hip"], "trials": 6}}}
    condition = {"n_frames": 300}
    return condition, simulate_condition(config, "hip", condition)


def test_the_hip_estimates_are_scored_relative_to_the_proximal_markers(hip_condition):
    """gauss-markov-frame0's centre relative to the proximal markers is far closer than its
    world-frame centre, whose error the noisy frame-0 placement sets; the estimate job's and
    collect's scores are the same numbers."""
    condition, trials = hip_condition
    rows = estimate("hip", "gauss-markov-frame0", trials, condition)
    assert rows["error_proximal_mm"].max() < 0.5 * rows["error_mm"].median()
    assert np.isfinite(rows[list(PROXIMAL_COLUMNS)].to_numpy()).all()
    assert np.isfinite(rows["mahalanobis_sq_proximal"]).all()


def test_collect_scores_the_proximal_columns_from_the_dataset(hip_condition, tmp_path):
    """collect reads each trial's frame-0 proximal markers from the dataset and holds the
    estimate job's proximal scores to its own; a file whose scores disagree is refused."""
    condition, trials = hip_condition
    dataset = tmp_path / "datasets" / "n_frames=300.parquet"
    dataset.parent.mkdir()
    write_dataset(dataset, trials, study="hip", condition=condition)
    rows = estimate("hip", "SCoRE", trials, condition)
    path = tmp_path / "SCoRE" / "n_frames=300.parquet"
    path.parent.mkdir()
    # Trials in another order than the dataset's: the markers are matched by trial number.
    write_table(rows.iloc[::-1].reset_index(drop=True), path, {})
    collected = collect("hip", [path], str(tmp_path / "collected.parquet"), [dataset])
    expected = rows.sort_values("trial")["error_proximal_mm"].to_numpy()
    np.testing.assert_allclose(collected["error_proximal_mm"].to_numpy(), expected, rtol=1e-12)
    assert np.isfinite(expected).all()
    wrong = rows.assign(error_proximal_mm=rows["error_proximal_mm"] + 1.0)
    write_table(wrong, path, {})
    with pytest.raises(ValueError, match="error_proximal_mm"):
        collect("hip", [path], str(tmp_path / "collected.parquet"), [dataset])


def test_a_frame_column_of_the_wrong_type_is_refused(hip_condition):
    condition, trials = hip_condition
    rows = estimate("hip", "gauss-markov-frame0", trials, condition)
    bad = rows.assign(proximal_center_x="near")
    with pytest.raises(ValueError, match="proximal_center_x"):
        check_estimates(bad, kind="joint_center", condition_keys=["n_frames"])


def test_the_noise_free_frame0_control_removes_the_bias_of_eq2():
    """The same trials with frame 0 recorded exactly: every later frame is the same draw, and
    gauss-markov's error against the true centre falls to the size of its predicted sqrt(tr Wc),
    which it exceeds many times over when frame 0 is noisy: the frame-0 diagnosis."""
    config = study_config.load_config(ROOT / "config" / "config.yaml")
    hip = {**config["studies"]["hip"], "trials": 8}
    default = {**config, "studies": {"hip": hip}}
    control = {**config, "studies": {"hip": {**hip, "protocol": {"noise_free_frame0": True}}}}
    condition = {"n_frames": 1200}
    noisy = simulate_condition(default, "hip", condition)
    exact = simulate_condition(control, "hip", condition)
    for name, markers in noisy.segments.items():
        np.testing.assert_array_equal(exact.segments[name][:, 1:], markers[:, 1:])
        assert np.ptp(exact.segments[name][:, 0], axis=0).max() == 0.0
    ratios = []
    for trials in (noisy, exact):
        rows = estimate("hip", "gauss-markov", trials, condition)
        rms = float(np.sqrt(np.mean(rows["error_mm"] ** 2)))
        ratios.append(rms / float(rows["sqrt_trace_cov_mm"].median()))
    assert ratios[0] > 5.0 and ratios[1] < 2.0, ratios
