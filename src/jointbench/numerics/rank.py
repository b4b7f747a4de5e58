"""The one threshold below which an eigenvalue or singular value counts as zero.

A normal matrix of a degenerate problem (a pure hinge for a sphere fit or SCoRE, no relative
rotation for SARA) is singular only to rounding: its smallest eigenvalue sits near
``eps * largest``. Ill-conditioned but regular systems keep eigenvalues far above ``1e-12`` of
the largest (a relative rotation off the main axis above about 1e-6 rad), and are solved as they
are: their poor answers at small ranges of motion are what the benchmark measures.
"""

from __future__ import annotations

import numpy as np

__all__ = ["RCOND", "negligible"]

RCOND = 1e-12


def negligible(values: np.ndarray, largest: np.ndarray | float) -> np.ndarray:
    """``True`` where ``|values|`` is at most :data:`RCOND` times ``largest``.

    ``largest`` broadcasts against ``values`` (pass ``largest[..., None]`` for stacks).
    """
    return np.abs(values) <= RCOND * largest
