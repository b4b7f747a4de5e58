"""Rigid segments of a recording: mean shape, technical frame, per-frame pose, artefacts.

A segment is a cluster of >= 3 markers assumed rigid. Its *mean shape* is the generalised
Procrustes mean of the cluster over all frames where it is seen: poses fitted to the current
shape by least squares (on the markers visible in each frame), the shape re-estimated as the
mean of the back-transformed measurements, repeated until it stops changing. No frame is
special, so the shape -- and everything built on it -- does not depend on frame order.

Its *technical frame* is defined on the mean shape from the labels, in the order given:
origin at the centroid of all the cluster's markers, ``x`` from the first marker towards the
second, ``z`` normal to the plane of the first three (``(p2 - p1) x (p3 - p1)``), ``y = z x x``.
A pose ``(R, t)`` maps technical coordinates to the world, ``R @ p + t``.

Artefacts are found by :func:`jointbench.screening.screen` (one home for files and arrays).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, NamedTuple

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy.spatial import ConvexHull

from jointbench.estimators.support import MAX_POSE_SD_RAD
from jointbench.estimators.validation import (
    CAPTURE_VOLUME,
    MAX_CAPTURE_SPAN_MM,
    MAX_JOINED_SPAN_MM,
    MAX_SPAN_MM,
    ONE_SEGMENT,
    TWO_SEGMENTS,
    cluster_span,
    frames_off_scale,
    scale_change,
    span_bound,
)
from jointbench.io.units import (
    UNIT_READ,
    fitting_units,
    the_files_unit,
    unit_hint,
    unit_read_in,
)
from jointbench.numerics.small import inertia
from jointbench.screening import (
    Artefact,
    ArtefactRules,
    Numbering,
    Screening,
    Swap,
    check_magnitudes,
    find_jumps,
    find_rigidity_breaks,
    find_swaps,
    fit_poses,
    flagged_frames,
    mean_shape,
    screen,
    summarise,
    to_local,
    typical_shape,
)

if TYPE_CHECKING:
    from jointbench.io.recording import Recording

__all__ = [
    "HELD_SAMPLES",
    "LAB_FIXED_FLAG",
    "LAB_FIXED_KEYWORD",
    "LAB_FIXED_MM",
    "Artefact",
    "ArtefactRules",
    "Numbering",
    "Screening",
    "Segment",
    "Swap",
    "check_axes_determined",
    "check_joined_span",
    "check_pose_determined",
    "check_span",
    "farthest_apart",
    "find_jumps",
    "find_rigidity_breaks",
    "find_swaps",
    "fit_poses",
    "held_positions",
    "lab_motion",
    "mean_shape",
    "screen",
    "summarise",
    "technical_frame",
    "to_local",
    "typical_shape",
]


def _check_seen(recording: Recording, index: list[int]) -> None:
    """``ValueError`` naming the file, the marker and the frames read when a marker of the
    columns ``index`` shows in none of them: a range of frames (``--frames``) can leave out
    every frame a marker shows in, where "never visible" would read as the whole file's. It
    says how to go on: the segment without that marker, or frames where it is seen."""
    seen = np.isfinite(recording.markers[:, index, 0]).any(axis=0)
    if seen.all():
        return
    label = recording.labels[index[int(np.argmin(seen))]]
    numbering = recording.numbering
    raise ValueError(
        f"{recording.source}: marker {label} is never visible in frames "
        f"{numbering.number(0)} to {numbering.number(recording.n_frames - 1)} (the frames "
        "read): leave it out of the segment's markers (moving, reference; --moving, "
        "--reference), or read frames where it is seen (frames; --frames)"
    )


#: A reference stays still in the lab when the positions each of its markers holds over the
#: frames it is seen in lie within this distance [mm] of one another, and the displacement its
#: markers share in any one sample stays within it too (:func:`lab_motion`). An optical system
#: reconstructs a marker fixed in the lab with noise well under a millimetre, so 5 mm leaves a
#: fixed marker room over a trial of any length, while a body segment's markers seldom stay so
#: still while a joint moves (a standing subject's pelvis sways further). A cluster measured in
#: another unit moves 10 or 1000 times as far: a segment read 10 times its size is taken as
#: still only if it moved under 0.5 mm.
LAB_FIXED_MM = 5.0


class _Bound(NamedTuple):
    """What markers may span: ``largest_mm`` [mm], what spans that in words (``largest``, as
    :func:`~jointbench.estimators.validation.span_bound` takes it), whose markers they are not
    when no unit makes them fit (``whose``), and, for a reference bounded as a segment, why it
    was not bounded by a capture volume (``why_not_lab``: it moves in the lab though stated
    fixed in it, or it stays still but was not stated so; ``""`` otherwise)."""

    largest_mm: float
    largest: str
    whose: str
    why_not_lab: str = ""


#: The bounds of a segment's markers (moving, or a reference not fixed in the lab), and of two
#: joined.
_ONE_SEGMENT = _Bound(MAX_SPAN_MM, ONE_SEGMENT, "one human body segment")
_TWO_SEGMENTS = _Bound(
    MAX_JOINED_SPAN_MM, TWO_SEGMENTS, "two human body segments joined at a joint"
)
#: ... and of a reference stated fixed in the lab that stays still, alone or with the moving
#: markers.
_CAPTURE_VOLUME = _Bound(MAX_CAPTURE_SPAN_MM, CAPTURE_VOLUME, "one optical capture volume")
#: The option by which a user states a reference fixed in the lab: the keyword of
#: :func:`jointbench.fit` and :func:`jointbench.prepare`, and the flag of ``jointbench fit``.
LAB_FIXED_KEYWORD = "lab_fixed_reference"
LAB_FIXED_FLAG = "--lab-fixed-reference"


#: A marker's held position at a sample is the median, axis by axis, of this many consecutive
#: samples of it centred there (:func:`held_positions`): a displacement shown in fewer than half
#: of them, ten samples or fewer, is no position the marker holds. So many samples hold a
#: median steady enough that noise of a millimetre or two on each axis, more than an optical
#: system's, spends little of :data:`LAB_FIXED_MM` on spreading a still marker's held positions
#: over thousands of frames, while a segment's sway, drift or step lasts far longer than eleven
#: samples (a tenth of a second at 100 Hz).
HELD_SAMPLES = 21

#: Above this many held positions their farthest two are sought among their convex hull's
#: vertices (a few dozen), not among every pair.
_PAIRS_AT_MOST = 64


def held_positions(samples: np.ndarray) -> np.ndarray:
    """The positions ``(k - HELD_SAMPLES + 1, 3)`` [mm] that a marker seen in the ``samples``
    ``(k, 3)`` [mm] (in time order, gaps left out) holds: the median, axis by axis, of each run
    of :data:`HELD_SAMPLES` consecutive samples; one position, the median of all, where there
    are fewer."""
    if len(samples) < HELD_SAMPLES:
        return np.median(samples, axis=0, keepdims=True)
    # The median of an odd number of samples is their middle one: a partial sort finds it
    # some thirty times faster than np.median.
    middle = HELD_SAMPLES // 2
    runs = sliding_window_view(samples, HELD_SAMPLES, axis=0)
    return np.partition(runs, middle, axis=-1)[..., middle]


def farthest_apart(points: np.ndarray) -> tuple[float, int, int]:
    """The two of the ``points`` ``(m, 3)`` [mm] that lie farthest apart: their distance [mm]
    and their indices, in order (``0.0, 0, 0`` for one point). The farthest two of a set are
    vertices of its convex hull, so a long trial's are sought among those (joggled, ``QJ``, so
    that points on a line or a plane, or all at one place, make a hull too)."""
    candidates = np.arange(len(points))
    if len(points) > _PAIRS_AT_MOST:
        candidates = np.sort(ConvexHull(points, qhull_options="QJ").vertices)
    among = points[candidates]
    distances = np.linalg.norm(among[:, None] - among[None], axis=-1)
    first, second = np.unravel_index(int(np.argmax(distances)), distances.shape)
    first, second = sorted((int(candidates[first]), int(candidates[second])))
    return float(distances.max()), first, second


def lab_motion(markers: np.ndarray) -> tuple[float, int, int, int]:
    """How far the markers ``(n_frames, n, 3)`` [mm], each seen in some frame, move in the lab
    and hold there: how far apart the positions that each holds lie (:func:`held_positions`,
    over the frames it is seen in, gaps skipped), the largest over the markers, with that
    marker's column and the rows of the two farthest apart, in order (the middle rows of their
    runs of samples); or, where larger, the displacement the markers share in one sample, with
    the column of the marker farthest from its median position in that sample and that row
    twice.

    This rests on the stillness's design (:data:`LAB_FIXED_MM`): "a body segment's markers
    seldom stay so still while a joint moves (a standing subject's pelvis sways further)".
    What tells a reference that moves from one fixed in the lab is sway, and a capture samples
    any sway, drift or step of a segment over many consecutive frames: a displacement held over
    fewer than half of :data:`HELD_SAMPLES` samples is no motion the capture followed, and one
    held longer moves the reference by its full extent, however it lies about the trial's
    median position. A step half-way through the trial leaves each marker half the step from
    its median, a drift half the drift; the positions held before and after lie the whole step
    apart, the drift's ends the whole drift. So a marker's motion is the extent of its held
    positions, not their distance from one median. A bump of a few samples (a marker
    reconstructed a few mm off) is the artefact screen's to judge, not the stillness's: where
    it is under the screen's level
    (:func:`screen`; one corner of a flat cluster bumped out of its plane leaves a quarter of
    the bump as residual, the rest taken by a tilt of the pose) the frames are kept in the fit
    with that error, as any cluster's frames the screen does not flag, and where it is over,
    they are flagged and left out or refused by the artefact policy.

    The screen sees only what changes the cluster's shape, so the displacement the markers
    share in a sample (their mean, over those seen in it, from their median positions) counts
    in every sample, held or not: a mount displaced in every third frame keeps the shape, and
    moves. The shared displacement is no farther than the marker named lies from its median."""
    farthest = (-1.0, 0, 0, 0)
    for column in range(markers.shape[1]):
        rows = np.flatnonzero(np.isfinite(markers[:, column, 0]))
        held = held_positions(markers[rows, column])
        middle = rows[(min(len(rows), HELD_SAMPLES) - 1) // 2 :]
        apart, first, second = farthest_apart(held)
        if apart > farthest[0]:
            farthest = (apart, column, int(middle[first]), int(middle[second]))
    displacements = markers - np.nanmedian(markers, axis=0)
    distances = np.linalg.norm(displacements, axis=-1)
    seen_rows = np.flatnonzero(np.isfinite(distances).any(axis=1))
    shared = np.linalg.norm(np.nanmean(displacements[seen_rows], axis=1), axis=-1)
    k = int(np.argmax(shared))
    if shared[k] > farthest[0]:
        row = int(seen_rows[k])
        column = int(np.nanargmax(distances[row]))
        farthest = (float(shared[k]), column, row, row)
    return farthest


def _reference_bounds(
    recording: Recording,
    labels: tuple[str, ...],
    artefacts: tuple[Artefact, ...],
    stated_lab_fixed: bool,
) -> tuple[_Bound, _Bound]:
    """The bounds of the markers ``labels``, each seen in some frame, of a reference that may
    be fixed in the lab (the frame of a one-segment fit, not the proximal segment of a joint),
    alone and with the moving markers: a capture volume's where the user states it fixed in
    the lab (``stated_lab_fixed``) and its markers stay still in it (:data:`LAB_FIXED_MM`);
    otherwise a body segment's and two joined segments', saying why not a capture volume's
    where that is what the reference looks like or was said to be. The statement is needed: a
    still reference's size tells no unit, and a moving cluster too compact to tell it either
    would let a reference in the wrong unit through.

    Stillness is measured over the frames that the reference's own ``artefacts`` (its screen's,
    :func:`screen`) do not spoil: a bump, a ghost or a label swap in a few frames is an artefact
    that the screen names, and that excluding artefacts leaves out, as for any cluster, not
    motion in the lab. Where the artefacts spoil every frame showing one of the markers, no
    frame shows them still, and all are measured."""
    markers = recording.markers[:, recording.index(labels)]
    unspoilt = markers.copy()
    unspoilt[flagged_frames(artefacts, len(markers))] = np.nan
    if np.isfinite(unspoilt[..., 0]).any(axis=0).all():
        markers = unspoilt
    moved, column, row, next_row = lab_motion(markers)
    still = moved <= LAB_FIXED_MM
    if still and stated_lab_fixed:
        return _CAPTURE_VOLUME, _CAPTURE_VOLUME
    if still:
        unstated = (
            f", and they stay still in the lab, the positions each marker holds within "
            f"{LAB_FIXED_MM:g} mm of one another: a reference fixed in the lab is bounded by what "
            "one optical "
            f"capture volume spans where it is stated so ({LAB_FIXED_KEYWORD}=True, "
            f"{LAB_FIXED_FLAG})"
        )
        return _ONE_SEGMENT._replace(why_not_lab=unstated), _TWO_SEGMENTS._replace(
            why_not_lab=unstated
        )
    if not stated_lab_fixed:
        return _ONE_SEGMENT, _TWO_SEGMENTS
    moves = (
        f", and they move in the lab: {_moved(recording, labels[column], moved, row, next_row)}"
        ", more than the "
        f"{LAB_FIXED_MM:g} mm a reference fixed in the lab stays within (one bumped in some "
        "frames is fitted over frames that leave them out, --frames)"
    )
    return _ONE_SEGMENT._replace(why_not_lab=moves), _TWO_SEGMENTS


def _moved(recording: Recording, label: str, moved: float, row: int, other_row: int) -> str:
    """How the marker ``label`` moved ``moved`` [mm], as :func:`lab_motion` found it, in words:
    how far apart the positions it holds at the rows ``row`` and ``other_row`` lie, or, where
    the markers' shared displacement in one frame (``row == other_row``) is the larger, how far
    that frame shows the marker from its median position."""
    if other_row == row:
        return (
            f"{label} lies {moved:.3g} mm or more from its median position in {recording.when(row)}"
        )
    return (
        f"{label} holds positions {moved:.3g} mm apart, at {recording.when(row)} and at "
        f"{recording.when(other_row)}"
    )


def check_span(markers: np.ndarray, labels: tuple[str, ...], recording: Recording) -> None:
    """``ValueError`` naming the file, its unit and the markers when the cluster
    ``(n_frames, n, 3)`` [mm] of one segment is smaller than a marker or larger than the
    markers of a human body segment can span
    (:func:`~jointbench.estimators.validation.span_bound`,
    :data:`~jointbench.estimators.validation.MAX_SPAN_MM`): coordinates in another unit than
    the file states, whose every answer would be off by a factor of 10 to 1000 and pass the
    checks, which are built for millimetres, or fail them for the wrong reason. Frames in
    another unit than the rest are named first (:func:`_check_frames_scale`)."""
    _check_frames_scale(markers, labels, recording)
    _check_unit(markers, labels, recording, _ONE_SEGMENT)


def _check_frames_scale(markers: np.ndarray, labels: tuple[str, ...], recording: Recording) -> None:
    """``ValueError`` naming the file, the markers ``labels`` and the file's frames where some
    frames of ``markers`` ``(n_frames, n, 3)`` [mm] lie off the cluster's scale, a frame with a
    gap judged by the markers it shows
    (:func:`~jointbench.estimators.validation.frames_off_scale`): frames in another unit than
    the rest, which the artefact screen would otherwise read as a broken shape, or leave out
    as artefacts and fit the rest as if nothing were wrong. It says which of the two groups is
    a body segment's size in the unit the file states."""
    judged = frames_off_scale(markers)
    off = judged[0]
    if off.size == 0:
        return
    first = recording.when(int(off[0]))
    named = scale_change(
        markers, judged, first, recording.first_frame + off, the_files_unit(recording.units)
    )
    raise ValueError(
        f"{recording.source}: markers {', '.join(labels)} {named}, or markers not of one "
        "segment; correct those frames' coordinates, or choose other frames (frames=, --frames)"
    )


