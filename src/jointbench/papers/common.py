"""Pieces every paper uses: its claims table as an output, and that table's headline."""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
import pandas as pd

from jointbench.comparison.published import NOT_APPLICABLE, claims_rows, status_legend
from jointbench.papers.base import Inputs, Measured, Output, Table

__all__ = ["claims_headline", "claims_output", "one_step_changes"]


def one_step_changes(table: pd.DataFrame) -> np.ndarray:
    """The changes from each column of ``table`` to the next (rows: lines of the grid, columns:
    one key's levels in order), flattened: only those between two cells the run measured, as a
    step to or from a cell it did not is no step of a trend. Empty when there is none (one
    level, or no line with two measured levels): a share of it would be no measurement."""
    steps = np.diff(table.to_numpy(dtype=float), axis=1).ravel()
    return steps[np.isfinite(steps)]


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
