"""Typed tolerances: the one place a published value is compared with a reproduced one.

A tolerance is a mapping with exactly one type key (and, inside ``all``, an ``of`` naming the
part of a compound measurement it reads):

============================  ============================================================
``{abs: a}``                  ``|m − p| ≤ a``
``{rel: r}``                  ``|m − p| ≤ r |p|``
``{max_abs_rel: [a, r]}``     ``|m − p| ≤ max(a, r |p|)``
``{factor: f}``               ``p / f ≤ m ≤ p f``
``{at_least: v}``             ``m ≥ v``
``{at_most: v}``              ``m ≤ v``
``{greater_than: v}``         ``m > v``
``{less_than: v}``            ``m < v``
``{range: [lo, hi]}``         ``lo ≤ m ≤ hi``
``{binomial95: {of_n: n}}``   each count inside the central 95 % range of Binomial(trials,
                              p / n), with the measurement ``{count: [...], trials: [...]}``
``{all: [t, ...]}``           every part holds (a part with ``of: key`` reads that part of a
                              compound measurement, and may carry its own ``published``)
``{shown_only: true}``        not compared: the value is shown beside ours
============================  ============================================================

``m`` and ``p`` may be numbers or equal-length lists (elementwise, all must hold); ``v`` may be
a number or a list of the same length. The **margin** is how far inside (positive) or outside
(negative) the tolerance the worst element lies, in the tolerance's own units (mm, degrees,
shares, counts, or the factor for ``factor``); its text says it in words ("1.70 inside",
"3 trials outside", "on the edge"; an ``all`` names each part: "LS worst share: on the edge").
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from jointbench.numerics.special import scipy_special
from jointbench.resultfiles.formatting import margin_words, words

__all__ = ["TYPES", "Verdict", "binomial_interval", "describe", "evaluate", "wilson_interval"]


@dataclass(frozen=True)
class Verdict:
    """Whether a reproduced value is within its tolerance, and by how much (see module doc)."""

    holds: bool
    margin: float
    margin_text: str


def _array(value: object) -> np.ndarray:
    return np.atleast_1d(np.asarray(value, dtype=float))


def _same_length(measured: np.ndarray, published: np.ndarray) -> None:
    if published.size not in (1, measured.size):
        raise ValueError(
            f"{measured.size} reproduced value(s) for {published.size} published: this run "
            "lacks part of what the entry compares"
        )


def _margin_verdict(margins: np.ndarray, unit: str = "") -> Verdict:
    worst = float(np.min(margins)) if margins.size else float("nan")
    holds = bool(margins.size and np.all(margins >= 0) and np.isfinite(worst))
    return Verdict(holds, worst, margin_words(worst, unit))


def _abs(spec, published, measured) -> Verdict:
    m, p = _array(measured), _array(published)
    _same_length(m, p)
    return _margin_verdict(spec - np.abs(m - p))


def _rel(spec, published, measured) -> Verdict:
    m, p = _array(measured), _array(published)
    _same_length(m, p)
    return _margin_verdict(spec * np.abs(p) - np.abs(m - p))


def _max_abs_rel(spec, published, measured) -> Verdict:
    absolute, relative = spec
    m, p = _array(measured), _array(published)
    _same_length(m, p)
    return _margin_verdict(
        np.maximum(absolute, relative * np.abs(p)) - np.abs(_array(measured) - p)
    )


def _factor(spec, published, measured) -> Verdict:
    p, m = _array(published), _array(measured)
    _same_length(m, p)
    with np.errstate(divide="ignore", invalid="ignore"):
        # Inside by a factor ``spec / (m/p or p/m)``: 1 at the edge; the margin is that less one.
        off = np.maximum(m / p, p / m)
        margins = spec / off - 1.0
    return _margin_verdict(np.where(np.isfinite(margins), margins, -np.inf), "×")


def _bound(spec, measured) -> tuple[np.ndarray, np.ndarray]:
    m, bound = _array(measured), _array(spec)
    _same_length(m, bound)
    return m, bound


def _at_least(spec, published, measured) -> Verdict:
    m, bound = _bound(spec, measured)
    return _margin_verdict(m - bound)


def _at_most(spec, published, measured) -> Verdict:
    m, bound = _bound(spec, measured)
    return _margin_verdict(bound - m)


def _strict(margins: np.ndarray) -> Verdict:
    verdict = _margin_verdict(margins)
    holds = verdict.holds and bool(np.all(margins > 0))
    return Verdict(holds, verdict.margin, verdict.margin_text)


def _greater_than(spec, published, measured) -> Verdict:
    m, bound = _bound(spec, measured)
    return _strict(m - bound)


def _less_than(spec, published, measured) -> Verdict:
    m, bound = _bound(spec, measured)
    return _strict(bound - m)


def _range(spec, published, measured) -> Verdict:
    low, high = spec
    m = _array(measured)
    return _margin_verdict(np.minimum(m - low, high - m))


def _binomial_quantile(q: float, trials: int, proportion: float) -> int:
    """The smallest count ``k`` with ``P(X ≤ k) ≥ q`` for ``X ~ Binomial(trials, proportion)``
    and ``0 < q < 1``: ``scipy.stats.binom.ppf``, from ``scipy.special``, which costs a fraction
    of ``scipy.stats`` to import (tests/test_tolerance.py compares the two)."""
    if not (trials >= 0 and 0 <= proportion <= 1):
        raise ValueError(f"Binomial({trials}, {proportion}) is not a distribution")
    # bdtrik inverts the cdf continued to real k, so the quantile is its ceiling or one below:
    # start below and step up to the first count whose cdf reaches q. bdtrik is NaN where the
    # count is surely or nearly surely 0 (no trials, a proportion below ~1e-16): start at 0.
    special = scipy_special()
    guess = special.bdtrik(q, trials, proportion)
    k = max(math.ceil(guess) - 1, 0) if math.isfinite(guess) else 0
    while special.bdtr(k, trials, proportion) < q:
        k += 1
    return k


def binomial_interval(trials: int, proportion: float) -> tuple[int, int]:
    """Central 95 % range of a Binomial(``trials``, ``proportion``) count."""
    low, high = (_binomial_quantile(q, int(trials), float(proportion)) for q in (0.025, 0.975))
    return low, high


def wilson_interval(successes: int, n: int, z: float = 1.959964) -> tuple[float, float]:
    """Wilson score interval of a share ``successes / n`` (95 % for the default ``z``).

    Unlike the normal approximation it stays inside [0, 1] and is not empty at 0 or ``n``
    successes; ``(0, 1)`` for ``n = 0``, where nothing is known.
    """
    if not 0 <= successes <= n:
        raise ValueError(f"{successes} successes of {n} trials")
    if n == 0:
        return 0.0, 1.0
    share = successes / n
    denominator = 1 + z**2 / n
    centre = (share + z**2 / (2 * n)) / denominator
    half = z * math.sqrt(share * (1 - share) / n + z**2 / (4 * n**2)) / denominator
    return max(0.0, centre - half), min(1.0, centre + half)


def _binomial95(spec, published, measured) -> Verdict:
    counts, trials = _array(measured["count"]), _array(measured["trials"])
    proportions = _array(published) / _array(spec["of_n"])
    _same_length(counts, proportions)
    margins = []
    for count, n, proportion in zip(
        counts, trials, np.broadcast_to(proportions, counts.shape), strict=True
    ):
        low, high = binomial_interval(int(n), float(proportion))
        margins.append(min(count - low, high - count))
    return _margin_verdict(np.asarray(margins, dtype=float), " trials")


def _all(spec, published, measured) -> Verdict:
    verdicts = []
    for part in spec:
        rest = {k: v for k, v in part.items() if k not in ("of", "published")}
        value = measured[part["of"]] if "of" in part else measured
        verdicts.append(evaluate(rest, part.get("published", published), value))
    holds = all(v.holds for v in verdicts)
    margin = min(v.margin for v in verdicts)
    text = "; ".join(
        f"{_part_name(part)}: {v.margin_text}" for part, v in zip(spec, verdicts, strict=True)
    )
    return Verdict(holds, margin, text)


def _part_name(part: Mapping) -> str:
    """A part of an ``all`` tolerance in words: the measurement it reads, else its bound."""
    return words(part["of"]) if "of" in part else describe(part)


TYPES: dict[str, Callable[[object, object, object], Verdict]] = {
    "abs": _abs,
    "rel": _rel,
    "max_abs_rel": _max_abs_rel,
    "factor": _factor,
    "at_least": _at_least,
    "at_most": _at_most,
    "greater_than": _greater_than,
    "less_than": _less_than,
    "range": _range,
    "binomial95": _binomial95,
    "all": _all,
}
NOT_COMPARED = "shown_only"


def _type_of(tolerance: Mapping) -> str:
    kinds = [key for key in tolerance if key in TYPES or key == NOT_COMPARED]
    if len(kinds) != 1:
        raise ValueError(
            f"a tolerance needs exactly one type of {sorted([*TYPES, NOT_COMPARED])}; "
            f"got {dict(tolerance)}"
        )
    return kinds[0]


def is_compared(tolerance: Mapping) -> bool:
    """False for ``{shown_only: true}``: the value is shown beside ours, not tested."""
    return _type_of(tolerance) != NOT_COMPARED


def evaluate(tolerance: Mapping, published: object, measured: object) -> Verdict:
    """Whether ``measured`` is within ``tolerance`` of ``published`` (see the module doc)."""
    kind = _type_of(tolerance)
    if kind == NOT_COMPARED:
        raise ValueError("a shown-only value is not compared; check is_compared() first")
    return TYPES[kind](tolerance[kind], published, measured)


def describe(tolerance: Mapping) -> str:
    """A short human-readable form, e.g. ``max(2, 25 %)`` or ``≥ 0.8``."""
    kind = _type_of(tolerance)
    value = tolerance[kind]
    simple = {
        "abs": lambda v: f"± {v:g}",
        "rel": lambda v: f"± {v:.0%}",
        "max_abs_rel": lambda v: f"± max({v[0]:g}, {v[1]:.0%})",
        "factor": lambda v: f"within a factor {v:g}",
        "at_least": lambda v: f"≥ {v}",
        "at_most": lambda v: f"≤ {v}",
        "greater_than": lambda v: f"> {v}",
        "less_than": lambda v: f"< {v}",
        "range": lambda v: f"in [{v[0]:g}, {v[1]:g}]",
        "binomial95": lambda v: f"inside the 95 % binomial range (of {v['of_n']})",
        NOT_COMPARED: lambda v: "none (shown beside ours)",
    }
    if kind == "all":
        return " and ".join(
            f"{words(part['of'])} {describe(part)}" if "of" in part else describe(part)
            for part in value
        )
    return simple[kind](value)
