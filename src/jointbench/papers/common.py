"""Pieces every paper uses: its claims table as an output, and that table's headline."""

from __future__ import annotations

import math
import numbers
import warnings
from collections.abc import Callable, Mapping

import numpy as np
import pandas as pd

from jointbench.comparison.published import NOT_APPLICABLE, claims_rows, status_legend
from jointbench.papers.base import Inputs, Measured, Output, Table

__all__ = ["claims_headline", "claims_output", "measured_claims", "one_step_changes"]


def one_step_changes(table: pd.DataFrame) -> np.ndarray:
    """The changes from each column of ``table`` to the next (rows: lines of the grid, columns:
    one key's levels in order), flattened: only those between two cells the run measured, as a
    step to or from a cell it did not is no step of a trend. Empty when there is none (one
    level, or no line with two measured levels): a share of it would be no measurement."""
    steps = np.diff(table.to_numpy(dtype=float), axis=1).ravel()
    return steps[np.isfinite(steps)]


#: What a claim check raises when the run lacks the data its sentence speaks of (a method, a
#: level of the grid, a recorded column): the claim is then not measured in this run.
NOT_IN_THIS_RUN = (KeyError, IndexError, ValueError, StopIteration)


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
    that raises one of :data:`NOT_IN_THIS_RUN`, or whose value is not finite (a mean or share
    of cells the run lacks). A numpy or pandas ``RuntimeWarning`` (a mean of nothing, a
    division by zero) is a check that did not guard its selection: ``RuntimeError`` naming the
    claim, so the mistake is mended rather than a number printed from it."""
    out = {}
    for key, claim in claims.items():
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("error", RuntimeWarning)
                measured = claim(*data)
        except NOT_IN_THIS_RUN:
            continue
        except RuntimeWarning as warning:
            raise RuntimeError(f"claim {key}: {warning}") from warning
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
