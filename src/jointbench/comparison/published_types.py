"""What each kind of tolerance reads in a published-values entry, checked when the file is read.

The schema (``published.schema.yaml``) allows any ``published`` value, because what it must be
depends on the tolerance (:mod:`jointbench.comparison.tolerance`):

* ``abs``, ``rel``, ``max_abs_rel`` compare the measurement with it: a real number, or a
  non-empty list of them (elementwise);
* ``factor`` divides by it: positive real numbers;
* the width these four carry (``abs``, ``rel``, ``factor``, both of ``max_abs_rel``) is a
  finite number above zero, and no narrower than :data:`MIN_RELATIVE_WIDTH` of the published
  value (a factor at least ``1 + MIN_RELATIVE_WIDTH``);
* ``binomial95`` reads it as success counts (integers >= 0) out of ``of_n`` trials (integers
  >= 1, one for every count or one for all), no count above its ``of_n``;
* the bounds (``at_least``, ``at_most``, ``greater_than``, ``less_than``, ``range``) carry their
  own finite numbers, a range two increasing ones, and show the published value as the paper's
  words: there it may be text;
* ``all`` checks each part, a part's own ``published`` in place of the entry's;
* ``shown_only`` compares nothing.

A value the comparison would misread (``true`` as 1, ``"8"`` as 8) or could not read
(``"8.0 mm"``) is thus refused before any verdict, not turned into one; so is a list of
another length than its check measures (:func:`length_problem`, one value per level of the
paper's :class:`~jointbench.papers.base.PerLevel`), which a run could only fail to compare, and
a single value or range there, which it would hold every level to.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Iterator, Mapping

__all__ = ["MIN_RELATIVE_WIDTH", "entry_problem", "is_number", "length_problem"]

#: The narrowest width a tolerance may have, relative to what it compares: a factor at least
#: ``1 + MIN_RELATIVE_WIDTH``, a relative width at least this, an absolute one at least this
#: times the largest published value it applies to. Narrower, a check passes only a measurement
#: equal to the paper's rounded number to within the rounding of a double (about 1e-16 of it,
#: which arithmetic on the measurement accumulates far beyond): no simulation can be held to
#: that, so such a width is a mistake in the file (a 0 typed for 0.5, a factor of 1).
MIN_RELATIVE_WIDTH = 1e-9
#: The share by which a width may fall short of its floor and still be at it: a floor written
#: as a decimal (1.23456e-07 for 1e-9 of 123.456, 3e-09 of 3) reads as the double nearest it,
#: which can lie a unit or two of the last place (about 2e-16 of it) below the double product
#: ``MIN_RELATIVE_WIDTH * published`` it is held to. A few of those units, far below any
#: width's meaning.
_ROUNDING = 8 * sys.float_info.epsilon
_REFERENCE = ("abs", "rel", "max_abs_rel")
_BOUNDS = ("at_least", "at_most", "greater_than", "less_than")


def is_number(value: object) -> bool:
    """A finite real number as YAML gives it: not a bool (YAML's true/false, which Python counts
    as integers), not a string, not NaN or infinite."""
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def _is_integer(value: object) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def entry_problem(entry: Mapping) -> tuple[str, str] | None:
    """``(key, what is wrong)`` with the first value of a schema-checked published-values
    ``entry`` that its tolerance cannot read as the module doc says, or None; ``key`` is its
    dotted path in the entry (``published``, ``tolerance.all[1].published``). Wherever it is
    only shown, ``published`` is the paper's numbers or words, never YAML's true, false or
    null."""
    shown = _shown_problem(entry["published"])
    if shown:
        return "published", shown
    return _tolerance_problem(entry["tolerance"], entry["published"], "published", "tolerance")


def _shown_problem(value: object) -> str | None:
    """A boolean or null in ``value`` (a number, text, or lists and mappings of them), which
    no paper prints: a value lost or mistyped in the file."""
    if isinstance(value, list):
        items = value
    elif isinstance(value, Mapping):
        items = list(value.values())
    else:
        items = [value]
    for item in items:
        if isinstance(item, bool) or item is None:
            return f"{item!r} is neither a number nor the paper's words"
        if isinstance(item, list | Mapping):
            problem = _shown_problem(item)
            if problem:
                return problem
    return None


def _leaves(
    tolerance: Mapping, published: object, published_key: str, key: str
) -> Iterator[tuple[str, object, object, str, str]]:
    """``(kind, spec, published, published_key, key)`` of each tolerance that compares:
    ``tolerance`` itself, or each part of an ``all``, a part's own ``published`` in place of
    the entry's."""
    (kind,) = [k for k in tolerance if k not in ("of", "published")]
    if kind != "all":
        yield kind, tolerance[kind], published, published_key, key
        return
    for index, part in enumerate(tolerance[kind]):
        where = f"{key}.all[{index}]"
        own = "published" in part
        yield from _leaves(
            part,
            part["published"] if own else published,
            f"{where}.published" if own else published_key,
            where,
        )


