"""Artefacts of a marker cluster: rigid fits, label swaps, rigidity breaks and jumps.

Artefacts. A label swap or a marker that falls off breaks rigidity: that marker's residual from
the fitted pose jumps far above the trial's own level, which for skin markers is soft-tissue
artefact of a few mm. A sample is flagged when its residual exceeds ``residual_factor`` times
the lower quartile of the cluster's residuals and ``min_residual_mm``. The residuals are first
taken from the cluster's most typical frame (which a minority of broken frames cannot distort,
as they would a mean), then from the mean shape of the samples not flagged, until the flags settle.
A label swap is an event at a frame: the frames it flags are explained by exchanging two labels,
and :func:`find_swaps` reports the runs of frames carrying the pair one way round, so a message
names where the labelling changes and both sides can be kept. None of this depends on the order
of the frames. A step of one marker is flagged when it differs from both neighbouring steps by
more than ``jump_factor`` times the median such difference and ``min_jump_mm``
(:func:`find_jumps`), which needs the frames in time order: it is the only check of markers
outside a cluster, and in a cluster it counts only where no rigidity break explains it (a swap
of two markers of an isosceles triangle keeps the shape).

:func:`screen` runs these checks on bare arrays, for :func:`jointbench.screen` and the fit
functions of :mod:`jointbench.api`; :meth:`Segment.fit` runs the same on a recording.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations, pairwise

import numpy as np

from jointbench.numerics.poses import best_rotation

__all__ = [
    "Artefact",
    "ArtefactRules",
    "Numbering",
    "Screening",
    "Swap",
    "find_jumps",
    "find_rigidity_breaks",
    "find_swaps",
    "fit_poses",
    "mean_shape",
    "residuals",
    "screen",
    "summarise",
    "to_local",
    "typical_shape",
]

_MAX_ITERATIONS = 200
_TOL_MM = 1e-10


def fit_poses(shape: np.ndarray, markers: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares pose of ``shape`` ``(n, 3)`` onto every frame of ``markers``
    ``(n_frames, n, 3)`` [mm], using the markers visible (finite) in each frame.

    Returns ``R`` ``(n_frames, 3, 3)`` and ``t`` ``(n_frames, 3)`` [mm]; NaN in frames with
    fewer than three visible markers.
    """
    visible = np.isfinite(markers).all(axis=-1)
    count = visible.sum(axis=1)
    weight = visible / np.maximum(count, 1)[:, None]
    filled = np.where(visible[..., None], markers, 0.0)
    target_mean = np.einsum("fm,fmi->fi", weight, filled)
    shape_mean = weight @ shape
    cross = np.einsum(
        "fm,fmi,fmj->fij",
        visible.astype(float),
        filled - target_mean[:, None],
        shape[None] - shape_mean[:, None],
    )
    rotation = best_rotation(cross)
    translation = target_mean - np.einsum("fij,fj->fi", rotation, shape_mean)
    posed = count >= 3
    rotation[~posed] = np.nan
    translation[~posed] = np.nan
    return rotation, translation


def to_local(rotation: np.ndarray, translation: np.ndarray, markers: np.ndarray) -> np.ndarray:
    """World markers ``(n_frames, n, 3)`` into the frame posed by ``(R, t)``: ``R' (x - t)``."""
    return np.einsum("fji,fmj->fmi", rotation, markers - translation[:, None, :])


def typical_shape(markers: np.ndarray, labels: tuple[str, ...], source: str) -> np.ndarray:
    """The cluster ``(n, 3)`` in its most typical complete frame: the one whose inter-marker
    distances are nearest their medians over the trial, which a minority of broken frames
    cannot pull."""
    seen = np.isfinite(markers[..., 0]).any(axis=0)
    if not seen.all():
        raise ValueError(f"{source}: marker {labels[int(np.argmin(seen))]} is never visible")
    complete = np.flatnonzero(np.isfinite(markers).all(axis=(1, 2)))
    if complete.size == 0:
        raise ValueError(
            f"{source}: markers {', '.join(labels)} are never all visible in one frame; "
            "a segment needs one frame showing its whole cluster"
        )
    clusters = markers[complete]
    distances = np.linalg.norm(clusters[:, :, None] - clusters[:, None], axis=-1)
    deviation = np.abs(distances - np.median(distances, axis=0)).max(axis=(1, 2))
    return clusters[int(np.argmin(deviation))].copy()


