"""Fitting a recording: segments, gaps, artefacts, frames, and an optional bootstrap.

Every answer is in the reference segment's technical frame (:mod:`jointbench.io.segments`),
whose definition travels with the result. For ``center`` and ``axis`` the moving markers are
expressed in that frame, frame by frame, and passed to the estimator. For ``joint_center`` both
clusters are expressed in it: the reference cluster's poses are then the identity, so the
estimators' "world at frame 0" is the technical frame itself. Paper C's analytic and
Gauss–Markov models (and SCoRE's reported centre) also need one instant at which both body
frames coincide; it is taken at the *anchor* frame, the frame whose relative orientation of the
two segments is nearest their mean relative orientation (chordal mean), which no reordering of
the frames changes. It is moved to the front before the estimator is called.

Gaps: a frame enters a fit only when the reference pose is defined (>= 3 reference markers, not
so nearly collinear that the noise turns the pose about their line: :meth:`Segment.determined`)
and every moving marker is visible (two-segment methods: every marker of both segments); the others
are left out and counted. Artefacts (label swaps, markers falling off;
:func:`jointbench.screening.screen`) are refused with a message naming the markers and frame --
for a swap, the frame where the labels change and the frames on each side, which ``frames``
(``--frames``) can keep -- or, with ``artefacts="exclude"``, their frames are left out with a
warning. Which frames a cluster excludes does not depend on the order of the frames: they are
those that break the shape most frames share (for a swap, the side with fewer frames, whichever
labelling is right).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field

import numpy as np

from jointbench.estimators import results
from jointbench.estimators.batching import failed_trial, mistakes_named, numerical_failure
from jointbench.estimators.centre_precision import stated_covariance
from jointbench.estimators.registry import KINDS, check_options, get_for_passed, many
from jointbench.estimators.results import with_warnings
from jointbench.estimators.validation import check_input
from jointbench.geometry import angle_between_lines_deg
from jointbench.io.caller import warn_caller
from jointbench.io.recording import Recording
from jointbench.io.segments import (
    LAB_FIXED_FLAG,
    LAB_FIXED_KEYWORD,
    Artefact,
    ArtefactRules,
    Segment,
    Swap,
    check_axes_determined,
    check_joined_span,
    check_pose_determined,
    check_span,
    find_jumps,
    summarise,
)
from jointbench.numerics.poses import best_rotation
from jointbench.screening import checked_rules, flagged_frames
from jointbench.uncertainty import Bootstrap, bootstrap, check_level, check_resampling

__all__ = [
    "ARTEFACT_POLICIES",
    "BLOCK_SPANS",
    "DEFAULT_METHODS",
    "LAB_FIXED_KINDS",
    "NOT_DETERMINED",
    "SD_NAMES",
    "SD_STATED",
    "Prepared",
    "RecordingFit",
    "fit",
    "point_precision",
    "prepare",
]

ARTEFACT_POLICIES = ("refuse", "exclude")

#: A moving-block bootstrap's blocks should span this many times the frames one independent
#: frame spans (the frames over ``support_independent_frames``): for noise that keeps a share
#: of itself from frame to frame, the bootstrap's variance of a mean, the autocorrelations'
#: sum weighted by ``1 - k / L``, keeps some 60 % of the true one over blocks of one such span
#: and some 84 % over three.
BLOCK_SPANS = 3

DEFAULT_METHODS = {"center": "NM", "axis": "combined", "joint_center": "gauss-markov"}

#: The kinds whose reference is only the frame of the answer, which may be fixed in the lab (a
#: treadmill, a force plate) and, stated so by the user and still, is then bounded by a capture
#: volume rather than a segment (:meth:`~jointbench.io.segments.Segment.fit`); a
#: ``joint_center``'s is the proximal body segment of the joint.
LAB_FIXED_KINDS = ("center", "axis")

#: What an output prints in place of an SD that states no precision
#: (:meth:`RecordingFit.stated_sd`), as the result's status says.
NOT_DETERMINED = "not determined"

#: Per kind, the name outputs give the SD a method states (:meth:`RecordingFit.sd_fields`).
SD_NAMES = {"center": "sd_mm", "axis": "sd_deg", "joint_center": "sd_mm"}

#: The flag a machine-readable output sets beside the SD (:meth:`RecordingFit.sd_fields`):
#: true where it holds a number that states a precision.
SD_STATED = "sd_stated"


@dataclass(frozen=True, eq=False)
class RecordingFit:
    """An estimator's answer on a recording, and how it was obtained.

    ``result`` is the estimator's own result, its coordinates in the reference segment's
    technical frame (``frame`` holds that frame's definition; ``None`` when no reference was
    given and the markers were taken as already in the reference frame). ``frames_used`` are
    the recording's frame indices that entered the fit; ``n_gap_frames`` the frames left out for
    missing markers; ``excluded`` the artefacts whose frames were left out; ``anchor_frame`` the
    frame at which two-segment models let both body frames coincide. ``bootstrap`` holds the
    moving-block refits when requested: the centre ``(3,)``, or for an axis its direction
    ``(3,)`` (sign-aligned with the estimate) and the point ``(3,)`` where it crosses the plane
    through the estimate's point normal to its direction.
    """

    kind: str
    method: str
    result: object
    frame: dict | None
    frames_used: np.ndarray
    n_gap_frames: int
    excluded: tuple[Artefact, ...] = ()
    anchor_frame: int | None = None
    bootstrap: Bootstrap | None = None
    reference: Segment | None = field(default=None, repr=False)
    first_frame: int = 0

    def estimate(self) -> np.ndarray:
        """The centre ``(3,)``, or an axis' direction and point ``(6,)``, in the frame."""
        return _estimate_vector(self.kind, self.result)

    def world(self) -> np.ndarray:
        """The centre (or the axis point) in the world in every frame ``(n_frames, 3)`` [mm]
        of the fitted range, whose row 0 is frame ``first_frame`` (NaN where the reference pose
        is undefined). Needs a reference segment."""
        if self.reference is None:
            raise ValueError("no reference segment: the result is already in the data's frame")
        return self.reference.world(self.estimate()[-3:])

    def stated_covariance(self) -> tuple[np.ndarray, str] | None:
        """A joint centre's covariance ``(3, 3)`` [mm^2] of its answer's scatter, the one its
        ``diagnostics["center_sd_mm"]`` is read from, and where it comes from
        (:func:`jointbench.estimators.centre_precision.stated_covariance`); ``None`` for
        another kind, or where the method states none. For paper C's ``gauss-markov`` it is not
        ``result.covariance``: that, ``W_c``, is conditional on the frame-0 poses and several
        times smaller than the answers' scatter."""
        if self.kind != "joint_center":
            return None
        return stated_covariance(self.result)

    def stated_sd(self) -> float | str | None:
        """The SD the method states of its answer where it states a precision
        (:func:`jointbench.estimators.results.stated_sd`, the one rule: an axis direction's
        [deg], a centre's along its least determined direction [mm]); :data:`NOT_DETERMINED`
        where the method gives an SD that states none (above the bound the status declares the
        answer not determined beyond, or where the method did not converge, the status says the
        precision is not determined or the support verdict refused the data); ``None`` where
        the method gives none."""
        if results.method_sd(self.result) is None:
            return None
        sd = results.stated_sd(self.result)
        return NOT_DETERMINED if sd is None else sd

    def sd_fields(self) -> dict:
        """:meth:`stated_sd` as a machine-readable output gives it, so that its column holds
        numbers only: under ``sd_deg`` (an axis) or ``sd_mm`` (a centre) the SD, ``None``
        where it states no precision, and :data:`SD_STATED`, whether it holds a number. Where
        the method states no SD, the flag alone (false)."""
        stated = self.stated_sd()
        if stated is None:
            return {SD_STATED: False}
        name = SD_NAMES[self.kind]
        number = None if stated == NOT_DETERMINED else stated
        return {name: number, SD_STATED: number is not None}

    def covariances(self, fields: dict) -> dict[str, np.ndarray | None]:
        """The covariances ``(3, 3)`` [mm^2] the method gives of its answer, by the rule of its
        SD as ``fields`` (:meth:`sd_fields`, read once) state it: under ``"own"`` the method's
        own (``result.covariance``), under ``"stated"`` the one its SD is read from
        (:meth:`stated_covariance`), each only where the method gives it, and ``None`` where
        the SD states no precision: a covariance of the same answer states none either."""
        no_precision = len(fields) > 1 and not fields[SD_STATED]
        own = getattr(self.result, "covariance", None)
        stated = self.stated_covariance()
        given = {"own": own, "stated": None if stated is None else stated[0]}
        return {
            which: None if no_precision else np.asarray(covariance, dtype=float)
            for which, covariance in given.items()
            if covariance is not None
        }

    def bootstrap_cone_deg(self, level: float = 0.95) -> float:
        """Axis: the angle [deg] from the estimate holding ``level`` (in (0, 1)) of the refit
        directions."""
        if self.kind != "axis" or self.bootstrap is None:
            raise ValueError("only an axis fit with a bootstrap has a direction cone")
        level = check_level(level)
        angles = angle_between_lines_deg(self.bootstrap.valid[:, :3], self.result.direction)
        return float(np.quantile(angles, level))

    def to_dict(self) -> dict:
        """A JSON-ready summary: estimate, status, frames, artefacts, frame definition."""
        out: dict = {"kind": self.kind, "method": self.method}
        if self.kind == "axis":
            out["direction"] = self.result.direction.tolist()
            out["point_mm"] = self.result.point.tolist()
        else:
            out["center_mm"] = self.result.center.tolist()
            out.update(_joint_points(self.kind, self.result))
        fields = self.sd_fields()
        out.update(fields)
        if self.kind == "axis":
            out.update(point_precision(self.result))
        names = {"own": "covariance_mm2", "stated": "center_covariance_mm2"}
        covariances = self.covariances(fields)
        for which, covariance in covariances.items():
            out[names[which]] = None if covariance is None else covariance.tolist()
        if "stated" in covariances:
            out["center_covariance_is"] = self.stated_covariance()[1]
        out.update(
            converged=bool(self.result.converged),
            status=self.result.status,
            n_frames_used=len(self.frames_used),
            n_gap_frames=self.n_gap_frames,
            excluded=[vars(a) for a in self.excluded],
            anchor_frame=self.anchor_frame,
        )
        if self.bootstrap is not None:
            boot = {
                "n_resamples": len(self.bootstrap.samples),
                "n_failed": self.bootstrap.n_failed,
                "block_length_frames": self.bootstrap.block_length,
                "interval_95": self.bootstrap.interval().tolist(),
            }
            if self.kind == "axis":
                boot["direction_cone_95_deg"] = self.bootstrap_cone_deg()
            else:
                boot["covariance_mm2"] = self.bootstrap.covariance().tolist()
            out["bootstrap"] = boot
        out["frame"] = self.frame or "as recorded (markers taken as already in the reference frame)"
        return out


