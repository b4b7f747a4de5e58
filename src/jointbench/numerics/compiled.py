"""Kernels compiled by Numba on first use.

A kernel is a plain Python function over NumPy arrays and scalars that calls no other function
of the package but other kernels: loops a stack of small problems through, where NumPy would
pay its per-call overhead on every tiny array. :func:`kernel` compiles it on its first call, so
a process that never calls it never pays for importing and starting Numba. The machine code is
cached beside the source file and rebuilt when anything compiled into it changes: Numba itself
checks only the kernel's own file, so each kernel's cache entry is named by a digest of its
code as the process loaded it (its bytecode, what Numba compiles: never the file, which an
edit saved after the import may already hold), of the functions it calls (other kernels,
functions of ``numba.njit`` or ``register_jitable``: their code and what they read in turn)
and of the constants it reads,
by name or as a module's attribute (``module.NAME``) (:meth:`_Kernel.digest`), and an edit in
another module gets an entry of its own instead of the old machine code. The Python source stays the
specification: it runs as written (slowly) through ``kernel.__wrapped__``, and it counts in
the code fingerprint (:mod:`jointbench.fingerprint`) of every job that can import it.
"""

from __future__ import annotations

import functools
import hashlib
import types
from collections.abc import Callable

import numpy as np

from jointbench.owncode import own_code

__all__ = ["kernel", "kernel_array", "kernel_called"]


#: How every kernel is compiled (``numba.njit``'s options besides the cache). They name its
#: cache entry with its code (:meth:`_Kernel.digest`): Numba's cache tells neither an edit of
#: them nor of this file from the machine code it holds, and would load code compiled under
#: other options (``fastmath``'s fused multiply-adds, say) as if it were this. error_model
#: "numpy": a float division by zero gives inf or nan, as NumPy's does, instead of raising.
COMPILE_OPTIONS: dict[str, object] = {"nogil": True, "error_model": "numpy"}


class _Kernel:
    """A function compiled on its first call (see the module doc)."""

    def __init__(self, function: Callable) -> None:
        functools.update_wrapper(self, function)
        self._compiled: Callable | None = None
        self._digest: str | None = None

    def __call__(self, *args):
        # The dispatcher once compiled, without a method call: a checked fit calls a few
        # kernels of microseconds each, where that call is a measurable share.
        compiled = self._compiled
        if compiled is None:
            compiled = self.compiled()
        return compiled(*args)

    def compiled(self) -> Callable:
        """The compiled function (Numba's dispatcher), compiled now if it was not yet."""
        if self._compiled is None:
            import numba

            function = self.__wrapped__
            # The kernels it calls, by the names it calls them, as compiled functions: Numba
            # calls those from compiled code, not the Python objects around them.
            called = {
                name: value.compiled()
                for name in _global_names(function.__code__)
                if isinstance(value := function.__globals__.get(name), _Kernel)
            }
            function = types.FunctionType(
                function.__code__,
                {**function.__globals__, **called},
                function.__name__,
                function.__defaults__,
                function.__closure__,
            )
            # Numba names a cache entry by the function's qualified name and rebuilds it only
            # when the function's own file changes; the digest in the name gives every version
            # of what is compiled in an entry of its own.
            function.__qualname__ = f"{self.__wrapped__.__qualname__}.{self.digest()}"
            self._compiled = numba.njit(cache=True, **COMPILE_OPTIONS)(function)
        return self._compiled

    def digest(self) -> str:
        """A digest of everything compiled into the kernel (:func:`_code_digest`) and of how
        (:data:`COMPILE_OPTIONS`)."""
        if self._digest is None:
            code = _code_digest(self.__wrapped__, set())
            options = repr(sorted(COMPILE_OPTIONS.items()))
            self._digest = hashlib.sha256(f"{code}\n{options}".encode()).hexdigest()[:16]
        return self._digest


#: The code of a kernel's call and compilation: a traceback through a kernel shows these frames
#: of the wrapper, never the kernel's own lines, which run as machine code.
_CALL_CODES = frozenset({_Kernel.__call__.__code__, _Kernel.compiled.__code__})


def kernel_called(frame: types.FrameType) -> _Kernel | None:
    """The kernel whose call (or compilation) ``frame``, a traceback's frame, runs; ``None``
    for a frame of anything else."""
    if frame.f_code not in _CALL_CODES:
        return None
    return frame.f_locals.get("self")


