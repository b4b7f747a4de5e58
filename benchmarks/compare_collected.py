"""Compare the collected results of two runs of the workflow value for value.

    python benchmarks/compare_collected.py RUN_A RUN_B [--atol 1e-12]

RUN_A and RUN_B are workflow directories (each holding ``results/collected/*.parquet``). Every
study's table must have the same rows in the same order, the same columns and dtypes, equal
non-float values, and float values equal to ``--atol`` with missing values in the same places.
Timing columns (wall-clock seconds per call) differ between any two runs and are left out.
Exits 1 and names every difference found; prints one line per study otherwise.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

# Measured durations: they depend on the machine and its load, never on the arithmetic.
TIMING_COLUMNS = frozenset({"seconds"})


def collected_tables(run: Path) -> dict[str, Path]:
    """The collected table of each study in a workflow directory, by study name."""
    folder = run / "results" / "collected"
    tables = {path.stem: path for path in sorted(folder.glob("*.parquet"))}
    if not tables:
        raise FileNotFoundError(f"no collected results in {folder}")
    return tables


def _float_difference(a: pd.Series, b: pd.Series, atol: float) -> str | None:
    """Why two float columns differ beyond ``atol``, or None when they agree."""
    x = a.to_numpy(dtype=float)
    y = b.to_numpy(dtype=float)
    missing_x, missing_y = np.isnan(x), np.isnan(y)
    if not np.array_equal(missing_x, missing_y):
        return f"missing values in different rows ({missing_x.sum()} vs {missing_y.sum()})"
    both = ~missing_x
    gap = np.abs(x[both] - y[both])
    if gap.size and gap.max() > atol:
        row = int(np.flatnonzero(both)[np.argmax(gap)])
        return f"{int((gap > atol).sum())} values differ, largest {gap.max():.3g} in row {row}"
    return None


def _same_value(u: object, v: object) -> bool:
    """Equal, or both missing (None and NaN alike: parquet may store either)."""
    if pd.isna(u) or pd.isna(v):
        return bool(pd.isna(u) and pd.isna(v))
    return bool(u == v)


def _value_difference(a: pd.Series, b: pd.Series) -> str | None:
    """Why two non-float columns differ, or None when every value is equal."""
    x = a.astype(object).to_numpy()
    y = b.astype(object).to_numpy()
    same = np.array([_same_value(u, v) for u, v in zip(x, y, strict=True)], dtype=bool)
    if not same.all():
        row = int(np.flatnonzero(~same)[0])
        return f"{int((~same).sum())} values differ, first in row {row}: {x[row]!r} vs {y[row]!r}"
    return None


def compare_frames(a: pd.DataFrame, b: pd.DataFrame, atol: float = 1e-12) -> list[str]:
    """Every difference between two collected tables, timing columns aside (empty: equal)."""
    if list(a.columns) != list(b.columns):
        return [f"columns differ: {list(a.columns)} vs {list(b.columns)}"]
    if len(a) != len(b):
        return [f"{len(a)} rows vs {len(b)} rows"]
    problems = []
    for column in a.columns:
        if column in TIMING_COLUMNS:
            continue
        if a[column].dtype != b[column].dtype:
            problems.append(f"{column}: dtype {a[column].dtype} vs {b[column].dtype}")
            continue
        if pd.api.types.is_float_dtype(a[column]):
            why = _float_difference(a[column], b[column], atol)
        else:
            why = _value_difference(a[column], b[column])
        if why:
            problems.append(f"{column}: {why}")
    return problems


def compare_runs(run_a: Path, run_b: Path, atol: float = 1e-12) -> dict[str, list[str]]:
    """The differences of each study's collected table between two workflow directories."""
    tables_a, tables_b = collected_tables(run_a), collected_tables(run_b)
    if set(tables_a) != set(tables_b):
        return {"(studies)": [f"{sorted(tables_a)} vs {sorted(tables_b)}"]}
    return {
        study: compare_frames(
            pd.read_parquet(tables_a[study]), pd.read_parquet(tables_b[study]), atol
        )
        for study in tables_a
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run_a", type=Path)
    parser.add_argument("run_b", type=Path)
    parser.add_argument("--atol", type=float, default=1e-12, help="float tolerance (default 1e-12)")
    arguments = parser.parse_args(argv)
    differences = compare_runs(arguments.run_a, arguments.run_b, arguments.atol)
    for study, problems in differences.items():
        if problems:
            print(f"{study}: DIFFERENT", file=sys.stderr)
            for problem in problems:
                print(f"  {problem}", file=sys.stderr)
        else:
            rows = len(pd.read_parquet(collected_tables(arguments.run_a)[study]))
            print(f"{study}: {rows} rows equal (floats to {arguments.atol:g}, timing aside)")
    return 1 if any(differences.values()) else 0


if __name__ == "__main__":
    sys.exit(main())
