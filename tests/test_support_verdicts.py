"""The support verdict and the input checks, pinned on the hard cases.

``tests/snapshots/support_verdicts.json`` holds, for every case below, what
:func:`jointbench.estimators.validation.check_input` and
:func:`jointbench.estimators.support.assess` decided when it was written: the input check's
or the verdict's refusal, or the verdict's warnings and numbers. A faster implementation must
decide the same: the same errors and warnings word for word, the same numbers to rounding
(noise-free cases' rotations, which are rounding themselves, to 1e-6 deg).
``python tests/test_support_verdicts.py`` rewrites the file, for a deliberate change of the
verdict only.
"""

from __future__ import annotations

import json
import math
import re
import sys
from pathlib import Path

import numpy as np
import pytest
from rigs import DISTAL, HINGE, JOINT, apply_pose, two_segments

from jointbench.estimators import support, validation
from jointbench.geometry import rotation_matrix, unit

PINNED = Path(__file__).parent / "snapshots" / "support_verdicts.json"
N_FRAMES = 150


def _about_joint(rotvec: np.ndarray, body: np.ndarray = DISTAL) -> np.ndarray:
    rotation = rotation_matrix(rotvec)
    return apply_pose(rotation, JOINT - rotation @ JOINT, body)


def _ball(n_frames: int = N_FRAMES) -> np.ndarray:
    t = np.linspace(0.0, 4.0, n_frames)
    return _about_joint(
        np.stack([0.6 * np.sin(1.9 * t), 0.4 * np.sin(1.3 * t), 0.1 * np.sin(t)], -1)
    )


def _hinge(amplitude: float = 0.7) -> np.ndarray:
    t = np.linspace(0.0, 4.0, N_FRAMES)
    return _about_joint(amplitude * np.sin(1.9 * t)[:, None] * HINGE)


