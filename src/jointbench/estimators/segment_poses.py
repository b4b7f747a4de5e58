"""Rigid-body poses of the segments of many trials, fitted once and shared.

Every pose-based method (SCoRE, SARA, the hip joint centre's fits, the amplitude screen) and the
two-segment support verdict (:mod:`jointbench.estimators.support`) read the same poses: those of
:func:`jointbench.numerics.poses.rigid_poses` (paper C §5), with the body frame equal to the
world at frame 0. :func:`trial_poses` fits them for all trials at once and checks what a pose
needs, so a caller can fit them once and pass them to each method (``poses=``) and to the verdict.
Poses cannot be altered after their fit: their arrays are read-only, and poses rebuilt with
other parts than those that leave their residual on their markers, or in another body frame,
are refused (:class:`SegmentPoses`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, fields

import numpy as np

from jointbench.estimators.batching import (
    NUMERICAL_FAILURES,
    check_one_shape,
    check_same_trials,
    each_alone,
)
from jointbench.estimators.results import with_fields
from jointbench.estimators.validation import (
    check_counts,
    check_markers,
    check_not_collinear,
    check_same_frames,
)
from jointbench.numerics import poses as pose_fit
from jointbench.numerics.compiled import kernel

__all__ = [
    "POSE_MIN_FRAMES",
    "AlteredPoses",
    "SegmentPoses",
    "pose_segments",
    "precision_on_poses",
    "residual_differs",
    "stopped_fit",
    "trial_poses",
    "with_stopped_fits",
]

#: Fewest frames a pose-based method accepts: every one of them needs the same, so their
#: poses can be fitted once and shared.
POSE_MIN_FRAMES = 3


#: The arrays of :class:`SegmentPoses`, in field order.
_POSE_ARRAYS = ("markers", "rotation", "translation", "body")


class AlteredPoses(ValueError):
    """Poses whose rotation, translation and body-fixed coordinates leave on their markers a
    residual sum of squares ``found`` [mm^2] other than the ``stored`` one they were fitted
    with (see :func:`residual_differs`)."""

    def __init__(self, message: str, *, found: float, stored: float) -> None:
        super().__init__(message)
        self.found = found
        self.stored = stored


@dataclass(frozen=True)
class SegmentPoses:
    """One segment's pose in every frame (body frame = world at frame 0).

    ``markers`` ``(N, n_markers, 3)`` [mm] the checked input, ``rotation`` ``(N, 3, 3)``,
    ``translation`` ``(N, 3)`` [mm], ``body`` ``(n_markers, 3)`` [mm] the estimated body-fixed
    marker coordinates, ``residual_ss`` the sum of squared marker residuals [mm^2] and ``dof``
    its degrees of freedom, ``3 (n_markers - 2) (N - 1)``: ``3 n N`` coordinates less ``6 N``
    pose parameters and ``3 n`` body coordinates, plus the 6 of the
    gauge (the body frame is pinned to frame 0); ``residual_fourths`` the sum of the markers'
    residual lengths to the fourth power [mm^4], formed with ``residual_ss`` (not an argument).

    The poses cannot be altered after their fit. Built, they refuse (``ValueError``) arrays
    shaped otherwise than their markers ask, a ``dof`` other than theirs, and a rotation,
    translation and body that leave on the markers another residual than ``residual_ss``
    (:class:`AlteredPoses`, beyond the allowance of :func:`residual_differs`): poses edited
    and rebuilt, by hand or with ``dataclasses.replace``; and a frame-0 pose other than the
    identity (the same motion in another body frame, which leaves the same residual but moves
    the answers of the methods that read body-fixed coordinates). ``residual_ss`` and ``dof`` left
    ``None`` (a fresh fit) are computed. The arrays are read-only copies of their own, so
    a caller's array is left as it was and cannot change them. Not caught:
    poses forged together with the residual they leave, which only a re-fit of the markers
    would tell, edits too small to move the residual beyond the allowance (at the fit's
    minimum the residual moves with the square of an edit), and Python's own ways round a
    frozen dataclass (``object.__setattr__``, ``__dict__``, a subclass that skips the checks).
    """

    markers: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    body: np.ndarray
    residual_ss: float | None = None
    dof: int | None = None
    iterations: int | None = None
    change_mm: float | None = None
    residual_fourths: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        arrays = {name: _owned_read_only(name, getattr(self, name)) for name in _POSE_ARRAYS}
        what = _check_pose_shapes(**arrays)
        n_frames, n_markers, _ = arrays["markers"].shape
        dof = 3 * (n_markers - 2) * (n_frames - 1)
        if self.dof is not None and (np.ndim(self.dof) != 0 or self.dof != dof):
            raise ValueError(
                f"{what}: dof is {self.dof}, not the {dof} their shapes give "
                "(3 (n_markers - 2) (n_frames - 1))"
            )
        residual, fourths = _pose_residuals(**arrays)
        found = float(np.sum(residual * residual))
        if self.residual_ss is not None:
            residual_ss = _checked_residual(what, found, self.residual_ss, arrays["markers"])
        elif np.isfinite(found):
            residual_ss = found
        else:
            raise ValueError(
                f"{what}: rotation/translation/body leave a residual of {found} mm^2 on their "
                "markers: markers and poses must be finite numbers"
            )
        _check_gauge(what, arrays["rotation"][0], arrays["translation"][0], arrays["markers"])
        _check_fit_end(what, self.iterations, self.change_mm)
        for name, array in arrays.items():
            object.__setattr__(self, name, array)
        object.__setattr__(self, "residual_ss", residual_ss)
        object.__setattr__(self, "dof", dof)
        object.__setattr__(self, "residual_fourths", fourths)

    @property
    def variance(self) -> float:
        """The rigid-body residual per coordinate, ``s^2 = residual_ss / dof`` [mm^2]."""
        return self.residual_ss / self.dof

    @property
    def converged(self) -> bool | None:
        """Whether the alternation that fitted these poses had converged (its last change of
        the body-fixed coordinates under :func:`jointbench.numerics.poses.change_limit`), or
        ``None`` for poses whose fit did not record how it ended."""
        if self.change_mm is None:
            return None
        return bool(self.change_mm < pose_fit.change_limit(self.markers[None])[0])

    def __reduce__(self) -> tuple:
        # A copy or an unpickled pose is built, and so checked and read-only, as any other.
        return (type(self), tuple(getattr(self, f.name) for f in fields(self) if f.init))


def _owned_read_only(name: str, array: object) -> np.ndarray:
    """Pose array ``name`` as a read-only ``float64`` copy no one can write: a caller's array
    is neither made read-only nor able to change the poses afterwards, and neither the copy
    nor its ``base`` can be made writeable."""
    try:
        copy = np.array(array, dtype=float)
    except (TypeError, ValueError) as error:
        raise ValueError(f"segment poses: {name} is no array of numbers ({error})") from None
    # Over an immutable buffer: an array that owns its memory, or a view of one, can be made
    # writeable again through itself or its ``base``.
    return np.frombuffer(copy.tobytes(), dtype=float).reshape(copy.shape)


def _check_pose_shapes(
    markers: np.ndarray, rotation: np.ndarray, translation: np.ndarray, body: np.ndarray
) -> str:
    """``ValueError`` unless the pose arrays are shaped as ``markers`` ``(N, n, 3)``, ``n >= 3``,
    asks (see :class:`SegmentPoses`); else what the poses are, for the errors that follow."""
    if markers.ndim != 3 or markers.shape[0] < 1 or markers.shape[1] < 3 or markers.shape[2] != 3:
        raise ValueError(
            f"segment poses: markers is shaped {markers.shape}, not (n_frames, n_markers, 3) "
            "with at least 1 frame and 3 markers"
        )
    n_frames, n_markers, _ = markers.shape
    what = f"poses of a segment of {n_frames} frames and {n_markers} markers"
    wanted = {
        "rotation": (rotation, (n_frames, 3, 3)),
        "translation": (translation, (n_frames, 3)),
        "body": (body, (n_markers, 3)),
    }
    for name, (array, shape) in wanted.items():
        if array.shape != shape:
            raise ValueError(f"{what}: {name} is shaped {array.shape}, not {shape}")
    return what


def _check_gauge(
    what: str, first_rotation: np.ndarray, first_translation: np.ndarray, markers: np.ndarray
) -> None:
    """``ValueError`` unless frame 0's pose, ``first_rotation`` ``(3, 3)`` and
    ``first_translation`` ``(3,)`` [mm], is the identity to rounding: the body frame is the
    world at frame 0. Poses in another body frame leave the same residual on the markers, but
    the methods that read body-fixed coordinates (the hip joint centre's fits) answer in it."""
    scale = float(np.max(np.abs(markers), initial=0.0))
    turned = float(np.max(np.abs(first_rotation - np.eye(3))))
    moved = float(np.max(np.abs(first_translation)))
    # The fit anchors its poses at frame 0 (jointbench.numerics.poses), which leaves rounding.
    if not (turned <= 1e-9 and moved <= 1e-9 * max(scale, 1.0)):
        raise ValueError(
            f"{what}: the body frame is not the world at frame 0 (rotation[0] differs from the "
            f"identity by {turned:.3g}, translation[0] is {moved:.3g} mm): poses in another "
            "body frame are not the fitted ones"
        )


def _check_fit_end(what: str, iterations: object, change_mm: object) -> None:
    """``ValueError`` unless ``iterations`` and ``change_mm`` are both ``None`` or both given,
    a count >= 1 and a change >= 0 [mm]."""
    if iterations is None and change_mm is None:
        return
    if (
        isinstance(iterations, bool)
        or not isinstance(iterations, (int, np.integer))
        or iterations < 1
        or isinstance(change_mm, bool)
        or not isinstance(change_mm, (int, float, np.integer, np.floating))
        or not change_mm >= 0.0
    ):
        raise ValueError(
            f"{what}: iterations {iterations!r} and change_mm {change_mm!r} must be both None "
            "or a count >= 1 and a change >= 0 [mm] (how the pose fit ended)"
        )


def residual_differs(found: np.ndarray, stored: np.ndarray, markers: np.ndarray) -> np.ndarray:
    """Whether residual sums of squares ``found`` ``(...)`` [mm^2], recomputed from poses of
    ``markers`` ``(..., N, n, 3)`` [mm], differ from the ``stored`` ``(...)`` [mm^2] they were
    fitted with by more than a recomputation of the same poses can move them; a stored sum
    that is no finite number differs."""
    # Rounding of coordinates of this size, summed over every coordinate, bounds what a
    # recomputation of the same poses may move the sum by.
    scale = np.max(np.abs(markers), axis=(-3, -2, -1), initial=0.0)
    rounding = np.prod(markers.shape[-3:]) * (1e-10 * scale) ** 2
    # An infinite stored sum would make the relative allowance infinite.
    return ~np.isfinite(stored) | ~(np.abs(found - stored) <= 1e-6 * stored + rounding)


def _checked_residual(what: str, found: float, stored: object, markers: np.ndarray) -> float:
    """``stored`` [mm^2], the residual sum of squares poses that leave ``found`` [mm^2] on
    ``markers`` were fitted with; :class:`AlteredPoses` when it is another beyond rounding,
    ``ValueError`` when it is no number."""
    try:
        stored = float(stored)
    except (TypeError, ValueError):
        raise ValueError(f"{what}: residual_ss is {stored!r}, not a number [mm^2]") from None
    if residual_differs(found, stored, markers):
        raise AlteredPoses(
            f"{what}: rotation/translation/body leave a residual of {found:.6g} mm^2 on their "
            f"markers, not the {stored:.6g} mm^2 they were fitted with: they were altered "
            "after their fit",
            found=found,
            stored=stored,
        )
    return stored


def _segment_poses(
    markers, rotation, translation, body, iterations, change_mm, *, name: str
) -> SegmentPoses:
    check_not_collinear(body[None], name=f"{name} (body-fixed coordinates)")
    return SegmentPoses(
        markers,
        rotation,
        translation,
        body,
        iterations=int(iterations),
        change_mm=float(change_mm),
    )


def _pose_residuals(
    markers: np.ndarray, rotation: np.ndarray, translation: np.ndarray, body: np.ndarray
) -> tuple[np.ndarray, float]:
    """``markers - (R_f b_m + t_f)`` ``(N, n, 3)`` [mm]: what the poses ``rotation`` ``(N, 3,
    3)`` and ``translation`` ``(N, 3)`` [mm] of the body-fixed coordinates ``body`` ``(n, 3)``
    [mm] leave of ``markers`` ``(N, n, 3)``; and the sum of their fourth powers ``sum_fm
    |r_fm|^4`` [mm^4], which paper C's model test reads the noise's kurtosis from
    (:mod:`jointbench.estimators.hjc`)."""
    # R_f b_m for every frame and marker as one (3N, 3) @ (3, n) product.
    turned = rotation.reshape(-1, 3) @ np.swapaxes(body, -1, -2)
    return _less_turned(markers, turned, translation)


@kernel
def _less_turned(markers: np.ndarray, turned: np.ndarray, translation: np.ndarray) -> tuple:
    """``(r, sum |r_fm|^4)``: ``r = markers - turned' - translation`` ``(N, n, 3)`` [mm] of
    ``markers`` ``(N, n, 3)``, the poses' rotated body coordinates ``turned`` ``(3 N, n)`` (frame
    ``f``'s coordinate ``k`` of marker ``m`` at ``[3 f + k, m]``) and ``translation`` ``(N, 3)``
    [mm]. A compiled kernel: NumPy's subtraction of the transposed product, and a sum over the
    markers' three coordinates, each cost more than this pass."""
    n_frames, n_markers, _ = markers.shape
    residual = np.empty((n_frames, n_markers, 3))
    fourths = 0.0
    for f in range(n_frames):
        for m in range(n_markers):
            squared = 0.0
            for k in range(3):
                value = markers[f, m, k] - turned[3 * f + k, m] - translation[f, k]
                residual[f, m, k] = value
                squared += value * value
            fourths += squared * squared
    return residual, fourths


def trial_poses(
    segments: dict[str, np.ndarray], *, min_frames: int
) -> list[dict[str, SegmentPoses] | ValueError]:
    """Poses of many trials at once: ``segments`` maps a name (``"markers"``, or ``"proximal"``
    and ``"distal"``) to ``(n_trials, N, n_markers, 3)`` [mm], or to a list or tuple of
    trials; every segment holds the same trials (``ValueError`` otherwise).

    Per trial, each segment's markers are checked (at least ``min_frames`` frames and 3
    markers, not collinear at frame 0), two segments must share frames, and the body-fixed
    coordinates the fit estimates must not be collinear; a trial that fails a check carries
    its ``ValueError``. The trials that pass must share their shapes (``ValueError`` naming
    the first that does not): every segment's poses are fitted for all trials in one call of
    :func:`jointbench.numerics.poses.rigid_poses`. Compute them once and pass them to the
    ``batched`` form of every pose-based method.
    """
    return _trial_poses(segments, min_frames=min_frames, samples_checked=False)


def _trial_poses(
    segments: dict[str, np.ndarray], *, min_frames: int, samples_checked: bool
) -> list[dict[str, SegmentPoses] | ValueError]:
    """:func:`trial_poses`; ``samples_checked``: every trial's arrays are float64
    ``(N, n, 3)`` arrays whose samples :func:`check_markers` passed just before (a checked
    call's), and are not scanned again (their counts, frames and collinearity are still
    checked)."""
    names = list(segments)
    check_same_trials(tuple(segments.values()), tuple(names))
    # A list or a tuple of trials (batching.trial_shapes) may hold trials of other shapes,
    # which each trial's checks name; only an array of trials is read as one array.
    arrays = {
        name: markers if isinstance(markers, list | tuple) else np.asarray(markers)
        for name, markers in segments.items()
    }
    n_trials = len(arrays[names[0]])
    outcomes: list = [None] * n_trials
    checked: dict[int, list[np.ndarray]] = {}
    for trial in range(n_trials):
        try:
            checked[trial] = [
                (check_counts if samples_checked else check_markers)(
                    arrays[name][trial], min_frames=min_frames, min_markers=3, name=name
                )
                for name in names
            ]
            if len(names) == 2:
                check_same_frames(*checked[trial])
            for name, markers in zip(names, checked[trial], strict=True):
                check_not_collinear(markers[:1], name=name)
        except ValueError as error:
            outcomes[trial] = error
            checked.pop(trial, None)
    good = list(checked)
    check_one_shape(
        tuple(names),
        {trial: tuple(array.shape for array in arrays) for trial, arrays in checked.items()},
    )
    stacked = [
        np.stack([checked[trial][index] for trial in good]) if good else None
        for index in range(len(names))
    ]
    fitted = [_fitted_poses(markers) if good else [] for markers in stacked]
    for row, trial in enumerate(good):
        try:
            outcomes[trial] = {
                name: _segment_poses(stacked[index][row], *_parts(fitted[index][row]), name=name)
                for index, name in enumerate(names)
            }
        except ValueError as error:
            outcomes[trial] = error
    return outcomes


def _fitted_poses(markers: np.ndarray) -> list:
    """Per trial of ``markers`` ``(T, N, P, 3)`` its
    :func:`~jointbench.numerics.poses.fit_rigid_poses` parts (poses,
    body-fixed coordinates, iterations and last change), all trials in one call; when that call
    fails numerically, each trial alone, a failing trial's error in place of its parts."""
    try:
        return list(zip(*pose_fit.fit_rigid_poses(markers)[:5], strict=True))
    except NUMERICAL_FAILURES:
        return each_alone(
            lambda t: tuple(part[0] for part in pose_fit.fit_rigid_poses(markers[t : t + 1])[:5]),
            len(markers),
        )


def _parts(fitted: tuple | Exception) -> tuple:
    """A trial's pose parts, or its numerical failure raised."""
    if isinstance(fitted, Exception):
        raise fitted
    return fitted


def stopped_fit(name: str, iterations: int, change_mm: float) -> str:
    """What a result says of segment ``name``'s pose fit (``"markers"``, ``"proximal"``,
    ``"distal"``) that stopped after ``iterations`` re-estimations of the body-fixed
    coordinates, the last moving them ``change_mm`` [mm]."""
    whose = "the markers'" if name == "markers" else f"the {name} markers'"
    return (
        f"{whose} pose fit stopped after {iterations} re-estimations of their body-fixed "
        f"coordinates, the last moving them {change_mm:.3g} mm"
    )


def with_stopped_fits(result, stopped: list[str]):
    """``result`` with ``converged=False`` and its status led by the ``stopped`` pose fits
    (:func:`stopped_fit`): poses that are not the least-squares ones, on which an answer moves
    with the starting frame. ``result`` as it was when none stopped."""
    if not stopped:
        return result
    reason = (
        "did not converge: "
        + "; ".join(stopped)
        + " (paper C §5's alternation): the poses are not the least-squares ones"
    )
    # The method's own stop, if any, joins the same "did not converge" sentence.
    own = result.status.removeprefix("did not converge: ")
    status = reason if own == "ok" else f"{reason}; {own}"
    return with_fields(result, converged=False, status=status)


def pose_segments(many: Callable) -> tuple[str, ...] | None:
    """The segments whose poses (from :func:`trial_poses`) the many-trial form ``many`` (see
    :func:`jointbench.estimators.registry.many`) accepts as ``poses=``, or ``None`` when it is
    not pose-based."""
    return getattr(many, "pose_segments", None)


def precision_on_poses(check: Callable) -> Callable[..., list]:
    """A two-segment method's ``precision_many`` that gives each of its results
    ``check(result, proximal_poses, distal_poses)``, on the poses its checked call fitted (one
    :func:`trial_poses` entry per trial in ``poses``), or where that call shared none on poses
    fitted here. The support ``verdicts`` are not read: each check holds the result to those
    poses' own rigid-body fits."""

    def precision_many(results: list, proximal, distal, *, verdicts, poses=None) -> list:
        del verdicts
        if poses is None:
            segments = {"proximal": proximal, "distal": distal}
            poses = trial_poses(segments, min_frames=POSE_MIN_FRAMES)
        return [
            check(result, trial["proximal"], trial["distal"])
            for result, trial in zip(results, poses, strict=True)
        ]

    precision_many.pose_segments = ("proximal", "distal")
    return precision_many
