"""A fit on frames whose noise is not independent says so.

Every p-value of the support verdict and every SD a method states counts each frame's noise as
new. Frames interpolated (gap filling, resampling), low-pass filtered, or markers sliding on
the skin share their errors from frame to frame, and a fit on them would state precision it
does not have: on noisy frames interpolated tenfold, the centre fits' answers lie a median 6
of their SDs off (``benchmarks/frame_independence.py``). The support verdict reads how the
means of the markers' pair distances, which the rigid motion leaves alone, vary over blocks of
frames (:data:`jointbench.estimators.support.MIN_VARIANCE_RATIO`). Here: it warns on
interpolated, filtered, gap-filled, sliding-marker and slowly drifting data and on the real
knee trial, for every method; it does not warn on noise independent in each frame, nor on
noise-free data; its numbers are the NumPy ones; and a recording's bootstrap over blocks too
short for the correlation says so.
"""

from __future__ import annotations

import math
import re
import statistics
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import butter, filtfilt

import jointbench
from jointbench.estimators import results, support
from jointbench.geometry import rotation_matrix, unit
from jointbench.io.fit import BLOCK_SPANS
from jointbench.numerics import compiled

WARNING = "the frames are not independent"
SHANK, THIGH = "RLEG1,RLEG2,RLEG3,RATT,RLM,RSPH", "RTHI1,RTHI2,RTHI3,RGT"
KNEE = Path(__file__).resolve().parents[1] / "data" / "functional-trials" / "right_knee.c3d"
FIT = {
    "center": jointbench.fit_center,
    "axis": jointbench.fit_axis,
    "joint_center": jointbench.fit_joint_center,
}


def _body(rng: np.random.Generator) -> np.ndarray:
    """Four body-fixed markers ``(4, 3)`` [mm] about 150 mm from the joint at the origin."""
    return rng.normal(scale=20.0, size=(4, 3)) + np.array([150.0, 0.0, 30.0])


def _swing(n_frames: int, hinge: bool = False) -> np.ndarray:
    """Rotation vectors ``(N, 3)`` [rad]: a 30 degree circumduction, or a 60 degree hinge."""
    t = np.linspace(0.0, 1.0, n_frames)
    if hinge:
        return np.outer(np.radians(30.0) * np.sin(2.0 * np.pi * t), [0.0, 0.0, 1.0])
    rom = np.radians(30.0)
    phase = 2.0 * np.pi * t
    return np.column_stack([rom * np.cos(phase), 0.3 * rom * np.sin(phase), rom * np.sin(phase)])


