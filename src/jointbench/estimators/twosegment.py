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

Poses the alternation did not bring to its fixed point (it stops after
:data:`jointbench.numerics.poses.POSE_MAX_ITERATIONS` re-estimations) are not the
least-squares poses, and an answer from them moves with the starting frame: every pose-based
method's result on them reads ``converged=False`` and says which segment's fit stopped where
(:func:`batched_all`).

One-segment use (``center`` "SCoRE", ``axis`` "SARA"): the markers are already in the
reference segment's frame, so the reference pose is exactly the identity (``R1 = I``,
``t1 = 0``) and the answer is ``c1`` (or the axis ``n1``, ``p1``), in the reference frame.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import TypeVar

import numpy as np

from jointbench.declared import NonNegative
from jointbench.estimators import precision
from jointbench.estimators.batching import isolated, one_trial
from jointbench.estimators.pose_noise import centre_covariance, score_covariance
from jointbench.estimators.registry import register, register_many
from jointbench.estimators.results import (
    AxisResult,
    CenterResult,
    JointCenterResult,
    with_warnings,
)
from jointbench.estimators.segment_poses import (
    POSE_MIN_FRAMES,
    SegmentPoses,
    stopped_fit,
    trial_poses,
    with_stopped_fits,
)
from jointbench.numerics.compiled import kernel, kernel_array
from jointbench.numerics.joint_system import stacked_normal_equations
from jointbench.numerics.rank import negligible
from jointbench.numerics.small import inertia_into, tangent_basis_into

__all__ = [
    "PoseStack",
    "batched",
    "batched_all",
    "eigen_solution",
    "fit_sara",
    "fit_sara_two_segment",
    "fit_score",
    "fit_score_center",
    "trial_outcomes",
]

Outcome = TypeVar("Outcome")


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


def _stacked(field: str) -> functools.cached_property:
    """A :class:`PoseStack` attribute: ``field`` of its trials' poses, stacked when first read."""
    return functools.cached_property(
        lambda stack: np.stack([getattr(pose, field) for pose in stack.poses])
    )


class PoseStack:
    """The poses of trials with the same numbers of frames and markers (``poses``, one
    :class:`SegmentPoses` per trial), stacked on a leading trial axis as a method reads them:
    ``markers`` ``(T, N, P, 3)`` [mm], ``rotation`` ``(T, N, 3, 3)``, ``translation``
    ``(T, N, 3)`` [mm], ``body`` ``(T, P, 3)`` [mm]. A method that does not read the markers
    does not pay for stacking them."""

    markers = _stacked("markers")
    rotation = _stacked("rotation")
    translation = _stacked("translation")
    body = _stacked("body")

    def __init__(self, poses: list[SegmentPoses]) -> None:
        self.poses = poses


def _eigen(
    normal: np.ndarray, *, what: str, min_rank: int
) -> tuple[np.ndarray, np.ndarray, list[ValueError | None]]:
    """Eigen-decomposition of normal matrices ``(T, 6, 6)``, and per trial ``None`` or the
    ``ValueError`` of a rank below ``min_rank`` (the segments do not rotate relative to each
    other, or only about one axis)."""
    values, vectors = np.linalg.eigh(normal)
    ranks = np.sum(~negligible(values, values[:, -1:]), axis=1)
    return values, vectors, [_rank_error(int(rank), what, min_rank) for rank in ranks]


def _rank_error(rank: int, what: str, min_rank: int) -> ValueError | None:
    if rank >= min_rank:
        return None
    if rank <= 3:
        problem = "the segments do not rotate relative to each other"
    else:
        problem = (
            "the relative rotation is about a single axis (a hinge), so the centre is not "
            "determined along that axis; fit an axis (SARA) instead"
        )
    return ValueError(f"{what}: degenerate motion: {problem}")


def _applied(rotation: np.ndarray, point: np.ndarray) -> np.ndarray:
    """``R_f p`` for rotations ``(T, N, 3, 3)`` and a point per trial ``(T, 3)``: ``(T, N, 3)``."""
    return np.einsum("tfij,tj->tfi", rotation, point)


def _residual_ss(r1, t1, c1, r2, t2, c2) -> np.ndarray:
    """``sum_f |R1 c1 + t1 - R2 c2 - t2|^2`` [mm^2] per trial ``(T,)``; ``r1 = t1 = None`` is
    the identity."""
    world2 = _applied(r2, c2) + t2
    world1 = c1[:, None, :] if r1 is None else _applied(r1, c1) + t1
    return np.sum((world1 - world2) ** 2, axis=(1, 2))


