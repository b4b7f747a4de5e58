"""Input checks shared by the estimators. Every failure is a ``ValueError`` naming the problem.

The registry applies :func:`check_input` to every registered estimator, so a new estimator is
held to these checks without code of its own; estimators still call :func:`check_markers` with
their own minimum numbers of frames and markers.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from jointbench.numerics.compiled import kernel, kernel_array

__all__ = [
    "ARRAY_NAMES",
    "check_input",
    "check_markers",
    "check_moves",
    "check_not_collinear",
    "check_rotates",
    "check_same_frames",
    "prepare_trials",
]

#: The marker arrays each estimator kind takes, in order.
ARRAY_NAMES = {"center": ("markers",), "axis": ("markers",), "joint_center": ("proximal", "distal")}

_GAP_ADVICE = "mark gaps as NaN and drop those frames before fitting"

# A trajectory counts as a straight line when its second principal spread is below this
# fraction of its first; the same relative level at which check_not_collinear calls markers
# collinear, far below any rotation a marker set can resolve.
_LINE_RTOL = 1e-6


def _real_array(markers: object, name: str) -> np.ndarray:
    """``markers`` as a float64 array; complex, boolean, non-numeric and masked data raise."""
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
    return array.astype(float, copy=False)


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
    mask would otherwise be dropped silently), checks the shape, rejects NaN/inf and samples at
    exactly ``(0, 0, 0)`` (how some C3D readers store gaps), naming marker and frame, and
    checks the minimum numbers of frames and markers a method needs.
    """
    array = _real_array(markers, name)
    if array.ndim != 3 or array.shape[-1] != 3:
        raise ValueError(f"{name} must be shaped (n_frames, n_markers, 3), got shape {array.shape}")
    if array.size == 0:
        raise ValueError(f"{name} is empty (shape {array.shape})")
    # One compiled pass finds whether there is anything to report; only then are the
    # offending samples located.
    all_finite, any_origin = _sample_flags(kernel_array(array))
    if not all_finite:
        finite = np.isfinite(array)
        frame, marker = _first_sample(~finite)
        count = int((~finite).any(axis=-1).sum())
        raise ValueError(
            f"{name} contains NaN or inf at marker {marker}, frame {frame} ({count} in all); "
            f"{_GAP_ADVICE}"
        )
    if any_origin:
        origin = ~array.any(axis=-1)
        if origin.any():
            frame, marker = _first_sample(origin)
            raise ValueError(
                f"{name} has a sample at exactly (0, 0, 0) at marker {marker}, frame {frame} "
                f"({int(origin.sum())} in all): some C3D readers store gaps as zeros; "
                f"{_GAP_ADVICE}"
            )
    n_frames, n_markers, _ = array.shape
    if n_frames < min_frames:
        raise ValueError(f"{name} has {n_frames} frames; this method needs at least {min_frames}")
    if n_markers < min_markers:
        raise ValueError(
            f"{name} has {n_markers} markers; this method needs at least {min_markers}"
        )
    return array


@kernel
def _sample_flags(markers: np.ndarray) -> tuple[bool, bool]:
    """Whether every coordinate of ``markers`` ``(n_frames, n_markers, 3)`` is finite, and
    whether some sample is exactly ``(0, 0, 0)``. A compiled kernel: these checks run before
    every fit, and NumPy's passes over the array cost a tenth of a closed-form fit."""
    all_finite = True
    any_origin = False
    for f in range(markers.shape[0]):
        for m in range(markers.shape[1]):
            x, y, z = markers[f, m, 0], markers[f, m, 1], markers[f, m, 2]
            all_finite = all_finite and math.isfinite(x) and math.isfinite(y) and math.isfinite(z)
            any_origin = any_origin or (x == 0.0 and y == 0.0 and z == 0.0)
    return all_finite, any_origin


@kernel
def _largest_move(markers: np.ndarray) -> tuple[float, float]:
    """The largest absolute coordinate change from frame 0 of ``markers``
    ``(n_frames, n_markers, 3)`` [mm], and the largest absolute coordinate of frame 0 [mm]. A
    compiled kernel (see :func:`_sample_flags`)."""
    spread = 0.0
    first = 0.0
    for m in range(markers.shape[1]):
        for i in range(3):
            first = max(first, abs(markers[0, m, i]))
            for f in range(markers.shape[0]):
                spread = max(spread, abs(markers[f, m, i] - markers[0, m, i]))
    return spread, first


def check_moves(markers: np.ndarray, *, name: str = "markers", tol_mm: float = 1e-9) -> None:
    """Raise ``ValueError`` when no marker moves (every trajectory is a single point)."""
    spread, first = _largest_move(kernel_array(markers))
    if spread <= tol_mm * max(1.0, first):
        raise ValueError(f"{name} do not move: every marker stays at one point in every frame")


def check_rotates(markers: np.ndarray, *, name: str = "markers") -> None:
    """Raise ``ValueError`` when every marker moves along a straight line (or not at all).

    Such a segment translates without rotating: no centre or axis of rotation exists, yet the
    sphere and axis fits would still return one. Each marker's trajectory ``(n_frames, 3)`` is a
    line when the second eigenvalue of its scatter matrix vanishes relative to the first.
    Fewer than three frames always lie on a line and are left to the frame-count checks.
    """
    if markers.shape[0] < 3:
        return
    if _all_straight(kernel_array(markers), _LINE_RTOL**2):
        raise ValueError(
            f"{name} do not rotate: every marker moves along a straight line, so there is no "
            "centre or axis of rotation"
        )


@kernel
def _all_straight(markers: np.ndarray, ratio: float) -> bool:
    """Whether every marker's trajectory over the frames of ``markers``
    ``(n_frames, n_markers, 3)`` is a line: the second eigenvalue of its scatter matrix about
    its mean position at most ``ratio`` times the largest. A compiled kernel: the checks run
    before every fit, and NumPy's per-call overhead on these 3 x 3 matrices cost as much as a
    closed-form fit."""
    n_frames, n_markers, _ = markers.shape
    scatter = np.empty((3, 3))
    mean = np.empty(3)
    for p in range(n_markers):
        for i in range(3):
            total = 0.0
            for f in range(n_frames):
                total += markers[f, p, i]
            mean[i] = total / n_frames
        scatter[:] = 0.0
        for f in range(n_frames):
            for i in range(3):
                for j in range(3):
                    scatter[i, j] += (markers[f, p, i] - mean[i]) * (markers[f, p, j] - mean[j])
        eigenvalues = np.linalg.eigvalsh(scatter)
        if eigenvalues[1] > ratio * eigenvalues[2]:
            return False
    return True


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
    checked = tuple(
        check_markers(array, name=name) for array, name in zip(arrays, names, strict=True)
    )
    if kind == "joint_center":
        check_same_frames(*checked)
    else:
        check_moves(checked[0])
        check_rotates(checked[0])
    return checked


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