def _tolerance_problem(
    tolerance: Mapping, published: object, published_key: str, key: str
) -> tuple[str, str] | None:
    for kind, spec, value, value_key, where in _leaves(tolerance, published, published_key, key):
        problem = _leaf_problem(kind, spec, value, value_key, where)
        if problem:
            return problem
    return None


def _leaf_problem(
    kind: str, spec: object, published: object, published_key: str, key: str
) -> tuple[str, str] | None:
    if kind in _REFERENCE or kind == "factor":
        own = _width_problem(spec)
        if own:
            return f"{key}.{kind}", own
        problem = _numbers_problem(published, positive=kind == "factor")
        if problem:
            return published_key, problem
        narrow = _narrow_problem(kind, spec, published)
        return (f"{key}.{kind}", narrow) if narrow else None
    if kind in _BOUNDS:
        problem = _numbers_problem(spec)
        return (f"{key}.{kind}", problem) if problem else None
    if kind == "range":
        problem = _range_problem(spec)
        return (f"{key}.range", problem) if problem else None
    if kind == "binomial95":
        return _binomial_problem(spec["of_n"], published, published_key, f"{key}.binomial95.of_n")
    return None  # shown_only


def _compared_values(entry: Mapping) -> list[tuple[str, object]]:
    """``(key, value)`` of each number or list of a schema-checked published-values ``entry``
    that its tolerance holds a measurement to element by element: the published value where
    the tolerance compares it (``abs``, ``rel``, ``max_abs_rel``, ``factor``, ``binomial95``'s
    counts), a bound's value, ``binomial95``'s ``of_n``. Not a published value only shown
    beside a bound (paper C's eight v), nor a range's or ``max_abs_rel``'s pair."""
    found = []
    for kind, spec, published, published_key, key in _leaves(
        entry["tolerance"], entry["published"], "published", "tolerance"
    ):
        if kind in (*_REFERENCE, "factor", "binomial95"):
            found.append((published_key, published))
        if kind in _BOUNDS:
            found.append((f"{key}.{kind}", spec))
        if kind == "binomial95":
            found.append((f"{key}.binomial95.of_n", spec["of_n"]))
    return list(dict(found).items())  # an ``all``'s parts may read the same published value


def length_problem(entry: Mapping, count: int | None, needs: str = "") -> tuple[str, str] | None:
    """``(key, what is wrong)`` with the first value of a typed ``entry`` (one
    :func:`entry_problem` passes) that is not a list of ``count`` values, the number its check
    measures (``needs`` says how many and why, in words), or None: a list of another length, a
    single value (which the comparison would hold every level to), a ``range`` (one interval
    for every level). Its published value counts even where only shown: one number per value
    measured. With ``count`` None the paper declares no such number, so any list the tolerance
    compares (:func:`_compared_values`) is refused: nothing says how long it must be."""
    compared = _compared_values(entry)
    if count is None:
        lists = [(key, value) for key, value in compared if isinstance(value, list)]
        if lists:
            return lists[0][0], (
                "a list, where the paper declares no levels its check measures at, so its "
                "length cannot be held to the measurement's; write one number, or declare "
                "the entry per level in the paper (PerLevel)"
            )
        return None
    for kind, spec, _, _, key in _leaves(entry["tolerance"], None, "", "tolerance"):
        if kind == "range":
            return f"{key}.range", (
                f"a single range {spec!r} where its check needs {needs}: a range holds every "
                "level to one interval; bound each level with at_least and at_most lists"
            )
    published = entry["published"]
    if "published" not in dict(compared):
        if isinstance(published, list):
            problem = _numbers_problem(published)
            if problem:
                return "published", f"{problem} (its check needs {needs})"
        compared.insert(0, ("published", published))
    for key, value in compared:
        if not isinstance(value, list):
            return key, f"a single value, {value!r}, where its check needs {needs}"
        if len(value) != count:
            values = f"{len(value)} value{'s' if len(value) != 1 else ''}"
            return key, f"{values} where its check needs {needs}"
    return None


