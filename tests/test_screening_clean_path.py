"""The clean-cluster path of the artefact screen: what it decides alone must be what the whole
screen finds.

:func:`jointbench.screening.find_artefacts` settles a complete cluster in one compiled call
(:func:`jointbench.screening._clean_screen`), which answers the distance test's question
"is any frame swapped?" itself, skipping the test where a bound
(:func:`jointbench.screening._surely_unexchanged`) shows it finds nothing. On seeded trials of
every kind (clean, noisy, swapped frames and runs, jumps, gaps, nearly symmetric clusters, 3
to 6 markers, 2 to 5000 frames) its answer must be the test's own, the bound must never clear
a trial the test flags, and the artefacts and swaps must be those of :func:`screen`.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jointbench import screening
from jointbench.geometry import rotation_matrix

RULES = screening.ArtefactRules()
LIMIT = RULES.min_residual_mm / (1.0 + 1e-9)


def _labels(n_markers: int) -> tuple[str, ...]:
    return tuple(f"m[:, {column}]" for column in range(n_markers))


def _body(rng: np.random.Generator, n_markers: int, shape: str) -> np.ndarray:
    """A cluster ``(n, 3)`` [mm]: ``"large"`` (sides of tens of mm), ``"small"`` (a few mm),
    ``"isosceles"`` (markers 0 and 1 mirror images about a plane through the others, up to
    0.3 mm) or ``"regular"`` (all sides nearly equal, as far as the markers allow)."""
    if shape == "large":
        return rng.normal(scale=30.0, size=(n_markers, 3))
    if shape == "small":
        return rng.uniform(-6.0, 6.0, size=(n_markers, 3))
    if shape == "isosceles":
        body = rng.normal(scale=25.0, size=(n_markers, 3))
        body[:, 0] = np.where(np.arange(n_markers) < 2, body[:, 0], 0.0)
        body[1] = body[0] * [-1.0, 1.0, 1.0] + rng.normal(scale=0.3, size=3)
        return body
    # A regular tetrahedron's corners, then further markers near its centre's far side.
    corners = 20.0 * np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=float)
    extra = rng.normal(scale=15.0, size=(max(n_markers - 4, 0), 3))
    return np.vstack([corners, extra])[:n_markers] + rng.normal(scale=0.2, size=(n_markers, 3))


def _moving(rng: np.random.Generator, body: np.ndarray, n_frames: int, noise_mm: float):
    """``body`` turning and drifting over ``n_frames``, with isotropic noise [mm]."""
    t = np.linspace(0.0, 1.0, n_frames)[:, None]
    phase = rng.uniform(0.0, 2.0 * np.pi, size=3)
    rotvec = np.radians(35.0) * np.sin(2.0 * np.pi * t * [1.0, 1.3, 0.6] + phase)
    markers = np.einsum("fij,mj->fmi", rotation_matrix(rotvec), body)
    markers += 25.0 * t[:, :, None] + rng.normal(scale=100.0, size=3)
    return markers + rng.normal(scale=noise_mm, size=markers.shape)


def _spoilt(rng: np.random.Generator, markers: np.ndarray, kind: str) -> np.ndarray:
    """``markers`` with an artefact of ``kind``: ``"clean"`` none; ``"swap frame"`` two
    labels exchanged in one frame; ``"swap run"`` in a run of frames; ``"jump"`` a marker
    displaced from a frame on; ``"spike"`` in one frame; ``"bend"`` a marker drifting away
    smoothly (deformation); ``"gap"`` a sample missing."""
    markers = markers.copy()
    n_frames, n_markers = markers.shape[:2]
    i, j = rng.choice(n_markers, size=2, replace=False)
    frame = int(rng.integers(n_frames))
    if kind == "swap frame":
        markers[frame, [i, j]] = markers[frame, [j, i]]
    elif kind == "swap run":
        start, stop = np.sort(rng.integers(0, n_frames + 1, size=2))
        markers[start:stop, [i, j]] = markers[start:stop, [j, i]]
    elif kind == "jump":
        markers[frame:, i] += rng.normal(scale=25.0, size=3)
    elif kind == "spike":
        markers[frame, i] += rng.normal(scale=15.0, size=3)
    elif kind == "bend":
        markers[:, i] += np.linspace(0.0, 1.0, n_frames)[:, None] * rng.normal(scale=6.0, size=3)
    elif kind == "gap":
        markers[frame, i, int(rng.integers(3))] = np.nan
    return markers


KINDS = ("clean", "swap frame", "swap run", "jump", "spike", "bend", "gap")
SHAPES = ("large", "small", "isosceles", "regular")


def _cases(seed: int, n_cases: int, frames: tuple[int, ...]):
    """Seeded trials ``(n_frames, n, 3)`` [mm] of every kind, shape, noise and size."""
    rng = np.random.default_rng(seed)
    for _ in range(n_cases):
        n_markers = int(rng.integers(3, 7))
        body = _body(rng, n_markers, SHAPES[int(rng.integers(len(SHAPES)))])
        n_frames = int(rng.choice(frames))
        noise = float(rng.choice([0.0, 0.05, 0.3, 1.0, 3.0]))
        markers = _moving(rng, body, n_frames, noise)
        yield _spoilt(rng, markers, KINDS[int(rng.integers(len(KINDS)))])


def _distance_test_swaps(markers: np.ndarray, rules: screening.ArtefactRules = RULES) -> bool:
    """Whether the whole distance test, under ``rules``, finds a swapped frame in ``markers``."""
    far, near = screening._exchange_levels(markers.shape[1], rules)
    exchange, _, _ = screening._exchange_test(markers, far, near, rules.swap_min_frames)
    return bool((exchange >= 0).any())


def _check_verdict(markers: np.ndarray) -> tuple[bool, bool]:
    """The clean path's answers on ``markers`` against the whole test's and the rigidity
    kernel's; returns whether the bound cleared it and whether the test flags it."""
    n_markers = markers.shape[1]
    far, near = screening._exchange_levels(n_markers, RULES)
    typical, cleared, largest, exchanged = screening._clean_screen(
        markers, LIMIT, far, near, RULES.swap_min_frames
    )
    np.testing.assert_equal((typical, cleared, largest), screening._screen_sums(markers, LIMIT))
    flagged = _distance_test_swaps(markers)
    complete = bool(np.isfinite(markers).all())
    assert exchanged == (flagged and complete)
    bounded = False
    if complete:
        distances = screening._pair_distances(markers)
        medians = screening._medians(distances)
        bounded = screening._surely_unexchanged(distances, medians, n_markers, far, near)
        assert not (bounded and flagged)
    return bounded, flagged


