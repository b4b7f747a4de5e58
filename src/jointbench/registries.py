"""Named values of one kind, collected in registration order: the studies, the papers and, per
kind, the estimators (:mod:`jointbench.estimators.registry`); and the discovery of the built-in
studies and papers."""

from __future__ import annotations

import importlib.util
import pkgutil
from collections.abc import Callable, Iterable
from types import ModuleType
from typing import Generic, TypeVar

__all__ = ["Registry", "exported", "submodules"]

T = TypeVar("T")


class Registry(Generic[T]):
    """Values of one kind by name. ``what`` names the kind in messages ("study", "paper");
    ``name_of`` gives a value's name."""

    def __init__(self, what: str, name_of: Callable[[T], str]) -> None:
        self._what = what
        self._name_of = name_of
        self._values: dict[str, T] = {}

    def register(self, value: T) -> T:
        """Add ``value``; registering the same value twice is harmless, another of the same
        name is refused."""
        name = self._name_of(value)
        known = self._values.get(name)
        if known is not None and known is not value:
            raise ValueError(f"a different {self._what} named {name!r} is already registered")
        self._values[name] = value
        return value

    def remove(self, name: str) -> None:
        """Forget the value called ``name`` (``KeyError`` if there is none)."""
        del self._values[name]

    def get(self, name: str) -> T:
        """The value called ``name``; ``ValueError`` listing the known names otherwise."""
        try:
            return self._values[name]
        except KeyError:
            known = ", ".join(self._values) or "none"
            raise ValueError(f"unknown {self._what} {name!r}; known: {known}") from None

    def names(self) -> tuple[str, ...]:
        """The registered names, in registration order."""
        return tuple(self._values)

    def values(self) -> tuple[T, ...]:
        """The registered values, in registration order."""
        return tuple(self._values.values())


def submodules(package: str) -> list[str]:
    """The full names of the modules of ``package`` (its dotted name, written as a literal so
    that the code fingerprint finds them: :mod:`jointbench.fingerprint`), in name order: where
    the built-in studies and papers are found, so that adding one is adding its module, not
    also editing a list. The importing is the caller's, at its module level."""
    folders = importlib.util.find_spec(package).submodule_search_locations
    return sorted(f"{package}.{m.name}" for m in pkgutil.iter_modules(folders))


def exported(modules: Iterable[ModuleType], attribute: str) -> list:
    """The ``attribute`` of each of ``modules`` that defines one (``STUDY``, ``PAPER``)."""
    return [getattr(m, attribute) for m in modules if hasattr(m, attribute)]
