"""One segment with more markers than the rigidity test compares: judged without it, promptly,
and the status says what was not tested.

The one-segment verdict's pairwise-distance test costs about ``n^6`` in the marker count, so an
array of many markers (e.g. 120 frames of 4 markers passed as ``(markers, frames, 3)``) must
not reach it.
"""

from __future__ import annotations

import numpy as np
import pytest
from peak_memory import peak_growth_mb
from rigs import two_segments

import jointbench
from jointbench.estimators import registry, support
from jointbench.geometry import rotation_matrix

CENTRE = np.array([20.0, -25.0, -30.0])


def _ball(n_markers: int, n_frames: int, seed: int = 0) -> np.ndarray:
    """Noisy markers ``(n_frames, n_markers, 3)`` [mm] of a rigid cluster turning about
    CENTRE about three axes."""
    rng = np.random.default_rng(seed)
    body = rng.normal(scale=60.0, size=(n_markers, 3))
    t = np.linspace(0.0, 2.0 * np.pi, n_frames)
    rotvec = np.stack([0.5 * np.cos(t), 0.5 * np.sin(2.0 * t), 0.25 * np.sin(t)], -1)
    markers = CENTRE + np.einsum("fij,mj->fmi", rotation_matrix(rotvec), body)
    return markers + rng.normal(scale=0.3, size=markers.shape)


def _refuse_the_distance_test(monkeypatch) -> None:
    """Make the pairwise-distance kernel fail the test if it is reached."""

    def reached(*_):
        raise AssertionError("the pairwise-distance test ran on a cluster it cannot take")

    monkeypatch.setattr(support, "_one_segment_numbers", reached)


@pytest.mark.parametrize(
    ("n_markers", "n_frames"), [(support.MAX_DISTANCE_MARKERS + 1, 60), (120, 4)]
)
def test_a_large_cluster_skips_the_distance_test_and_says_so(monkeypatch, n_markers, n_frames):
    _refuse_the_distance_test(monkeypatch)
    verdict = support.assess("center", (_ball(n_markers, n_frames),))
    assert verdict.diagnostics["assessed"] is False
    first = verdict.warnings[0]
    assert first.startswith(f"not verified: {n_markers} markers, more than the ")
    assert f"{support.MAX_DISTANCE_MARKERS} whose pairwise distances" in first
    assert "whether the markers are one rigid body and rotate about more than one axis" in first
    # The markers do have a pose: the status must not claim otherwise.
    assert "no rigid-body pose" not in first


def test_a_batch_of_large_clusters_is_judged_trial_by_trial(monkeypatch):
    _refuse_the_distance_test(monkeypatch)
    trials = np.stack([_ball(30, 20, seed) for seed in range(2)])
    verdicts = support.assess_many("axis", (trials,))
    assert [v.diagnostics["assessed"] for v in verdicts] == [False, False]
    for verdict, trial in zip(verdicts, trials, strict=True):
        assert verdict == support.assess("axis", (trial,))


def test_a_cluster_at_the_limit_is_still_fully_assessed():
    verdict = support.assess("center", (_ball(support.MAX_DISTANCE_MARKERS, 30),))
    assert verdict.diagnostics["assessed"] is True and verdict.warnings == ()


def test_the_public_fit_of_a_large_cluster_returns_with_the_warning(monkeypatch):
    _refuse_the_distance_test(monkeypatch)
    result = jointbench.fit_center(_ball(40, 60), method="LS", artefacts="ignore")
    assert result.status.startswith("warning: not verified: 40 markers")
    assert np.linalg.norm(result.center - CENTRE) < 1.0


@pytest.mark.parametrize("kind", ["center", "axis"])
def test_two_frames_of_a_large_cluster_are_refused(kind):
    """Two frames lie on a line whatever the motion: the straight-line test has no degrees of
    freedom, and the verdict refuses fewer frames than its tests need, naming the array and
    its count, as for any cluster (tests/test_support_few_frames.py), instead of dividing by
    them."""
    with pytest.raises(ValueError, match=r"^markers has 2 frames; the support verdict needs"):
        support.assess(kind, (_ball(support.MAX_DISTANCE_MARKERS + 1, 2),))


#: Frames of a recording of few markers passed as (markers, frames, 3): as many "markers" as
#: it has frames, whose marker pairs (79,800 here) are far more than their frames.
TRANSPOSED_FRAMES = 400


@pytest.mark.parametrize(
    ("kind", "method"),
    [("center", method) for method in registry.methods("center")]
    + [("axis", method) for method in ("planar", "radial", "combined")],
)
def test_a_long_recording_passed_transposed_is_judged_and_named(kind, method):
    """Its frames' dependence is read from the pair distances' scatter, whose size is the
    smaller of the pairs and the frames squared: a scatter over the pairs would be 51 GB."""
    frames = max(registry.claims(kind, method).min_frames, support.MIN_JUDGED_FRAMES)
    markers = np.swapaxes(_ball(frames, TRANSPOSED_FRAMES), 0, 1)
    fit = jointbench.fit_center if kind == "center" else jointbench.fit_axis
    result = fit(markers, method, artefacts="warn")
    assert f"not verified: {TRANSPOSED_FRAMES} markers, more than the " in result.status
    assert "may be (markers, frames, 3); it must be (frames, markers, 3)" in result.status