def _code_digest(function: types.FunctionType, seen: set[int]) -> str:
    """A digest of what of ``function`` Numba compiles in: its code and defaults, and what
    each global it names holds (:func:`_value_digest`). ``seen`` holds the ids of the functions
    and namespaces being digested, which a recursive reference meets again."""
    names = _global_names(function.__code__)
    # The code as loaded, which Numba compiles: the file may hold an edit saved since.
    parts = [_code_text(function.__code__), repr(function.__defaults__)]
    for name in sorted(names):
        if name in function.__globals__:
            parts.append(f"{name}={_value_digest(function.__globals__[name], names, seen)}")
    return hashlib.sha256("\n".join(parts).encode()).hexdigest()[:16]


def _code_text(code: types.CodeType) -> str:
    """The bytecode, names and constants of ``code`` and of the code nested in it
    (comprehensions, inner functions), as text; line numbers left out, as they change no
    machine code."""
    constants = [_constant_text(c) for c in code.co_consts]
    return (
        f"{code.co_code.hex()} {code.co_names} {code.co_varnames} {code.co_freevars} "
        f"{code.co_cellvars} [{', '.join(constants)}]"
    )


def _constant_text(constant: object) -> str:
    """A constant of a code object as text, the same in every process: a set's members sorted,
    as string hashing orders them differently in each."""
    if isinstance(constant, types.CodeType):
        return _code_text(constant)
    if isinstance(constant, frozenset):
        return f"frozenset({sorted(map(repr, constant))})"
    return repr(constant)


def _global_names(code: types.CodeType) -> set[str]:
    """The names ``code`` and the code nested in it (comprehensions, inner functions) look up
    as globals or attributes: a superset of the globals it reads."""
    names = set(code.co_names)
    for constant in code.co_consts:
        if isinstance(constant, types.CodeType):
            names |= _global_names(constant)
    return names


def _value_digest(value: object, names: set[str], seen: set[int]) -> str:
    """What of a global ``value`` a kernel's machine code can depend on, as text, for a kernel
    that names ``names`` (as globals or attributes): a kernel's digest; the code digest of a
    function of the package's or the user's own that Numba compiles in (a dispatcher of
    ``numba.njit``, a function of ``register_jitable``); a constant's value; for a module or a
    class, what its attributes among ``names`` hold (``module.NAME``); else a name."""
    if isinstance(value, _Kernel):
        return value.digest()
    if isinstance(value, np.ndarray):
        content = hashlib.sha256(np.ascontiguousarray(value).tobytes()).hexdigest()
        return f"array({value.dtype}, {value.shape}, {content})"
    if isinstance(value, tuple):
        return "(" + ", ".join(_value_digest(item, names, seen) for item in value) + ")"
    if value is None or isinstance(value, (bool, int, float, complex, str, bytes, np.generic)):
        return repr(value)
    named = f"{type(value).__qualname__} {getattr(value, '__module__', '')}." + str(
        getattr(value, "__qualname__", getattr(value, "__name__", ""))
    )
    if id(value) in seen:
        return named  # met again inside itself: digested where it was met first
    function = _python_function(value)
    if function is not None and own_code(function.__code__.co_filename):
        return _code_digest(function, seen | {id(value)})
    if isinstance(value, (types.ModuleType, type)):
        # Read through the namespace's dictionary: a module's lazy names are not imported.
        attributes = vars(value)
        held = [
            f"{name}={_value_digest(attributes[name], names, seen | {id(value)})}"
            for name in sorted(names & attributes.keys())
        ]
        return f"{named} {{{', '.join(held)}}}"
    # Other objects by name (their repr may hold an address).
    return named


def _python_function(value: object) -> types.FunctionType | None:
    """The Python function behind ``value``: itself, or the ``py_func`` a Numba dispatcher
    compiles; ``None`` for anything else."""
    function = getattr(value, "py_func", value)
    return function if isinstance(function, types.FunctionType) else None


def kernel_array(array: object, dtype: type = float) -> np.ndarray:
    """``array`` as a kernel's input: ``dtype``, C-contiguous and writable, copied only when it
    is not. Numba compiles a kernel once per argument type, and a read-only or strided array is
    a type of its own, which would cost another compilation."""
    # A checked call hands a dozen arrays through here: np.require's own checks, and comparing
    # a dtype with a Python type (which builds a dtype), cost more than a small kernel call.
    # NumPy's float64 dtype is one object; ``carray`` is C-contiguous, writable and aligned.
    if isinstance(array, np.ndarray) and array.flags.carray:
        wanted = _FLOAT64 if dtype is float else dtype
        if array.dtype is wanted or array.dtype == wanted:
            return array
    return np.require(array, dtype, ["C", "W"])


_FLOAT64 = np.dtype(np.float64)


def kernel(function: Callable) -> Callable:
    """Decorator: ``function`` compiled by Numba when first called (see the module doc)."""
    return _Kernel(function)
