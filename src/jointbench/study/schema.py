"""The columns every estimates file must carry, by estimator kind.

A user's estimator (built-in or a rule in any language) writes one parquet file per study
condition with one row per trial. :func:`check_estimates` is run on every such file before it
is collected, so a wrong or missing column fails with its name rather than as a broken figure;
:func:`check_against_dataset` then holds it to its dataset, so that a missing, repeated or
invented trial or condition cannot change a ranking unnoticed.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence

import pandas as pd
from pandas.api import types

__all__ = [
    "COMMON_COLUMNS",
    "KIND_COLUMNS",
    "check_against_dataset",
    "check_estimates",
    "required_columns",
]

# column -> predicate on the pandas dtype, and what the predicate means for the message
_NUMBER = (types.is_numeric_dtype, "numeric")
_INTEGER = (types.is_integer_dtype, "integer")
_BOOL = (types.is_bool_dtype, "boolean")
_TEXT = (lambda d: types.is_string_dtype(d) or types.is_object_dtype(d), "text")

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
    """Column name -> (dtype predicate, description) for an estimates file of ``kind``."""
    if kind not in KIND_COLUMNS:
        raise ValueError(f"unknown estimator kind {kind!r}")
    return {
        **dict.fromkeys(condition_keys, (lambda d: True, "any")),
        **COMMON_COLUMNS,
        **KIND_COLUMNS[kind],
    }


def check_estimates(
    frame: pd.DataFrame,
    *,
    kind: str,
    condition_keys: Sequence[str],
    method: str | None = None,
    source: str = "estimates",
) -> None:
    """Raise ``ValueError`` naming the first missing or mistyped column of an estimates table."""
    for column, (accepts, description) in required_columns(kind, condition_keys).items():
        if column not in frame.columns:
            raise ValueError(f"{source}: missing column {column!r} (needed for {kind} estimates)")
        if not accepts(frame[column].dtype):
            raise ValueError(
                f"{source}: column {column!r} must be {description}, got {frame[column].dtype}"
            )
    if method is not None and not frame.empty and set(frame["method"]) != {method}:
        found = sorted(set(map(str, frame["method"])))
        raise ValueError(f"{source}: column 'method' must be {method!r} in every row, got {found}")


def check_against_dataset(
    frame: pd.DataFrame,
    *,
    trials: Iterable[int],
    condition: Mapping[str, object],
    source: str = "estimates",
) -> None:
    """Raise ``ValueError`` naming ``source`` unless ``frame`` (checked by
    :func:`check_estimates`) has one row per trial of its dataset, no other trial, and the
    dataset's ``condition`` values in every row."""
    expected = sorted(set(map(int, trials)))
    described = f"the dataset has {len(expected)} trials ({_listed(expected)})"
    if frame.empty:
        raise ValueError(f"{source}: no rows; {described}")
    found = frame["trial"].astype(int)
    problems = {
        "missing trials": sorted(set(expected) - set(found)),
        "trials not in the dataset": sorted(set(found) - set(expected)),
        "trials listed more than once": sorted(set(found[found.duplicated()])),
    }
    found_problems = [
        f"{problem}: {_listed(numbers)}" for problem, numbers in problems.items() if numbers
    ]
    if found_problems:
        raise ValueError(f"{source}: {'; '.join(found_problems)}; {described}")
    for key, value in condition.items():
        wrong = sorted({str(v) for v in frame[key] if not _same_value(v, value)})
        if wrong:
            raise ValueError(
                f"{source}: column {key!r} must be the dataset's {value!r} in every row, "
                f"got {', '.join(wrong)}"
            )


def _same_value(found: object, expected: object) -> bool:
    # 5 and 5.0 are one grid value; "5" is not.
    if isinstance(expected, str) or isinstance(found, str):
        return found == expected
    return bool(pd.notna(found)) and float(found) == float(expected)


def _listed(numbers: Sequence[int], most: int = 10) -> str:
    """``0–29`` for a run, else the first ``most`` numbers and how many in all."""
    if len(numbers) > 2 and numbers[-1] - numbers[0] == len(numbers) - 1:
        return f"{numbers[0]}–{numbers[-1]}"
    shown = ", ".join(map(str, numbers[:most]))
    return shown if len(numbers) <= most else f"{shown}, … ({len(numbers)} in all)"
