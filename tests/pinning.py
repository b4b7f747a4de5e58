"""What the pinned-answer tests share: answers as JSON, their numbers by path, how far rounding
moves each, and the comparison of a new answer with the pinned one.

A pinned answer is compared flags and words exactly and numbers to :data:`AGREE` of their
size (:func:`agreement`) or, for a number that rounding alone moves by more, to
:data:`ROUNDING_TIMES` what rounding moved it when the pin was written: its largest change
under three perturbations of the markers by one unit in the last place
(:func:`rounding_moves`). Numbers are the floats, the counts (iterations) and the numbers
written in a string (a statement's "p = 2.8e-59"): another processor or library build rounds
differently, and where the perturbations show that rounding moves one of them, that machine
may read another iteration count or another last digit of a statement about noise-free data.
The words around a string's numbers are compared exactly.

A float or a count agrees relative to its size where large and absolutely below 1: a centre
of 1e-12 mm is the origin. A number written in a string agrees relative to its size however
small: it carries its own significant digits, and a p of 1e-257 is not one of 5e-10.
"""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable

import numpy as np

from jointbench.estimators import registry

#: Numbers agree to this of their size (:func:`agreement`).
AGREE = 1e-9
#: A number rounding moves by more than :data:`AGREE` agrees to this many times that move.
ROUNDING_TIMES = 10.0
#: The relative perturbation of the markers, one unit in the last place.
ULP = 2.0**-52
#: A number written in a string: a sign, digits with a point and digits after it, an exponent.
#: A sign right after a letter, a digit or a point is a hyphen or an operator ("frame-0",
#: "lag-1", "0.5-1"), a word; so is a point no digit follows (a sentence's end): neither may
#: change unseen as a number's sign or a number's point would.
_WRITTEN_NUMBER = re.compile(r"(?:(?<![\w.])[-+])?(?:\d+(?:\.\d+)?|\.\d+)(?:[eE][-+]?\d+)?")


def words(text: str) -> str:
    """``text`` with each number written in it replaced by ``#``: what must stay word for word."""
    return _WRITTEN_NUMBER.sub("#", text)


def written_numbers(text: str) -> list[float]:
    """The numbers written in ``text``, in order."""
    return [float(number) for number in _WRITTEN_NUMBER.findall(text)]


def written_at(where: str, index: int) -> str:
    """The path of the ``index``-th number written in the string at path ``where``."""
    return f"{where}#{index}"


def _written(where: str) -> bool:
    """Whether the path ``where`` (:func:`numbers`) is a number written in a string's: its last
    step names one (:func:`written_at`)."""
    return "#" in where.rpartition("/")[2]


def agreement(pinned: float, where: str) -> float:
    """How far a number may be from its ``pinned`` value at path ``where`` where rounding did
    not move it: :data:`AGREE` of its size, at least of 1 for a float or a count, which agree
    absolutely below 1; a number written in a string agrees relative to its size however
    small, since it carries its own significant digits."""
    size = abs(pinned) if _written(where) else max(1.0, abs(pinned))
    return AGREE * size


def _counted(value: object) -> bool:
    """Whether a JSON value is a count (an int, not a flag)."""
    return isinstance(value, int) and not isinstance(value, bool)


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
    """Every number of ``held`` (as JSON) by its path: floats, counts, and the numbers written
    in a string (its ``k``-th at ``{path}#{k}``)."""
    if isinstance(held, dict):
        for key, value in held.items():
            numbers(value, f"{where}/{key}", out)
    elif isinstance(held, list):
        for index, value in enumerate(held):
            numbers(value, f"{where}[{index}]", out)
    elif isinstance(held, float) or _counted(held):
        out[where] = held
    elif isinstance(held, str):
        for index, value in enumerate(written_numbers(held)):
            out[written_at(where, index)] = value
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


class _AnyMove(dict):
    """Rounding that moves every number by any amount: :func:`assert_same` under it compares
    only what is not a number (words, flags, ``None``, the shape of the answer)."""

    def get(self, where: str, default: object = None) -> float:
        return math.inf


