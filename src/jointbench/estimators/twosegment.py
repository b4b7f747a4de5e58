"""SCoRE and SARA (Ehrig et al. 2006, 2007): joint centre and axis from two segments' poses.

Both segments' poses per frame come from :func:`jointbench.numerics.poses.rigid_poses` (paper C §5:
SVD fits alternating with re-estimated body-fixed marker coordinates); each body frame
coincides with the world at frame 0 (``R(0) = I``, ``t(0) = 0``).

SCoRE: a point fixed in both segments, ``c1`` in the proximal frame and ``c2`` in the distal
frame, has the same world position in every frame, ``R1 c1 + t1 = R2 c2 + t2``. Stacking the
frames gives the ``3N x 6`` least-squares problem ``[R1, -R2] [c1; c2] = t2 - t1``.

SARA: for a hinge the same matrix has a null vector: the axis direction ``n1`` (proximal frame)
and ``n2`` (distal frame) with ``R1 n1 = R2 n2``. The right singular vector of the smallest
singular value is taken as the axis (both frames); a point on the axis is the least-squares
solution with that singular value dropped (pseudo-inverse).

Numerics: the normal matrix of the stacked system is built from 3x3 sums,
``A'A = [[N I, -S], [-S', N I]]`` with ``S = sum_t R1' R2``, and ``A'b`` likewise, so no
``3N x 6`` matrix is formed. Its eigen-decomposition gives the right singular vectors of ``A``
and the squared singular values. Squaring the condition number is harmless here: the
eigenvalues are ``N -+ sigma_k(S)``, bounded by ``2N``, and a pose set that determines the
centre keeps the smallest well away from rounding level (the noise-free tests recover the
centre to ~1e-10 mm).

Degenerate motion: the relative rotation must not be about a single axis (SCoRE) and must not
vanish (SCoRE, SARA). An eigenvalue below ``1e-12`` of the largest counts as zero
(:mod:`jointbench.numerics.rank`) -- that is a
relative rotation off the axis of less than about 1e-6 rad, a thousand times below what markers
with micrometre noise resolve -- and raises ``ValueError``. Merely ill-conditioned motion is
solved as it is: its poor answer is what a benchmark should see.

One-segment use (``center`` "SCoRE", ``axis`` "SARA"): the markers are already in the
reference segment's frame, so the reference pose is exactly the identity (``R1 = I``,
``t1 = 0``) and the answer is ``c1`` (or the axis ``n1``, ``p1``), in the reference frame.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TypeVar

import numpy as np

from jointbench.declared import NonNegative
from jointbench.estimators.batching import NUMERICAL_FAILURES, each_alone, isolated
from jointbench.estimators.registry import register
from jointbench.estimators.results import AxisResult, CenterResult, JointCenterResult
from jointbench.estimators.validation import (
    check_markers,
    check_not_collinear,
    check_same_frames,
)
from jointbench.numerics.poses import rigid_poses
from jointbench.numerics.rank import negligible

__all__ = [
    "POSE_MIN_FRAMES",
    "SegmentPoses",
    "batched",
    "batched_all",
    "fit_sara",
    "fit_sara_two_segment",
    "fit_score",
    "fit_score_center",
    "pose_segments",
    "segment_poses",
    "stored_segment_poses",
    "trial_poses",
    "two_segment_poses",
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


def segment_poses(markers: np.ndarray, *, name: str) -> SegmentPoses:
    """Paper C §5 poses of one segment's (already checked) markers ``(N, n_markers, 3)``.

    Collinearity is checked on frame 0 (the starting body coordinates) and on the estimated
    body-fixed coordinates, which is what every frame's fit uses -- checking every frame would
    cost more than the fit.
    """
    check_not_collinear(markers[:1], name=name)
    return _segment_poses(markers, *rigid_poses(markers), name=name)


def _segment_poses(markers, rotation, translation, body, *, name: str) -> SegmentPoses:
    check_not_collinear(body[None], name=f"{name} (body-fixed coordinates)")
    # R_f b_p for every frame and marker as one (3N, 3) @ (3, P) product.
    turned = (rotation.reshape(-1, 3) @ body.T).reshape(len(rotation), 3, -1)
    residual = markers - np.swapaxes(turned, 1, 2) - translation[:, None, :]
    residual_ss = float(np.sum(residual * residual))
    return stored_segment_poses(markers, rotation, translation, body, residual_ss)


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


def two_segment_poses(
    proximal: object, distal: object, *, min_frames: int
) -> tuple[SegmentPoses, SegmentPoses]:
    """Check both segments' world-frame markers and fit their poses."""
    proximal = check_markers(proximal, min_frames=min_frames, min_markers=3, name="proximal")
    distal = check_markers(distal, min_frames=min_frames, min_markers=3, name="distal")
    check_same_frames(proximal, distal)
    return segment_poses(proximal, name="proximal"), segment_poses(distal, name="distal")


