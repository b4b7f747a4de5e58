"""Moving-block bootstrap over frames: an interval that respects time correlation.

A fit's analytic covariance (Gauss–Markov's ``W_c``) assumes white marker noise. Soft-tissue
artefact is smooth in time, so neighbouring frames carry nearly the same error and the
white-noise covariance is far too small. The moving-block bootstrap (Künsch 1989) resamples
whole blocks of consecutive frames, keeping that correlation inside each block: a resample of
``n`` frames is ``ceil(n / L)`` blocks of ``L`` consecutive frames with uniformly random starts,
cut to ``n``. The estimator is refitted on each resample; the spread of the refits is the
interval. Blocks must be longer than the correlation time of the error for the interval to hold
(choose ``block_length`` of about one movement cycle on real data); the default ``ceil(sqrt n)``
is a common compromise between that and having enough distinct blocks.
"""

from __future__ import annotations

import math
import numbers
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Annotated

import numpy as np

from jointbench.declared import Count, Range, check

__all__ = [
    "BATCH_FRAMES",
    "RESAMPLING",
    "Bootstrap",
    "block_indices",
    "bootstrap",
    "check_level",
    "check_resampling",
    "default_block_length",
]

#: The names of a bootstrap's arguments (resamples, block length, seed) in its refusals.
RESAMPLING = ("n_resamples", "block_length", "seed")

# What a block length and a seed must be (jointbench.declared): a fractional value would be
# truncated and a negative seed is refused by NumPy deep inside the refits, blamed on them.
_BLOCK_LENGTH = Count | None
_SEED = Annotated[int, Range(0)]
_NONE_OR_MORE = Annotated[int, Range(0)]


def default_block_length(n_frames: int) -> int:
    """``ceil(sqrt(n_frames))`` frames."""
    return int(np.ceil(np.sqrt(n_frames)))


