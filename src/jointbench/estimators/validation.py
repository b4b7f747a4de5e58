"""Input checks shared by the estimators. Every failure is a ``ValueError`` naming the problem.

The registry applies :func:`check_input` to every registered estimator (to a batch of trials,
:func:`check_input_many`, which decides and words each trial's error as :func:`check_input`
does), so a new estimator is held to these checks without code of its own; estimators still
call :func:`check_markers` with their own minimum numbers of frames and markers.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from jointbench.numerics import reuse
from jointbench.numerics.compiled import kernel, kernel_array
from jointbench.numerics.magnitudes import first_beyond, largest_coordinate
from jointbench.numerics.small import add_outer, symmetric_into

__all__ = [
    "ARRAY_NAMES",
    "CAPTURE_VOLUME",
    "MAX_CAPTURE_SPAN_MM",
    "MAX_JOINED_SPAN_MM",
    "MAX_SCALE_CHANGE",
    "MAX_SPAN_MM",
    "MIN_SPAN_MM",
    "ONE_SEGMENT",
    "TWO_SEGMENTS",
    "CheckedTrials",
    "check_counts",
    "check_input",
    "check_input_many",
    "check_markers",
    "check_moves",
    "check_not_collinear",
    "check_rotates",
    "check_same_frames",
    "check_span",
    "cluster_span",
    "frames_listed",
    "frames_off_scale",
    "prepare_trials",
    "scale_change",
    "span_bound",
    "span_problem",
    "typical_span",
]

#: The marker arrays each estimator kind takes, in order.
ARRAY_NAMES = {"center": ("markers",), "axis": ("markers",), "joint_center": ("proximal", "distal")}

# What to do with the frames of a gap, however it is stored: the fits take complete frames
# only, and a Recording reads NaN, inf and (0, 0, 0) as gaps (the last unless its marker moves
# through the origin: jointbench.io.recording.origin_gaps) and leaves their frames out.
_GAP_ADVICE = (
    "drop those frames before fitting, or fit a jointbench.io.Recording, which leaves out "
    "frames with gaps"
)

# A trajectory counts as a straight line when its second principal spread is below this
# fraction of its first; the same relative level at which check_not_collinear calls markers
# collinear, far below any rotation a marker set can resolve.
_LINE_RTOL = 1e-6
# The same level as a ratio of eigenvalues (squared singular values) of a trajectory's scatter.
_LINE_RATIO = _LINE_RTOL**2
# A scatter matrix whose principal 2 x 2 minors sum to more than this times its squared trace
# is not a line's: the sum is at most three times the product of the two largest eigenvalues,
# and the largest at most the trace, so its middle eigenvalue exceeds a thousand times
# _LINE_RATIO times the largest, a margin rounding in the minors or the eigenvalue solver
# cannot close. Only the other matrices need their eigenvalues.
_CURVED_MINORS = 3e3 * _LINE_RATIO

# The largest change from frame 0 [mm], relative to frame 0's largest coordinate (at least
# 1 mm), of markers that do not move: rounding.
_MOVE_TOL_MM = 1e-9

_FLOAT64 = np.dtype(np.float64)

#: A cluster's markers lie further apart than this [mm] (:func:`typical_span`): a marker is a few
#: millimetres across, so two cannot sit closer, and a cluster this small is one measured in
#: another unit (metres read as millimetres).
MIN_SPAN_MM = 1.0
#: ... and closer than this [mm]: no rigid cluster on one human body segment spans more.
#: Segment lengths scale with stature H (Winter, *Biomechanics and Motor Control of Human
#: Movement*, after Drillis and Contini): the longest segment that carries a cluster, the head,
#: arms and trunk, runs from the vertex (1.0 H) to the greater trochanter (0.530 H), 0.47 H:
#: 1.28 m in the tallest person measured (2.72 m); a thigh is 0.245 H, a pelvis 0.191 H wide.
#: 1.5 m leaves room for markers on wands off the skin. A cluster in millimetres read as
#: centimetres is 10 times its size: a thigh (about 320 mm) reads 3.2 m and is refused, a
#: cluster under 150 mm (a thumb's, 11 to 40 mm) reads as a real one and cannot be told.
MAX_SPAN_MM = 1_500.0
#: The markers of two segments that meet at a joint lie closer together than this [mm]: each
#: lies within its own segment's extent of the joint (:data:`MAX_SPAN_MM`). It catches the
#: factor of 10 where each cluster is small (plates of 100 mm read 1 m) but the two lie far
#: apart (a thigh's and a shank's plates, their markers more than 300 mm apart: 3 m read in
#: centimetres).
MAX_JOINED_SPAN_MM = 2 * MAX_SPAN_MM
#: A reference fixed in the lab (a treadmill's frame, a force plate, a wand frame, a lab-fixed
#: "world" cluster) is no body segment, and may span metres: its markers, and the moving ones
#: with them, lie closer together than this [mm], what one optical capture volume spans. The
#: largest, built for sprints and team sports, are some tens of metres long; 100 m bounds them
#: with room and still refuses millimetres read as metres (a treadmill 2 m across reads 2 km).
#: Millimetres read as centimetres (20 m) it lets through: the moving markers tell that unit
#: only where their cluster spans over a tenth of :data:`MAX_SPAN_MM`; a more compact one
#: passes read 10 times its size, and so does the answer. So this bound holds only a reference
#: the user states fixed in the lab (:data:`jointbench.io.segments.LAB_FIXED_KEYWORD`); any
#: other is a segment's, and a still wand read 10 times its size is refused as one.
MAX_CAPTURE_SPAN_MM = 100_000.0
#: What :data:`MAX_SPAN_MM` bounds, :data:`MAX_JOINED_SPAN_MM` and
#: :data:`MAX_CAPTURE_SPAN_MM`, in messages.
ONE_SEGMENT = "the markers of any one human body segment span"
TWO_SEGMENTS = "the markers of two human body segments joined at a joint span"
CAPTURE_VOLUME = "the markers of one optical capture volume span"

#: No frame of one cluster is this many times larger or smaller than its typical frame: units
#: differ by a factor of 10 at least (centimetres and millimetres; 25.4 for inches, 1000 for
#: metres), and its square root, the geometric middle between one and ten, puts a frame with
#: the scale it lies nearer. Skin markers change their distances by tens of percent, not
#: three times (:func:`frames_off_scale`).
MAX_SCALE_CHANGE = math.sqrt(10.0)

# Frames the check of a cluster's size reads at most, evenly spaced: a median of this many
# tells a unit 10 or 1000 times off at any gap or glitch a check before it lets through.
_SPAN_FRAMES = 25


def _real_array(markers: object, name: str) -> np.ndarray:
    """``markers`` as a real numeric array of its own dtype (a float64 one as it is); complex,
    boolean, non-numeric and masked data raise."""
    if type(markers) is np.ndarray and markers.dtype is _FLOAT64:
        return markers  # the common case, before the checks' own cost
    if np.ma.isMaskedArray(markers):
        mask = np.ma.getmaskarray(markers)
        if mask.any():
            frame, marker = _first_sample(mask)
            raise ValueError(
                f"{name} is a masked array with masked values (first at marker {marker}, frame "
                f"{frame}; {int(mask.sum())} in all); masks are not read: {_GAP_ADVICE}"
            )
        markers = np.ma.getdata(markers)
    try:
        array = np.asarray(markers)
    except ValueError as error:
        raise ValueError(f"{name} is not a regular numeric array ({error})") from None
    if array.dtype.kind == "c":
        raise ValueError(
            f"{name} is complex ({array.dtype}); marker coordinates must be real numbers [mm]"
        )
    if array.dtype.kind not in "iuf":
        raise ValueError(
            f"{name} has dtype {array.dtype}; marker coordinates must be real numbers [mm]"
        )
    return array


def _as_float64(array: np.ndarray, name: str) -> np.ndarray:
    """The real numeric ``array`` ``(n_frames, n_markers, 3)`` as float64, or ``ValueError``
    where another float dtype does not hold its coordinates: an inf in a narrower one (float32,
    float16) is what a value beyond the largest it holds becomes when it is stored or computed
    in it (or a gap stored so), and a wider one's (longdouble) value beyond float64's largest
    becomes inf in float64. Either would otherwise read as a bare "NaN or inf". Integers
    convert exactly up to 2^53 mm, far past every coordinate bound the checks set."""
    if array.dtype.kind != "f" or array.dtype == _FLOAT64:
        return array.astype(float, copy=False)
    with np.errstate(over="ignore"):  # an overflow is reported below, by name
        converted = array.astype(float, copy=False)
    narrow = array.dtype.itemsize < _FLOAT64.itemsize
    # In a wider float, only the values that float64 turned into inf: an inf given is a gap's,
    # which the checks of the samples name.
    infinite = np.isinf(converted) if narrow else np.isinf(converted) & np.isfinite(array)
    if not infinite.any():
        return converted
    frame, marker = _first_sample(infinite)
    count = int(infinite.any(axis=-1).sum())
    largest = np.finfo(array.dtype if narrow else _FLOAT64)
    if narrow:
        raise ValueError(
            f"{name} is {array.dtype} and holds inf at marker {marker}, frame {frame} ({count} "
            f"in all): what a value beyond the largest {largest.dtype} holds ({largest.max:.3g}) "
            f"becomes when it is stored or computed in {array.dtype} (a corrupt sample or a "
            f"wrong unit), or a gap stored as inf; {_GAP_ADVICE}"
        )
    value = np.format_float_scientific(
        array[frame, marker][infinite[frame, marker]][0], 2, trim="-"
    )
    raise ValueError(
        f"{name} is {array.dtype} and has a coordinate of {value} mm at marker {marker}, "
        f"frame {frame} ({count} in all), beyond the largest float64 holds "
        f"({largest.max:.3g}), which the fits compute in: a corrupt sample or a wrong unit; "
        "drop those frames before fitting"
    )


def _first_sample(flags: np.ndarray) -> tuple[int, int]:
    """``(frame, marker)`` of the first flagged sample of a ``(n_frames, n_markers, ...)`` mask."""
    per_sample = flags.reshape(flags.shape[0], flags.shape[1], -1).any(axis=-1)
    frame, marker = np.argwhere(per_sample)[0]
    return int(frame), int(marker)


def check_markers(
    markers: object, *, min_frames: int = 1, min_markers: int = 1, name: str = "markers"
) -> np.ndarray:
    """Return ``markers`` as a float64 ``(n_frames, n_markers, 3)`` array, or raise ``ValueError``.

    Rejects complex, boolean or non-numeric data and masked arrays with masked values (the
    mask would otherwise be dropped silently), checks the shape, rejects NaN/inf, coordinates
    beyond :func:`~jointbench.numerics.magnitudes.largest_coordinate` and samples at exactly
    ``(0, 0, 0)`` (how some C3D readers store gaps), naming marker and frame, and
    checks the minimum numbers of frames and markers a method needs.
    """
    array = _shaped(markers, name)
    _refuse(array, name, _first_failure(array, _SAMPLES))
    return check_counts(array, min_frames=min_frames, min_markers=min_markers, name=name)


def check_counts(
    markers: np.ndarray, *, min_frames: int = 1, min_markers: int = 1, name: str = "markers"
) -> np.ndarray:
    """Return ``markers`` ``(n_frames, n_markers, 3)`` [mm], an array :func:`check_markers`
    passed, or raise the ``ValueError`` it raises for fewer frames or markers than a method
    needs: the part of its checks that depends on the method, for a caller holding an array
    whose samples it checked."""
    n_frames, n_markers, _ = markers.shape
    if n_frames < min_frames:
        raise ValueError(f"{name} has {n_frames} frames; this method needs at least {min_frames}")
    if n_markers < min_markers:
        raise ValueError(
            f"{name} has {n_markers} markers; this method needs at least {min_markers}"
        )
    return markers


def _shaped(markers: object, name: str) -> np.ndarray:
    """``markers`` as a float64 array of shape ``(n_frames, n_markers, 3)``, not empty; what
    :func:`_real_array` refuses, a wrong shape and an empty array raise."""
    array = _real_array(markers, name)
    if array.ndim != 3 or array.shape[-1] != 3:
        raise ValueError(f"{name} must be shaped (n_frames, n_markers, 3), got shape {array.shape}")
    if array.size == 0:
        raise ValueError(f"{name} is empty (shape {array.shape})")
    return _as_float64(array, name)


# The checks _first_failures can make, as bits: the samples, the motion from frame 0 and the
# straightness of the trajectories; and the failures it reports, in the order their errors are
# raised (0: none).
_SAMPLES, _MOVES, _LINES, _SCALE = 1, 2, 4, 8
_NOT_FINITE, _TOO_LARGE, _AT_ORIGIN, _STILL, _STRAIGHT, _OFF_SCALE = 1, 2, 3, 4, 5, 6


def _refuse(array: np.ndarray, name: str, failure: int) -> None:
    """Raise the ``ValueError`` for the ``failure`` :func:`_first_failures` found in ``array``
    ``(n_frames, n_markers, 3)``, locating the offending samples only then; nothing for 0."""
    if not failure:
        return
    if failure == _NOT_FINITE:
        bad = ~np.isfinite(array)
        frame, marker = _first_sample(bad)
        raise ValueError(
            f"{name} contains NaN or inf at marker {marker}, frame {frame} "
            f"({int(bad.any(axis=-1).sum())} in all); {_GAP_ADVICE}"
        )
    if failure == _TOO_LARGE:
        frame, marker, value, bound, count = first_beyond(array)
        raise ValueError(
            f"{name} has a coordinate of {value:.3g} mm at marker {marker}, frame {frame} "
            f"({count} in all), beyond the {bound:.3g} mm whose squares float64 can sum over "
            f"its {array.shape[0] * array.shape[1]} samples: a corrupt sample or a wrong unit; "
            "drop those frames before fitting"
        )
    if failure == _AT_ORIGIN:
        at_origin = ~array.any(axis=-1)
        frame, marker = _first_sample(at_origin)
        raise ValueError(
            f"{name} has a sample at exactly (0, 0, 0) at marker {marker}, frame {frame} "
            f"({int(at_origin.sum())} in all): some C3D readers store gaps as zeros; if these "
            f"are gaps, {_GAP_ADVICE} (it reads (0, 0, 0) as a gap unless its marker moves "
            "through the origin)"
        )
    if failure == _STILL and array.shape[0] == 1:
        # No motion is seen in one frame, and none is refused: the markers may well move.
        raise ValueError(f"{name} has 1 frame: no motion to fit a centre or an axis to")
    if failure == _STILL:
        raise ValueError(f"{name} do not move: every marker stays at one point in every frame")
    if failure == _STRAIGHT:
        raise ValueError(
            f"{name} do not rotate: every marker moves along a straight line, so there is no "
            "centre or axis of rotation"
        )
    if failure == _OFF_SCALE:
        judged = frames_off_scale(array)
        frames = judged[0]
        named = scale_change(array, judged, f"frame {frames[0]}", frames, "millimetres")
        raise ValueError(
            f"{name} {named}, or markers not of one cluster. Marker positions are millimetres "
            "in every frame"
        )


def scale_change(
    markers: np.ndarray,
    judged: tuple[np.ndarray, np.ndarray, np.ndarray],
    first: str,
    frames: np.ndarray,
    unit: str,
) -> str:
    """How a refusal of the frames of the cluster ``markers`` ``(n_frames, n, 3)`` [mm] off its
    scale names them, ``judged`` what :func:`frames_off_scale` returns of them: the size of
    the markers the first of them shows, typical (over the other frames) and there, ``first``
    (in the caller's words), and all of them, ``frames`` (increasing, as the caller numbers
    them); how many times larger or smaller than the rest they are, and which of the two groups
    is a body segment's size in ``unit`` (in words, "millimetres", "the file's 'mm'"), that
    either group may be the one in another unit."""
    off, typical, spans = judged
    row = int(off[0])
    typical_mm, span_mm = float(typical[row]), float(spans[row])
    complete = bool(np.isfinite(markers[row]).all())
    which = "markers" if complete else f"of the markers shown at {first}"
    others = "other frames" if complete else "other frames that show them"
    times = (
        f"{typical_mm / span_mm:.4g} times smaller"
        if span_mm < typical_mm
        else f"{span_mm / typical_mm:.4g} times larger"
    )
    one = frames.size == 1
    return (
        f"change size between frames: the farthest two {which} lie {typical_mm:.3g} mm apart "
        f"(median over the {others}) but {span_mm:.3g} mm at {first} ({frames.size} "
        f"frame{'' if one else 's'} in all, {frames_listed(frames)}, each with every distance "
        f"more than {MAX_SCALE_CHANGE:.3g} times larger or smaller than in any frame of the "
        f"typical size): {'that frame is' if one else 'those frames are'} {times} than the "
        f"rest: {_in_which_unit(typical_mm, span_mm, unit)}"
    )


def _in_which_unit(typical_mm: float, span_mm: float, unit: str) -> str:
    """Which of two groups of frames, the rest of typical size ``typical_mm`` [mm] and those
    of size ``span_mm`` [mm], is in ``unit`` (in words) and which in another, as far as a body
    segment's size (:func:`span_bound`) tells: either may be, the rest as well."""
    rest = span_bound(typical_mm, MAX_SPAN_MM, ONE_SEGMENT) is None
    those = span_bound(span_mm, MAX_SPAN_MM, ONE_SEGMENT) is None
    if rest and not those:
        return f"the rest are a body segment's size in {unit} and those frames in another unit"
    if those and not rest:
        return f"those frames are a body segment's size in {unit} and the rest in another unit"
    return f"one of the two groups is in another unit than {unit} (their sizes cannot tell which)"


