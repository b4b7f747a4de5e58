"""What the pinned-answer tests share: answers as JSON, their numbers by path, how far rounding
moves each, and the comparison of a new answer with the pinned one.

A pinned answer is compared strings and flags exactly and numbers to :data:`AGREE` (relative
where large) or, for a number that rounding alone moves by more, to :data:`ROUNDING_TIMES`
what rounding moved it when the pin was written: its largest change under three
perturbations of the markers by one unit in the last place (:func:`rounding_moves`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable

import numpy as np

from jointbench.estimators import registry

#: Numbers agree to this, relative where large.
AGREE = 1e-9
#: A number rounding moves by more than :data:`AGREE` agrees to this many times that move.
ROUNDING_TIMES = 10.0
#: The relative perturbation of the markers, one unit in the last place.
ULP = 2.0**-52


def plain(value: object) -> object:
    """``value`` as JSON: arrays as lists, non-finite numbers as strings."""
    if isinstance(value, np.ndarray):
        return plain(value.tolist())
    if isinstance(value, dict):
        return {str(key): plain(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [plain(item) for item in value]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else repr(float(value))
    return value


def answer(outcome: object, fields: tuple[str, ...]) -> dict:
    """What a pin holds of one trial's outcome: its error, or its ``fields`` and diagnostics."""
    if isinstance(outcome, Exception):
        return {"error": f"{type(outcome).__name__}: {outcome}"}
    held = {name: plain(getattr(outcome, name)) for name in fields}
    held["diagnostics"] = plain(outcome.diagnostics)
    return held


def checked_calls(
    kind: str, method: str, markers: tuple[np.ndarray, ...], options: dict, fields: tuple[str, ...]
) -> dict:
    """:func:`answer` of every trial of a case, its ``markers`` one ``(T, N, n, 3)`` [mm] array
    per segment, by the checked call of ``method`` of ``kind`` with ``options``, one trial at a
    time (its ``ValueError`` the answer where it raises one) and in one many-trial call:
    ``{"one": [...], "many": [...]}``."""
    one = registry.get(kind, method)
    each: list[object] = []
    for trial in range(len(markers[0])):
        try:
            each.append(one(*(segment[trial] for segment in markers), **options))
        except ValueError as error:
            each.append(error)
    many = registry.many(kind, method)(*markers, **options)
    return {
        "one": [answer(o, fields) for o in each],
        "many": [answer(o, fields) for o in many],
    }


def all_answers(
    cases: dict[str, tuple[tuple[np.ndarray, ...], dict]],
    methods: tuple[str, ...],
    called: Callable[[str, tuple[np.ndarray, ...], dict], dict],
) -> dict:
    """case -> method -> ``called(method, markers, options)`` over every case."""
    return {
        case: {method: called(method, trials, options) for method in methods}
        for case, (trials, options) in cases.items()
    }


def assert_case_as_pinned(answers: dict, pinned: dict, case: str) -> None:
    """Every method's one-trial and many-trial answers of ``case`` are its pinned one-trial
    answers (:func:`assert_same`)."""
    for method, called in answers[case].items():
        one = pinned["answers"][case][method]["one"]
        for call in ("one", "many"):
            assert_same(called[call], one, f"/{case}/{method}/{call}", pinned["rounding"])


def assert_changed_number_fails(held: dict, path: tuple[str | int, ...], rounding: dict) -> None:
    """A pinned answer ``held`` whose number at ``path`` (keys and indices) moves by 1e-7 of
    itself (at least 1e-7) fails :func:`assert_same`: the comparison can fail."""
    moved = json.loads(json.dumps(held))
    *inner, last = path
    container = moved
    for key in inner:
        container = container[key]
    container[last] += 1e-7 * max(1.0, abs(container[last]))
    try:
        assert_same(moved, held, "moved", rounding)
    except AssertionError:
        return
    raise AssertionError(f"a number moved at {path} passed the comparison")


def one_trial(answers: dict) -> dict:
    """What a pin keeps of ``answers`` (case -> method -> call -> outcomes): the one-trial
    calls'."""
    return {
        case: {method: {"one": called["one"]} for method, called in methods.items()}
        for case, methods in answers.items()
    }