def _noisy(array: np.ndarray, sd_mm: float, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return array + rng.normal(scale=sd_mm / np.sqrt(3.0), size=array.shape)


def _still(array: np.ndarray) -> np.ndarray:
    return np.repeat(array[:1], N_FRAMES, axis=0)


def _sliding(array: np.ndarray) -> np.ndarray:
    steps = np.linspace(0.0, 80.0, N_FRAMES)[:, None, None] * unit(np.array([0.3, 0.5, 0.8]))
    return _still(array) + steps


def _cloud(where: np.ndarray, n_markers: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return where + rng.uniform(-25.0, 25.0, size=(N_FRAMES, n_markers, 3))


def _collinear(noise_mm: float, seed: int, rotate: bool) -> np.ndarray:
    """Three markers on a line, translating along it or turning about the joint."""
    line = unit(np.array([1.0, 0.5, 0.2]))
    body = np.array([0.0, 40.0, 100.0])[:, None] * line + JOINT + 300.0
    if rotate:
        markers = _about_joint(
            np.stack(
                [
                    0.5 * np.sin(np.linspace(0, 4, N_FRAMES)),
                    0.3 * np.cos(np.linspace(0, 3, N_FRAMES)),
                    np.zeros(N_FRAMES),
                ],
                -1,
            ),
            body,
        )
    else:
        markers = body + np.linspace(0.0, 80.0, N_FRAMES)[:, None, None] * line
    return _noisy(markers, noise_mm, seed)


def _nearly_collinear(noise_mm: float) -> np.ndarray:
    body = JOINT + np.array([[0.0, 0.0, -300.0], [40.0, 1.0, -300.0], [90.0, -0.5, -300.0]])
    t = np.linspace(0.0, 4.0, N_FRAMES)
    rotvec = np.stack([0.5 * np.sin(1.9 * t), 0.4 * np.sin(1.3 * t), 0.1 * np.sin(t)], -1)
    return _noisy(_about_joint(rotvec, body), noise_mm, 11)


def _m_set(noise_mm: float) -> np.ndarray:
    body = unit(np.array([[0.2, 0.3, 1.0], [0.0, 0.1, 1.0], [-0.3, 0.2, 1.0]]))
    body = body * np.array([[13.8], [29.0], [15.7]]) + JOINT
    t = np.linspace(0.0, 4.0, 120)
    rotvec = np.stack([0.6 * np.sin(1.9 * t), 0.4 * np.sin(1.3 * t), 0.1 * np.sin(t)], -1)
    rotation = rotation_matrix(rotvec)
    return _noisy(apply_pose(rotation, JOINT - rotation @ JOINT, body), noise_mm, 7)


def _small_rotation(amplitude: float, noise_mm: float, seed: int) -> np.ndarray:
    return _noisy(
        _hinge(amplitude)
        if seed % 2
        else _about_joint(
            amplitude
            * np.stack(
                [
                    np.sin(np.linspace(0, 6, N_FRAMES)),
                    np.cos(np.linspace(0, 5, N_FRAMES)),
                    np.zeros(N_FRAMES),
                ],
                -1,
            )
        ),
        noise_mm,
        seed,
    )


def _one_segment_cases() -> dict[str, np.ndarray]:
    ball, hinge = _ball(), _hinge()
    return {
        "ball-noisy": _noisy(ball, 0.5, 0),
        "ball-noise-free": ball,
        "ball-far": ball + 1e9,
        "hinge-noisy": _noisy(hinge, 0.5, 8),
        "hinge-noise-free": hinge,
        "hinge-noise-free-offset": hinge + 1e6,
        "static-with-noise": _noisy(_still(ball), 0.5, 1),
        "static-noise-free": _still(ball),
        "sliding-noise-free": _sliding(ball),
        "sliding-with-noise": _noisy(_sliding(ball), 0.5, 2),
        "random-cloud": _cloud(ball[0].mean(axis=0), 3, 3),
        "random-cloud-5": _cloud(ball[0].mean(axis=0), 5, 4),
        "one-marker-cloud": _cloud(np.full(3, 100.0), 1, 0),
        "two-marker-cloud": _cloud(np.full(3, 100.0), 2, 1),
        "one-marker-arc": ball[:, :1],
        "two-marker-arc": ball[:, :2],
        "one-marker-arc-noisy": _noisy(ball[:, :1], 0.5, 5),
        "two-marker-arc-noisy": _noisy(ball[:, :2], 0.5, 6),
        "collinear-translation": _collinear(0.3, 0, rotate=False),
        "collinear-rotation": _collinear(0.3, 1, rotate=True),
        "collinear-rotation-noise-free": _collinear(0.0, 1, rotate=True),
        "nearly-collinear-0.3mm": _nearly_collinear(0.3),
        "nearly-collinear-0.05mm": _nearly_collinear(0.05),
        "m-set-2mm": _m_set(2.0),
        "m-set-0.5mm": _m_set(0.5),
        "small-rotation-hinge": _small_rotation(0.003, 0.5, 9),
        "small-rotation-ball": _small_rotation(0.003, 0.5, 10),
        "medium-rotation-hinge": _small_rotation(0.02, 0.5, 13),
        "medium-rotation-ball": _small_rotation(0.02, 0.5, 12),
        "two-frames": ball[:2],
        "three-frames": _noisy(ball[:3], 0.5, 14),
    }


def _rigidly_joined(noise_mm: float) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    rotations = rotation_matrix(rng.normal(scale=0.3, size=(50, 3)))
    shifts = rng.normal(scale=100.0, size=(50, 1, 3)) + np.array([500.0, 800.0, 1000.0])
    proximal_body = rng.normal(scale=40.0, size=(4, 3))
    distal_body = rng.normal(scale=40.0, size=(4, 3)) + np.array([0.0, 0.0, -300.0])
    proximal, distal = (
        np.einsum("fij,mj->fmi", rotations, body) + shifts for body in (proximal_body, distal_body)
    )
    return _noisy(proximal, noise_mm, 20), _noisy(distal, noise_mm, 21)


def _two_segment_cases() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    proximal, distal = two_segments(N_FRAMES)
    hinge_proximal, hinge_distal = two_segments(N_FRAMES, relative="hinge")
    fixed_proximal, fixed_distal = two_segments(N_FRAMES, proximal_moves=False)
    return {
        "ball-noisy": (_noisy(proximal, 0.5, 30), _noisy(distal, 0.5, 31)),
        "ball-noise-free": (proximal, distal),
        "hinge-noisy": (_noisy(hinge_proximal, 0.5, 32), _noisy(hinge_distal, 0.5, 33)),
        "hinge-noise-free": (hinge_proximal, hinge_distal),
        "fixed-proximal-noisy": (_noisy(fixed_proximal, 0.5, 34), _noisy(fixed_distal, 0.5, 35)),
        "static-with-noise": (_noisy(_still(proximal), 0.5, 36), _noisy(_still(distal), 0.5, 37)),
        "distal-cloud": (proximal, _cloud(distal[0].mean(axis=0), 3, 38)),
        "proximal-cloud": (_cloud(proximal[0].mean(axis=0), 3, 39), distal),
        "rigidly-joined-noise-free": _rigidly_joined(0.0),
        "rigidly-joined-noisy": _rigidly_joined(0.5),
        "two-distal-markers": (proximal, distal[:, :2]),
        "collinear-distal": (proximal, _collinear(0.3, 40, rotate=True)),
    }


def cases() -> dict[str, tuple[str, tuple[np.ndarray, ...]]]:
    """Every pinned case by id: ``(kind, arrays)``."""
    found: dict[str, tuple[str, tuple[np.ndarray, ...]]] = {}
    for name, markers in _one_segment_cases().items():
        for kind in ("center", "axis"):
            found[f"{kind}/{name}"] = (kind, (markers,))
    for name, arrays in _two_segment_cases().items():
        found[f"joint_center/{name}"] = ("joint_center", arrays)
    return found


def decide(kind: str, arrays: tuple[np.ndarray, ...]) -> dict:
    """What the checks decide on ``arrays``: the input's or the verdict's refusal, or the
    verdict."""
    try:
        verdict = support.assess(kind, validation.check_input(kind, arrays))
    except ValueError as error:
        return {"error": str(error)}
    return {
        "warnings": list(verdict.warnings + verdict.caveats),
        "diagnostics": verdict.diagnostics,
    }


_NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?")


def _same_number(found: object, expected: object, key: str) -> bool:
    """Equal to rounding: the noise-free cases' numbers are rounding themselves, hence the
    absolute floors (1e-6 deg, 1e-6 mm, 1e-9 for shares and p-values)."""
    if isinstance(expected, str):
        return _same_text(str(found), expected)
    if isinstance(expected, bool) or expected is None:
        return found == expected
    if math.isnan(expected):  # a number not read (the correlation of noise-free frames)
        return math.isnan(float(found))
    floor = 1e-6 if key.endswith(("_deg", "_mm")) else 1e-9
    return math.isclose(float(found), float(expected), rel_tol=1e-6, abs_tol=floor)


def _same_text(found: str, expected: str) -> bool:
    """The same words, and the same printed numbers to their printed precision (a digit may
    flip where rounding-level values are printed)."""
    if _NUMBER.sub("#", found) != _NUMBER.sub("#", expected):
        return False
    pairs = zip(_NUMBER.findall(found), _NUMBER.findall(expected), strict=True)
    return all(math.isclose(float(a), float(b), rel_tol=0.02, abs_tol=1e-6) for a, b in pairs)


def _pinned() -> dict:
    return json.loads(PINNED.read_text())


CASES = cases()


@pytest.mark.parametrize("case", list(CASES))
def test_the_checks_decide_as_pinned(case):
    expected = _pinned()[case]
    found = decide(*CASES[case])
    assert found.keys() == expected.keys(), found
    if "error" in expected:
        assert found["error"] == expected["error"]
        return
    assert len(found["warnings"]) == len(expected["warnings"]), found
    for warning, pinned in zip(found["warnings"], expected["warnings"], strict=True):
        assert _same_text(warning, pinned), (warning, pinned)
    assert found["diagnostics"].keys() == expected["diagnostics"].keys()
    for key, value in expected["diagnostics"].items():
        assert _same_number(found["diagnostics"][key], value, key), (key, found, expected)


def test_every_case_is_pinned():
    assert set(_pinned()) == set(CASES)


@pytest.mark.parametrize("kind", ["center", "axis", "joint_center"])
def test_many_trials_are_judged_as_each_alone(kind):
    """A batch mixing supported, unsupported, collinear and two-marker... trials of one shape
    is judged trial by trial as each alone."""
    same_shape: dict[tuple, list] = {}
    for case_kind, arrays in CASES.values():
        if case_kind != kind:
            continue
        try:
            clean = validation.check_input(kind, arrays)
        except ValueError:
            continue
        same_shape.setdefault(tuple(a.shape for a in clean), []).append(clean)
    batches = [group for group in same_shape.values() if len(group) > 1]
    assert batches
    for group in batches:
        stacked = tuple(np.stack(arrays) for arrays in zip(*group, strict=True))
        for arrays, verdict in zip(group, support.assess_many(kind, stacked), strict=True):
            alone = support.assess(kind, arrays)
            assert len(verdict.warnings) == len(alone.warnings)
            for warning, pinned in zip(verdict.warnings, alone.warnings, strict=True):
                assert _same_text(warning, pinned), (warning, pinned)
            for key, value in alone.diagnostics.items():
                assert _same_number(verdict.diagnostics[key], value, key), key


def _write() -> None:
    decided = {case: decide(kind, arrays) for case, (kind, arrays) in CASES.items()}
    PINNED.write_text(json.dumps(decided, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).parent))
    _write()
