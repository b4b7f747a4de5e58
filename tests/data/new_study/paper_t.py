"""Paper T: the toy study's paper (the recipe's test): one table and one claim."""

from __future__ import annotations

from pathlib import Path

from jointbench.papers.base import Inputs, Measured, Output, Paper, Table

__all__ = ["PAPER"]


def measure(inputs: Inputs) -> dict[str, Measured]:
    """T1: the mean NM error at 0.5 mm noise [mm]."""
    means = inputs.collected.groupby(["method", "noise_mm"])["error_mm"].mean()
    nm = float(means[("NM", 0.5)])
    return {"T1": Measured(nm, f"{nm:.2f} mm")}


def _errors(inputs: Inputs) -> Table:
    means = inputs.collected.groupby(["noise_mm", "method"])["error_mm"].mean()
    return Table(means.unstack("method").reset_index(), title="mean centre error (mm)")


PAPER = Paper(
    key="paper_t",
    letter="T",
    title="Paper T: a toy study",
    citation="Toy (2026), the recipe's study",
    study="toy",
    methods=("NM", "LS"),
    published=Path(__file__).with_name("paper_t.yaml"),
    measure=measure,
    outputs=(Output("paper_t_errors", "table", _errors, caption="Mean error per noise level."),),
)
