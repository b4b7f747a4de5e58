"""Label swaps in clusters of any size, found by the distance test of the screen.

A swap in a small cluster (a finger's, sides of 5-20 mm) displaces the rigid-fit residuals by
less than the rigidity level, which is set for the soft-tissue artefact of body segments; the
distance test sees it, because exchanging the two labels brings the frame's inter-marker
distances back to the trial's own noise level. It must find such swaps in every path (the
screen, the public fits' fast path, a recording's segments), still find swaps of large
clusters, and stay silent on clean trials, on smooth soft-tissue-like deformation, on a swap
that keeps an isosceles triangle's shape (the jump check's business) and on the real knee trial.
"""

from __future__ import annotations

import sys
from itertools import combinations
from pathlib import Path

import numpy as np
import pytest

import jointbench
from jointbench import screening
from jointbench.geometry import rotation_matrix
from jointbench.io import Recording, prepare, read
from jointbench.io.segments import Segment

ROOT = Path(__file__).resolve().parents[1]
KNEE = ROOT / "data" / "functional-trials" / "right_knee.c3d"
THIGH = ("RTHI1", "RTHI2", "RTHI3", "RGT")
SHANK = ("RLEG1", "RLEG2", "RLEG3", "RATT", "RLM", "RSPH")
RULES = screening.ArtefactRules()


def _labels(n_markers: int) -> tuple[str, ...]:
    return tuple(f"m[:, {column}]" for column in range(n_markers))