def check_joined_span(reference: Segment, moving: tuple[str, ...], recording: Recording) -> None:
    """``ValueError`` as :func:`check_span`'s when the markers of the ``reference`` segment
    and the ``moving`` ones, which turn about a joint between them, lie further apart than
    two joined human body segments' can
    (:data:`~jointbench.estimators.validation.MAX_JOINED_SPAN_MM`): clusters each small
    enough to pass for a segment in the wrong unit, but too far from each other. A reference
    stated fixed in the lab and found still lies with them within one capture volume
    (:attr:`Segment.joined_bound`)."""
    labels = reference.labels + moving
    _check_unit(
        recording.markers[:, recording.index(labels)], labels, recording, reference.joined_bound
    )


def _check_unit(
    markers: np.ndarray, labels: tuple[str, ...], recording: Recording, bound: _Bound
) -> None:
    """``ValueError`` naming the file, the unit it states and, in the units that fit
    (:func:`~jointbench.io.units.unit_hint`), the size its numbers make, when the typical span
    of ``markers`` ``(n_frames, n, 3)`` [mm] (:func:`cluster_span`) of ``labels`` is under a
    marker's size or over ``bound``. Over it in every unit, they are not the markers of
    ``bound.whose`` (a whole body's, say) or in no unit a file states, and the message says so
    rather than blame the unit the file states."""
    span = cluster_span(markers)
    broken = span_bound(span, bound.largest_mm, bound.largest)
    if broken is None:
        return
    if span > bound.largest_mm:
        broken += bound.why_not_lab
    read_in = recording.units or UNIT_READ
    hint = unit_hint(span, read_in, bound.largest_mm)
    if span > bound.largest_mm and fitting_units(span, read_in, bound.largest_mm) == {}:
        raise ValueError(
            f"{recording.source}: markers {', '.join(labels)} lie {span:.3g} mm apart (the "
            f"farthest two, median over the frames), {broken}, in "
            f"{unit_read_in(recording.units)}, and {hint}: they are not the markers of "
            f"{bound.whose}, or are in a unit no file states; choose one segment's markers "
            "(moving, reference; --moving, --reference)"
        )
    raise ValueError(
        f"{recording.source}: markers {', '.join(labels)} lie {span:.3g} mm apart (the farthest "
        f"two, median over the frames), {broken}. The coordinates are not in "
        f"{unit_read_in(recording.units)}{': ' + hint if hint else ''}; correct the "
        "file's unit (C3D POINT:UNITS, TRC Units; a CSV is in mm)"
    )


