"""The largest coordinate float64's sums over a recording hold, and where an array exceeds it."""

from __future__ import annotations

import math

import numpy as np

from jointbench.numerics.compiled import kernel

__all__ = ["first_beyond", "largest_coordinate", "largest_magnitude"]

# 2^255, ~5.8e76: the power of two below the fourth root of the largest float64 (just under
# 2^1024), so that the bound of largest_coordinate leaves products no rounding can overflow.
_FOURTH_ROOT_MAX = 2.0**255


@kernel
def largest_coordinate(n_samples: int) -> float:
    """The largest magnitude [mm] a coordinate of an array of ``n_samples`` samples (frames
    times markers) may have: a larger one is refused as a non-finite one is.

    The checks, the screen and the fits sum squared distances over the samples and multiply
    two such sums (a scatter matrix's minors and squared trace; the sphere fits' sums of
    ``|x|^2 x x'``): with every coordinate within ``M``, two samples lie within ``sqrt(12) M``
    of each other, a sum of squared distances is within ``12 n M^2`` and a product of two
    within ``(12 n M^2)^2``, which float64 holds while ``M`` is at most the fourth root of its
    largest value (taken as 2^255) over ``sqrt(12 n)``. No capture volume comes near it; a
    coordinate beyond it is a corrupt sample (or a wrong unit), and past it the arithmetic
    overflows into NaN, which no check can read. A compiled kernel, for the checks' own."""
    return _FOURTH_ROOT_MAX / math.sqrt(12.0 * n_samples)


@kernel
def largest_magnitude(markers: np.ndarray) -> float:
    """The largest absolute coordinate [mm] of ``markers`` ``(n_frames, n_markers, 3)``, 0 for
    none: what a running ``max(largest, abs(x))`` from 0 over every coordinate gives (a NaN
    coordinate is passed over, as Numba's ``max`` passes it over in its second argument). The
    three coordinates are taken by three running maxima, which the processor advances side by
    side: one alone waits on each comparison, at a few times the cost of the pass. The largest
    of a set does not depend on the order it is read in, so the answer is that of one. A
    compiled kernel."""
    x = y = z = 0.0
    for f in range(markers.shape[0]):
        for m in range(markers.shape[1]):
            x = max(x, abs(markers[f, m, 0]))
            y = max(y, abs(markers[f, m, 1]))
            z = max(z, abs(markers[f, m, 2]))
    return max(max(x, y), z)


def first_beyond(markers: np.ndarray) -> tuple[int, int, float, float, int] | None:
    """The first sample of ``markers`` ``(n_frames, n_markers, 3)`` [mm] (frame by frame) with
    a coordinate beyond :func:`largest_coordinate`: ``(frame, marker, that coordinate, the
    bound, the samples beyond it)``; ``None`` where there is none (NaN is never beyond)."""
    markers = np.asarray(markers)
    n_frames, n_markers, _ = markers.shape
    bound = largest_coordinate(n_frames * n_markers)
    beyond = np.abs(markers) > bound
    if not beyond.any():
        return None
    per_sample = beyond.any(axis=-1)
    frame, marker = np.argwhere(per_sample)[0]
    value = float(markers[frame, marker][beyond[frame, marker]][0])
    return int(frame), int(marker), value, bound, int(per_sample.sum())