@pytest.mark.parametrize("method", registry.methods("joint_center"))
def test_a_long_two_segment_recording_passed_transposed_is_judged_and_named(method):
    proximal, distal = (
        np.swapaxes(markers, 0, 1) for markers in two_segments(n_frames=TRANSPOSED_FRAMES)
    )
    result = jointbench.fit_joint_center(proximal, distal, method, artefacts="warn")
    assert "may be (markers, frames, 3); it must be (frames, markers, 3)" in result.status


def shapes_passed(monkeypatch, module, name: str) -> list[tuple[int, ...]]:
    """The shapes of the arrays each call of ``module.<name>`` (one array argument) is given,
    as the calls are made."""
    shapes: list[tuple[int, ...]] = []
    original = getattr(module, name)

    def counted(array):
        shapes.append(array.shape)
        return original(array)

    monkeypatch.setattr(module, name, counted)
    return shapes


def _count_frame_numbers(monkeypatch) -> list[tuple[int, ...]]:
    """The shapes of the markers each pass of the frames' numbers is given."""
    return shapes_passed(monkeypatch, support, "_frame_numbers")


@pytest.mark.parametrize(("kind", "method"), [("center", "LS"), ("axis", "planar")])
def test_a_large_cluster_s_frames_are_read_once_per_checked_call(monkeypatch, kind, method):
    """The pair distances' numbers serve the block test and the lag-1 statement alike: over
    the pairs of thousands of markers (a recording passed as ``(markers, frames, 3)``) each
    pass costs seconds and the distances' gigabytes."""
    markers = _ball(support.MAX_DISTANCE_MARKERS + 10, 40)
    plain = registry.get(kind, method)(markers)
    passes = _count_frame_numbers(monkeypatch)
    counted = registry.get(kind, method)(markers)
    assert passes == [(1, *markers.shape)]
    assert counted.status == plain.status
    assert counted.diagnostics == plain.diagnostics


def test_a_batch_of_large_clusters_reads_its_frames_in_one_pass(monkeypatch):
    trials = np.stack([_ball(30, 20, seed) for seed in range(3)])
    plain = support.assess_many("center", (trials,))
    passes = _count_frame_numbers(monkeypatch)
    assert support.assess_many("center", (trials,)) == plain
    assert passes == [trials.shape]


@pytest.mark.parametrize(("n_markers", "n_frames"), [(8, 27), (9, 12), (40, 20), (60, 5)])
def test_many_pairs_over_few_frames_are_read_pair_by_pair_to_the_same_numbers(n_markers, n_frames):
    """More pairs than frames: each pair's distances are made and pooled in turn, the same
    sums in the same order as over the distances kept (bitwise), and the lag-1 correlation's
    SD from the Gram matrix over the frames is the scatter's over the pairs to rounding."""
    markers = _ball(n_markers, n_frames)
    (row,) = support._frame_numbers(markers[None])
    kept = np.empty(4)
    distances = support._dependence_into(markers, kept)
    assert distances.shape[0] > n_frames
    np.testing.assert_array_equal(row[:4], kept)
    deviations = distances - distances.mean(axis=1, keepdims=True)
    scatter = deviations @ deviations.T
    sd = support._scatter_correlation_sd(scatter, n_frames)
    assert row[4] == pytest.approx(sd, rel=1e-10)


#: Markers whose pair distances over FEW_FRAMES frames, kept, would take 144 MB.
MANY_MARKERS, FEW_FRAMES = 3000, 4


@pytest.mark.parametrize(
    "call",
    [
        "support._frame_numbers(markers)",
        # The fit's screen of a cluster past the exchange test: no distance test to keep them for.
        "screening._clean_screen(markers[0], 1.0, 0.0, 0.0, markers.shape[1] + 1)",
    ],
)
def test_many_markers_over_few_frames_are_judged_without_keeping_their_pair_distances(call):
    """The frames' numbers and the screen's typical frame of 3,000 markers over 4 frames, in a
    process of its own: its peak memory grows by far less than their 4.5 million pairs'
    distances (144 MB) would take. The peak is Linux's (``VmHWM``), reset after the kernels
    are loaded, whose compilation can take more memory than the call."""
    setup = f"""
        import numpy as np
        from jointbench import screening
        from jointbench.estimators import support
        markers = np.random.default_rng(0).normal(scale=60.0, size=(1, {FEW_FRAMES}, n, 3))
    """
    grown = peak_growth_mb(setup, call, 30, MANY_MARKERS)
    pairs_mb = MANY_MARKERS * (MANY_MARKERS - 1) // 2 * FEW_FRAMES * 8 / 2**20
    assert grown < pairs_mb / 4
