"""Pieces every paper uses: its claims table as an output, that table's headline, and the loop
its claims are measured through, with the selections by which a claim says what a run lacks and
what the paper declares a run may hold, which tells a run's lack from a check's mistake."""

from __future__ import annotations

import math
import numbers
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from jointbench.comparison.published import (
    NOT_APPLICABLE,
    Measurements,
    claims_rows,
    status_legend,
)
from jointbench.configuration.studies import get_study
from jointbench.papers.base import Inputs, Measured, Output, Paper, Table
from jointbench.resultfiles.schema import recorded_columns

__all__ = [
    "RECORDED_COLUMN",
    "Declared",
    "NotMeasured",
    "at_levels",
    "claims_headline",
    "claims_output",
    "measured_claims",
    "none_measured",
    "one_step_changes",
    "require_declared",
    "rows_at",
    "with_columns",
]


def one_step_changes(table: pd.DataFrame) -> np.ndarray:
    """The changes from each column of ``table`` to the next (rows: lines of the grid, columns:
    one key's levels in order), flattened: only those between two cells the run measured, as a
    step to or from a cell it did not is no step of a trend. Empty when there is none (one
    level, or no line with two measured levels): a share of it would be no measurement."""
    steps = np.diff(table.to_numpy(dtype=float), axis=1).ravel()
    return steps[np.isfinite(steps)]


#: The key of a selection of recorded columns, held to the columns the paper's study records
#: (:func:`~jointbench.resultfiles.schema.recorded_columns`).
RECORDED_COLUMN = "recorded column"


class NotMeasured(Exception):
    """What a claim check raises when the run lacks the data its sentence speaks of (a method,
    a level of the grid, a recorded column), saying which: the claim is then not measured in
    this run, for that reason. Nothing else is: a ``KeyError``, ``IndexError``, ``ValueError``
    or ``StopIteration`` from elsewhere in a check is its mistake (:func:`measured_claims`).

    ``lacks`` maps each key the check asked the run by (``"method"``, a grid key,
    :data:`RECORDED_COLUMN`) to the values it named and did not get: those a selection found
    the run without (:func:`with_columns`), or every value of a selection by several keys that
    found nothing (:func:`at_levels`, :func:`rows_at`); a check that words its lack itself
    passes the names it selected by, spelt where it selects by them, or ``{}`` where what it
    lacks has no name (two levels on one line of the grid). Only names the check spells go
    there, never values read from the run, whose grid may hold levels no paper declares.
    :func:`measured_claims` holds them to what the paper declares (:class:`Declared`), so a
    misspelt name is the check's mistake, not the run's lack.
    """

    def __init__(self, reason: str, lacks: Mapping[str, tuple] | None = None) -> None:
        super().__init__(reason)
        self.lacks = dict(lacks or {})


def with_columns(
    table: pd.DataFrame, names: Sequence, key: str, what: str | None = None
) -> pd.DataFrame:
    """``table``'s columns ``names``, in that order, each a value of ``key`` (``"method"``, a
    grid key such as ``"protocol"``, or :data:`RECORDED_COLUMN`); :class:`NotMeasured` naming
    those this run lacks, each a ``what`` (``key`` unless given: "method with fitted radii")."""
    missing = tuple(name for name in names if name not in table.columns)
    if missing:
        raise NotMeasured(
            f"this run has no {what or key} {', '.join(map(str, missing))}", {key: missing}
        )
    return table[list(names)]


def rows_at(table: pd.DataFrame, reason: str | None = None, /, **values: object) -> pd.DataFrame:
    """The rows of ``table`` (one row per result, the keys as columns) whose columns equal
    ``values`` (column name to value: a method, a level the claim's sentence names);
    :class:`NotMeasured` for ``reason`` (by default naming them) when no row of this run is
    at all of them. A name that is no column is a mistake: ``KeyError``."""
    shown = _shown(values)
    default = (
        f"this run has no {shown}" if len(values) == 1 else f"this run has no result at {shown}"
    )
    return table[_at(table.__getitem__, len(table), values, reason or default)]