def test_the_clean_path_answers_the_distance_test_on_seeded_trials():
    """2 to 400 frames, every kind of trial: the one call's answer is the test's, and the
    bound clears many trials (else the test would prove nothing of it) but none it flags."""
    cleared = flagged = 0
    frames = (2, 3, 5, 19, 20, 21, 40, 120, 400)
    for markers in _cases(20261203, 1500, frames):
        bounded, swapped = _check_verdict(markers)
        cleared += bounded
        flagged += swapped
    assert cleared > 50 and flagged > 100, (cleared, flagged)


def test_the_clean_path_answers_the_distance_test_on_long_trials():
    """The benchmark's lengths, 1200 and 5000 frames."""
    for markers in _cases(7, 24, (1200, 5000)):
        _check_verdict(markers)


def test_the_bound_is_tight_where_a_swap_is_held_by_one_frame():
    """A frame whose two labels are exchanged departs from the typical distances by about
    the exchange's own size: the bound must refuse it however the sizes compare, here for
    each pair of a cluster whose exchanges range from small to large."""
    rng = np.random.default_rng(3)
    body = np.array([[0.0, 0.0, 0.0], [40.0, 0.0, 0.0], [12.0, 35.0, 0.0], [20.0, 10.0, 30.0]])
    for i, j in combinations(range(4), 2):
        for noise in (0.0, 0.1, 1.0):
            markers = _moving(rng, body, 120, noise)
            markers[70, [i, j]] = markers[70, [j, i]]
            bounded, _ = _check_verdict(markers)
            assert not bounded


def _triangles(seed: int, n_cases: int):
    """Seeded trials ``(n_frames, 3, 3)`` [mm] of triangles of sides of tens of mm, as the
    benchmark's segments are, under noise of a few tenths to 2 mm, of every kind."""
    rng = np.random.default_rng(seed)
    for _ in range(n_cases):
        body = rng.normal(scale=40.0, size=(3, 3))
        n_frames = int(rng.choice([20, 120, 1200]))
        markers = _moving(rng, body, n_frames, float(rng.choice([0.2, 0.5, 1.0, 2.0])))
        yield _spoilt(rng, markers, KINDS[int(rng.integers(len(KINDS)))])