def point_precision(result) -> dict:
    """An axis answer's point precision as every output of a fit gives it, where the method
    states one (``diagnostics["axis_point_sd_mm"]``): ``point_sd_mm``, its SD across the axis
    [mm], and ``point_covariance_mm2`` ``(3, 3)``, both ``None`` where they state no precision
    (:func:`jointbench.estimators.results.stated_point_sd`: the status says the point or the
    answer's precision is not determined); empty for a method that states none."""
    if "axis_point_sd_mm" not in result.diagnostics:
        return {}
    sd = results.stated_point_sd(result)
    covariance = None if sd is None else result.diagnostics["axis_point_covariance_mm2"]
    return {"point_sd_mm": sd, "point_covariance_mm2": covariance}


CENTER_IS = {
    "center": "the centre of rotation, fixed in the reference segment",
    "joint_center": (
        "the joint's position at the anchor frame, in the reference segment's technical frame at "
        "that frame (the world of the two-segment model)"
    ),
}


def _joint_points(kind: str, result) -> dict:
    """What ``center_mm`` is, and the estimates it is made of where the method has two.

    SCoRE estimates the centre once in each body; its ``center`` is their midpoint at the
    anchor frame, which differs by the soft-tissue misfit from the proximal-fixed centre that
    ``kind="center"`` (and other SCoRE implementations) report. Both are given.
    """
    out = {"center_is": CENTER_IS[kind]}
    proximal = result.diagnostics.get("center_proximal")
    distal = result.diagnostics.get("center_distal")
    if kind == "joint_center" and proximal is not None and distal is not None:
        out["center_is"] += ": the midpoint of center_proximal_mm and center_distal_mm"
        out["center_proximal_mm"] = [float(v) for v in proximal]
        out["center_distal_mm"] = [float(v) for v in distal]
        out["center_proximal_is"] = (
            "the centre fixed in the reference (proximal) segment, in its technical frame at the "
            "anchor frame (as kind='center' reports it)"
        )
        out["center_distal_is"] = (
            "the centre fixed in the moving (distal) segment, at the anchor frame, same frame"
        )
    return out


