"""The rule reading samples at exactly (0, 0, 0) as gaps (:func:`origin_gaps`), compiled, gives
the answers of its array implementation, kept here as the reference, bit for bit, and is not
run on a recording with no sample there."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from jointbench.io import Recording
from jointbench.io import recording as recording_module
from jointbench.io.recording import _REACH_FRAMES, _runs, origin_gaps


def reference_origin_gaps(markers: np.ndarray) -> np.ndarray:
    """:func:`origin_gaps` as array operations, one marker at a time."""
    at_origin = (markers == 0.0).all(axis=-1)
    gaps = at_origin.copy()
    for marker in np.flatnonzero(at_origin.any(axis=0)):
        gaps[:, marker] = _reference_track(markers[:, marker], at_origin[:, marker])
    return gaps


def _reference_track(track: np.ndarray, at_origin: np.ndarray) -> np.ndarray:
    """The gaps ``(n_frames,)`` among one marker's samples at the origin ``at_origin``
    ``(n_frames,)``, ``track`` ``(n_frames, 3)`` [mm]."""
    seen = np.isfinite(track).all(axis=-1) & ~at_origin
    rows = np.flatnonzero(seen)
    gaps = at_origin.copy()
    if rows.size == 0:
        return gaps
    steps = np.zeros(len(track) - 1 + 2 * _REACH_FRAMES)
    consecutive = np.flatnonzero(seen[1:] & seen[:-1])
    steps[_REACH_FRAMES + consecutive] = np.linalg.norm(
        track[consecutive + 1] - track[consecutive], axis=-1
    )
    window = np.arange(_REACH_FRAMES)
    starts, stops = _runs(at_origin)
    after = np.searchsorted(rows, starts)
    before = rows[np.maximum(after - 1, 0)]
    following = rows[np.minimum(after, rows.size - 1)]
    reach_before = steps[before[:, None] + window].max(axis=1)
    reach_after = steps[following[:, None] + _REACH_FRAMES + window].max(axis=1)
    reached_before = (before == starts - 1) & (
        np.linalg.norm(track[before], axis=-1) <= reach_before
    )
    reached_after = (following == stops) & (
        np.linalg.norm(track[following], axis=-1) <= reach_after
    )
    kept = ((after == 0) | reached_before) & ((after == rows.size) | reached_after)
    for start, stop in zip(starts[kept], stops[kept], strict=True):
        gaps[start:stop] = False
    return gaps


#: Coordinates [mm] near the origin, where the rule decides, and some a marker cannot reach
#: from there, missing ones among them.
_COORDINATES = st.one_of(
    st.sampled_from([0.0, -0.0, np.nan, np.inf, -np.inf, 1e308, 1.0, -3.0]),
    st.floats(-60.0, 60.0, allow_nan=False),
    st.floats(-2000.0, 2000.0, allow_nan=False),
)


@st.composite
def recordings(draw) -> np.ndarray:
    """Markers ``(n_frames, n_markers, 3)`` [mm], with runs of samples at (0, 0, 0)."""
    n_frames = draw(st.integers(0, 40))
    n_markers = draw(st.integers(1, 3))
    markers = draw(hnp.arrays(np.float64, (n_frames, n_markers, 3), elements=_COORDINATES))
    for _ in range(draw(st.integers(0, 6))):
        if n_frames == 0:
            break
        start = draw(st.integers(0, n_frames - 1))
        stop = draw(st.integers(start + 1, min(n_frames, start + 8)))
        markers[start:stop, draw(st.integers(0, n_markers - 1))] = 0.0
    return markers


@settings(max_examples=400, deadline=None)
@given(recordings())
def test_the_compiled_rule_gives_the_reference_answers(markers):
    with np.errstate(over="ignore"):  # a step of 1e308 mm
        expected = reference_origin_gaps(markers)
    np.testing.assert_array_equal(origin_gaps(markers), expected)


@st.composite
def walks(draw) -> np.ndarray:
    """Markers ``(n_frames, n_markers, 3)`` [mm] walking in whole-mm steps near the origin,
    mostly still, with runs at (0, 0, 0) and missing: a sample next to a run lies as far from
    the origin as a step within reach, or one frame out of it, often."""
    n_frames = draw(st.integers(1, 60))
    n_markers = draw(st.integers(1, 3))
    steps = draw(
        hnp.arrays(
            np.float64,
            (n_frames, n_markers, 3),
            elements=st.sampled_from([0.0, 0.0, 0.0, 0.0, 1.0, -1.0, 2.0, 3.0, -4.0]),
        )
    )
    markers = np.cumsum(steps, axis=0)
    for _ in range(draw(st.integers(0, 6))):
        start = draw(st.integers(0, n_frames - 1))
        stop = draw(st.integers(start + 1, min(n_frames, start + 12)))
        markers[start:stop, draw(st.integers(0, n_markers - 1))] = draw(
            st.sampled_from([0.0, 0.0, np.nan])
        )
    return markers


@settings(max_examples=400, deadline=None)
@given(walks())
def test_the_compiled_rule_gives_the_reference_answers_at_the_edge_of_reach(markers):
    np.testing.assert_array_equal(origin_gaps(markers), reference_origin_gaps(markers))


@settings(max_examples=60, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_the_compiled_rule_gives_the_reference_answers_over_long_motions(seed):
    """Markers moving at random through long runs at the origin."""
    rng = np.random.default_rng(seed)
    n_frames = int(rng.integers(50, 400))
    speed = rng.uniform(0.1, 30.0, (1, 4, 3))
    markers = np.cumsum(rng.normal(0.0, 1.0, (n_frames, 4, 3)) * speed, axis=0)
    markers -= markers[rng.integers(0, n_frames)]  # every marker at the origin in one frame
    for _ in range(int(rng.integers(0, 30))):
        start = int(rng.integers(0, n_frames))
        markers[start : start + int(rng.integers(1, 25)), int(rng.integers(0, 4))] = (
            0.0 if rng.random() < 0.8 else np.nan
        )
    np.testing.assert_array_equal(origin_gaps(markers), reference_origin_gaps(markers))


def test_a_marker_at_its_fastest_exactly_at_the_origin_loses_the_sample_named():
    """A wand swung through the origin, at its fastest there (``100 sin(0.3 i)`` mm): its
    steps on either side (27 mm) are shorter than its distance from the origin next to it
    (30 mm), and its step into the origin counts for no reach: the sample is read as a gap, and
    named (the rule's documented limit)."""
    frames = np.arange(-10, 11)
    markers = np.zeros((len(frames), 3, 3))
    markers[:, 0, 0] = 100.0 * np.sin(0.3 * frames)
    markers[:, 1] = [500.0, 0.0, 0.0]
    markers[:, 2] = [0.0, 500.0, 0.0]
    markers[:, 1:] += np.random.default_rng(0).normal(0.0, 0.1, (len(frames), 2, 3))
    assert markers[10, 0].tolist() == [0.0, 0.0, 0.0]
    with pytest.warns(UserWarning, match=r"A at frame 10$"):
        recording = Recording(("A", "B", "C"), markers)
    assert np.isnan(recording.markers[10, 0]).all()
    assert np.isfinite(np.delete(recording.markers, 10, axis=0)).all()


def test_a_recording_with_no_sample_at_the_origin_is_read_without_the_compiled_rule(monkeypatch):
    """Most recordings hold no sample at exactly (0, 0, 0): reading one needs neither the
    compiled rule nor Numba, which take a second of CPU to load or longer to compile. A
    coordinate at 0 alone, or a missing sample, is no sample at the origin."""

    def compiled(markers):
        raise AssertionError("the compiled rule was called")

    monkeypatch.setattr(recording_module, "_origin_gaps_of", compiled)
    markers = np.ones((5, 2, 3))
    markers[2, 0, 1] = 0.0
    markers[3, 1] = np.nan
    assert Recording(("A", "B"), markers).markers[2, 0, 1] == 0.0
    markers[1, 0] = 0.0
    with pytest.raises(AssertionError, match="compiled rule was called"):
        Recording(("A", "B"), markers)
