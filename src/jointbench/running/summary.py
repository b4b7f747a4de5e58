"""Per-condition summaries of estimates: the numbers behind rankings and regression snapshots."""

from __future__ import annotations

from collections.abc import Sequence

import pandas as pd

from jointbench.configuration.studies import get_study
from jointbench.running.scoring import ERROR_COLUMN

__all__ = ["ERROR_COLUMN", "summarise"]


def summarise(estimates: pd.DataFrame, study: str, by: Sequence[str] = ()) -> pd.DataFrame:
    """Mean and median error, trial and convergence counts and mean seconds per condition and
    method.

    Errors of failed trials (NaN) are left out of the mean and median and counted in
    ``failed``. ``by`` adds grouping columns after the study's condition keys.
    """
    spec = get_study(study)
    error = ERROR_COLUMN[spec.kind]
    keys = [*spec.grid_keys, *by, "method"]
    grouped = estimates.groupby(keys, observed=True, sort=True)
    summary = grouped.agg(
        trials=("trial", "size"),
        converged=("converged", "sum"),
        failed=(error, lambda e: int(e.isna().sum())),
        mean_error=(error, "mean"),
        median_error=(error, "median"),
        mean_seconds=("seconds", "mean"),
    ).reset_index()
    summary["converged"] = summary["converged"].astype(int)
    unit = error.removeprefix("error_")
    return summary.rename(
        columns={"mean_error": f"mean_error_{unit}", "median_error": f"median_error_{unit}"}
    )