def _estimate_vector(kind: str, result) -> np.ndarray:
    if kind == "axis":
        return np.concatenate([result.direction, result.point])
    return np.asarray(result.center, dtype=float)


def _bootstrap_row(kind: str, refit, estimate: np.ndarray) -> np.ndarray | str:
    """What a refit contributes to the bootstrap; why not, when it failed or did not converge
    (a mistake in the method's code is raised, not counted as a failed refit)."""
    if isinstance(refit, Exception):
        failed_trial(refit)
        return f"failed: {refit}"
    if not refit.converged:
        return refit.status
    if kind == "axis":
        return _axis_crossing(refit.direction, refit.point, estimate)
    return np.asarray(refit.center, dtype=float)


def _axis_crossing(direction, point, reference) -> np.ndarray:
    """Refit axis as (sign-aligned direction, its crossing of the reference plane) ``(6,)``."""
    ref_direction, ref_point = reference[:3], reference[3:]
    cosine = float(direction @ ref_direction)
    if abs(cosine) < 1e-12:
        return np.full(6, np.nan)
    along = float((ref_point - point) @ ref_direction) / cosine
    return np.concatenate([np.sign(cosine) * direction, point + along * direction])


def anchor_frame(reference: Segment, moving: Segment, frames: np.ndarray) -> int:
    """Of ``frames``, the one whose relative orientation is nearest the chordal mean."""
    relative = np.swapaxes(reference.rotation[frames], 1, 2) @ moving.rotation[frames]
    mean = best_rotation(relative.sum(axis=0))
    closeness = np.einsum("ij,fij->f", mean, relative)
    return int(frames[int(np.argmax(closeness))])


