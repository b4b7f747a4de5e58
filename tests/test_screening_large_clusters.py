"""A cluster of more markers than the label-exchange test takes: screened for rigidity breaks
and jumps only, promptly, and every answer says what was not tested.

The exchange test tries every exchange of two labels on every pair of markers, at a cost that
grows as the fourth power of the marker count times the frames (120 markers over 120 frames took
about 20 s), so a whole-body marker set passed as one segment, or a ``(markers, frames, 3)``
array passed transposed, must not reach it. ``benchmarks/screen_large_clusters.py`` times it.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_support_large_clusters import CENTRE, _ball, shapes_passed

import jointbench
from jointbench import screening
from jointbench.io import fit as fit_recording
from jointbench.io.recording import Recording

LIMIT = screening.MAX_EXCHANGE_MARKERS


def _swapped(markers: np.ndarray, first: int, second: int, rows: slice) -> np.ndarray:
    """``markers`` with the labels of columns ``first`` and ``second`` exchanged in ``rows``."""
    swapped = markers.copy()
    swapped[rows, first], swapped[rows, second] = markers[rows, second], markers[rows, first]
    return swapped


def _labels(n_markers: int) -> tuple[str, ...]:
    return tuple(f"m{column}" for column in range(n_markers))


def _refuse_the_exchange_test(monkeypatch) -> None:
    """Make the searches for two markers exchanging labels fail the test if the screen reaches
    them: the distance test and the search of the rigidity breaks for exchanged pairs, whose
    cost grows as the pairs times the markers (a recording of a few markers passed as
    ``(markers, frames, 3)``, every sample a break, took minutes at 2,000 frames)."""

    def reached(*_):
        raise AssertionError("the exchange test ran on a cluster it cannot take")

    monkeypatch.setattr(screening, "find_exchanges", reached)
    monkeypatch.setattr(screening, "find_swaps", reached)


def test_the_words_name_the_count_and_the_limit():
    assert screening.exchanges_untested(LIMIT) == ""
    assert screening.exchanges_untested(3) == ""
    words = screening.exchanges_untested(LIMIT + 1)
    assert words.startswith(f"{LIMIT + 1} markers, more than the {LIMIT} whose label exchanges")
    assert "whether two markers exchange labels in some frames was not tested" in words


@pytest.mark.parametrize(("n_markers", "n_frames"), [(LIMIT + 1, 60), (120, 120)])
def test_a_large_cluster_is_screened_without_the_exchange_test_and_says_so(
    monkeypatch, n_markers, n_frames
):
    _refuse_the_exchange_test(monkeypatch)
    markers = _ball(n_markers, n_frames)
    found = screening.screen(markers, _labels(n_markers), "m")
    assert found.artefacts == () and found.swaps == ()
    assert found.untested == screening.exchanges_untested(n_markers) != ""
    assert screening.find_artefacts(markers, _labels(n_markers), "m") == ((), ())


def test_the_public_fit_of_a_large_cluster_says_the_exchange_test_was_skipped():
    result = jointbench.fit_center(_ball(120, 120), method="LS")
    words = f"not verified in markers: {screening.exchanges_untested(120)}"
    assert f"warning: {words}" in result.status
    assert result.diagnostics["artefacts_untested"] == [words]
    assert result.diagnostics["artefacts"] == []
    assert np.linalg.norm(result.center - CENTRE) < 1.0


def test_a_large_cluster_still_gets_the_rigidity_and_jump_checks(monkeypatch):
    _refuse_the_exchange_test(monkeypatch)
    markers = _ball(120, 120)
    markers[50:60, 7] += 40.0  # a marker knocked off its place for ten frames
    found = screening.screen(markers, _labels(120), "m")
    assert {(a.kind, a.label) for a in found.artefacts} >= {("rigidity", "m7")}
    assert {a.frame for a in found.artefacts if a.label == "m7"} == set(range(50, 60))
    with pytest.raises(ValueError, match=r"^markers\[:, 7\] leaves its cluster's rigid"):
        jointbench.fit_center(markers, method="LS")
    with pytest.warns(UserWarning, match="artefacts in the data"):
        result = jointbench.fit_center(markers, method="LS", artefacts="warn")
    assert "warning: artefacts in the data: markers[:, 7] leaves" in result.status
    assert "warning: not verified in markers: 120 markers" in result.status
    assert {a["label"] for a in result.diagnostics["artefacts"]} == {"markers[:, 7]"}


@pytest.mark.parametrize("seed", range(4))
def test_a_cluster_at_the_limit_is_still_tested_for_swaps(seed):
    markers = _swapped(_ball(LIMIT, 60, seed), 2, 5, slice(30, 45))
    found = screening.screen(markers, _labels(LIMIT), "m")
    assert found.untested == ""
    assert [(swap.labels, swap.start, swap.stop) for swap in found.swaps] == [
        (("m2", "m5"), 30, 45)
    ]
    assert screening.find_artefacts(markers, _labels(LIMIT), "m") == (
        found.artefacts,
        found.swaps,
    )
    clean = jointbench.fit_center(_ball(LIMIT, 60, seed), method="LS")
    assert "not verified in markers" not in clean.status
    assert "artefacts_untested" not in clean.diagnostics


def test_only_the_exchange_test_finds_a_swap_in_a_small_cluster_and_above_the_limit_it_says_so():
    """A cluster of a few mm, in which a swap moves no marker past the rigidity level: at the
    limit the exchange test finds it, one marker more and the screen says it was not tested."""
    for n_markers, untested in ((LIMIT, False), (LIMIT + 1, True)):
        small = CENTRE + (_ball(n_markers, 60, seed=1) - CENTRE) / 30.0
        found = screening.screen(_swapped(small, 2, 5, slice(30, 45)), _labels(n_markers), "m")
        assert bool(found.untested) is untested
        if untested:
            assert found.artefacts == () and found.swaps == ()
        else:
            assert {a.kind for a in found.artefacts} == {"swap"}
            assert [(swap.labels, swap.start, swap.stop) for swap in found.swaps] == [
                (("m2", "m5"), 30, 45)
            ]


def test_a_recording_with_a_large_segment_says_so_in_its_status():
    markers = _ball(3 + LIMIT + 1, 120)
    labels = tuple(f"R{k}" for k in range(3)) + tuple(f"M{k}" for k in range(LIMIT + 1))
    # The reference cluster stands still; the moving one turns about CENTRE.
    markers[:, :3] = markers[0, :3] + np.random.default_rng(1).normal(0.0, 0.1, (120, 3, 3))
    recording = Recording(labels, markers, 100.0, "large")
    result = fit_recording(recording, "center", list(labels[3:]), list(labels[:3]), method="LS")
    words = f"not verified in the moving segment: {screening.exchanges_untested(LIMIT + 1)}"
    assert f"warning: {words}" in result.result.status
    assert result.to_dict()["status"] == result.result.status
    assert result.result.diagnostics["artefacts_untested"] == [words]


@pytest.mark.parametrize(("n_markers", "n_frames"), [(LIMIT + 1, 60), (400, 5)])
def test_a_clean_cluster_s_typical_frame_is_found_once(monkeypatch, n_markers, n_frames):
    """The mean shape of a cluster nothing was flagged in starts from the typical frame the
    screen started from: each search compares every marker pair over every frame, millions of
    pairs for a recording passed as ``(markers, frames, 3)``."""
    markers, labels = _ball(n_markers, n_frames), _labels(n_markers)
    plain = screening.screen(markers, labels, "m")
    searches = shapes_passed(monkeypatch, screening, "_most_typical")
    found = screening.screen(markers, labels, "m")
    assert searches == [markers.shape]
    assert found.artefacts == plain.artefacts == ()
    for name in ("shape", "rotation", "translation", "residuals"):
        assert np.array_equal(getattr(found, name), getattr(plain, name)), name
    # The fit's screen finds the typical frame in the pass that clears the cluster, or not.
    assert screening.find_artefacts(markers, labels, "m") == ((), ())
    assert searches == [markers.shape]