# Rules whose near level (chi2 within which an exchange explains a frame) exceeds the far one.
NEAR_ABOVE_FAR = screening.ArtefactRules(swap_far_probability=0.3, swap_near_probability=1e-12)


@pytest.mark.parametrize(
    ("rules", "least_cleared", "flags_some"),
    [(RULES, 40, False), (NEAR_ABOVE_FAR, 5, True)],
    ids=["default", "near above far"],
)
def test_the_bound_at_the_anchor_clears_only_what_the_test_clears(rules, least_cleared, flags_some):
    """:func:`screening._unexchanged_from_anchor`, the bound with its first step taken at the
    test's own anchor frame (where the frames' distances rank alike): on seeded trials of every
    kind it never clears one that the whole distance test flags, and it clears many that the
    bound through the largest departure (:func:`screening._surely_unexchanged`) leaves to the
    test.

    Where the frames' distances rank alike, an exchange moves no frame's distances nearer to
    distances ranked as they are (each exchanged pair of values meets the typical pair in the
    opposite order), so where the far level is above the near one, as by default, the whole
    test flags none of these trials and the clearance is not put to the test: the rules whose
    near level is above the far one let the test flag some, which the bound must not clear
    (a bound clearing every trial whose distances rank alike passes under the default)."""
    cleared_by_anchor_alone = flagged = 0
    for markers in [*_cases(20261206, 600, (20, 40, 120, 400)), *_triangles(5, 400)]:
        n_markers = markers.shape[1]
        distances = screening._pair_distances(markers)
        if not screening._ranked_alike(distances):  # the anchor is another frame's
            continue
        far, near = screening._exchange_levels(n_markers, rules)
        medians = screening._medians(distances)
        typical = distances[:, screening._nearest(distances, medians)].copy()
        largest_sq = screening._largest_departure_sq(distances, medians)
        moved = screening._relabelled_pairs(n_markers)
        swapped = _distance_test_swaps(markers, rules)
        flagged += swapped
        if screening._unexchanged_from_anchor(
            distances, moved, typical, medians, largest_sq, far, near
        ):
            assert not swapped
            cleared_by_anchor_alone += not screening._surely_unexchanged(
                distances, medians, n_markers, far, near
            )
    assert cleared_by_anchor_alone > least_cleared, cleared_by_anchor_alone
    assert (flagged > 0) == flags_some, flagged


def _found(screen, markers: np.ndarray):
    """``(artefacts, swaps)`` that ``screen`` (``screening.screen`` or ``find_artefacts``)
    finds in ``markers``, or the message of the error it raises."""
    try:
        found = screen(markers, _labels(markers.shape[1]), "m")
    except ValueError as refused:
        return str(refused)
    return (found.artefacts, found.swaps) if isinstance(found, screening.Screening) else found


@pytest.mark.parametrize("seed", range(4))
def test_find_artefacts_finds_what_the_whole_screen_finds(seed):
    """The artefacts (kind, label, frame, size, level) and swaps of every seeded trial, or
    the same error."""
    for markers in _cases(seed, 150, (2, 4, 20, 60, 120, 300)):
        assert _found(screening.find_artefacts, markers) == _found(screening.screen, markers)


def test_the_clean_screen_kernel_computes_what_its_source_says():
    """Compiled and as written, on clean, swapped and gapped trials, too short to judge or
    not."""
    for markers in _cases(11, 40, (2, 5, 20, 60)):
        far, near = screening._exchange_levels(markers.shape[1], RULES)
        inputs = (markers, LIMIT, far, near, RULES.swap_min_frames)
        compiled = screening._clean_screen(*inputs)
        python = screening._clean_screen.__wrapped__(*inputs)
        np.testing.assert_equal(compiled, python)


def _aligned_medians(distances, moved, typical, allowed, candidates):
    """What :func:`screening._nearest_exchanges` and :func:`screening._aligned_typical` find,
    in NumPy: each candidate frame relabelled by the allowed exchange nearest ``typical`` (the
    first on a tie), the rows' medians in the labelling most frames hold, and 1.4826 times
    the median departure."""
    aligned = distances.copy()
    held = np.zeros(len(moved), dtype=int)
    held[0] = distances.shape[1] - candidates.size
    for frame in candidates:
        misfits = [
            np.sum((distances[moved[e], frame] - typical) ** 2) if allowed[e] else np.inf
            for e in range(len(moved))
        ]
        best = int(np.argmin(misfits))
        aligned[:, frame] = distances[moved[best], frame]
        held[best] += 1
    median = np.median(aligned, axis=1)
    departure = np.median(np.abs(aligned - median[:, None]))
    noise = max(1.482602218505602 * departure, 1e-9 * max(median))
    return median[moved[np.argmax(held)]], noise