def _artefacts(
    recording: Recording, segments: list[Segment], loose: list[int], rules: ArtefactRules
) -> tuple[list[Artefact], list[Swap]]:
    """Every cluster's rigidity breaks and swaps, and the jumps of ``loose`` markers."""
    found = [a for segment in segments for a in segment.artefacts]
    swaps = [swap for segment in segments for swap in segment.swaps]
    if loose:
        labels = tuple(recording.labels[i] for i in loose)
        found += find_jumps(recording.markers[:, loose], labels, rules)
    return sorted(found, key=lambda a: (a.frame, a.label)), swaps


@dataclass(frozen=True, eq=False)
class Prepared:
    """A recording made ready for fitting (one preparation serves every method).

    ``arrays`` the estimator's inputs over all frames of the recording, in the reference
    technical frame; ``usable`` the frame rows that may enter a fit; ``found`` the artefacts
    and ``swaps`` the label swaps among them; ``untested`` what the segments' screens did not
    test, in words, which every result's ``status`` carries.
    """

    kind: str
    recording: Recording
    reference: Segment | None
    moving: Segment | None
    arrays: tuple[np.ndarray, ...]
    usable: np.ndarray
    n_gap_frames: int
    found: tuple[Artefact, ...]
    artefacts: str
    swaps: tuple[Swap, ...] = ()
    untested: tuple[str, ...] = ()

    def rows(self, indices: np.ndarray) -> np.ndarray:
        """Recording rows of ``usable[indices]``, the anchor frame first for two segments."""
        rows = self.usable[indices]
        if self.kind != "joint_center":
            return rows
        anchor = anchor_frame(self.reference, self.moving, rows)
        first = int(np.flatnonzero(rows == anchor)[0])
        return np.concatenate([[anchor], np.delete(rows, first)])

    def _left_out(self) -> str:
        """For a refusal, how many of the recording's frames enter the fit and why the others
        do not (``""`` when all do): a method counts the frames it is given, which gaps and
        artefacts can make far fewer than the file's."""
        n_frames = self.recording.n_frames
        if self.usable.size == n_frames:
            return ""
        excluded = n_frames - self.usable.size - self.n_gap_frames
        why = [f"{self.n_gap_frames} lack a marker it needs"] if self.n_gap_frames else []
        why += [f"{excluded} hold artefacts left out"] if excluded else []
        return (
            f" ({self.usable.size} of the {n_frames} frames read enter the fit: {', '.join(why)})"
        )

    def solve(self, method: str, rows: np.ndarray, options: dict):
        """The estimator's result on the recording ``rows``, with ``options`` that passed
        :func:`~jointbench.estimators.registry.check_options` (:meth:`fit` checks them)."""
        # The checked estimator, as the public fit functions call it: every input check and
        # the support verdict. Their artefact screen ran in prepare, over the whole recording;
        # the options' check in fit, with the recording's label, so it is not repeated here.
        arrays = tuple(a[rows] for a in self.arrays)
        try:
            result = get_for_passed(self.kind, method)(check_input(self.kind, arrays), **options)
        except ValueError as error:
            if not numerical_failure(error):
                raise  # a mistake in the method: :meth:`fit` names it as one
            raise ValueError(
                f"{self.recording.source}: {self.kind} {method}: {error}{self._left_out()}"
            ) from None
        if not self.untested:
            return result
        return with_warnings(result, self.untested, {"artefacts_untested": list(self.untested)})

    def refits(self, method: str, rows: list[np.ndarray], options: dict) -> list:
        """Results (or ``ValueError``) on many row sets, as one batch where the method can.

        The refits run the estimator without the input checks and support verdict of a user's
        call: their rows are resamples of frames that passed them in the main fit.
        """
        refit = many(self.kind, method, checked=False)
        return refit(*(np.stack([a[r] for r in rows]) for a in self.arrays), **options)

    def fit(
        self,
        method: str | None = None,
        *,
        n_bootstrap: int = 0,
        block_length: int | None = None,
        seed: int = 0,
        **options: object,
    ) -> RecordingFit:
        """One method's :class:`RecordingFit` (parameters as in :func:`fit`).

        A mistake in the method's code, in the fit or a bootstrap refit, raises a
        :class:`~jointbench.estimators.batching.ProgrammingError` naming the recording, the
        method and the line (:func:`~jointbench.estimators.batching.numerical_failure`); an
        option that is not what the method declares for it, a ``ValueError`` naming it before
        the fit (:func:`~jointbench.estimators.registry.check_options`); a bootstrap argument
        that is not what :func:`~jointbench.uncertainty.check_resampling` asks, a ``ValueError``
        naming it, also before the fit. ``method=None`` is the kind's default; any other value
        must name a method (``""`` does not).
        """
        kind = self.kind
        method = DEFAULT_METHODS[kind] if method is None else method
        label = f"{self.recording.source}: {kind} {method}"
        check_options(kind, method, options, label)  # an unknown method is named here
        try:
            check_resampling(
                self.usable.size,
                n_bootstrap,
                block_length,
                seed,
                names=("n_bootstrap", "block_length", "seed"),
                zero_is_none=True,
            )
        except ValueError as error:
            raise ValueError(f"{label}: {error}") from None
        rows = self.rows(np.arange(self.usable.size))
        with mistakes_named(label):
            result = self.solve(method, rows, options)
            boot = None
            if n_bootstrap:
                estimate = _estimate_vector(kind, result)

                def statistic(indices: np.ndarray) -> list[np.ndarray | None]:
                    outcomes = self.refits(method, [self.rows(i) for i in indices], options)
                    return [_bootstrap_row(kind, refit, estimate) for refit in outcomes]

                boot = bootstrap(
                    statistic,
                    self.usable.size,
                    n_resamples=n_bootstrap,
                    block_length=block_length,
                    seed=seed,
                    label=label,
                )
                result = _blocks_checked(result, boot, self.usable.size)
        anchor = int(rows[0]) if kind == "joint_center" else None
        offset = self.recording.first_frame
        return RecordingFit(
            kind=kind,
            method=method,
            result=result,
            frame=None if self.reference is None else self.reference.definition(),
            frames_used=self.usable + offset,
            n_gap_frames=self.n_gap_frames,
            excluded=self.found if self.artefacts == "exclude" else (),
            anchor_frame=None if anchor is None else anchor + offset,
            bootstrap=boot,
            reference=self.reference,
            first_frame=offset,
        )


