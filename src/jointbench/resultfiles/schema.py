"""The columns every estimates file must carry, by estimator kind.

A user's estimator (built-in or a rule in any language) writes one parquet file per study
condition with one row per trial. :func:`check_estimates` is run on every such file before it
is collected, so a wrong or missing column fails with its name rather than as a broken figure;
:func:`check_against_dataset` then holds it to its dataset, so that a missing, repeated or
invented trial or condition cannot change a ranking unnoticed. A file's errors are the
benchmark's to compute (:mod:`jointbench.running.scoring`): a file may leave them out, and
:func:`check_scores` stops the run when it gives ones that disagree; :func:`check_claimed_estimates`
refuses a trial that claims success without a finite estimate, :func:`check_not_negative` a
negative time or iteration count, and :func:`check_covariances` a predicted covariance that is
not one (given in part, asymmetric, or with a negative variance in some direction).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa

from jointbench.running.scoring import (
    COVARIANCE_COLUMNS,
    COVARIANCE_MIRRORS,
    ERROR_COLUMN,
    ESTIMATE_COLUMNS,
    PROXIMAL_COLUMNS,
    RADIUS_COLUMN,
    SCORE_COLUMNS,
    covariance_from_entries,
)

if TYPE_CHECKING:
    import pandas as pd

    from jointbench.simulate import Study

__all__ = [
    "COMMON_COLUMNS",
    "COVARIANCE_PSD_TOL",
    "COVARIANCE_RTOL",
    "KIND_COLUMNS",
    "OPTIONAL_COLUMNS",
    "SCORE_ATOL",
    "SCORE_RTOL",
    "check_against_dataset",
    "check_claimed_estimates",
    "check_covariances",
    "check_estimates",
    "check_not_negative",
    "check_scores",
    "estimates_columns",
    "recorded_columns",
    "required_columns",
]

# column -> predicate on the column's Arrow type, and what the predicate means for the message.
# Booleans count as numbers, as in NumPy; a column of nothing but missing values as text, and
# as booleans, for the check of missing values to name its first row.
_NUMBER = (
    lambda t: pa.types.is_integer(t) or pa.types.is_floating(t) or pa.types.is_boolean(t),
    "numeric",
)
_INTEGER = (pa.types.is_integer, "integer")
_BOOL = (lambda t: pa.types.is_boolean(t) or pa.types.is_null(t), "boolean")
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
#: Per kind, the prefixes of the predicted covariances [mm²] its files may give: a joint
#: centre's own (``cov_*``) and, relative to the proximal markers, ``proximal_cov_*``
#: (:data:`PROXIMAL_COLUMNS`).
_COVARIANCE_PREFIXES = {"joint_center": ("", "proximal_")}
#: Per kind, the mirror entries (below the diagonal) its files may give beside the six.
_MIRROR_COLUMNS = {
    kind: tuple(f"{prefix}{name}" for prefix in prefixes for name in COVARIANCE_MIRRORS)
    for kind, prefixes in _COVARIANCE_PREFIXES.items()
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
            *_MIRROR_COLUMNS.get(kind, ()),
        ],
        _NUMBER,
    )
    for kind, columns in SCORE_COLUMNS.items()
}
#: Per score column, the kinds whose files the benchmark computes it for: a file of another
#: kind may not give it, since nothing would check it (:func:`check_estimates`).
_SCORED_FOR = {
    column: tuple(kind for kind, columns in SCORE_COLUMNS.items() if column in columns)
    for column in dict.fromkeys(c for columns in SCORE_COLUMNS.values() for c in columns)
}
#: A reported score agrees with the benchmark's when equal to this relative tolerance, or
#: this absolute one in the column's own unit: rounding, not a different number.
SCORE_RTOL = 1e-6
SCORE_ATOL = 1e-6
#: A mirror entry (``cov_yx``) agrees with the entry it mirrors when they differ by no more than
#: this share of the matrix's largest entry: rounding, not an asymmetric matrix.
COVARIANCE_RTOL = 1e-9
#: A predicted covariance is positive semi-definite when its smallest eigenvalue is no lower
#: than minus this share of its largest: rounding, not a negative variance.
COVARIANCE_PSD_TOL = 1e-9


def required_columns(kind: str, condition_keys: Sequence[str]) -> dict[str, tuple]:
    """Column name -> (Arrow type predicate, description) for an estimates file of ``kind``."""
    if kind not in KIND_COLUMNS:
        raise ValueError(f"unknown estimator kind {kind!r}")
    return {
        **dict.fromkeys(condition_keys, (lambda d: True, "any")),
        **COMMON_COLUMNS,
        **KIND_COLUMNS[kind],
    }


def estimates_columns(kind: str, condition_keys: Sequence[str]) -> tuple[str, ...]:
    """Every column the estimate job writes itself into an estimates file of ``kind`` with
    ``condition_keys``: what it carries (:func:`required_columns`) and may carry
    (:data:`OPTIONAL_COLUMNS`: the scores the benchmark computes, a covariance, a fitted
    radius)."""
    return (*required_columns(kind, condition_keys), *OPTIONAL_COLUMNS[kind])


def recorded_columns(spec: Study) -> tuple[str, ...]:
    """Every column the collected results of study ``spec`` may hold from its own estimators,
    each once: per kind it runs, what the estimate job writes itself (:func:`estimates_columns`,
    with its grid keys), then the columns of its diagnostics
    (:attr:`~jointbench.simulate.Diagnostic.columns`). An external estimator's own extra
    columns are no study's."""
    by_kind = (estimates_columns(kind, spec.grid_keys) for kind in spec.kinds)
    diagnosed = (check.columns for check in spec.diagnostics.values())
    return tuple(dict.fromkeys(column for columns in (*by_kind, *diagnosed) for column in columns))