def eigen_solution(vectors: np.ndarray, values: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """``V diag(1 / values) V' b`` per trial: the least-squares solution of normal equations
    from their eigenvectors ``V`` ``(T, n, k)`` (all ``n``, or ``k`` of them to drop a
    direction), eigenvalues ``(T, k)`` and right-hand sides ``b`` ``(T, n)``: ``(T, n)``."""
    # Negligible eigenvalues (only a trial rejected for its rank has any) are left out, so that
    # trial's unused answer stays finite.
    kept = np.where(negligible(values, values[:, -1:]), np.inf, values)
    projected = (np.swapaxes(vectors, 1, 2) @ rhs[..., None])[..., 0] / kept
    return (vectors @ projected[..., None])[..., 0]


def _score_solve(r1, t1, r2, t2) -> tuple[np.ndarray, np.ndarray, np.ndarray, list]:
    """SCoRE's ``c1``, ``c2`` ``(T, 3)`` [mm], rcond ``(T,)`` and per-trial rank errors."""
    normal, rhs = stacked_normal_equations(r1, t1, r2, t2)
    values, vectors, errors = _eigen(normal, what="SCoRE", min_rank=6)
    solution = eigen_solution(vectors, values, rhs)
    return solution[:, :3], solution[:, 3:], values[:, 0] / values[:, -1], errors


def trial_outcomes(errors: list[ValueError | None], result: Callable[[int], Outcome]) -> list:
    """Per trial its error (a ``ValueError``), or ``result(trial)`` when it has none."""
    return [result(trial) if error is None else error for trial, error in enumerate(errors)]


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
    return one_trial(_score_trials, proximal, distal, noise_mm=noise_mm)


def _score_joint(prox: PoseStack, dist: PoseStack) -> list[JointCenterResult | ValueError]:
    r1, t1, r2, t2 = prox.rotation, prox.translation, dist.rotation, dist.translation
    c1, c2, rcond, errors = _score_solve(r1, t1, r2, t2)
    at_frame0 = _applied(r1[:, :1], c1)[:, 0], _applied(r2[:, :1], c2)[:, 0]
    world = 0.5 * (at_frame0[0] + t1[:, 0] + at_frame0[1] + t2[:, 0])
    cost = _residual_ss(r1, t1, c1, r2, t2, c2)
    return trial_outcomes(
        errors,
        lambda t: JointCenterResult(
            center=world[t],
            covariance=None,
            converged=True,
            iterations=0,
            status="ok",
            method="SCoRE",
            cost=float(cost[t]),
            diagnostics={
                "center_proximal": c1[t].tolist(),
                "center_distal": c2[t].tolist(),
                "rcond": float(rcond[t]),
            },
        ),
    )


def score_scattered(
    result: JointCenterResult, proximal: SegmentPoses, distal: SegmentPoses
) -> JointCenterResult:
    """SCoRE's joint-centre ``result`` with the covariance of its centre on the poses it was
    fitted to (:func:`jointbench.estimators.pose_noise.score_covariance`),
    ``diagnostics["center_covariance_mm2"]``."""
    points = (result.diagnostics["center_proximal"], result.diagnostics["center_distal"])
    covariance = centre_covariance(score_covariance, proximal, distal, points)
    return with_warnings(result, (), {"center_covariance_mm2": covariance.tolist()})


# Its precision_many, this covariance held to the model test, is set in
# jointbench.estimators.hjc, where that test lives.


@register("center", "SCoRE", min_frames=POSE_MIN_FRAMES, color="#a6761d", marker="P")
def fit_score_center(markers: np.ndarray) -> CenterResult:
    """SCoRE for one segment whose markers ``(n_frames >= 3, n_markers >= 3, 3)`` [mm] are
    already in the reference segment's frame: the reference pose is the identity, so the
    stacked system is ``[I, -R2] [c1; c2] = t2``; the centre ``c1`` is in the reference frame.
    ``cost`` is ``sum_t |c1 - R2 c2 - t2|^2`` [mm^2]; ``radii`` is ``None``.
    """
    return one_trial(_score_center_trials, markers)


def _score_center(poses: PoseStack) -> list[CenterResult | ValueError]:
    r2, t2 = poses.rotation, poses.translation
    c1, c2, rcond, errors = _score_solve(None, None, r2, t2)
    cost = _residual_ss(None, None, c1, r2, t2, c2)
    return trial_outcomes(
        errors,
        lambda t: CenterResult(
            center=c1[t],
            converged=True,
            iterations=0,
            status="ok",
            method="SCoRE",
            cost=float(cost[t]),
            diagnostics={"center_moving": c2[t].tolist(), "rcond": float(rcond[t])},
        ),
    )


def _sara_solve(r1, t1, r2, t2, origin: np.ndarray):
    """SARA's axis directions ``n1``, ``n2`` (unit) and points ``p1``, ``p2`` [mm], each
    ``(T, 3)``, the normal matrices' eigenvalues ``(T, 6)`` (ascending) and eigenvectors
    ``(T, 6, 6)`` (columns) and the per-trial rank errors.

    Both body frames coincide with the world at frame 0. The point is the minimum-norm
    least-squares solution about ``origin`` ``(T, 3)`` [mm] with the axis direction dropped, so
    ``(p1 - origin) . n1 + (p2 - origin) . n2 = 0``: for a noise-free hinge, the point of the
    axis nearest ``origin``. Solving about a point near the markers (not the coordinates'
    origin) keeps the right-hand side small, so the answer does not lose digits to the data's
    distance from the origin.
    """
    # Each body frame moved to ``origin``: x = R (b' + o) + t, so t' = R o + t - o.
    t2 = _applied(r2, origin) + t2 - origin[:, None, :]
    if r1 is not None:
        t1 = _applied(r1, origin) + t1 - origin[:, None, :]
    normal, rhs = stacked_normal_equations(r1, t1, r2, t2)
    values, vectors, errors = _eigen(normal, what="SARA", min_rank=5)
    axis = vectors[:, :, 0]
    point = eigen_solution(vectors[:, :, 1:], values[:, 1:], rhs)
    n1, n2 = axis[:, :3], axis[:, 3:]
    return (
        n1 / np.linalg.norm(n1, axis=1, keepdims=True),
        n2 / np.linalg.norm(n2, axis=1, keepdims=True),
        point[:, :3] + origin,
        point[:, 3:] + origin,
        values,
        vectors,
        errors,
    )


def _mean_distance_to_axis(points: np.ndarray, point: np.ndarray, direction: np.ndarray):
    """Mean over frames of each marker's distance [mm] from the line ``(point, direction)``,
    per trial: points ``(T, N, P, 3)``, one line per trial ``(T, 3)`` -> ``(T, P)``."""
    offset = points - point[:, None, None, :]
    along = np.einsum("tfpi,ti->tfp", offset, direction)
    perpendicular = offset - along[..., None] * direction[:, None, None, :]
    return np.linalg.norm(perpendicular, axis=-1).mean(axis=1)


@register("axis", "SARA", min_frames=POSE_MIN_FRAMES, color="#543005", marker="P")
def fit_sara(markers: np.ndarray) -> AxisResult:
    """Symmetrical Axis of Rotation Approach (Ehrig et al. 2007) for one segment whose markers
    ``(n_frames >= 3, n_markers >= 3, 3)`` [mm] are in the reference segment's frame.

    The reference pose is the identity (``R1 = I``, ``t1 = 0``); the axis ``(p1, n1)`` is
    returned in the reference frame, ``p1`` its point nearest the moving markers' centroid at
    frame 0 (for a noise-free hinge). ``radii`` are the markers' mean distances from the axis
    [mm]. ``diagnostics["ratio"]`` is the smallest over the second-smallest eigenvalue of the
    normal matrix: near 0 for hinge-like motion, near 1 when no axis stands out;
    ``diagnostics["eigenvalues"]`` ``(6,)`` and ``["eigenvectors"]`` ``(6, 6)`` (columns) are
    that matrix's, from which the checked call states the direction's SD (:func:`_sara_sd_deg`)
    and the covariance of the point ``p1`` across the axis
    (``diagnostics["axis_point_covariance_mm2"]``, :func:`_sara_point_covariance`; with
    ``diagnostics["point_moving"]``, ``p2``): the minimum-norm least-squares point, which
    for a noise-free hinge is the axis's point nearest the cluster's centroid at frame 0, on a
    short arc is pulled towards it by the rotations' noise, tens of millimetres at a few
    degrees, a bias that covariance holds.
    """
    return one_trial(_sara_trials, markers)


def _sara(poses: PoseStack) -> list[AxisResult | ValueError]:
    origin = poses.body.mean(axis=1)
    n1, n2, p1, p2, values, vectors, errors = _sara_solve(
        None, None, poses.rotation, poses.translation, origin
    )
    radii = _mean_distance_to_axis(poses.markers, p1, n1)
    # The eigen-problem is kept for the checked call's precision (:func:`_sara_sd_deg`).
    return _sara_results(
        errors,
        p1,
        n1,
        radii,
        values,
        direction_moving=n2,
        point_moving=p2,
        eigenvalues=values,
        eigenvectors=vectors,
    )


def _sara_results(errors, point, direction, radii, values, **versions) -> list:
    """Per trial its rank error or its SARA :class:`AxisResult`, from the stacks ``(T, ...)``
    of the answer and of the ``versions`` the diagnostics carry (with ``ratio``, of the
    eigenvalues ``values`` ``(T, 6)``)."""
    # A trial without relative rotation has a zero second eigenvalue; its error is returned.
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = values[:, 0] / values[:, 1]
    return trial_outcomes(
        errors,
        lambda t: AxisResult(
            point=point[t],
            direction=direction[t],
            radii=radii[t],
            converged=True,
            iterations=0,
            status="ok",
            method="SARA",
            diagnostics={
                **{name: version[t].tolist() for name, version in versions.items()},
                "ratio": float(ratio[t]),
            },
        ),
    )


@kernel
def _sara_sd_deg(values: np.ndarray, vectors: np.ndarray, n_frames: int, n_distinct: int) -> float:
    """The SD [deg] of SARA's one-segment direction ``n1`` implied by its eigen-problem
    (:mod:`jointbench.estimators.precision`): the normal matrix ``M = A'A`` ``(6, 6)`` of
    ``n_frames`` frames, ``n_distinct`` of them distinct, by its ascending eigenvalues ``values``
    ``(6,)`` and eigenvectors ``vectors`` ``(6, 6)`` (columns).

    Noise in a frame's rotation ``R_k`` moves ``A v`` (``v = [n1; n2]`` the null vector) by
    ``e_k = n1 x dw_k``, ``dw_k`` the rotation's error; to first order the null vector moves by
    ``dv = -sum_j v_j (v_j' A' e) / (lambda_j - lambda_0)`` over the other eigenvectors, so with
    ``e`` of variance ``tau^2`` per component ``cov(dv) = tau^2 sum_j lambda_j v_j v_j' /
    (lambda_j - lambda_0)^2``: the eigenvalue gap above the smallest, the noise's own share of
    ``M``, sets the precision, as ``S - lambda I`` does for the planar cost. ``e_k`` is normal
    to ``n1`` (its component along ``n1`` moves ``v`` only along ``[n1; -n2]``, which leaves
    the direction of ``n1`` as it is), so ``tau^2 = lambda_0 / (2 N - 4)``: two components a
    frame, less the four of ``v`` they fit. Repeated frames scale ``M`` and ``lambda_0`` alike;
    the covariance is scaled by ``n_frames / n_distinct`` to the distinct frames'. ``inf``
    where no gap separates the smallest eigenvalue or ``2 N - 4 < 1``. A compiled kernel, as
    :func:`_sara_validity` is: in NumPy, their products of 3 x 3 matrices cost a checked SARA
    call on a short trial more than its fit's own eigen-problem.
    """
    dof = 2 * n_frames - 4
    if dof < 1 or not (values[1:] - values[0] > 0.0).all():
        return math.inf
    tau_sq = max(values[0], 0.0) / dof
    # The 3 x 3 block of the covariance tau^2 sum_j lambda_j v_j v_j' / (lambda_j - lambda_0)^2.
    block = np.zeros((3, 3))
    for j in range(1, 6):
        weight = values[j] / (values[j] - values[0]) ** 2
        for i in range(3):
            for k in range(3):
                block[i, k] += vectors[i, j] * weight * vectors[k, j]
    block *= tau_sq * n_frames / n_distinct
    # n1 is the null vector's first half, normalised: its tangent moves as that half does.
    half = vectors[:3, 0].copy()
    length = math.sqrt(half[0] ** 2 + half[1] ** 2 + half[2] ** 2)
    basis = np.empty((3, 2))
    tangent_basis_into(half / length, basis)
    tangent = 0.0
    for c in range(2):
        tangent += _bilinear(basis[:, c], block, basis[:, c])
    return math.degrees(math.sqrt(max(tangent / length**2, 0.0)))


@kernel
def _sara_validity(values: np.ndarray, vectors: np.ndarray, shape: np.ndarray) -> tuple:
    """What tells whether SARA's first-order SD holds (:mod:`jointbench.estimators.precision`):
    ``(share, gap, bias_deg)``, the noise's share of the normal matrix in the tangent direction
    most exposed to it, the matrix's smallest eigenvalue gap (both in its unit) and the pull
    [deg] the noise's anisotropy gives the null vector, for the ascending eigenvalues
    ``values`` ``(6,)`` and eigenvectors ``vectors`` ``(6, 6)`` (columns) of the trial whose
    cluster has the ``shape`` ``(P, 3)`` [mm] (its markers at frame 0).

    A pose's rotation error ``dw`` has the covariance ``s^2 K^-1`` (Pennec & Thirion 1997;
    ``K = sum_i (|b_i|^2 I - b_i b_i')`` the inertia of the centred cluster), so along a unit
    direction ``t`` of the axis ``|t x dw|^2`` adds ``s^2 q(t)``, ``q(t) = tr K^-1 - t' K^-1 t``,
    to the matrix per frame: ``lambda_0`` is ``N s^2 q(n)`` along the answer ``n``, and in the
    tangent direction the noise reaches most the share is ``lambda_0 q_max / q(n)``, ``q_max``
    the largest ``q`` normal to ``n``. The same noise is not isotropic: its expected share has
    the cross terms ``N s^2 E' K^-1 n`` between the answer and its tangent basis ``E``, which
    move the null vector by ``lambda_0 |E' K^-1 n| / (q(n) gap)`` [rad] whatever the noise's
    draw: a bias, which the SD, a statement of the scatter about it, does not include. For an
    isotropic cluster ``q`` is the same in every direction and both reduce to the planar
    cost's: the share ``lambda_0`` and no bias. A compiled kernel."""
    gap = values[1] - values[0]
    centred = shape - shape.sum(axis=0) / shape.shape[0]
    inertia = np.empty((3, 3))
    inertia_into(centred, inertia)
    try:
        compliance = np.linalg.inv(inertia)
    except Exception:  # singular: LAPACK's verdict, as NumPy's inverse gives it
        return math.inf, gap, math.inf
    half = vectors[:3, 0].copy()
    direction = half / math.sqrt(half[0] ** 2 + half[1] ** 2 + half[2] ** 2)
    basis = np.empty((3, 2))
    tangent_basis_into(direction, basis)
    trace = compliance[0, 0] + compliance[1, 1] + compliance[2, 2]
    # The smaller eigenvalue of the compliance in the plane normal to the axis, as
    # jointbench.estimators.precision.smaller_eigenvalue takes it.
    a = _bilinear(basis[:, 0], compliance, basis[:, 0])
    b = _bilinear(basis[:, 0], compliance, basis[:, 1])
    d = _bilinear(basis[:, 1], compliance, basis[:, 1])
    most = trace - (0.5 * (a + d) - math.hypot(0.5 * (a - d), b))
    along = trace - _bilinear(direction, compliance, direction)
    if not (along > 0.0 and gap > 0.0):
        return math.inf, gap, math.inf
    noise = max(values[0], 0.0) / along  # N s^2
    pull = (
        noise
        * math.hypot(
            _bilinear(basis[:, 0], compliance, direction),
            _bilinear(basis[:, 1], compliance, direction),
        )
        / gap
    )
    return noise * most, gap, math.degrees(pull)


@kernel
def _bilinear(u: np.ndarray, matrix: np.ndarray, v: np.ndarray) -> float:
    """``u' M v`` of the vectors ``u``, ``v`` ``(3,)`` and the ``matrix`` ``M`` ``(3, 3)``. A
    compiled kernel."""
    total = 0.0
    for i in range(3):
        for j in range(3):
            total += u[i] * matrix[i, j] * v[j]
    return total


@kernel
def _sara_point_covariance(
    values: np.ndarray,
    vectors: np.ndarray,
    moving: np.ndarray,
    shape: np.ndarray,
    n_frames: int,
    n_distinct: int,
) -> np.ndarray:
    """The covariance ``(3, 3)`` [mm^2] of SARA's one-segment point ``p1`` across its axis
    ``n1`` (rank 2, in the plane normal to it), from the normal matrix ``M`` ``(6, 6)`` of
    ``n_frames`` frames, ``n_distinct`` of them distinct, by its ascending eigenvalues
    ``values`` ``(6,)`` and eigenvectors ``vectors`` ``(6, 6)`` (columns), the point's
    version ``p2`` in the moving body frame ``moving`` (3,) [mm] and the cluster's ``shape``
    ``(P, 3)`` [mm] (its markers at frame 0, where the body frame is the reference's).

    ``x = [p1 - o; p2 - o]`` (``o`` the cluster's centroid) is the least-squares solution of
    ``A x = b`` with ``M = A'A``'s null vector (the axis) dropped, ``M^+`` its pseudo-inverse.
    A frame's residual ``p1 - R p2 - t`` takes the pose noise as ``-R (dw x (p2 - o)) - dt``
    (Pennec & Thirion 1997: ``dw`` of covariance ``s^2 K^-1``, ``K`` the centred cluster's
    inertia, ``dt`` at ``o`` of ``s^2 / P`` per coordinate); across the axis, which ``R``
    keeps, its variance per coordinate is ``s^2 (1 / P + tr(P_n L K^-1 L') / 2)``, ``L`` the
    cross-product matrix of ``p2 - o`` and ``P_n`` the projector across ``n``, whatever the
    frame's rotation: the covariance ``s^2 (...) M^+``, its ``p1`` block taken across the axis.
    The noise in ``A`` itself adds ``Psi = N s^2 [[0, 0], [0, tr(K^-1) I - K^-1]]`` to ``M``
    in expectation, which pulls ``x`` towards ``o`` by ``-M^+ Psi x`` (the attenuation of an
    errors-in-variables fit, largest on a short arc, whose ``M`` holds little more than that
    noise across the axis): a bias, added as its outer product, as the direction's is judged
    (:func:`_sara_validity`). A change of the direction moves the minimum-norm point along the
    axis only, to first order. ``s^2`` is read from the smallest eigenvalue, ``lambda_0 =
    N s^2 q(n) / 2`` over the null vector's halves of length ``1 / sqrt(2)``, ``q`` as in
    :func:`_sara_validity`. ``inf`` throughout where the cluster's inertia is singular or no
    eigenvalue above the smallest is positive. A compiled kernel."""
    covariance = np.full((3, 3), np.inf)
    n_markers = shape.shape[0]
    centroid = shape.sum(axis=0) / n_markers
    inertia = np.empty((3, 3))
    inertia_into(shape - centroid, inertia)
    try:
        compliance = np.linalg.inv(inertia)
    except Exception:  # singular: LAPACK's verdict, as NumPy's inverse gives it
        return covariance
    half = vectors[:3, 0].copy()
    direction = half / math.sqrt(half[0] ** 2 + half[1] ** 2 + half[2] ** 2)
    trace = compliance[0, 0] + compliance[1, 1] + compliance[2, 2]
    along = trace - _bilinear(direction, compliance, direction)
    if not (along > 0.0 and (values[1:] > 0.0).all()):
        return covariance
    noise = 2.0 * max(values[0], 0.0) / along  # N s^2
    lever = moving - centroid
    cross = np.array(
        [
            [0.0, -lever[2], lever[1]],
            [lever[2], 0.0, -lever[0]],
            [-lever[1], lever[0], 0.0],
        ]
    )
    spread = cross @ compliance @ cross.T
    across = spread[0, 0] + spread[1, 1] + spread[2, 2] - _bilinear(direction, spread, direction)
    variance = noise / n_frames * (1.0 / n_markers + 0.5 * across) * n_frames / n_distinct
    # The rows of M^+ that give p1: sum_j v_j[:3] v_j' / lambda_j over the eigenvectors kept.
    rows = np.zeros((3, 6))
    for j in range(1, 6):
        for i in range(3):
            for k in range(6):
                rows[i, k] += vectors[i, j] * vectors[k, j] / values[j]
    attenuated = noise * (trace * lever - compliance @ lever)  # Psi x, its moving half
    pull = np.zeros(3)
    for i in range(3):
        for k in range(3):
            pull[i] -= rows[i, 3 + k] * attenuated[k]
    full = np.empty((3, 3))
    for i in range(3):
        for k in range(3):
            full[i, k] = variance * rows[i, k] + pull[i] * pull[k]
    projector = np.eye(3)
    for i in range(3):
        for k in range(3):
            projector[i, k] -= direction[i] * direction[k]
    return projector @ full @ projector


def _sara_annotated(result: AxisResult, sd_deg: float, share: float, gap: float, bias_deg: float):
    """SARA's one-segment ``result`` with its direction's SD ``sd_deg`` (:func:`_sara_sd_deg`),
    above :data:`jointbench.estimators.precision.MAX_AXIS_SD_DEG` a warning, and where the
    noise's ``share`` reaches the eigen-``gap`` or its anisotropy pulls the axis by more than
    the SD (``bias_deg``, :func:`_sara_validity`) the warning that the SD does not hold
    (:func:`jointbench.estimators.precision.annotate_validity`)."""
    annotated = precision.annotate(result, sd_deg, "SARA's eigen-problem")
    return precision.annotate_validity(
        annotated, share, gap, "SARA's normal matrix", bias_deg=bias_deg
    )


@kernel
def _sara_precision_numbers(
    values: np.ndarray,
    vectors: np.ndarray,
    n_distinct: np.ndarray,
    markers: np.ndarray,
    moving: np.ndarray,
    covariances: np.ndarray,
) -> np.ndarray:
    """Per trial, :func:`_sara_sd_deg` and :func:`_sara_validity` of its eigenvalues ``values``
    ``(T, 6)`` and eigenvectors ``vectors`` ``(T, 6, 6)``, for its markers ``(T, N, P, 3)``
    [mm], ``n_distinct`` ``(T,)`` of whose frames are distinct: ``(T, 4)``, the SD [deg], the
    noise's share, the eigen-gap and the pull [deg]; and into ``covariances`` ``(T, 3, 3)``
    [mm^2] its point's :func:`_sara_point_covariance`, its version in the moving body frame
    ``moving`` ``(T, 3)`` [mm]. A compiled kernel: one call for a batch, where several per
    trial cost a checked call more than their arithmetic."""
    numbers = np.empty((values.shape[0], 4))
    for t in range(values.shape[0]):
        numbers[t, 0] = _sara_sd_deg(values[t], vectors[t], markers.shape[1], n_distinct[t])
        numbers[t, 1], numbers[t, 2], numbers[t, 3] = _sara_validity(
            values[t], vectors[t], markers[t, 0]
        )
        covariances[t] = _sara_point_covariance(
            values[t], vectors[t], moving[t], markers[t, 0], markers.shape[1], n_distinct[t]
        )
    return numbers


def _sara_precision_many(
    results: list[AxisResult], markers: np.ndarray, *, verdicts
) -> list[AxisResult]:
    """Each of SARA's one-segment ``results`` (the trials of ``markers`` ``(T, N, P, 3)``
    [mm]) annotated by :func:`_sara_annotated` with the numbers of its eigen-problem and with
    its point's covariance across the axis
    (:func:`jointbench.estimators.precision.annotate_point`), both from
    :func:`_sara_precision_numbers`. The support ``verdicts`` are not read: the eigen-problem
    states its own noise."""
    del verdicts
    if not results:
        return []
    markers = kernel_array(markers)
    covariances = np.empty((len(results), 3, 3))
    numbers = _sara_precision_numbers(
        np.array([result.diagnostics["eigenvalues"] for result in results], dtype=float),
        np.array([result.diagnostics["eigenvectors"] for result in results], dtype=float),
        np.array([len(precision.distinct_frames(trial)) for trial in markers]),
        markers,
        np.array([result.diagnostics["point_moving"] for result in results], dtype=float),
        covariances,
    )
    return [
        precision.annotate_point(_sara_annotated(result, *row), covariance)
        for result, row, covariance in zip(results, numbers.tolist(), covariances, strict=True)
    ]


fit_sara.precision_many = _sara_precision_many


def fit_sara_two_segment(proximal: np.ndarray, distal: np.ndarray) -> AxisResult:
    """SARA for two segments moving in the world ``(n_frames >= 3, n_markers >= 3, 3)`` [mm].

    The axis is returned in the body-fixed frame shared at frame 0 (the world at frame 0) as
    the mean of the two segments' versions mapped by their frame-0 poses: direction
    ``unit(R1(0) n1 + R2(0) n2)`` (one eigenvector gives both, so their signs agree), point
    ``(R1(0) p1 + t1(0) + R2(0) p2 + t2(0)) / 2``. ``radii`` are the distal markers' mean
    distances from the axis ``(p1, n1)`` in the proximal frame [mm]. ``diagnostics`` carries each
    frame's version and ``ratio`` (see :func:`fit_sara`).
    """
    return one_trial(_sara_two_segment_trials, proximal, distal)


def _sara_two_segment(prox: PoseStack, dist: PoseStack) -> list[AxisResult | ValueError]:
    r1, t1, r2, t2 = prox.rotation, prox.translation, dist.rotation, dist.translation
    n1, n2, p1, p2, values, _, errors = _sara_solve(r1, t1, r2, t2, dist.body.mean(axis=1))
    direction = _applied(r1[:, :1], n1)[:, 0] + _applied(r2[:, :1], n2)[:, 0]
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    at_frame0 = _applied(r1[:, :1], p1)[:, 0], _applied(r2[:, :1], p2)[:, 0]
    point = 0.5 * (at_frame0[0] + t1[:, 0] + at_frame0[1] + t2[:, 0])
    distal_in_proximal = np.einsum("tfji,tfmj->tfmi", r1, dist.markers - t1[:, :, None, :])
    radii = _mean_distance_to_axis(distal_in_proximal, p1, n1)
    return _sara_results(
        errors,
        point,
        direction,
        radii,
        values,
        direction_proximal=n1,
        point_proximal=p1,
        direction_distal=n2,
        point_distal=p2,
    )


def batched(
    finish: Callable[..., Outcome], names: tuple[str, ...]
) -> Callable[..., list[Outcome | ValueError]]:
    """The many-trial form of a pose-based method: ``(*segments, poses=None, **options)``.

    Each segment is ``(n_trials, N, n_markers, 3)`` [mm]; ``poses`` (from :func:`trial_poses`)
    lets several methods share one pose fit. Returns one result, or the ``ValueError`` of a
    trial that cannot be fitted, per trial; options the method ignores are accepted.
    ``finish(*stacks, **options)`` fits trials whose poses are stacked, one
    :class:`PoseStack` per segment in ``names`` order, and returns one outcome per trial.
    """

    def finish_stacked(poses: list, **options) -> list[Outcome | ValueError]:
        outcomes = list(poses)
        # Trials of one batch share their shapes; poses passed in are grouped to be safe.
        groups: dict[tuple, list[int]] = {}
        for trial, fitted in enumerate(poses):
            if not isinstance(fitted, ValueError):
                shapes = tuple(fitted[name].markers.shape for name in names)
                groups.setdefault(shapes, []).append(trial)
        for group in groups.values():
            stacks = [PoseStack([poses[trial][name] for trial in group]) for name in names]
            for trial, outcome in zip(group, finish(*stacks, **options), strict=True):
                outcomes[trial] = outcome
        return outcomes

    return batched_all(finish_stacked, names)


def batched_all(
    finish_all: Callable[..., list[Outcome | ValueError]], names: tuple[str, ...]
) -> Callable[..., list[Outcome | ValueError]]:
    """:func:`batched` for a method that fits all trials' poses in one call:
    ``finish_all(poses, **options)`` takes every trial's poses (or its ``ValueError``)."""

    def run(*segments: np.ndarray, poses=None, **options) -> list[Outcome | ValueError]:
        if poses is None:
            segments_by_name = dict(zip(names, segments, strict=True))
            poses = trial_poses(segments_by_name, min_frames=POSE_MIN_FRAMES)
        outcomes = finish_all(poses, **options)
        return [
            _with_pose_fit_end(outcome, fitted, names)
            for outcome, fitted in zip(outcomes, poses, strict=True)
        ]

    run.pose_segments = names
    return isolated(run)


def _with_pose_fit_end(outcome, poses, names: tuple[str, ...]):
    """``outcome`` (a result, or a trial's ``ValueError``) with ``converged=False`` and its
    status led by what stopped, where a segment's poses ``poses`` (by name) did not
    converge (:func:`~jointbench.estimators.segment_poses.with_stopped_fits`)."""
    if isinstance(outcome, BaseException) or not isinstance(poses, dict):
        return outcome
    stopped = [
        stopped_fit(name, poses[name].iterations, poses[name].change_mm)
        for name in names
        if poses[name].converged is False
    ]
    return with_stopped_fits(outcome, stopped)


def _ignoring_noise(finish: Callable[..., list]) -> Callable[..., list]:
    def run(*stacks: PoseStack, noise_mm: float | None = None) -> list:
        del noise_mm
        return finish(*stacks)

    return run


_score_trials = batched(_ignoring_noise(_score_joint), ("proximal", "distal"))
_score_center_trials = batched(_score_center, ("markers",))
_sara_trials = batched(_sara, ("markers",))
_sara_two_segment_trials = batched(_sara_two_segment, ("proximal", "distal"))

register_many("joint_center", "SCoRE", _score_trials)
register_many("center", "SCoRE", _score_center_trials)
register_many("axis", "SARA", _sara_trials)
