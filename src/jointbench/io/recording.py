"""One in-memory motion-capture recording: labels, frames, rate, markers in mm, gaps as NaN."""

from __future__ import annotations

import copy
import difflib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from jointbench.io.caller import warn_caller
from jointbench.io.segments import Numbering, Segment
from jointbench.numerics.compiled import kernel

__all__ = ["Recording", "parse_frames"]


def _as_missing(markers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``markers`` ``(n_frames, n_markers, 3)`` as float64 with NaN in all three coordinates of
    each sample missing: not finite, or a gap stored at exactly (0, 0, 0)
    (:func:`origin_gaps`); and those gaps, ``(n_frames, n_markers)`` bool, for the warning that
    names them. Other arrays are returned as given, for the shape check to name."""
    markers = np.array(markers, dtype=float)
    if markers.ndim != 3 or markers.shape[-1] != 3:
        return markers, np.zeros(markers.shape[:2], dtype=bool)
    gaps = origin_gaps(markers)
    markers[~np.isfinite(markers).all(axis=-1) | gaps] = np.nan
    return markers, gaps


def origin_gaps(markers: np.ndarray) -> np.ndarray:
    """Which samples of ``markers`` ``(n_frames, n_markers, 3)`` [mm] at exactly (0, 0, 0) are
    gaps a writer stored as zeros, ``(n_frames, n_markers)`` bool: the rule every format is
    read by.

    The C3D format writes an invalid point's coordinates as zeros beside its residual of -1
    ("If a point is invalid then the fourth word (camera mask and residual) will be set to -1
    and the X, Y and Z co-ordinate values should all be zero", c3d.org, notes for programmers,
    integer 3D data); an exporter that drops the residual (a TRC, a CSV) or sets it to 0 keeps
    the zeros, and so do capture programs padding a trial. A measured marker lands at the
    origin to the last bit in all three coordinates only where it moves through it, so such a
    sample is a gap unless its marker could be there: its nearest samples away from the origin
    before and after the run of such samples it belongs to (those the recording holds) are next
    to it, with no missing sample between, and lie no farther from the origin than the marker
    moves, at its fastest between two consecutive samples within :data:`_REACH_FRAMES` frames
    on that side of the run, in a frame.
    Its motion next to the run, not its fastest anywhere: one sample of an artefact (a ghost
    labelled as the marker) jumps far enough to reach the origin from anywhere, and would keep
    every gap of its trial. A marker never away from the origin was never seen (a labelled
    template's marker): all its samples are gaps.

    A marker at its fastest exactly at the origin (a wand swung through it) loses the sample
    there, with the warning: its steps into and out of the origin are the ones being judged,
    and cannot count towards its reach (the step from any sample to a writer's zeros is as long
    as that sample's distance, and would keep every gap), so its reach is its slower steps on
    either side, shorter than its distance from the origin. A reach read across the run
    instead (the step from the sample before to the sample after, the origin between them)
    would keep that sample, and with it the zeros of a marker invalid while it passed the
    origin at that distance, which only the residual tells apart, and which TRC and CSV
    exports drop: the rule leaves the sample out, and names it."""
    markers = np.ascontiguousarray(markers, dtype=np.float64)
    if not (markers == 0.0).all(axis=-1).any():
        # Most recordings hold no sample at the origin, and their reading needs no compiler.
        return np.zeros(markers.shape[:2], dtype=bool)
    return _origin_gaps_of(markers)


@kernel
def _origin_gaps_of(markers: np.ndarray) -> np.ndarray:
    """:func:`origin_gaps` of ``markers`` ``(n_frames, n_markers, 3)`` [mm], C-contiguous
    float64: ``(n_frames, n_markers)`` bool. A compiled kernel: one pass over each marker's
    frames, where array operations would read them a dozen times."""
    n_frames, n_markers = markers.shape[0], markers.shape[1]
    gaps = np.zeros((n_frames, n_markers), dtype=np.bool_)
    at_origin = np.empty(n_frames, dtype=np.bool_)
    seen = np.empty(n_frames, dtype=np.bool_)
    step = np.zeros(max(n_frames - 1, 0))
    for k in range(n_markers):
        first_seen, last_seen, any_at_origin = n_frames, -1, False
        for i in range(n_frames):
            x, y, z = markers[i, k, 0], markers[i, k, 1], markers[i, k, 2]
            at_origin[i] = x == 0.0 and y == 0.0 and z == 0.0
            gaps[i, k] = at_origin[i]
            seen[i] = not at_origin[i] and np.isfinite(x) and np.isfinite(y) and np.isfinite(z)
            any_at_origin |= at_origin[i]
            if seen[i]:
                first_seen, last_seen = min(first_seen, i), i
        if last_seen < 0 or not any_at_origin:
            continue  # never away from the origin: every sample there is a gap
        for i in range(n_frames - 1):
            step[i] = 0.0
            if seen[i] and seen[i + 1]:
                dx = markers[i + 1, k, 0] - markers[i, k, 0]
                dy = markers[i + 1, k, 1] - markers[i, k, 1]
                dz = markers[i + 1, k, 2] - markers[i, k, 2]
                step[i] = np.sqrt((dx * dx + dy * dy) + dz * dz)  # as numpy's norm sums
        start = 0
        while start < n_frames:
            if not at_origin[start]:
                start += 1
                continue
            stop = start
            while stop < n_frames and at_origin[stop]:
                stop += 1
            # The run's nearest samples away from the origin reach it only from right next to
            # it (frames unseen between say nothing of where the marker went), and only where
            # they lie within its fastest step in the _REACH_FRAMES frames on their side.
            kept_before = first_seen > start
            if not kept_before and start > 0 and seen[start - 1]:
                reach = 0.0
                for i in range(max(start - 1 - _REACH_FRAMES, 0), start - 1):
                    reach = max(reach, step[i])
                x, y, z = (
                    markers[start - 1, k, 0],
                    markers[start - 1, k, 1],
                    markers[start - 1, k, 2],
                )
                kept_before = np.sqrt((x * x + y * y) + z * z) <= reach
            kept_after = last_seen < stop
            if not kept_after and stop < n_frames and seen[stop]:
                reach = 0.0
                for i in range(stop, min(stop + _REACH_FRAMES, n_frames - 1)):
                    reach = max(reach, step[i])
                x, y, z = markers[stop, k, 0], markers[stop, k, 1], markers[stop, k, 2]
                kept_after = np.sqrt((x * x + y * y) + z * z) <= reach
            if kept_before and kept_after:
                gaps[start:stop, k] = False
            start = stop
    return gaps


#: The frames on each side of a run at the origin whose steps tell how fast its marker moves
#: there (:func:`origin_gaps`): a tenth of a second at 100 Hz.
_REACH_FRAMES = 10


def _runs(flags: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The runs of ``True`` in ``flags`` ``(n,)`` bool: their first rows and the rows after
    their last, ``(n_runs,)`` int each, in order."""
    edges = np.diff(np.concatenate([[False], flags, [False]]).astype(np.int8))
    return np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)


def _warn_origin_gaps(
    gaps: np.ndarray, missing: np.ndarray, labels: tuple[str, ...], first: int, source: str
) -> None:
    """Warn of the ``gaps`` ``(n_frames, n_markers)`` :func:`origin_gaps` found in ``source``,
    whose row 0 is frame ``first`` and whose other samples ``missing`` ``(n_frames,
    n_markers)`` are missing, naming them: once, as frames zero-filled past the capture's end,
    where the last frames (:func:`_padded_frames`) hold every marker at the origin or missing,
    naming the markers missing there; and each other marker's frames after."""
    n_padded = _padded_frames(gaps, missing)
    if n_padded:
        last = first + len(gaps) - 1
        warn_caller(
            f"{source}: frames {last - n_padded + 1} to {last} (the last {n_padded}) hold every "
            f"marker at exactly (0, 0, 0){_missing_named(missing[-n_padded:], labels)}: frames "
            "zero-filled past the capture's end (a capture stopped early and padded, or a file "
            "cut and padded), not gaps a recording writes; they are read as missing"
        )
    gaps = gaps[: len(gaps) - n_padded]
    if not gaps.any():
        return
    named = "; ".join(
        f"{labels[marker]} {_frames_named(gaps[:, marker], first)}"
        for marker in np.flatnonzero(gaps.any(axis=0))
    )
    n_gaps = int(gaps.sum())
    many = n_gaps > 1
    warn_caller(
        f"{source}: {n_gaps} sample{'s' if many else ''} at exactly (0, 0, 0) "
        f"{'are' if many else 'is'} read as missing, as {'gaps' if many else 'a gap'} a writer "
        "stored as zeros (the C3D format's coordinates of an invalid point), not "
        f"{'positions' if many else 'a position'} at the lab's origin: the marker's nearest "
        f"sample before or after {'each' if many else 'it'} lies farther from the origin than "
        f"the marker moves in a frame nearby (or it has none): {named}"
    )


def _padded_frames(gaps: np.ndarray, missing: np.ndarray) -> int:
    """How many of the last frames are zero-filled past a capture's end: each holds every marker
    (of two or more) at the origin where :func:`origin_gaps` reads it as a gap (``gaps``
    ``(n_frames, n_markers)``), or two or more markers seen elsewhere in the recording there
    and every other marker ``missing`` (a marker unseen before the capture stopped is no
    zero-filling's). One marker alone at the origin may have stopped there, and its gap is its
    own; so are a never seen marker's zeros where the markers seen are missing (a template's
    marker as the subject leaves the volume), which stopped nothing."""
    seen = (~gaps & ~missing).any(axis=0)
    every = gaps.all(axis=1) & (gaps.shape[1] >= 2)
    padded = every | ((gaps | missing).all(axis=1) & ((gaps & seen).sum(axis=1) >= 2))
    kept = np.flatnonzero(~padded)
    return len(padded) - (int(kept[-1]) + 1 if kept.size else 0)


def _missing_named(missing: np.ndarray, labels: tuple[str, ...]) -> str:
    """``" but C, D (in 3 of them), missing there"``: the markers ``missing`` ``(n_frames,
    n_markers)`` marks in some of a warning's frames, by ``labels``; ``""`` for none."""
    parts = [
        labels[marker]
        + ("" if missing[:, marker].all() else f" (in {missing[:, marker].sum()} of them)")
        for marker in np.flatnonzero(missing.any(axis=0))
    ]
    return f" but {', '.join(parts)}, missing there" if parts else ""


#: The runs of a marker's frames a warning names; the rest it counts.
_RUNS_NAMED = 3


def _frames_named(flags: np.ndarray, first: int) -> str:
    """``"at frames 5 to 7 and 13"``: the rows ``flags`` ``(n_frames,)`` bool marks, by frame
    number (row 0 is frame ``first``); ``"at every frame (never away from the origin)"``."""
    if flags.all():
        return "at every frame (never away from the origin)"
    parts = [
        f"{first + start}" if stop == start + 1 else f"{first + start} to {first + stop - 1}"
        for start, stop in zip(*_runs(flags), strict=True)
    ]
    if parts == [parts[0]] and " to " not in parts[0]:
        return f"at frame {parts[0]}"
    if len(parts) > _RUNS_NAMED:
        shown = [*parts[:_RUNS_NAMED], f"{len(parts) - _RUNS_NAMED} more runs"]
    else:
        shown = parts
    listed = shown[0] if len(shown) == 1 else f"{', '.join(shown[:-1])} and {shown[-1]}"
    return f"at frames {listed}"


def _bare(label: str) -> str:
    """``label`` without a subject prefix (``Sub01:``), surrounding spaces or case."""
    return label.rsplit(":", 1)[-1].strip().casefold()


def _near_labels(asked: list[str], labels: tuple[str, ...]) -> str:
    """For a refusal of the ``asked`` labels, the ``labels`` of the file that differ from them
    only by case, spaces or a subject prefix, as the file writes them (a trailing space does not
    show in a list of labels); ``""`` when there are none. They are named, not taken: two
    markers may differ only so."""
    pairs = [
        f"{label!r} for {name!r}"
        for name in asked
        for label in labels
        if _bare(label) == _bare(name)
    ]
    if not pairs:
        return ""
    return (
        f"; the file writes {', '.join(pairs)} (labels are matched as written: case, spaces "
        "and a subject prefix count)"
    )


def _close_labels(asked: list[str], labels: tuple[str, ...]) -> str:
    """For a refusal of the ``asked`` labels, up to three ``labels`` of the file spelled much as
    each is (:func:`difflib.get_close_matches`, a similarity of 0.75 or more), most alike
    first, for those :func:`_near_labels` names none: ``"; close to 'RTH1': 'RTHI1'"``, or
    ``""``. A typing slip is then shown, not left to be found among the file's labels."""
    parts = []
    for name in asked:
        if any(_bare(label) == _bare(name) for label in labels):
            continue
        close = difflib.get_close_matches(name, labels, n=3, cutoff=0.75)
        if close:
            parts.append(f"; close to {name!r}: {', '.join(map(repr, close))}")
    return "".join(parts)


def parse_frames(text: str, n_frames: int, first_frame: int = 0) -> slice:
    """``"start:stop"`` in the file's frame numbers (stop excluded, either side may be empty)
    -> the ``slice`` of rows of a recording of ``n_frames`` whose row 0 is ``first_frame``."""
    end = first_frame + n_frames
    parts = str(text).split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        start = int(parts[0]) if parts[0].strip() else first_frame
        stop = int(parts[1]) if parts[1].strip() else end
    except ValueError:
        raise ValueError(
            f"frames must be 'start:stop' (the file's frame numbers, stop excluded), got {text!r}"
        ) from None
    if not first_frame <= start < stop <= end:
        raise ValueError(
            f"frames {text!r} do not fit the recording, frames {first_frame} to {end - 1}: "
            f"need {first_frame} <= start < stop <= {end}"
        )
    return slice(start - first_frame, stop - first_frame)


@dataclass(frozen=True, eq=False)
class Recording:
    """Marker trajectories of one trial.

    ``labels`` ``(n_markers,)`` names; ``markers`` ``(n_frames, n_markers, 3)`` float64 [mm],
    NaN where a sample is missing (NaN or inf in the file, a negative residual where the format
    has one, or exactly (0, 0, 0) where :func:`origin_gaps` reads that as a gap a writer stored
    as zeros, which a warning names; a marker passing through the lab's origin keeps it);
    ``rate_hz`` the frame rate (``None`` when the file does not say); ``source`` the file it
    came from, for messages; ``units`` the point unit the file states (the markers are
    converted to mm whatever it is), ``""`` where it states none and its coordinates were read
    as mm (a C3D without ``POINT:UNITS``, a CSV), which messages say
    (:func:`~jointbench.io.units.unit_read_in`).

    Frames are named by the file's own numbers, as other motion-capture software shows them:
    row ``i`` is frame ``first_frame + i`` (a C3D header's first frame, a TRC's first
    ``Frame#``, a CSV's smallest ``frame``; 0 for arrays). Messages, frame ranges, fitted frames
    and anchor frames all use these numbers.
    """

    labels: tuple[str, ...]
    markers: np.ndarray
    rate_hz: float | None = None
    source: str = "<memory>"
    first_frame: int = 0
    units: str = "mm"

    def __post_init__(self) -> None:
        labels = tuple(str(label) for label in self.labels)
        markers, gaps = _as_missing(self.markers)
        if markers.ndim != 3 or markers.shape[1:] != (len(labels), 3):
            raise ValueError(
                f"{self.source}: markers must be (n_frames, {len(labels)}, 3) for "
                f"{len(labels)} labels, got shape {markers.shape}"
            )
        seen: dict[str, int] = {}
        for i, label in enumerate(labels):
            if label in seen:
                raise ValueError(
                    f"{self.source}: markers {seen[label] + 1} and {i + 1} (of {len(labels)}) "
                    f"are both labelled {label!r}; each marker needs a label of its own "
                    "(relabel them, or export the trial without unlabelled trajectories)"
                )
            seen[label] = i
        if self.rate_hz is not None and not (np.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ValueError(f"{self.source}: frame rate must be positive, got {self.rate_hz!r}")
        markers.setflags(write=False)
        object.__setattr__(self, "labels", labels)
        object.__setattr__(self, "markers", markers)
        if gaps.any():
            missing = np.isnan(markers[..., 0]) & ~gaps
            _warn_origin_gaps(gaps, missing, labels, self.first_frame, self.source)

    @property
    def n_frames(self) -> int:
        return self.markers.shape[0]

    @property
    def name(self) -> str:
        return Path(self.source).name

    def index(self, labels: str | list[str] | tuple[str, ...]) -> list[int]:
        """Column indices of ``labels`` (a list, or one comma-separated string); a recording
        without markers (an analog-only C3D) refuses any, saying so."""
        if not self.labels:
            raise ValueError(
                f"{self.source}: the file holds no markers (no 3D points: only analog "
                "channels?); a fit needs marker trajectories"
            )
        if isinstance(labels, str):
            labels = [label.strip() for label in labels.split(",") if label.strip()]
        if not labels:
            raise ValueError(f"{self.source}: no marker labels given")
        known = {label: i for i, label in enumerate(self.labels)}
        unknown = [label for label in labels if label not in known]
        if unknown:
            raise ValueError(
                f"{self.source}: no marker labelled {', '.join(map(repr, unknown))}; "
                f"labels in the file: {', '.join(self.labels)}{_near_labels(unknown, self.labels)}"
                f"{_close_labels(unknown, self.labels)}"
            )
        if len(set(labels)) != len(labels):
            raise ValueError(f"{self.source}: a label is named twice in {list(labels)}")
        return [known[label] for label in labels]

    def select(self, labels: str | list[str] | tuple[str, ...]) -> np.ndarray:
        """Markers of ``labels``: ``(n_frames, len(labels), 3)`` [mm], NaN where missing."""
        return self.markers[:, self.index(labels)]

    def frames(self, frames: slice | str) -> Recording:
        """The recording restricted to ``frames``: ``"start:stop"`` in the file's frame numbers
        (stop excluded), or a ``slice`` of rows (steps other than 1 are refused)."""
        if isinstance(frames, str):
            try:
                frames = parse_frames(frames, self.n_frames, self.first_frame)
            except ValueError as error:
                raise ValueError(f"{self.source}: {error}") from None
        start, stop, step = frames.indices(self.n_frames)
        if step != 1:
            raise ValueError(f"{self.source}: a frame range takes consecutive frames, got {frames}")
        # The samples at the origin kept were judged with the whole recording's motion
        # (origin_gaps), which a part may not hold: a part is taken as it is, not judged again.
        part = copy.copy(self)
        object.__setattr__(part, "markers", self.markers[start:stop])
        object.__setattr__(part, "first_frame", self.first_frame + start)
        return part

    def gaps(self) -> dict[str, int]:
        """Missing samples per marker label."""
        missing = np.isnan(self.markers[..., 0]).sum(axis=0)
        return {label: int(n) for label, n in zip(self.labels, missing, strict=True)}

    def when(self, frame: int) -> str:
        """``"frame 731 (7.31 s)"``: how messages name row ``frame`` (by the file's number)."""
        return self.numbering.name(frame)

    @property
    def numbering(self) -> Numbering:
        """How the rows are numbered in messages (:class:`~jointbench.io.segments.Numbering`)."""
        return Numbering(self.first_frame, self.rate_hz)

    def segment(self, labels: str | list[str] | tuple[str, ...]) -> Segment:
        """The rigid segment carried by ``labels``: mean shape, technical frame, poses."""
        return Segment.fit(self, labels)
