"""Moving-block bootstrap: resampling, failures, calibration under white noise, real data."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats
from test_io_recordings import KNEE

from jointbench.configuration.seeds import trial_rng
from jointbench.configuration.studies import get_study
from jointbench.io import Recording, prepare, read
from jointbench.io.segments import technical_frame
from jointbench.running.scoring import CHI2_3DOF_95
from jointbench.simulate.hip import marker_layout
from jointbench.uncertainty import BATCH_FRAMES, block_indices, bootstrap, default_block_length

HIP = ("P1", "P2", "P3", "D1", "D2", "D3")


def test_block_indices_are_runs_of_consecutive_frames():
    indices = block_indices(100, 7, np.random.default_rng(0))
    assert indices.shape == (100,) and indices.min() >= 0 and indices.max() < 100
    runs = indices.reshape(-1)[:98].reshape(14, 7)
    assert np.all(np.diff(runs, axis=1) == 1)
    starts = runs[:, 0]
    assert len(np.unique(starts)) > 1


def test_block_length_out_of_range_is_refused():
    with pytest.raises(ValueError, match="block_length must be in"):
        block_indices(10, 11, np.random.default_rng(0))


def test_refits_that_fail_are_counted_and_too_many_refuse():
    def statistic(resamples):
        return [None if rows[0] % 3 == 0 else np.array([rows.mean()]) for rows in resamples]

    result = bootstrap(statistic, 50, n_resamples=40, block_length=5, seed=1, label="a mean")
    assert 0 < result.n_failed < 40
    assert np.isnan(result.samples).any(axis=1).sum() == result.n_failed

    with pytest.raises(ValueError, match="refits failed"):
        bootstrap(lambda resamples: [None] * len(resamples), 50, n_resamples=10, label="nothing")


def test_refits_are_asked_for_in_batches_of_bounded_size():
    """The refits of a long recording once came in one batch of every resample: 200 of a
    100,000-frame trial held some 12 GB. The batches keep the resamples and their order."""
    n_frames = BATCH_FRAMES // 4
    sizes = []

    def statistic(resamples):
        sizes.append(resamples.size)
        return [np.array([rows.mean()]) for rows in resamples]

    result = bootstrap(statistic, n_frames, n_resamples=10, seed=3, label="a mean")
    assert max(sizes) <= BATCH_FRAMES and sum(sizes) == 10 * n_frames
    rng = np.random.default_rng(3)
    length = default_block_length(n_frames)
    expected = [block_indices(n_frames, length, rng).mean() for _ in range(10)]
    np.testing.assert_array_equal(result.samples[:, 0], expected)


def test_mean_of_white_noise_has_the_textbook_spread():
    values = np.random.default_rng(4).normal(size=400)
    result = bootstrap(
        lambda resamples: [np.array([values[rows].mean()]) for rows in resamples],
        400,
        n_resamples=400,
        seed=2,
        label="a mean",
    )
    spread = float(np.sqrt(result.covariance()[0, 0]))
    assert 0.8 < spread / (1.0 / np.sqrt(400)) < 1.2


def hip_trial(trial: int, n_frames: int):
    spec = get_study("hip")
    protocol = spec.protocol()
    condition = {"n_frames": n_frames}
    trials = spec.simulate(condition, protocol, [trial_rng(11, "bootstrap", condition, trial)])
    markers = np.concatenate([trials.segments["proximal"][0], trials.segments["distal"][0]], 1)
    proximal, _ = marker_layout(protocol)
    frame = technical_frame(proximal, HIP[:3], "layout")
    truth = frame[:3, :3].T @ (np.asarray(protocol.joint_mm) - frame[:3, 3])
    return Recording(HIP, markers, protocol.fps), truth


def test_bootstrap_covers_the_true_hip_centre_under_white_noise():
    """Small-sample check of calibration; benchmarks/own_data.py runs the large one."""
    n_trials = 12
    covered = 0
    for trial in range(n_trials):
        recording, truth = hip_trial(trial, 150)
        fitted = prepare(recording, "joint_center", "D1,D2,D3", "P1,P2,P3").fit(
            "SCoRE", n_bootstrap=40, seed=trial
        )
        error = fitted.result.center - truth
        covered += error @ np.linalg.solve(fitted.bootstrap.covariance(), error) <= CHI2_3DOF_95
    low, high = stats.binom.interval(0.99, n_trials, 0.95)
    assert low <= covered <= high


def test_knee_bootstrap_is_much_wider_than_gauss_markov():
    """Skin-marker artefact is correlated in time: the white-noise covariance is far too small."""
    prepared = prepare(
        read(KNEE), "joint_center", "RLEG1,RLEG2,RLEG3,RATT,RLM,RSPH", "RTHI1,RTHI2,RTHI3,RGT"
    )
    fitted = prepared.fit("gauss-markov", n_bootstrap=30, seed=0)
    predicted = np.sqrt(np.trace(fitted.result.covariance))
    resampled = np.sqrt(np.trace(fitted.bootstrap.covariance()))
    assert resampled > 5.0 * predicted


@pytest.mark.parametrize(("kind", "method"), [("joint_center", "SCoRE"), ("center", "SCoRE")])
def test_batched_refits_equal_one_at_a_time(kind, method):
    recording, _ = hip_trial(0, 120)
    prepared = prepare(recording, kind, "D1,D2,D3", "P1,P2,P3")
    rng = np.random.default_rng(5)
    rows = [prepared.rows(block_indices(prepared.usable.size, 11, rng)) for _ in range(3)]
    for batched, subset in zip(prepared.refits(method, rows, {}), rows, strict=True):
        alone = prepared.solve(method, subset, {})
        np.testing.assert_allclose(batched.center, alone.center, atol=1e-9)