def check_estimates(
    table: pa.Table | pd.DataFrame,
    *,
    kind: str,
    condition_keys: Sequence[str],
    method: str | None = None,
    source: str = "estimates",
) -> None:
    """Raise ``ValueError`` naming the first missing or mistyped column of an estimates table
    (a score column, :data:`OPTIONAL_COLUMNS`, may be absent, but not of another type), a score
    the benchmark computes for other kinds only, and the first trial with no ``converged``.

    ``table`` is an Arrow table or a pandas data frame; a column's type is its Arrow type (a
    frame's columns are converted as parquet would store them).
    """
    names = table.column_names if isinstance(table, pa.Table) else list(table.columns)
    _check_no_foreign_scores(names, kind, source)
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
                + _first_offender(
                    columns[column], None if column == "trial" else columns["trial"], description
                )
            )
    if columns["trial"].null_count:
        raise ValueError(f"{source}: column 'trial' has missing values")
    _check_converged_given(columns["converged"], columns["trial"], source)
    if method is not None and len(table):
        found = set(columns["method"].to_pylist())
        if found != {method}:
            listed = sorted(map(str, found))
            raise ValueError(
                f"{source}: column 'method' must be {method!r} in every row, got {listed}"
            )


def _check_no_foreign_scores(names: Sequence[str], kind: str, source: str) -> None:
    """``ValueError`` naming ``source`` and the column when a file of ``kind`` gives a score
    the benchmark computes for other kinds only: it is neither computed nor checked for this
    file, so a study running both kinds would collect it beside the benchmark's own."""
    for column in names:
        kinds = _SCORED_FOR.get(column, (kind,))
        if kind not in kinds:
            raise ValueError(
                f"{source}: column {column!r} is a score the benchmark computes for "
                f"{' and '.join(kinds)} estimates, not for {kind} ones: leave it out"
            )


def _check_converged_given(converged, trials, source: str) -> None:
    """``ValueError`` naming ``source`` and the first trial whose ``converged`` is missing: such
    a row claims neither success nor failure, and would be counted as neither."""
    if not converged.null_count:
        return
    row = converged.to_pylist().index(None)
    raise ValueError(
        f"{source}: column 'converged' is empty in the row of trial {trials[row].as_py()!r} "
        f"({converged.null_count} such rows): each row says whether its method converged, "
        "true or false (1 or 0)"
    )


