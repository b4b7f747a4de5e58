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

__all__ = ["scipy_special"]


@functools.cache
def scipy_special() -> types.ModuleType:
    """The module ``scipy.special``, imported on the first call and held after it: an import
    statement per call would cost a share of a one-trial check."""
    # Here, not at the top: see the module doc.
    import scipy.special

    return scipy.special
