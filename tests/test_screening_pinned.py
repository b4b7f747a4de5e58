"""What the artefact screen finds, pinned on many seeded trials.

``tests/snapshots/screening_outcomes.json`` holds, for every case below, what the screen found
when it was written: per array whether :func:`jointbench.screening.surely_rigid` cleared it,
the artefacts and swaps :func:`jointbench.screening.find_artefacts` found (or its error), and
the messages the public fits refuse or warn with (``jointbench.api._screen_valid``). The cases
are clean clusters of 3-8 markers and 2-5000 frames, one segment or two; clusters with a label
swap, a marker dropping out or falling off, a spike or a step; and clusters whose residuals lie
near the certificate's threshold (one frame stretched, or much noise). A faster screen must
find the same: the same decisions, frames, labels and messages word for word, the same sizes
to rounding. ``python tests/test_screening_pinned.py`` rewrites the file, for a deliberate
change of the screen only.
"""

from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from test_screening import _cluster, _one_frame_stretched

from jointbench import api, screening

PINNED = Path(__file__).parent / "snapshots" / "screening_outcomes.json"
RULES = screening.ArtefactRules()
_NAMES = {"center": ("markers",), "joint_center": ("proximal", "distal")}


def _clean(rng: np.random.Generator, n_markers: int, n_frames: int) -> np.ndarray:
    return _cluster(
        rng,
        n_markers=n_markers,
        n_frames=n_frames,
        noise_mm=float(rng.choice([0.0, 0.3, 1.0, 2.0])),
        rom_deg=float(rng.choice([5.0, 30.0, 60.0])),
    )