def frames_listed(frames: np.ndarray, most: int = 4) -> str:
    """The increasing frame numbers ``frames`` as runs in words ("frames 3, 7 to 9", "frame
    3"), the first ``most`` runs and a count of the rest."""
    breaks = np.flatnonzero(np.diff(frames) != 1) + 1
    runs = [(int(run[0]), int(run[-1])) for run in np.split(frames, breaks)]
    words = [f"{a}" if a == b else f"{a} to {b}" for a, b in runs[:most]]
    rest = f" and {len(runs) - most} more runs" if len(runs) > most else ""
    return f"frame{'' if frames.size == 1 else 's'} {', '.join(words)}{rest}"


# The failures and spans arrays of a call of _first_failures that needs only its return value.
_UNRECORDED = np.empty(0, dtype=np.int8)
_UNMEASURED = np.empty(0)


def _first_failure(
    markers: object,
    checks: int,
    move_tol_mm: float = _MOVE_TOL_MM,
    span: np.ndarray = _UNMEASURED,
) -> int:
    """:func:`_first_failures` of one trial ``markers`` ``(n_frames, n_markers, 3)``, a batch
    of one: its failure, or 0, and its size [mm] written into ``span`` ``(1,)`` unless it is
    empty. Made on every call but for the very array a checked call's input checks passed and
    handed to the package's own fit (:func:`passed`), which writes to no array it reads: an
    estimator may write into the markers it was given before it hands them to a fit, and a
    user's is handed copies, outside the scope that holds what passed."""
    if not span.size and (move_tol_mm == _MOVE_TOL_MM or not checks & _MOVES):
        held = reuse.kept_for(_PASSED, markers)
        if held is not None and not checks & ~held:
            return 0  # every check asked passed on these very markers
    return _first_failures(kernel_array(markers)[None], checks, move_tol_mm, _UNRECORDED, span)