def at_levels(data: pd.DataFrame | pd.Series, **levels: object) -> pd.DataFrame | pd.Series:
    """The rows of ``data`` (indexed by a MultiIndex) at ``levels`` (level name to value), those
    levels dropped from the index; :class:`NotMeasured` naming them when no row of this run is
    at all of them. A name that is no level of the index is a mistake: ``KeyError``."""
    reason = f"this run has no cell at {_shown(levels)}"
    _at(data.index.get_level_values, len(data.index), levels, reason)
    return data.xs(tuple(levels.values()), level=list(levels))


def _shown(selection: Mapping[str, object]) -> str:
    """A selection in words: ``marker_set M, rom_deg 15``."""
    return ", ".join(f"{name} {value}" for name, value in selection.items())


def _at(
    values_of: Callable[[str], object], size: int, selection: Mapping[str, object], reason: str
) -> np.ndarray:
    """``(size,)``: where every key of ``selection`` has its value (``values_of(key)``, the
    ``size`` rows' values of that key); :class:`NotMeasured` for ``reason``, lacking every value
    of ``selection``, where no row has all of them."""
    at = np.ones(size, dtype=bool)
    for name, value in selection.items():
        at &= np.asarray(values_of(name) == value)
    if not at.any():
        raise NotMeasured(reason, {name: (value,) for name, value in selection.items()})
    return at


@dataclass(frozen=True)
class Declared:
    """What a run of ``paper`` may hold for its claims to ask for, by key: ``"method"`` the
    paper's methods and those it also measures (:attr:`~jointbench.papers.base.Paper.methods`,
    :attr:`~jointbench.papers.base.Paper.also_measures`), each key of its design grid
    (``design.grid`` of ``published``, its published values) the levels listed there,
    :data:`RECORDED_COLUMN` the columns its study records
    (:func:`~jointbench.resultfiles.schema.recorded_columns`). Read only when a check finds the
    run without something."""

    paper: Paper
    published: Mapping

    def values(self) -> dict[str, tuple]:
        """The declared values by key."""
        grid = {key: tuple(levels) for key, levels in self.published["design"]["grid"].items()}
        return {
            **grid,
            "method": (*self.paper.methods, *self.paper.also_measures),
            RECORDED_COLUMN: recorded_columns(get_study(self.paper.study)),
        }


#: How :func:`_undeclared` names the declared values of a key that is no grid key.
_DECLARED_AS = {"method": "the paper's methods", RECORDED_COLUMN: "the columns its study records"}


def _is_one_of(value: object, declared: Sequence) -> bool:
    # bool is an int to Python but never a method or a level: True is no 1.
    return not isinstance(value, bool) and any(value == level for level in declared)


def _undeclared(lacks: Mapping[str, tuple], declared: Mapping[str, Sequence]) -> list[str]:
    """The parts of a selection's ``lacks`` (:attr:`NotMeasured.lacks`) that no run could hold,
    given the ``declared`` values by key (:meth:`Declared.values`), in words: a key none of
    them is, a value none of its key's is (misspelt, of another type, a level the design grid
    does not list, a column the study does not record)."""
    wrong = []
    for key, values in lacks.items():
        if key not in declared:
            keys = ", ".join(declared) or "none given"
            wrong.append(f"{key}, no key the paper declares ({keys})")
            continue
        what = _DECLARED_AS.get(key, f"the paper's {key} levels")
        shown = ", ".join(map(repr, declared[key]))
        wrong += [
            f"{key} {value!r}, none of {what} ({shown})"
            for value in values
            if not _is_one_of(value, declared[key])
        ]
    return wrong


def _finite(value: object) -> bool:
    """Whether every number of a measured value (a number, a list, or a mapping of them) is
    finite."""
    if isinstance(value, Mapping):
        return all(_finite(part) for part in value.values())
    if isinstance(value, list | tuple):
        return all(_finite(part) for part in value)
    return not isinstance(value, numbers.Real) or math.isfinite(value)


