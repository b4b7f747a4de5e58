"""Kernels compiled by Numba on first use.

A kernel is a plain Python function over NumPy arrays and scalars that calls no other function
of the package but other kernels: loops a stack of small problems through, where NumPy would
pay its per-call overhead on every tiny array. :func:`kernel` compiles it on its first call, so
a process that never calls it never pays for importing and starting Numba. The machine code is
cached beside the source file and rebuilt when that file changes. The Python source stays the
specification: it runs as written (slowly) through ``kernel.__wrapped__``, and it counts in
the code fingerprint (:mod:`jointbench.fingerprint`) of every job that can import it.
"""

from __future__ import annotations

import functools
import types
from collections.abc import Callable

import numpy as np

__all__ = ["kernel", "kernel_array"]


class _Kernel:
    """A function compiled on its first call (see the module doc)."""

    def __init__(self, function: Callable) -> None:
        functools.update_wrapper(self, function)
        self._compiled: Callable | None = None

    def __call__(self, *args):
        return self.compiled()(*args)

    def compiled(self) -> Callable:
        """The compiled function (Numba's dispatcher), compiled now if it was not yet."""
        if self._compiled is None:
            import numba

            function = self.__wrapped__
            # The kernels it calls, by the names it calls them, as compiled functions: Numba
            # calls those from compiled code, not the Python objects around them.
            called = {
                name: value.compiled()
                for name in function.__code__.co_names
                if isinstance(value := function.__globals__.get(name), _Kernel)
            }
            if called:
                function = types.FunctionType(
                    function.__code__,
                    {**function.__globals__, **called},
                    function.__name__,
                    function.__defaults__,
                    function.__closure__,
                )
            # error_model="numpy": a float division by zero gives inf or nan, as NumPy's does,
            # instead of raising.
            self._compiled = numba.njit(cache=True, nogil=True, error_model="numpy")(function)
        return self._compiled


def kernel_array(array: object, dtype: type = float) -> np.ndarray:
    """``array`` as a kernel's input: ``dtype``, C-contiguous and writable, copied only when it
    is not. Numba compiles a kernel once per argument type, and a read-only or strided array is
    a type of its own, which would cost another compilation."""
    if (
        isinstance(array, np.ndarray)
        and array.dtype == dtype
        and array.flags.c_contiguous
        and array.flags.writeable
    ):
        return array  # np.require's own checks cost more than a small kernel call
    return np.require(array, dtype, ["C", "W"])


def kernel(function: Callable) -> Callable:
    """Decorator: ``function`` compiled by Numba when first called (see the module doc)."""
    return _Kernel(function)
