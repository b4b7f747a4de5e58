"""Minimal amplitude point (MA) of Marin et al. (2003), as compared in paper A.

The centre of rotation is taken as the point fixed in the moving segment whose trajectory in the
reference frame moves least. Unlike the sphere fits it needs the segment's pose in every frame,
hence at least three non-collinear markers.
"""

from __future__ import annotations

import math
from functools import partial

import numpy as np

from jointbench.declared import Point
from jointbench.estimators import selfcheck
from jointbench.estimators.batching import isolated
from jointbench.estimators.registry import many, register, register_many
from jointbench.estimators.results import CenterResult
from jointbench.estimators.segment_poses import (
    POSE_MIN_FRAMES,
    stopped_fit,
    trial_poses,
    with_stopped_fits,
)
from jointbench.estimators.sphere import _check_point, _prepared_fits, fit_ls
from jointbench.estimators.validation import (
    check_markers,
    check_moves,
    check_not_collinear,
)
from jointbench.numerics.poses import fit_rigid_poses, rigid_poses
from jointbench.numerics.simplex import FMINSEARCH_OPTIONS, lockstep, stop_status

__all__ = ["amplitude", "fit_ma"]

# Fewest frames MA takes (registered as its claim, checked in _ma_prepare).
_MIN_FRAMES = 4


def _amplitudes(
    points: np.ndarray, rotation: np.ndarray, translation: np.ndarray, trials: np.ndarray
) -> np.ndarray:
    """Bounding-box sizes of ``q_k = R_k p + t_k`` for body-fixed points ``(k, 3)`` [mm], each
    in its trial's poses ``rotation[trials]`` ``(N, 3, 3)`` and ``translation[trials]``
    ``(N, 3)``.

    Element by element, so a point's amplitude is the same whichever points share the call (the
    one-trial search and the many-trial one then take the same path).
    """
    rotations, translations = rotation[trials], translation[trials]
    x, y, z = (points[:, axis, None, None] for axis in range(3))
    trajectory = rotations[..., 0] * x + rotations[..., 1] * y + rotations[..., 2] * z
    trajectory += translations
    sides = trajectory.max(axis=1) - trajectory.min(axis=1)
    return sides[:, 0] + sides[:, 1] + sides[:, 2]


def amplitude(rotation: np.ndarray, translation: np.ndarray, point: np.ndarray) -> float:
    """Amplitude of the trajectory of a body-fixed point: ``sum_xyz (max_k q_k - min_k q_k)``.

    Parameters
    ----------
    rotation : (n_frames, 3, 3), translation : (n_frames, 3) [mm]
        Pose of the moving segment per frame (body to reference frame).
    point : (3,) [mm], body-fixed coordinates ``p``; ``q_k = R_k p + t_k``.

    Returns
    -------
    The summed side lengths of the trajectory's axis-aligned bounding box [mm].
    """
    rotation = np.asarray(rotation, dtype=float)[None]
    translation = np.asarray(translation, dtype=float)[None]
    point = np.asarray(point, dtype=float)[None]
    return float(_amplitudes(point, rotation, translation, np.zeros(1, dtype=int))[0])


