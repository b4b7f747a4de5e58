"""Regression guard: a committed snapshot of the tabulated means, and the README summary.

The pipeline is deterministic (seeded per trial), so the per-condition mean and median errors of
every estimator over its converged trials, and how many converged, are fixed numbers.
``tests/snapshots/summary.csv`` holds them; a change in any of them beyond round-off fails the
tests. A trial whose iteration did not converge is left out of the snapshot's means: where an
iteration oscillates without settling, the iterate it stops at amplifies round-off, so it
differs between BLAS builds and processors by far more than round-off. After an intended
change, regenerate it with ``jointbench snapshot`` (after ``snakemake -j2``) and commit it.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np
import pandas as pd

from jointbench.comparison.published import NOT_APPLICABLE, STATUSES
from jointbench.configuration.studies import get_study
from jointbench.running.scoring import ERROR_COLUMN
from jointbench.running.summary import summarise

__all__ = [
    "SNAPSHOT_RTOL",
    "compare_snapshot",
    "reproduction_counts",
    "reproduction_summary",
    "snapshot_table",
    "update_readme",
]

# Relative tolerance on snapshot means and medians. Seeds fix every random number, so the only
# differences left are floating-point round-off (BLAS, SIMD paths), orders of magnitude below
# this; any real change of an estimator or a simulation moves some mean by far more.
SNAPSHOT_RTOL = 1e-6
SNAPSHOT_ATOL = 1e-9
#: The README's generated blocks, each between ``<!-- NAME:start -->`` and ``<!-- NAME:end -->``:
#: the reproduction summary, and the verdicts over seeds in "What stands out" (that section's
#: bullets: :data:`jointbench.comparison.readme_standout.STANDOUT_BLOCK`).
SUMMARY_BLOCK = "reproduction-summary"
VERDICTS_BLOCK = "verdicts-summary"


def _markers(block: str) -> tuple[str, str]:
    return f"<!-- {block}:start -->", f"<!-- {block}:end -->"


def _block_span(text: str, block: str, readme) -> tuple[int, int]:
    """Where the text between ``block``'s markers starts and ends in ``text``."""
    start, end = _markers(block)
    if start not in text or end not in text:
        raise ValueError(f"{readme}: no {start} … {end} block")
    return text.index(start) + len(start), text.index(end)


def snapshot_table(collected_dir: str | Path, studies: Iterable[str]) -> pd.DataFrame:
    """Mean and median error over the converged trials, and the converged count, per study,
    condition and method, in long form, of the collected results of ``studies`` (a run's,
    :func:`jointbench.configuration.config.study_names`), in the order of their names. A file
    in ``collected_dir`` of another study was left by another run and is no result of this
    one's; a study of the run without its file is a ``ValueError`` naming the file.

    Columns: study, condition, method, statistic, value.
    """
    paths = {study: Path(collected_dir) / f"{study}.parquet" for study in sorted(studies)}
    missing = [str(path) for path in paths.values() if not path.is_file()]
    if missing:
        raise ValueError(
            f"{', '.join(missing)}: no such file; the run has not collected "
            f"{'these studies' if len(missing) > 1 else 'this study'}: run `snakemake -j2` "
            "with the same --configfile first"
        )
    rows = []
    for study, path in paths.items():
        collected = pd.read_parquet(path)
        error = ERROR_COLUMN[get_study(study).kind]
        collected[error] = collected[error].where(collected["converged"].astype(bool))
        summary = summarise(collected, study)
        error_columns = [c for c in summary.columns if c.startswith(("mean_error", "median_error"))]
        keys = [
            c
            for c in summary.columns
            if c not in {*error_columns, "trials", "converged", "failed", "mean_seconds", "method"}
        ]
        for row in summary.itertuples(index=False):
            record = row._asdict()
            condition = "__".join(f"{k}-{record[k]}" for k in keys)
            for column in [*error_columns, "converged"]:
                rows.append(
                    {
                        "study": study,
                        "condition": condition,
                        "method": record["method"],
                        "statistic": column if column == "converged" else f"{column}_converged",
                        "value": float(record[column]),
                    }
                )
    return pd.DataFrame(rows, columns=["study", "condition", "method", "statistic", "value"])