_ANY_MOVE = _AnyMove()


def rounding_moves(
    answers: dict,
    cases: dict[str, tuple[tuple[np.ndarray, ...], dict]],
    methods: tuple[str, ...],
    called: Callable[[str, tuple[np.ndarray, ...], dict], dict],
    perturbed: Callable[[np.ndarray, int], np.ndarray] = random_signs,
) -> dict[str, float]:
    """By path, the largest change of each number of ``answers`` (:func:`numbers`) under three
    perturbations of every case's markers by one unit in the last place
    (``perturbed(markers, seed)``), where it is above what :func:`agreement` allows (so a
    written number's relative to its size, however small).
    ``called(method, markers, options)`` answers a case as ``answers`` hold it. An answer
    whose words (:func:`words`), flags or shape rounding changes (a warning more, a flag
    flipped, a number turned "nan") is no answer a pin can hold: ``AssertionError`` naming
    it."""
    pinned = numbers(answers, "", {})
    moved: dict[str, float] = {}
    for seed in range(3):
        for case, (trials, options) in cases.items():
            markers = tuple(perturbed(m, seed) for m in trials)
            for method in methods:
                again = called(method, markers, options)
                for call, outcomes in again.items():
                    try:
                        held = answers[case][method]["one"]
                        assert_same(outcomes, held, f"/{case}/{method}/{call}", _ANY_MOVE)
                    except AssertionError as unlike:
                        raise AssertionError(f"rounding changes its words: {unlike}") from None
                for where, value in numbers(again, f"/{case}/{method}", {}).items():
                    if as_one_trial(where) in pinned:
                        where = as_one_trial(where)
                        change = abs(value - pinned[where])
                        moved[where] = max(moved.get(where, 0.0), change)
    return {
        where: change
        for where, change in moved.items()
        if change > agreement(pinned[where], where) / ROUNDING_TIMES
    }


def assert_same(now: object, pinned: object, where: str, rounding: dict[str, float]) -> None:
    """``now`` equals ``pinned``: flags and the words of strings exactly, numbers (floats,
    counts, the numbers written in strings) to :func:`agreement` or :data:`ROUNDING_TIMES`
    their move by rounding (``rounding``, by path)."""
    if isinstance(pinned, dict):
        assert isinstance(now, dict) and now.keys() == pinned.keys(), where
        for key in pinned:
            assert_same(now[key], pinned[key], f"{where}/{key}", rounding)
    elif isinstance(pinned, list):
        assert isinstance(now, list) and len(now) == len(pinned), where
        for index, (mine, theirs) in enumerate(zip(now, pinned, strict=True)):
            assert_same(mine, theirs, f"{where}[{index}]", rounding)
    elif isinstance(pinned, float):
        assert isinstance(now, (int, float)) and not isinstance(now, bool), where
        _assert_near(now, pinned, where, rounding)
    elif _counted(pinned):
        assert _counted(now), f"{where}: {now!r} != {pinned!r}"
        _assert_near(now, pinned, where, rounding)
    elif isinstance(pinned, str):
        assert isinstance(now, str) and words(now) == words(pinned), (
            f"{where}: {now!r} != {pinned!r}"
        )
        for index, (mine, theirs) in enumerate(
            zip(written_numbers(now), written_numbers(pinned), strict=True)
        ):
            _assert_near(mine, theirs, written_at(where, index), rounding, f"{now!r} != {pinned!r}")
    else:
        assert now == pinned and type(now) is type(pinned), f"{where}: {now!r} != {pinned!r}"


def _assert_near(
    now: float, pinned: float, where: str, rounding: dict[str, float], shown: str = ""
) -> None:
    """The number ``now`` is within :func:`agreement` of ``pinned``, or within
    :data:`ROUNDING_TIMES` its move by rounding at ``where``."""
    moved = rounding.get(as_one_trial(where), 0.0)
    allowed = max(agreement(pinned, where), ROUNDING_TIMES * moved)
    assert abs(now - pinned) <= allowed, f"{where}: {shown or f'{now!r} != {pinned!r}'}"