def _blocks_checked(result: object, boot: Bootstrap, n_frames: int) -> object:
    """``result`` with a warning where ``boot``'s blocks are shorter than :data:`BLOCK_SPANS`
    times the frames one independent frame spans: the ``n_frames`` fitted over the independent
    frames the support verdict counted (``diagnostics["support_independent_frames"]``, given
    only where the frames are not independent). Resampled in shorter blocks, the refits
    scatter as if the frames were more independent than they are, and the interval understates
    the scatter, if less than the SDs do."""
    independent = result.diagnostics.get("support_independent_frames")
    if independent is None:
        return result
    span = math.ceil(BLOCK_SPANS * n_frames / independent)
    if boot.block_length >= span:
        return result
    remedy = (
        f"pass block_length (--block-length) of {span} frames or more"
        if span <= n_frames
        else f"no block of these {n_frames} frames is that long"
    )
    warning = (
        f"the bootstrap's blocks of {boot.block_length} frames are shorter than {span}, "
        f"{BLOCK_SPANS} times the frames each independent one spans (the frames are not "
        f"independent, above): its interval understates the scatter; {remedy}"
    )
    return with_warnings(result, (warning,), {"bootstrap_block_span_frames": span})


def _checked_frames(frames: object) -> slice | str:
    """``frames`` when it is what :func:`fit` documents (``"start:stop"`` or a slice of rows
    whose bounds are integers or ``None``); otherwise a ``ValueError`` naming it, where a
    tuple would fail deep inside with an ``AttributeError``."""
    if isinstance(frames, str):
        return frames
    if isinstance(frames, slice) and all(
        bound is None or (isinstance(bound, numbers.Integral) and not isinstance(bound, bool))
        for bound in (frames.start, frames.stop, frames.step)
    ):
        return frames
    raise ValueError(
        f"frames must be 'start:stop' (the file's frame numbers) or a slice of rows with "
        f"integer bounds, got {frames!r}"
    )