def measured_claims(
    claims: Mapping[str, Callable[..., Measured]],
    *data: object,
    declared: Declared | None = None,
) -> Measurements:
    """Each claim of ``claims`` (id to check) measured from ``data``, the arguments every check
    takes, by id; those this run cannot measure left out (not measured in this run), with why
    (:attr:`~jointbench.comparison.published.Measurements.not_measured`): a check that raises
    :class:`NotMeasured` (its reason), or whose value is not finite (a mean or share of cells
    the run lacks).

    A selection's lack is the run's only where ``declared`` (the paper's :class:`Declared`;
    without it, nothing) holds what it asked for: a method, level or recorded column no run of
    the paper could hold is a misspelt or mistyped one (:func:`_undeclared`). That, any other
    exception of a check, and a numpy or pandas ``RuntimeWarning`` (a mean of nothing, a
    division by zero: a selection it did not guard) are mistakes of the check: ``RuntimeError``
    naming the claim, chained to it, so the mistake is mended rather than read as a run without
    the claim's data or a number printed from it."""
    out, not_measured = {}, {}
    for key, claim in claims.items():
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", RuntimeWarning)
                measured = claim(*data)
        except NotMeasured as lack:
            require_declared(f"claim {key}", lack, declared)
            not_measured[key] = str(lack)
            continue
        except RuntimeWarning as warning:
            raise RuntimeError(f"claim {key}: {warning}") from warning
        except Exception as error:
            # Any exception: whatever a check raises but NotMeasured is a mistake in it.
            raise RuntimeError(f"claim {key}: {type(error).__name__}: {error}") from error
        if _finite(measured.value):
            out[key] = measured
        else:
            not_measured[key] = "its value is not finite (a mean or share of cells it lacks)"
    return Measurements(out, not_measured)


def require_declared(label: str, lack: NotMeasured, declared: Declared | None) -> None:
    """``RuntimeError`` starting with ``label`` (``"claim A5"``) and naming what of ``lack`` no
    run could hold, chained to it; nothing when the run's lack is one the paper declares."""
    if not lack.lacks:
        return
    wrong = _undeclared(lack.lacks, {} if declared is None else declared.values())
    if wrong:
        raise RuntimeError(
            f"{label}: asks for {'; '.join(wrong)}: a mistake of the check, not a run "
            f"without it ({lack})"
        ) from lack


def none_measured(
    claims: Mapping[str, Callable[..., Measured]], lack: NotMeasured, declared: Declared | None
) -> Measurements:
    """Every claim of ``claims`` not measured for one ``lack`` they share (the run lacks the
    method all of them read), held to ``declared`` as a lack a claim raises is
    (:func:`require_declared`)."""
    for key in claims:
        require_declared(f"claim {key}", lack, declared)
    return Measurements({}, dict.fromkeys(claims, str(lack)))


def claims_headline(tables: Mapping) -> str:
    """How many of a paper's tested claims reproduced, from its claims table."""
    (table,) = tables.values()
    tested = table[table["status"] != NOT_APPLICABLE]
    return (
        f"{int((tested['status'] == 'reproduced').sum())} of {len(tested)} claims "
        "reproduced (criteria and reasons in the claims table)."
    )


def claims_output(
    key: str, measure: Callable[[Inputs], Mapping[str, Measured]], caption: str
) -> Output:
    """The ``<key>_claims`` table: every claim of the paper recomputed from our results."""

    def render(inputs: Inputs) -> Table:
        return Table(
            claims_rows(inputs.published, measure(inputs)),
            title=f"Paper {inputs.published['paper']} claims, recomputed from our results",
            note=f"{status_legend()}. Margin: how far inside or outside its criterion the "
            "reproduced value lies.",
        )

    return Output(
        f"{key}_claims",
        "table",
        render,
        caption=caption,
        summarises=(f"{key}_claims",),
        headline=claims_headline,
    )
