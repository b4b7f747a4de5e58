"""Priors over a study's unpublished modelling choices: what a plausible protocol may be.

Each study's simulator fills in what its paper leaves unsaid (marker directions, the shape of a
motion, where the joint sits) with one value each. A :class:`Prior` makes each such choice a
named scalar :class:`Choice` with the paper sentence it fills in, its bounds and the reason for
them, and a ``build`` function turning one value per choice into the study's ``protocol``
overrides, as the config writes them. The simulator's defaults are one member of the prior
(:func:`default_values`), so the default run is one named protocol among the plausible ones.

Draws are uniform within the bounds, or log-uniform for a choice whose plausible values span
orders of magnitude; ``accept`` rejects combinations the bounds alone allow but anatomy does
not (markers too close to tell apart). A draw is fixed by its seed alone.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Choice", "Prior", "default_values", "draw_values"]

#: Draws rejected by a prior's ``accept`` before the prior is declared unsatisfiable.
MAX_TRIES = 10_000


@dataclass(frozen=True)
class Choice:
    """One unpublished choice: drawn in ``[low, high]`` (log-uniformly when ``log``), its
    simulator default ``default``, the paper ``sentence`` it fills in and the ``reason`` for
    the bounds."""

    name: str
    low: float
    high: float
    default: float
    sentence: str
    reason: str
    log: bool = False

    def __post_init__(self) -> None:
        if not self.low < self.high:
            raise ValueError(f"choice {self.name!r}: low {self.low} is not below high {self.high}")
        if self.log and self.low <= 0:
            raise ValueError(f"choice {self.name!r}: a log-uniform range needs low > 0")
        # A tolerance of rounding: defaults are often derived from the simulator's coordinates.
        slack = 1e-9 * (self.high - self.low)
        if not self.low - slack <= self.default <= self.high + slack:
            raise ValueError(
                f"choice {self.name!r}: default {self.default} is outside [{self.low}, {self.high}]"
            )

    def draw(self, rng: np.random.Generator) -> float:
        """One value from ``rng``: uniform in ``[low, high]``, or uniform in its logarithm."""
        if self.log:
            return float(math.exp(rng.uniform(math.log(self.low), math.log(self.high))))
        return float(rng.uniform(self.low, self.high))


def _always(values: Mapping[str, float]) -> bool:
    return True


@dataclass(frozen=True)
class Prior:
    """The choices of one study; ``build`` maps one value per choice (by name) to the study's
    ``protocol`` overrides; ``accept`` says whether a combination is plausible."""

    study: str
    choices: tuple[Choice, ...]
    build: Callable[[Mapping[str, float]], dict]
    accept: Callable[[Mapping[str, float]], bool] = field(default=_always)

    def __post_init__(self) -> None:
        names = [choice.name for choice in self.choices]
        if len(set(names)) != len(names):
            raise ValueError(f"prior of {self.study!r} names a choice twice")
        if not self.accept(default_values(self)):
            raise ValueError(f"prior of {self.study!r} rejects its own defaults")


def default_values(prior: Prior) -> dict[str, float]:
    """The simulator's defaults as one value per choice: the default member of ``prior``."""
    return {choice.name: float(choice.default) for choice in prior.choices}


def draw_values(prior: Prior, seed: int) -> dict[str, float]:
    """One plausible protocol of ``prior``, one value per choice, fixed by ``seed`` alone:
    every choice drawn in turn, the whole draw repeated until ``accept`` takes it."""
    rng = np.random.default_rng(seed)
    for _ in range(MAX_TRIES):
        values = {choice.name: choice.draw(rng) for choice in prior.choices}
        if prior.accept(values):
            return values
    raise ValueError(f"prior of {prior.study!r} accepted none of {MAX_TRIES} draws")
