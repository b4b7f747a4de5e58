"""What the screen's distance test finds, pinned frame by frame on many seeded clusters.

``tests/snapshots/exchange_tests.npz`` holds, for every case below, the three outputs of
:func:`jointbench.screening._exchange_test` (per frame the exchange and the distance misfit, and
the misfit's level) as they were when the file was written; :func:`find_exchanges` makes its
artefacts from nothing else. The cases are clusters of 3-8 markers and 2-5000 frames: clean,
noise-free, small (sides of a few micrometres) and large (metres), far from the origin, with
frames missing a coordinate (down to fewer complete frames than ``swap_min_frames``), with a
swap of every pair of 3 and 4 markers in windows at the start, inside and at the end, with
several swaps, with a spike, and isosceles clusters whose base exchange keeps the shape. A
faster test must find the same, bit for bit (NaN equal to NaN).
``python tests/test_screening_exchanges_pinned.py`` rewrites the file, for a deliberate change
of the test only.
"""

from __future__ import annotations

from itertools import combinations
from pathlib import Path

import numba
import numpy as np
import pytest
from test_screening_swaps import _moving, _small_body, _swapped

from jointbench import screening

PINNED = Path(__file__).parent / "snapshots" / "exchange_tests.npz"
RULES = screening.ArtefactRules()
_KEYS = ("exchange", "misfit", "level")
# (n_frames, start, stop): swapped at the start, inside, at the end, and half of a short trial.
_WINDOWS = ((120, 0, 30), (120, 40, 100), (120, 60, 120), (40, 0, 20))


def _gappy(rng: np.random.Generator, markers: np.ndarray, n_gaps: int) -> np.ndarray:
    """``markers`` with one coordinate of one marker NaN in ``n_gaps`` random frames."""
    markers = markers.copy()
    frames = rng.choice(len(markers), min(n_gaps, len(markers)), replace=False)
    markers[frames, rng.integers(markers.shape[1]), rng.integers(3)] = np.nan
    return markers


def _isosceles(n_markers: int) -> np.ndarray:
    """A cluster ``(n, 3)`` [mm] whose markers 0 and 1 are the base of an isosceles triangle
    with every other marker: exchanging them keeps the shape."""
    others = [[0.0, 12.0, 0.0], [0.0, -7.0, 9.0], [0.0, 3.0, -14.0], [0.0, -10.0, -6.0]]
    return np.array([[-15.0, 0.0, 0.0], [15.0, 0.0, 0.0], *others[: n_markers - 2]])


