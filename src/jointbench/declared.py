"""Declared types and ranges of the values a config sets: estimator options, protocol fields.

A value's declaration is its annotation where it is defined: an estimator's keyword parameter
or a protocol dataclass's field. Plain types say what a value is (``int``, ``float``, ``str``,
``bool``, ``Literal[...]``, ``tuple[...]``, ``dict[str, ...]``, unions with ``None``);
``Annotated`` metadata says where it may lie::

    max_iterations: Annotated[int, Range(1)] = 600
    tol_x: Annotated[float, Range(0, exclusive_minimum=True)] = 1e-4
    start: Point | None = None

so the signature that runs is the one that is checked and the two cannot drift apart. Values
are checked as YAML gives them: lists stand for tuples and arrays, an integer is a number but
``true`` is neither, and every number must be finite.
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import numbers
import reprlib
import types
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Annotated, Literal

import numpy as np

__all__ = [
    "Count",
    "DeclarationError",
    "Length",
    "NonNegative",
    "Point",
    "Positive",
    "Range",
    "Vector3",
    "below",
    "check",
    "check_fields",
    "describe",
    "key",
    "key_texts",
    "keys",
    "keyword_types",
]

_REPR = reprlib.Repr()
_REPR.maxlist = _REPR.maxtuple = _REPR.maxdict = 6
_REPR.maxstring = _REPR.maxother = 40


@dataclass(frozen=True)
class Range:
    """Bounds of a number: ``minimum <= x <= maximum`` (``minimum < x`` with
    ``exclusive_minimum``); ``None`` leaves a side open."""

    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: bool = False

    def __contains__(self, value: float) -> bool:
        if self.minimum is not None and below(value, self.minimum, self.exclusive_minimum):
            return False
        return self.maximum is None or value <= self.maximum

    def words(self) -> list[str]:
        """The bounds in words, e.g. ``["> 0", "<= 180"]``."""
        words = []
        if self.minimum is not None:
            words.append(f"{'>' if self.exclusive_minimum else '>='} {self.minimum:g}")
        if self.maximum is not None:
            words.append(f"<= {self.maximum:g}")
        return words


def below(value: float, minimum: float, exclusive: bool = False) -> bool:
    """Whether ``value`` is below ``minimum`` (or equal to it, ``exclusive``). ``-0.0`` is below
    ``0``: numpy honours its sign (a normal draw of scale ``-0.0`` is refused, "scale < 0")."""
    if value == minimum and math.copysign(1.0, value) < math.copysign(1.0, minimum):
        return True
    return value <= minimum if exclusive else value < minimum


@dataclass(frozen=True)
class Length:
    """How many items a sequence holds: at least ``minimum``, at most ``maximum`` (``None``:
    no limit)."""

    minimum: int = 0
    maximum: int | None = None

    def __contains__(self, count: int) -> bool:
        return count >= self.minimum and (self.maximum is None or count <= self.maximum)

    def words(self) -> str:
        if self.maximum == self.minimum:
            return str(self.minimum)
        if self.maximum is None:
            return "one or more" if self.minimum == 1 else f"at least {self.minimum}"
        return f"{self.minimum} to {self.maximum}"


#: A point ``(3,)`` [mm], given as three numbers.
Point = Annotated[np.ndarray, Length(3, 3)]
#: ``(x, y, z)`` of a point or a direction, as a protocol stores it.
Vector3 = tuple[float, float, float]
#: A count of at least one (iterations, function evaluations, frames).
Count = Annotated[int, Range(1)]
#: A number > 0 (a tolerance, a frequency, a duration).
Positive = Annotated[float, Range(0, exclusive_minimum=True)]
#: A number >= 0 (a noise level, a tolerance that may be zero).
NonNegative = Annotated[float, Range(0)]


class DeclarationError(ValueError):
    """A value that does not fit its declaration, with the keys that lead to it.

    ``str()`` is ``"<key>: <reason>"``, e.g. ``"center_mm: must be 3 numbers, got [0, 0]"``;
    :meth:`under` puts the key below an outer one.
    """

    def __init__(
        self,
        path: Sequence[str | int],
        reason: str,
        beside: Sequence[Sequence[str | int]] = (),
    ) -> None:
        self.path = tuple(path)
        self.reason = reason
        # The paths of the other values a bound across fields is theirs as much, from the same
        # top as ``path``: a refusal names each where it is written.
        self.beside = tuple(tuple(other) for other in beside)
        super().__init__(str(self))

    @property
    def paths(self) -> tuple[tuple[str | int, ...], ...]:
        """``path``, then each of ``beside``."""
        return (self.path, *self.beside)

    def __str__(self) -> str:
        return f"{keys(self.paths)}: {self.reason}" if self.path else self.reason

    def under(self, *outer: str | int) -> DeclarationError:
        """The same error with ``outer`` keys in front of its own."""
        beside = [(*outer, *other) for other in self.beside]
        return DeclarationError((*outer, *self.path), self.reason, beside)


def key(path: Sequence[str | int]) -> str:
    """Dotted form of a path of keys, indices in brackets: ``directions.M[0]``; a key a reader
    would not see in it quoted (:func:`key_name`)."""
    text = ""
    for part in path:
        name = key_name(part)
        text += f"[{part}]" if isinstance(part, int) else f".{name}" if text else name
    return text


def key_name(name: object) -> str:
    """The text of one key, ``name``, in a path of keys: as written, but quoted where it is
    empty or begins or ends with a space (``''``, ``' a'``), which would leave nothing, or
    nothing to see, between the dots a reader looks for it by."""
    text = str(name)
    return repr(text) if not text or text != text.strip() else text


def keys(paths: Sequence[Sequence[str | int]]) -> str:
    """The text of several paths of keys, comma-separated (:func:`key_texts`):
    ``protocol.all.noise_sd_mm, knee.markers_mm``; ``protocol.swing_hz, fps``. Text for a
    reader alone: a key may hold a dot, a comma or a bracket, so a path is never read back
    from it."""
    return ", ".join(key_texts(paths))


def key_texts(paths: Sequence[Sequence[str | int]]) -> list[str]:
    """The text of each of several paths of keys (:func:`key`): the first whole, each after it
    from where it parts from the first, its list indices aside (``protocol.all.noise_sd_mm``,
    ``knee.markers_mm``)."""
    first, *beside = (tuple(path) for path in paths)
    stem = first
    while stem and isinstance(stem[-1], int):
        stem = stem[:-1]
    return [key(first), *(key(other[_shared(stem, other) :]) for other in beside)]


def _shared(stem: Sequence, other: Sequence) -> int:
    """How many of ``other``'s first keys it shares with ``stem``, all but its last at most:
    what :func:`keys` leaves out of it."""
    shared = 0
    while shared < min(len(stem), len(other) - 1) and stem[shared] == other[shared]:
        shared += 1
    return shared


def _split(annotation: object) -> tuple[object, tuple]:
    """The type under ``Annotated`` and its metadata."""
    if typing.get_origin(annotation) is Annotated:
        return annotation.__origin__, annotation.__metadata__
    return annotation, ()


def _metadata(metadata: tuple, kind: type):
    return next((item for item in metadata if isinstance(item, kind)), None)


def _is_union(base: object) -> bool:
    return typing.get_origin(base) in (typing.Union, types.UnionType)


def _numeric(base: object) -> bool:
    return base in (int, float)


def describe(annotation: object) -> str:
    """What ``annotation`` allows, in words: ``"an integer >= 1 or null"``."""
    base, metadata = _split(annotation)
    if _is_union(base):
        members = typing.get_args(base)
        words = [describe(m) for m in members if m is not type(None)]
        return " or ".join(words + ["null"] * (type(None) in members))
    if base is type(None):
        return "null"
    if base is bool:
        return "true or false"
    if _numeric(base):
        bounds = _metadata(metadata, Range)
        words = ["an integer" if base is int else "a number", *(bounds.words() if bounds else [])]
        return " and ".join([" ".join(words[:2]), *words[2:]])
    if base is str:
        return "text"
    if typing.get_origin(base) is Literal:
        return "one of " + ", ".join(map(str, typing.get_args(base)))
    if base is np.ndarray or typing.get_origin(base) is tuple:
        count, item = _sequence(base, metadata)
        return _items(count.words(), item)
    if typing.get_origin(base) in (dict, Mapping):
        return f"a mapping of names to {describe(typing.get_args(base)[1])}"
    if dataclasses.is_dataclass(base):
        return f"a mapping of {base.__name__} fields"
    if base in (object, typing.Any):
        return "any value"
    return f"a {getattr(base, '__name__', base)}"


def _sequence(base: object, metadata: tuple) -> tuple[Length, object]:
    """How many items a sequence annotation allows, and the annotation of each."""
    if base is np.ndarray:
        return _metadata(metadata, Length) or Length(), float
    arguments = typing.get_args(base)
    if len(arguments) == 2 and arguments[1] is Ellipsis:
        return _metadata(metadata, Length) or Length(), arguments[0]
    if len(set(arguments)) != 1:
        raise TypeError(f"a tuple declaration needs items of one type, got {base}")
    return Length(len(arguments), len(arguments)), arguments[0]


def _items(count: str, item: object) -> str:
    base, metadata = _split(item)
    plain = {int: "integers", float: "numbers"}.get(base)
    if plain is None:
        return f"a list of {count} items, each {describe(item)}"
    bounds = _metadata(metadata, Range)
    return f"{count} {plain}" + (f" (each {' and '.join(bounds.words())})" if bounds else "")


def _is_number(value: object, base: object) -> bool:
    if isinstance(value, bool | np.bool_):
        return False
    kind = numbers.Integral if base is int else numbers.Real
    return isinstance(value, kind) and math.isfinite(value)


def check(value: object, annotation: object, path: Sequence[str | int] = ()) -> None:
    """Raise :class:`DeclarationError` at ``path`` (deeper for an item of a list or mapping)
    when ``value`` is not what ``annotation`` declares."""
    base, metadata = _split(annotation)
    if _is_union(base):
        _check_union(value, base, path)
        return
    if base in (object, typing.Any) or _fits(value, base, metadata, path):
        return
    raise DeclarationError(path, f"must be {describe(annotation)}, got {_REPR.repr(value)}")


def _check_union(value: object, base: object, path: Sequence[str | int]) -> None:
    members = typing.get_args(base)
    if value is None and type(None) in members:
        return
    errors = []
    for member in (m for m in members if m is not type(None)):
        try:
            check(value, member, path)
            return
        except DeclarationError as error:
            errors.append(error)
    # An item deep inside a single alternative is named where it is; otherwise the union.
    if len(errors) == 1 and errors[0].path != tuple(path):
        raise errors[0]
    raise DeclarationError(path, f"must be {describe(base)}, got {_REPR.repr(value)}")


def _fits(value: object, base: object, metadata: tuple, path: Sequence[str | int]) -> bool:
    """Whether ``value`` is of ``base`` within ``metadata``; raises for an item that is not."""
    if base is type(None):
        return value is None
    if base is bool:
        return isinstance(value, bool)
    if _numeric(base):
        bounds = _metadata(metadata, Range)
        return _is_number(value, base) and (bounds is None or value in bounds)
    if base is str:
        return isinstance(value, str)
    if typing.get_origin(base) is Literal:
        return not isinstance(value, bool) and value in typing.get_args(base)
    if base is np.ndarray or typing.get_origin(base) is tuple:
        if isinstance(value, np.ndarray):
            value = value.tolist()
        count, item = _sequence(base, metadata)
        if not isinstance(value, list | tuple) or len(value) not in count:
            return False
        for index, element in enumerate(value):
            check(element, item, (*path, index))
        return True
    if typing.get_origin(base) in (dict, Mapping):
        if not isinstance(value, Mapping):
            return False
        for name, element in value.items():
            check(name, typing.get_args(base)[0], (*path, name))
            check(element, typing.get_args(base)[1], (*path, name))
        return True
    if dataclasses.is_dataclass(base) and isinstance(value, base):
        check_fields(base, {f.name: getattr(value, f.name) for f in dataclasses.fields(base)}, path)
        return True
    return isinstance(value, base)


def field_types(cls: type) -> dict[str, object]:
    """The declared type of each field of dataclass ``cls``, by name."""
    hints = typing.get_type_hints(cls, include_extras=True)
    return {f.name: hints[f.name] for f in dataclasses.fields(cls)}


def check_fields(cls: type, values: Mapping[str, object], path: Sequence[str | int] = ()) -> None:
    """Raise :class:`DeclarationError` when ``values`` (some or all fields of dataclass
    ``cls``, e.g. a config's overrides) name a field ``cls`` lacks or one that is not what its
    annotation declares."""
    declared = field_types(cls)
    for name, value in values.items():
        if name not in declared:
            raise DeclarationError(
                (*path, name),
                f"{cls.__name__} has no such field; its fields: {', '.join(declared)}",
            )
        check(value, declared[name], (*path, name))


def keyword_types(fn: Callable, n_arrays: int) -> dict[str, object] | None:
    """The keyword options ``fn`` takes after its ``n_arrays`` marker arrays, each with its
    declared type (``inspect.Parameter.empty`` where it has none); ``None`` when it takes any
    keyword (``**options``)."""
    fn = inspect.unwrap(fn)
    parameters = list(inspect.signature(fn).parameters.values())[n_arrays:]
    if any(p.kind is inspect.Parameter.VAR_KEYWORD for p in parameters):
        return None
    # Evaluated in the function's own module, where its annotations' names are defined.
    hints = typing.get_type_hints(fn, include_extras=True)
    keyword = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    return {p.name: hints.get(p.name, p.empty) for p in parameters if p.kind in keyword}
