"""One in-memory motion-capture recording: labels, frames, rate, markers in mm, gaps as NaN."""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from jointbench.io.segments import Numbering, Segment

__all__ = ["Recording", "parse_frames"]


def _as_missing(markers: np.ndarray) -> np.ndarray:
    """Samples that are not finite or exactly (0, 0, 0) become NaN in all three coordinates.

    Several C3D and TRC writers store an occluded marker as the origin; a real marker exactly
    at the lab origin to the last bit does not happen, a gap stored that way does.
    """
    markers = np.array(markers, dtype=float)
    missing = ~np.isfinite(markers).all(axis=-1) | (markers == 0.0).all(axis=-1)
    markers[missing] = np.nan
    return markers


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
    NaN where a sample is missing (NaN, inf or exactly (0, 0, 0) in the file, or a negative
    residual where the format has one); ``rate_hz`` the frame rate (``None`` when the file does
    not say); ``source`` the file it came from, for messages; ``units`` the point unit the file
    states (the markers are converted to mm whatever it is), ``""`` where it states none and
    its coordinates were read as mm (a C3D without ``POINT:UNITS``, a CSV), which messages say
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
        markers = _as_missing(self.markers)
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
        return Recording(
            self.labels,
            self.markers[start:stop],
            self.rate_hz,
            self.source,
            self.first_frame + start,
            self.units,
        )

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