def _numbers_problem(value: object, positive: bool = False) -> str | None:
    """What keeps ``value`` from being a real number (above zero with ``positive``) or a
    non-empty list of them, in words naming the position; None if nothing."""
    wanted = "a number > 0" if positive else "a number"
    if isinstance(value, list):
        if not value:
            return f"an empty list: give {wanted} or a list of them"
        for position, item in enumerate(value, start=1):
            if not is_number(item) or (positive and item <= 0):
                return f"position {position} holds {item!r}, not {wanted}"
        return None
    if not is_number(value) or (positive and value <= 0):
        return f"{value!r} is not {wanted}"
    return None


def _width_problem(spec: object) -> str | None:
    """What keeps the tolerance's own number(s) (``abs``, ``rel``, ``factor``, the pair of
    ``max_abs_rel``) from being finite and above zero, or None. The schema's ``minimum`` lets
    NaN through (no comparison with NaN is true), and inf or NaN would pass or fail every
    measurement whatever it is; a width of 0 asks a simulation to equal the paper's rounded
    number exactly."""
    for item in spec if isinstance(spec, list) else [spec]:
        if not is_number(item) or item <= 0:
            return f"{item!r} is not a finite number > 0 (the tolerance's width)"
    return None


def _narrow_problem(kind: str, spec: object, published: object) -> str | None:
    """What makes a width (one :func:`_width_problem` passes) of tolerance ``kind`` narrower
    than :data:`MIN_RELATIVE_WIDTH` allows, or None: a factor below ``1 + MIN_RELATIVE_WIDTH``,
    a relative width (``rel``, ``max_abs_rel``'s second) below ``MIN_RELATIVE_WIDTH``, an
    absolute one (``abs``, ``max_abs_rel``'s first) below ``MIN_RELATIVE_WIDTH`` times the
    largest magnitude of ``published`` (numbers, checked), the values it is applied to; below
    by more than rounding (:func:`_below`), so a floor written as a decimal is at it."""
    if kind == "factor":
        if not _below(spec, 1 + MIN_RELATIVE_WIDTH):
            return None
        return (
            f"{spec!r} is not >= 1 + {MIN_RELATIVE_WIDTH:g}: a factor of 1 passes only a "
            "measurement equal to the published value, a factor below 1 none"
        )
    largest = max(
        abs(value) for value in (published if isinstance(published, list) else [published])
    )
    widths = {"abs": [(spec, True)], "rel": [(spec, False)]}.get(kind)
    for width, absolute in widths or [(spec[0], True), (spec[1], False)]:
        if absolute and _below(width, MIN_RELATIVE_WIDTH * largest):
            return (
                f"{width!r} is narrower than {MIN_RELATIVE_WIDTH:g} x {largest!r}, the largest "
                f"published value it applies to: {_EXACT}"
            )
        if not absolute and _below(width, MIN_RELATIVE_WIDTH):
            return f"{width!r} is not >= {MIN_RELATIVE_WIDTH:g} (a relative width): {_EXACT}"
    return None


_EXACT = "a width that narrow passes only the published number itself, to rounding"


def _below(width: float, floor: float) -> bool:
    """Whether ``width`` falls short of ``floor`` (both > 0) by more than the rounding of
    writing one as a decimal (:data:`_ROUNDING` of it)."""
    return width < floor * (1 - _ROUNDING)


def _range_problem(spec: object) -> str | None:
    low, high = spec  # the schema gives two numbers
    if is_number(low) and is_number(high) and low < high:
        return None
    return f"{spec!r} is not two increasing finite numbers [low, high]"


def _binomial_problem(
    of_n: object, published: object, published_key: str, of_n_key: str
) -> tuple[str, str] | None:
    """The first of: a number of trials that is not an integer >= 1; a published count that is
    not an integer >= 0; counts (one, or a list) other in number than a list of ``of_n`` (one
    number of trials serves every count, one count no list of them); a count above its number
    of trials."""
    trials = of_n if isinstance(of_n, list) else [of_n]
    for n in trials:
        if not _is_integer(n) or n < 1:
            return of_n_key, f"{n!r} is not an integer >= 1 (a number of trials)"
    counts = published if isinstance(published, list) else [published]
    if not counts:
        return published_key, "an empty list: give the published count(s)"
    for count in counts:
        if not _is_integer(count) or count < 0:
            return published_key, f"{count!r} is not a count (an integer >= 0)"
    if len(trials) not in (1, len(counts)):
        given = (
            f"{len(counts)} count{'s' if len(counts) != 1 else ''}"
            if isinstance(published, list)
            else f"one count, {published!r},"
        )
        return published_key, f"{given} for {len(trials)} numbers of trials in {of_n_key}"
    for count, n in zip(counts, trials * len(counts) if len(trials) == 1 else trials, strict=True):
        if count > n:
            return published_key, f"{count} of {n} trials: more successes than trials"
    return None
