"""Which code is the package's or its user's own, and which an installed library's.

Two rules read it: a ``ValueError`` is a trial's stated failure only when a ``raise`` statement
of the method's own code raised it (:func:`jointbench.estimators.batching.numerical_failure`),
and a compiled kernel's cache digest follows the functions it calls into their source only
where they are own code (:mod:`jointbench.numerics.compiled`); a library's change comes with a
new version of it. Own code is any file of the package, wherever it is installed; any file of
the package that defines a registered method (:func:`claim`), wherever it is installed (a user's
estimators installed beside the libraries are still the method's own code); and any file outside
the standard library and the installed packages' folders (a user's extension file, a script,
code made by ``exec``).
"""

from __future__ import annotations

import functools
import inspect
import os
import site
import sys
import sysconfig
import types
from collections.abc import Callable

__all__ = ["claim", "own_code", "package_code"]

_PACKAGE = os.path.join(os.path.dirname(os.path.realpath(__file__)), "")

#: Files and folders (a folder ending in a separator) of the packages that define registered
#: methods (:func:`claim`): own code wherever they are installed, for the process's life.
_CLAIMED: set[str] = set()


@functools.cache
def _library_roots() -> tuple[str, ...]:
    """The folders of the standard library and of installed packages, each ending in a
    separator."""
    paths = sysconfig.get_paths()
    roots = {paths[key] for key in ("stdlib", "platstdlib", "purelib", "platlib")}
    roots |= {*site.getsitepackages(), site.getusersitepackages()}
    return tuple(os.path.join(os.path.realpath(root), "") for root in roots)


@functools.lru_cache(maxsize=1024)
def own_code(filename: str) -> bool:
    """Whether code of ``filename`` (a code object's ``co_filename``) is own code (module doc);
    frozen modules and Cython sources are the library's."""
    if filename.startswith("<frozen") or filename.endswith((".pyx", ".pxd", ".pxi")):
        return False
    path = os.path.realpath(filename)
    return (
        _in_package(filename)
        or path.startswith(tuple(_CLAIMED))
        or not path.startswith(_library_roots())
    )


def package_code(function: Callable) -> bool:
    """Whether ``function`` and every function it wraps (its ``__wrapped__`` chain) are Python
    functions defined in files of this package itself, not a user's (claimed or not) nor a
    library's: code whose every read and write of its arrays the package knows. Every layer
    is asked, as a user's wrapper states the package's fit as the one it wraps yet runs its
    own code around it, and a package's wrapper may run a user's fit."""
    wrappers: list[Callable] = []  # each layer that wraps another, outermost first
    innermost = inspect.unwrap(function, stop=wrappers.append)  # append returns None: no stop
    return all(_package_function(layer) for layer in (*wrappers, innermost))


def _package_function(function: Callable) -> bool:
    """Whether ``function`` itself (not what it wraps) is a Python function of this package."""
    code = getattr(function, "__code__", None)
    return code is not None and _in_package(code.co_filename)


@functools.lru_cache(maxsize=1024)
def _in_package(filename: str) -> bool:
    """Whether the file ``filename`` (a code object's ``co_filename``) is one of this
    package's, wherever it is installed."""
    return os.path.realpath(filename).startswith(_PACKAGE)


def claim(function: Callable) -> None:
    """Count the top-level package (or module) that defines ``function``, a method being
    registered, as own code wherever it is installed: where that method goes wrong, and which
    ``ValueError`` it states, is read in its own code even when it lives in site-packages.
    Anything but a Python function (a ``functools.partial``, a builtin) claims nothing."""
    function = inspect.unwrap(function)
    if not isinstance(function, types.FunctionType):
        return
    top = sys.modules.get((function.__module__ or "").partition(".")[0])
    if top is None or top.__name__ == __package__:
        return
    places = _places(top)
    if not places <= _CLAIMED:
        _CLAIMED.update(places)
        own_code.cache_clear()


def _places(top: types.ModuleType) -> set[str]:
    """Where a top-level package or module is: the real paths of a package's folders, each
    ending in a separator, or of a module's file."""
    folders = list(getattr(top, "__path__", ()))
    if folders:
        return {os.path.join(os.path.realpath(folder), "") for folder in folders}
    file = getattr(top, "__file__", None)
    return {os.path.realpath(file)} if file else set()