def _spoilt(rng: np.random.Generator, markers: np.ndarray, kind: str) -> np.ndarray:
    """``markers`` with one artefact of ``kind`` injected at a random frame."""
    n_frames, n_markers = markers.shape[:2]
    markers = markers.copy()
    marker, frame = int(rng.integers(n_markers)), int(rng.integers(n_frames))
    if kind in ("swap", "swap and back") and n_markers >= 2:
        i, j = rng.choice(n_markers, 2, replace=False)
        stop = n_frames if kind == "swap" else int(rng.integers(frame, n_frames + 1))
        markers[frame:stop, [i, j]] = markers[frame:stop, [j, i]]
    elif kind == "drop-out":
        markers[frame : frame + int(rng.integers(1, n_frames // 3 + 2)), marker] = np.nan
    elif kind == "falls off":
        markers[frame:, marker] += rng.normal(scale=float(rng.choice([3.0, 40.0])), size=3)
    elif kind == "spike":
        markers[frame, marker] += rng.normal(scale=float(rng.choice([3.0, 15.0, 60.0])), size=3)
    return markers


def cases() -> dict[str, tuple[str, tuple[np.ndarray, ...]]]:
    """``{case: (kind, arrays)}``: ``kind`` ``"center"`` (one array) or ``"joint_center"``
    (two), each trial made from its own seed."""
    found: dict[str, tuple[str, tuple[np.ndarray, ...]]] = {}
    for n_markers in range(3, 9):
        for n_frames in (2, 3, 4, 7, 120, 1200, 5000):
            rng = np.random.default_rng([1, n_markers, n_frames])
            markers = _clean(rng, n_markers, n_frames)
            found[f"clean {n_markers} x {n_frames}"] = ("center", (markers,))
    for n_frames in (4, 120, 1200, 3000):
        for seed in range(3):
            rng = np.random.default_rng([2, n_frames, seed])
            arrays = tuple(_clean(rng, int(rng.integers(3, 9)), n_frames) for _ in range(2))
            found[f"clean two segments {n_frames} #{seed}"] = ("joint_center", arrays)
    kinds = ("swap", "swap and back", "drop-out", "falls off", "spike")
    for kind in kinds:
        for seed in range(24):
            rng = np.random.default_rng([3, kinds.index(kind), seed])
            n_markers = int(rng.integers(1, 9))
            n_frames = int(rng.choice([6, 30, 120, 250]))
            markers = _spoilt(rng, _clean(rng, n_markers, n_frames), kind)
            found[f"{kind} {n_markers} x {n_frames} #{seed}"] = ("center", (markers,))
        for seed in range(4):
            rng = np.random.default_rng([4, kinds.index(kind), seed])
            arrays = [_clean(rng, int(rng.integers(3, 9)), 200) for _ in range(2)]
            side = int(rng.integers(2))
            arrays[side] = _spoilt(rng, arrays[side], kind)
            found[f"{kind} two segments #{seed}"] = ("joint_center", tuple(arrays))
    for seed in range(4):
        rng = np.random.default_rng([7, seed])
        markers = _clean(rng, int(rng.integers(3, 9)), 60)
        markers[:, int(rng.integers(markers.shape[1]))] = np.nan
        found[f"a marker never seen #{seed}"] = ("center", (markers,))
        markers = _clean(rng, int(rng.integers(3, 9)), 60)
        markers[::2, 0] = markers[1::2, 1] = np.nan
        found[f"never all seen #{seed}"] = ("center", (markers,))
    for seed in range(60):
        rng = np.random.default_rng([5, seed])
        n_markers = int(rng.integers(3, 7))
        n_frames = int(rng.choice([8, 120, 2000]))
        size_mm = float(rng.uniform(0.8, 1.2)) * RULES.min_residual_mm
        noise_mm = float(rng.choice([0.0, 0.02, 0.2]))
        markers = _one_frame_stretched(rng, n_markers, n_frames, size_mm, noise_mm)
        found[f"stretched {n_markers} x {n_frames} #{seed}"] = ("center", (markers,))
    for seed in range(40):
        rng = np.random.default_rng([6, seed])
        n_markers, n_frames = int(rng.integers(3, 9)), int(rng.choice([30, 120, 1200]))
        noise_mm = float(rng.uniform(0.2, 1.5))
        markers = _cluster(rng, n_markers=n_markers, n_frames=n_frames, noise_mm=noise_mm)
        found[f"noisy {n_markers} x {n_frames} #{seed}"] = ("center", (markers,))
    return found


def _artefacts(markers: np.ndarray, name: str) -> dict:
    """What the screen finds in one array: ``surely_rigid``'s decision (``None`` for fewer than
    three markers), the artefacts and swaps, or the error."""
    labels = tuple(screening.column_label(name, column) for column in range(markers.shape[1]))
    surely = screening.surely_rigid(markers, labels, name, RULES) if len(labels) >= 3 else None
    try:
        artefacts, swaps = screening.find_artefacts(markers, labels, name)
    except ValueError as error:
        return {"surely": surely, "error": str(error)}
    return {
        "surely": surely,
        "artefacts": [[a.kind, a.label, a.frame, a.size_mm, a.level_mm] for a in artefacts],
        "swaps": [[*s.labels, s.start, s.stop, s.n_frames] for s in swaps],
    }


def _message(kind: str, arrays: tuple[np.ndarray, ...], artefacts: str) -> str | None:
    """What the public fits say of ``arrays`` under ``artefacts`` "refuse" or "warn": the
    error or the warning, ``None`` when they say nothing."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            api._screen_valid(kind, arrays, artefacts)
        except ValueError as error:
            return f"error: {error}"
    return "; ".join(f"warning: {warning.message}" for warning in caught) or None


def decide(kind: str, arrays: tuple[np.ndarray, ...]) -> dict:
    return {
        "arrays": [_artefacts(a, name) for a, name in zip(arrays, _NAMES[kind], strict=True)],
        "refuse": _message(kind, arrays, "refuse"),
        "warn": _message(kind, arrays, "warn"),
    }


CASES = cases()


def _pinned() -> dict:
    return json.loads(PINNED.read_text())


def _same(found, expected) -> bool:
    """Equal, floats to rounding."""
    if isinstance(expected, float):
        return math.isclose(found, expected, rel_tol=1e-12)
    if isinstance(expected, list):
        return len(found) == len(expected) and all(map(_same, found, expected))
    return found == expected


@pytest.mark.parametrize("case", list(CASES))
def test_the_screen_finds_what_is_pinned(case):
    expected = _pinned()[case]
    found = json.loads(json.dumps(decide(*CASES[case])))
    assert found.keys() == expected.keys()
    assert found["refuse"] == expected["refuse"]
    assert found["warn"] == expected["warn"]
    for got, want in zip(found["arrays"], expected["arrays"], strict=True):
        assert got.keys() == want.keys(), (got, want)
        for key in want:
            assert _same(got[key], want[key]), (key, got[key], want[key])


def test_every_case_is_pinned_and_the_cases_are_varied():
    pinned = _pinned()
    assert set(pinned) == set(CASES)
    arrays = [found for case in pinned.values() for found in case["arrays"]]
    # Both decisions of the certificate, the fitted screen's errors, swaps and every kind of
    # artefact occur.
    assert {found["surely"] for found in arrays} == {True, False, None}
    assert any("error" in found for found in arrays)
    assert any(found.get("swaps") for found in arrays)
    kinds = {a[0] for found in arrays for a in found.get("artefacts", [])}
    assert kinds == {"jump", "rigidity", "swap"}
    assert any(case["refuse"] is None for case in pinned.values())


def _write() -> None:
    # A case to a line: the file stays small and a change shows case by case.
    lines = [
        f"{json.dumps(case)}: {json.dumps(decide(kind, arrays), sort_keys=True)}"
        for case, (kind, arrays) in sorted(CASES.items())
    ]
    PINNED.write_text("{\n" + ",\n".join(lines) + "\n}\n")


if __name__ == "__main__":
    _write()
