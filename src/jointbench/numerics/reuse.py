"""Values of a trial's frames that several stages of one checked call read, computed once.

A checked call (:func:`jointbench.estimators.registry.get` and ``many``) runs a method's fit,
its self-check and its statement of precision on the same arrays, and each stage may need the
same sum over every frame (paper B's scatter ``S``, for the axis methods): on a long trial that
sum costs more than the arithmetic of the check that reads it. Inside :func:`one_call` the
first stage to compute such a value for an array keeps it and the later stages read it back
(:func:`remembered`); outside one, every value is computed where it is asked for, so a stage
returns the same numbers either way.

An array is known by its memory: its address, shape, strides and dtype, so the view of a trial
that another stage takes of the same batch finds the value; a value of several arrays (two
segments' rotations) by the memory of each, in order. The scope holds every array it has
seen, so no memory it knows can be freed and reused by another array while it lasts; the
stages of a call read their input and never write to it.
"""

from __future__ import annotations

from collections.abc import Callable
from contextlib import AbstractContextManager
from contextvars import ContextVar
from typing import TypeVar

import numpy as np

__all__ = ["keep", "kept_for", "one_call", "remembered"]

_Value = TypeVar("_Value")

# Per scope: by (name, address, shape, strides, dtype), the array and its value. A context
# variable, so that each thread (and each task) has scopes of its own.
_KEPT: ContextVar[dict | None] = ContextVar("jointbench_reuse", default=None)


class _Scope:
    """The context manager of :func:`one_call`: a class, as a generator's context manager costs
    a few microseconds a call, a share of a checked one-trial fit."""

    __slots__ = ("_token",)

    def __enter__(self) -> None:
        self._token = _KEPT.set({})

    def __exit__(self, *_exception: object) -> None:
        _KEPT.reset(self._token)


def one_call() -> AbstractContextManager[None]:
    """The scope of one checked call: values remembered inside it are forgotten at its end. A
    scope opened inside another starts empty and the outer one's values return with it."""
    return _Scope()


def remembered(
    name: str, array: np.ndarray | tuple[np.ndarray, ...], compute: Callable[..., _Value]
) -> _Value:
    """``compute(array)``, or inside :func:`one_call` the value ``name`` already computed for
    an array of the same memory (for a tuple of arrays, each of the same memory). The value is
    shared by every stage that asks: ``compute`` returns one that no caller writes to (a
    read-only array)."""
    kept = _KEPT.get()
    if kept is None:
        return compute(array)
    arrays = array if isinstance(array, tuple) else (array,)
    # The same array objects asked again are found by their identity first: the scope holds
    # every array it has seen, so no other object takes its id while it lasts, and reading an
    # array's address (its __array_interface__) costs microseconds a look-up. Each id in a
    # tuple of its own, never equal to the address a memory key below holds.
    asked = (name, *[((id(each),), each.shape, each.strides, each.dtype) for each in arrays])
    found = kept.get(asked)
    if found is None:
        key = (name, *(_memory(each) for each in arrays))
        found = kept.get(key)
        if found is None:
            found = kept[key] = (array, compute(array))
        kept[asked] = (array, found[1])  # held, so that no other object takes its id
    return found[1]


def keep(name: str, array: np.ndarray, value: object) -> None:
    """Inside :func:`one_call`, hold ``value`` as what ``name`` is of this very array object
    (:func:`kept_for`); outside one, nothing. For a value a stage states of an array rather
    than computes from its frames (that it passed a check): it is known by the object, not by
    its memory, whose address costs a look-up microseconds."""
    kept = _KEPT.get()
    if kept is not None:
        kept[_identity(name, array)] = (array, value)  # held, so no other object takes its id


def kept_for(name: str, array: np.ndarray) -> object | None:
    """The value :func:`keep` holds as ``name`` of this very array object in the open scope
    of one call; ``None`` outside one, or where none is held."""
    kept = _KEPT.get()
    if kept is None:
        return None
    found = kept.get(_identity(name, array))
    return None if found is None else found[1]


def _identity(name: str, array: np.ndarray) -> tuple:
    """The key of ``array`` known by its identity, as :func:`remembered` keys it first."""
    return (name, ((id(array),), array.shape, array.strides, array.dtype))


def _memory(array: np.ndarray) -> tuple:
    """What tells ``array``'s memory from any other's: its address, shape, strides and
    dtype."""
    return (array.__array_interface__["data"][0], array.shape, array.strides, array.dtype)
