"""Pieces every paper uses: its claims table as an output, and wording of timing ratios."""

from __future__ import annotations

from collections.abc import Callable, Mapping

from jointbench.papers.base import Inputs, Measured, Output, Table
from jointbench.study.published import claims_rows

__all__ = ["claims_headline", "claims_output", "timing_text"]


def timing_text(ours_s: float, paper_s: float, *, short: bool = False) -> str:
    """Our time beside the paper's, worded by the ratio's direction.

    ``paper_s / ours_s`` above one means we are faster, below one slower: "0.00165 s (2.2×
    slower)". ``short`` gives only the ratio part ("2.2× slower").
    """
    ratio = paper_s / ours_s if ours_s > 0 else float("nan")
    if ratio != ratio:  # NaN: no time measured
        comparison = "no time measured"
    elif ratio >= 1:
        comparison = f"{ratio:.2g}× faster" if ratio < 10 else f"{ratio:.0f}× faster"
    else:
        inverse = 1 / ratio
        comparison = f"{inverse:.2g}× slower" if inverse < 10 else f"{inverse:.0f}× slower"
    return comparison if short else f"{ours_s:.3g} s ({comparison})"


def claims_headline(tables: Mapping) -> str:
    """How many of a paper's tested claims reproduced, from its claims table."""
    (table,) = tables.values()
    tested = table[table["status"] != "not applicable"]
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
        )

    return Output(
        f"{key}_claims",
        "table",
        render,
        caption=caption,
        summarises=(f"{key}_claims",),
        headline=claims_headline,
    )