def _check_lab_fixed(lab_fixed_reference: object, kind: str, reference: object) -> None:
    """``ValueError`` naming the option when ``lab_fixed_reference`` is not a bool, or states
    fixed in the lab a reference that is none (no ``reference``) or a body segment (a
    ``joint_center``'s proximal one): stated so, a still reference is bounded by a capture
    volume rather than a segment, and no other cluster may be."""
    option = f"{LAB_FIXED_KEYWORD} ({LAB_FIXED_FLAG})"
    if not isinstance(lab_fixed_reference, bool):
        raise ValueError(f"{option} must be True or False, got {lab_fixed_reference!r}")
    if not lab_fixed_reference:
        return
    if kind not in LAB_FIXED_KINDS:
        raise ValueError(
            f"{option} is for the reference of a {' or '.join(LAB_FIXED_KINDS)} fit: a {kind}'s "
            "reference is the proximal body segment of the joint, bounded as one"
        )
    if reference is None:
        raise ValueError(
            f"{option} needs a reference (--reference): without one the moving markers are "
            "taken as already in the reference frame"
        )


def _refuse_kept_origin(
    world: np.ndarray, usable: np.ndarray, labels: tuple[str, ...], recording: Recording
) -> None:
    """``ValueError`` where the moving markers ``world`` ``(len(usable), n_markers, 3)`` [mm],
    rows ``usable`` of ``recording``, fitted without a reference, hold a sample at exactly
    (0, 0, 0) the recording kept (:func:`~jointbench.io.recording.origin_gaps`: its marker
    passes through the lab's origin): the estimators' input checks refuse any such sample as a
    possible gap stored as zeros, and their advice, to fit a Recording, is what was done. It
    names the first such sample and the ways round it: a reference, in whose frame none is at
    the origin, or the frames on either side."""
    at_origin = (world == 0.0).all(axis=-1)
    if not at_origin.any():
        return
    rows, markers = np.nonzero(at_origin)
    first, end = recording.first_frame, recording.first_frame + recording.n_frames
    before, after = first + int(usable[rows[0]]), first + int(usable[rows[-1]]) + 1
    sides = [f"'{a}:{b}'" for a, b in ((first, before), (after, end)) if a < b]
    without = f", or fit frames without it (frames={' or '.join(sides)})" if sides else ""
    raise ValueError(
        f"{recording.source}: {labels[markers[0]]} is at exactly (0, 0, 0) at "
        f"{recording.when(int(usable[rows[0]]))}, read as a position (its samples on either side "
        "lie within its motion of the lab's origin), which the fits refuse as a possible gap "
        f"stored as zeros: name a --reference segment (reference=), in whose frame the markers "
        f"are fitted{without}"
    )


