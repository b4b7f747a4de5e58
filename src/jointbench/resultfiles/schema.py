"""The columns every estimates file must carry, by estimator kind.

A user's estimator (built-in or a rule in any language) writes one parquet file per study
condition with one row per trial. :func:`check_estimates` is run on every such file before it
is collected, so a wrong or missing column fails with its name rather than as a broken figure;
:func:`check_against_dataset` then holds it to its dataset, so that a missing, repeated or
invented trial or condition cannot change a ranking unnoticed. A file's errors are the
benchmark's to compute (:mod:`jointbench.running.scoring`): a file may leave them out, and
:func:`check_scores` stops the run when it gives ones that disagree; :func:`check_claimed_estimates`
refuses a trial that claims success without a finite estimate, :func:`check_not_negative` a
negative time or iteration count.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa

from jointbench.running.scoring import (
    COVARIANCE_COLUMNS,
    ERROR_COLUMN,
    ESTIMATE_COLUMNS,
    PROXIMAL_COLUMNS,
    RADIUS_COLUMN,
    SCORE_COLUMNS,
)

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "COMMON_COLUMNS",
    "KIND_COLUMNS",
    "OPTIONAL_COLUMNS",
    "SCORE_ATOL",
    "SCORE_RTOL",
    "check_against_dataset",
    "check_claimed_estimates",
    "check_estimates",
    "check_not_negative",
    "check_scores",
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
#: Per kind, the estimate columns every file must carry.
KIND_COLUMNS = {kind: dict.fromkeys(columns, _NUMBER) for kind, columns in ESTIMATE_COLUMNS.items()}
#: Per kind, the columns a file may carry and the benchmark computes itself (see
#: :mod:`jointbench.running.scoring`): when present, they must be numeric, and collect holds them
#: to its own computation (:func:`check_scores`).
OPTIONAL_COLUMNS = {
    kind: dict.fromkeys(
        [
            *columns,
            *((*COVARIANCE_COLUMNS, *PROXIMAL_COLUMNS) if kind == "joint_center" else ()),
            *((RADIUS_COLUMN,) if kind == "center" else ()),
        ],
        _NUMBER,
    )
    for kind, columns in SCORE_COLUMNS.items()
}
#: A reported score agrees with the benchmark's when equal to this relative tolerance, or
#: this absolute one in the column's own unit: rounding, not a different number.
SCORE_RTOL = 1e-6
SCORE_ATOL = 1e-6


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
    """Raise ``ValueError`` naming the first missing or mistyped column of an estimates table
    (a score column, :data:`OPTIONAL_COLUMNS`, may be absent, but not of another type).

    ``table`` is an Arrow table or a pandas data frame; a column's type is its Arrow type (a
    frame's columns are converted as parquet would store them).
    """
    names = table.column_names if isinstance(table, pa.Table) else list(table.columns)
    columns = {}
    required = required_columns(kind, condition_keys)
    optional = {c: check for c, check in OPTIONAL_COLUMNS[kind].items() if c in names}
    for column, (accepts, description) in {**required, **optional}.items():
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


def check_scores(
    table: pd.DataFrame, scores: Mapping[str, np.ndarray], *, source: str = "estimates"
) -> None:
    """Raise ``ValueError`` naming ``source``, the trial and the column when a score column
    ``table`` gives disagrees with the benchmark's ``scores`` (name -> ``(n,)``, the rows'
    order) beyond rounding (:data:`SCORE_RTOL`, :data:`SCORE_ATOL`); NaN agrees only with NaN.
    Columns ``table`` leaves out are not checked."""
    for column, ours in scores.items():
        if column not in table:
            continue
        given = np.asarray(table[column], dtype=float)
        agree = np.isclose(given, ours, rtol=SCORE_RTOL, atol=SCORE_ATOL, equal_nan=True)
        if not agree.all():
            row = int(np.argmin(agree))
            raise ValueError(
                f"{source}: trial {int(table['trial'].iloc[row])}: column {column!r} is "
                f"{float(given[row])!r}, but the estimate and the dataset's truth give "
                f"{float(ours[row])!r} "
                f"({np.count_nonzero(~agree)} of {len(agree)} rows disagree); the benchmark "
                f"computes {column!r} itself: leave the column out or fix it"
            )


def check_claimed_estimates(
    table: pd.DataFrame, kind: str, error: np.ndarray, *, source: str = "estimates"
) -> None:
    """Raise ``ValueError`` naming ``source``, the method and the trial when a row claims
    success (``converged`` true or ``status`` "ok") without a finite estimate and a finite
    ``error`` ``(n,)`` (the benchmark's, e.g. NaN for an axis direction of zero length): a
    failed trial says it failed, so that it is counted as one."""
    claimed = np.asarray(table["converged"], dtype=bool) | (
        np.asarray(table["status"], dtype=object) == "ok"
    )
    estimates = np.column_stack([np.asarray(table[c], dtype=float) for c in ESTIMATE_COLUMNS[kind]])
    finite = np.isfinite(estimates).all(axis=1) & np.isfinite(error)
    bad = np.flatnonzero(claimed & ~finite)
    if bad.size:
        row = int(bad[0])
        values = ", ".join(
            f"{c}={float(v)!r}" for c, v in zip(ESTIMATE_COLUMNS[kind], estimates[row], strict=True)
        )
        raise ValueError(
            f"{source}: method {table['method'].iloc[row]!r}, trial "
            f"{int(table['trial'].iloc[row])}: converged={bool(table['converged'].iloc[row])}, "
            f"status {table['status'].iloc[row]!r}, but the estimate is not finite ({values}; "
            f"{ERROR_COLUMN[kind]}={float(error[row])!r}); {bad.size} such rows. A trial "
            "without an estimate is a failure: converged=False and the reason in 'status'"
        )


def check_not_negative(
    table: pd.DataFrame, columns: Sequence[str] = ("seconds", "iterations"), *, source: str
) -> None:
    """Raise ``ValueError`` naming ``source``, the trial and the column when one of
    ``columns`` (a time, a count of iterations) is below 0: no fit takes less than no time or
    work, and the extended ranking shows each method's mean time. NaN is not measured."""
    for column in columns:
        values = np.asarray(table[column], dtype=float)
        negative = np.flatnonzero(values < 0)
        if negative.size:
            row = int(negative[0])
            raise ValueError(
                f"{source}: trial {int(table['trial'].iloc[row])}: column {column!r} is "
                f"{table[column].iloc[row].item()!r}, below 0 ({negative.size} such rows)"
            )
