"""Artefacts of a marker cluster: rigid fits, label swaps, rigidity breaks and jumps.

Artefacts. A label swap or a marker that falls off breaks rigidity: that marker's residual from
the fitted pose jumps far above the trial's own level, which for skin markers is soft-tissue
artefact of a few mm. A sample is flagged when its residual exceeds ``residual_factor`` times
the lower quartile of the cluster's residuals and ``min_residual_mm``. The residuals are first
taken from the cluster's most typical frame (which a minority of broken frames cannot distort,
as they would a mean), then from the mean shape of the samples not flagged, until the flags settle.
A swap in a cluster of a few mm moves the residuals less than soft-tissue artefact of a body
segment does, so a scale-free test looks for swaps too (:func:`find_exchanges`): a frame is
swapped when its inter-marker distances depart from the cluster's typical ones far beyond the
trial's own noise and exchanging two labels brings them back to it (thresholds from a noise
model, :class:`ArtefactRules`); in a cluster of more than :data:`MAX_EXCHANGE_MARKERS`, whose
cost it cannot bear, it is not run, and the screen says so (:func:`exchanges_untested`). A
label swap is an event at a frame: the frames it flags are explained by exchanging two labels,
and :func:`find_swaps` reports the runs of frames carrying the pair one way round, so a message
names where the labelling changes and both sides can be kept. None of this depends on the
order of the frames. A step of one marker is flagged when it differs from both neighbouring
steps by more than ``jump_factor`` times the median such difference and ``min_jump_mm``
(:func:`find_jumps`), which needs the frames in time order: it is the only check of markers
outside a cluster, and in a cluster it counts only where no rigidity break or swapped frame
explains it. A swap that keeps the shape (a square's diagonal, an isosceles triangle's base)
shows only so: both markers jump where the labels change and back, and exchanging them between
those frames leaves no jump (:func:`_shape_keeping_swaps`), which makes every frame between a
swapped one.

:func:`screen` runs these checks on bare arrays, for :func:`jointbench.screen`;
:meth:`Segment.fit` runs the same on a recording. The fit functions of :mod:`jointbench.api`
need only what it finds, not the cluster's fit: :func:`find_artefacts` gives the same, and for
a complete cluster whose residuals a bound keeps below ``min_residual_mm``
(:func:`surely_rigid`, at most one pose fit) and in which the distance test finds no swap it
skips the iterated mean shape. Such a clean cluster costs one compiled call
(:func:`_clean_screen`): the typical frame, the rigidity bound, the largest step and the
distance test's verdict share one set of inter-marker distances, and two bounds skip the steps
of the distance test that they show cannot flag a frame.
"""

from __future__ import annotations

import dataclasses
import functools
import re
from collections.abc import Sequence
from dataclasses import dataclass
from itertools import combinations, pairwise

import numpy as np

from jointbench.numerics.compiled import kernel, kernel_array
from jointbench.numerics.magnitudes import first_beyond
from jointbench.numerics.poses import _horn_rotations, best_rotation
from jointbench.numerics.special import scipy_special

__all__ = [
    "MAX_EXCHANGE_MARKERS",
    "Artefact",
    "ArtefactRules",
    "Numbering",
    "Screening",
    "Swap",
    "check_magnitudes",
    "column_label",
    "exchanges_untested",
    "find_artefacts",
    "find_exchanges",
    "find_jumps",
    "find_rigidity_breaks",
    "find_swaps",
    "fit_poses",
    "flagged_frames",
    "markers_named",
    "mean_shape",
    "residuals",
    "screen",
    "summarise",
    "surely_rigid",
    "to_local",
    "typical_shape",
]

_MAX_ITERATIONS = 200
_TOL_MM = 1e-10

#: The most markers of a cluster whose label exchanges the screen tests (:func:`find_exchanges`).
#: The test tries every exchange of two labels on every pair of markers of every frame judged:
#: its cost grows as the fourth power of the marker count times the frames, and its table of
#: exchanges as the fourth power (measured, 120 frames: 8 markers take under a millisecond, 20
#: a few, 40 some tens, 120 from 10 to 20 s and 400 MB). A larger cluster (a whole-body marker set
#: passed as one segment, or a ``(markers, frames, 3)`` array passed transposed) is screened for
#: rigidity breaks and jumps only, which cost about the marker count times the frames, and the
#: screen says what it did not test (:func:`exchanges_untested`).
MAX_EXCHANGE_MARKERS = 20


#: A label :func:`column_label` makes: an expression that says itself it names a marker.
_COLUMN_LABEL = re.compile(r"\w+\[:, \d+\]")


def column_label(name: str, column: int) -> str:
    """The label in messages of column ``column`` of the marker array ``name``
    ``(n_frames, n, 3)``: ``name[:, column]``."""
    return f"{name}[:, {column}]"


def markers_named(labels: Sequence[str], listed: str) -> str:
    """``listed``, the ``labels`` in words, after "marker" or "markers" as they are one or
    more; labels of array columns (:func:`column_label`) already say they name markers, and
    stand alone ("markers[:, 0] and markers[:, 2]", not "markers markers[:, 0] and ...")."""
    if all(_COLUMN_LABEL.fullmatch(label) for label in labels):
        return listed
    return f"{'marker' if len(labels) == 1 else 'markers'} {listed}"


def exchanges_untested(n_markers: int) -> str:
    """Why the screen of a cluster of ``n_markers`` does not test label exchanges, in words;
    ``""`` when it does (at most :data:`MAX_EXCHANGE_MARKERS`, or too few markers for a
    shape)."""
    if n_markers <= MAX_EXCHANGE_MARKERS:
        return ""
    return (
        f"{n_markers} markers, more than the {MAX_EXCHANGE_MARKERS} whose label exchanges the "
        "artefact screen tests: whether two markers exchange labels in some frames was not "
        "tested (rigidity breaks and jumps were)"
    )