def _moved(body: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    return np.einsum("kij,pj->kpi", rotation_matrix(vectors), body)


def _interpolated(markers: np.ndarray, factor: int) -> np.ndarray:
    """``markers`` ``(N, n, 3)`` linearly interpolated ``factor`` times between frames, as gap
    filling and resampling do."""
    n_frames = markers.shape[0]
    at = np.linspace(0.0, n_frames - 1.0, (n_frames - 1) * factor + 1)
    below = np.minimum(at.astype(int), n_frames - 2)
    share = (at - below)[:, None, None]
    return markers[below] * (1.0 - share) + markers[below + 1] * share


def _noisy(rng: np.random.Generator, shape: tuple, noise_mm: float) -> np.ndarray:
    return rng.normal(scale=noise_mm / np.sqrt(3.0), size=shape)


def _kind_trial(kind: str, rng: np.random.Generator, n_frames: int, noise) -> tuple:
    """One trial of ``kind`` over ``n_frames`` frames with ``noise(shape)`` added to every
    segment."""
    if kind == "joint_center":
        lifted = np.array([0.0, 0.0, 400.0])
        proximal = _moved(_body(rng), 0.2 * _swing(n_frames)[:, ::-1]) + lifted
        turning = rotation_matrix(0.2 * _swing(n_frames)[:, ::-1])
        distal = np.einsum("kij,kpj->kpi", turning, _moved(_body(rng), _swing(n_frames)))
        distal = distal + lifted
        return proximal + noise(proximal.shape), distal + noise(distal.shape)
    markers = _moved(_body(rng), _swing(n_frames, hinge=kind == "axis"))
    return (markers + noise(markers.shape),)


def _fits(kind: str, arrays: tuple) -> dict[str, object]:
    return {method: FIT[kind](*arrays, method=method) for method in jointbench.methods(kind)}


@pytest.mark.parametrize("kind", sorted(FIT))
def test_noise_independent_in_each_frame_is_never_warned_about(kind):
    rng = np.random.default_rng(20261205)
    checked = 0
    for n_frames in (8, 30, 120, 1000):
        for _ in range(30):
            arrays = _kind_trial(kind, rng, n_frames, lambda shape: _noisy(rng, shape, 0.5))
            verdict = support.assess(kind, arrays)
            assert not any(WARNING in warning for warning in verdict.caveats)
            assert abs(verdict.diagnostics["frame_correlation"]) < 0.5
            checked += 1
    assert checked == 120


@pytest.mark.parametrize("kind", sorted(FIT))
def test_noise_free_frames_have_no_correlation_to_read(kind):
    arrays = _kind_trial(kind, np.random.default_rng(1), 200, np.zeros)
    verdict = support.assess(kind, arrays)
    assert "frame_correlation" not in verdict.diagnostics
    assert not any(WARNING in warning for warning in verdict.caveats)


@pytest.mark.parametrize("kind", sorted(FIT))
def test_every_method_says_so_on_frames_interpolated_tenfold(kind):
    rng = np.random.default_rng(7)
    for _ in range(5):
        arrays = _kind_trial(kind, rng, 30, lambda shape: _noisy(rng, shape, 0.5))
        arrays = tuple(_interpolated(array, 10) for array in arrays)
        for method, result in _fits(kind, arrays).items():
            assert WARNING in result.status, method
            # Thirty frames of noise, interpolated: about thirty independent ones.
            assert 10.0 < result.diagnostics["support_independent_frames"] < 60.0, method


@pytest.mark.parametrize("kind", sorted(FIT))
def test_every_method_says_so_on_low_pass_filtered_frames(kind):
    rng = np.random.default_rng(8)
    # 6 Hz at 100 frames a second, forwards and backwards: a motion laboratory's usual filter.
    b, a = butter(2, 6.0 / 50.0)

    def filtered(shape: tuple) -> np.ndarray:
        return filtfilt(b, a, _noisy(rng, shape, 1.0), axis=0)

    arrays = _kind_trial(kind, rng, 500, filtered)
    for method, result in _fits(kind, arrays).items():
        assert WARNING in result.status, method


def test_a_marker_sliding_with_the_flexion_is_warned_about():
    # One marker slides 10 mm as the hinge flexes: a smooth change in its distances that the
    # rigidity test takes for noise, and that left SARA 45 degrees off with an SD near 1.
    rng = np.random.default_rng(1)
    n_frames = 60
    flexion = np.radians(30.0) * np.sin(np.linspace(0.0, np.pi, n_frames))
    body = _body(rng)[None].repeat(n_frames, axis=0)
    body[:, 0] += (flexion / flexion.max())[:, None] * 10.0 * unit(rng.normal(size=3))
    turned = rotation_matrix(np.outer(flexion, [0.0, 0.0, 1.0]))
    markers = np.einsum("kij,kpj->kpi", turned, body) + _noisy(rng, body.shape, 0.5)
    for method, result in _fits("axis", (markers,)).items():
        assert WARNING in result.status, method


def test_the_real_knee_trial_is_warned_about_naming_the_segment():
    recording = jointbench.read(KNEE)

    def segment(labels: list[str]) -> np.ndarray:
        return recording.markers[:, [recording.labels.index(label) for label in labels]]

    thigh = segment(["RTHI1", "RTHI2", "RTHI3", "RGT"])
    shank = segment(["RLEG1", "RLEG2", "RLEG3", "RATT"])
    kept = np.isfinite(thigh).all(axis=(1, 2)) & np.isfinite(shank).all(axis=(1, 2))
    for method, result in _fits("joint_center", (thigh[kept], shank[kept])).items():
        named = re.search(r"the means of the (proximal|distal) markers' distances", result.status)
        assert named is not None, method
        assert result.diagnostics["support_frame_correlation"] > 0.98, method


def test_the_check_reads_the_frames_order():
    """Shuffled, interpolated frames no longer show their correlation: the check reads the
    sequence, as no other part of the verdict does (the README says so)."""
    rng = np.random.default_rng(9)
    (markers,) = _kind_trial("center", rng, 30, lambda shape: _noisy(rng, shape, 0.5))
    markers = _interpolated(markers, 10)
    assert any(WARNING in w for w in support.assess("center", (markers,)).caveats)
    shuffled = markers[rng.permutation(markers.shape[0])]
    assert not any(WARNING in w for w in support.assess("center", (shuffled,)).caveats)


def _numpy_dependence(markers: np.ndarray) -> list[float]:
    """The numbers of :func:`jointbench.estimators.support._frame_dependence` for ``markers``
    ``(N, n, 3)`` [mm], written out in NumPy from the module docstring: the pooled lag-1
    autocorrelation of the pair distances, then per block length ``L = 2, 4, ...`` (at least
    8 blocks) the variance ratio over its quantile, keeping the largest excess."""
    a, b = np.triu_indices(markers.shape[1], 1)
    distances = np.linalg.norm(markers[:, a] - markers[:, b], axis=-1)
    deviations = distances - distances.mean(axis=0)
    n_frames = deviations.shape[0]
    correlation = float(np.sum(deviations[1:] * deviations[:-1]) / np.sum(deviations**2))
    lengths = [2**k for k in range(1, 40) if n_frames // 2**k >= support.MIN_BLOCKS]
    z = statistics.NormalDist().inv_cdf(1.0 - support.ROTATION_ALPHA / len(lengths))
    per_frame = np.sum(deviations**2) / (n_frames - 1)
    best = [math.nan, math.nan, -1.0]
    for length in lengths:
        n_blocks = n_frames // length
        kept = deviations[: n_blocks * length].reshape(n_blocks, length, -1)
        sums = kept.sum(axis=1)
        ratio = np.sum((sums - sums.mean(axis=0)) ** 2) / (n_blocks - 1) / (length * per_frame)
        weights = np.sum(kept**2, axis=(1, 2))
        dof = max(weights.sum() ** 2 / np.sum(weights**2) - 1.0, 1.0)
        spread = 2.0 / (9.0 * dof)
        quantile = (1.0 - spread + z * math.sqrt(spread)) ** 3
        excess = ratio / max(quantile, support.MIN_VARIANCE_RATIO)
        if excess > best[2]:
            best = [ratio, float(length), excess]
    return [correlation, *best]


@pytest.mark.parametrize("n_markers", [3, 4, 7])
def test_both_passes_compute_the_numbers_written_out_in_numpy(n_markers):
    rng = np.random.default_rng(n_markers)
    trials = []
    for n_frames, factor in ((100, 1), (34, 3)):
        body = rng.normal(scale=30.0, size=(n_markers, 3))
        markers = _moved(body, _swing(n_frames)) + _noisy(rng, (n_frames, n_markers, 3), 0.5)
        trials.append(_interpolated(markers, factor))
    stacked = np.stack(trials)
    expected = [_numpy_dependence(markers) for markers in trials]
    one_segment = support._one_segment_numbers(stacked, support._FLEX)
    np.testing.assert_allclose(one_segment[:, support._DEPENDENCE], expected, rtol=1e-9)
    np.testing.assert_allclose(support._frame_numbers(stacked)[:, :4], expected, rtol=1e-9)


def test_two_markers_that_give_no_pose_are_read_from_their_distance():
    """Two markers give no pose, but their distance holds whatever the motion: the verdict
    reads it, and says so of interpolated frames, not of independent noise."""
    rng = np.random.default_rng(11)
    for factor, warned in ((1, False), (10, True)):
        for _ in range(10):
            markers = _moved(_body(rng)[:2], _swing(40))
            markers = _interpolated(markers + _noisy(rng, markers.shape, 0.5), factor)
            result = jointbench.fit_center(markers, method="LS")
            assert (WARNING in result.status) == warned, result.status
            assert np.isfinite(result.diagnostics["support_frame_correlation"])


def test_a_single_marker_has_no_distance_to_read():
    """One marker keeps no distance a rigid motion leaves alone: nothing is read (the README
    says so), rather than reading the misfit of a model."""
    rng = np.random.default_rng(12)
    markers = _interpolated(_moved(_body(rng)[:1], _swing(40)) + _noisy(rng, (40, 1, 3), 0.5), 10)
    result = jointbench.fit_center(markers, method="LS")
    assert WARNING not in result.status
    assert "support_frame_correlation" not in result.diagnostics


def test_a_bootstrap_over_blocks_shorter_than_the_correlation_says_so():
    """On the knee trial the default blocks (the root of the frames) are shorter than three
    times the frames one independent frame spans, so the bootstrap shares some of the SDs'
    fault: the status says so, naming a block length that long; such blocks give no warning."""
    prepared = jointbench.prepare(
        jointbench.read(KNEE), "center", "RLEG1,RLEG2,RLEG3,RATT", "RTHI1,RTHI2,RTHI3,RGT"
    )
    short = prepared.fit("NM", n_bootstrap=20)
    independent = short.result.diagnostics["support_independent_frames"]
    span = int(np.ceil(BLOCK_SPANS * short.frames_used.size / independent))
    assert short.bootstrap.block_length < span
    assert f"the bootstrap's blocks of {short.bootstrap.block_length} frames" in short.result.status
    assert f"block_length (--block-length) of {span} frames or more" in short.result.status
    long = prepared.fit("NM", n_bootstrap=20, block_length=span)
    assert "the bootstrap's blocks" not in long.result.status
    plain = prepared.fit("NM")
    assert "the bootstrap's blocks" not in plain.result.status


def drifting(rng: np.random.Generator, n_frames: int, drift_mm: float) -> np.ndarray:
    """A circumduction ``(N, 4, 3)`` [mm] whose markers each drift ``drift_mm`` in a direction of
    their own, three slow cycles over the trial, under 0.3 mm of noise per coordinate."""
    t = np.linspace(0.0, 1.0, n_frames)
    markers = _moved(_body(rng), _swing(n_frames))
    drift = np.stack(
        [
            np.outer(np.sin(2.0 * np.pi * (3.0 * t + rng.random())), rng.normal(size=3))
            for _ in range(markers.shape[1])
        ],
        axis=1,
    )
    return markers + drift_mm * drift + rng.normal(scale=0.3, size=markers.shape)


def test_a_small_slow_drift_under_the_noise_is_warned_about():
    """Markers that drift 0.25 mm slowly under 0.3 mm of noise hardly correlate from one frame
    to the next, but their means over many frames vary far more than independent frames'
    would: left unsaid, NM's centres lay a median 4-6 of their SDs off, many reading ``ok``."""
    rng = np.random.default_rng(21)
    for _ in range(10):
        result = jointbench.fit_center(drifting(rng, 3000, 0.25), method="NM")
        assert WARNING in result.status


def test_two_long_gaps_filled_by_straight_lines_are_warned_about():
    """One marker's two gaps of 100 frames each, filled linearly as capture software does, in
    1000 frames of 0.5 mm noise."""
    rng = np.random.default_rng(22)
    for _ in range(5):
        markers = _moved(_body(rng), _swing(1000)) + _noisy(rng, (1000, 4, 3), 0.5)
        for start in (200, 600):
            stop = start + 101
            share = np.linspace(0.0, 1.0, stop - start + 1)[:, None]
            markers[start : stop + 1, 0] = (1 - share) * markers[start, 0] + share * markers[
                stop, 0
            ]
        assert WARNING in jointbench.fit_center(markers, method="LS").status


def independent_alarms(
    rng: np.random.Generator, n_markers: int, n_frames: int, n_trials: int, spread_mm: float
) -> int:
    """How many of ``n_trials`` trials of one cluster of ``n_markers`` markers (spread
    ``spread_mm`` across their line, 80 mm along it) under noise independent in each frame
    (0.3 mm per coordinate) the check finds not independent. In half of them only one marker is
    noisy: the cluster that pools least."""
    body = np.outer(np.linspace(-40.0, 40.0, n_markers), unit(rng.normal(size=3)))
    body = body + rng.normal(scale=spread_mm, size=body.shape) + 100.0
    clean = _moved(body, _swing(n_frames))
    noise = rng.normal(scale=0.3, size=(n_trials, n_frames, n_markers, 3))
    noise[: n_trials // 2, :, 1:] = 0.0
    dependence = support._frame_numbers(clean[None] + noise)[:, :4]
    return int(np.sum(dependence[:, 3] >= 1.0))


@pytest.mark.parametrize("n_markers", [3, 4, 8])
def test_independent_noise_raises_no_alarm_in_many_trials(n_markers):
    """The check's own numbers over 4,650 trials of independent noise per marker count, from
    16 to 2,000 frames, nearly collinear markers included. At the verdict's level, 1e-3, some 5
    alarms would be allowed; the variance ratios pooled over pairs that share their noise vary
    less than one pair's, and the lengths share the level, so there are fewer."""
    rng = np.random.default_rng(n_markers)
    frames_and_trials = ((16, 1500), (40, 1500), (150, 1500), (2000, 150))
    alarms = sum(independent_alarms(rng, n_markers, n, k, 0.5) for n, k in frames_and_trials)
    assert alarms <= 2


def test_a_burst_of_noise_on_one_marker_is_not_read_as_dependent_frames():
    """Noise independent in each frame but loud on one marker for 20 frames: a few blocks
    carry the variance, so the block means vary more than a chi-square of one degree per block
    allows, though no frame shares its noise with another. The degrees of freedom count it
    (Satterthwaite's); without them a quarter of these trials read as dependent."""
    rng = np.random.default_rng(23)
    trials = []
    for _ in range(400):
        markers = _moved(_body(rng), _swing(1000)) + rng.normal(scale=0.1, size=(1000, 4, 3))
        start = rng.integers(0, 980)
        markers[start : start + 20, 1] += rng.normal(scale=3.0, size=(20, 3))
        trials.append(markers)
    dependence = support._frame_numbers(np.stack(trials))[:, :4]
    assert np.sum(dependence[:, 3] >= 1.0) <= 1


def test_the_independent_frames_of_noise_carried_over_from_frame_to_frame():
    """Noise that keeps a share r of itself from one frame to the next holds about
    N (1 - r) / (1 + r) independent frames."""
    rng = np.random.default_rng(24)
    n_frames = 5000
    clean = _moved(_body(rng), _swing(n_frames))
    for share in (0.5, 0.9):
        fresh = rng.normal(scale=0.3, size=clean.shape) * np.sqrt(1.0 - share**2)
        noise = np.empty_like(fresh)
        noise[0] = rng.normal(scale=0.3, size=fresh.shape[1:])
        for frame in range(1, n_frames):
            noise[frame] = share * noise[frame - 1] + fresh[frame]
        verdict = support.assess("center", (clean + noise,))
        expected = n_frames * (1.0 - share) / (1.0 + share)
        assert verdict.diagnostics["independent_frames"] == pytest.approx(expected, rel=0.15)


UNTESTED = "the frames' independence was not tested"


def _cluster_trial(
    kind: str, rng: np.random.Generator, n_frames: int, n_markers: int, share: float
) -> tuple:
    """One trial of ``kind`` over ``n_frames`` frames, its segments of ``n_markers`` markers
    each, under 0.5 mm of noise that keeps ``share`` of itself from frame to frame (0:
    independent in each frame)."""

    def noise(shape: tuple) -> np.ndarray:
        fresh = _noisy(rng, shape, 0.5)
        carried = fresh.copy()
        for frame in range(1, shape[0]):
            carried[frame] = share * carried[frame - 1] + math.sqrt(1.0 - share**2) * fresh[frame]
        return carried

    body = rng.normal(scale=30.0, size=(n_markers, 3)) + np.array([150.0, 0.0, 30.0])
    if kind == "joint_center":
        lifted = np.array([0.0, 0.0, 400.0])
        proximal = _moved(body[::-1] - 300.0, 0.2 * _swing(n_frames)[:, ::-1]) + lifted
        turning = rotation_matrix(0.2 * _swing(n_frames)[:, ::-1])
        distal = np.einsum("kij,kpj->kpi", turning, _moved(body, _swing(n_frames))) + lifted
        return proximal + noise(proximal.shape), distal + noise(distal.shape)
    markers = _moved(body, _swing(n_frames, hinge=kind == "axis"))
    return (markers + noise(markers.shape),)


def _untested_count(kind: str, n_frames: int, n_markers: int, share: float, n_trials: int) -> int:
    """In how many of ``n_trials`` trials (:func:`_cluster_trial`) the verdict says that the
    frames' independence was not tested."""
    rng = np.random.default_rng(n_frames * 100 + n_markers)
    return sum(
        support.assess(kind, _cluster_trial(kind, rng, n_frames, n_markers, share)).untested
        is not None
        for _ in range(n_trials)
    )


@pytest.mark.parametrize("kind", sorted(FIT))
def test_a_short_fit_of_frames_that_carry_their_noise_over_says_it_was_not_tested(kind):
    """Below 32 frames no variance ratio can be tested; noise keeping half of itself from
    frame to frame (SDs understated 1.7 times) is said so in every trial, by the public fit
    as by the verdict."""
    assert _untested_count(kind, 22, 4, 0.5, 40) == 40
    assert _untested_count(kind, 10, 3, 0.5, 40) >= 38
    arrays = _cluster_trial(kind, np.random.default_rng(5), 22, 4, 0.5)
    result = FIT[kind](*arrays)
    assert UNTESTED in result.status
    assert result.diagnostics["frames_independence_untested"] == 22
    bound = result.diagnostics["frames_independence_bound"]
    assert bound < support.DEPENDENT_CORRELATION == pytest.approx(0.2)


@pytest.mark.parametrize("kind", sorted(FIT))
def test_short_fits_of_independent_frames_are_cleared_where_their_correlation_shows_it(kind):
    """Independent frames are cleared where their lag-1 autocorrelation is below 0.2 by 1.64
    of its SDs. For clusters of six markers, whose pooled correlation spreads little, most are,
    and most frames at the bound (noise keeping a fifth of itself) are not; three markers'
    correlation can barely be told from 0.2 in 22 frames, and fewer are, but still more than
    at the bound."""
    assert _untested_count(kind, 22, 6, 0.0, 100) <= 20
    assert _untested_count(kind, 22, 6, 0.2, 100) >= 70
    assert _untested_count(kind, 22, 3, 0.0, 100) <= _untested_count(kind, 22, 3, 0.2, 100) - 20
    rng = np.random.default_rng(8)
    cleared = [
        arrays
        for arrays in (_cluster_trial(kind, rng, 22, 6, 0.0) for _ in range(10))
        if support.assess(kind, arrays).untested is None
    ]
    result = FIT[kind](*cleared[0])
    assert UNTESTED not in result.status
    assert "frames_independence_untested" not in result.diagnostics


UNCONFIRMED = "the frames' dependence test did not reject their independence"


def _flags(kind: str, n_frames: int, share: float, n_trials: int, seed: int) -> list[str]:
    """Per trial (:func:`_cluster_trial`, four markers a segment), what the verdict says of
    the frames: ``"caveat"`` (the block test found them not independent), ``"untested"``
    (too few frames to test), ``"unconfirmed"`` (tested, not rejected, lag-1 autocorrelation
    not clearly below 0.2) or ``""``."""
    rng = np.random.default_rng(seed)
    flags = []
    for _ in range(n_trials):
        verdict = support.assess(kind, _cluster_trial(kind, rng, n_frames, 4, share))
        if verdict.caveats:
            assert verdict.untested is None
            flags.append("caveat")
        elif verdict.untested is None:
            flags.append("")
        else:
            flags.append("unconfirmed" if verdict.untested.tested else "untested")
    return flags


@pytest.mark.parametrize("kind", sorted(FIT))
def test_from_32_frames_the_verdict_tests_the_frames_itself(kind):
    """At 31 frames the frames cannot be tested; from 32 they are, and where the block test
    does not reject their independence, the lag-1 autocorrelation still speaks."""
    assert support.MIN_TESTED_FRAMES == 32
    assert set(_flags(kind, 31, 0.9, 20, 1)) == {"untested"}
    assert set(_flags(kind, 32, 0.9, 20, 1)) <= {"caveat", "unconfirmed"}


@pytest.mark.parametrize("kind", sorted(FIT))
@pytest.mark.parametrize("n_frames", [32, 48])
def test_frames_carrying_most_of_their_noise_over_are_flagged_where_the_block_test_is_weak(
    kind, n_frames
):
    """Noise keeping 0.87 of itself from frame to frame (the knee trial's short windows read
    0.87 to 0.99) understates every SD about 3.8 times, yet the block test of 32 frames rejects
    it in few trials and of 48 in some: every trial is flagged, by its caveat or, where it did
    not reject, by the lag-1 autocorrelation, and the public fit says so."""
    flags = _flags(kind, n_frames, 0.87, 40, n_frames)
    assert "" not in flags and "untested" not in flags
    assert "unconfirmed" in flags
    rng = np.random.default_rng(n_frames)
    for _ in range(40):
        arrays = _cluster_trial(kind, rng, n_frames, 4, 0.87)
        if not support.assess(kind, arrays).caveats:
            break
    result = FIT[kind](*arrays)
    assert UNCONFIRMED in result.status, result.status
    assert UNTESTED not in result.status
    assert result.diagnostics["frames_independence_unconfirmed"] == n_frames
    assert "frames_independence_untested" not in result.diagnostics
    assert result.diagnostics["frames_independence_bound"] < support.DEPENDENT_CORRELATION


#: Of 100 trials of independent noise (four markers a segment), at most this many read the
#: lag-1 statement, per frames: its bound's margin under 0.2 shrinks as ``1 / sqrt(N)``
#: while the correlation's own spread does, so false alarms fall off fast with the frames
#: (README: measured rates).
FALSE_ALARMS = {32: 35, 64: 10, 120: 2, 500: 0}


@pytest.mark.parametrize("kind", sorted(FIT))
def test_independent_frames_seldom_read_the_lag_1_statement_and_long_ones_never(kind):
    for n_frames, most in FALSE_ALARMS.items():
        flags = _flags(kind, n_frames, 0.0, 100, 7 * n_frames)
        assert flags.count("unconfirmed") <= most, (n_frames, flags.count("unconfirmed"))
        assert "caveat" not in flags and "untested" not in flags


@pytest.mark.parametrize("kind", sorted(FIT))
def test_short_noise_free_frames_have_no_correlation_to_call_untested(kind):
    arrays = _kind_trial(kind, np.random.default_rng(1), 20, np.zeros)
    assert support.assess(kind, arrays).untested is None


def test_the_correlation_sd_is_that_of_the_distances_covariance():
    """``sqrt(N - 1) |C|_F / (N tr C)`` of the pair distances' covariance ``C``, compiled and
    as written, whether it sums the pairs' scatter or, where the pairs outnumber the frames
    (the last three), the frames' (``|D D'|_F = |D' D|_F``); NaN where no distance varies."""
    rng = np.random.default_rng(4)
    for n_frames, n_markers in (
        (2, 2),
        (5, 3),
        (32, 4),
        (300, 6),
        (6, 4),
        (3, 4),
        (4, 12),
        (10, 8),
    ):
        markers = rng.normal(scale=30.0, size=(3, n_frames, n_markers, 3))
        expected = []
        for trial in markers:
            pairs = [(a, b) for a in range(n_markers) for b in range(a + 1, n_markers)]
            distances = np.array(
                [np.linalg.norm(trial[:, a] - trial[:, b], axis=1) for a, b in pairs]
            )
            covariance = np.cov(distances, bias=True).reshape(len(pairs), len(pairs))
            spread = math.sqrt(n_frames - 1) * np.linalg.norm(covariance)
            expected.append(spread / (n_frames * np.trace(covariance)))
        for function in (support._frame_numbers, support._frame_numbers.__wrapped__):
            np.testing.assert_allclose(function(markers)[:, 4], expected, rtol=1e-12)
    # Two frames, whose mean is exact: the deviations are zero, not rounding.
    still = np.repeat(rng.normal(size=(1, 1, 4, 3)), 2, axis=1)
    assert np.isnan(support._frame_numbers(still)[:, 4]).all()


def test_distances_at_rounding_level_have_no_correlation_sd():
    """A rigid body turned without noise: its distances vary by rounding alone, which has no
    correlation to read (NaN), and no SD of one either, however its scatter is summed: the
    verdict's pass and :func:`support._frame_numbers` agree on NaN."""
    rng = np.random.default_rng(8)
    body = rng.normal(scale=40.0, size=(4, 3))
    turns = rotation_matrix(np.outer(np.linspace(0.0, 1.0, 60), unit(rng.normal(size=3))))
    markers = np.einsum("fij,mj->fmi", turns, body)[None] + 500.0
    numbers = support._frame_numbers(markers)
    assert np.isnan(numbers[0, 0])
    assert np.isnan(numbers[0, 4])
    assert np.isnan(support._one_segment_numbers(markers, support._FLEX)[0, -1])


def _counting_kernel_calls(monkeypatch) -> list[str]:
    """The names of the compiled kernels called from now on, in order."""
    calls: list[str] = []
    kernel_call = compiled._Kernel.__call__

    def counting(self, *args):
        calls.append(self.__qualname__)
        return kernel_call(self, *args)

    monkeypatch.setattr(compiled._Kernel, "__call__", counting)
    return calls


def test_a_one_segment_verdict_makes_one_compiled_call(monkeypatch):
    """Its numbers and the lag-1 statement's correlation and SD in one compiled call: a
    checked one-trial fit pays each call's overhead. The statement reads the numbers
    :func:`support._frame_numbers` gives, to rounding: the verdict's pass takes them from
    the distances of each frame's centred markers and their scatter."""
    rng = np.random.default_rng(2)
    (markers,) = _kind_trial("center", rng, 120, lambda shape: rng.normal(0.0, 0.5, shape))
    expected = support._frame_numbers(markers[None])
    calls = _counting_kernel_calls(monkeypatch)
    numbers = support._one_segment_numbers(markers[None], support._FLEX)
    assert calls == ["_one_segment_numbers"]
    np.testing.assert_allclose(numbers[:, -support._FRAME_COLUMNS :], expected, rtol=1e-10)
    calls.clear()
    support.assess_many("center", (markers[None],))
    assert calls == ["_one_segment_numbers"]


@pytest.mark.parametrize("kind", sorted(FIT))
def test_a_batch_states_each_trials_lag_1_correlation_as_the_trial_alone(kind):
    """In a batch whose trials the block test flags in part (noise carrying 0.9 of itself
    over), the lag-1 statement of each trial it leaves is that trial's own, as judging it
    alone gives: the statement reads the rows of the trials left, not the batch's first
    rows (a one-segment verdict hands the statement its numbers for every trial)."""
    rng = np.random.default_rng(31)
    trials = [_cluster_trial(kind, rng, 64, 4, share) for share in (0.9, 0.3, 0.9, 0.3, 0.0)]
    batch = tuple(np.stack(segment) for segment in zip(*trials, strict=True))
    together = support.assess_many(kind, batch)
    alone = [support.assess(kind, arrays) for arrays in trials]
    assert [bool(verdict.caveats) for verdict in alone] == [True, False, True, False, False]
    assert alone[1].untested is not None and alone[4].untested is None
    for verdict, expected in zip(together, alone, strict=True):
        assert verdict.caveats == expected.caveats
        assert verdict.untested == expected.untested


def test_a_checked_joint_centre_call_reads_each_segments_distances_once(monkeypatch):
    """The block test and the lag-1 statement of a checked two-segment call read one compiled
    pass over each segment's pair distances, not one pass each: the second finds the first's
    numbers (:func:`jointbench.numerics.reuse.remembered`)."""
    rng = np.random.default_rng(2)
    arrays = _kind_trial("joint_center", rng, 120, lambda shape: rng.normal(0.0, 0.5, shape))
    fit = jointbench.estimators.registry.get("joint_center", "SCoRE")
    fit(*arrays)
    calls = _counting_kernel_calls(monkeypatch)
    result = fit(*arrays)
    assert "support_frame_correlation" in result.diagnostics
    assert calls.count("_frame_numbers") == 2


def _unsupported_count(kind: str, n_frames: int, share: float, n_trials: int) -> int:
    """In how many of ``n_trials`` trials of four markers a segment (:func:`_cluster_trial`)
    the verdict says that the frames are not independent or that it did not test them."""
    rng = np.random.default_rng(n_frames)
    count = 0
    for _ in range(n_trials):
        verdict = support.assess(kind, _cluster_trial(kind, rng, n_frames, 4, share))
        dependent = any("the frames are not independent" in words for words in verdict.caveats)
        count += dependent or verdict.untested is not None
    return count


@pytest.mark.parametrize("kind", sorted(FIT))
def test_frames_that_carry_most_of_their_noise_over_are_not_ok_just_past_the_bound(kind):
    """Noise keeping 0.9 of itself from frame to frame (SDs understated 4.4 times) is said so,
    or said untested, in 31 frames; one frame more must not let it pass unsaid."""
    assert _unsupported_count(kind, support.MIN_TESTED_FRAMES - 1, 0.9, 20) == 20
    assert _unsupported_count(kind, support.MIN_TESTED_FRAMES, 0.9, 20) >= 18


@pytest.mark.parametrize("kind", ["center", "axis"])
def test_a_short_fit_of_one_marker_says_its_frames_independence_was_not_tested(kind):
    """One marker of the knee trial in the lab's frame, over 22 frames: no pair of markers
    has a distance whose lag-1 autocorrelation could clear the frames, so nothing tests them,
    and the status says so."""
    knee = jointbench.read(KNEE)
    fitted = jointbench.fit(
        knee, kind, "RLM", method="LS" if kind == "center" else "planar", frames="700:722"
    )
    assert UNTESTED in fitted.result.status
    assert fitted.result.diagnostics["frames_independence_untested"] == 22


def test_a_stretch_whose_correlation_shows_its_frames_dependent_states_no_sd():
    """Frames 300 to 339 of the knee trial: the block test does not reject their independence
    over 40 frames, but their distances' lag-1 autocorrelation, 0.89, is beyond 0.2 (where an
    SD that counts every frame understates the scatter by 1.22 times) and resolved from 0 at
    the level the block test rejects at: the frames are shown not independent, as the caveat
    would show them, and the planar axis, 5.3 degrees from the whole trial's, states no SD of
    half a degree."""
    knee = jointbench.read(KNEE)
    prepared = jointbench.prepare(knee, "axis", SHANK, THIGH, frames="300:340")
    result = prepared.fit("planar").result
    assert "did not reject their independence over 40 frames" in result.status
    assert result.diagnostics["frames_independence_unconfirmed"] == 40
    assert results.PRECISION_NOT_DETERMINED in result.status
    assert results.stated_sd(result) is None
