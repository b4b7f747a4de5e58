"""scipy.special, imported on first use.

The workflow's start and every one of its jobs import the estimators, the screening and the
tolerance kinds, but only a check (a checked call's support, a screened trial's label swaps, a
Gauss–Markov model test, a tolerance's binomial quantile) calls a distribution function of
scipy.special. Imported with the modules, scipy.special, whose array-API layer loads
``numpy.f2py`` and ``numpy.testing``, would be paid by every ``snakemake`` invocation and every
job (``tests/test_imports.py`` holds both to not loading it).
"""

from __future__ import annotations

import functools
import types

__all__ = ["f_survival", "scipy_special"]


@functools.cache
def scipy_special() -> types.ModuleType:
    """The module ``scipy.special``, imported on the first call and held after it: an import
    statement per call would cost a share of a one-trial check."""
    # Here, not at the top: see the module doc.
    import scipy.special

    return scipy.special


@functools.cache
def _cython_special() -> types.ModuleType:
    """``scipy.special.cython_special``, imported on the first call (see the module doc)."""
    from scipy.special import cython_special

    return cython_special


def f_survival(dfn: float, dfd: float, ratio: float) -> float:
    """The F distribution's survival function at ``ratio`` on ``(dfn, dfd)`` degrees of
    freedom, three real numbers: ``scipy.special.fdtrc``'s number, through its scalar form
    (``cython_special``), which skips the ufunc's dispatch over arrays, a microsecond a call
    where a checked call reads a few."""
    fdtrc = _cython_special().fdtrc
    try:
        return fdtrc(dfn, dfd, ratio)
    except TypeError:  # an integer: the scalar form takes floats, as the ufunc makes it doubles
        return fdtrc(float(dfn), float(dfd), float(ratio))