def block_indices(n_frames: int, block_length: int, rng: np.random.Generator) -> np.ndarray:
    """Frame indices ``(n_frames,)`` of one moving-block resample."""
    if not 1 <= block_length <= n_frames:
        raise ValueError(f"block_length must be in [1, {n_frames}] frames, got {block_length}")
    n_blocks = -(-n_frames // block_length)
    starts = rng.integers(0, n_frames - block_length + 1, size=n_blocks)
    return (starts[:, None] + np.arange(block_length)).ravel()[:n_frames]


@dataclass(frozen=True)
class Bootstrap:
    """Refits of an estimate on moving-block resamples.

    ``samples`` ``(n_resamples, d)``, NaN rows where the refit failed (``n_failed`` of them);
    ``block_length`` [frames]. Summaries use the successful refits only.
    """

    samples: np.ndarray
    block_length: int
    n_failed: int

    @property
    def valid(self) -> np.ndarray:
        return self.samples[np.isfinite(self.samples).all(axis=1)]

    def covariance(self) -> np.ndarray:
        """``(d, d)`` covariance of the refits."""
        return np.atleast_2d(np.cov(self.valid, rowvar=False))

    def interval(self, level: float = 0.95) -> np.ndarray:
        """Percentile interval ``(2, d)``: lower and upper bounds holding ``level`` of refits,
        ``level`` in (0, 1)."""
        level = check_level(level)
        tail = 100.0 * (1.0 - level) / 2.0
        return np.percentile(self.valid, [tail, 100.0 - tail], axis=0)


def check_level(level: object) -> float:
    """``level``, the share of refits an interval holds, as a float; ``ValueError`` unless it
    is a number strictly between 0 and 1 (95 is not 0.95, and a negative one would swap the
    bounds)."""
    if (
        isinstance(level, bool | np.bool_)
        or not isinstance(level, numbers.Real)
        or not (math.isfinite(level) and 0.0 < level < 1.0)
    ):
        raise ValueError(f"level must be a number in (0, 1), e.g. 0.95, got {level!r}")
    return float(level)


def check_resampling(
    n_frames: int,
    n_resamples: object,
    block_length: object,
    seed: object,
    *,
    names: tuple[str, str, str] = RESAMPLING,
    zero_is_none: bool = False,
) -> tuple[int, int]:
    """The number of resamples and the block length [frames] of a bootstrap over ``n_frames``
    frames, checked before any refit: ``n_resamples`` an integer >= 2 (or 0, none, with
    ``zero_is_none``), ``block_length`` an integer in [1, ``n_frames``] or ``None`` (the
    default, :func:`default_block_length`), ``seed`` an integer >= 0. A ``ValueError`` names
    the first that is not by its entry of ``names``; a bool or a whole float is not an
    integer, nor is text."""
    resamples_name, block_name, seed_name = names
    check(n_resamples, _NONE_OR_MORE, (resamples_name,))
    if n_resamples < 2 and not (zero_is_none and n_resamples == 0):
        none = "0 (none) or " if zero_is_none else ""
        raise ValueError(f"{resamples_name}: must be {none}an integer >= 2, got {n_resamples!r}")
    check(block_length, _BLOCK_LENGTH, (block_name,))
    if block_length is not None and block_length > n_frames:
        raise ValueError(
            f"{block_name}: must be at most the {n_frames} frames resampled, got {block_length}"
        )
    check(seed, _SEED, (seed_name,))
    length = default_block_length(n_frames) if block_length is None else int(block_length)
    return int(n_resamples), length


#: The frames, over all its resamples, that one call of a bootstrap's statistic refits at most:
#: a recording's refits hold some 600 bytes per frame (an axis on twelve markers), so 1.2 GB,
#: where 200 resamples of a 100,000-frame trial in one batch held 12 GB.
BATCH_FRAMES = 2_000_000


def bootstrap(
    statistic: Callable[[np.ndarray], Sequence[np.ndarray | None]],
    n_frames: int,
    *,
    n_resamples: int = 200,
    block_length: int | None = None,
    seed: int = 0,
    label: str,
) -> Bootstrap:
    """Moving-block bootstrap over ``n_frames`` frames.

    ``statistic`` receives the frame indices of the resamples, ``(k, n_frames)``, in order, in
    batches of as many as hold :data:`BATCH_FRAMES` frames in all (at least one: an estimator
    can refit a batch at once, in memory that does not grow with the recording's length times
    ``n_resamples``), and returns one ``(d,)`` row per resample, or where the refit cannot
    support an answer why (a ``str``) or ``None``; those count as failed. ``label`` names what
    is refitted (the recording or study, and the method), in front of the ``ValueError`` raised
    when more than half the refits fail, which says how
    often each reason came and quotes the commonest. ``n_resamples``,
    ``block_length`` and ``seed`` are refused as :func:`check_resampling` says, before any
    refit. It is required, and refused when
    blank, before any refit: ``statistic`` is any callable, so nothing else can say what it
    refits, and of several bootstraps an unnamed refusal would not say which one failed.
    """
    if not isinstance(label, str) or not label.strip():
        raise ValueError(f"bootstrap: label must name what is refitted, got {label!r}")
    n_resamples, block_length = check_resampling(n_frames, n_resamples, block_length, seed)
    rng = np.random.default_rng(seed)
    per_batch = max(1, BATCH_FRAMES // n_frames)
    rows = []
    for start in range(0, n_resamples, per_batch):
        count = min(per_batch, n_resamples - start)
        rows += statistic(
            np.stack([block_indices(n_frames, block_length, rng) for _ in range(count)])
        )
    width = next((len(row) for row in rows if _is_row(row)), 1)
    samples = np.array([row if _is_row(row) else np.full(width, np.nan) for row in rows], float)
    failed = ~np.isfinite(samples).all(axis=1)
    n_failed = int(np.sum(failed))
    if n_failed > len(rows) // 2:
        reasons = [row if isinstance(row, str) else None for row in rows]
        raise ValueError(
            f"{label}: bootstrap: {n_failed} of {len(rows)} refits failed"
            f"{_failures(np.asarray(reasons, dtype=object)[failed].tolist())}; the frames "
            "cannot support an interval"
        )
    return Bootstrap(samples, block_length, n_failed)


def _is_row(row: object) -> bool:
    return row is not None and not isinstance(row, str)


def _failures(reasons: list[str | None]) -> str:
    """How often each kind of failure came among failed refits' ``reasons`` (their text up to
    the first colon, ``None`` for a row that was no number), and the commonest in full."""
    kinds = ["no answer" if reason is None else reason.split(":")[0].strip() for reason in reasons]
    counts = Counter(kinds)
    commonest, _ = counts.most_common(1)[0]
    example = next(
        (r for r, kind in zip(reasons, kinds, strict=True) if r is not None and kind == commonest),
        None,
    )
    counted = ", ".join(f"{count} {kind}" for kind, count in counts.most_common())
    return f" ({counted}" + ("" if example is None else f"; e.g. {example}") + ")"