def mean_shape(markers: np.ndarray, labels: tuple[str, ...], source: str) -> np.ndarray:
    """Generalised Procrustes mean shape ``(n, 3)`` [mm] of a cluster (module docstring),
    in the frame of its most typical complete frame (the caller fixes the frame)."""
    shape = typical_shape(markers, labels, source)
    for _ in range(_MAX_ITERATIONS):
        rotation, translation = fit_poses(shape, markers)
        posed = np.isfinite(rotation[:, 0, 0])
        local = to_local(rotation[posed], translation[posed], markers[posed])
        new = np.nanmean(local, axis=0)
        change = float(np.max(np.abs(new - shape)))
        shape = new
        if change < _TOL_MM * max(1.0, float(np.abs(shape).max())):
            return shape
    raise ValueError(
        f"{source}: the mean shape of {', '.join(labels)} did not converge in "
        f"{_MAX_ITERATIONS} iterations (last change {change:.3g} mm)"
    )


@dataclass(frozen=True)
class Numbering:
    """How messages name the rows of a marker array: row ``i`` is frame ``first_frame + i``
    (the file's numbering), at ``number / rate_hz`` seconds when the rate is known."""

    first_frame: int = 0
    rate_hz: float | None = None

    def number(self, row: int) -> int:
        return self.first_frame + int(row)

    def name(self, row: int) -> str:
        """``"frame 731 (7.31 s)"``."""
        frame = self.number(row)
        if self.rate_hz is None:
            return f"frame {frame}"
        return f"frame {frame} ({frame / self.rate_hz:.2f} s)"


@dataclass(frozen=True)
class ArtefactRules:
    """When a sample or a step is far above the trial's own level (module docstring)."""

    residual_factor: float = 15.0
    min_residual_mm: float = 5.0
    jump_factor: float = 20.0
    min_jump_mm: float = 20.0


@dataclass(frozen=True)
class Artefact:
    """One flagged sample: ``kind`` ``"jump"`` or ``"rigidity"``, ``size_mm`` the step or the
    residual, ``level_mm`` the threshold it crossed."""

    kind: str
    label: str
    frame: int
    size_mm: float
    level_mm: float

    def describe(self, frames: Numbering) -> str:
        """One line, naming the frame as ``frames`` does."""
        what = "jumps" if self.kind == "jump" else "leaves its cluster's rigid shape by"
        return (
            f"marker {self.label} {what} {self.size_mm:.1f} mm at {frames.name(self.frame)} "
            f"(threshold {self.level_mm:.1f} mm; a label swap or a marker falling off?)"
        )

    def rows(self) -> tuple[int, ...]:
        """The frames it spoils: a rigidity break its own; a jump the two frames of its step,
        so that the same step gives the same frames whichever way the frames run."""
        return (self.frame - 1, self.frame) if self.kind == "jump" else (self.frame,)


@dataclass(frozen=True)
class Swap:
    """Markers ``labels`` carried the other way round, relative to the rest of the trial, in
    rows ``start`` to ``stop - 1``: the labelling changes at ``start`` (unless 0) and back at
    ``stop`` (unless the end of the trial, ``n_frames``)."""

    labels: tuple[str, str]
    start: int
    stop: int
    n_frames: int

    def sides(self) -> list[tuple[int, int]]:
        """Row ranges ``[start, stop)`` each labelled one consistent way, in time order."""
        bounds = sorted({0, self.start, self.stop, self.n_frames})
        return list(pairwise(bounds))

    def describe(self, frames: Numbering) -> str:
        """One line naming the frames where the labels change and both sides, as ``frames``
        numbers them."""
        first, second = self.labels
        changes = [row for row in (self.start, self.stop) if 0 < row < self.n_frames]
        sides = ", ".join(f"{frames.number(a)} to {frames.number(b - 1)}" for a, b in self.sides())
        return (
            f"markers {first} and {second} exchange labels at "
            f"{' and back at '.join(frames.name(row) for row in changes)}; frames {sides} are "
            "each labelled one consistent way and the data cannot tell which is right"
        )