def fit_poses(shape: np.ndarray, markers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares pose of ``shape`` ``(n, 3)`` onto every frame of ``markers``
    ``(n_frames, n, 3)`` [mm], using the markers visible (finite) in each frame.

    Returns ``R`` ``(n_frames, 3, 3)`` and ``t`` ``(n_frames, 3)`` [mm]; NaN in frames with
    fewer than three visible markers.
    """
    shape, markers = kernel_array(shape), kernel_array(markers)
    n_frames = markers.shape[0]
    cross = np.empty((n_frames, 3, 3))
    centroids = np.empty((n_frames, 2, 3))
    bound = np.empty(n_frames)
    _pose_sums(shape, markers, cross, centroids, bound)
    rotation = best_rotation(cross, bound=bound)
    translation = np.empty((n_frames, 3))
    _translations(rotation, centroids, translation)
    return rotation, translation


@kernel
def _pose_sums(
    shape: np.ndarray,
    markers: np.ndarray,
    cross: np.ndarray,
    centroids: np.ndarray,
    bound: np.ndarray,
) -> None:
    """Per frame of ``markers`` ``(n_frames, n, 3)``, over its visible (finite) markers: the
    cross-covariance ``cross`` ``(n_frames, 3, 3)`` of the markers (rows) and ``shape``
    ``(n, 3)`` (columns); ``centroids`` ``(n_frames, 2, 3)`` of the markers and of their
    points of ``shape``, NaN where fewer than three are visible; and ``bound`` ``(n_frames,)``
    [mm^2], half the summed squared lengths of both centred point sets, which no rotation's
    ``trace(R' cross)`` exceeds. A compiled kernel (:mod:`jointbench.numerics.compiled`)."""
    n_markers = shape.shape[0]
    visible = np.empty(n_markers, dtype=np.bool_)
    for f in range(markers.shape[0]):
        # Sums in local variables, not in the arrays: the compiler must assume that a store
        # into an array may change any other, and would reload every operand after each.
        count = 0
        tx = ty = tz = sx = sy = sz = 0.0
        for m in range(n_markers):
            visible[m] = (
                np.isfinite(markers[f, m, 0])
                and np.isfinite(markers[f, m, 1])
                and np.isfinite(markers[f, m, 2])
            )
            if visible[m]:
                count += 1
                tx, ty, tz = tx + markers[f, m, 0], ty + markers[f, m, 1], tz + markers[f, m, 2]
                sx, sy, sz = sx + shape[m, 0], sy + shape[m, 1], sz + shape[m, 2]
        divisor = max(count, 1)
        tx, ty, tz = tx / divisor, ty / divisor, tz / divisor
        sx, sy, sz = sx / divisor, sy / divisor, sz / divisor
        hxx = hxy = hxz = hyx = hyy = hyz = hzx = hzy = hzz = total = 0.0
        for m in range(n_markers):
            if visible[m]:
                x, y, z = markers[f, m, 0] - tx, markers[f, m, 1] - ty, markers[f, m, 2] - tz
                a, b, c = shape[m, 0] - sx, shape[m, 1] - sy, shape[m, 2] - sz
                total += 0.5 * (x * x + a**2)
                total += 0.5 * (y * y + b**2)
                total += 0.5 * (z * z + c**2)
                hxx, hxy, hxz = hxx + x * a, hxy + x * b, hxz + x * c
                hyx, hyy, hyz = hyx + y * a, hyy + y * b, hyz + y * c
                hzx, hzy, hzz = hzx + z * a, hzy + z * b, hzz + z * c
        cross[f, 0, 0], cross[f, 0, 1], cross[f, 0, 2] = hxx, hxy, hxz
        cross[f, 1, 0], cross[f, 1, 1], cross[f, 1, 2] = hyx, hyy, hyz
        cross[f, 2, 0], cross[f, 2, 1], cross[f, 2, 2] = hzx, hzy, hzz
        bound[f] = total
        complete = count >= 3
        centroids[f, 0, 0] = tx if complete else np.nan
        centroids[f, 0, 1] = ty if complete else np.nan
        centroids[f, 0, 2] = tz if complete else np.nan
        centroids[f, 1, 0] = sx if complete else np.nan
        centroids[f, 1, 1] = sy if complete else np.nan
        centroids[f, 1, 2] = sz if complete else np.nan


@kernel
def _translations(rotation: np.ndarray, centroids: np.ndarray, translation: np.ndarray):
    """``translation`` ``(n_frames, 3)`` taking the shape's centroid ``centroids[:, 1]`` by
    ``rotation`` ``(n_frames, 3, 3)`` onto the markers' ``centroids[:, 0]``; ``rotation`` and
    ``translation`` NaN where the centroids are (too few markers). A compiled kernel."""
    for f in range(rotation.shape[0]):
        if not np.isfinite(centroids[f, 0, 0]):
            rotation[f] = np.nan
            translation[f] = np.nan
            continue
        for i in range(3):
            moved = 0.0
            for j in range(3):
                moved += rotation[f, i, j] * centroids[f, 1, j]
            translation[f, i] = centroids[f, 0, i] - moved


def to_local(rotation: np.ndarray, translation: np.ndarray, markers: np.ndarray) -> np.ndarray:
    """World markers ``(n_frames, n, 3)`` into the frame posed by ``(R, t)``: ``R' (x - t)``."""
    return np.einsum("fji,fmj->fmi", rotation, markers - translation[:, None, :])


def typical_shape(markers: np.ndarray, labels: tuple[str, ...], source: str) -> np.ndarray:
    """The cluster ``(n, 3)`` in its most typical complete frame: the one whose inter-marker
    distances are nearest their medians over the trial, which a minority of broken frames
    cannot pull."""
    seen = np.isfinite(markers[..., 0]).any(axis=0)
    if not seen.all():
        unseen = labels[int(np.argmin(seen))]
        raise ValueError(f"{source}: {markers_named([unseen], unseen)} is never visible")
    complete = _complete_frames(kernel_array(markers))
    if complete.size == 0:
        raise ValueError(
            f"{source}: {markers_named(labels, ', '.join(labels))} are never all visible in "
            "one frame; a segment needs one frame showing its whole cluster"
        )
    clusters = markers[complete]
    return clusters[_most_typical(kernel_array(clusters))].copy()


@kernel
def _most_typical(clusters: np.ndarray) -> int:
    """The index of the frame of ``clusters`` ``(n_frames, n, 3)`` [mm] whose largest
    inter-marker distance deviation from that distance's median over the frames is least (the
    first, on a tie). A compiled kernel (:mod:`jointbench.numerics.compiled`)."""
    return _typical_and_finite(clusters)[0]


@kernel
def _typical_and_finite(clusters: np.ndarray) -> tuple[int, bool]:
    """:func:`_most_typical` of ``clusters`` ``(n_frames, n >= 2, 3)`` [mm] and whether their
    distances are all finite (:func:`_finite_pair_distances`), each pair's distances made,
    their median taken and the frames' largest departures updated in turn: the numbers of
    :func:`_nearest` over :func:`_medians` of the distances kept, without their ``(n_pairs,
    n_frames)`` array, gigabytes for thousands of markers (a recording passed as
    ``(markers, frames, 3)``). A compiled kernel."""
    n_frames, n_markers = clusters.shape[0], clusters.shape[1]
    deviation = np.zeros(n_frames)
    lengths = np.empty(n_frames)
    row_copy = np.empty(n_frames)
    finite = True
    for a in range(n_markers):
        for b in range(a + 1, n_markers):
            _pair_distances_into(clusters, a, b, lengths)
            for f in range(n_frames):
                finite &= lengths[f] < np.inf
            row_copy[:] = lengths
            median = _median_in_place(row_copy)
            for f in range(n_frames):
                deviation[f] = max(deviation[f], abs(lengths[f] - median))
    return int(np.argmin(deviation)), finite


@kernel
def _medians(values: np.ndarray) -> np.ndarray:
    """The median of each row of ``values`` ``(n_rows, n)``. A compiled kernel."""
    medians = np.empty(values.shape[0])
    row_copy = np.empty(values.shape[1])
    for row in range(values.shape[0]):
        row_copy[:] = values[row]
        medians[row] = _median_in_place(row_copy)
    return medians


@kernel
def _median_in_place(values: np.ndarray) -> float:
    """The median of ``values`` ``(n,)``, NaN if empty, perhaps reordering them: the middle
    value, or ``(a + b) / 2`` of the middle two; ``np.median`` would first copy them. Values
    without NaN have one order, in which any selection finds the same numbers (equal ones:
    -0.0 and 0.0 are equal in it, so a zero median's sign depends on the selection, which the
    screen's distances and departures, never -0.0, do not meet):
    :func:`_select_sweeping` is the fastest at every count, measured on values new to each
    call, as a trial's are (the same values over and over let the branch predictor learn a
    quickselect's branches and hide their cost); from :data:`_BAND_MIN_VALUES` values up it
    first tries the band about the median that a sample brackets (:func:`_median_by_band`).
    NaN leave no order: values with one are taken as Numba's ``np.median`` takes them
    (:func:`_quickselect_median`), so that the median is the number it gives. A compiled
    kernel."""
    n = values.size
    if n == 0:
        return np.nan
    if n >= _BAND_MIN_VALUES:
        found, median = _median_by_band(values)
        if found:
            return median
    for value in values:
        if value != value:
            return _quickselect_median(values)
    upper = _select_sweeping(values, n >> 1)
    if n & 1:
        return upper
    # The middle value below is the greatest of those the selection left before the other.
    lower = values[0]
    for index in range(1, n >> 1):
        lower = max(lower, values[index])
    return (lower + upper) / 2


# From this many values up, a median is first looked for in the band a sample brackets
# (:func:`_median_by_band`): below it the sample's own selections cost what they save.
_BAND_MIN_VALUES = 2048


@kernel
def _median_by_band(values: np.ndarray) -> tuple[bool, float]:
    """The median of ``values`` ``(n >= 2,)`` as :func:`_median_in_place` gives it, found among
    the values of a band about it, which are copied out, leaving ``values`` as they are; and
    whether it was: ``(False, NaN)`` where a value is NaN or the band misses the middle.

    Every 8th value is a sample; the band holds the values between the sample's order
    statistics three of their standard deviations below and above the middle's rank, so that
    it nearly always holds the middle (one or two) values and a small share of the others.
    One pass counts the values below the band and copies the band's out: the middle values
    are the band's own order statistics (with ``c`` values below the band, the ``k``-th
    smallest of all is the ``(k - c)``-th of the band, when the band has more than ``k - c``
    values), which :func:`_select_sweeping` selects as from all of them. The same order
    statistics are the same numbers, so the median is too. A compiled kernel."""
    n = values.size
    k = n >> 1
    n_sample = (n + 7) // 8
    sample = np.empty(n_sample)
    for s in range(n_sample):
        sample[s] = values[8 * s]
        if sample[s] != sample[s]:
            return False, np.nan
    centre = (k * n_sample) // n
    half = int(3.0 * np.sqrt(n_sample)) + 2
    low_rank = max(centre - half, 0)
    high_rank = min(centre + half, n_sample - 1)
    low = _select_sweeping(sample, low_rank)
    # The selection left every value after low_rank at or above low.
    high = low
    if high_rank > low_rank:
        high = _select_sweeping(sample[low_rank + 1 :], high_rank - low_rank - 1)
    band = np.empty(n)
    below = within = above = 0
    for index in range(n):
        value = values[index]
        below += value < low
        above += value > high
        band[within] = value
        within += (value >= low) & (value <= high)
    # A NaN is none of the three.
    if below + within + above != n:
        return False, np.nan
    # Both middle values (one for an odd count) must be in the band.
    if not (below + 1 - (n & 1) <= k < below + within):
        return False, np.nan
    rank = k - below
    in_band = band[:within]
    upper = _select_sweeping(in_band, rank)
    if n & 1:
        return True, upper
    # The middle value below is the greatest of those the selection left before the other.
    lower = in_band[0]
    for index in range(1, rank):
        lower = max(lower, in_band[index])
    return True, (lower + upper) / 2


@kernel
def _select_sweeping(values: np.ndarray, k: int) -> float:
    """The ``k``-th smallest of ``values`` ``(n,)``, which hold no NaN, reordering them so that
    none before it is greater and none after it is less. Each round sweeps the range left
    about the median of its first, middle and last value, those less than it first, and goes
    on in the part that holds the ``k``-th: above the pivot, that part starts with the values
    equal to it, so a second sweep, for those, is needed only where none was less (then the
    range would not shrink), which distinct values, as measured ones are, seldom meet. A
    sweep adds each comparison to a count rather than branching on it, for in measured
    values it is true as often as not, and a mispredicted branch costs more than the sweep;
    it is written out twice, as a kernel call per sweep would cost more than a short sweep.
    A compiled kernel."""
    low, high = 0, values.size
    while high - low > 1:
        first, middle, last = values[low], values[(low + high) >> 1], values[high - 1]
        pivot = max(min(first, middle), min(max(first, middle), last))
        less = low
        for index in range(low, high):
            value = values[index]
            values[index] = values[less]
            values[less] = value
            less += value < pivot
        # The pivot is one of the values, so fewer than all are less.
        if k < less:
            high = less
            continue
        if less > low:
            low = less
            continue
        equal = less
        for index in range(less, high):
            value = values[index]
            values[index] = values[equal]
            values[equal] = value
            equal += value <= pivot
        if k < equal:
            return pivot
        low = equal
    return values[low]


@kernel
def _quickselect_median(values: np.ndarray) -> float:
    """The median of ``values`` ``(n >= 1,)``, reordering them, found step for step as Numba's
    ``np.median`` finds it (:func:`_select`), which decides even where NaN leave no order. A
    compiled kernel."""
    n = values.size
    k = (n >> 1) - 1
    if n & 1:
        return _select(values, k + 1, 0, n - 1)
    # The two middle values together: partition until one of them is in place, then select
    # the other on its side.
    low, high = 0, n - 1
    while True:
        i = _partition(values, low, high)
        if i < k:
            low = i + 1
        elif i > k + 1:
            high = i - 1
        elif i == k:
            _select(values, k + 1, i + 1, high)
            break
        else:
            _select(values, k, low, i - 1)
            break
    return (values[k] + values[k + 1]) / 2


@kernel
def _select(values: np.ndarray, k: int, low: int, high: int) -> float:
    """The ``k``-th smallest of ``values[low : high + 1]`` (Hoare's quickselect), which end
    partitioned about it. A compiled kernel."""
    i = _partition(values, low, high)
    while i != k:
        if i < k:
            low = i + 1
        else:
            high = i - 1
        i = _partition(values, low, high)
    return values[k]


@kernel
def _partition(values: np.ndarray, low: int, high: int) -> int:
    """Partition ``values[low : high + 1]`` about the median of its first, middle and last
    value, and return where that pivot ends: before it none greater, after it none less. A
    compiled kernel."""
    mid = (low + high) >> 1
    # The swaps of Numba's partition, step for step (its pivots do well on sorted and uniform
    # values).
    if values[mid] < values[low]:
        values[low], values[mid] = values[mid], values[low]
    if values[high] < values[mid]:
        values[high], values[mid] = values[mid], values[high]
    if values[mid] < values[low]:
        values[low], values[mid] = values[mid], values[low]
    pivot = values[mid]
    values[high], values[mid] = values[mid], values[high]
    i, j = low, high - 1
    while True:
        while i < high and values[i] < pivot:
            i += 1
        while j >= low and pivot < values[j]:
            j -= 1
        if i >= j:
            break
        values[i], values[j] = values[j], values[i]
        i += 1
        j -= 1
    values[i], values[high] = values[high], values[i]
    return i


@kernel
def _nearest(distances: np.ndarray, medians: np.ndarray) -> int:
    """The frame of ``distances`` ``(n_pairs, n_frames)`` [mm] whose largest departure from
    ``medians`` ``(n_pairs,)`` [mm] is least (the first, on a tie). A compiled kernel."""
    n_pairs, n_frames = distances.shape
    deviation = np.zeros(n_frames)
    for pair in range(n_pairs):
        for f in range(n_frames):
            deviation[f] = max(deviation[f], abs(distances[pair, f] - medians[pair]))
    return int(np.argmin(deviation))


@kernel
def _pair_distances(clusters: np.ndarray) -> np.ndarray:
    """The inter-marker distances ``(n_pairs, n_frames)`` [mm] of ``clusters``
    ``(n_frames, n, 3)`` [mm], the pairs ``(a, b)``, ``a < b``, in the order of
    ``itertools.combinations``. A compiled kernel."""
    return _finite_pair_distances(clusters)[0]


@kernel
def _finite_pair_distances(clusters: np.ndarray) -> tuple[np.ndarray, bool]:
    """The distances of :func:`_pair_distances` and whether they are all finite. Where they
    are, so is every coordinate of ``clusters`` ``(n_frames, n >= 2, 3)`` [mm]: a NaN or an
    infinite coordinate makes every distance of its marker NaN or infinite. Not the converse:
    finite coordinates of 1e155 mm or more overflow the squares. A compiled kernel."""
    n_frames, n_markers = clusters.shape[0], clusters.shape[1]
    distances = np.empty((n_markers * (n_markers - 1) // 2, n_frames))
    # One flag and-ed over all distances, not a branch per distance: the test costs a cycle.
    finite = True
    pair = 0
    for a in range(n_markers):
        for b in range(a + 1, n_markers):
            _pair_distances_into(clusters, a, b, distances[pair])
            for f in range(n_frames):
                finite &= distances[pair, f] < np.inf
            pair += 1
    return distances, finite


@kernel
def _pair_distances_into(clusters: np.ndarray, a: int, b: int, out: np.ndarray) -> None:
    """The distances ``(n_frames,)`` [mm] between markers ``a`` and ``b`` of ``clusters``
    ``(n_frames, n, 3)`` [mm], frame by frame, into ``out``. A compiled kernel."""
    for f in range(clusters.shape[0]):
        dx = clusters[f, a, 0] - clusters[f, b, 0]
        dy = clusters[f, a, 1] - clusters[f, b, 1]
        dz = clusters[f, a, 2] - clusters[f, b, 2]
        out[f] = np.sqrt(dx * dx + dy * dy + dz * dz)


def mean_shape(
    markers: np.ndarray, labels: tuple[str, ...], source: str, typical: np.ndarray | None = None
) -> np.ndarray:
    """Generalised Procrustes mean shape ``(n, 3)`` [mm] of a cluster (module docstring),
    in the frame of its most typical complete frame (the caller fixes the frame):
    ``typical`` ``(n, 3)`` [mm] where the caller has found it (:func:`typical_shape`), else
    found here."""
    shape = typical_shape(markers, labels, source) if typical is None else typical.copy()
    markers = kernel_array(markers)
    done = 0
    while done < _MAX_ITERATIONS:
        # Compiled iterations, a few microseconds each where a pose fit from Python costs
        # tens, until the shape settles or a frame's rotation needs the SVD
        # (:func:`fit_poses`), which that iteration then takes here.
        shape, steps, change, settled = _mean_shape_steps(
            shape, markers, _MAX_ITERATIONS - done, _TOL_MM
        )
        done += steps
        if settled:
            return shape
        if done < _MAX_ITERATIONS:
            rotation, translation = fit_poses(shape, markers)
            shape, change, settled = _mean_step(rotation, translation, markers, shape, _TOL_MM)
            done += 1
            if settled:
                return shape
    raise ValueError(
        f"{source}: the mean shape of {', '.join(labels)} did not converge in "
        f"{_MAX_ITERATIONS} iterations (last change {change:.3g} mm)"
    )


@kernel
def _mean_shape_steps(
    shape: np.ndarray, markers: np.ndarray, most: int, tolerance: float
) -> tuple[np.ndarray, int, float, bool]:
    """Up to ``most`` iterations of :func:`mean_shape` from ``shape`` ``(n, 3)`` [mm] on
    ``markers`` ``(n_frames, n, 3)`` [mm], each pose fit as :func:`fit_poses` fits it where
    Horn's method settles every frame it poses (:func:`jointbench.numerics.poses._horn_rotations`,
    :func:`_needs_svd`): the shape, the iterations done, the last change [mm] (NaN if none)
    and whether the shape settled (:func:`_mean_step`). They stop before an iteration in
    which a frame needs the SVD, for the caller to take. A compiled kernel."""
    n_frames = markers.shape[0]
    rotation = np.empty((n_frames, 3, 3))
    translation = np.empty((n_frames, 3))
    change = np.nan
    for step in range(most):
        if not _horn_poses(shape, markers, rotation, translation):
            return shape, step, change, False
        shape, change, settled = _mean_step(rotation, translation, markers, shape, tolerance)
        if settled:
            return shape, step + 1, change, True
    return shape, most, change, False


@kernel
def _horn_poses(
    shape: np.ndarray, markers: np.ndarray, rotation: np.ndarray, translation: np.ndarray
) -> bool:
    """:func:`fit_poses` of ``shape`` ``(n, 3)`` [mm] onto ``markers`` ``(n_frames, n, 3)``
    [mm], written into ``rotation`` ``(n_frames, 3, 3)`` and ``translation`` ``(n_frames,
    3)``, where Horn's method settles every frame it poses
    (:func:`jointbench.numerics.poses._horn_rotations`): then ``True``; ``False`` where a frame
    needs the SVD (:func:`_needs_svd`), leaving both unfinished. A compiled kernel."""
    n_frames = markers.shape[0]
    cross = np.empty((n_frames, 3, 3))
    centroids = np.empty((n_frames, 2, 3))
    bound = np.empty(n_frames)
    unsettled = np.empty(n_frames, dtype=np.bool_)
    _pose_sums(shape, markers, cross, centroids, bound)
    _horn_rotations(cross, bound, rotation, unsettled)
    if _needs_svd(unsettled, cross, centroids):
        return False
    _translations(rotation, centroids, translation)
    return True


@kernel
def _needs_svd(unsettled: np.ndarray, cross: np.ndarray, centroids: np.ndarray) -> bool:
    """Whether :func:`fit_poses` would take the SVD's rotation of a frame that Horn's method
    left ``unsettled`` ``(n_frames,)``: one it poses (finite ``centroids`` ``(n_frames, 2,
    3)``); of a frame of fewer than three markers :func:`_translations` keeps NaN, whatever
    the SVD of its ``cross`` ``(n_frames, 3, 3)`` gives, but one not finite would stop the
    SVD with an error, which the SVD is left to raise. A compiled kernel."""
    for f in range(unsettled.size):
        if unsettled[f]:
            if np.isfinite(centroids[f, 0, 0]) or not np.isfinite(cross[f]).all():
                return True
    return False


@kernel
def _mean_step(
    rotation: np.ndarray,
    translation: np.ndarray,
    markers: np.ndarray,
    shape: np.ndarray,
    tolerance: float,
) -> tuple[np.ndarray, float, bool]:
    """One iteration of :func:`mean_shape` from ``shape`` ``(n, 3)`` [mm], given the poses
    ``(rotation, translation)`` of ``markers`` ``(n_frames, n, 3)`` [mm] fitted to it: the
    mean of the markers in those poses (:func:`_mean_local`), its largest change from
    ``shape`` [mm] (NaN if any is) and whether that change is below ``tolerance`` times the
    largest coordinate, or 1 mm if that is less (a NaN coordinate counts as less). A compiled
    kernel."""
    new = np.empty_like(shape)
    _mean_local(rotation, translation, markers, new)
    change = _largest_magnitude(new, shape)
    size = _largest_magnitude(new, np.zeros_like(new))
    return new, change, change < tolerance * (size if size > 1.0 else 1.0)


@kernel
def _largest_magnitude(values: np.ndarray, less: np.ndarray) -> float:
    """``np.max(np.abs(values - less))`` of two arrays ``(n, 3)``: NaN if any difference is.
    A compiled kernel."""
    largest = 0.0
    for m in range(values.shape[0]):
        for i in range(3):
            difference = abs(values[m, i] - less[m, i])
            if difference != difference:
                return np.nan
            largest = max(largest, difference)
    return largest


@kernel
def _mean_local(
    rotation: np.ndarray, translation: np.ndarray, markers: np.ndarray, mean: np.ndarray
) -> None:
    """``mean`` ``(n, 3)`` [mm]: each marker of ``markers`` ``(n_frames, n, 3)`` taken into
    the local frame ``R' (x - t)`` of every posed frame (finite ``rotation``) and averaged over
    the frames where it is visible; NaN for a marker never seen. A compiled kernel."""
    n_markers = markers.shape[1]
    for m in range(n_markers):
        total = np.zeros(3)
        count = 0
        for f in range(markers.shape[0]):
            x = markers[f, m]
            if not (np.isfinite(rotation[f, 0, 0]) and np.isfinite(x[0] + x[1] + x[2])):
                continue
            count += 1
            for i in range(3):
                local = 0.0
                for j in range(3):
                    local += rotation[f, j, i] * (x[j] - translation[f, j])
                total[i] += local
        for i in range(3):
            mean[m, i] = total[i] / count if count else np.nan


@dataclass(frozen=True)
class Numbering:
    """How messages name the rows of a marker array: row ``i`` is frame ``first_frame + i``
    (the file's numbering), at ``number / rate_hz`` seconds when the rate is known."""

    first_frame: int = 0
    rate_hz: float | None = None

    def number(self, row: int) -> int:
        return self.first_frame + int(row)

    def name(self, row: int) -> str:
        """``"frame 731 (7.31 s)"``."""
        frame = self.number(row)
        if self.rate_hz is None:
            return f"frame {frame}"
        return f"frame {frame} ({frame / self.rate_hz:.2f} s)"


def check_magnitudes(
    markers: np.ndarray, labels: Sequence[str], source: str, numbering: Numbering = Numbering()
) -> None:
    """``ValueError`` naming ``source``, the label and the frame (by ``numbering``) of the
    first coordinate of ``markers`` ``(n_frames, len(labels), 3)`` [mm] beyond
    :func:`~jointbench.numerics.magnitudes.largest_coordinate`: the screen's sums, scale-free
    as they are, overflow on it (gaps, NaN, pass)."""
    found = first_beyond(markers)
    if found is None:
        return
    frame, marker, value, bound, count = found
    raise ValueError(
        f"{source}: marker {labels[marker]} has a coordinate of {value:.3g} mm at "
        f"{numbering.name(frame)} ({count} samples in all), beyond the {bound:.3g} mm whose "
        "squares float64 can sum over the cluster's samples: a corrupt sample or a wrong "
        "unit; leave those frames out"
    )


@dataclass(frozen=True)
class ArtefactRules:
    """When a sample or a step is far above the trial's own level (module docstring).

    The rigidity and jump levels are set so that soft-tissue artefact of body segments (a few
    mm, smooth) is not flagged, which leaves a swap in a cluster of a few mm unseen. The swap
    test (:func:`find_exchanges`) is scale-free and specific instead. Its noise model: each
    inter-marker distance of a frame departs from the cluster's typical one by noise of one
    standard deviation ``s`` for every pair, ``s`` the trial's own (1.4826 times the median
    absolute departure over all frames and pairs, the frames first relabelled to one
    labelling, so that a swap cannot lift it however many frames it holds), so that a frame's
    misfit ``chi2`` (its squared departures summed over the ``P = n (n - 1) / 2`` pairs, over
    ``s^2``) follows about a chi-square law with ``P`` degrees of freedom. A frame is swapped
    when

    * its ``chi2`` exceeds the level the law exceeds with probability ``swap_far_probability``:
      1e-12, beyond any trial's length, with room for tails heavier than Gaussian noise's, as
      soft-tissue artefact's are (59 for 3 markers, 116 for 8); and
    * exchanging two labels brings it within the level exceeded with probability
      ``swap_near_probability``: 1e-6, so that a swapped frame is missed about once in a
      million (31 for 3 markers, 79 for 8).

    Only an exchange that moves the typical distances by ``sqrt(far) + sqrt(near)`` times ``s``
    or more is tried (13.2 for 3 markers, 19.7 for 8): then every frame it holds clears the
    far level unless its noise exceeds the near one, so a swap is found as whole runs of
    frames, not in fragments. A smaller exchange, down to the base of an isosceles triangle
    which keeps the shape, is one that deformation or noise can mimic, and is left to the jump
    check. Smooth deformation rarely departs far from the trial's own level, and where it does,
    no such exchange brings it back.

    The noise level is taken only from ``swap_min_frames`` complete frames or more (20): from
    a handful, the median of each distance is one of the few frames itself and the level comes
    out too low, so that noisy frames of a clean trial pass the far level. A shorter trial is
    left to the rigidity and jump checks.
    """

    residual_factor: float = 15.0
    min_residual_mm: float = 5.0
    jump_factor: float = 20.0
    min_jump_mm: float = 20.0
    swap_far_probability: float = 1e-12
    swap_near_probability: float = 1e-6
    swap_min_frames: int = 20


_RULES = ArtefactRules()  # the default, made once: a clean trial's screen takes microseconds


def checked_rules(rules: object) -> ArtefactRules:
    """``rules``, or the default for ``None``; ``ValueError`` for anything but an
    :class:`ArtefactRules` (a dict of thresholds would otherwise be taken for the default when
    empty, and fail deep inside when not)."""
    if rules is None:
        return _RULES
    if not isinstance(rules, ArtefactRules):
        raise ValueError(
            f"rules must be an ArtefactRules (jointbench.io.ArtefactRules(min_jump_mm=...)) or "
            f"None for the default, got {rules!r}"
        )
    return rules


@dataclass(frozen=True)
class Artefact:
    """One flagged sample: ``kind`` ``"jump"``, ``"rigidity"`` or ``"swap"``, ``size_mm`` the
    step, the residual or (a swap) the frame's inter-marker distance misfit, ``level_mm`` the
    threshold it crossed; for a swap, ``partner`` the marker whose label it carries."""

    kind: str
    label: str
    frame: int
    size_mm: float
    level_mm: float
    partner: str = ""

    def describe(self, frames: Numbering) -> str:
        """One line, naming the frame as ``frames`` does."""
        if self.kind == "swap":
            pair = (self.label, self.partner)
            return (
                f"{markers_named(pair, ' and '.join(pair))} exchange labels at "
                f"{frames.name(self.frame)} (the cluster's inter-marker distances depart "
                f"{self.size_mm:.1f} mm from their typical values, threshold "
                f"{self.level_mm:.1f} mm, and fit them with the two labels exchanged)"
            )
        what = "jumps" if self.kind == "jump" else "leaves its cluster's rigid shape by"
        return (
            f"{markers_named([self.label], self.label)} {what} {self.size_mm:.1f} mm at "
            f"{frames.name(self.frame)} (threshold {self.level_mm:.1f} mm; a label swap or a "
            "marker falling off?)"
        )

    def rows(self) -> tuple[int, ...]:
        """The frames it spoils: a rigidity break its own; a jump the two frames of its step,
        so that the same step gives the same frames whichever way the frames run."""
        return (self.frame - 1, self.frame) if self.kind == "jump" else (self.frame,)


@dataclass(frozen=True)
class Swap:
    """Markers ``labels`` carried the other way round, relative to the rest of the trial, in
    rows ``start`` to ``stop - 1``: the labelling changes at ``start`` (unless 0) and back at
    ``stop`` (unless the end of the trial, ``n_frames``). ``alternatives``: other pairs that
    the cluster's symmetry fits alike and the frames next to the swap do not rule out
    (:func:`find_swaps`), so that ``labels`` is one of them, not the one; ``()`` where the data
    tell the pair."""

    labels: tuple[str, str]
    start: int
    stop: int
    n_frames: int
    alternatives: tuple[tuple[str, str], ...] = ()

    def sides(self) -> list[tuple[int, int]]:
        """Row ranges ``[start, stop)`` each labelled one consistent way, in time order."""
        bounds = sorted({0, self.start, self.stop, self.n_frames})
        return list(pairwise(bounds))

    def changes(self) -> list[int]:
        """The rows at which the labelling changes: ``start`` and ``stop``, where within the
        trial."""
        return [row for row in (self.start, self.stop) if 0 < row < self.n_frames]

    def named(self) -> list[str]:
        """Every label the swap may name, in its message's order: its pair's, then each of
        its ``alternatives``'."""
        return [label for pair in (self.labels, *self.alternatives) for label in pair]

    def steps(self) -> set[tuple[str, int]]:
        """The samples ``(label, row)`` that step where the labelling changes: each marker the
        swap may name (:meth:`named`) at each of :meth:`changes`."""
        return {(label, row) for label in self.named() for row in self.changes()}

    def describe(self, frames: Numbering) -> str:
        """One line naming the frames where the labels change and both sides, as ``frames``
        numbers them."""
        first, second = self.labels
        sides = ", ".join(f"{frames.number(a)} to {frames.number(b - 1)}" for a, b in self.sides())
        which = f"{first} and {second}"
        if self.alternatives:
            which += "".join(f", or {a} and {b}" for a, b in self.alternatives)
            pairs = "either pair" if len(self.alternatives) == 1 else "each of these pairs"
            which += (
                f" (the cluster's symmetry fits {pairs} alike, and the frames next to the swap "
                "do not tell which),"
            )
        at = " and back at ".join(frames.name(row) for row in self.changes())
        return (
            f"{markers_named(self.named(), which)} exchange labels at {at}; frames {sides} are "
            "each labelled one consistent way and the data cannot tell which is right"
        )


def flagged_frames(artefacts: Sequence[Artefact], n_frames: int) -> np.ndarray:
    """Which of ``n_frames`` rows ``(n_frames,)`` bool the ``artefacts`` spoil
    (:meth:`Artefact.rows`): the frames that excluding them leaves out."""
    flagged = np.zeros(n_frames, dtype=bool)
    for artefact in artefacts:
        flagged[[row for row in artefact.rows() if row >= 0]] = True
    return flagged


def summarise(artefacts: list[Artefact], swaps: list[Swap], frames: Numbering) -> str:
    """The swaps in full, else the first flagged frame's largest artefact; then how many
    flagged samples, over which frames and markers."""
    # One corrupt sample pulls its frame's pose fit, so the frame's other markers may cross
    # the level too, by less: the largest departure names the marker to look at.
    first = min(artefacts, key=lambda a: (a.frame, -a.size_mm))
    lines = [swap.describe(frames) for swap in swaps] or [first.describe(frames)]
    text = "; ".join(lines)
    if len(artefacts) > 1:
        rows = [a.frame for a in artefacts]
        markers = sorted({a.label for a in artefacts})
        text += (
            f"; {len(artefacts)} flagged samples in all, frames {frames.number(min(rows))} to "
            f"{frames.number(max(rows))}, {markers_named(markers, ', '.join(markers))}"
        )
    return text


def find_jumps(
    markers: np.ndarray, labels: tuple[str, ...], rules: ArtefactRules
) -> list[Artefact]:
    """Steps of one marker that differ from both neighbouring steps by far more than usual.

    A fast but smooth movement changes its step little from frame to frame; a label swap or a
    marker knocked off adds a step of its own. The size of the step at frame ``k`` is
    ``min(|s_k - s_(k-1)|, |s_k - s_(k+1)|)`` with ``s_k = x_k - x_(k-1)``.
    """
    n_frames, n_markers = markers.shape[:2]
    if n_frames < 4:
        return []
    size = np.empty((n_frames - 3, n_markers))
    # The level is at least min_jump_mm, so no step below it needs the median.
    if not _jump_sizes(kernel_array(markers), size) > rules.min_jump_mm:
        return []
    level = _level_of_steps(size, rules)
    step, marker = np.nonzero(size > level)
    return [
        Artefact("jump", labels[m], int(k) + 2, float(size[k, m]), level)
        for k, m in zip(step, marker, strict=True)
    ]


def _level_of_steps(size: np.ndarray, rules: ArtefactRules) -> float:
    """The level [mm] above which :func:`find_jumps` flags a step of ``size``
    ``(n_frames - 3, n)`` [mm]: ``jump_factor`` times their median, at least ``min_jump_mm``."""
    return max(rules.min_jump_mm, rules.jump_factor * _finite_median(size))


def _jump_level(markers: np.ndarray, rules: ArtefactRules) -> float:
    """:func:`_level_of_steps` of the steps of ``markers`` ``(n_frames, n, 3)`` [mm]
    (``min_jump_mm`` for fewer than four frames, which have none)."""
    if len(markers) < 4:
        return rules.min_jump_mm
    size = np.empty((len(markers) - 3, markers.shape[1]))
    _jump_sizes(kernel_array(markers), size)
    return _level_of_steps(size, rules)


@kernel
def _jump_sizes(markers: np.ndarray, size: np.ndarray) -> float:
    """Fill ``size`` ``(n_frames - 3, n)`` [mm] with the step sizes of :func:`find_jumps` of
    ``markers`` ``(n_frames, n, 3)`` (NaN where a gap leaves neither neighbour difference) and
    return the largest (-inf if all are NaN). A compiled kernel
    (:mod:`jointbench.numerics.compiled`)."""
    largest = -np.inf
    for m in range(size.shape[1] if size.shape[0] else 0):
        # Each change of step is the one after a frame and the one before the next.
        back = _step_change_sq(markers, 2, m)
        for k in range(size.shape[0]):
            ahead = _step_change_sq(markers, k + 3, m)
            size[k, m] = np.sqrt(_lesser(back, ahead))
            if size[k, m] > largest:  # never for NaN
                largest = size[k, m]
            back = ahead
    return largest


@kernel
def _step_change_sq(markers: np.ndarray, k: int, m: int) -> float:
    """``|s_k - s_(k-1)|^2`` [mm^2] of marker ``m`` of ``markers`` ``(n_frames, n, 3)`` at frame
    ``2 <= k < n_frames``, ``s_k = x_k - x_(k-1)``: the squared change of :func:`find_jumps`
    from the step before frame ``k - 1`` to the step after it. A compiled kernel."""
    change = 0.0
    for i in range(3):
        step = markers[k, m, i] - markers[k - 1, m, i]
        change += (step - (markers[k - 1, m, i] - markers[k - 2, m, i])) ** 2
    return change


@kernel
def _lesser(back: float, ahead: float) -> float:
    """The lesser of two squared changes, or the one that is not NaN, as ``np.fmin``; squares
    order as their roots do. A compiled kernel."""
    return ahead if np.isnan(back) or ahead < back else back


@kernel
def _finite_median(values: np.ndarray) -> float:
    """The median of the ``values`` (any shape) that are not NaN, NaN if none. A compiled
    kernel."""
    return np.nanmedian(values)


def find_rigidity_breaks(
    residuals: np.ndarray, labels: tuple[str, ...], rules: ArtefactRules
) -> list[Artefact]:
    """Samples whose rigid-fit residual ``(n_frames, n)`` [mm] is far above the trial's level
    (its lower quartile), so that up to three quarters of the samples may be broken."""
    # The level is at least min_residual_mm, so no residual below it needs the quartile.
    if not np.fmax.reduce(residuals, axis=None) > rules.min_residual_mm:
        return []
    level = _rigidity_level(residuals, rules)
    frame, marker = np.nonzero(residuals > level)
    return [
        Artefact("rigidity", labels[m], int(f), float(residuals[f, m]), level)
        for f, m in zip(frame, marker, strict=True)
    ]


def _rigidity_level(residuals: np.ndarray, rules: ArtefactRules) -> float:
    """The level [mm] above which :func:`find_rigidity_breaks` flags a residual of
    ``residuals`` ``(n_frames, n)`` [mm]: ``residual_factor`` times their lower quartile, at
    least ``min_residual_mm``."""
    # The lower quartile, not the median: a swap held by half the frames displaces more than
    # half the samples (the pose fit spreads it), which would lift a median above them.
    typical = _lower_quartile(kernel_array(residuals))
    return max(rules.min_residual_mm, rules.residual_factor * typical)


@kernel
def _lower_quartile(values: np.ndarray) -> float:
    """The lower quartile of the ``values`` (any shape) that are not NaN, NaN if none: NumPy's
    ``nanpercentile(values, 25)`` (linear interpolation) to the last bit. A compiled kernel."""
    flat = values.ravel()
    known = flat[~np.isnan(flat)]
    if known.size == 0:
        return np.nan
    index = (known.size - 1) * 0.25
    below = int(np.floor(index))
    # Selection, not a sort: the order statistic at ``below`` and the least value after it.
    known = np.partition(known, below)
    low = known[below]
    high = np.min(known[below + 1 :]) if below + 1 < known.size else low
    gamma = index - below
    # NumPy's interpolation, which works from the nearer end.
    if gamma >= 0.5:
        return high - (high - low) * (1.0 - gamma)
    return low + (high - low) * gamma


def find_exchanges(
    markers: np.ndarray, labels: tuple[str, ...], rules: ArtefactRules
) -> list[Artefact]:
    """Frames whose shape is far from the cluster's and is the cluster's with two labels
    exchanged: two ``"swap"`` artefacts for each, one per marker, naming the other as
    ``partner``.

    ``markers`` ``(n_frames, n, 3)`` [mm]; only the frames showing every marker are judged (a
    frame missing one is left to the rigidity check), and only where there are at least
    ``rules.swap_min_frames`` of them; fewer than three markers have no shape. The test
    compares each frame's inter-marker distances, which fix its shape up to congruence without
    a pose fit, with the cluster's typical ones in units of the trial's own noise, as labelled
    and with each pair of labels exchanged (:class:`ArtefactRules`, :func:`_exchange_test`);
    it does not depend on the cluster's size or on the frames' order.
    """
    if len(labels) < 3:
        return []
    far, near = _exchange_levels(len(labels), rules)
    exchange, misfit, level = _exchange_test(
        kernel_array(markers), far, near, rules.swap_min_frames
    )
    swapped = np.flatnonzero(exchange >= 0)
    if swapped.size == 0:
        return []
    pairs = list(combinations(range(len(labels)), 2))
    found = []
    for frame in swapped:
        frame, size = int(frame), float(misfit[frame])
        i, j = pairs[exchange[frame]]
        found.append(Artefact("swap", labels[i], frame, size, level, labels[j]))
        found.append(Artefact("swap", labels[j], frame, size, level, labels[i]))
    return found


# Bounded: a sweep over the rules (a sensitivity study) makes a new set per step.
@functools.lru_cache(maxsize=256)
def _exchange_levels(n_markers: int, rules: ArtefactRules) -> tuple[float, float]:
    """The levels of a frame's distance misfit ``chi2`` (:class:`ArtefactRules`) for a cluster
    of ``n_markers``: above the first it is far from the trial's noise, within the second an
    exchange of labels explains it; chi-square quantiles with one degree of freedom per pair."""
    n_pairs = n_markers * (n_markers - 1) // 2
    return (
        float(scipy_special().chdtri(n_pairs, rules.swap_far_probability)),
        float(scipy_special().chdtri(n_pairs, rules.swap_near_probability)),
    )


@kernel
def _exchange_test(
    markers: np.ndarray, far: float, near: float, min_frames: int
) -> tuple[np.ndarray, np.ndarray, float]:
    """The distance test of :func:`find_exchanges` on the frames of ``markers``
    ``(n_frames, n >= 3, 3)`` [mm] that show every marker, where there are ``min_frames`` of
    them or more, with the levels ``far`` and ``near`` of ``chi2`` (:func:`_exchange_levels`).

    Returns per frame the exchange that explains it (the index of the pair of labels, in the
    order of ``itertools.combinations``; -1 for none, and in a frame not judged), its distance
    misfit [mm] (the norm of its distances' departures from the typical ones; NaN in a frame
    not judged) and the misfit's level [mm] (``sqrt(far)`` times the noise; NaN if no frame is
    judged). The typical distances and the noise come from :func:`_aligned_typical`,
    relabelling the frames only by the exchanges that the anchor frame and the labelling-free
    noise of :func:`_anchor_frame` show distinct (:func:`_distinct_exchanges`): relabelling by
    an exchange that noise can mimic would blur them. A compiled kernel.
    """
    n_frames = markers.shape[0]
    exchange = np.full(n_frames, -1)
    misfit = np.full(n_frames, np.nan)
    complete = _complete_frames(markers)
    if complete.size < max(min_frames, 1):
        return exchange, misfit, np.nan
    distances = _pair_distances(markers if complete.size == n_frames else markers[complete])
    found, misfit_sq, noise = _judge_frames(
        distances, _medians(distances), markers.shape[1], far, near, False
    )
    for k in range(complete.size):
        exchange[complete[k]] = found[k]
        misfit[complete[k]] = np.sqrt(misfit_sq[k])
    return exchange, misfit, noise * np.sqrt(far)


@kernel
def _judge_frames(
    distances: np.ndarray,
    medians: np.ndarray,
    n_markers: int,
    far: float,
    near: float,
    verdict: bool,
) -> tuple[np.ndarray, np.ndarray, float]:
    """:func:`_exchange_test` on the inter-marker distances ``(n_pairs, n_frames)`` [mm]
    (:func:`_pair_distances`) of the frames it judges, of a cluster of ``n_markers``, and
    their rows' ``medians`` ``(n_pairs,)`` [mm] (:func:`_medians`): per frame the exchange
    (-1 for none) and the squared distance misfit [mm^2], and the noise of one distance [mm].
    With ``verdict``, only whether any frame has an exchange counts: where the bound at the
    anchor frame shows none (:func:`_unexchanged_from_anchor`), or no frame is relabelled and
    :func:`_within_far` shows every frame within the far level, no frame has one, and the
    misfits and the noise are left NaN. A compiled kernel."""
    largest_sq = _largest_departure_sq(distances, medians) if verdict else np.nan
    return _judged(
        distances, medians, _relabelled_pairs(n_markers), -1, largest_sq, far, near, verdict
    )


@kernel
def _judged(
    distances: np.ndarray,
    medians: np.ndarray,
    moved: np.ndarray,
    nearest: int,
    largest_sq: float,
    far: float,
    near: float,
    verdict: bool,
) -> tuple[np.ndarray, np.ndarray, float]:
    """:func:`_judge_frames`, given what its caller may have found already: ``moved``
    (:func:`_relabelled_pairs` of the cluster), ``nearest`` (:func:`_nearest` of
    ``distances`` and ``medians``; -1 if not found) and, with ``verdict``,
    ``largest_sq`` (:func:`_largest_departure_sq` of them). A compiled kernel."""
    n_frames = distances.shape[1]
    # One buffer of the distances' shape holds in turn their departures, the anchor's sorted
    # distances and the aligned ones, which each median selection reorders in place.
    work = np.empty_like(distances)
    ranked = _ranked_alike(distances)
    if ranked:
        # Sorting each frame's distances then moves whole rows, which changes no row's median,
        # no frame's largest departure and not the set of departures: the anchor and its noise
        # are the labelled distances' own.
        anchor = nearest if nearest >= 0 else _nearest(distances, medians)
        typical = distances[:, anchor].copy()
        if verdict and _unexchanged_from_anchor(
            distances, moved, typical, medians, largest_sq, far, near
        ):
            return np.full(n_frames, -1), np.full(n_frames, np.nan), np.nan
        spread = _median_departure(distances, medians, work)
        noise = spread
    else:
        spread = np.nan
        anchor, noise = _anchor_frame(distances, work)
        typical = distances[:, anchor].copy()
    allowed = _distinct_exchanges(moved, typical, noise, far, near)
    allowed[0] = True
    candidates = _candidates(distances, moved, typical, allowed)
    best = _nearest_exchanges(distances, moved, typical, allowed, candidates)
    if best.any():
        reference, noise = _aligned_typical(distances, moved, candidates, best, work)
    elif verdict and _within_far_of(distances, medians, far, largest_sq):
        return np.full(n_frames, -1), np.full(n_frames, np.nan), np.nan
    else:
        # No frame is relabelled: the aligned distances are the labelled ones.
        if not ranked:
            spread = _median_departure(distances, medians, work)
        # A floor far below any real noise keeps exact data from dividing by zero.
        reference, noise = medians, max(spread, 1e-9 * medians.max())
    distinct = _distinct_exchanges(moved, reference, noise, far, near)
    found, misfit_sq = _exchanges(
        distances, moved, reference, distinct, far * noise**2, near * noise**2
    )
    return found, misfit_sq, noise


@kernel
def _within_far(distances: np.ndarray, medians: np.ndarray, far: float) -> bool:
    """Whether a count shows that no frame of ``distances`` ``(n_pairs, n_frames)`` [mm]
    departs from their rows' ``medians`` ``m`` ``(n_pairs,)`` [mm] beyond the far level
    (``chi2 > far``) of the noise that :func:`_judge_frames` takes from them where no frame
    is relabelled, without selecting that noise's median; ``False`` means not shown. A
    compiled kernel.

    That noise is at least ``1.4826 q``, ``q`` the median of the ``N`` departures
    ``|d_pf - m_p|``, and a frame is beyond the level when ``|d_f - m|^2 > far noise^2``.
    With ``L = sqrt(max |d_f - m|^2 / far) / 1.4826`` (and margins): when at most
    ``(N - 1) // 2`` departures are below ``L``, the lower of the middle ones, and so ``q``,
    is at least ``L``, and ``far noise^2 >= max |d_f - m|^2``. The squared departures are
    summed as :func:`_misfits_sq` sums them, so that the largest is the one it finds; the
    margins (relative 1e-6, absolute 1e-150 mm) exceed the rounding of the products, and a
    NaN or an infinity fails the count."""
    return _within_far_of(distances, medians, far, _largest_departure_sq(distances, medians))


@kernel
def _within_far_of(
    distances: np.ndarray, medians: np.ndarray, far: float, largest_sq: float
) -> bool:
    """:func:`_within_far`, given ``largest_sq``, :func:`_largest_departure_sq` of
    ``distances`` and ``medians``. A compiled kernel."""
    level = np.sqrt(largest_sq / far) / 1.482602218505602
    level = level * (1.0 + 1e-6) + 1e-150
    if not level < np.inf:
        return False
    below = 0
    for p in range(distances.shape[0]):
        for f in range(distances.shape[1]):
            below += abs(distances[p, f] - medians[p]) < level
    return below <= (distances.size - 1) // 2


@kernel
def _largest_departure_sq(distances: np.ndarray, medians: np.ndarray) -> float:
    """The largest squared departure ``|d_f - m|^2`` [mm^2] of a frame of ``distances``
    ``(n_pairs, n_frames)`` [mm] from ``medians`` ``(n_pairs,)`` [mm], summed over the pairs
    in :func:`_misfits_sq`'s order; NaN if any is. A compiled kernel."""
    largest = 0.0
    for f in range(distances.shape[1]):
        total = 0.0
        for p in range(distances.shape[0]):
            total += (distances[p, f] - medians[p]) ** 2
        if np.isnan(total):
            return np.nan
        largest = max(largest, total)
    return largest


@kernel
def _complete_frames(markers: np.ndarray) -> np.ndarray:
    """The indices of the frames of ``markers`` ``(n_frames, n, 3)`` [mm] whose coordinates
    are all finite. A compiled kernel."""
    complete = np.empty(markers.shape[0], dtype=np.int64)
    count = 0
    for f in range(markers.shape[0]):
        # x - x is 0 for a finite x and NaN for any other, so the sum is 0 only in a complete
        # frame, without a branch per coordinate.
        total = 0.0
        for m in range(markers.shape[1]):
            for i in range(3):
                total += markers[f, m, i] - markers[f, m, i]
        if total == 0.0:
            complete[count] = f
            count += 1
    return complete[:count]


@kernel
def _anchor_frame(distances: np.ndarray, ranked: np.ndarray) -> tuple[int, float]:
    """A frame of ``distances`` ``(n_pairs, n_frames)`` [mm] to relabel the others by, and the
    noise of one distance [mm], both without regard to labels: each frame's distances sorted
    (which no exchange of labels changes), the frame whose largest departure from the sorted
    distances' medians is least, and 1.4826 times the median absolute departure. However many
    frames a swap holds, neither moves. ``ranked``, of the shape of ``distances``, is
    overwritten. A compiled kernel."""
    n_pairs, n_frames = distances.shape
    ranked[:] = distances
    for f in range(n_frames):
        # Insertion sort: a frame has few pairs, and this allocates nothing.
        for p in range(1, n_pairs):
            value, q = ranked[p, f], p
            while q > 0 and ranked[q - 1, f] > value:
                ranked[q, f] = ranked[q - 1, f]
                q -= 1
            ranked[q, f] = value
    medians = _medians(ranked)
    return _nearest(ranked, medians), _median_departure(ranked, medians, ranked)


@kernel
def _ranked_alike(distances: np.ndarray) -> bool:
    """Whether the ``distances`` ``(n_pairs, n_frames)`` [mm] are all finite and rank alike in
    every frame: in the order that sorts the first frame's, every frame's are sorted (ties in
    either order). A compiled kernel."""
    n_pairs, n_frames = distances.shape
    order = np.argsort(distances[:, 0].copy())
    for f in range(n_frames):
        for r in range(n_pairs):
            value = distances[order[r], f]
            if not np.isfinite(value) or (r > 0 and distances[order[r - 1], f] > value):
                return False
    return True


@kernel
def _median_departure(values: np.ndarray, medians: np.ndarray, departures: np.ndarray) -> float:
    """1.4826 times the median absolute departure [mm] of ``values`` ``(n_rows, n)`` [mm] from
    their rows' ``medians`` ``(n_rows,)``, over all rows: Gaussian noise's standard deviation,
    whose median absolute departure is 0.6745 of it. ``departures``, of the shape of
    ``values`` (or ``values`` itself), is overwritten. A compiled kernel."""
    for p in range(values.shape[0]):
        for f in range(values.shape[1]):
            departures[p, f] = abs(values[p, f] - medians[p])
    return 1.482602218505602 * _median_in_place(departures.reshape(departures.size))


@kernel
def _candidates(
    distances: np.ndarray, moved: np.ndarray, typical: np.ndarray, allowed: np.ndarray
) -> np.ndarray:
    """The frames of ``distances`` ``(n_pairs, n_frames)`` [mm] that an exchange (a row of
    ``moved``, :func:`_relabelled_pairs`, that ``allowed`` allows) may match to the
    ``typical`` frame's distances ``(n_pairs,)`` better than the labels as they are: those
    departing from it by half the exchange's own size or more (triangle inequality). Without
    an allowed exchange, none but a frame whose departure overflows. A compiled kernel."""
    least = np.inf
    sizes_sq = _exchange_sizes_sq(moved, typical)
    for e in range(1, moved.shape[0]):
        if allowed[e]:
            least = min(least, sizes_sq[e])
    as_labelled = np.empty(distances.shape[1])
    _misfits_sq(distances, np.arange(distances.shape[1]), moved, 0, typical, as_labelled)
    return np.flatnonzero(4.0 * as_labelled >= least)


@kernel
def _nearest_exchanges(
    distances: np.ndarray,
    moved: np.ndarray,
    typical: np.ndarray,
    allowed: np.ndarray,
    candidates: np.ndarray,
) -> np.ndarray:
    """Per frame of the ``candidates`` (:func:`_candidates`) of ``distances``
    ``(n_pairs, n_frames)`` [mm], the exchange (a row of ``moved``,
    :func:`_relabelled_pairs`, that ``allowed`` allows, 0 for none) that matches the
    ``typical`` frame's distances ``(n_pairs,)`` best, the first on a tie. A compiled
    kernel."""
    best = np.zeros(candidates.size, dtype=np.int64)
    best_misfit = np.full(candidates.size, np.inf)
    misfit = np.empty(candidates.size)
    for e in range(moved.shape[0]):
        if allowed[e]:
            _misfits_sq(distances, candidates, moved, e, typical, misfit)
            for k in range(candidates.size):
                if misfit[k] < best_misfit[k]:
                    best[k], best_misfit[k] = e, misfit[k]
    return best


@kernel
def _aligned_typical(
    distances: np.ndarray,
    moved: np.ndarray,
    candidates: np.ndarray,
    best: np.ndarray,
    aligned: np.ndarray,
) -> tuple[np.ndarray, float]:
    """The typical inter-marker distances ``(n_pairs,)`` [mm] of ``distances``
    ``(n_pairs, n_frames)`` and the noise of one distance [mm]: the medians over the frames,
    each of the ``candidates`` first relabelled by its ``best`` exchange (a row of ``moved``,
    :func:`_nearest_exchanges`), so that they are one labelling's however many frames hold
    the other (half, say, where plain medians would fall between the two), in the labelling
    most frames hold; and the median departure from them (:func:`_median_departure`).
    ``aligned``, of the shape of ``distances``, is overwritten. A compiled kernel."""
    n_pairs, n_frames = distances.shape
    aligned[:] = distances
    held = np.zeros(moved.shape[0], dtype=np.int64)
    held[0] = n_frames - candidates.size
    for k in range(candidates.size):
        for p in range(n_pairs):
            aligned[p, candidates[k]] = distances[moved[best[k], p], candidates[k]]
        held[best[k]] += 1
    median = _medians(aligned)
    # A floor far below any real noise keeps exact data from dividing by zero.
    noise = max(_median_departure(aligned, median, aligned), 1e-9 * median.max())
    # In the labelling most frames hold, so that the swapped side is the one with fewer frames.
    most = np.argmax(held)
    reference = np.empty(n_pairs)
    for p in range(n_pairs):
        reference[p] = median[moved[most, p]]
    return reference, noise


@kernel
def _distinct_exchanges(
    moved: np.ndarray, reference: np.ndarray, noise: float, far: float, near: float
) -> np.ndarray:
    """Which exchanges (rows of ``moved``, :func:`_relabelled_pairs`) move the typical
    distances ``reference`` ``(n_pairs,)`` [mm] by more than ``sqrt(far) + sqrt(near)`` times
    the ``noise`` [mm]: then every frame an exchange holds clears the far level unless its
    own noise exceeds the near one (triangle inequality), so that its frames form whole runs.
    A smaller exchange (an isosceles triangle's base) is one that deformation or noise can
    mimic. Row 0 (no exchange) is not one. A compiled kernel."""
    separation_sq = (np.sqrt(far) + np.sqrt(near)) ** 2 * noise**2
    distinct = _exchange_sizes_sq(moved, reference) > separation_sq
    distinct[0] = False
    return distinct


@kernel
def _exchanges(
    distances: np.ndarray,
    moved: np.ndarray,
    reference: np.ndarray,
    distinct: np.ndarray,
    far_sq: float,
    near_sq: float,
) -> tuple[np.ndarray, np.ndarray]:
    """Per frame of ``distances`` ``(n_pairs, n_frames)`` [mm], the exchange that explains it
    and its squared misfit [mm^2] from ``reference`` ``(n_pairs,)`` as labelled: for a frame
    whose misfit exceeds ``far_sq``, the first of the ``distinct`` exchanges (rows of
    ``moved``, :func:`_relabelled_pairs`) with the least misfit, if that is within
    ``near_sq`` (as the index of its pair, one less than its row), else -1. A compiled
    kernel."""
    n_frames = distances.shape[1]
    as_labelled = np.empty(n_frames)
    _misfits_sq(distances, np.arange(n_frames), moved, 0, reference, as_labelled)
    found = np.full(n_frames, -1)
    beyond = np.flatnonzero(as_labelled > far_sq)
    best = np.full(beyond.size, -1)
    best_misfit = np.full(beyond.size, near_sq)
    exchanged = np.empty(beyond.size)
    for e in range(1, moved.shape[0]):
        if distinct[e]:
            _misfits_sq(distances, beyond, moved, e, reference, exchanged)
            for k in range(beyond.size):
                if exchanged[k] <= best_misfit[k]:
                    best[k], best_misfit[k] = e - 1, exchanged[k]
    found[beyond] = best
    return found, as_labelled


@kernel
def _exchange_sizes_sq(moved: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``(1 + n_pairs,)``: how far [mm^2] each exchange (row of ``moved``,
    :func:`_relabelled_pairs`) moves the distances ``reference`` ``(n_pairs,)`` [mm], squared:
    the misfit (:func:`_misfits_sq`) of ``reference`` relabelled, as a frame of its own. A
    compiled kernel."""
    sizes_sq = np.empty(moved.shape[0])
    frame, first = reference.reshape(reference.size, 1), np.zeros(1, dtype=np.int64)
    for e in range(moved.shape[0]):
        _misfits_sq(frame, first, moved, e, reference, sizes_sq[e : e + 1])
    return sizes_sq


@kernel
def _misfits_sq(
    distances: np.ndarray,
    frames: np.ndarray,
    moved: np.ndarray,
    e: int,
    reference: np.ndarray,
    misfit_sq: np.ndarray,
) -> None:
    """Into ``misfit_sq`` ``(n,)``: the squared departure [mm^2] of the distances of each of
    the ``frames`` ``(n,)`` of ``distances`` ``(n_pairs, n_frames)``, relabelled by row ``e``
    of ``moved`` (:func:`_relabelled_pairs`), from ``reference`` ``(n_pairs,)``. One call for
    many frames: a call per frame would cost more than its sum. A compiled kernel."""
    for k in range(frames.size):
        total = 0.0
        for p in range(reference.size):
            total += (distances[moved[e, p], frames[k]] - reference[p]) ** 2
        misfit_sq[k] = total


@kernel
def _relabelled_pairs(n_markers: int) -> np.ndarray:
    """``(1 + n_pairs, n_pairs)``: row 0 the pairs of markers as they are, row ``1 + e`` the
    pair whose distance pair ``p`` takes when the labels of pair ``e`` are exchanged; pairs in
    the order of ``itertools.combinations``. A compiled kernel."""
    index = np.empty((n_markers, n_markers), dtype=np.int64)
    n_pairs = 0
    for a in range(n_markers):
        for b in range(a + 1, n_markers):
            index[a, b] = index[b, a] = n_pairs
            n_pairs += 1
    moved = np.empty((1 + n_pairs, n_pairs), dtype=np.int64)
    for p in range(n_pairs):
        moved[0, p] = p
    e = 0
    for i in range(n_markers):
        for j in range(i + 1, n_markers):
            e += 1
            p = 0
            for a in range(n_markers):
                for b in range(a + 1, n_markers):
                    first = j if a == i else i if a == j else a
                    second = j if b == i else i if b == j else b
                    moved[e, p] = index[first, second]
                    p += 1
    return moved


def find_swaps(
    shape: np.ndarray,
    markers: np.ndarray,
    flagged: np.ndarray,
    labels: tuple[str, ...],
    level_mm: float,
    exchanged: Sequence[Artefact] = (),
    rules: ArtefactRules | None = None,
) -> list[Swap]:
    """Runs of frames in which exchanging two markers' labels fits the cluster's ``shape``.

    ``markers`` ``(n_frames, n, 3)`` [mm] the cluster, ``flagged`` ``(n_frames, n)`` its
    rigidity breaks, ``level_mm`` their threshold. A frame whose two flagged markers, exchanged,
    fit ``shape`` within ``level_mm`` belongs to that pair's swap; frames where either marker
    is missing do not interrupt a run. A frame that the distance test found swapped
    (``exchanged``, :func:`find_exchanges`) belongs to the swap of the pair it names and to no
    other pair's, which in a cluster of a few mm ``level_mm`` cannot tell apart.

    A symmetric shape fits some exchanges alike (:func:`_alike_pairs`, within the distance
    test's near level, else ``level_mm``): a rectangle's with its first two markers exchanged
    or its last two (the shape turned 180 deg between them), and the pair a frame shows is then
    the noise's choice. Those pairs are one swap's candidates and their frames one run, which
    names the one pair the data tell: the run's distances, where one pair fits them better
    than every other beyond the near probability (:func:`_told_pairs`), else the frames next
    to the run (:func:`_continuing`): relabelled by the pair that swapped, every marker steps
    on where it was, while a pair the symmetry only fits alike carries its markers across the
    cluster, a step the jump check flags (``rules``' jump level). Where neither tells (a
    perfect symmetry, and gaps next to the swap or a cluster smaller than a jump) the run
    names every candidate, the best fitting first (:attr:`Swap.alternatives`): one pair named
    with a confidence the data do not give would send a user to the wrong markers.
    """
    rules = rules or _RULES
    pairs = list(combinations(range(len(labels)), 2))
    named: dict[int, set[str]] = {a.frame: {a.label, a.partner} for a in exchanged}
    states = {}
    for i, j in pairs:
        both = flagged[:, i] & flagged[:, j]
        state = np.zeros(len(markers), dtype=bool)
        if both.any():
            rows = np.flatnonzero(both)
            exchanged_rows = markers[rows].copy()
            exchanged_rows[:, [i, j]] = exchanged_rows[:, [j, i]]
            misfit = _posed(shape, exchanged_rows)[2]
            state[rows[np.nanmax(misfit, axis=1) <= level_mm]] = True
        for frame, pair in named.items():
            state[frame] = pair == {labels[i], labels[j]}
        if state.any():
            states[(i, j)] = state
    if not states:
        return []
    radius, noise = level_mm, None
    if exchanged:
        far, near = _exchange_levels(len(labels), rules)
        noise = exchanged[0].level_mm / float(np.sqrt(far))
        radius = noise * float(np.sqrt(near))
    alike = _alike_pairs(shape, radius)
    # One state per set of candidates, the union of its pairs' frames.
    candidates: dict[tuple[tuple[int, int], ...], np.ndarray] = {}
    for pair, state in states.items():
        key = tuple(sorted(alike[pair]))
        candidates[key] = candidates.get(key, False) | state
    # The jump level is needed only to tell candidates apart.
    several = any(len(members) > 1 for members in candidates)
    level = _jump_level(markers, rules) if several else rules.min_jump_mm
    swaps = []
    for members, state in candidates.items():
        seen = np.flatnonzero(
            np.isfinite(markers[:, sorted({m for p in members for m in p})]).all(axis=(1, 2))
        )
        # Runs of swapped frames among the frames showing the candidates' markers.
        changes = np.flatnonzero(np.diff(state[seen].astype(int))) + 1
        for run in np.split(np.arange(seen.size), changes):
            if run.size and state[seen[run[0]]]:
                start = 0 if run[0] == 0 else int(seen[run[0]])
                stop = len(markers) if run[-1] == seen.size - 1 else int(seen[run[-1]]) + 1
                told = _told_pairs(markers[start:stop], members, shape, noise, rules)
                told = _continuing(markers, start, stop, told, level)
                (i, j), *others = told
                swaps.append(
                    Swap(
                        (labels[i], labels[j]),
                        start,
                        stop,
                        len(markers),
                        tuple((labels[a], labels[b]) for a, b in others),
                    )
                )
    return sorted(swaps, key=lambda swap: (swap.start, swap.labels))


def _alike_pairs(shape: np.ndarray, radius_mm: float) -> dict[tuple[int, int], set]:
    """For each pair of markers ``(i, j)`` of ``shape`` ``(n, 3)`` [mm], the pairs whose
    exchange gives the shape the same inter-marker distances as its own exchange, within
    ``radius_mm`` (their norm over the pairs): the exchanges a frame's shape cannot tell apart
    (itself among them). Only a symmetric shape has others: a rectangle's two long sides, its
    two short sides, its two diagonals."""
    n_markers = len(shape)
    moved = _relabelled_pairs(n_markers)[1:]
    distances = _pair_distances(kernel_array(shape[None]))[:, 0]
    relabelled = distances[moved]
    apart = np.linalg.norm(relabelled[:, None, :] - relabelled[None, :, :], axis=-1)
    pairs = list(combinations(range(n_markers), 2))
    return {
        pair: {pairs[k] for k in np.flatnonzero(apart[e] <= radius_mm)}
        for e, pair in enumerate(pairs)
    }


def _told_pairs(
    frames: np.ndarray,
    members: tuple[tuple[int, int], ...],
    shape: np.ndarray,
    noise_mm: float | None,
    rules: ArtefactRules,
) -> list[tuple[int, int]]:
    """The candidate pairs ``members`` of a swap held by ``frames`` ``(n_frames, n, 3)`` [mm],
    best first, as the distances tell them: each pair's exchange fits the frames' inter-marker
    distances to ``shape``'s ``(n, 3)`` with a sum of squared misfits over the frames; in units
    of the distance test's ``noise_mm`` (:class:`ArtefactRules`), the best pair is the only one
    left where every other's sum exceeds it by more than the level one degree of freedom
    exceeds with probability ``swap_near_probability``. Otherwise (or without the distance
    test's noise, ``None``) every candidate is left."""
    if len(members) == 1 or noise_mm is None:
        return list(members)
    complete = _complete_frames(kernel_array(frames))
    if complete.size == 0:
        return list(members)
    distances = _pair_distances(kernel_array(frames[complete]))
    typical = _pair_distances(kernel_array(shape[None]))[:, 0]
    moved = _relabelled_pairs(len(shape))
    pairs = list(combinations(range(len(shape)), 2))
    misfits = [
        float(np.sum((distances[moved[1 + pairs.index(pair)]] - typical[:, None]) ** 2))
        for pair in members
    ]
    ranked = [members[k] for k in np.argsort(misfits, kind="stable")]
    margin = float(scipy_special().chdtri(1, rules.swap_near_probability)) * noise_mm**2
    if all(misfit - min(misfits) > margin for misfit in sorted(misfits)[1:]):
        return ranked[:1]
    return ranked


def _continuing(
    markers: np.ndarray,
    start: int,
    stop: int,
    left: list[tuple[int, int]],
    level_mm: float,
) -> list[tuple[int, int]]:
    """Of the pairs ``left`` for a swap in rows ``start`` to ``stop - 1`` of ``markers``
    ``(n_frames, n, 3)`` [mm], the one no edge refutes (:func:`_refuted`) where the edges
    refute every other; else all of them, in their order."""
    if len(left) == 1:
        return left
    kept = [pair for pair in left if not _refuted(markers, start, stop, pair, level_mm)]
    return kept if len(kept) == 1 else left


def _refuted(
    markers: np.ndarray, start: int, stop: int, pair: tuple[int, int], level_mm: float
) -> bool:
    """Whether exchanging the ``pair``'s labels in rows ``start`` to ``stop - 1`` of ``markers``
    ``(n_frames, n, 3)`` [mm] leaves either marker a jump (:func:`find_jumps`' step size over
    ``level_mm``) where the labelling changes, at ``start`` or at ``stop``: the pair did not
    swap there. A step the gaps leave unmeasured refutes nothing."""
    n_frames = len(markers)
    low, high = max(start - 2, 0), min(stop + 2, n_frames)
    window = markers[low:high].copy()
    i, j = pair
    window[start - low : stop - low, [i, j]] = window[start - low : stop - low, [j, i]]
    if len(window) < 4:
        return False
    size = np.empty((len(window) - 3, markers.shape[1]))
    _jump_sizes(kernel_array(window), size)
    edges = [row - low - 2 for row in (start, stop) if 0 < row < n_frames]
    edges = [row for row in edges if 0 <= row < len(size)]
    return bool((size[edges][:, [i, j]] > level_mm).any())


@dataclass(frozen=True, eq=False)
class Screening:
    """What :func:`screen` found in one marker set: flagged ``artefacts`` (rigidity breaks and
    swapped frames of a cluster of >= 3 markers, jumps of any) and the ``swaps`` explaining
    some of them.
    A cluster's fit is kept for :class:`Segment`: ``shape`` ``(n, 3)`` [mm], its ``rotation``
    ``(n_frames, 3, 3)``, ``translation`` ``(n_frames, 3)`` and ``residuals`` ``(n_frames, n)``
    [mm]; ``None`` for fewer than three markers. ``untested`` says in words which check did
    not run (:func:`exchanges_untested`), ``""`` when every one did."""

    artefacts: tuple[Artefact, ...]
    swaps: tuple[Swap, ...] = ()
    shape: np.ndarray | None = None
    rotation: np.ndarray | None = None
    translation: np.ndarray | None = None
    residuals: np.ndarray | None = None
    untested: str = ""


def screen(
    markers: np.ndarray,
    labels: tuple[str, ...],
    source: str,
    rules: ArtefactRules | None = None,
) -> Screening:
    """Artefacts of one marker set ``(n_frames, n, 3)`` [mm] (module docstring): rigidity
    breaks, swapped frames and swaps of a cluster of >= 3 markers, jumps of fewer. ``source``
    names the data in messages. Frame order matters only to the jumps. A cluster of more than
    :data:`MAX_EXCHANGE_MARKERS` is not tested for label exchanges, and its ``untested`` says
    so. ``rules`` other than :class:`ArtefactRules` or ``None``, or ``markers`` not shaped
    ``(n_frames, len(labels), 3)``, raise ``ValueError``."""
    rules = checked_rules(rules)
    if np.ndim(markers) != 3 or np.shape(markers)[1:] != (len(labels), 3):
        raise ValueError(
            f"{source}: markers must be shaped (n_frames, {len(labels)} labels, 3), got shape "
            f"{np.shape(markers)}"
        )
    check_magnitudes(markers, labels, source)
    if len(labels) < 3:
        return Screening(tuple(find_jumps(markers, labels, rules)))
    exchanged = [] if exchanges_untested(len(labels)) else find_exchanges(markers, labels, rules)
    # First judged against one typical frame, which the broken frames cannot distort; then the
    # mean shape is refitted on the samples neither flagged nor swapped, until the flags settle.
    # The typical frame is one the swaps do not hold, so that both checks judge by one side.
    unswapped = np.ones(len(markers), dtype=bool)
    unswapped[[a.frame for a in exchanged]] = False
    shape = typical_shape(markers[unswapped] if exchanged else markers, labels, source)
    return _screened(markers, labels, source, rules, exchanged, shape, _posed(shape, markers))


def _posed(shape: np.ndarray, markers: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``shape`` ``(n, 3)`` [mm] in its best pose in every frame of ``markers``
    ``(n_frames, n, 3)`` [mm] (:func:`fit_poses`), and each marker's residual ``(n_frames, n)``
    [mm] (:func:`residuals`)."""
    shape, markers = kernel_array(shape), kernel_array(markers)
    posed = _posed_by_horn(shape, markers)
    if posed[3]:
        return posed[:3]
    rotation, translation = fit_poses(shape, markers)
    return rotation, translation, residuals(shape, rotation, translation, markers)


@kernel
def _posed_by_horn(
    shape: np.ndarray, markers: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, bool]:
    """:func:`_posed` in one compiled call where Horn's method settles every frame it poses
    (:func:`_horn_poses`), and whether it did; where it did not, the arrays are unfinished. A
    compiled kernel."""
    n_frames, n_markers = markers.shape[0], markers.shape[1]
    rotation = np.empty((n_frames, 3, 3))
    translation = np.empty((n_frames, 3))
    distance = np.empty((n_frames, n_markers))
    settled = _horn_poses(shape, markers, rotation, translation)
    if settled:
        _residuals(shape, rotation, translation, markers, distance)
    return rotation, translation, distance, settled


def _screened(
    markers: np.ndarray,
    labels: tuple[str, ...],
    source: str,
    rules: ArtefactRules,
    exchanged: list[Artefact],
    shape: np.ndarray,
    posed: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> Screening:
    """:func:`screen` of a cluster of >= 3 ``markers`` ``(n_frames, n, 3)`` [mm] from its
    swapped frames ``exchanged`` (:func:`find_exchanges`), its typical frame ``shape``
    (:func:`typical_shape`, of the frames the swaps do not hold) and that shape's
    :func:`_posed` fit ``posed``: the iterated mean shape and all that follows."""
    untested = exchanges_untested(len(labels))
    typical = shape
    breaks: list[Artefact] | None = None
    for _ in range(5):
        rotation, translation, misfit = posed
        found = find_rigidity_breaks(misfit, labels, rules)
        if found == breaks:
            break
        breaks = found
        clean = markers.copy()
        for artefact in [*breaks, *exchanged]:
            clean[artefact.frame, labels.index(artefact.label)] = np.nan
        # With nothing flagged the samples are the markers themselves, whose typical frame the
        # screen started from: its search over every marker pair is not made again.
        unflagged = typical if not (breaks or exchanged) else None
        shape = mean_shape(clean, labels, source, unflagged)
        posed = _posed(shape, markers)
    else:
        rotation, translation, misfit = posed
    # A swapped sample that also breaks rigidity is flagged once, as the break.
    broken = {(a.label, a.frame) for a in breaks}
    flags = [*breaks, *(a for a in exchanged if (a.label, a.frame) not in broken)]
    swaps: list[Swap] = []
    # Above MAX_EXCHANGE_MARKERS no exchange of labels is searched for, as ``untested`` says:
    # the search of the breaks tries every pair of markers, each with a pose fit of them all.
    if flags and not untested:
        flagged = np.zeros(misfit.shape, dtype=bool)
        for artefact in flags:
            flagged[artefact.frame, labels.index(artefact.label)] = True
        level = breaks[0].level_mm if breaks else _rigidity_level(misfit, rules)
        swaps = find_swaps(shape, markers, flagged, labels, level, exchanged, rules)
        flags = _named_by_swaps(flags, swaps, labels, broken)
    # A jump that a flagged sample or a found swap's change of labelling explains adds
    # nothing, and would spoil the frame on its other side (or be taken for a second swap of
    # the same pair); jumps without one may be a swap that keeps the shape, which only time
    # order shows.
    explained = {(a.label, a.frame) for a in flags}.union(*(swap.steps() for swap in swaps))
    jumps = [
        jump
        for jump in find_jumps(markers, labels, rules)
        if not {(jump.label, row) for row in jump.rows()} & explained
    ]
    kept, swapped, jumps = _shape_keeping_swaps(markers, labels, jumps, rules)
    artefacts = sorted([*jumps, *flags, *swapped], key=lambda a: (a.frame, a.label))
    swaps = sorted([*swaps, *kept], key=lambda swap: (swap.start, swap.labels))
    return Screening(tuple(artefacts), tuple(swaps), shape, rotation, translation, misfit, untested)


def _shape_keeping_swaps(
    markers: np.ndarray, labels: tuple[str, ...], jumps: list[Artefact], rules: ArtefactRules
) -> tuple[list[Swap], list[Artefact], list[Artefact]]:
    """The swaps among the ``jumps`` of the cluster ``markers`` ``(n_frames, n >= 3, 3)`` [mm]
    that keep its shape (a square's diagonal, an isosceles triangle's base), which only time
    order shows: two markers that jump at the same frames, where exchanging their labels in
    every other stretch between those frames leaves neither a jump there (:func:`_refuted`).
    The stretches alternate between two labellings; those of the labelling fewer frames hold
    are the swaps, as :func:`find_swaps` reports a swap the shape shows, and their frames are
    flagged swapped (``"swap"`` artefacts, sized as the largest jump they explain, at the jump
    level), so that excluding artefacts leaves out every frame turned over, not only its two
    steps. Returns the swaps, their artefacts and the jumps left unexplained."""
    jumped: dict[str, set[int]] = {}
    for jump in jumps:
        jumped.setdefault(jump.label, set()).add(jump.frame)
    if len(jumped) < 2:
        return [], [], jumps
    n_frames = len(markers)
    level = _jump_level(markers, rules)
    swaps, swapped, explained = [], [], set()
    for first, second in combinations([label for label in labels if label in jumped], 2):
        changes = sorted(jumped[first] & jumped[second])
        if not changes:
            continue
        i, j = labels.index(first), labels.index(second)
        stretches = list(pairwise([0, *changes, n_frames]))
        turned = stretches[1::2]
        if any(_refuted(markers, start, stop, (i, j), level) for start, stop in turned):
            continue
        held = sum(stop - start for start, stop in turned)
        minority = turned if 2 * held <= n_frames else stretches[0::2]
        size = max(a.size_mm for a in jumps if a.label in (first, second) and a.frame in changes)
        for start, stop in minority:
            if start == stop:
                continue
            swaps.append(Swap((first, second), start, stop, n_frames))
            for row in range(start, stop):
                swapped.append(Artefact("swap", first, row, size, level, second))
                swapped.append(Artefact("swap", second, row, size, level, first))
        explained |= {(label, frame) for label in (first, second) for frame in changes}
    left = [jump for jump in jumps if (jump.label, jump.frame) not in explained]
    return swaps, swapped, left


def _named_by_swaps(
    flags: list[Artefact],
    swaps: list[Swap],
    labels: tuple[str, ...],
    broken: set[tuple[str, int]],
) -> list[Artefact]:
    """The ``flags`` with each swapped frame's pair the one its swap names where the data tell
    it (a :class:`Swap` without ``alternatives``): of a symmetric shape the distance test names,
    frame by frame, whichever of the pairs it fits alike the noise favours. A renamed sample
    that breaks rigidity (``broken``, ``(label, frame)``) is flagged once, as the break."""
    told: dict[int, list[tuple[str, str]]] = {}
    for swap in swaps:
        if not swap.alternatives:
            for row in range(swap.start, swap.stop):
                told.setdefault(row, []).append(swap.labels)
    renamed = []
    for artefact in flags:
        pairs = told.get(artefact.frame, [])
        shown = {artefact.label, artefact.partner}
        if artefact.kind != "swap" or len(pairs) != 1 or shown == set(pairs[0]):
            renamed.append(artefact)
            continue
        first, second = pairs[0]
        # The sample of the pair's earlier label stands for the named pair's first.
        earlier = min(shown, key=labels.index) == artefact.label
        label, partner = (first, second) if earlier else (second, first)
        if (label, artefact.frame) not in broken:
            renamed.append(dataclasses.replace(artefact, label=label, partner=partner))
    return renamed


def find_artefacts(
    markers: np.ndarray,
    labels: tuple[str, ...],
    source: str,
    rules: ArtefactRules | None = None,
) -> tuple[tuple[Artefact, ...], tuple[Swap, ...]]:
    """The ``artefacts`` and ``swaps`` :func:`screen` finds in ``markers`` ``(n_frames, n, 3)``
    [mm], without the cluster's fit (:func:`_find_artefacts`), once :func:`check_magnitudes`
    passed them: ``ValueError`` naming ``source``, the marker and the frame of a coordinate
    beyond what float64's sums over them can hold, an inf among them."""
    check_magnitudes(markers, labels, source)
    return _find_artefacts(markers, labels, source, rules)


def _find_artefacts(
    markers: np.ndarray, labels: tuple[str, ...], source: str, rules: ArtefactRules | None = None
) -> tuple[tuple[Artefact, ...], tuple[Swap, ...]]:
    """:func:`find_artefacts` of ``markers`` that passed :func:`check_magnitudes` (or
    :func:`~jointbench.estimators.validation.check_markers`, which refuses every coordinate it
    refuses) just before, not run again: a complete cluster that :func:`surely_rigid` clears and
    in which :func:`find_exchanges` finds no swap needs only the jump check, anything else
    gets the whole screen. A cluster the marker-frame bounds clear costs one compiled call
    (:func:`_clean_screen`), which finds what the bound, the distance test's verdict and the
    jump check need together; the jumps are located only where a step exceeds
    ``min_jump_mm``. Where the whole screen runs on a complete cluster without a swapped
    frame, it starts from the typical frame and pose fit of the fitted bounds, which are its
    own first. A cluster of more than :data:`MAX_EXCHANGE_MARKERS` is not tested for
    label exchanges, as in :func:`screen`: its callers say so (:func:`exchanges_untested`)."""
    if len(labels) < 3:
        return tuple(find_jumps(markers, labels, rules or _RULES)), ()
    # Looked up before the default is filled in: None hashes faster than the rules.
    limit, far, near, min_frames = _clean_levels(len(labels), rules)
    rules = rules or _RULES
    markers = kernel_array(markers)
    # Asked for more frames than there are, the distance test does not run.
    if min_frames is None:
        min_frames = markers.shape[0] + 1
    typical, cleared, largest_jump, exchanged = _clean_screen(markers, limit, far, near, min_frames)
    posed = None
    if not (exchanged or cleared) and typical >= 0:
        cleared = _refined_clears(markers, typical, limit)
    if not (exchanged or cleared) and typical >= 0:
        # The fitted bounds' pose fit is the whole screen's first, from the same typical frame
        # (every frame is complete), and serves it too.
        shape = markers[typical].copy()
        posed = _posed(shape, markers)
        cleared = all(bound <= limit for bound in _fitted_misfits(markers, typical, posed))
    if exchanged or not cleared:
        if posed is None:
            found = screen(markers, labels, source, rules)
        else:
            # No swapped frame: the distance test found none, or did not run, as in the screen.
            found = _screened(markers, labels, source, rules, [], shape, posed)
        return found.artefacts, found.swaps
    if not largest_jump > rules.min_jump_mm:  # the jumps' level is at least min_jump_mm
        return (), ()
    kept, swapped, jumps = _shape_keeping_swaps(
        markers, labels, find_jumps(markers, labels, rules), rules
    )
    artefacts = sorted([*jumps, *swapped], key=lambda a: (a.frame, a.label))
    return tuple(artefacts), tuple(sorted(kept, key=lambda swap: (swap.start, swap.labels)))


def surely_rigid(
    markers: np.ndarray, labels: tuple[str, ...], source: str, rules: ArtefactRules
) -> bool:
    """Whether a bound shows that :func:`screen` flags no rigidity break in the complete cluster
    ``markers`` ``(n_frames, n >= 3, 3)`` [mm]; ``False`` means not shown (gaps, or the bound
    is too loose), not broken. It tries the bounds of :func:`_rigid_misfits`, the cheaper
    first, the marker-frame ones refined on the frames that exceed them
    (:func:`_refined_clears`) before the fitted ones. It does not show that the screen's mean
    shape converges (where it does not, the screen raises)."""
    markers, limit = kernel_array(markers), _rigid_limit(rules)
    typical, cleared, _ = _screen_sums(markers, limit)
    return _fitted_clears(markers, typical, cleared, limit)


@functools.lru_cache(maxsize=256)  # bounded as _exchange_levels is
def _clean_levels(
    n_markers: int, rules: ArtefactRules | None
) -> tuple[float, float, float, int | None]:
    """What :func:`_clean_screen` takes of ``rules`` (``None``: the default) for a cluster of
    ``n_markers``, found once per cluster size: :func:`_rigid_limit`, the levels of
    :func:`_exchange_levels` and the least number of frames the distance test judges
    (``None`` where it does not run, :func:`exchanges_untested`)."""
    rules = rules or _RULES
    far, near = _exchange_levels(n_markers, rules)
    min_frames = None if exchanges_untested(n_markers) else rules.swap_min_frames
    return _rigid_limit(rules), far, near, min_frames


def _rigid_limit(rules: ArtefactRules) -> float:
    """The bound [mm] that :func:`surely_rigid` holds the residuals' bounds to:
    ``min_residual_mm`` less a margin for rounding."""
    return rules.min_residual_mm / (1.0 + 1e-9)


def _fitted_clears(markers: np.ndarray, typical: int, cleared: bool, limit: float) -> bool:
    """:func:`surely_rigid`'s decision on ``markers`` ``(n_frames, n >= 3, 3)`` [mm] (a kernel
    array), given what :func:`_screen_sums` found (its ``typical`` frame and whether the
    marker-frame bounds ``cleared`` it): those, else where there is a typical frame those
    refined (:func:`_refined_clears`), else the fitted bounds (a pose fit)."""
    if not cleared and typical >= 0:
        cleared = _refined_clears(markers, typical, limit)
    if not cleared and typical >= 0:
        cleared = all(bound <= limit for bound in _rigid_misfits(markers, typical, True))
    return cleared


#: The most frames whose marker-frame bound :func:`_refined_clears` replaces by a pose fit of
#: their own: beyond it the fit of every frame costs little more.
_MAX_REFINED_FRAMES = 64


def _refined_clears(markers: np.ndarray, typical: int, limit: float) -> bool:
    """Whether the marker-frame bounds of :func:`_rigid_misfits` (without ``fitted``) are at
    most ``limit`` [mm] once the few frames ``f`` that exceed it read ``e_f``, the residual
    norm of the mean ``M`` in a pose fitted to that frame alone, in place of ``u_f``; a cluster
    ``markers`` ``(n_frames, n >= 3, 3)`` [mm] (a kernel array) with ``typical`` frame ``t``.
    ``False`` means not shown, as where more than :data:`_MAX_REFINED_FRAMES` frames exceed.

    ``u_f`` entered the bounds only as a bound of ``d_f(M)`` (steps 2 and 3), which any pose of
    ``M`` bounds: ``r_fm(T) <= c (d_f(M) + u_t)`` and ``r_fm(S) <= c (d_f(M) + mean u +
    sqrt(mean u^2 + u_t^2))``, the second no less than the first. A cluster just short of the
    bound of each frame's marker frame is cleared by a handful of small fits instead of a pose
    fit of every frame."""
    mean, u = _triad_distances(markers, typical)
    c = _per_marker(markers.shape[1])
    rest = u.mean() + np.hypot(np.sqrt((u**2).mean()), u[typical])
    if not np.isfinite(rest):  # collinear markers, or squares beyond the floats' range
        return False
    over = np.flatnonzero(~(c * (u + rest) <= limit))
    if over.size > _MAX_REFINED_FRAMES:
        return False
    return bool(np.all(c * (_posed_misfits(mean, markers[over]) + rest) <= limit))


@kernel
def _triad_distances(markers: np.ndarray, typical: int) -> tuple[np.ndarray, np.ndarray]:
    """The mean ``M`` ``(n, 3)`` [mm] of the frames of ``markers`` ``(n_frames, n >= 3, 3)``
    [mm] each in its marker frame (:func:`_triad_local`) and every frame's distance ``u_f``
    ``(n_frames,)`` [mm] from it. A compiled kernel."""
    local = np.empty_like(markers)
    _triad_local(markers, typical, local)
    n_frames, n_markers = local.shape[0], local.shape[1]
    mean = _frame_mean(local)
    distance = np.empty(n_frames)
    for f in range(n_frames):
        norm_sq = 0.0
        for m in range(n_markers):
            for i in range(3):
                norm_sq += (local[f, m, i] - mean[m, i]) ** 2
        distance[f] = np.sqrt(norm_sq)
    return mean, distance


@kernel
def _frame_mean(local: np.ndarray) -> np.ndarray:
    """The mean ``(n, 3)`` [mm] of the frames ``local`` ``(n_frames, n, 3)`` [mm], summed in
    frame order. A compiled kernel."""
    n_frames, n_markers = local.shape[0], local.shape[1]
    mean = np.zeros((n_markers, 3))
    for f in range(n_frames):
        for m in range(n_markers):
            for i in range(3):
                mean[m, i] += local[f, m, i]
    mean /= n_frames
    return mean


def _posed_misfits(shape: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """Each frame's residual norm ``(k,)`` [mm] of ``shape`` ``(n, 3)`` [mm] in a pose fitted
    to it, centroid on centroid and rotated by :func:`best_rotation`, of the frames ``frames``
    ``(k, n, 3)`` [mm]: at least the least residual norm of any pose, whichever rotation the
    fit settles on (NaN where the sums overflow, which bounds nothing)."""
    source = shape - shape.mean(axis=0)
    target = frames - frames.mean(axis=1, keepdims=True)
    cross = np.einsum("kmi,mj->kij", target, source)
    if not np.isfinite(cross).all():  # beyond the floats' range: no pose shown
        return np.full(len(frames), np.nan)
    rotation = best_rotation(cross)
    misfit = target - np.einsum("kij,mj->kmi", rotation, source)
    return np.sqrt((misfit**2).sum(axis=(1, 2)))


@kernel
def _screen_sums(markers: np.ndarray, limit: float) -> tuple[int, bool, float]:
    """What :func:`surely_rigid` and the jump check need of the cluster ``markers``
    ``(n_frames, n >= 3, 3)`` [mm] before a pose fit: :func:`_clean_screen`'s first three
    answers, without the distance test (asked for more frames than there are). A compiled
    kernel."""
    typical, cleared, largest_jump, _ = _clean_screen(
        markers, limit, 0.0, 0.0, markers.shape[0] + 1
    )
    return typical, cleared, largest_jump


@kernel
def _clean_screen(
    markers: np.ndarray, limit: float, far: float, near: float, min_frames: int
) -> tuple[int, bool, float, bool]:
    """What :func:`find_artefacts` needs of the cluster ``markers`` ``(n_frames, n >= 3, 3)``
    [mm] before a pose fit: its typical frame (:func:`typical_shape`'s; -1 where a sample is
    missing, which leaves no bound to try), whether the marker-frame bounds of
    :func:`_rigid_misfits` are at most ``limit`` [mm], the largest step size [mm] of
    :func:`find_jumps` (-inf if none; NaN where a sample is missing) and whether the distance
    test of :func:`_exchange_test` (levels ``far``, ``near``, at least ``min_frames`` frames)
    finds a swapped frame (``False`` where a sample is missing, as the whole screen then
    runs). Where the distance test runs, the inter-marker distances and their medians serve
    both it and the typical frame (without it, the typical frame is found pair by pair,
    :func:`_typical_and_finite`), and where :func:`_surely_unexchanged` shows that the test
    finds nothing it is not run. The bound and the test share the exchanges and the largest
    departure, and the test's anchor is the typical frame wherever it is the labelled
    distances' own. A compiled kernel."""
    n_frames, n_markers, _ = markers.shape
    tested = n_frames >= max(min_frames, 1)
    # The distance test reads the distances kept; without it, each pair's are made in turn.
    if tested:
        distances, finite = _finite_pair_distances(markers)
    else:
        typical, finite = _typical_and_finite(markers)
    # Finite distances show every coordinate finite; else the frames are counted.
    if not finite and _complete_frames(markers).size < n_frames:
        return -1, False, np.nan, False  # the whole screen finds the jumps
    if tested:
        medians = _medians(distances)
        typical = _nearest(distances, medians)  # _most_typical's, every frame being complete
    first, second = _frame_misfits(markers, typical)
    largest_jump = _jump_sizes(markers, np.empty((max(n_frames - 3, 0), n_markers)))
    exchanged = False
    if tested:
        moved = _relabelled_pairs(n_markers)
        largest_sq = _largest_departure_sq(distances, medians)
        if not _unexchanged_by_bound(moved, medians, largest_sq, far, near):
            found = _judged(distances, medians, moved, typical, largest_sq, far, near, True)[0]
            exchanged = (found >= 0).any()
    return typical, first <= limit and second <= limit, largest_jump, exchanged


@kernel
def _surely_unexchanged(
    distances: np.ndarray, medians: np.ndarray, n_markers: int, far: float, near: float
) -> bool:
    """Whether a bound shows that :func:`_judge_frames` finds no exchange in any frame of
    ``distances`` ``(n_pairs, n_frames)`` [mm], with their rows' ``medians`` ``m``
    ``(n_pairs,)`` [mm], levels ``far`` and ``near``; ``False`` means not shown. A compiled
    kernel.

    Notation: ``d_f`` a frame's distances, ``P_e`` the exchange ``e >= 1`` (a permutation of
    the pairs, :func:`_relabelled_pairs`: ``|P_e x| = |x|``), ``s_e(x) = |P_e x - x|``, ``U``
    the largest ``|d_f - m|``, ``S`` the least ``s_e(m)``, ``r = sqrt(far) / (sqrt(far) +
    sqrt(near))``. The bound is ``6 U < S`` and ``U < r S``.

    1. For any frames ``a``, ``f``: ``|d_f - d_a| <= 2 U`` and ``s_e(d_a) >= s_e(m) - 2 U``
       (``P_e d_a - d_a`` differs from ``P_e m - m`` by ``P_e (d_a - m) - (d_a - m)``). The
       test's anchor is a frame ``a``, and a frame is a candidate only when
       ``2 |d_f - d_a| >= s_e(d_a)`` for an exchange ``e`` it allows (:func:`_candidates`);
       with ``6 U < S``, ``2 |d_f - d_a| <= 4 U < S - 2 U <= s_e(d_a)`` for every ``e``, so
       there is none, and the reference distances are ``m`` (:func:`_judge_frames`).
    2. A frame is swapped by ``e`` only when ``e`` is distinct, ``s_e(m) > (sqrt(far) +
       sqrt(near)) noise``, and ``|P_e d_f - m| <= sqrt(near) noise`` (:func:`_exchanges`).
       As ``|P_e d_f - m| >= s_e(m) - |d_f - m|``, that needs ``|d_f - m| >= s_e(m) -
       sqrt(near) noise > r s_e(m) >= r S``, which ``U < r S`` rules out.

    The margins (relative 1e-6, absolute 1e-150 mm) exceed the rounding of the few sums of
    squares on either side, underflow included; NaN or overflow fails the bound.
    """
    return _unexchanged_by_bound(
        _relabelled_pairs(n_markers), medians, _largest_departure_sq(distances, medians), far, near
    )


@kernel
def _unexchanged_by_bound(
    moved: np.ndarray, medians: np.ndarray, largest_sq: float, far: float, near: float
) -> bool:
    """:func:`_surely_unexchanged`, given ``moved`` (:func:`_relabelled_pairs` of the cluster)
    and ``largest_sq`` (:func:`_largest_departure_sq` of the distances and ``medians``). A
    compiled kernel."""
    largest, least, ratio = _bound_terms(moved, medians, largest_sq, far, near)
    return 6.0 * largest < least and largest < ratio * least


@kernel
def _unswapped_by_bound(
    moved: np.ndarray, medians: np.ndarray, largest_sq: float, far: float, near: float
) -> bool:
    """Step 2 of :func:`_surely_unexchanged` alone, ``U < r S``: where the distance test
    relabels no frame, its reference distances are ``medians`` and it finds no swapped frame,
    whatever the noise. ``moved`` and ``largest_sq`` as for :func:`_unexchanged_by_bound`. A
    compiled kernel."""
    largest, least, ratio = _bound_terms(moved, medians, largest_sq, far, near)
    return largest < ratio * least


@kernel
def _bound_terms(
    moved: np.ndarray, medians: np.ndarray, largest_sq: float, far: float, near: float
) -> tuple[float, float, float]:
    """The terms of :func:`_surely_unexchanged`'s bound: ``U`` [mm] with its margins, ``S``
    [mm] (NaN where the cluster has no exchange, which fails every comparison) and ``r``. A
    compiled kernel."""
    sizes_sq = _exchange_sizes_sq(moved, medians)
    least = np.sqrt(np.min(sizes_sq[1:])) if sizes_sq.size >= 2 else np.nan
    largest = np.sqrt(largest_sq) * (1.0 + 1e-6) + 1e-150
    ratio = np.sqrt(far) / (np.sqrt(far) + np.sqrt(near))
    return largest, least, ratio


@kernel
def _unexchanged_from_anchor(
    distances: np.ndarray,
    moved: np.ndarray,
    typical: np.ndarray,
    medians: np.ndarray,
    largest_sq: float,
    far: float,
    near: float,
) -> bool:
    """Whether the distance test's verdict on ``distances`` ``(n_pairs, n_frames)`` [mm], with
    their rows' ``medians`` ``(n_pairs,)`` [mm], is shown to be "no swapped frame" where its
    anchor frame's distances are ``typical`` ``(n_pairs,)`` [mm] (the labelled distances'
    own anchor, :func:`_judged`), without the noise's median; ``False`` means not shown.
    ``moved`` and ``largest_sq`` as for :func:`_unexchanged_by_bound`. A compiled kernel.

    It is :func:`_surely_unexchanged`'s bound with step 1 taken at the anchor itself instead
    of through ``U``: no frame is a candidate of any exchange (:func:`_candidates`, every
    exchange allowed). The exchanges the test allows are some of those, so the least size it
    compares with is no less and its candidates are among these (the same numbers, computed
    the same way): none, and the test relabels no frame. Its reference distances are then
    ``medians``, and step 2 (:func:`_unswapped_by_bound`) shows that it finds no swapped
    frame."""
    every = np.ones(moved.shape[0], dtype=np.bool_)
    if _candidates(distances, moved, typical, every).size:
        return False
    return _unswapped_by_bound(moved, medians, largest_sq, far, near)


def _rigid_misfits(markers: np.ndarray, typical: int, fitted: bool) -> tuple[float, float]:
    """Bounds [mm] of the largest residual :func:`screen` finds in the complete cluster
    ``markers`` ``(n_frames, n >= 3, 3)`` [mm] from its typical frame ``T``
    (``markers[typical]``) and of the largest from its mean shape ``S``, from a pose ``Q_f``
    of each frame: with ``fitted`` ``T``'s best poses (one pose fit, and the first bound is
    the largest residual itself), else a frame of each frame's own, at its centroid and
    along three of its markers (no fit).

    ``screen`` flags nothing when every residual from ``T`` and from ``S`` is at most
    ``rules.min_residual_mm``. Notation: ``d_f(A)`` is frame ``f``'s residual norm from shape
    ``A`` in its best pose, ``d(A, B)`` the least norm between poses of two shapes, ``J(A)``
    the mean of ``d_f(A)^2``; ``y_f`` is frame ``f`` taken into ``Q_f``, ``M`` the mean of the
    ``y_f``, ``u_f = |y_f - M| >= d_f(M)`` (a pose, perhaps not the best, of ``M``) and ``t``
    the typical frame, so that ``d(M, T) = d_t(M) <= u_t``.

    1. Per marker: a best pose matches the centroids, so the residual vectors ``e_m`` of a
       frame sum to zero; then ``|e_m|^2 = |sum of the others|^2 <= (n - 1) (d^2 - |e_m|^2)``,
       and ``r_fm(A) <= c d_f(A)`` with ``c = sqrt((n - 1) / n)``, for any shape ``A``.
    2. ``d_f(A) <= d_f(M) + d(M, A)``, so ``r_fm(T) <= c (u_f + u_t)``.
    3. Averaging ``d(M, S) <= d_g(M) + d_g(S)`` over the frames ``g`` gives
       ``d(M, S) <= mean u + rms d(S)``, so ``r_fm(S) <= c (u_f + mean u + rms d(S))``.
    4. Every iterate of the mean shape (the mean of the frames in the previous iterate's best
       poses, from ``T``) lowers ``J``, so ``rms d(S) <= sqrt(J(T))``, and
       ``J(T) <= mean |y_f - y_t|^2 = mean u^2 + u_t^2``. With ``T``'s best poses ``M`` is the
       first iterate, so ``rms d(S) <= sqrt(J(M)) <= rms u``.

    Step 1 is attained (one marker displaced away from the centroid, the others
    ``1 / (n - 1)`` as far back), steps 2-4 nearly so when one frame of many carries all the
    misfit and ``Q_f`` is its best pose.
    """
    if not fitted:
        return _frame_misfits(markers, typical)
    return _fitted_misfits(markers, typical, _posed(markers[typical], markers))


def _fitted_misfits(
    markers: np.ndarray, typical: int, posed: tuple[np.ndarray, np.ndarray, np.ndarray]
) -> tuple[float, float]:
    """The bounds [mm] of :func:`_rigid_misfits` with ``fitted``, given ``posed``, the
    typical frame's :func:`_posed` fit to ``markers`` ``(n_frames, n >= 3, 3)`` [mm]."""
    rotation, translation, misfit = posed
    local = np.empty_like(markers)
    _fitted_local(rotation, translation, markers, local)
    highest, mean, rms, _ = _spread(local, typical)
    return float(misfit.max()), _per_marker(markers.shape[1]) * (highest + mean + rms)


@kernel
def _frame_misfits(markers: np.ndarray, typical: int) -> tuple[float, float]:
    """The bounds [mm] of :func:`_rigid_misfits` without ``fitted``: from each frame of
    ``markers`` ``(n_frames, n >= 3, 3)`` [mm] in its marker frame (:func:`_triad_local`).
    A compiled kernel."""
    local = np.empty_like(markers)
    _triad_local(markers, typical, local)
    highest, mean, rms, at_typical = _spread(local, typical)
    c = _per_marker(markers.shape[1])
    return c * (highest + at_typical), c * (highest + mean + np.hypot(rms, at_typical))


@kernel
def _per_marker(n_markers: int) -> float:
    """``c = sqrt((n - 1) / n)`` of :func:`_rigid_misfits`, which takes a frame's residual
    norm to a bound of its markers' residuals. A compiled kernel."""
    return np.sqrt((n_markers - 1) / n_markers)


@kernel
def _fitted_local(
    rotation: np.ndarray, translation: np.ndarray, markers: np.ndarray, local: np.ndarray
) -> None:
    """Fill ``local`` ``(n_frames, n, 3)`` [mm] with ``markers`` ``(n_frames, n, 3)`` taken
    into the poses ``(rotation, translation)``: ``R' (x - t)``. A compiled kernel."""
    for f in range(markers.shape[0]):
        for m in range(markers.shape[1]):
            for i in range(3):
                x = 0.0
                for j in range(3):
                    x += rotation[f, j, i] * (markers[f, m, j] - translation[f, j])
                local[f, m, i] = x


@kernel
def _triad_local(markers: np.ndarray, typical: int, local: np.ndarray) -> None:
    """Fill ``local`` ``(n_frames, n, 3)`` [mm] with each frame of ``markers``
    ``(n_frames, n >= 3, 3)`` in a frame of its own: origin the centroid (as a best pose
    places it), axes along markers ``a`` to ``b``, then normal to them and ``c`` (NaN if the
    three are collinear), chosen in frame ``typical`` as the two farthest apart and the one
    farthest from their line, which makes the axes least sensitive to noise. A compiled
    kernel."""
    n_markers = markers.shape[1]
    x = markers[typical]
    a = b = c = 0
    longest = farthest = -1.0
    for i in range(n_markers):
        for j in range(i + 1, n_markers):
            length = np.sqrt(
                (x[j, 0] - x[i, 0]) ** 2 + (x[j, 1] - x[i, 1]) ** 2 + (x[j, 2] - x[i, 2]) ** 2
            )
            if length > longest:
                a, b, longest = i, j, length
    ux, uy, uz = x[b, 0] - x[a, 0], x[b, 1] - x[a, 1], x[b, 2] - x[a, 2]
    for k in range(n_markers):
        px, py, pz = x[k, 0] - x[a, 0], x[k, 1] - x[a, 1], x[k, 2] - x[a, 2]
        distance = (uy * pz - uz * py) ** 2 + (uz * px - ux * pz) ** 2 + (ux * py - uy * px) ** 2
        if distance > farthest:
            c, farthest = k, distance
    n_frames = markers.shape[0]
    # The axes' reciprocal lengths in a loop of their own, where the roots and divisions of
    # many frames overlap instead of waiting on each other; the axes are made again after.
    scales = np.empty(3 * n_frames)
    for f in range(n_frames):
        ux, uy, uz, vx, vy, vz, wx, wy, wz = _triad_axes(markers, f, a, b, c)
        scales[3 * f] = ux * ux + uy * uy + uz * uz
        scales[3 * f + 1] = vx * vx + vy * vy + vz * vz
        scales[3 * f + 2] = wx * wx + wy * wy + wz * wz
    for k in range(scales.size):
        scales[k] = 1.0 / np.sqrt(scales[k])
    for f in range(n_frames):
        cx = cy = cz = 0.0
        for m in range(n_markers):
            cx += markers[f, m, 0]
            cy += markers[f, m, 1]
            cz += markers[f, m, 2]
        cx, cy, cz = cx / n_markers, cy / n_markers, cz / n_markers
        ux, uy, uz, vx, vy, vz, wx, wy, wz = _triad_axes(markers, f, a, b, c)
        scale = scales[3 * f]
        ux, uy, uz = ux * scale, uy * scale, uz * scale
        scale = scales[3 * f + 1]
        vx, vy, vz = vx * scale, vy * scale, vz * scale
        scale = scales[3 * f + 2]
        wx, wy, wz = wx * scale, wy * scale, wz * scale
        for m in range(n_markers):
            dx = markers[f, m, 0] - cx
            dy = markers[f, m, 1] - cy
            dz = markers[f, m, 2] - cz
            local[f, m, 0] = ux * dx + uy * dy + uz * dz
            local[f, m, 1] = vx * dx + vy * dy + vz * dz
            local[f, m, 2] = wx * dx + wy * dy + wz * dz


@kernel
def _triad_axes(
    markers: np.ndarray, f: int, a: int, b: int, c: int
) -> tuple[float, float, float, float, float, float, float, float, float]:
    """The axes ``u, v, w`` of :func:`_triad_local`'s frame of frame ``f`` of ``markers``
    ``(n_frames, n, 3)`` [mm], not yet of unit length: ``u`` from marker ``a`` to ``b``,
    ``w = u x (c - a)``, ``v = w x u``, a right-handed frame (a proper rotation once
    normalised). A compiled kernel."""
    ux = markers[f, b, 0] - markers[f, a, 0]
    uy = markers[f, b, 1] - markers[f, a, 1]
    uz = markers[f, b, 2] - markers[f, a, 2]
    px = markers[f, c, 0] - markers[f, a, 0]
    py = markers[f, c, 1] - markers[f, a, 1]
    pz = markers[f, c, 2] - markers[f, a, 2]
    wx, wy, wz = uy * pz - uz * py, uz * px - ux * pz, ux * py - uy * px
    vx, vy, vz = wy * uz - wz * uy, wz * ux - wx * uz, wx * uy - wy * ux
    return ux, uy, uz, vx, vy, vz, wx, wy, wz


@kernel
def _spread(local: np.ndarray, typical: int) -> tuple[float, float, float, float]:
    """``max u``, ``mean u``, ``rms u`` and ``u_typical`` [mm] of the distances
    ``u_f = |local[f] - M|`` of the frames ``local`` ``(n_frames, n, 3)`` [mm] from their mean
    ``M`` (:func:`_rigid_misfits`). A compiled kernel."""
    n_frames, n_markers = local.shape[0], local.shape[1]
    mean = _frame_mean(local)
    highest = total = total_sq = at_typical = 0.0
    for f in range(n_frames):
        norm_sq = 0.0
        for m in range(n_markers):
            for i in range(3):
                norm_sq += (local[f, m, i] - mean[m, i]) ** 2
        norm = np.sqrt(norm_sq)
        highest = max(highest, norm)  # a NaN (collinear markers) stays in the mean
        total += norm
        total_sq += norm_sq
        if f == typical:
            at_typical = norm
    return highest, total / n_frames, np.sqrt(total_sq / n_frames), at_typical


def residuals(
    shape: np.ndarray, rotation: np.ndarray, translation: np.ndarray, markers: np.ndarray
) -> np.ndarray:
    """Each marker's distance ``(n_frames, n)`` [mm] from ``shape`` ``(n, 3)`` posed by
    ``(R, t)`` in every frame (NaN where missing)."""
    markers = kernel_array(markers)
    distance = np.empty(markers.shape[:2])
    _residuals(
        kernel_array(shape), kernel_array(rotation), kernel_array(translation), markers, distance
    )
    return distance


@kernel
def _residuals(
    shape: np.ndarray,
    rotation: np.ndarray,
    translation: np.ndarray,
    markers: np.ndarray,
    distance: np.ndarray,
) -> None:
    """``distance`` ``(n_frames, n)`` [mm] of :func:`residuals`. A compiled kernel."""
    for f in range(markers.shape[0]):
        for m in range(markers.shape[1]):
            total = 0.0
            for i in range(3):
                fitted = translation[f, i]
                for j in range(3):
                    fitted += rotation[f, i, j] * shape[m, j]
                total += (markers[f, m, i] - fitted) ** 2
            distance[f, m] = np.sqrt(total)
