"""Minimal amplitude point (MA) of Marin et al. (2003), as compared in paper A.

The centre of rotation is taken as the point fixed in the moving segment whose trajectory in the
reference frame moves least. Unlike the sphere fits it needs the segment's pose in every frame,
hence at least three non-collinear markers.
"""

from __future__ import annotations

import math

import numpy as np

from jointbench.estimators.registry import register
from jointbench.estimators.results import CenterResult
from jointbench.estimators.sphere import _check_point, fit_ls
from jointbench.estimators.validation import check_markers, check_moves, check_not_collinear
from jointbench.numerics.poses import rigid_poses
from jointbench.numerics.simplex import FMINSEARCH_OPTIONS, nelder_mead, stop_status

__all__ = ["amplitude", "fit_ma"]


def _amplitude(point: np.ndarray, stacked: np.ndarray, translation: np.ndarray) -> float:
    """Bounding-box size of ``q_k = R_k p + t_k``; ``stacked`` is ``R`` as ``(3 N, 3)`` rows."""
    trajectory = (stacked @ point).reshape(-1, 3) + translation
    return float(np.sum(trajectory.max(axis=0) - trajectory.min(axis=0)))


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
    rotation = np.asarray(rotation, dtype=float)
    stacked = rotation.reshape(-1, 3)
    return _amplitude(np.asarray(point, dtype=float), stacked, np.asarray(translation, float))


@register("center", "MA")
def fit_ma(markers: np.ndarray, start: np.ndarray | None = None) -> CenterResult:
    """Minimal amplitude point of Marin et al. (2003), minimised as in paper A (§5).

    1. Pose ``(R_k, t_k)`` of the moving segment in every frame by SVD with iterated body-fixed
       marker coordinates (:func:`jointbench.numerics.poses.rigid_poses`); the body frame coincides
       with the reference frame at frame 0.
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
    * The start is expressed in the body frame through frame 0's pose,
      ``p_0 = R_0' (c_LS - t_0)``, so the simplex (5 % of ``p_0``'s coordinates) is built in
      the body frame, which at frame 0 is the reference frame.
    * ``q_k(p*)`` is not a single point when ``p*`` does not stay fixed; the reported centre is
      its mean over frames, ``mean_k q_k(p*)`` [mm] (the bounding box's centre would be
      another choice; the mean is less sensitive to the extreme frames).

    Parameters
    ----------
    markers : (n_frames >= 4, n_markers >= 3, 3) array [mm], reference frame, not collinear.
    start : (3,) [mm] starting point in the reference frame; default the LS centre.

    Returns
    -------
    CenterResult with ``center`` (3,) [mm], ``radii=None``, ``cost`` the amplitude at ``p*``
    [mm], ``converged`` the optimiser's success, ``iterations`` its iteration count;
    ``diagnostics["body_point"]`` is ``p*`` (a list [mm]), with
    ``diagnostics["function_evaluations"]``.
    """
    markers = check_markers(markers, min_frames=4, min_markers=3)
    check_moves(markers)
    check_not_collinear(markers)
    start = fit_ls(markers).center if start is None else _check_point(start, "start")
    rotation, translation, _ = rigid_poses(markers)
    body_start = rotation[0].T @ (start - translation[0])
    stacked = np.ascontiguousarray(rotation.reshape(-1, 3))
    search = nelder_mead(
        lambda *p: _amplitude(np.array(p), stacked, translation), body_start, **FMINSEARCH_OPTIONS
    )
    point = np.array(search.x)
    trajectory = (stacked @ point).reshape(-1, 3) + translation
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
        diagnostics={"body_point": point.tolist(), "function_evaluations": search.evaluations},
    )