#: What a checked call holds, in its scope, of each array its input checks passed
#: (:func:`passed`): the checks of :func:`_first_failures`, as bits.
_PASSED = "input checks passed"

#: The checks of :func:`_first_failures` that :func:`check_input` makes of each array, by kind.
_INPUT_CHECKS = {
    "center": _SAMPLES | _MOVES | _LINES | _SCALE,
    "axis": _SAMPLES | _MOVES | _LINES | _SCALE,
    "joint_center": _SAMPLES | _SCALE,
}


def passed(kind: str, arrays: tuple[np.ndarray, ...]) -> None:
    """State, in the open scope of one checked call (:func:`jointbench.numerics.reuse.one_call`),
    that ``arrays``, as :func:`check_input` returned them for ``kind``, passed its checks: the
    package's own fit that checks these very arrays again (:func:`check_markers`,
    :func:`check_moves`, :func:`check_rotates`) then does not repeat the compiled pass; the
    counts of frames and markers a method needs are still checked. Outside a scope, nothing."""
    checks = _INPUT_CHECKS[kind]
    for array in arrays:
        reuse.keep(_PASSED, array, checks)


@kernel
def _first_failures(
    markers: np.ndarray, checks: int, move_tol_mm: float, failures: np.ndarray, spans: np.ndarray
) -> int:
    """The first check each trial of ``markers`` ``(n_trials, n_frames, n_markers, 3)`` [mm]
    fails, of those asked, in this order, or 0: written into ``failures`` ``(n_trials,)``
    (unless it is empty), and the first trial's that fails one returned (0 if none does).
    ``checks`` asks for some, as bits:

    * :data:`_SAMPLES`: :data:`_NOT_FINITE`, a coordinate is NaN or inf; :data:`_TOO_LARGE`,
      one is beyond :func:`~jointbench.numerics.magnitudes.largest_coordinate` (a bound that
      also keeps the sums of the checks below finite; the line test alone refuses it too);
      :data:`_AT_ORIGIN`, a sample is exactly ``(0, 0, 0)``;
    * :data:`_MOVES`: :data:`_STILL`, no coordinate changes from frame 0 by more than
      ``move_tol_mm`` times the largest absolute coordinate of frame 0 (at least 1 mm);
    * :data:`_LINES`: :data:`_STRAIGHT`, every marker's trajectory is a line, the second
      eigenvalue of its scatter matrix about its mean position at most :data:`_LINE_RATIO`
      times the largest (never for fewer than three frames, which always lie on a line);
    * :data:`_SCALE`: :data:`_OFF_SCALE`, some frames lie off the cluster's scale, in another
      unit than the rest (:func:`frames_off_scale`).

    Unless ``spans`` is empty, each trial's :func:`typical_span` over :data:`_SPAN_FRAMES`
    frames is written into it ``(n_trials,)`` [mm], failing or not: the size check then needs
    no kernel call of its own.

    A compiled kernel: the checks run before every fit, and NumPy's passes over the array and
    its per-call overhead on 3 x 3 matrices cost as much as a closed-form fit.
    """
    n_trials, n_frames, n_markers, _ = markers.shape
    scatter = np.empty((3, 3))
    mean = np.empty(3)
    totals = np.empty((n_markers, 3))
    scaled = n_frames if checks & _SCALE else 0  # the scale check's buffers, where asked
    off = np.empty(scaled, dtype=np.bool_)
    extents = np.empty(scaled)
    moves, lines = checks & _MOVES, checks & _LINES
    first_failure = 0
    for t in range(n_trials):
        trial = markers[t]
        failure = 0
        # One pass over the samples for the checks of each sample, the motion from frame 0 and
        # each trajectory's sum (for its mean): each is what its own pass would give, and a
        # check is read only where the checks before it passed.
        # Without a branch per sample: x * 0 is NaN for a NaN or infinite x, else +-0, so the
        # sum of those is 0 exactly when every coordinate is finite.
        # One probe per axis, likewise: each is 0 exactly when its coordinates are finite.
        probe_x = probe_y = probe_z = 0.0
        # The largest |coordinate| as three running maxima, one per axis, that advance side by
        # side (one alone waits on each comparison); their largest is the same number.
        largest_x = largest_y = largest_z = 0.0
        origins = 0
        # The motion from frame 0 per axis, likewise.
        spread_x = spread_y = spread_z = 0.0
        totals[:] = 0.0
        for f in range(n_frames):
            for m in range(n_markers):
                x, y, z = trial[f, m, 0], trial[f, m, 1], trial[f, m, 2]
                probe_x += x * 0.0
                probe_y += y * 0.0
                probe_z += z * 0.0
                largest_x = max(largest_x, abs(x))
                largest_y = max(largest_y, abs(y))
                largest_z = max(largest_z, abs(z))
                origins += (x == 0.0) & (y == 0.0) & (z == 0.0)
                if moves and f > 0:
                    spread_x = max(spread_x, abs(x - trial[0, m, 0]))
                    spread_y = max(spread_y, abs(y - trial[0, m, 1]))
                    spread_z = max(spread_z, abs(z - trial[0, m, 2]))
                if lines:
                    totals[m, 0] += x
                    totals[m, 1] += y
                    totals[m, 2] += z
        largest = max(max(largest_x, largest_y), largest_z)
        probe = probe_x + probe_y + probe_z
        spread = max(max(spread_x, spread_y), spread_z)
        if checks & _SAMPLES:
            if not probe == 0.0:
                failure = _NOT_FINITE
            elif largest > largest_coordinate(n_frames * n_markers):
                failure = _TOO_LARGE
            elif origins > 0:
                failure = _AT_ORIGIN
        elif lines and largest > largest_coordinate(n_frames * n_markers):
            failure = _TOO_LARGE  # the line test's sums would overflow
        if failure == 0 and moves:
            first = 0.0
            for m in range(n_markers):
                for i in range(3):
                    first = max(first, abs(trial[0, m, i]))
            if spread <= move_tol_mm * max(1.0, first):
                failure = _STILL
        if failure == 0 and lines and n_frames >= 3:
            every = True
            for p in range(n_markers):
                for i in range(3):
                    mean[i] = totals[p, i] / n_frames
                sums = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
                for f in range(n_frames):
                    sums = add_outer(
                        sums,
                        trial[f, p, 0] - mean[0],
                        trial[f, p, 1] - mean[1],
                        trial[f, p, 2] - mean[2],
                    )
                symmetric_into(sums, scatter)
                trace = scatter[0, 0] + scatter[1, 1] + scatter[2, 2]
                minors = (
                    (scatter[0, 0] * scatter[1, 1] - scatter[0, 1] * scatter[0, 1])
                    + (scatter[0, 0] * scatter[2, 2] - scatter[0, 2] * scatter[0, 2])
                    + (scatter[1, 1] * scatter[2, 2] - scatter[1, 2] * scatter[1, 2])
                )
                if minors > _CURVED_MINORS * trace * trace:
                    every = False  # so far above the line that the eigenvalues need no solver
                    break
                eigenvalues = np.linalg.eigvalsh(scatter)
                if eigenvalues[1] > _LINE_RATIO * eigenvalues[2]:
                    every = False
                    break
            if every:
                failure = _STRAIGHT
        if failure == 0 and checks & _SCALE and _scale_flags(trial, off, extents) > 0:
            failure = _OFF_SCALE
        if len(failures):
            failures[t] = failure
        if len(spans):
            spans[t] = typical_span(trial, _SPAN_FRAMES)
        if first_failure == 0:
            first_failure = failure
    return first_failure