def test_the_typical_distances_are_the_aligned_frames_medians():
    """With no frame, one frame or many frames relabelled: the exchange each candidate takes
    and the medians and noise of the frames so aligned, which are the labelled frames' own
    where no exchange is taken, and where one is the clean path does not stop short."""
    rng = np.random.default_rng(5)
    for n_markers in (3, 4, 5):
        body = _body(rng, n_markers, "large")
        moved = screening._relabelled_pairs(n_markers)
        allowed = np.ones(len(moved), dtype=bool)
        far, near = screening._exchange_levels(n_markers, RULES)
        for n_swapped in (0, 1, 2, 7, 30):
            markers = _moving(rng, body, 60, 0.5)
            markers[:n_swapped, [0, 1]] = markers[:n_swapped, [1, 0]]
            distances = screening._pair_distances(markers)
            typical = distances[:, -1].copy()
            candidates = np.arange(distances.shape[1])
            best = screening._nearest_exchanges(distances, moved, typical, allowed, candidates)
            assert (best > 0).sum() == n_swapped
            reference, noise = screening._aligned_typical(
                distances, moved, candidates, best, np.empty_like(distances)
            )
            want = _aligned_medians(distances, moved, typical, allowed, candidates)
            np.testing.assert_allclose(reference, want[0], rtol=1e-12)
            np.testing.assert_allclose(noise, want[1], rtol=1e-12)
            medians = screening._medians(distances)
            verdict = screening._judge_frames(distances, medians, n_markers, far, near, True)
            whole = screening._judge_frames(distances, medians, n_markers, far, near, False)
            np.testing.assert_array_equal(verdict[0], whole[0])
            assert (whole[0] >= 0).sum() == n_swapped


def test_the_far_count_clears_only_what_the_noise_clears():
    """:func:`screening._within_far` clears a trial only where every frame is within the far
    level of the noise the whole test takes (where no frame is relabelled), and, with an odd
    number of departures, wherever it is by a hair."""
    rng = np.random.default_rng(17)
    for n_markers, n_frames in ((3, 61), (3, 40), (4, 35), (5, 41)):
        for shape in SHAPES:
            markers = _moving(rng, _body(rng, n_markers, shape), n_frames, 0.5)
            distances = screening._pair_distances(markers)
            medians = screening._medians(distances)
            work = np.empty_like(distances)
            spread = screening._median_departure(distances, medians, work)
            noise = max(spread, 1e-9 * medians.max())
            largest = screening._largest_departure_sq(distances, medians)
            edge = largest / noise**2  # the far level at which the farthest frame sits
            for factor in (0.5, 0.999, 1.001, 2.0):
                far = edge * factor
                cleared = screening._within_far(distances, medians, far)
                assert not cleared or largest <= far * noise**2
                if distances.size % 2:
                    assert cleared == (factor > 1.0)


@pytest.mark.parametrize("scale", [0.0, 1e-160, 1e-3, 1e150, 1e156])
def test_extreme_scales_find_what_the_whole_screen_finds(scale):
    """Clusters shrunk to a point, to where squares underflow, and grown to where they
    overflow: the same findings, or the same error, with a swapped run and without."""
    rng = np.random.default_rng(23)
    for kind in ("clean", "swap run"):
        markers = _spoilt(rng, _moving(rng, _body(rng, 4, "large"), 60, 0.5), kind) * scale
        assert _found(screening.find_artefacts, markers) == _found(screening.screen, markers)
        if np.isfinite(markers).all():
            _check_verdict(markers)