def cases() -> dict[str, np.ndarray]:
    """``{case: markers (n_frames, n, 3) [mm]}``, each made from its own seed."""
    found: dict[str, np.ndarray] = {}
    for n_markers in range(3, 9):
        for n_frames in (2, 3, 19, 20, 21, 40, 120, 1200, 5000):
            rng = np.random.default_rng([1, n_markers, n_frames])
            body = rng.normal(scale=float(rng.choice([6.0, 30.0])), size=(n_markers, 3))
            noise_mm = float(rng.choice([0.05, 0.3, 1.0]))
            found[f"clean {n_markers} x {n_frames}"] = _moving(rng, body, n_frames, noise_mm)
    for n_markers in (3, 4, 6, 8):
        for scale in (1e-3, 6.0, 1e3):
            rng = np.random.default_rng([2, n_markers, int(scale * 1e3)])
            body = rng.normal(scale=scale, size=(n_markers, 3))
            found[f"noise-free {n_markers} scale {scale:g}"] = _moving(rng, body, 60, 0.0)
            markers = _moving(rng, body, 200, scale * 0.02)
            found[f"scaled {n_markers} scale {scale:g}"] = markers
            i, j = sorted(int(k) for k in rng.choice(n_markers, 2, replace=False))
            found[f"scaled swap {n_markers} scale {scale:g}"] = _swapped(markers, i, j, 50, 130)
        for offset in (1e6, 1e9):
            rng = np.random.default_rng([3, n_markers, int(np.log10(offset))])
            markers = _moving(rng, _small_body(rng, n_markers), 150, 0.2) + offset
            found[f"offset {n_markers} {offset:g}"] = markers
            found[f"offset swap {n_markers} {offset:g}"] = _swapped(markers, 0, 1, 40, 90)
    for n_markers in (3, 4):
        for i, j in combinations(range(n_markers), 2):
            for n_frames, start, stop in _WINDOWS:
                rng = np.random.default_rng([4, n_markers, i, j, n_frames, start])
                markers = _moving(rng, _small_body(rng, n_markers), n_frames, 0.2)
                name = f"swap {n_markers} ({i}, {j}) {start}:{stop} of {n_frames}"
                found[name] = _swapped(markers, i, j, start, stop)
    for seed in range(24):
        rng = np.random.default_rng([5, seed])
        n_markers = int(rng.integers(3, 9))
        n_frames = int(rng.choice([30, 250, 1200]))
        markers = _moving(rng, _small_body(rng, n_markers), n_frames, float(rng.uniform(0.02, 1)))
        for _ in range(int(rng.integers(2, 4))):
            i, j = rng.choice(n_markers, 2, replace=False)
            start = int(rng.integers(0, n_frames))
            markers = _swapped(markers, i, j, start, int(rng.integers(start, n_frames + 1)))
        found[f"several swaps #{seed}"] = markers
        if seed % 2:
            found[f"several swaps with gaps #{seed}"] = _gappy(rng, markers, n_frames // 5)
    for n_markers in (3, 4, 5, 6):
        for n_frames in (19, 20, 21, 25, 120, 5000):
            rng = np.random.default_rng([6, n_markers, n_frames])
            markers = _moving(rng, _small_body(rng, n_markers), n_frames, 0.3)
            markers = _swapped(markers, 0, 2, n_frames // 2, n_frames)
            found[f"gaps {n_markers} x {n_frames}"] = _gappy(rng, markers, 3)
        rng = np.random.default_rng([7, n_markers])
        markers = np.full((30, n_markers, 3), np.nan)
        found[f"never complete {n_markers}"] = markers
        isosceles = _moving(rng, _isosceles(n_markers), 120, 0.3)
        found[f"isosceles {n_markers}"] = _swapped(isosceles, 0, 1, 50, 70)
        found[f"isosceles noise-free {n_markers}"] = _swapped(
            _moving(rng, _isosceles(n_markers), 80, 0.0), 0, 1, 20, 80
        )
    for n_markers in (3, 4):
        # Sides 8, 20 and 21 mm (and 32, 35 and 52 mm): exchanging markers 0 and 1 moves the
        # distances by more than noise can, and marker 2 leaving along the triangle's axis for
        # three frames makes them candidates for it, ranks kept.
        body = np.array([[-4.0, 0.0, 0.0], [4.0, 0.0, 0.0], [-2.5625, 19.948, 0.0]])
        body = np.vstack([body, [[10.0, -30.0, 10.0]]])[:n_markers]
        markers = _moving(np.random.default_rng([8, n_markers]), body, 120, 0.05)
        axis = markers[30:33, 2] - markers[30:33, :2].mean(axis=1)
        markers[30:33, 2] += 1.5 * axis / np.linalg.norm(axis, axis=1, keepdims=True)
        found[f"spike {n_markers}"] = markers
    return found


CASES = cases()


def _outputs(markers: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    far, near = screening._exchange_levels(markers.shape[1], RULES)
    return screening._exchange_test(markers, far, near, RULES.swap_min_frames)


@pytest.fixture(scope="module")
def pinned():
    with np.load(PINNED) as stored:
        return dict(stored)


def _assert_identical(got: np.ndarray, want: np.ndarray) -> None:
    got, want = np.asarray(got), np.asarray(want)
    assert got.dtype == want.dtype and got.shape == want.shape
    np.testing.assert_array_equal(got, want)  # NaN equal to NaN
    np.testing.assert_array_equal(np.signbit(got), np.signbit(want))


@pytest.mark.parametrize("case", list(CASES))
def test_the_distance_test_finds_what_is_pinned(case, pinned):
    exchange, misfit, level = _outputs(CASES[case])
    _assert_identical(exchange, pinned[f"{case}/exchange"])
    _assert_identical(misfit, pinned[f"{case}/misfit"])
    _assert_identical(np.float64(level), pinned[f"{case}/level"])


def test_every_case_is_pinned_and_the_cases_are_varied(pinned):
    assert set(pinned) == {f"{case}/{key}" for case in CASES for key in _KEYS}
    exchanges = np.concatenate([pinned[f"{case}/exchange"] for case in CASES])
    levels = np.array([pinned[f"{case}/level"] for case in CASES])
    # Swaps of many pairs are found, not in every frame, and some trials are too short.
    assert len(set(exchanges[exchanges >= 0])) >= 6
    assert (exchanges == -1).any() and np.isnan(levels).any() and np.isfinite(levels).any()


def _write() -> None:
    outputs = {}
    for case, markers in CASES.items():
        for key, value in zip(_KEYS, _outputs(markers), strict=True):
            outputs[f"{case}/{key}"] = np.asarray(value)
    np.savez_compressed(PINNED, **outputs)


if __name__ == "__main__":
    _write()


def test_the_medians_are_those_numbas_median_finds():
    """The in-place selection gives the number Numba's ``np.median`` gives (equal, so that a
    zero's sign may differ, :func:`screening._median_in_place`): for odd and even counts,
    ties, infinities and NaN (which leave no order, so that the number depends on how it is
    found), and none; from ``_BAND_MIN_VALUES`` up also where the sample
    of every 8th value misses the middle (``"strided"``, the whole selection's answer)."""
    numba_median = numba.njit(lambda values: np.median(values))
    rng = np.random.default_rng(11)
    band = screening._BAND_MIN_VALUES
    for n in (*range(0, 12), 99, 100, 119, 120, 360, 1000, 1001, band - 1, band, 5000, 15001):
        for kind in ("normal", "ties", "equal", "sorted", "infinite", "nan", "strided"):
            values = rng.normal(size=n)
            if kind == "strided":
                values[::8] = -1e9
            elif kind == "ties":
                values = np.round(values)
            elif kind == "equal":
                values = np.full(n, 2.5)
            elif kind == "sorted":
                values = np.sort(values)
            elif kind in ("infinite", "nan") and n:
                spoilt = rng.integers(n, size=max(1, n // 3))
                values[spoilt] = np.inf if kind == "infinite" else np.nan
                values[spoilt[::2]] *= -1
            want = numba_median(values.copy())
            got = screening._median_in_place(values.copy())
            assert np.array_equal(got, want, equal_nan=True), (n, kind, got, want)