def summarise(artefacts: list[Artefact], swaps: list[Swap], frames: Numbering) -> str:
    """The swaps in full, else the first artefact; then how many flagged samples, over which
    frames and markers."""
    lines = [swap.describe(frames) for swap in swaps] or [artefacts[0].describe(frames)]
    text = "; ".join(lines)
    if len(artefacts) > 1:
        rows = [a.frame for a in artefacts]
        markers = sorted({a.label for a in artefacts})
        text += (
            f"; {len(artefacts)} flagged samples in all, frames {frames.number(min(rows))} to "
            f"{frames.number(max(rows))}, markers {', '.join(markers)}"
        )
    return text


def find_jumps(
    markers: np.ndarray, labels: tuple[str, ...], rules: ArtefactRules
) -> list[Artefact]:
    """Steps of one marker that differ from both neighbouring steps by far more than usual.

    A fast but smooth movement changes its step little from frame to frame; a label swap or a
    marker knocked off adds a step of its own. The size of the step at frame ``k`` is
    ``min(|s_k - s_(k-1)|, |s_k - s_(k+1)|)`` with ``s_k = x_k - x_(k-1)``.
    """
    steps = np.diff(markers, axis=0)  # (n_frames - 1, n, 3), NaN at gaps
    if steps.shape[0] < 3:
        return []
    size = np.fmin(
        np.linalg.norm(steps[1:-1] - steps[:-2], axis=-1),
        np.linalg.norm(steps[1:-1] - steps[2:], axis=-1),
    )
    if not np.isfinite(size).any():
        return []
    level = max(rules.min_jump_mm, rules.jump_factor * float(np.nanmedian(size)))
    step, marker = np.nonzero(np.nan_to_num(size) > level)
    return [
        Artefact("jump", labels[m], int(k) + 2, float(size[k, m]), level)
        for k, m in zip(step, marker, strict=True)
    ]


def find_rigidity_breaks(
    residuals: np.ndarray, labels: tuple[str, ...], rules: ArtefactRules
) -> list[Artefact]:
    """Samples whose rigid-fit residual ``(n_frames, n)`` [mm] is far above the trial's level
    (its lower quartile), so that up to three quarters of the samples may be broken."""
    if not np.isfinite(residuals).any():
        return []
    # The lower quartile, not the median: a swap held by half the frames displaces more than
    # half the samples (the pose fit spreads it), which would lift a median above them.
    typical = float(np.nanpercentile(residuals, 25))
    level = max(rules.min_residual_mm, rules.residual_factor * typical)
    frame, marker = np.nonzero(np.nan_to_num(residuals) > level)
    return [
        Artefact("rigidity", labels[m], int(f), float(residuals[f, m]), level)
        for f, m in zip(frame, marker, strict=True)
    ]


def find_swaps(
    shape: np.ndarray,
    markers: np.ndarray,
    flagged: np.ndarray,
    labels: tuple[str, ...],
    level_mm: float,
) -> list[Swap]:
    """Runs of frames in which exchanging two markers' labels fits the cluster's ``shape``.

    ``markers`` ``(n_frames, n, 3)`` [mm] the cluster, ``flagged`` ``(n_frames, n)`` its
    rigidity breaks, ``level_mm`` their threshold. A frame whose two flagged markers, exchanged,
    fit ``shape`` within ``level_mm`` belongs to that pair's swap; frames where either marker
    is missing do not interrupt a run.
    """
    swaps = []
    for i, j in combinations(range(len(labels)), 2):
        both = flagged[:, i] & flagged[:, j]
        if not both.any():
            continue
        rows = np.flatnonzero(both)
        exchanged = markers[rows].copy()
        exchanged[:, [i, j]] = exchanged[:, [j, i]]
        rotation, translation = fit_poses(shape, exchanged)
        fits = np.nanmax(residuals(shape, rotation, translation, exchanged), axis=1) <= level_mm
        state = np.zeros(len(markers), dtype=bool)
        state[rows[fits]] = True
        seen = np.flatnonzero(np.isfinite(markers[:, [i, j]]).all(axis=(1, 2)))
        # Runs of swapped frames among the frames showing both markers.
        changes = np.flatnonzero(np.diff(state[seen].astype(int))) + 1
        for run in np.split(np.arange(seen.size), changes):
            if run.size and state[seen[run[0]]]:
                start = 0 if run[0] == 0 else int(seen[run[0]])
                stop = len(markers) if run[-1] == seen.size - 1 else int(seen[run[-1]]) + 1
                swaps.append(Swap((labels[i], labels[j]), start, stop, len(markers)))
    return sorted(swaps, key=lambda swap: (swap.start, swap.labels))