def _reference_clean_screen(markers, limit, far, near, min_frames):
    """What :func:`screening._clean_screen` finds, composed as it was first written: the
    frames counted, the distances, medians and typical frame, the marker-frame bounds, the
    step sizes stored and their largest taken, the bound of
    :func:`screening._surely_unexchanged` and the distance test's verdict, each kernel
    finding what it needs itself."""
    n_frames, n_markers, _ = markers.shape
    if screening._complete_frames(markers).size < n_frames:
        return -1, False, np.nan, False
    distances = screening._pair_distances(markers)
    medians = screening._medians(distances)
    typical = screening._nearest(distances, medians)
    first, second = screening._frame_misfits(markers, typical)
    size = np.empty((max(n_frames - 3, 0), n_markers))
    largest_jump = screening._jump_sizes(markers, size)
    exchanged = False
    if n_frames >= max(min_frames, 1) and not screening._surely_unexchanged(
        distances, medians, n_markers, far, near
    ):
        found = screening._judge_frames(distances, medians, n_markers, far, near, True)[0]
        exchanged = bool((found >= 0).any())
    return typical, first <= limit and second <= limit, largest_jump, exchanged


_TRIALS = st.tuples(
    st.integers(0, 2**32 - 1),
    st.integers(3, 6),
    st.sampled_from((2, 3, 4, 5, 19, 20, 21, 60, 121)),
    st.sampled_from(SHAPES),
    st.sampled_from((0.0, 0.05, 0.5, 3.0)),
    st.sampled_from(KINDS),
)


def _trial(drawn) -> np.ndarray:
    """A seeded trial ``(n_frames, n, 3)`` [mm] of the drawn size, shape, noise and kind."""
    seed, n_markers, n_frames, shape, noise, kind = drawn
    rng = np.random.default_rng(seed)
    return _spoilt(rng, _moving(rng, _body(rng, n_markers, shape), n_frames, noise), kind)


@settings(max_examples=300, deadline=None)
@given(_TRIALS, st.sampled_from((0, 1, 20, 10**6)))
def test_the_clean_screen_is_its_first_formulation(drawn, min_frames):
    """The one compiled call, which shares the distances' finiteness, the exchanges, the
    largest departure and the typical frame between its steps and keeps only the largest
    step, finds what its steps found each for itself, bit for bit."""
    markers = _trial(drawn)
    far, near = screening._exchange_levels(markers.shape[1], RULES)
    inputs = (markers, LIMIT, far, near, min_frames)
    np.testing.assert_equal(screening._clean_screen(*inputs), _reference_clean_screen(*inputs))


@settings(max_examples=200, deadline=None)
@given(_TRIALS)
def test_find_artefacts_finds_what_the_whole_screen_finds_on_drawn_trials(drawn):
    """Clean and corrupted clusters drawn at random: the same artefacts and swaps, or the
    same error."""
    markers = _trial(drawn)
    assert _found(screening.find_artefacts, markers) == _found(screening.screen, markers)


_VALUES = st.sampled_from((0.0, 1.0, -2.5, 1e-160, 1e155, -1e200, np.nan, np.inf, -np.inf))


@settings(max_examples=300, deadline=None)
@given(
    st.integers(0, 2**32 - 1),
    st.integers(0, 7),
    st.integers(2, 5),
    st.lists(st.tuples(st.integers(0, 10**6), _VALUES), max_size=4),
)
def test_the_distances_flag_is_true_exactly_where_every_distance_is_finite(seed, n_frames, n, odd):
    """On finite, huge, tiny, NaN and infinite coordinates, 0 to 7 frames: the distances'
    finiteness flag is true exactly where every distance is finite, which it is only where
    every coordinate is."""
    rng = np.random.default_rng(seed)
    markers = rng.normal(scale=50.0, size=(n_frames, n, 3))
    for where, value in odd:
        if markers.size:
            markers.flat[where % markers.size] = value
    with np.errstate(all="ignore"):
        distances, finite = screening._finite_pair_distances(markers)
    np.testing.assert_array_equal(distances, screening._pair_distances(markers))
    assert finite == bool(np.isfinite(distances).all())
    assert not finite or np.isfinite(markers).all()


def test_a_sweep_over_many_rules_keeps_a_bounded_memo_of_their_levels():
    """A sensitivity study screens with a new set of rules per step; the levels remembered per
    cluster size and rules must not grow with every one of them."""
    rng = np.random.default_rng(0)
    markers = rng.normal(size=(40, 3, 3)) * 0.1 + np.array([[0, 0, 0], [30, 0, 0], [0, 30, 0]])
    for step in range(600):
        rules = screening.ArtefactRules(swap_far_probability=1e-12 * (1 + step))
        screening.find_artefacts(markers, ("a", "b", "c"), "sweep", rules)
        screening.screen(markers, ("a", "b", "c"), "sweep", rules)
    assert screening._clean_levels.cache_info().currsize <= 256
    assert screening._exchange_levels.cache_info().currsize <= 256