def _benchmark_trial() -> np.ndarray:
    """The benchmark's centre trial: 3 markers (sides about 6.8, 14.9 and 15.8 mm), 120
    frames, 1 mm noise."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import estimators

    return estimators.center_data(np.random.default_rng(1), 1).trials[0][0].copy()


def _moving(rng, body, n_frames=120, noise_mm=1.0, rom_deg=40.0):
    """``body`` ``(n, 3)`` [mm] turning and drifting over ``n_frames``, with noise."""
    t = np.linspace(0.0, 1.0, n_frames)[:, None]
    phase = rng.uniform(0.0, 2.0 * np.pi, size=3)
    rotvec = np.radians(rom_deg) * np.sin(2.0 * np.pi * t * [1.0, 1.5, 0.7] + phase)
    markers = np.einsum("fij,mj->fmi", rotation_matrix(rotvec), body)
    markers += 30.0 * t[:, :, None] + rng.normal(scale=100.0, size=3)
    return markers + rng.normal(scale=noise_mm, size=markers.shape)


def _small_body(rng, n_markers):
    """A cluster ``(n, 3)`` [mm] whose inter-marker distances all lie in 5-20 mm."""
    while True:
        body = rng.uniform(-8.0, 8.0, size=(n_markers, 3))
        sides = [np.linalg.norm(body[a] - body[b]) for a, b in combinations(range(n_markers), 2)]
        if 5.0 <= min(sides) and max(sides) <= 20.0:
            return body


def _exchange_size(body, i, j):
    """How far [mm] exchanging markers ``i`` and ``j`` moves the cluster's inter-marker
    distances (their Euclidean norm): zero for a swap that keeps the shape."""
    exchanged = body.copy()
    exchanged[[i, j]] = exchanged[[j, i]]
    pairs = list(combinations(range(len(body)), 2))
    return np.linalg.norm(
        [
            np.linalg.norm(body[a] - body[b]) - np.linalg.norm(exchanged[a] - exchanged[b])
            for a, b in pairs
        ]
    )


def _swapped(markers, i, j, start, stop):
    markers = markers.copy()
    markers[start:stop, [i, j]] = markers[start:stop, [j, i]]
    return markers


def _changes(swaps):
    """The frames where the labelling changes, over all swaps."""
    return sorted({row for s in swaps for row in (s.start, s.stop) if 0 < row < s.n_frames})


def _assert_swap_found(markers, i, j, start, stop):
    """Every path finds the swap of ``i`` and ``j`` in rows ``start`` to ``stop - 1`` alike: as
    runs whose labelling changes exactly there, which the public fits refuse, naming both
    labels and a frame where they change."""
    labels = _labels(markers.shape[1])
    whole = screening.screen(markers, labels, "m")
    artefacts, swaps = screening.find_artefacts(markers, labels, "m")
    assert (artefacts, swaps) == (whole.artefacts, whole.swaps)
    assert {s.labels for s in swaps} == {(labels[i], labels[j])}
    changes = [row for row in (start, stop) if 0 < row < len(markers)]
    assert _changes(swaps) == changes
    with pytest.raises(ValueError) as refused:
        jointbench.fit_center(markers, method="LS")
    named = f"markers[:, {i}] and markers[:, {j}] exchange labels at frame "
    assert str(refused.value).startswith(named)
    assert int(str(refused.value)[len(named) :].split()[0].rstrip(";")) in changes


# --- swaps found ----------------------------------------------------------------------------


@pytest.mark.parametrize("pair", [(0, 1), (1, 2)])
@pytest.mark.parametrize("window", [(60, 80), (60, 100), (40, 100), (60, 120), (30, 120)])
def test_swaps_in_the_benchmark_trial_are_found(pair, window):
    """The benchmark's small cluster, where the rigidity check misses every one of them. (Its
    third pair, markers 0 and 2, is all but isosceles about them: the swap moves its distances
    by 1.4 mm against 0.8 mm of distance noise, and no test of single frames can tell.)"""
    markers = _swapped(_benchmark_trial(), *pair, *window)
    _assert_swap_found(markers, *pair, *window)


def test_swaps_in_small_clusters_are_found():
    """Seeded clusters of 3-6 markers, sides 5-20 mm, noise 0.05-1 mm, one pair exchanged in
    a window (at the start, the end or inside, held by few frames or most): found whenever the
    swap moves the distances by the far and the near levels together (``ArtefactRules``) and a
    margin of 30 % for the noise, which 30 frames estimate only roughly."""
    rng = np.random.default_rng(20260101)
    tested = 0
    for _ in range(200):
        n_markers = int(rng.integers(3, 7))
        body = _small_body(rng, n_markers)
        noise_mm = float(rng.uniform(0.05, 1.0))
        i, j = sorted(int(k) for k in rng.choice(n_markers, 2, replace=False))
        far, near = screening._exchange_levels(n_markers, RULES)
        separation = 1.3 * (np.sqrt(far) + np.sqrt(near)) * np.sqrt(2.0) * noise_mm
        if _exchange_size(body, i, j) < separation:
            continue
        n_frames = int(rng.choice([30, 120, 400]))
        start = int(rng.integers(0, n_frames))
        stop = int(rng.integers(start + 1, n_frames + 1))
        if (start, stop) == (0, n_frames):
            continue
        markers = _swapped(_moving(rng, body, n_frames, noise_mm), i, j, start, stop)
        _assert_swap_found(markers, i, j, start, stop)
        tested += 1
    assert tested >= 30


def test_a_swap_in_a_body_segment_cluster_is_still_found():
    """Sides of 60-120 mm with 1 mm noise and smooth soft-tissue artefact of 3 mm."""
    rng = np.random.default_rng(3)
    body = np.array([[0.0, 0.0, 0.0], [110.0, 10.0, 0.0], [40.0, 70.0, 5.0], [60.0, 30.0, 50.0]])
    markers = _soft_tissue(rng, _moving(rng, body, 300), 3.0)
    _assert_swap_found(_swapped(markers, 1, 3, 100, 160), 1, 3, 100, 160)


def test_a_swap_in_a_recording_is_found_by_its_segment():
    rng = np.random.default_rng(4)
    body = np.array([[0.0, 0.0, 0.0], [7.0, 0.0, 0.0], [2.0, 14.0, 1.0]])
    markers = _swapped(_moving(rng, body, 200, 0.3), 1, 2, 120, 200)
    recording = Recording(("F1", "F2", "F3"), markers, 100.0, "finger.c3d")
    segment = Segment.fit(recording, "F1,F2,F3")
    assert [(s.labels, s.start, s.stop) for s in segment.swaps] == [(("F2", "F3"), 120, 200)]
    assert {a.frame for a in segment.artefacts} == set(range(120, 200))
    message = r"finger.c3d: markers F2 and F3 exchange labels at frame 120 \(1\.20 s\)"
    with pytest.raises(ValueError, match=message):
        prepare(recording, "center", "F1,F2,F3")


# --- no false alarms ------------------------------------------------------------------------


def _soft_tissue(rng, markers, amplitude_mm):
    """``markers`` with each marker displaced smoothly (a few slow sinusoids per coordinate) by
    up to about ``amplitude_mm``: soft-tissue-like deformation, which no label exchange
    explains."""
    n_frames, n_markers = markers.shape[:2]
    t = np.linspace(0.0, 1.0, n_frames)[:, None, None, None]
    frequency = rng.uniform(0.3, 3.0, size=(1, n_markers, 3, 3))
    phase = rng.uniform(0.0, 2.0 * np.pi, size=(1, n_markers, 3, 3))
    wave = np.sin(2.0 * np.pi * frequency * t + phase).sum(axis=-1) / 3.0
    return markers + amplitude_mm * wave


def _exchanges_found(markers):
    found = screening.screen(markers, _labels(markers.shape[1]), "m")
    return [a for a in found.artefacts if a.kind == "swap"], found.swaps


def test_clean_trials_raise_no_swap():
    """1000 seeded clean clusters of 3-8 markers, small or large, 2-1000 frames, noise from none
    to 2 mm: no frame is taken for a swap."""
    rng = np.random.default_rng(20260102)
    for _ in range(1000):
        n_markers = int(rng.integers(3, 9))
        scale = float(rng.choice([6.0, 30.0]))
        body = rng.normal(scale=scale, size=(n_markers, 3))
        noise_mm = float(rng.choice([0.0, 0.05, 0.3, 1.0, 2.0]))
        markers = _moving(rng, body, int(rng.choice([2, 3, 5, 30, 120, 1000])), noise_mm)
        assert screening.find_exchanges(markers, _labels(n_markers), RULES) == []


@pytest.mark.parametrize("amplitude_mm", [2.0, 4.0, 6.0])
@pytest.mark.parametrize("scale", [6.0, 30.0])
def test_smooth_soft_tissue_deformation_raises_no_swap(amplitude_mm, scale):
    rng = np.random.default_rng([5, int(amplitude_mm), int(scale)])
    for _ in range(20):
        n_markers = int(rng.integers(3, 7))
        body = rng.normal(scale=scale, size=(n_markers, 3))
        markers = _soft_tissue(rng, _moving(rng, body, 300, 0.3), amplitude_mm)
        assert _exchanges_found(markers) == ([], ())


def _regular_polygon(n_markers: int, radius_mm: float = 100.0) -> np.ndarray:
    """``n_markers`` at the corners of a regular polygon of circumradius ``radius_mm``, in the
    xy plane ``(n, 3)`` [mm]: a cluster whose symmetry fits several exchanges alike."""
    angle = 2.0 * np.pi * np.arange(n_markers) / n_markers
    return radius_mm * np.c_[np.cos(angle), np.sin(angle), np.zeros(n_markers)]


@pytest.mark.parametrize("n_markers", [4, 5, 6], ids=["square", "pentagon", "hexagon"])
def test_a_swap_in_a_regular_polygon_is_listed_once_over_its_frames(n_markers):
    """Each pair of a regular polygon's corners exchanged in rows 150 to 159: the swap that the
    distance test finds explains the jumps where the labels change, so they raise no second
    swap of the same pair (or one from the change back to the end of the trial). One swap,
    of that pair, and exactly its frames flagged."""
    body = _regular_polygon(n_markers)
    labels = _labels(n_markers)
    for i, j in combinations(range(n_markers), 2):
        markers = _swapped(_moving(np.random.default_rng(1), body, 300, 0.3), i, j, 150, 160)
        found = screening.screen(markers, labels, "m")
        listed = [(s.labels, s.start, s.stop) for s in found.swaps]
        assert listed == [((labels[i], labels[j]), 150, 160)], (i, j)
        flagged = np.flatnonzero(screening.flagged_frames(found.artefacts, len(markers)))
        assert flagged.tolist() == list(range(150, 160)), (i, j)


def test_a_swap_that_keeps_an_isosceles_shape_is_found_through_its_jumps():
    """Markers 0 and 1 are the base of an isosceles triangle: exchanged, the shape is the same,
    and only the jump of each (30 mm) shows the swap. Both jump where the labels change and
    back, and exchanging them in between leaves no jump: a swap of those two over every frame
    it holds, not two jumps that would leave the frames between them, the triangle turned
    over, in a fit."""
    rng = np.random.default_rng(8)
    body = np.array([[-15.0, 0.0, 0.0], [15.0, 0.0, 0.0], [0.0, 12.0, 0.0]])
    markers = _swapped(_moving(rng, body, 120, 0.3), 0, 1, 50, 70)
    labels = _labels(3)
    artefacts, swaps = screening.find_artefacts(markers, labels, "m")
    whole = screening.screen(markers, labels, "m")
    assert (artefacts, swaps) == (whole.artefacts, whole.swaps)
    assert [(s.labels, s.start, s.stop) for s in swaps] == [((labels[0], labels[1]), 50, 70)]
    assert {a.kind for a in artefacts} == {"swap"}
    assert {a.frame for a in artefacts} == set(range(50, 70))


def test_a_cluster_shifted_as_a_whole_for_some_frames_is_no_swap():
    """The triangle shifted 40 mm as a whole in frames 50 to 69: every marker jumps at the same
    frames, but exchanging two labels leaves their jumps, so they stay jumps, not a swap."""
    rng = np.random.default_rng(8)
    body = np.array([[-15.0, 0.0, 0.0], [15.0, 0.0, 0.0], [0.0, 12.0, 0.0]])
    markers = _moving(rng, body, 120, 0.3)
    markers[50:70] += [40.0, 0.0, 0.0]
    artefacts, swaps = screening.find_artefacts(markers, _labels(3), "m")
    assert swaps == ()
    assert {a.kind for a in artefacts} == {"jump"}
    assert {a.frame for a in artefacts} == {50, 70}


@pytest.fixture(scope="module")
def knee():
    return read(KNEE)


@pytest.mark.parametrize("cluster", [THIGH, SHANK])
def test_the_knee_trial_raises_no_swap(knee, cluster):
    """The real skin-marker trial: no swap in its thigh or shank cluster, nor in any three of
    their markers."""
    for size in range(3, len(cluster) + 1):
        for labels in combinations(cluster, size):
            segment = Segment.fit(knee, list(labels))
            assert segment.swaps == ()
            assert not [a for a in segment.artefacts if a.kind == "swap"], labels


# --- the compiled test ----------------------------------------------------------------------


def test_the_distance_test_kernel_computes_what_its_source_says():
    """On swapped small clusters, with and without gaps, long enough to judge or not."""
    rng = np.random.default_rng(9)
    for n_markers in (3, 4, 6):
        body = _small_body(rng, n_markers)
        far, near = screening._exchange_levels(n_markers, RULES)
        for n_frames in (1, 2, 3, 20, 40):
            markers = _swapped(_moving(rng, body, n_frames, 0.2), 0, 2, n_frames // 2, n_frames)
            for gap in (False, True):
                if gap:
                    markers[n_frames // 3, 1, 2] = np.nan
                inputs = (markers, far, near, RULES.swap_min_frames)
                compiled = screening._exchange_test(*inputs)
                python = screening._exchange_test.__wrapped__(*inputs)
                for got, want in zip(compiled, python, strict=True):
                    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
                assert (compiled[0] >= 0).any() == (n_frames - gap >= RULES.swap_min_frames)