def prepare(
    recording: Recording,
    kind: str,
    moving: str | list[str],
    reference: str | list[str] | None = None,
    *,
    frames: slice | str | None = None,
    artefacts: str = "refuse",
    rules: ArtefactRules | None = None,
    lab_fixed_reference: bool = False,
) -> Prepared:
    """Segments, gaps and artefacts of a recording for one kind of fit (see :func:`fit`)."""
    if kind not in KINDS:
        raise ValueError(f"unknown kind {kind!r}; choose one of {', '.join(KINDS)}")
    if kind == "joint_center" and reference is None:
        raise ValueError("joint_center needs a reference segment (the proximal markers)")
    _check_lab_fixed(lab_fixed_reference, kind, reference)
    if artefacts not in ARTEFACT_POLICIES:
        raise ValueError(
            f"artefacts must be one of {', '.join(ARTEFACT_POLICIES)}, got {artefacts!r}"
        )
    rules = checked_rules(rules)
    if frames is not None:
        recording = recording.frames(_checked_frames(frames))
    moving_index = recording.index(moving)
    moving_labels = tuple(recording.labels[i] for i in moving_index)
    # The moving markers tell the file's unit first, their span checked once, by their
    # segment's fit where they form one: a reference may be fixed in the lab, where its size,
    # and how still it stays, are no segment's.
    mov = None
    if kind == "joint_center" or len(moving_index) >= 3:
        mov = Segment.fit(recording, moving, rules)
    else:
        check_span(recording.markers[:, moving_index], moving_labels, recording)
    # None: the reference is a body segment, and no statement is asked of it.
    stated_lab_fixed = lab_fixed_reference if kind in LAB_FIXED_KINDS else None
    segments: list[Segment] = []
    ref = None
    if reference is not None:
        ref = Segment.fit(recording, reference, rules, stated_lab_fixed=stated_lab_fixed)
        check_pose_determined(ref, recording.source)
        check_axes_determined(ref, recording.source)
        ref = ref.determined()
        overlap = set(ref.labels) & {recording.labels[i] for i in moving_index}
        if overlap:
            raise ValueError(
                f"{recording.source}: {', '.join(sorted(overlap))} named in both the reference "
                "and the moving segment"
            )
        segments.append(ref)
    if mov is not None:
        segments.append(mov)
    if ref is not None:
        check_joined_span(ref, moving_labels, recording)
    found, swaps = _artefacts(recording, segments, [] if mov else moving_index, rules)
    if found and artefacts == "refuse":
        keep = ""
        if swaps:
            sides = " or ".join(
                f"'{recording.first_frame + a}:{recording.first_frame + b}'"
                for a, b in swaps[0].sides()
            )
            keep = f"keep one side with frames={sides} (--frames), or "
        raise ValueError(
            f"{recording.source}: {summarise(found, swaps, recording.numbering)}. Choose other "
            f"frames: {keep}pass artefacts='exclude' (--artefacts exclude) to leave out the "
            "frames that break the shape most frames share"
        )

    world = recording.markers[:, moving_index]
    if kind == "joint_center":
        reference_world = recording.markers[:, recording.index(ref.labels)]
        arrays = (ref.local(reference_world), ref.local(world))
    else:
        arrays = (world if ref is None else ref.local(world),)
    visible = np.all([np.isfinite(a).all(axis=(1, 2)) for a in arrays], axis=0)
    bad = flagged_frames(found, recording.n_frames)
    if found:
        warn_caller(
            f"{recording.source}: left out {int(bad.sum())} frames with artefacts: "
            f"{summarise(found, swaps, recording.numbering)}"
        )
    usable = np.flatnonzero(visible & ~bad)
    if usable.size == 0:
        raise ValueError(f"{recording.source}: no frame has every marker the fit needs")
    if ref is None:
        _refuse_kept_origin(world[usable], usable, moving_labels, recording)
    return Prepared(
        kind=kind,
        recording=recording,
        reference=ref,
        moving=mov,
        arrays=arrays,
        usable=usable,
        n_gap_frames=int(np.sum(~visible & ~bad)),
        found=tuple(found),
        artefacts=artefacts,
        swaps=tuple(swaps),
        untested=tuple(
            f"not verified in the {role} segment: {segment.untested}"
            for role, segment in (("reference", ref), ("moving", mov))
            if segment is not None and segment.untested
        ),
    )