Outcome = TypeVar("Outcome")


def trial_poses(
    segments: dict[str, np.ndarray], *, min_frames: int
) -> list[dict[str, SegmentPoses] | ValueError]:
    """Poses of many trials at once: ``segments`` maps a name (``"markers"``, or ``"proximal"``
    and ``"distal"``) to ``(n_trials, N, n_markers, 3)`` [mm].

    Per trial, the checks of :func:`two_segment_poses` / :func:`segment_poses` in the same
    order, so a trial that the one-trial path rejects carries the same ``ValueError``; every
    segment's poses are fitted for all trials in one call of
    :func:`jointbench.numerics.poses.rigid_poses`. Compute them once and pass them to the
    ``batched`` form of every pose-based method.
    """
    names = list(segments)
    arrays = {name: np.asarray(markers, dtype=float) for name, markers in segments.items()}
    n_trials = next(iter(arrays.values())).shape[0]
    outcomes: list = [None] * n_trials
    for trial in range(n_trials):
        try:
            for name in names:
                check_markers(arrays[name][trial], min_frames=min_frames, min_markers=3, name=name)
            if len(names) == 2:
                check_same_frames(*(arrays[name][trial] for name in names))
            for name in names:
                check_not_collinear(arrays[name][trial, :1], name=name)
        except ValueError as error:
            outcomes[trial] = error
    good = [trial for trial in range(n_trials) if outcomes[trial] is None]
    fitted = {name: _fitted_poses(arrays[name][good]) for name in names}
    for index, trial in enumerate(good):
        try:
            outcomes[trial] = {
                name: _segment_poses(arrays[name][trial], *_parts(fitted[name][index]), name=name)
                for name in names
            }
        except ValueError as error:
            outcomes[trial] = error
    return outcomes


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


def each_trial(
    poses: list[dict[str, SegmentPoses] | ValueError],
    finish: Callable[[dict[str, SegmentPoses]], Outcome],
) -> list[Outcome | ValueError]:
    """``finish`` applied to every trial's poses; a trial's ``ValueError`` is kept as its value."""
    outcomes: list = []
    for trial_poses_ in poses:
        if isinstance(trial_poses_, ValueError):
            outcomes.append(trial_poses_)
            continue
        try:
            outcomes.append(finish(trial_poses_))
        except ValueError as error:
            outcomes.append(error)
    return outcomes