def _first_offender(column: pa.Array | pa.ChunkedArray, trials, description: str) -> str:
    """Where a column of the wrong type first holds what makes it so: what a CSV's author looks
    for. A text column that should hold numbers: its first word that is none (``"two"``,
    ``"1,5"``); a float column that should hold integers: its first value that is no whole
    number, or nothing (an empty cell). Empty for any other column."""
    if pa.types.is_string(column.type) or pa.types.is_large_string(column.type):
        return _first_word(column, trials)
    if description == "integer" and pa.types.is_floating(column.type):
        for row, value in enumerate(column.to_pylist()):
            if value is None or not float(value).is_integer():
                held = "nothing" if value is None or math.isnan(value) else repr(value)
                return f"; the row{_of_trial(trials, row)} holds {held}"
    return ""


def _of_trial(trials, row: int) -> str:
    """`` of trial N`` for row ``row`` of the ``trials`` column, or nothing without one."""
    return "" if trials is None else f" of trial {trials[row].as_py()!r}"


def _first_word(column: pa.Array | pa.ChunkedArray, trials) -> str:
    """For a text column that should hold numbers, where it first holds a word that is none
    (``"two"``, ``"1,5"``)."""
    for row, value in enumerate(column.to_pylist()):
        try:
            float(value)
        except (TypeError, ValueError):
            if value is None:
                continue
            return f"; the row{_of_trial(trials, row)} holds {value!r}"
    return ""


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
        wrong = sorted({_typed(v) for v in values if not _same_value(v, value)})
        if wrong:
            raise ValueError(
                f"{source}: column {key!r} must be the dataset's {_typed(value)} in every row, "
                f"got {', '.join(wrong)}"
            )


def _typed(value: object) -> str:
    """``value`` as its repr and type, ``'15' (str)`` or ``15 (int)``: the text 15 and the
    number 15 print alike, and telling them apart is the point of the message."""
    return f"{value!r} ({type(value).__name__})"


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
    claimed = _claims_success(table)
    estimates = np.column_stack([np.asarray(table[c], dtype=float) for c in ESTIMATE_COLUMNS[kind]])
    finite = np.isfinite(estimates).all(axis=1) & np.isfinite(error)
    bad = np.flatnonzero(claimed & ~finite)
    if bad.size:
        row = int(bad[0])
        values = ", ".join(
            f"{c}={float(v)!r}" for c, v in zip(ESTIMATE_COLUMNS[kind], estimates[row], strict=True)
        )
        raise ValueError(
            f"{_where(table, row, source)}: {_claim(table, row)}, but the estimate is not "
            f"finite ({values}; "
            f"{ERROR_COLUMN[kind]}={float(error[row])!r}); {bad.size} such rows. A trial "
            "without an estimate is a failure: converged=False and the reason in 'status'"
        )


def _claims_success(table: pd.DataFrame) -> np.ndarray:
    """``(n,)``: whether each row claims success, ``converged`` true or ``status`` "ok"."""
    return np.asarray(table["converged"], dtype=bool) | (
        np.asarray(table["status"], dtype=object) == "ok"
    )


def _where(table: pd.DataFrame, row: int, source: str) -> str:
    """The file, method and trial of a row (its position in ``table``), for a message."""
    return f"{source}: method {table['method'].iloc[row]!r}, trial {int(table['trial'].iloc[row])}"


def _claim(table: pd.DataFrame, row: int) -> str:
    """What a row claims, for a message."""
    return f"converged={bool(table['converged'].iloc[row])}, status {table['status'].iloc[row]!r}"


def check_covariances(table: pd.DataFrame, kind: str, *, source: str = "estimates") -> None:
    """Raise ``ValueError`` naming ``source``, the method, the trial and the column when a
    predicted covariance [mm²] of ``table`` (an estimates file of ``kind`` checked by
    :func:`check_estimates`: a joint centre's ``cov_*`` and ``proximal_cov_*``) is not one.

    Refused: a file giving some of a covariance's six entries (:data:`COVARIANCE_COLUMNS`) but
    not all; a row that claims success (as in :func:`check_claimed_estimates`) with some entries
    finite and others not (NaN in all of them: the method predicts none for that trial); and in
    every row whose entries are all finite, which is scored whatever it claims, a mirror entry
    (``cov_yx``, ``cov_zx``, ``cov_zy``, optional) that differs from the entry it mirrors by more
    than :data:`COVARIANCE_RTOL` of the matrix's largest entry, or a smallest eigenvalue below
    minus :data:`COVARIANCE_PSD_TOL` times the largest. A row that claims failure may carry NaN.
    """
    for prefix in _COVARIANCE_PREFIXES.get(kind, ()):
        names = [f"{prefix}{name}" for name in COVARIANCE_COLUMNS]
        mirrors = {f"{prefix}{m}": f"{prefix}{entry}" for m, entry in COVARIANCE_MIRRORS.items()}
        given = [name for name in (*names, *mirrors) if name in table]
        if not given:
            continue
        absent = [name for name in names if name not in table]
        if absent:
            raise ValueError(
                f"{source}: column {absent[0]!r} is missing, but {given[0]!r} is given: a "
                f"predicted covariance gives all six entries, {', '.join(names)}"
            )
        entries = {name: np.asarray(table[name], dtype=float) for name in given}
        full = _check_given_in_full(table, entries, source)
        matrices = covariance_from_entries(
            {name.removeprefix(prefix): entries[name] for name in names}, len(table)
        )
        _check_mirrors(table, entries, mirrors, matrices, full, source)
        _check_semi_definite(table, matrices, full, names, source)


