"""A fingerprint of the code behind a result: what makes an edited estimator rerun its jobs.

Snakemake reruns a job when its rule's code or parameters change, but the library lives in an
installed package it does not track. The workflow therefore passes each job a parameter
``code``: the hash of the compiled code of the functions that job runs, and of every
function, class and simple constant of jointbench (or of an extension module) they reach through
their global names; a cached or compiled callable counts as the function it wraps. Comments
and line numbers do not count; any change of what the code does does. Editing NM changes the
fingerprint of NM's estimate job only; editing a helper shared by
several estimators changes each of theirs.
"""

from __future__ import annotations

import hashlib
import inspect
import types
from collections.abc import Iterable, Mapping
from functools import partial

import numpy as np

__all__ = ["code_fingerprint", "reached"]

_SIMPLE = (int, float, str, bytes, bool, type(None))


def _ours(obj: object, prefixes: tuple[str, ...]) -> bool:
    module = getattr(obj, "__module__", None) or getattr(obj, "__name__", "")
    return isinstance(module, str) and module.startswith(prefixes)


def _code_objects(code: types.CodeType) -> Iterable[types.CodeType]:
    yield code
    for constant in code.co_consts:
        if isinstance(constant, types.CodeType):
            yield from _code_objects(constant)


def _names(obj: object) -> set[str]:
    """Global names a function (or every method of a class) refers to."""
    functions = [obj] if inspect.isfunction(obj) else []
    if inspect.isclass(obj):
        functions = [v for v in vars(obj).values() if inspect.isfunction(v)]
        functions += [v.__func__ for v in vars(obj).values() if isinstance(v, classmethod)]
    names: set[str] = set()
    for function in functions:
        for code in _code_objects(function.__code__):
            names.update(code.co_names)
    return names


def _is_simple(value: object) -> bool:
    """A constant whose ``repr`` is stable across runs: scalars, small numeric arrays, and
    containers of them."""
    if isinstance(value, (*_SIMPLE, np.generic)):
        return True
    if isinstance(value, np.ndarray):
        return value.size <= 100_000 and value.dtype.kind in "biuf"
    if isinstance(value, Mapping):
        return all(_is_simple(k) and _is_simple(v) for k, v in value.items())
    if isinstance(value, tuple | list | frozenset):
        return all(_is_simple(v) for v in value)
    return False


def _contents(value: object) -> list:
    """The values inside a container (a mapping's keys and values), one level deep."""
    if isinstance(value, Mapping):
        return [*value.keys(), *value.values()]
    return list(value)


def _has_contents(cell) -> bool:
    try:
        cell.cell_contents  # noqa: B018
    except ValueError:  # an empty cell
        return False
    return True


def _globals(obj: object) -> dict:
    if inspect.isfunction(obj):
        return obj.__globals__
    module = inspect.getmodule(obj)
    return vars(module) if module else {}


def reached(roots: Iterable[object], prefixes: tuple[str, ...] = ("jointbench",)) -> list:
    """The functions and classes of our modules reachable from ``roots``, with ``(module, name,
    value)`` triples for the simple constants they read; in a stable order."""
    seen: dict[int, object] = {}
    constants: dict[tuple[str, str], object] = {}
    stack = [r for r in roots if r is not None]
    while stack:
        obj = stack.pop()
        if isinstance(obj, partial):
            stack.append(obj.func)
            continue
        if not inspect.isfunction(obj) and inspect.isfunction(getattr(obj, "__wrapped__", None)):
            # A cache (functools.lru_cache) or compiled callable runs the function it wraps, the
            # way its class says (a compiled kernel's options); a class not of ours is dropped.
            stack.extend((obj.__wrapped__, type(obj)))
            continue
        if id(obj) in seen or not (inspect.isfunction(obj) or inspect.isclass(obj)):
            continue
        if not _ours(obj, prefixes):
            continue
        seen[id(obj)] = obj
        if inspect.isfunction(obj):
            stack.extend(c.cell_contents for c in obj.__closure__ or () if _has_contents(c))
            # Attributes such as a ``batched`` form run in the same job as the function.
            stack.extend(vars(obj).values())
        names = _names(obj)
        namespace = _globals(obj)
        for name in names:
            value = namespace.get(name)
            if isinstance(value, types.ModuleType) and _ours(value, prefixes):
                # ``module.attribute``: the attribute's name is among the same code's names.
                stack.extend(getattr(value, n) for n in names if hasattr(value, n))
            elif _is_simple(value):
                constants[(namespace.get("__name__", ""), name)] = value
            elif isinstance(value, Mapping | tuple | list | frozenset):
                stack.extend(_contents(value))
            elif value is not None:
                stack.append(value)
        if inspect.isclass(obj):
            stack.extend(obj.__mro__[1:])
    ordered = sorted(seen.values(), key=lambda o: (o.__module__, o.__qualname__, _identity(o)))
    return [*ordered, *sorted((m, n, _stable_repr(v)) for (m, n), v in constants.items())]


def _code_bytes(code: types.CodeType) -> bytes:
    """Bytecode, names and constants of ``code`` and its nested code: what it does, not where it
    stands in its file (line numbers and comments do not count)."""
    parts = [code.co_code, repr(code.co_names).encode(), repr(code.co_varnames).encode()]
    for constant in code.co_consts:
        if isinstance(constant, types.CodeType):
            parts.append(_code_bytes(constant))
        else:
            parts.append(_stable_repr(constant).encode())
    return b"\x00".join(parts)


def _stable_repr(value: object) -> str:
    """``repr`` where it is stable across runs, else the type's name (no memory addresses)."""
    if isinstance(value, np.ndarray) and _is_simple(value):
        return f"array{value.shape}{value.dtype}{value.tobytes().hex()}"
    return repr(value) if _is_simple(value) else type(value).__qualname__


# Functions and classes do not change while a process runs; the workflow fingerprints dozens
# of jobs whose code overlaps, so each object's identity is computed once.
_IDENTITIES: dict[int, tuple[object, bytes]] = {}


def _identity(obj: object) -> bytes:
    if isinstance(obj, tuple):
        return repr(obj).encode()
    cached = _IDENTITIES.get(id(obj))
    if cached is None or cached[0] is not obj:
        cached = _IDENTITIES[id(obj)] = (obj, _compute_identity(obj))
    return cached[1]


def _compute_identity(obj: object) -> bytes:
    name = f"{obj.__module__}.{obj.__qualname__}".encode()
    if inspect.isfunction(obj):
        defaults = [_stable_repr(v) for v in obj.__defaults__ or ()]
        # A function made by a factory differs from its siblings by its closure's values.
        cells = [_stable_repr(c.cell_contents) for c in obj.__closure__ or () if _has_contents(c)]
        return name + _code_bytes(obj.__code__) + repr([defaults, cells]).encode()
    members = [
        (key, _identity(v) if inspect.isfunction(v) else repr(v).encode())
        for key, v in sorted(vars(obj).items())
        if key not in ("__dict__", "__weakref__", "__doc__", "__module__")
        and (inspect.isfunction(v) or _is_simple(v))
    ]
    return name + repr(members).encode() + repr(getattr(obj, "__annotations__", {})).encode()


def code_fingerprint(*roots: object, prefixes: tuple[str, ...] = ("jointbench",)) -> str:
    """A short hash of the source of ``roots`` and all our code they reach (see module doc)."""
    digest = hashlib.sha256()
    for obj in reached(roots, prefixes):
        digest.update(_identity(obj))
    return digest.hexdigest()[:16]
