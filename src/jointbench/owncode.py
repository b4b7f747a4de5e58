"""Which code is the package's or its user's own, and which an installed library's.

Two rules read it: a ``ValueError`` is a trial's stated failure only when a ``raise`` statement
of the method's own code raised it (:func:`jointbench.estimators.batching.numerical_failure`),
and a compiled kernel's cache digest follows the functions it calls into their source only
where they are own code (:mod:`jointbench.numerics.compiled`); a library's change comes with a
new version of it. Own code is any file of the package, wherever it is installed, and any file
outside the standard library and the installed packages' folders (a user's extension file, a
script, code made by ``exec``).
"""

from __future__ import annotations

import functools
import os
import site
import sysconfig

__all__ = ["own_code"]

_PACKAGE = os.path.join(os.path.dirname(os.path.realpath(__file__)), "")


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
    return path.startswith(_PACKAGE) or not path.startswith(_library_roots())
