"""Rigid-body poses of the segments of many trials, fitted once and shared.

Every pose-based method (SCoRE, SARA, the hip joint centre's fits, the amplitude screen) and the
two-segment support verdict (:mod:`jointbench.estimators.support`) read the same poses: those of
:func:`jointbench.numerics.poses.rigid_poses` (paper C §5), with the body frame equal to the
world at frame 0. :func:`trial_poses` fits them for all trials at once and checks what a pose
needs, so a caller can fit them once and pass them to each method (``poses=``) and to the verdict.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from jointbench.estimators.batching import NUMERICAL_FAILURES, check_same_trials, each_alone
from jointbench.estimators.validation import (
    check_markers,
    check_not_collinear,
    check_same_frames,
)
from jointbench.numerics.poses import rigid_poses

__all__ = [
    "POSE_MIN_FRAMES",
    "SegmentPoses",
    "pose_residuals",
    "pose_segments",
    "stored_segment_poses",
    "trial_poses",
]

#: Fewest frames a pose-based method accepts: every one of them needs the same, so their
#: poses can be fitted once and shared.
POSE_MIN_FRAMES = 3


@dataclass(frozen=True)
class SegmentPoses:
    """One segment's pose in every frame (body frame = world at frame 0).

    ``markers`` ``(N, n_markers, 3)`` [mm] the checked input, ``rotation`` ``(N, 3, 3)``,
    ``translation`` ``(N, 3)`` [mm], ``body`` ``(n_markers, 3)`` [mm] the estimated body-fixed
    marker coordinates, ``residual_ss`` the sum of squared marker residuals [mm^2] and ``dof``
    its degrees of freedom, ``3 (n_markers - 2) (N - 1)``: ``3 n N`` coordinates less ``6 N``
    pose parameters and ``3 n`` body coordinates, plus the 6 of the
    gauge (the body frame is pinned to frame 0).
    """

    markers: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    body: np.ndarray
    residual_ss: float
    dof: int


def _segment_poses(markers, rotation, translation, body, *, name: str) -> SegmentPoses:
    check_not_collinear(body[None], name=f"{name} (body-fixed coordinates)")
    residual = pose_residuals(markers, rotation, translation, body)
    residual_ss = float(np.sum(residual * residual))
    return stored_segment_poses(markers, rotation, translation, body, residual_ss)


def pose_residuals(
    markers: np.ndarray, rotation: np.ndarray, translation: np.ndarray, body: np.ndarray
) -> np.ndarray:
    """``markers - (R_f b_m + t_f)`` ``(..., N, n, 3)`` [mm]: what the poses ``rotation``
    ``(..., N, 3, 3)`` and ``translation`` ``(..., N, 3)`` [mm] of the body-fixed coordinates
    ``body`` ``(..., n, 3)`` [mm] leave of ``markers`` ``(..., N, n, 3)``; leading axes are
    trials."""
    *lead, n_frames, _, _ = rotation.shape
    # R_f b_m for every frame and marker as one (3N, 3) @ (3, n) product per trial.
    turned = (rotation.reshape(*lead, -1, 3) @ np.swapaxes(body, -1, -2)).reshape(
        *lead, n_frames, 3, -1
    )
    return markers - np.swapaxes(turned, -1, -2) - translation[..., None, :]


def stored_segment_poses(
    markers: np.ndarray,
    rotation: np.ndarray,
    translation: np.ndarray,
    body: np.ndarray,
    residual_ss: float,
) -> SegmentPoses:
    """A segment's poses rebuilt from what a pose fit stored (see :class:`SegmentPoses` for the
    shapes), with the markers they were fitted to."""
    n_frames, n_markers, _ = markers.shape
    return SegmentPoses(
        markers=markers,
        rotation=rotation,
        translation=translation,
        body=body,
        residual_ss=float(residual_ss),
        dof=3 * (n_markers - 2) * (n_frames - 1),
    )


def trial_poses(
    segments: dict[str, np.ndarray], *, min_frames: int
) -> list[dict[str, SegmentPoses] | ValueError]:
    """Poses of many trials at once: ``segments`` maps a name (``"markers"``, or ``"proximal"``
    and ``"distal"``) to ``(n_trials, N, n_markers, 3)`` [mm], or to a list of trials; every
    segment holds the same trials (``ValueError`` otherwise).

    Per trial, each segment's markers are checked (at least ``min_frames`` frames and 3
    markers, not collinear at frame 0), two segments must share frames, and the body-fixed
    coordinates the fit estimates must not be collinear; a trial that fails a check carries
    its ``ValueError``. The trials that pass must share their shapes (``ValueError`` naming
    the first that does not): every segment's poses are fitted for all trials in one call of
    :func:`jointbench.numerics.poses.rigid_poses`. Compute them once and pass them to the
    ``batched`` form of every pose-based method.
    """
    names = list(segments)
    check_same_trials(tuple(segments.values()), tuple(names))
    arrays = {
        name: markers if isinstance(markers, list) else np.asarray(markers)
        for name, markers in segments.items()
    }
    n_trials = len(arrays[names[0]])
    outcomes: list = [None] * n_trials
    checked: dict[int, list[np.ndarray]] = {}
    for trial in range(n_trials):
        try:
            checked[trial] = [
                check_markers(arrays[name][trial], min_frames=min_frames, min_markers=3, name=name)
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
    _check_one_shape(names, checked)
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


def _check_one_shape(names: list[str], checked: dict[int, list[np.ndarray]]) -> None:
    """``ValueError`` naming the first trial of ``checked`` (per trial, its checked arrays in
    ``names`` order) shaped otherwise than the first: the trials are fitted as one batch."""
    if not checked:
        return
    first, *others = checked
    for trial in others:
        for name, array, first_array in zip(names, checked[trial], checked[first], strict=True):
            if array.shape != first_array.shape:
                raise ValueError(
                    f"{name} of trial {trial} has {array.shape[0]} frames and "
                    f"{array.shape[1]} markers, of trial {first} {first_array.shape[0]} and "
                    f"{first_array.shape[1]}: the trials of one call share their numbers of "
                    "frames and markers; fit the others in a call of their own"
                )


def _fitted_poses(markers: np.ndarray) -> list:
    """Per trial of ``markers`` ``(T, N, P, 3)`` its :func:`rigid_poses` parts, all trials in
    one call; when that call fails numerically, each trial alone, a failing trial's error in
    place of its parts."""
    try:
        return list(zip(*rigid_poses(markers), strict=True))
    except NUMERICAL_FAILURES:
        return each_alone(
            lambda t: tuple(part[0] for part in rigid_poses(markers[t : t + 1])), len(markers)
        )


def _parts(fitted: tuple | Exception) -> tuple:
    """A trial's pose parts, or its numerical failure raised."""
    if isinstance(fitted, Exception):
        raise fitted
    return fitted


def pose_segments(many: Callable) -> tuple[str, ...] | None:
    """The segments whose poses (from :func:`trial_poses`) the many-trial form ``many`` (see
    :func:`jointbench.estimators.registry.many`) accepts as ``poses=``, or ``None`` when it is
    not pose-based."""
    return getattr(many, "pose_segments", None)