def as_one_trial(where: str) -> str:
    """The pinned path a many-trial answer's number ``where`` is held to."""
    return where.replace("/many[", "/one[")


def numbers(held: object, where: str, out: dict[str, float]) -> dict[str, float]:
    """Every number of ``held`` (as JSON) by its path."""
    if isinstance(held, dict):
        for key, value in held.items():
            numbers(value, f"{where}/{key}", out)
    elif isinstance(held, list):
        for index, value in enumerate(held):
            numbers(value, f"{where}[{index}]", out)
    elif isinstance(held, float):
        out[where] = held
    return out


def random_signs(markers: np.ndarray, seed: int) -> np.ndarray:
    """``markers`` each moved by one unit in the last place up or down at random."""
    rng = np.random.default_rng(seed)
    return markers * (1.0 + ULP * rng.choice([-1.0, 1.0], markers.shape))


def signs_by_value(markers: np.ndarray, seed: int) -> np.ndarray:
    """``markers`` each moved by one unit in the last place up or down by a bit of its value,
    so that equal coordinates move alike: frames recorded twice stay equal, as a perturbation
    by rounding would keep them."""
    bit = np.floor(np.abs(markers) * 2.0 ** (20 + seed)) % 2.0
    return markers * (1.0 + ULP * (2.0 * bit - 1.0))


def rounding_moves(
    answers: dict,
    cases: dict[str, tuple[tuple[np.ndarray, ...], dict]],
    methods: tuple[str, ...],
    called: Callable[[str, tuple[np.ndarray, ...], dict], dict],
    perturbed: Callable[[np.ndarray, int], np.ndarray] = random_signs,
) -> dict[str, float]:
    """By path, the largest change of each number of ``answers`` under three perturbations of
    every case's markers by one unit in the last place (``perturbed(markers, seed)``), where it
    is above what :data:`AGREE` allows. ``called(method, markers, options)`` answers a case as
    ``answers`` hold it."""
    pinned = numbers(answers, "", {})
    moved: dict[str, float] = {}
    for seed in range(3):
        for case, (trials, options) in cases.items():
            markers = tuple(perturbed(m, seed) for m in trials)
            for method in methods:
                again = called(method, markers, options)
                for where, value in numbers(again, f"/{case}/{method}", {}).items():
                    if as_one_trial(where) in pinned:
                        where = as_one_trial(where)
                        change = abs(value - pinned[where])
                        moved[where] = max(moved.get(where, 0.0), change)
    return {
        where: change
        for where, change in moved.items()
        if change > AGREE * max(1.0, abs(pinned[where])) / ROUNDING_TIMES
    }


def assert_same(now: object, pinned: object, where: str, rounding: dict[str, float]) -> None:
    """``now`` equals ``pinned``: strings and flags exactly, numbers to :data:`AGREE`
    (relative where large) or :data:`ROUNDING_TIMES` their move by rounding (``rounding``, by
    path)."""
    if isinstance(pinned, dict):
        assert isinstance(now, dict) and now.keys() == pinned.keys(), where
        for key in pinned:
            assert_same(now[key], pinned[key], f"{where}/{key}", rounding)
    elif isinstance(pinned, list):
        assert isinstance(now, list) and len(now) == len(pinned), where
        for index, (mine, theirs) in enumerate(zip(now, pinned, strict=True)):
            assert_same(mine, theirs, f"{where}[{index}]", rounding)
    elif isinstance(pinned, float) and not isinstance(pinned, bool):
        assert isinstance(now, (int, float)) and not isinstance(now, bool), where
        moved = rounding.get(as_one_trial(where), 0.0)
        allowed = max(AGREE * max(1.0, abs(pinned)), ROUNDING_TIMES * moved)
        assert abs(now - pinned) <= allowed, f"{where}: {now!r} != {pinned!r}"
    else:
        assert now == pinned and type(now) is type(pinned), f"{where}: {now!r} != {pinned!r}"