def compare_snapshot(current: pd.DataFrame, snapshot: pd.DataFrame) -> list[str]:
    """Human-readable differences between two snapshot tables (empty when they agree)."""
    keys = ["study", "condition", "method", "statistic"]
    merged = snapshot.merge(
        current, on=keys, how="outer", suffixes=("_snapshot", "_now"), indicator="where"
    )
    problems = []
    for row in merged.itertuples(index=False):
        name = f"{row.study} {row.method} {row.condition} {row.statistic}"
        if row.where == "left_only":
            problems.append(f"{name}: in the snapshot but not in the results")
        elif row.where == "right_only":
            problems.append(f"{name}: in the results but not in the snapshot")
        elif not np.isclose(
            row.value_now,
            row.value_snapshot,
            rtol=SNAPSHOT_RTOL,
            atol=SNAPSHOT_ATOL,
            equal_nan=True,
        ):
            problems.append(
                f"{name}: {row.value_snapshot:.6g} in the snapshot, now {row.value_now:.6g}"
            )
    return problems


#: A count cell of :func:`reproduction_counts` with nothing tested.
NONE_TESTED = "none tested"


def _reproduced_of_tested(rows: pd.DataFrame) -> str:
    """``"6 / 11"``: reproduced of those with a verdict, or :data:`NONE_TESTED`."""
    tested = rows[rows["status"] != NOT_APPLICABLE]
    if tested.empty:
        return NONE_TESTED
    return f"{int((tested['status'] == 'reproduced').sum())} / {len(tested)}"


def reproduction_counts(comparison: pd.DataFrame, titles: Mapping[str, str]) -> pd.DataFrame:
    """Per paper: values and claims reproduced out of those with a verdict, and how many rows
    are :data:`~jointbench.comparison.published.NOT_APPLICABLE`. ``titles`` maps each paper's letter
    to the label shown."""
    rows = []
    for paper, part in comparison.groupby("paper", sort=True):
        rows.append(
            {
                "paper": titles.get(paper, paper),
                "published values reproduced": _reproduced_of_tested(
                    part[part["entry"] == "value"]
                ),
                "claims reproduced": _reproduced_of_tested(part[part["entry"] == "claim"]),
                NOT_APPLICABLE: str(int((part["status"] == NOT_APPLICABLE).sum())),
            }
        )
    return pd.DataFrame(rows)


def reproduction_summary(comparison: pd.DataFrame, titles: Mapping[str, str]) -> str:
    """The README's opening table (:func:`reproduction_counts` as Markdown)."""
    counts = reproduction_counts(comparison, titles)
    lines = ["| " + " | ".join(counts.columns) + " |", "|---|---|---|---|"]
    lines += ["| " + " | ".join(row) + " |" for row in counts.astype(str).values.tolist()]
    cells = counts[["published values reproduced", "claims reproduced"]].to_numpy().ravel()
    example = next((f" such as {c}" for c in cells if c != NONE_TESTED), "")
    return (
        "**Reproduction summary** (generated from `results/tables/published_comparison.csv`; "
        f"every deviation has its reason there). A cell{example} counts the values or "
        "claims reproduced (within their tolerance) of those given a verdict; "
        f"*{NOT_APPLICABLE}*: {STATUSES[NOT_APPLICABLE]}.\n\n" + "\n".join(lines)
    )


def update_readme(readme: str | Path, summary: str, block: str = SUMMARY_BLOCK) -> bool:
    """Replace the README's generated ``block`` with ``summary``; return whether the file
    changed."""
    path = Path(readme)
    text = path.read_text()
    start, end = _block_span(text, block, readme)
    new = text[:start] + "\n" + summary.strip() + "\n" + text[end:]
    if new != text:
        path.write_text(new)
    return new != text


def readme_blocks(readme: str | Path) -> list[str]:
    """The names of the generated blocks in the README, in order."""
    return re.findall(r"<!-- (\S+):start -->", Path(readme).read_text())


def readme_summary(readme: str | Path, block: str = SUMMARY_BLOCK) -> str:
    """The generated ``block`` currently in the README."""
    text = Path(readme).read_text()
    start, end = _block_span(text, block, readme)
    return text[start:end].strip()