# The box is measured along the reference axes, so a rotation of noisy data is not followed;
# the simplex path depends on the coordinates (see the docstring).
@register(
    "center",
    "MA",
    invariances={"translation": 0.5, "marker_order": 1e-3, "frame_order": 1e-9},
    min_frames=_MIN_FRAMES,
    color="#e7298a",
    marker="D",
)
def fit_ma(markers: np.ndarray, start: Point | None = None) -> CenterResult:
    """Minimal amplitude point of Marin et al. (2003), minimised as in paper A (§5).

    1. Pose ``(R_k, t_k)`` of the moving segment in every frame by SVD with iterated body-fixed
       marker coordinates (:func:`jointbench.numerics.poses.rigid_poses`).
    2. The body-fixed point ``p`` minimising the amplitude of its trajectory
       ``q_k = R_k p + t_k``, ``sum_{x,y,z} (max_k q_k - min_k q_k)``, found by ``fminsearch``
       (:mod:`jointbench.numerics.simplex`) at its defaults (TolX = TolFun = 1e-4, at most 600
       iterations and evaluations), started from the LS centre (paper A initialised MA and IS
       with LS).

    Choices the papers leave open, made here:

    * Amplitude is the bounding-box size above, as in public implementations; Marin's exact
      definition was not confirmed. It is non-smooth (a sum of max/min), which Nelder–Mead
      tolerates but may stall on; a variance-based amplitude would be a different, linear
      estimator. The box is aligned with the reference frame's axes, so on noisy data the
      estimate depends on that frame's orientation (MA is not rotation invariant; noise-free
      it is, the minimum being the zero-amplitude centre). It moves with a translation of the
      data only to within the simplex's stopping point, which depends on the coordinates
      (tenths of a millimetre at 0.5 mm noise).
    * Body coordinates are those in which a point's coordinates are the mean of its trajectory
      (:func:`_mean_anchored`), not those of frame 0: the search is then over the reported
      centre itself, ``mean_k q_k(p) = p``, started at the LS centre with the simplex of
      ``fminsearch`` (5 % of its coordinates) in the reference frame's axes, and neither
      depends on which frame comes first (paper A does not say which body frame it used; one
      pinned to frame 0 moved the answer by 0.15 mm when a recording's frames were reversed).
    * ``q_k(p*)`` is not a single point when ``p*`` does not stay fixed; the reported centre is
      its mean over frames, ``mean_k q_k(p*) = p*`` [mm] (the bounding box's centre would be
      another choice; the mean is less sensitive to the extreme frames).

    Parameters
    ----------
    markers : (n_frames >= 4, n_markers >= 3, 3) array [mm], reference frame, not collinear.
    start : (3,) [mm] starting point in the reference frame; default the LS centre.

    Returns
    -------
    CenterResult with ``center`` (3,) [mm], ``radii=None``, ``cost`` the amplitude at ``p*``
    [mm], ``converged`` the optimiser's success (and the pose fit's: poses whose alternation
    stopped short say so, as every pose-based method's do), ``iterations`` its iteration count;
    ``diagnostics["body_point"]`` is ``p*`` in the body frame of
    :func:`jointbench.numerics.poses.rigid_poses` (its position at frame 0; a list [mm]), with
    ``diagnostics["function_evaluations"]``.
    """
    markers, start = _ma_prepare(markers, start)
    return _ma_fits([markers], [start])[0]


def _ma_prepare(markers: object, start: object | None) -> tuple[np.ndarray, np.ndarray]:
    """Validated markers and the starting point in the reference frame (default: LS centre)."""
    markers = check_markers(markers, min_frames=_MIN_FRAMES, min_markers=3)
    check_moves(markers)
    check_not_collinear(markers)
    return markers, fit_ls(markers).center if start is None else _check_point(start, "start")