def _check_given_in_full(table: pd.DataFrame, entries: Mapping[str, np.ndarray], source: str):
    """``(n,)``: which rows give every one of a covariance's ``entries`` (column -> ``(n,)``)
    finite; ``ValueError`` for a row that claims success and gives some of them only."""
    values = np.column_stack(list(entries.values()))
    finite = np.isfinite(values)
    partial = _claims_success(table) & ~finite.all(axis=1) & ~np.isnan(values).all(axis=1)
    if partial.any():
        row = int(np.argmax(partial))
        column = int(np.argmin(finite[row]))
        given = ", ".join(name for name, ok in zip(entries, finite[row], strict=True) if ok)
        raise ValueError(
            f"{_where(table, row, source)}: {_claim(table, row)}, but column "
            f"{list(entries)[column]!r} is {float(values[row, column])!r} while {given} "
            f"{'is' if finite[row].sum() == 1 else 'are'} finite ({np.count_nonzero(partial)} "
            "such rows): a predicted covariance is finite in every entry, or NaN in every "
            "entry when the method predicts none"
        )
    return finite.all(axis=1)


def _check_mirrors(table, entries, mirrors: Mapping[str, str], matrices, full, source: str):
    """``ValueError`` for a row of ``full`` (``(n,)``, the rows given in full) whose mirror
    entry differs from the entry it mirrors by more than :data:`COVARIANCE_RTOL` of the largest
    entry of its matrix (``matrices`` ``(n, 3, 3)``)."""
    scale = np.abs(matrices).max(axis=(1, 2))
    for mirror, entry in mirrors.items():
        if mirror not in entries:
            continue
        apart = full & (np.abs(entries[mirror] - entries[entry]) > COVARIANCE_RTOL * scale)
        if apart.any():
            row = int(np.argmax(apart))
            raise ValueError(
                f"{_where(table, row, source)}: column {mirror!r} is "
                f"{float(entries[mirror][row])!r}, but {entry!r}, which it mirrors, is "
                f"{float(entries[entry][row])!r} ({np.count_nonzero(apart)} such rows): a "
                "covariance is symmetric; give the mirror equal to its entry, or leave it out"
            )


def _check_semi_definite(table, matrices, full, names: Sequence[str], source: str) -> None:
    """``ValueError`` for a row of ``full`` whose matrix (``matrices`` ``(n, 3, 3)``, of the
    columns ``names``) has a smallest eigenvalue below minus :data:`COVARIANCE_PSD_TOL` times
    its largest."""
    rows = np.flatnonzero(full)
    eigenvalues = np.linalg.eigvalsh(matrices[rows])  # ascending, (k, 3)
    negative = eigenvalues[:, 0] < -COVARIANCE_PSD_TOL * eigenvalues[:, -1]
    if negative.any():
        first = int(np.argmax(negative))
        row = int(rows[first])
        shown = ", ".join(f"{float(value):.6g}" for value in eigenvalues[first])
        raise ValueError(
            f"{_where(table, row, source)}: the predicted covariance in columns "
            f"{', '.join(names)} is not positive semi-definite: its eigenvalues are {shown} "
            f"[mm²], the smallest below -{COVARIANCE_PSD_TOL:g} times the largest "
            f"({np.count_nonzero(negative)} such rows); no direction has a negative variance"
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