@kernel
def _extent(markers: np.ndarray, frame: int) -> tuple[float, float]:
    """The largest and the smallest squared distance [mm^2] between two markers of ``frame``
    of ``markers`` ``(n_frames, n, 3)`` [mm] that it shows (a marker with a NaN coordinate is
    not shown): ``(-1, inf)`` where it shows fewer than two. A compiled kernel."""
    n_markers = markers.shape[1]
    largest, smallest = -1.0, np.inf
    for a in range(n_markers):
        for b in range(a + 1, n_markers):
            dx = markers[frame, a, 0] - markers[frame, b, 0]
            dy = markers[frame, a, 1] - markers[frame, b, 1]
            dz = markers[frame, a, 2] - markers[frame, b, 2]
            squared = dx * dx + dy * dy + dz * dz
            if squared > largest:  # False for a NaN: a pair not shown
                largest = squared
            if squared < smallest:
                smallest = squared
    return largest, smallest


@kernel
def typical_span(markers: np.ndarray, n_sampled: int) -> float:
    """The typical size [mm] of a cluster ``markers`` ``(n_frames, n, 3)`` [mm]: the median,
    over at most ``n_sampled`` evenly spaced frames that show two of its markers or more (a
    marker with a NaN coordinate is not shown), of the largest distance between two of them;
    NaN where none does. A compiled kernel."""
    n_frames = markers.shape[0]
    stride = max(1, -(-n_frames // max(n_sampled, 1)))
    spans = np.empty(n_frames // stride + 1)
    seen = 0
    for f in range(0, n_frames, stride):
        largest = _extent(markers, f)[0]
        if largest >= 0.0:
            spans[seen] = math.sqrt(largest)
            seen += 1
    if seen == 0:
        return np.nan
    return np.median(spans[:seen])


@kernel
def _frame_spans(markers: np.ndarray, spans: np.ndarray, smallest: np.ndarray) -> None:
    """The largest and the smallest distance [mm] between two markers of each frame of
    ``markers`` ``(n_frames, n >= 2, 3)`` [mm] (finite), written into ``spans`` and
    ``smallest`` ``(n_frames,)``. A compiled kernel."""
    for f in range(markers.shape[0]):
        largest, least = _extent(markers, f)
        spans[f], smallest[f] = math.sqrt(largest), math.sqrt(least)


@kernel
def _scale_flags(markers: np.ndarray, off: np.ndarray, spans: np.ndarray) -> int:
    """How many frames of the cluster ``markers`` ``(n_frames, n, 3)`` [mm] (finite) lie off
    its scale, as every distance of a frame in another unit does: both the largest and the
    smallest distance between two of its markers (the smallest where its median is not 0, one
    marker given twice) more than :data:`MAX_SCALE_CHANGE` times larger than in every frame
    within that factor of their medians over the frames, or smaller than in every such frame,
    and every distance between two of its markers beyond that factor of the same two's median
    over those frames (:func:`_every_pair_off`). Frames apart from the others by that gap, not
    a cluster whose size wanders (markers not of one cluster, scattered at random, whose
    rigidity is the support verdict's to judge), nor one that a marker left (the others keep
    their distances, though the one it left may have been the smallest). Each frame's flag is
    written into ``off`` ``(n_frames,)`` and, unless every frame's largest distance lies within
    the factor of every other's (none is off then, and the pass over them ends there), that
    distance [mm] into ``spans`` ``(n_frames,)``. None for fewer than three markers: two
    have one distance, which one marker gap-filled along a chord, or a ghost taken for it,
    changes as a unit does; of three, the two others keep theirs. A compiled kernel."""
    n_frames, n_markers, _ = markers.shape
    off[:] = False
    if n_markers < 3:
        return 0
    low, high = np.inf, 0.0
    for f in range(n_frames):
        squared = _extent(markers, f)[0]
        low, high = min(low, squared), max(high, squared)
    if high <= MAX_SCALE_CHANGE * MAX_SCALE_CHANGE * low:
        return 0
    smallest = np.empty(n_frames)
    _frame_spans(markers, spans, smallest)
    typical, typical_least = np.median(spans), np.median(smallest)
    told = typical_least > 0.0  # duplicated markers: the smallest distance tells no scale
    # The range of the frames on the cluster's scale: within the factor of both medians.
    low, high, low_least, high_least = np.inf, -np.inf, np.inf, -np.inf
    on_scale = np.zeros(n_frames, dtype=np.bool_)
    for f in range(n_frames):
        if (
            typical <= MAX_SCALE_CHANGE * spans[f]
            and spans[f] <= MAX_SCALE_CHANGE * typical
            and (
                not told
                or (
                    typical_least <= MAX_SCALE_CHANGE * smallest[f]
                    and smallest[f] <= MAX_SCALE_CHANGE * typical_least
                )
            )
        ):
            low, high = min(low, spans[f]), max(high, spans[f])
            low_least, high_least = min(low_least, smallest[f]), max(high_least, smallest[f])
            on_scale[f] = True
    if high < low:
        return 0  # no frame on both medians' scale: no scale to hold the others to
    pairs = _pair_medians(markers, on_scale)
    count = 0
    for f in range(n_frames):
        larger = (
            spans[f] > MAX_SCALE_CHANGE * high
            and (not told or smallest[f] > MAX_SCALE_CHANGE * high_least)
            and _every_pair_off(markers, f, pairs, True)
        )
        smaller = (
            spans[f] * MAX_SCALE_CHANGE < low
            and (not told or smallest[f] * MAX_SCALE_CHANGE < low_least)
            and _every_pair_off(markers, f, pairs, False)
        )
        off[f] = larger or smaller
        count += off[f]
    return count


@kernel
def _pair_medians(markers: np.ndarray, frames: np.ndarray) -> np.ndarray:
    """The median over the frames ``frames`` ``(n_frames,)`` bool of the distance [mm] between
    each two markers of ``markers`` ``(n_frames, n, 3)`` [mm] (finite), ``(n (n - 1) / 2,)``,
    the pairs in the order (0, 1), (0, 2), ..., (1, 2), ... A compiled kernel."""
    n_markers = markers.shape[1]
    rows = np.flatnonzero(frames)
    distances = np.empty((n_markers * (n_markers - 1) // 2, rows.size))
    for column in range(rows.size):
        pair = 0
        for a in range(n_markers):
            for b in range(a + 1, n_markers):
                distances[pair, column] = _distance(markers, rows[column], a, b)
                pair += 1
    medians = np.empty(distances.shape[0])
    for pair in range(distances.shape[0]):
        medians[pair] = np.median(distances[pair])
    return medians


@kernel
def _every_pair_off(markers: np.ndarray, frame: int, typical: np.ndarray, larger: bool) -> bool:
    """Whether at ``frame`` of ``markers`` ``(n_frames, n, 3)`` [mm] every two markers lie more
    than :data:`MAX_SCALE_CHANGE` times further apart than their typical distance ``typical``
    ``(n (n - 1) / 2,)`` [mm] (:func:`_pair_medians`) (``larger``), or that many times closer:
    as in a frame in another unit, not one in which a marker lies astray (a ghost, a swap with
    a marker away), whose others keep their distances. A pair typically at distance 0 (one
    marker given twice) tells no scale and is passed over. A compiled kernel."""
    n_markers = markers.shape[1]
    pair = 0
    for a in range(n_markers):
        for b in range(a + 1, n_markers):
            distance, held = _distance(markers, frame, a, b), typical[pair]
            pair += 1
            if held == 0.0:
                continue
            if (
                (distance <= MAX_SCALE_CHANGE * held)
                if larger
                else (distance * MAX_SCALE_CHANGE >= held)
            ):
                return False
    return True


@kernel
def _distance(markers: np.ndarray, frame: int, a: int, b: int) -> float:
    """The distance [mm] between markers ``a`` and ``b`` at ``frame`` of ``markers``
    ``(n_frames, n, 3)`` [mm]. A compiled kernel."""
    dx = markers[frame, a, 0] - markers[frame, b, 0]
    dy = markers[frame, a, 1] - markers[frame, b, 1]
    dz = markers[frame, a, 2] - markers[frame, b, 2]
    return math.sqrt(dx * dx + dy * dy + dz * dz)


def frames_off_scale(markers: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The frames of the cluster ``markers`` ``(n_frames, n, 3)`` [mm] that lie off its scale
    (:func:`_scale_flags`), increasing; the typical size [mm] of the markers each frame shows,
    the median over the other frames that show them of the largest distance between two of
    them ``(n_frames,)``; and that distance in each frame ``(n_frames,)`` [mm] (NaN where it
    shows fewer than two).

    A frame with a gap (a marker with a NaN coordinate) is judged by the markers it shows
    against the same markers in every frame that shows them: like with like, since the
    markers a frame shows lie closer together than the whole cluster in every unit. One that
    shows fewer than three is not judged: its one distance cannot tell a unit from one marker
    astray (:func:`_scale_flags`), and it holds no pose a fit could take."""
    array = kernel_array(markers)
    n_frames = array.shape[0]
    off = np.zeros(n_frames, dtype=np.bool_)
    typical, spans = np.full(n_frames, np.nan), np.full(n_frames, np.nan)
    finite = np.isfinite(array)
    if finite.all():  # the common case: one pattern, every frame's, judged on the array itself
        off[:], spans[:] = _frames_off(array)
        typical[:] = np.median(spans[~off])
        return np.flatnonzero(off), typical, spans
    shown = finite.all(axis=-1)
    patterns, inverse = _patterns(shown)
    for k, pattern in enumerate(patterns):
        if pattern.sum() < 2:
            continue
        frames = np.flatnonzero(shown[:, pattern].all(axis=1))  # those that show these markers
        own = inverse[frames] == k  # ... of which those that show no other
        flags, sizes = _frames_off(np.ascontiguousarray(array[frames][:, pattern]))
        off[frames[own]], spans[frames[own]] = flags[own], sizes[own]
        typical[frames[own]] = np.median(sizes[~flags])
    return np.flatnonzero(off), typical, spans


def _patterns(shown: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The distinct rows of ``shown`` ``(n_frames, n)`` bool, ``(k, n)``, and the index of each
    frame's among them ``(n_frames,)``. Each row is packed into bytes and the bytes compared
    as one value: NumPy's ``unique`` over rows sorts them as records, twenty times slower."""
    packed = np.ascontiguousarray(np.packbits(shown, axis=1))
    keys = packed.view(np.dtype((np.void, packed.shape[1]))).reshape(-1)
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    return shown[first], inverse.reshape(-1)


def _frames_off(markers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which frames of the complete cluster ``markers`` ``(n_frames, n >= 2, 3)`` [mm] lie off
    its scale (:func:`_scale_flags`) ``(n_frames,)`` bool, and the largest distance between
    two of its markers in each ``(n_frames,)`` [mm]."""
    off = np.empty(markers.shape[0], dtype=np.bool_)
    spans, smallest = np.full(markers.shape[0], np.nan), np.empty(markers.shape[0])
    _scale_flags(markers, off, spans)
    _frame_spans(markers, spans, smallest)
    return off, spans


def cluster_span(markers: np.ndarray) -> float:
    """:func:`typical_span` of the markers ``(n_frames, n, 3)`` [mm] over the frames the checks
    read."""
    return typical_span(kernel_array(markers), _SPAN_FRAMES)


def span_problem(span_mm: float) -> str | None:
    """What a cluster of typical size ``span_mm`` [mm] (:func:`typical_span`) says about its
    unit, or ``None`` where its size is a body's (or unknown): a cluster smaller than a marker
    or larger than a body was measured in another unit than millimetres. Markers at one point
    (a size of 0) are one marker given several times, not a unit, and are left to the checks
    of the markers a method needs. An array states no unit, and millimetres taken for
    centimetres or for metres both make a cluster too large, as the markers of more than one
    segment (a whole body's) do: a cluster too large is named as any of the three."""
    bound = span_bound(span_mm, MAX_SPAN_MM, ONE_SEGMENT)
    if bound is None:
        return None
    if span_mm < MIN_SPAN_MM:
        return f"{bound}: metres read as millimetres?"
    return (
        f"{bound}: millimetres read as centimetres or metres, or the markers of more than one "
        "segment?"
    )


def span_bound(span_mm: float, largest_mm: float, largest: str) -> str | None:
    """Which bound a cluster of typical size ``span_mm`` [mm] (:func:`typical_span`) breaks, in
    words: smaller than a marker (:data:`MIN_SPAN_MM`), or larger than ``largest_mm``, what
    ``largest`` can span (:data:`MAX_SPAN_MM` for :data:`ONE_SEGMENT`,
    :data:`MAX_JOINED_SPAN_MM` for :data:`TWO_SEGMENTS`, :data:`MAX_CAPTURE_SPAN_MM` for
    :data:`CAPTURE_VOLUME`); ``None`` where it breaks neither, or
    is unknown, or 0 (one marker given several times, which is no unit's doing)."""
    if not (math.isfinite(span_mm) and span_mm > 0.0) or MIN_SPAN_MM <= span_mm <= largest_mm:
        return None
    if span_mm < MIN_SPAN_MM:
        return f"less than a marker's own size ({MIN_SPAN_MM:g} mm)"
    return f"more than {largest} ({largest_mm:g} mm)"


def check_span(markers: np.ndarray, *, name: str = "markers") -> None:
    """Raise ``ValueError`` when some frames of the markers ``(n_frames, n, 3)``, which are
    millimetres, are in another unit than the rest (:func:`frames_off_scale`, a frame with a
    gap judged by the markers it shows), or when they lie closer together than a marker's own
    size or further apart than a body segment's (:func:`typical_span`, :func:`span_problem`):
    an answer in another unit would pass every check, which are built for millimetres, at a
    thousandth of its size, or fail them for the wrong reason."""
    array = kernel_array(markers)
    if frames_off_scale(array)[0].size:
        _refuse(array, name, _OFF_SCALE)
    _refuse_span(cluster_span(array), name)


def _refuse_span(span: float, name: str) -> None:
    """Raise :func:`check_span`'s ``ValueError`` for the markers ``name`` of typical size
    ``span`` [mm] (:func:`typical_span`) where :func:`span_problem` finds one."""
    problem = span_problem(span)
    if problem is not None:
        raise ValueError(
            f"{name} lie {span:.3g} mm apart (the farthest two, median over the frames), "
            f"{problem} Marker positions are millimetres"
        )


def check_moves(
    markers: np.ndarray, *, name: str = "markers", tol_mm: float = _MOVE_TOL_MM
) -> None:
    """Raise ``ValueError`` when no marker moves (every trajectory is a single point)."""
    _refuse(markers, name, _first_failure(markers, _MOVES, tol_mm))


def check_rotates(markers: np.ndarray, *, name: str = "markers") -> None:
    """Raise ``ValueError`` when every marker moves along a straight line (or not at all).

    Such a segment translates without rotating: no centre or axis of rotation exists, yet the
    sphere and axis fits would still return one. Each marker's trajectory ``(n_frames, 3)`` is a
    line when the second eigenvalue of its scatter matrix vanishes relative to the first.
    Fewer than three frames always lie on a line and are left to the frame-count checks.
    """
    _refuse(markers, name, _first_failure(markers, _LINES))


def check_not_collinear(markers: np.ndarray, *, name: str = "markers") -> None:
    """Raise ``ValueError`` when the markers of some frame are (nearly) collinear.

    A rigid-body pose needs three non-collinear markers: the second singular value of the
    centred cluster must not vanish relative to the first.
    """
    centred = markers - markers.mean(axis=1, keepdims=True)
    singular = np.linalg.svd(centred, compute_uv=False)
    ratio = singular[:, 1] / np.maximum(singular[:, 0], np.finfo(float).tiny)
    if np.any(ratio < _LINE_RTOL):
        frame = int(np.argmin(ratio))
        raise ValueError(
            f"{name} are collinear in frame {frame}: a rigid-body pose needs three "
            "non-collinear markers"
        )


def check_same_frames(first: np.ndarray, second: np.ndarray) -> None:
    """Raise ``ValueError`` when two segments were not recorded over the same frames."""
    if first.shape[0] != second.shape[0]:
        raise ValueError(
            f"proximal and distal markers have {first.shape[0]} and {second.shape[0]} frames; "
            "they must share frames"
        )


def check_input(kind: str, arrays: tuple[object, ...]) -> tuple[np.ndarray, ...]:
    """The checks every estimator of ``kind`` needs; returns the arrays as float64.

    ``arrays`` are the marker arrays named by :data:`ARRAY_NAMES` for ``kind``. One-segment
    kinds (``center``, ``axis``) also need markers that move and rotate; two-segment data must
    share frames (whether the segments rotate relative to each other is the estimators' and
    the support check's business, as it needs their poses).
    """
    names = ARRAY_NAMES[kind]
    if len(arrays) != len(names):
        raise ValueError(
            f"a {kind} estimator takes {len(names)} marker arrays ({', '.join(names)}), "
            f"got {len(arrays)}"
        )
    if kind == "joint_center":
        # One pass of the kernel per array for the checks of check_markers and check_span;
        # the errors in their order: each array's samples, the shared frames, then each
        # array's frames' scales and size.
        checked = tuple(_shaped(array, name) for array, name in zip(arrays, names, strict=True))
        spans = np.empty(len(checked))
        failures = []
        for i, (array, name) in enumerate(zip(checked, names, strict=True)):
            failures.append(_first_failure(array, _SAMPLES | _SCALE, span=spans[i : i + 1]))
            if failures[-1] != _OFF_SCALE:
                _refuse(array, name, failures[-1])
        check_same_frames(*checked)
        for array, name, failure, span in zip(checked, names, failures, spans, strict=True):
            _refuse(array, name, failure)
            _refuse_span(span, name)
        return checked
    # One pass of the kernel for the checks of check_markers, check_moves and check_rotates,
    # in their order (the counts of frames and markers: at least one, as the array is not empty),
    # and for the frames' scales and the cluster's size of check_span, whose errors come after
    # theirs.
    name = names[0]
    array = _shaped(arrays[0], name)
    span = np.empty(1)
    _refuse(array, name, _first_failure(array, _SAMPLES | _MOVES | _LINES | _SCALE, span=span))
    _refuse_span(span[0], name)
    return (array,)


@dataclass(frozen=True)
class CheckedTrials:
    """The input checks of a batch of trials (:func:`check_input_many`).

    ``errors``: per trial, the ``ValueError`` :func:`check_input` raises for it, or ``None``.
    The checked float64 arrays of the trials that passed are those of ``batch``, one
    ``(n_trials, n_frames, n_markers, 3)`` array per segment where the segments were regular
    arrays, or else of ``each``, per trial its tuple of arrays (``None`` for a refused trial).
    """

    errors: list[ValueError | None]
    batch: tuple[np.ndarray, ...] | None = None
    each: list[tuple[np.ndarray, ...] | None] | None = None

    def arrays(self, trial: int) -> tuple[np.ndarray, ...]:
        """The checked arrays of ``trial``, one that passed, as :func:`check_input` returns
        them."""
        if self.batch is None:
            return self.each[trial]
        return tuple(segment[trial] for segment in self.batch)

    def stacked(self, trials: list[int]) -> tuple[np.ndarray, ...]:
        """The checked arrays of ``trials`` (increasing, each one that passed), one
        ``(len(trials), ...)`` array per segment; the batch's own arrays, not copies, when
        ``trials`` are all of them."""
        if self.batch is None:
            chosen = [self.each[trial] for trial in trials]
            return tuple(np.stack(arrays) for arrays in zip(*chosen, strict=True))
        if len(trials) == len(self.errors):
            return self.batch
        return tuple(segment[trials] for segment in self.batch)


def check_input_many(kind: str, segments: tuple[object, ...], n_trials: int) -> CheckedTrials:
    """:func:`check_input` on each of the ``n_trials`` trials of ``segments``, the marker arrays
    of ``kind`` with a leading trials axis ``(n_trials, n_frames, n_markers, 3)``.

    Where every segment is a regular real array of that shape (none empty, the two segments
    sharing frames), one pass of the compiled kernel over all trials finds the trials that
    pass; only those that do not are checked one by one, for :func:`check_input`'s own error.
    Other segments (lists of trials, other shapes or types) are checked trial by trial.
    """
    batch = _regular_batch(kind, segments, n_trials)
    if batch is None:
        return _check_each(kind, segments, n_trials)
    checks = _SAMPLES | _SCALE if kind == "joint_center" else _SAMPLES | _MOVES | _LINES | _SCALE
    passes = np.ones(n_trials, dtype=bool)
    failures = np.empty(n_trials, dtype=np.int8)
    spans = np.empty(n_trials)
    for array in batch:
        if _first_failures(kernel_array(array), checks, _MOVE_TOL_MM, failures, spans):
            passes &= failures == 0
        passes &= ~(((spans > 0.0) & (spans < MIN_SPAN_MM)) | (spans > MAX_SPAN_MM))
    errors: list[ValueError | None] = [None] * n_trials
    for trial in np.flatnonzero(~passes).tolist():
        errors[trial] = _error_of(kind, tuple(segment[trial] for segment in segments))
    return CheckedTrials(errors, batch=batch)


def _check_each(kind: str, segments: tuple[object, ...], n_trials: int) -> CheckedTrials:
    """:func:`check_input_many` trial by trial."""
    errors: list[ValueError | None] = []
    each: list[tuple[np.ndarray, ...] | None] = []
    for trial in range(n_trials):
        try:
            each.append(check_input(kind, tuple(segment[trial] for segment in segments)))
            errors.append(None)
        except ValueError as error:
            each.append(None)
            errors.append(error)
    return CheckedTrials(errors, each=each)


def _regular_batch(
    kind: str, segments: tuple[object, ...], n_trials: int
) -> tuple[np.ndarray, ...] | None:
    """``segments`` as float64 arrays (views where they already are), when each is a real,
    unmasked ``(n_trials, n_frames, n_markers, 3)`` array whose trials are not empty and the
    segments share frames: a batch the kernel checks at once. ``None`` otherwise."""
    if len(segments) != len(ARRAY_NAMES[kind]):
        return None
    batch = []
    for segment in segments:
        if (
            not isinstance(segment, np.ndarray)
            or np.ma.isMaskedArray(segment)
            or segment.dtype.kind not in "iuf"
            or segment.ndim != 4
            or segment.shape[0] != n_trials
            or segment.shape[-1] != 3
            or 0 in segment.shape[1:]
        ):
            return None
        with np.errstate(over="ignore"):  # a trial that overflows is checked on its own
            batch.append(segment.astype(float, copy=False))
    if len({array.shape[1] for array in batch}) > 1:
        return None
    return tuple(batch)


def _error_of(kind: str, arrays: tuple[object, ...]) -> ValueError | None:
    """The ``ValueError`` :func:`check_input` raises for ``arrays``, or ``None``."""
    try:
        check_input(kind, arrays)
    except ValueError as error:
        return error
    return None


def prepare_trials(
    markers: object, prepare: Callable[[np.ndarray], object]
) -> tuple[list[ValueError | None], dict[int, object]]:
    """``prepare`` (a one-trial function's checks and set-up) on each trial of ``markers``
    ``(n_trials, ...)``: per trial the ``ValueError`` it raised or ``None``, and the prepared
    values of the trials that passed, by trial. A list's trials reach ``prepare`` as given."""
    outcomes: list[ValueError | None] = []
    prepared: dict[int, object] = {}
    trials = markers if isinstance(markers, list) else np.asarray(markers, dtype=float)
    for trial, data in enumerate(trials):
        try:
            prepared[trial] = prepare(data)
            outcomes.append(None)
        except ValueError as error:
            outcomes.append(error)
    return outcomes, prepared
