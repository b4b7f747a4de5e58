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
    """Whether ``function`` and every Python function a call of it may run that it holds are
    Python functions defined in files of this package itself, not a user's (claimed or not) nor
    a library's: code whose every read and write of its arrays the package knows. Held are the
    functions it wraps (its ``__wrapped__`` chain: a user's wrapper states the package's fit as
    the one it wraps yet runs its own code around it) and those it closes over, their own
    likewise (a many-trial form the package builds around a user's function, such as
    :func:`jointbench.estimators.twosegment.batched`'s, runs that function and says nothing
    of it); a ``functools.partial`` holds its function and the callables among its arguments,
    an object its class's ``__call__``. Remembered per function (one that can be hashed): a
    checked call asks it of its method's fit."""
    try:
        hash(function)
    except TypeError:  # unhashable, as its class says or as a field of it (a frozen dataclass
        # of a list, whose class states a hash its fields cannot give): found anew each time
        return _all_package_code(function)
    return _remembered_package_code(function)


@functools.lru_cache(maxsize=256)
def _remembered_package_code(function: Callable) -> bool:
    return _all_package_code(function)


def _all_package_code(function: Callable) -> bool:
    """:func:`package_code`, found anew."""
    return all(_package_function(held) for held in _functions_held(function))


def _functions_held(function: Callable) -> list:
    """``function`` and the Python functions it holds (:func:`package_code`), each once."""
    found: dict[int, object] = {}
    pending = [function]
    while pending:
        item = pending.pop()
        if id(item) in found:
            continue
        found[id(item)] = item
        if isinstance(item, functools.partial):
            pending += [item.func, *filter(callable, (*item.args, *item.keywords.values()))]
            continue
        wrapped = getattr(item, "__wrapped__", None)
        if wrapped is not None:
            pending.append(wrapped)
        if isinstance(item, types.FunctionType):
            cells = item.__closure__ or ()
            pending += [cell.cell_contents for cell in cells if _held_code(cell)]
        elif _python_call(item) is not None:
            pending.append(_python_call(item))
    # A callable object is its class's __call__, held above; the one asked about is itself
    # too (anything but a Python function or a partial is no function of the package's).
    held = [item for item in found.values() if isinstance(item, types.FunctionType)]
    if not isinstance(function, types.FunctionType | functools.partial):
        held.append(function)
    return held


def _held_code(cell: types.CellType) -> bool:
    """Whether a closure's ``cell`` holds code a call may run: a Python function, a partial, or
    an object whose class defines ``__call__`` in Python (not a class, nor a library's
    callable, such as a NumPy ufunc)."""
    try:
        item = cell.cell_contents
    except ValueError:  # a cell not yet filled
        return False
    return isinstance(item, types.FunctionType | functools.partial) or (
        _python_call(item) is not None
    )


def _python_call(item: object) -> types.FunctionType | None:
    """The ``__call__`` of ``item``'s class where the class defines it in Python, for an
    object that is not itself a class; else ``None``."""
    if isinstance(item, type):
        return None
    for klass in type(item).__mro__:  # as inspect.getattr_static finds it, at a tenth the cost
        if "__call__" in vars(klass):
            call = vars(klass)["__call__"]
            return call if isinstance(call, types.FunctionType) else None
    return None


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