@dataclass(frozen=True, eq=False)
class Screening:
    """What :func:`screen` found in one marker set: flagged ``artefacts`` (rigidity breaks of
    a cluster of >= 3 markers, or jumps of fewer) and the ``swaps`` explaining some of them.
    A cluster's fit is kept for :class:`Segment`: ``shape`` ``(n, 3)`` [mm], its ``rotation``
    ``(n_frames, 3, 3)``, ``translation`` ``(n_frames, 3)`` and ``residuals`` ``(n_frames, n)``
    [mm]; ``None`` for fewer than three markers."""

    artefacts: tuple[Artefact, ...]
    swaps: tuple[Swap, ...] = ()
    shape: np.ndarray | None = None
    rotation: np.ndarray | None = None
    translation: np.ndarray | None = None
    residuals: np.ndarray | None = None


def screen(
    markers: np.ndarray,
    labels: tuple[str, ...],
    source: str,
    rules: ArtefactRules | None = None,
) -> Screening:
    """Artefacts of one marker set ``(n_frames, n, 3)`` [mm] (module docstring): rigidity
    breaks and swaps of a cluster of >= 3 markers, jumps of fewer. ``source`` names the data
    in messages. Frame order matters only to the jumps."""
    rules = rules or ArtefactRules()
    if len(labels) < 3:
        return Screening(tuple(find_jumps(markers, labels, rules)))
    # First judged against one typical frame, which the broken frames cannot distort; then the
    # mean shape is refitted on the samples not flagged, until the flags settle.
    shape = typical_shape(markers, labels, source)
    breaks: list[Artefact] | None = None
    for _ in range(5):
        rotation, translation = fit_poses(shape, markers)
        misfit = residuals(shape, rotation, translation, markers)
        found = find_rigidity_breaks(misfit, labels, rules)
        if found == breaks:
            break
        breaks = found
        clean = markers.copy()
        for artefact in breaks:
            clean[artefact.frame, labels.index(artefact.label)] = np.nan
        shape = mean_shape(clean, labels, source)
    else:
        rotation, translation = fit_poses(shape, markers)
        misfit = residuals(shape, rotation, translation, markers)
    swaps: list[Swap] = []
    if breaks:
        flagged = np.zeros(misfit.shape, dtype=bool)
        for artefact in breaks:
            flagged[artefact.frame, labels.index(artefact.label)] = True
        swaps = find_swaps(shape, markers, flagged, labels, breaks[0].level_mm)
    # A jump that a rigidity break explains adds nothing, and would spoil the frame on its
    # other side; a jump without one is a swap that keeps the shape (two markers of an
    # isosceles triangle), which only time order shows.
    broken = {(a.label, a.frame) for a in breaks}
    jumps = [
        jump
        for jump in find_jumps(markers, labels, rules)
        if not {(jump.label, row) for row in jump.rows()} & broken
    ]
    artefacts = sorted([*jumps, *breaks], key=lambda a: (a.frame, a.label))
    return Screening(tuple(artefacts), tuple(swaps), shape, rotation, translation, misfit)


def residuals(
    shape: np.ndarray, rotation: np.ndarray, translation: np.ndarray, markers: np.ndarray
) -> np.ndarray:
    """Each marker's distance ``(n_frames, n)`` [mm] from ``shape`` ``(n, 3)`` posed by
    ``(R, t)`` in every frame (NaN where missing)."""
    fitted = np.einsum("fij,mj->fmi", rotation, shape) + translation[:, None, :]
    return np.linalg.norm(markers - fitted, axis=-1)
