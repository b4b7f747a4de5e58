"""Gather a study's estimates files into its collected results, and one estimator's summary."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import pandas as pd

from jointbench.study.io import (
    read_metadata,
    read_provenance,
    read_table,
    read_trial_numbers,
    write_table,
)
from jointbench.study.schema import check_against_dataset, check_estimates
from jointbench.study.studies import get_study
from jointbench.study.summary import summarise

__all__ = ["collect", "summarise_estimates"]


def collect(
    study: str,
    paths: Sequence[str | Path],
    output: str,
    datasets: Sequence[str | Path],
    provenance: Mapping[str, object] | None = None,
) -> pd.DataFrame:
    """Concatenate a study's estimates files after checking each one's schema and holding it to
    the dataset file of its condition (same trials, each once, same condition values).

    The collected file's provenance adds, per estimator, the provenance of its estimates files
    (an external estimator's files have none)."""
    spec = get_study(study)
    # Each dataset is read once, whatever the number of estimators.
    expected = {
        Path(path).stem: {
            "trials": read_trial_numbers(path),
            "condition": read_metadata(path)["condition"],
        }
        for path in datasets
    }
    frames = []
    estimators: dict[str, dict] = {}
    for path in paths:
        frame = read_table(path)
        method = Path(path).parent.name
        estimators.setdefault(method, read_provenance(path))
        check_estimates(
            frame, kind=spec.kind, condition_keys=spec.grid_keys, method=method, source=str(path)
        )
        if Path(path).stem not in expected:
            raise ValueError(f"{path}: no dataset file of condition {Path(path).stem!r}")
        check_against_dataset(frame, **expected[Path(path).stem], source=str(path))
        frames.append(frame)
    collected = pd.concat(frames, ignore_index=True)
    collected = collected.sort_values([*spec.grid_keys, "method", "trial"], kind="stable")
    write_table(collected, output, {**(provenance or {}), "estimators": estimators})
    return collected


def summarise_estimates(study: str, paths: Sequence[str], output: str) -> None:
    """One estimator's mean and median error per condition, from its estimates files."""
    estimates = pd.concat([read_table(path) for path in paths], ignore_index=True)
    summarise(estimates, study).to_csv(output, index=False)