def check_pose_determined(segment: Segment, source: str) -> None:
    """``ValueError`` naming the file and the markers of the reference ``segment`` when the
    noise leaves the rotation of their frame about the axis they fix worst to chance
    (:meth:`Segment.weakest_rotation_sd` above
    :data:`~jointbench.estimators.support.MAX_POSE_SD_RAD`): nearly collinear markers, whose
    frame turns about their line from frame to frame with the noise, and carries every answer
    expressed in it along. The exact collinearity :func:`technical_frame` refuses is the limit
    of this."""
    sd, noise, spread = segment.weakest_rotation_sd()
    if not sd > MAX_POSE_SD_RAD:
        return
    raise ValueError(
        f"{source}: reference markers {', '.join(segment.labels)} are nearly collinear: their "
        f"frame's rotation about their line is determined to {math.degrees(sd):.2g} deg (the "
        f"rigid fit's noise of {noise:.2g} mm against their RMS distance of {spread:.2g} mm from "
        f"the line), more than {math.degrees(MAX_POSE_SD_RAD):.0f} deg, and every answer in "
        "that frame turns with it; add a marker off their line to the reference"
    )


def check_axes_determined(segment: Segment, source: str) -> None:
    """``ValueError`` naming the file and the markers when the first three labels of the
    reference ``segment``, which set its technical frame's axes (:func:`technical_frame`), lie
    within the rigid fit's noise of one line (the third's distance from the line of the first
    two, in the mean shape, under the noise per coordinate of
    :meth:`Segment.weakest_rotation_sd`): the other markers may fix the pose, but the axes
    then turn about that line with the frames fitted, and every answer in them. The exact
    collinearity :func:`technical_frame` refuses is the limit of this."""
    first, second = segment.shape[:2]
    along = (second - first) / np.linalg.norm(second - first)
    offsets = segment.shape - first
    distances = np.linalg.norm(offsets - np.outer(offsets @ along, along), axis=1)
    _, noise, _ = segment.weakest_rotation_sd()
    if not distances[2] < noise:
        return
    a, b, c = segment.labels[:3]
    farthest = segment.labels[int(np.argmax(distances))]
    raise ValueError(
        f"{source}: the reference's first three markers {a}, {b}, {c} set its frame's axes, but "
        f"{c} lies {distances[2]:.2g} mm from the line from {a} to {b}, less than the rigid "
        f"fit's noise of {noise:.2g} mm, within the noise: the axes would be the noise's; name "
        f"first three that span a plane ({farthest} lies farthest from that line)"
    )


