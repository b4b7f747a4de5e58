"""The columns every estimates file must carry, by estimator kind.

A user's estimator (built-in or a rule in any language) writes one parquet file per study
condition with one row per trial. :func:`check_estimates` is run on every such file before it
is collected, so a wrong or missing column fails with its name rather than as a broken figure;
:func:`check_against_dataset` then holds it to its dataset, so that a missing, repeated or
invented trial or condition cannot change a ranking unnoticed.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "COMMON_COLUMNS",
    "KIND_COLUMNS",
    "check_against_dataset",
    "check_estimates",
    "required_columns",
]

# column -> predicate on the column's Arrow type, and what the predicate means for the message.
# Booleans count as numbers, as in NumPy; a column of nothing but missing values as text.
_NUMBER = (
    lambda t: pa.types.is_integer(t) or pa.types.is_floating(t) or pa.types.is_boolean(t),
    "numeric",
)
_INTEGER = (pa.types.is_integer, "integer")
_BOOL = (pa.types.is_boolean, "boolean")
_TEXT = (
    lambda t: pa.types.is_string(t) or pa.types.is_large_string(t) or pa.types.is_null(t),
    "text",
)

COMMON_COLUMNS = {
    "trial": _INTEGER,
    "method": _TEXT,
    "converged": _BOOL,
    "iterations": _INTEGER,
    "seconds": _NUMBER,
    "status": _TEXT,
}
KIND_COLUMNS = {
    "center": {"center_x": _NUMBER, "center_y": _NUMBER, "center_z": _NUMBER, "error_mm": _NUMBER},
    "axis": {
        "point_x": _NUMBER,
        "point_y": _NUMBER,
        "point_z": _NUMBER,
        "direction_x": _NUMBER,
        "direction_y": _NUMBER,
        "direction_z": _NUMBER,
        "error_deg": _NUMBER,
    },
    "joint_center": {
        "center_x": _NUMBER,
        "center_y": _NUMBER,
        "center_z": _NUMBER,
        "error_mm": _NUMBER,
        "sqrt_trace_cov_mm": _NUMBER,
        "mahalanobis_sq": _NUMBER,
        "validation_index": _NUMBER,
    },
}


def required_columns(kind: str, condition_keys: Sequence[str]) -> dict[str, tuple]:
    """Column name -> (Arrow type predicate, description) for an estimates file of ``kind``."""
    if kind not in KIND_COLUMNS:
        raise ValueError(f"unknown estimator kind {kind!r}")
    return {
        **dict.fromkeys(condition_keys, (lambda d: True, "any")),
        **COMMON_COLUMNS,
        **KIND_COLUMNS[kind],
    }


def check_estimates(
    table: pa.Table | pd.DataFrame,
    *,
    kind: str,
    condition_keys: Sequence[str],
    method: str | None = None,
    source: str = "estimates",
) -> None:
    """Raise ``ValueError`` naming the first missing or mistyped column of an estimates table.

    ``table`` is an Arrow table or a pandas data frame; a column's type is its Arrow type (a
    frame's columns are converted as parquet would store them).
    """
    names = table.column_names if isinstance(table, pa.Table) else list(table.columns)
    columns = {}
    for column, (accepts, description) in required_columns(kind, condition_keys).items():
        if column not in names:
            raise ValueError(f"{source}: missing column {column!r} (needed for {kind} estimates)")
        columns[column] = _arrow_column(table, column, source)
        if not accepts(columns[column].type):
            raise ValueError(
                f"{source}: column {column!r} must be {description}, got {columns[column].type}"
            )
    if columns["trial"].null_count:
        raise ValueError(f"{source}: column 'trial' has missing values")
    if method is not None and len(table):
        found = set(columns["method"].to_pylist())
        if found != {method}:
            listed = sorted(map(str, found))
            raise ValueError(
                f"{source}: column 'method' must be {method!r} in every row, got {listed}"
            )


def _arrow_column(table, column: str, source: str) -> pa.Array | pa.ChunkedArray:
    """One column of an Arrow table or pandas frame as Arrow values."""
    if isinstance(table, pa.Table):
        return table.column(column)
    try:
        return pa.array(table[column])
    except (pa.ArrowInvalid, pa.ArrowTypeError) as error:
        raise ValueError(f"{source}: column {column!r} mixes types: {error}") from None
    except pa.ArrowException as error:
        raise ValueError(f"{source}: column {column!r} cannot be stored: {error}") from None


def check_against_dataset(
    table: pa.Table | pd.DataFrame,
    *,
    trials: Iterable[int],
    condition: Mapping[str, object],
    source: str = "estimates",
) -> None:
    """Raise ``ValueError`` naming ``source`` unless ``table`` (checked by
    :func:`check_estimates`) has one row per trial of its dataset, no other trial, and the
    dataset's ``condition`` values in every row."""
    expected = sorted(set(map(int, trials)))
    described = f"the dataset has {len(expected)} trials ({_listed(expected)})"
    if not len(table):
        raise ValueError(f"{source}: no rows; {described}")
    found, counts = np.unique(np.asarray(table["trial"], dtype=np.int64), return_counts=True)
    found_set = set(found.tolist())
    problems = {
        "missing trials": sorted(set(expected) - found_set),
        "trials not in the dataset": sorted(found_set - set(expected)),
        "trials listed more than once": found[counts > 1].tolist(),
    }
    found_problems = [
        f"{problem}: {_listed(numbers)}" for problem, numbers in problems.items() if numbers
    ]
    if found_problems:
        raise ValueError(f"{source}: {'; '.join(found_problems)}; {described}")
    for key, value in condition.items():
        column = table[key]
        values = column.to_pylist() if isinstance(column, pa.ChunkedArray) else column.tolist()
        wrong = sorted({str(v) for v in values if not _same_value(v, value)})
        if wrong:
            raise ValueError(
                f"{source}: column {key!r} must be the dataset's {value!r} in every row, "
                f"got {', '.join(wrong)}"
            )


def _same_value(found: object, expected: object) -> bool:
    # 5 and 5.0 are one grid value; "5" is not; a missing value is none.
    if isinstance(expected, str) or isinstance(found, str):
        return found == expected
    try:
        number = float(found)
    except (TypeError, ValueError):
        return False
    return not math.isnan(number) and number == float(expected)


def _listed(numbers: Sequence[int], most: int = 10) -> str:
    """``0–29`` for a run, else the first ``most`` numbers and how many in all."""
    if len(numbers) > 2 and numbers[-1] - numbers[0] == len(numbers) - 1:
        return f"{numbers[0]}–{numbers[-1]}"
    shown = ", ".join(map(str, numbers[:most]))
    return shown if len(numbers) <= most else f"{shown}, … ({len(numbers)} in all)"