def _mean_anchored(rotation: np.ndarray, translation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Poses ``(..., N, 3, 3)``, ``(..., N, 3)`` re-expressed so that a body point's coordinates
    are the mean of its trajectory: ``R_k' = R_k M^-1``, ``t_k' = t_k - R_k' t_mean`` with
    ``M = mean_k R_k`` and ``t_mean = mean_k t_k``, so ``mean_k (R_k' p + t_k') = p``.

    The body frame of :func:`rigid_poses` is pinned to frame 0; a search built in it starts
    from a point and a simplex that depend on which frame is first. These coordinates depend on
    no frame (a change of body frame ``R_k Q'`` cancels in ``R_k M^-1``), so the search, and
    MA's answer, do not depend on the order of the frames.
    """
    inverse = np.linalg.inv(rotation.mean(axis=-3))
    turned = rotation @ inverse[..., None, :, :]
    mean = translation.mean(axis=-2)
    return turned, translation - np.einsum("...kij,...j->...ki", turned, mean)


def _ma_result(search, rotation: np.ndarray, translation: np.ndarray) -> CenterResult:
    """MA's :class:`CenterResult` from its simplex search in the poses ``(N, 3, 3)``, ``(N, 3)``."""
    point = np.array(search.x)
    trajectory = rotation @ point + translation
    center = trajectory.mean(axis=0)
    finite = bool(np.all(np.isfinite(center)) and math.isfinite(search.fun))
    ok = search.converged and finite
    return CenterResult(
        center=center,
        radii=None,
        converged=ok,
        iterations=search.iterations,
        status="ok" if ok else stop_status(search, FMINSEARCH_OPTIONS["max_fev"]),
        method="MA",
        cost=float(search.fun),
        # In the body frame of rigid_poses, which is the reference frame at frame 0.
        diagnostics={
            "body_point": trajectory[0].tolist(),
            "function_evaluations": search.evaluations,
        },
    )


def _ma_fits(arrays: list[np.ndarray], starts: list[np.ndarray]) -> list[CenterResult]:
    """:func:`fit_ma` of validated trials (each ``(N, P, 3)`` [mm], the same shape) from
    ``starts`` (each ``(3,)`` [mm]), the searches advanced together
    (:func:`jointbench.numerics.simplex.lockstep`), each on its own path."""
    # Each trial's poses are those of its own call (the pose fit is per trial).
    poses = fit_rigid_poses(np.stack(arrays))
    rotations, translations = _mean_anchored(poses.rotation, poses.translation)
    searches = lockstep(
        lambda points, owners: _amplitudes(points, rotations, translations, owners),
        np.stack(starts),
        **FMINSEARCH_OPTIONS,
    )
    return [
        with_stopped_fits(
            _ma_result(search, rotations[trial], translations[trial]),
            []
            if poses.converged[trial]
            else [stopped_fit("markers", poses.iterations[trial], poses.change_mm[trial])],
        )
        for trial, search in enumerate(searches)
    ]


def _fit_ma_batch(markers: object, start: object | None = None) -> list[CenterResult | ValueError]:
    """:func:`fit_ma` for every trial of ``markers`` ``(n_trials, N, P, 3)``."""
    return _prepared_fits(markers, lambda data: _ma_prepare(data, start), _ma_fits)


def _ma_self_check(result: CenterResult, markers: np.ndarray, start=None) -> CenterResult:
    """MA's amplitude against its amplitude at the closed-form neighbours, the LS, NM and
    SCoRE centres (SCoRE's is the least-squares point fixed in the segment, the linear
    cousin of MA's); where one is lower by more than fminsearch's TolFun, MA restarted from it
    (one more search, paid only then). See :mod:`jointbench.estimators.selfcheck`."""
    return _ma_self_check_many([result], markers[None], start)[0]


def _ma_self_check_many(
    results: list[CenterResult], markers: np.ndarray, start=None
) -> list[CenterResult]:
    """:func:`_ma_self_check` of MA's answers ``results`` for the trials of ``markers``
    ``(T, N, P, 3)`` [mm] (or a list of equal-shape trials): the neighbours of all trials
    from the many-trial forms, SCoRE's and the amplitudes' from one pose fit (each trial's
    poses are those it has alone)."""
    del start  # each answer is judged, wherever it was started
    data = markers if isinstance(markers, np.ndarray) else np.stack(markers)
    poses = trial_poses({"markers": data}, min_frames=POSE_MIN_FRAMES)
    centres = {
        "the LS centre": many("center", "LS", checked=False)(data),
        "the NM centre": many("center", "NM", checked=False)(data),
        "the SCoRE centre": many("center", "SCoRE", checked=False)(data, poses=poses),
    }
    if isinstance(centres["the LS centre"][0], ValueError):
        raise centres["the LS centre"][0]  # as the one-trial fit would
    rotation, translation = _mean_anchored(*_segment_poses(data, poses))
    return [
        _ma_judged(
            result,
            data[trial],
            {
                name: np.asarray(outcomes[trial].center)
                for name, outcomes in centres.items()
                if not isinstance(outcomes[trial], ValueError)
            },
            rotation[trial],
            translation[trial],
        )
        for trial, result in enumerate(results)
    ]


def _segment_poses(data: np.ndarray, poses: list) -> tuple[np.ndarray, np.ndarray]:
    """Rotations ``(T, N, 3, 3)`` and translations ``(T, N, 3)`` [mm] of the trials ``data``
    from their :func:`trial_poses`; a trial those refuse (its body-fixed coordinates collinear)
    gets its own :func:`rigid_poses`, as MA's fit does."""
    rotations, translations = [], []
    for trial, fitted in enumerate(poses):
        if isinstance(fitted, ValueError):
            rotation, translation = rigid_poses(data[trial])[:2]
        else:
            rotation, translation = fitted["markers"].rotation, fitted["markers"].translation
        rotations.append(rotation)
        translations.append(translation)
    return np.stack(rotations), np.stack(translations)


def _ma_judged(
    result: CenterResult,
    markers: np.ndarray,
    neighbours: dict[str, np.ndarray],
    rotation: np.ndarray,
    translation: np.ndarray,
) -> CenterResult:
    """``result`` judged against the amplitudes at its ``neighbours`` (each ``(3,)`` [mm]) in
    the trial's mean-anchored poses ``rotation`` ``(N, 3, 3)``, ``translation`` ``(N, 3)``."""
    points = np.stack(list(neighbours.values()))
    costs = _amplitudes(points, rotation[None], translation[None], np.zeros(len(points), dtype=int))
    return selfcheck.lowest_neighbour(
        result,
        neighbours,
        costs,
        partial(fit_ma, markers),
        tol_fun=FMINSEARCH_OPTIONS["fatol"],
        cost_name="the amplitude",
        unit=" mm",
    )


fit_ma.self_check = _ma_self_check
fit_ma.self_check_many = _ma_self_check_many
register_many("center", "MA", isolated(_fit_ma_batch, min_frames=_MIN_FRAMES))