def technical_frame(shape: np.ndarray, labels: tuple[str, ...], source: str) -> np.ndarray:
    """Pose ``(4, 4)`` of the technical frame (module docstring) in ``shape``'s coordinates."""
    first, second, third = shape[:3]
    x = second - first
    normal = np.cross(x, third - first)
    if np.linalg.norm(normal) <= 1e-6 * np.linalg.norm(x) * np.linalg.norm(third - first):
        raise ValueError(
            f"{source}: markers {', '.join(labels[:3])} are collinear; the first three labels "
            "of a segment define its frame and must span a plane"
        )
    x = x / np.linalg.norm(x)
    z = normal / np.linalg.norm(normal)
    pose = np.eye(4)
    pose[:3, :3] = np.column_stack([x, np.cross(z, x), z])
    pose[:3, 3] = shape.mean(axis=0)
    return pose


@dataclass(frozen=True, eq=False)
class Segment:
    """A rigid marker cluster of a recording in its technical frame.

    ``labels`` the markers (the first three define the frame); ``shape`` ``(n, 3)`` [mm] the
    mean shape in technical coordinates; ``rotation`` ``(n_frames, 3, 3)`` and ``translation``
    ``(n_frames, 3)`` [mm] the technical frame's pose in every frame (NaN where fewer than three
    markers are seen); ``residuals`` ``(n_frames, n)`` [mm] each marker's distance from its
    fitted position (NaN where missing); ``artefacts`` the flagged rigidity breaks, swapped
    frames and jumps, and ``swaps`` the label swaps that explain some of them (:func:`screen`);
    ``untested`` what the screen did not test, in words (``""`` when it tested everything);
    ``joined_bound`` what its markers may span with the moving ones (:func:`check_joined_span`):
    two joined body segments, or a capture volume for a reference stated fixed in the lab and
    found still.
    """

    labels: tuple[str, ...]
    shape: np.ndarray
    rotation: np.ndarray
    translation: np.ndarray
    residuals: np.ndarray
    artefacts: tuple[Artefact, ...]
    swaps: tuple[Swap, ...] = ()
    untested: str = ""
    joined_bound: _Bound = field(default=_TWO_SEGMENTS, repr=False)

    @classmethod
    def fit(
        cls,
        recording: Recording,
        labels: str | list[str] | tuple[str, ...],
        rules: ArtefactRules | None = None,
        *,
        stated_lab_fixed: bool | None = None,
    ) -> Segment:
        """Fit the segment (:func:`screen`); frames whose samples break rigidity do not shape
        the mean. Its markers' span is bounded as a body segment's (:func:`check_span`), or,
        where it is a reference that may be fixed in the lab (``stated_lab_fixed`` not
        ``None``: whether the user states it is), by a capture volume where it is stated so
        and they stay still over the frames its artefacts do not spoil
        (:func:`_reference_bounds`): that one is screened first, and its stillness measured
        once, for its span alone and with the moving markers (``joined_bound``)."""
        rules = rules or ArtefactRules()
        index = recording.index(labels)
        labels = tuple(recording.labels[i] for i in index)
        if len(labels) < 3:
            raise ValueError(
                f"{recording.source}: a segment needs at least three markers, got {list(labels)}"
            )
        _check_seen(recording, index)
        markers = recording.markers[:, index]
        # Before the screen, whose own check would name the frame by its row.
        check_magnitudes(markers, labels, recording.source, recording.numbering)
        joined_bound = _TWO_SEGMENTS
        if stated_lab_fixed is None:
            check_span(markers, labels, recording)
        screening = screen(markers, labels, recording.source, rules)
        if stated_lab_fixed is not None:
            bound, joined_bound = _reference_bounds(
                recording, labels, screening.artefacts, stated_lab_fixed
            )
            _check_unit(markers, labels, recording, bound)
        shape, rotation, translation = screening.shape, screening.rotation, screening.translation
        # World x = R (A q + o) + t for technical coordinates q: pose (R A, R o + t).
        frame = technical_frame(shape, labels, recording.source)
        axes, origin = frame[:3, :3], frame[:3, 3]
        shape_local = (shape - origin) @ axes
        translation = translation + rotation @ origin
        rotation = rotation @ axes
        return cls(
            labels,
            shape_local,
            rotation,
            translation,
            screening.residuals,
            screening.artefacts,
            screening.swaps,
            screening.untested,
            joined_bound,
        )

    def weakest_rotation_sd(self) -> tuple[float, float, float]:
        """How well the markers fix their frame's rotation about the axis they fix worst (their
        line, for nearly collinear ones), to first order: the SD of that rotation [rad], the
        rigid fit's noise per coordinate [mm] (its residuals over their ``3 n - 6`` degrees of
        freedom in each frame with a pose) and the markers' RMS distance from that axis
        through their centroid [mm] (the noise over ``sqrt(n)`` times it is the SD). The frames
        its artefacts spoil do not count: a swap's or a bump's residuals are not noise."""
        seen = np.isfinite(self.residuals)
        posed = np.isfinite(self.rotation[:, 0, 0])
        posed &= ~flagged_frames(self.artefacts, len(posed))
        dof = 3 * int(seen[posed].sum()) - 6 * int(posed.sum())
        noise = math.sqrt(np.nansum(self.residuals[posed] ** 2) / dof) if dof > 0 else math.nan
        # The smallest principal moment of the centred shape: sum over the markers of their
        # squared distances from the axis through the centroid that they fix worst.
        moment = float(np.linalg.eigvalsh(inertia(self.shape - self.shape.mean(axis=0)))[0])
        spread = math.sqrt(max(moment, 0.0) / len(self.labels))
        sd = noise / math.sqrt(moment) if moment > 0.0 else math.inf
        return sd, noise, spread

    def posed_to_chance(self) -> np.ndarray:
        """Frames ``(n_frames,)`` bool whose pose the markers seen in them leave to the noise:
        a rotation SD above :data:`~jointbench.estimators.support.MAX_POSE_SD_RAD` about the
        axis those markers of the mean shape fix worst, at the rigid fit's noise
        (:meth:`weakest_rotation_sd`). A marker off the line of the others, missing, leaves
        them so."""
        _, noise, _ = self.weakest_rotation_sd()
        posed = np.isfinite(self.rotation[:, 0, 0])
        patterns, inverse = np.unique(np.isfinite(self.residuals), axis=0, return_inverse=True)
        loose = np.zeros(len(patterns), dtype=bool)
        for k, seen in enumerate(patterns):
            if seen.sum() >= 3:
                shown = self.shape[seen] - self.shape[seen].mean(axis=0)
                moment = float(np.linalg.eigvalsh(inertia(shown))[0])
                loose[k] = not noise < MAX_POSE_SD_RAD * math.sqrt(max(moment, 0.0))
        return posed & loose[inverse.reshape(-1)]

    def determined(self) -> Segment:
        """This segment with no pose (NaN) in the frames :meth:`posed_to_chance` finds, as
        where fewer than three markers are seen: those frames then count as gaps."""
        loose = self.posed_to_chance()
        if not loose.any():
            return self
        rotation, translation = self.rotation.copy(), self.translation.copy()
        rotation[loose] = np.nan
        translation[loose] = np.nan
        return dataclasses.replace(self, rotation=rotation, translation=translation)

    def local(self, markers: np.ndarray) -> np.ndarray:
        """World markers ``(n_frames, m, 3)`` in this segment's technical frame, per frame."""
        return to_local(self.rotation, self.translation, markers)

    def world(self, point: np.ndarray) -> np.ndarray:
        """A point ``(3,)`` fixed in the technical frame, in the world: ``(n_frames, 3)``."""
        return np.einsum("fij,j->fi", self.rotation, np.asarray(point, float)) + self.translation

    def definition(self) -> dict:
        """The technical frame's definition, as reported beside a result."""
        first, second, third = self.labels[:3]
        return {
            "segment": list(self.labels),
            "origin": f"centroid of {', '.join(self.labels)} (mean shape over the frames)",
            "x": f"from {first} towards {second}",
            "z": f"normal to the plane {first}, {second}, {third}: ({second}-{first}) x "
            f"({third}-{first})",
            "y": "z x x",
            "mean_shape_mm": {
                label: [float(v) for v in point]
                for label, point in zip(self.labels, self.shape, strict=True)
            },
        }
