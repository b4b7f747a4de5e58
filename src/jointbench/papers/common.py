"""Pieces every paper uses: its claims table as an output, that table's headline, and the loop
its claims are measured through, with the selections by which a claim says what a run lacks."""

from __future__ import annotations

import math
import numbers
import warnings
from collections.abc import Callable, Mapping, Sequence

import numpy as np
import pandas as pd

from jointbench.comparison.published import NOT_APPLICABLE, claims_rows, status_legend
from jointbench.papers.base import Inputs, Measured, Output, Table

__all__ = [
    "NotMeasured",
    "at_levels",
    "claims_headline",
    "claims_output",
    "measured_claims",
    "one_step_changes",
    "with_columns",
]


def one_step_changes(table: pd.DataFrame) -> np.ndarray:
    """The changes from each column of ``table`` to the next (rows: lines of the grid, columns:
    one key's levels in order), flattened: only those between two cells the run measured, as a
    step to or from a cell it did not is no step of a trend. Empty when there is none (one
    level, or no line with two measured levels): a share of it would be no measurement."""
    steps = np.diff(table.to_numpy(dtype=float), axis=1).ravel()
    return steps[np.isfinite(steps)]


class NotMeasured(Exception):
    """What a claim check raises when the run lacks the data its sentence speaks of (a method,
    a level of the grid, a recorded column), saying which: the claim is then not measured in
    this run. Nothing else is: a ``KeyError``, ``IndexError``, ``ValueError`` or
    ``StopIteration`` from elsewhere in a check is its mistake (:func:`measured_claims`)."""


def with_columns(table: pd.DataFrame, names: Sequence, what: str) -> pd.DataFrame:
    """``table``'s columns ``names``, in that order; :class:`NotMeasured` naming those this run
    lacks, each a ``what`` (``"method"``, ``"protocol"``, ``"recorded column"``)."""
    missing = [name for name in names if name not in table.columns]
    if missing:
        raise NotMeasured(f"this run has no {what} {', '.join(map(str, missing))}")
    return table[list(names)]


def at_levels(data: pd.DataFrame | pd.Series, **levels: object) -> pd.DataFrame | pd.Series:
    """The rows of ``data`` (indexed by a MultiIndex) at ``levels`` (level name to value), those
    levels dropped from the index; :class:`NotMeasured` naming them when no row of this run is
    at all of them. A name that is no level of the index is a mistake: ``KeyError``."""
    at = np.ones(len(data.index), dtype=bool)
    for name, value in levels.items():
        at &= np.asarray(data.index.get_level_values(name) == value)
    if not at.any():
        shown = ", ".join(f"{name} {value}" for name, value in levels.items())
        raise NotMeasured(f"this run has no cell at {shown}")
    return data.xs(tuple(levels.values()), level=list(levels))


def _finite(value: object) -> bool:
    """Whether every number of a measured value (a number, a list, or a mapping of them) is
    finite."""
    if isinstance(value, Mapping):
        return all(_finite(part) for part in value.values())
    if isinstance(value, list | tuple):
        return all(_finite(part) for part in value)
    return not isinstance(value, numbers.Real) or math.isfinite(value)


def measured_claims(
    claims: Mapping[str, Callable[..., Measured]], *data: object
) -> dict[str, Measured]:
    """Each claim of ``claims`` (id to check) measured from ``data``, the arguments every check
    takes, by id; those this run cannot measure left out (not measured in this run): a check
    that raises :class:`NotMeasured`, or whose value is not finite (a mean or share of cells
    the run lacks). Any other exception of a check is its mistake, and so is a numpy or pandas
    ``RuntimeWarning`` (a mean of nothing, a division by zero: a selection it did not guard):
    ``RuntimeError`` naming the claim, chained to it, so the mistake is mended rather than read
    as a run without the claim's data or a number printed from it."""
    out = {}
    for key, claim in claims.items():
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", RuntimeWarning)
                measured = claim(*data)
        except NotMeasured:
            continue
        except RuntimeWarning as warning:
            raise RuntimeError(f"claim {key}: {warning}") from warning
        except Exception as error:
            # Any exception: whatever a check raises but NotMeasured is a mistake in it.
            raise RuntimeError(f"claim {key}: {type(error).__name__}: {error}") from error
        if _finite(measured.value):
            out[key] = measured
    return out


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