def fit(
    recording: Recording,
    kind: str,
    moving: str | list[str],
    reference: str | list[str] | None = None,
    *,
    method: str | None = None,
    frames: slice | str | None = None,
    artefacts: str = "refuse",
    rules: ArtefactRules | None = None,
    lab_fixed_reference: bool = False,
    n_bootstrap: int = 0,
    block_length: int | None = None,
    seed: int = 0,
    **options: object,
) -> RecordingFit:
    """Fit ``method`` of ``kind`` to the ``moving`` markers relative to the ``reference`` ones.

    Parameters
    ----------
    recording : what :func:`jointbench.read` returns.
    kind : ``"center"``, ``"axis"`` or ``"joint_center"``.
    moving, reference : marker labels (list, or comma-separated string). The first three
        reference labels define the technical frame of the answer. Without ``reference`` the
        moving markers are taken as already expressed in the reference frame (not for
        ``joint_center``, which needs both segments).
    method : a name of ``jointbench.methods(kind)``; ``None`` (the default) is
        :data:`DEFAULT_METHODS`' (``""`` names no method and is refused).
    frames : ``"start:stop"`` in the file's frame numbers (stop excluded), or a slice of rows
        with integer bounds; anything else is a ``ValueError``. The refusal of a label swap
        names the ranges that keep either side of it.
    artefacts : ``"refuse"`` (``ValueError`` naming markers and frame) or ``"exclude"`` (leave
        out, with a warning, the frames that break the shape most frames share; the same
        frames whatever their order).
    rules : thresholds of the artefact detection (:class:`ArtefactRules`), ``None`` for the
        default.
    lab_fixed_reference : ``True`` states that the ``reference`` markers are fixed in the lab
        (a treadmill's frame, a force plate, a wand frame; ``center`` and ``axis`` only,
        anything but a bool is refused): where they also stay still
        (:data:`~jointbench.io.segments.LAB_FIXED_MM`) they are bounded, alone and with the
        moving markers, by a capture volume rather than a body segment; where they move, the
        refusal of their span names the marker, how far it moved and the frames. Without it a
        reference is bounded as a segment, and a still one too wide says so and names this
        option. A still reference's size tells no unit: stated fixed, a unit 10 times off is
        caught only by the moving markers.
    n_bootstrap, block_length, seed : moving-block bootstrap (:mod:`jointbench.uncertainty`);
        0 resamples means none, otherwise at least 2; a block of 1 to all the frames fitted
        (``None``: ``ceil(sqrt(n))``); a seed >= 0. Each an integer (not a bool, a float or
        text), refused with a ``ValueError`` naming it before the fit. The refits are
        conditional on the reference's mean shape.
    options : passed to the estimator.

    To fit several methods on one preparation, use :func:`prepare` and :meth:`Prepared.fit`.
    """
    prepared = prepare(
        recording,
        kind,
        moving,
        reference,
        frames=frames,
        artefacts=artefacts,
        rules=rules,
        lab_fixed_reference=lab_fixed_reference,
    )
    return prepared.fit(
        method, n_bootstrap=n_bootstrap, block_length=block_length, seed=seed, **options
    )