def stacked_normal_equations(
    r1: np.ndarray | None, t1: np.ndarray | None, r2: np.ndarray, t2: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``A'A`` ``(6, 6)`` and ``A'b`` ``(6,)`` of ``A = [R1, -R2]`` (stacked), ``b = t2 - t1``.

    ``r1 = t1 = None`` means the identity reference pose (one-segment data).
    """
    n_frames = r2.shape[0]
    rhs = t2 if t1 is None else t2 - t1
    normal = np.empty((6, 6))
    normal[:3, :3] = normal[3:, 3:] = n_frames * np.eye(3)
    if r1 is None:
        s = r2.sum(axis=0)
        g1 = rhs.sum(axis=0)
    else:
        s = np.einsum("fji,fjk->ik", r1, r2)
        g1 = np.einsum("fji,fj->i", r1, rhs)
    normal[:3, 3:] = -s
    normal[3:, :3] = -s.T
    g2 = -np.einsum("fji,fj->i", r2, rhs)
    return normal, np.concatenate([g1, g2])


def _eigen(normal: np.ndarray, *, what: str, min_rank: int) -> tuple[np.ndarray, np.ndarray]:
    """Eigen-decomposition of a normal matrix; ``ValueError`` when its rank is below
    ``min_rank`` (the segments do not rotate relative to each other, or only about one axis)."""
    values, vectors = np.linalg.eigh(normal)
    zero = negligible(values, values[-1])
    rank = int(np.sum(~zero))
    if rank < min_rank:
        if rank <= 3:
            problem = "the segments do not rotate relative to each other"
        else:
            problem = (
                "the relative rotation is about a single axis (a hinge), so the centre is not "
                "determined along that axis; fit an axis (SARA) instead"
            )
        raise ValueError(f"{what}: degenerate motion: {problem}")
    return values, vectors


def _residual_ss(r1, t1, c1, r2, t2, c2) -> float:
    """``sum_t |R1 c1 + t1 - R2 c2 - t2|^2`` [mm^2]; ``r1 = t1 = None`` is the identity."""
    world2 = r2 @ c2 + t2
    world1 = c1 if r1 is None else r1 @ c1 + t1
    return float(np.sum((world1 - world2) ** 2))


def _score_solve(r1, t1, r2, t2, *, what: str) -> tuple[np.ndarray, np.ndarray, float]:
    normal, rhs = stacked_normal_equations(r1, t1, r2, t2)
    values, vectors = _eigen(normal, what=what, min_rank=6)
    solution = vectors @ ((vectors.T @ rhs) / values)
    return solution[:3], solution[3:], float(values[0] / values[-1])


@register("joint_center", "SCoRE", min_frames=POSE_MIN_FRAMES, color="#a6761d", marker="P")
def fit_score(
    proximal: np.ndarray, distal: np.ndarray, *, noise_mm: NonNegative | None = None
) -> JointCenterResult:
    """Symmetrical Centre of Rotation Estimation (Ehrig et al. 2006) for two moving segments.

    Parameters
    ----------
    proximal, distal : (n_frames >= 3, n_markers >= 3, 3) [mm], world frame, same frames.
    noise_mm : accepted for a uniform ``joint_center`` signature; SCoRE does not use it.

    Returns
    -------
    JointCenterResult
        ``center`` ``(3,)`` [mm] in the body-fixed frame shared at frame 0 (the world at frame
        0): the mean of the two segments' estimates mapped by their frame-0 poses,
        ``(R1(0) c1 + t1(0) + R2(0) c2 + t2(0)) / 2``, i.e. the least-squares world position of
        the joint at frame 0 (Ehrig et al. average the two per-frame positions the same way).
        ``covariance`` is ``None``. ``cost`` is ``sum_t |R1 c1 + t1 - R2 c2 - t2|^2`` [mm^2].
        ``diagnostics``: ``center_proximal`` ``c1``, ``center_distal`` ``c2`` (body frames) and
        ``rcond`` (smallest over largest eigenvalue of the normal matrix).
    """
    del noise_mm
    return _score_joint(*two_segment_poses(proximal, distal, min_frames=POSE_MIN_FRAMES))


def _score_joint(prox: SegmentPoses, dist: SegmentPoses) -> JointCenterResult:
    r1, t1, r2, t2 = prox.rotation, prox.translation, dist.rotation, dist.translation
    c1, c2, rcond = _score_solve(r1, t1, r2, t2, what="SCoRE")
    world = 0.5 * (r1[0] @ c1 + t1[0] + r2[0] @ c2 + t2[0])
    return JointCenterResult(
        center=world,
        covariance=None,
        converged=True,
        iterations=0,
        status="ok",
        method="SCoRE",
        cost=_residual_ss(r1, t1, c1, r2, t2, c2),
        diagnostics={"center_proximal": c1.tolist(), "center_distal": c2.tolist(), "rcond": rcond},
    )


@register("center", "SCoRE", min_frames=POSE_MIN_FRAMES, color="#a6761d", marker="P")
def fit_score_center(markers: np.ndarray) -> CenterResult:
    """SCoRE for one segment whose markers ``(n_frames >= 3, n_markers >= 3, 3)`` [mm] are
    already in the reference segment's frame: the reference pose is the identity, so the
    stacked system is ``[I, -R2] [c1; c2] = t2``; the centre ``c1`` is in the reference frame.
    ``cost`` is ``sum_t |c1 - R2 c2 - t2|^2`` [mm^2]; ``radii`` is ``None``.
    """
    markers = check_markers(markers, min_frames=POSE_MIN_FRAMES, min_markers=3)
    return _score_center(segment_poses(markers, name="markers"))


def _score_center(poses: SegmentPoses) -> CenterResult:
    r2, t2 = poses.rotation, poses.translation
    c1, c2, rcond = _score_solve(None, None, r2, t2, what="SCoRE")
    return CenterResult(
        center=c1,
        converged=True,
        iterations=0,
        status="ok",
        method="SCoRE",
        cost=_residual_ss(None, None, c1, r2, t2, c2),
        diagnostics={"center_moving": c2.tolist(), "rcond": rcond},
    )


def _sara_solve(
    r1, t1, r2, t2, origin: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """Axis directions ``n1``, ``n2`` (unit) and points ``p1``, ``p2`` of SARA.

    Both body frames coincide with the world at frame 0. The point is the minimum-norm
    least-squares solution about ``origin`` (3,) [mm] with the axis direction dropped, so
    ``(p1 - origin) . n1 + (p2 - origin) . n2 = 0``: for a noise-free hinge, the point of the
    axis nearest ``origin``. Solving about a point near the markers (not the coordinates'
    origin) keeps the right-hand side small, so the answer does not lose digits to the data's
    distance from the origin.
    """
    # Each body frame moved to ``origin``: x = R (b' + o) + t, so t' = R o + t - o.
    t2 = np.einsum("fij,j->fi", r2, origin) + t2 - origin
    if r1 is not None:
        t1 = np.einsum("fij,j->fi", r1, origin) + t1 - origin
    normal, rhs = stacked_normal_equations(r1, t1, r2, t2)
    values, vectors = _eigen(normal, what="SARA", min_rank=5)
    axis = vectors[:, 0]
    rest = vectors[:, 1:]
    point = rest @ ((rest.T @ rhs) / values[1:])
    n1, n2 = axis[:3], axis[3:]
    return (
        n1 / np.linalg.norm(n1),
        n2 / np.linalg.norm(n2),
        point[:3] + origin,
        point[3:] + origin,
        float(values[0] / values[1]),
    )


def _mean_distance_to_axis(points: np.ndarray, point: np.ndarray, direction: np.ndarray):
    """Mean over frames of each marker's distance from the line ``(point, direction)``."""
    offset = points - point
    along = offset @ direction
    perpendicular = offset - along[..., None] * direction
    return np.linalg.norm(perpendicular, axis=-1).mean(axis=0)


@register("axis", "SARA", min_frames=POSE_MIN_FRAMES, color="#543005", marker="P")
def fit_sara(markers: np.ndarray) -> AxisResult:
    """Symmetrical Axis of Rotation Approach (Ehrig et al. 2007) for one segment whose markers
    ``(n_frames >= 3, n_markers >= 3, 3)`` [mm] are in the reference segment's frame.

    The reference pose is the identity (``R1 = I``, ``t1 = 0``); the axis ``(p1, n1)`` is
    returned in the reference frame, ``p1`` its point nearest the moving markers' centroid at
    frame 0 (for a noise-free hinge). ``radii`` are the markers' mean distances from the axis
    [mm]. ``diagnostics["ratio"]`` is the smallest over the second-smallest eigenvalue of the
    normal matrix: near 0 for hinge-like motion, near 1 when no axis stands out.
    """
    markers = check_markers(markers, min_frames=POSE_MIN_FRAMES, min_markers=3)
    return _sara(segment_poses(markers, name="markers"))


def _sara(poses: SegmentPoses) -> AxisResult:
    origin = poses.body.mean(axis=0)
    n1, n2, p1, p2, ratio = _sara_solve(None, None, poses.rotation, poses.translation, origin)
    return AxisResult(
        point=p1,
        direction=n1,
        radii=_mean_distance_to_axis(poses.markers, p1, n1),
        converged=True,
        iterations=0,
        status="ok",
        method="SARA",
        diagnostics={"direction_moving": n2.tolist(), "point_moving": p2.tolist(), "ratio": ratio},
    )


def fit_sara_two_segment(proximal: np.ndarray, distal: np.ndarray) -> AxisResult:
    """SARA for two segments moving in the world ``(n_frames >= 3, n_markers >= 3, 3)`` [mm].

    The axis is returned in the body-fixed frame shared at frame 0 (the world at frame 0) as
    the mean of the two segments' versions mapped by their frame-0 poses: direction
    ``unit(R1(0) n1 + R2(0) n2)`` (one eigenvector gives both, so their signs agree), point
    ``(R1(0) p1 + t1(0) + R2(0) p2 + t2(0)) / 2``. ``radii`` are the distal markers' mean
    distances from the axis ``(p1, n1)`` in the proximal frame [mm]. ``diagnostics`` carries each
    frame's version and ``ratio`` (see :func:`fit_sara`).
    """
    prox, dist = two_segment_poses(proximal, distal, min_frames=POSE_MIN_FRAMES)
    r1, t1, r2, t2 = prox.rotation, prox.translation, dist.rotation, dist.translation
    n1, n2, p1, p2, ratio = _sara_solve(r1, t1, r2, t2, dist.body.mean(axis=0))
    direction = r1[0] @ n1 + r2[0] @ n2
    point = 0.5 * (r1[0] @ p1 + t1[0] + r2[0] @ p2 + t2[0])
    distal_in_proximal = np.einsum("fji,fmj->fmi", r1, dist.markers - t1[:, None, :])
    return AxisResult(
        point=point,
        direction=direction / np.linalg.norm(direction),
        radii=_mean_distance_to_axis(distal_in_proximal, p1, n1),
        converged=True,
        iterations=0,
        status="ok",
        method="SARA",
        diagnostics={
            "direction_proximal": n1.tolist(),
            "point_proximal": p1.tolist(),
            "direction_distal": n2.tolist(),
            "point_distal": p2.tolist(),
            "ratio": ratio,
        },
    )


def batched(
    finish: Callable[..., Outcome], names: tuple[str, ...]
) -> Callable[..., list[Outcome | ValueError]]:
    """The many-trial form of a pose-based method: ``(*segments, poses=None, **options)``.

    Each segment is ``(n_trials, N, n_markers, 3)`` [mm]; ``poses`` (from :func:`trial_poses`)
    lets several methods share one pose fit. Returns one result, or the ``ValueError`` the
    one-trial function would raise, per trial; options the method ignores are accepted as the
    one-trial function accepts them. ``finish(*segment_poses, **options)`` fits one trial.
    """

    def finish_each(poses: list, **options) -> list[Outcome | ValueError]:
        return each_trial(poses, lambda p: finish(*(p[name] for name in names), **options))

    return batched_all(finish_each, names)


def batched_all(
    finish_all: Callable[..., list[Outcome | ValueError]], names: tuple[str, ...]
) -> Callable[..., list[Outcome | ValueError]]:
    """:func:`batched` for a method that fits all trials' poses in one call:
    ``finish_all(poses, **options)`` takes every trial's poses (or its ``ValueError``)."""

    def run(*segments: np.ndarray, poses=None, **options) -> list[Outcome | ValueError]:
        if poses is None:
            segments_by_name = dict(zip(names, segments, strict=True))
            poses = trial_poses(segments_by_name, min_frames=POSE_MIN_FRAMES)
        return finish_all(poses, **options)

    run.pose_segments = names
    return isolated(run)


def pose_segments(fit: Callable) -> tuple[str, ...] | None:
    """The segments whose poses (from :func:`trial_poses`) the ``batched`` form of ``fit``
    accepts as ``poses=``, or ``None`` when it is not pose-based."""
    return getattr(getattr(fit, "batched", None), "pose_segments", None)


def _ignoring_noise(finish: Callable[..., Outcome]) -> Callable[..., Outcome]:
    def run(*poses: SegmentPoses, noise_mm: float | None = None) -> Outcome:
        del noise_mm
        return finish(*poses)

    return run


fit_score.batched = batched(_ignoring_noise(_score_joint), ("proximal", "distal"))
fit_score_center.batched = batched(_score_center, ("markers",))
fit_sara.batched = batched(_sara, ("markers",))
