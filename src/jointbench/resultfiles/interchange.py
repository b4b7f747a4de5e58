"""Plain text for estimators in any language: a condition's markers as CSV, estimates from CSV.

A C, R, Julia or awk program reads the CSV form of a dataset and writes its estimates as CSV; the
workflow converts both ways (``workflow/rules/interchange.smk``), so the program needs no Parquet
reader and no wrapper. The truth is not in the CSV: the benchmark scores the estimates itself.
The CSV is made from the blind file, each trial placed anew (:mod:`jointbench.running.placement`),
and a program answers in its coordinates; the answers are mapped back before scoring.

Dataset CSV (:func:`write_dataset_csv`), one header line, then one row per marker sample ordered
by trial, segment (as in the dataset), frame and marker::

    trial,segment,frame,marker,x,y,z

``trial``, ``frame`` and ``marker`` count from 0; ``segment`` is ``moving`` for one-segment
studies, ``proximal`` and ``distal`` for two-segment ones, plus any segment a study derives
for another kind of estimator (``thigh_in_pelvis`` in ``hip_sta``); ``x``, ``y``, ``z`` in mm,
written with the digits that read back to the same double. The file ends with a newline; before
the program's estimates are used, the file is checked to hold its header and one line per sample
of the dataset, each as written (:func:`check_dataset_csv`), so that a file cut short after it was
written, at a line's end or inside one, cannot pass for a complete one, nor one a program
rewrote in place for the markers the others read.

Estimates CSV (:func:`read_estimates_csv`), one header line, one row per trial: ``trial``, the
estimate columns of the study's kind (``center_x, center_y, center_z``; or ``point_*`` and
``direction_*``; for a joint centre optionally ``cov_*``, and ``cov_yx``, ``cov_zx``,
``cov_zy`` equal to their mirrors), ``converged`` (``true``/``false`` or ``1``/``0``),
``iterations``, ``seconds`` and ``status``, every line ending with a newline (a file cut
inside its last value would otherwise read as a finished one). The condition's columns and
``method`` are added from the dataset and the file's folder; the result is then checked and
collected like any estimates file, and the estimates file records the CSV's path, which its
refusals name.
"""

from __future__ import annotations

import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import BinaryIO

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pacsv
import pyarrow.parquet as pq

from jointbench.invocation import snakemake_command
from jointbench.resultfiles.parquet import (
    read_metadata,
    read_row_count,
    read_trial_numbers,
    write_table,
)

__all__ = [
    "DATASET_COLUMNS",
    "ESTIMATE_ROW_COLUMNS",
    "check_dataset_csv",
    "read_estimates_csv",
    "write_dataset_csv",
]

#: The columns of a dataset's CSV form, in order.
DATASET_COLUMNS = ("trial", "segment", "frame", "marker", "x", "y", "z")

#: The columns every estimates CSV has besides its estimate columns.
ESTIMATE_ROW_COLUMNS = ("trial", "converged", "iterations", "seconds", "status")


def write_dataset_csv(dataset: str | Path, output: str | Path) -> None:
    """Write the markers of a dataset file as CSV (see the module docstring)."""
    Path(output).parent.mkdir(parents=True, exist_ok=True)
    with open(output, "wb") as stream:
        _write_csv(dataset, stream)


def _write_csv(dataset: str | Path, stream: BinaryIO) -> None:
    """The CSV of :func:`write_dataset_csv` written to the binary ``stream``."""
    table = pq.read_table(dataset, columns=list(DATASET_COLUMNS))
    segment = table.column("segment").cast(pa.string())
    table = table.set_column(table.schema.get_field_index("segment"), "segment", segment)
    order = [("trial", "ascending"), ("frame", "ascending"), ("marker", "ascending")]
    first_seen = pa.array(list(dict.fromkeys(segment.unique().to_pylist())), pa.string())
    table = table.append_column("segment_rank", pc.index_in(segment, value_set=first_seen))
    order.insert(1, ("segment_rank", "ascending"))
    table = table.sort_by(order).drop_columns(["segment_rank"])
    # Arrow quotes a header it writes; a plain one is easier for a C or awk reader.
    stream.write((",".join(DATASET_COLUMNS) + "\n").encode())
    options = pacsv.WriteOptions(include_header=False, quoting_style="none")
    pacsv.write_csv(table, stream, options)


def check_dataset_csv(path: str | Path, dataset: str | Path) -> None:
    """``ValueError`` naming ``path`` unless it is the CSV :func:`write_dataset_csv` writes for
    ``dataset``: first its lines are counted, the header and one per row of the dataset file,
    each ending with a newline, then each is compared with the one written anew.

    Any cut of the file removes at least its final newline, so a file cut short, at a line's
    end or inside one, has fewer newlines than that; a file rewritten in place (by a program
    that read it, before the others that read it did) keeps its count but not its lines. The
    estimates a program made from either are refused, naming the first line that differs.
    """
    expected = read_row_count(dataset) + 1
    found, last = _newlines(path)
    if found != expected or last != b"\n":
        ending = "" if last in (b"", b"\n") else f", and its last line {found + 1} ends without one"
        raise ValueError(
            f"{path}: {found} lines ending with a newline{ending}; the markers CSV of {dataset} "
            f"has {expected} (a header and one per marker sample): the file was cut short or "
            + _changed(path)
        )
    difference = _first_difference(path, dataset)
    if difference is not None:
        number, held, written = difference
        # The blind copy may be the file that changed (rewritten by a program that read it
        # after the CSV was made): writing it anew writes the CSV anew too.
        raise ValueError(
            f"{path}: line {number} is not the line the markers CSV of {dataset} has there "
            f"({held!r} where it has {written!r}): the CSV or the blind copy it was made from "
            "was " + _changed(dataset)
        )


def _changed(path: str | Path) -> str:
    """How a refusal of a markers CSV ends: what the change means, and the command that writes
    the file at ``path`` anew with everything made from it."""
    return (
        "changed after it was written, and a program that read it saw other markers than the "
        "dataset's. Regenerate it and what depends on it with: "
        + snakemake_command("--forcerun", str(path))
    )


def _first_difference(path: str | Path, dataset: str | Path) -> tuple[int, str, str] | None:
    """The number of the first line of the file at ``path`` that differs from the CSV of
    ``dataset`` written anew, with both lines; ``None`` when none does. Written to a temporary
    file and read a line at a time: the CSV may be far larger than memory."""
    with tempfile.TemporaryFile() as written, open(path, "rb") as held:
        _write_csv(dataset, written)
        written.seek(0)
        for number, (mine, theirs) in enumerate(zip(held, written, strict=False), start=1):
            if mine != theirs:
                return number, mine.decode(errors="replace"), theirs.decode(errors="replace")
    return None


def _newlines(path: str | Path, chunk_bytes: int = 2**20) -> tuple[int, bytes]:
    """The number of newlines in the file at ``path`` and its last byte (``b""`` when empty),
    read a chunk of ``chunk_bytes`` at a time: the file may be far larger than memory."""
    count, last = 0, b""
    with open(path, "rb") as stream:
        while chunk := stream.read(chunk_bytes):
            count += chunk.count(b"\n")
            last = chunk[-1:]
    return count, last


def read_estimates_csv(
    path: str | Path, dataset: str | Path, output: str | Path, provenance: Mapping | None = None
) -> None:
    """Write the estimates CSV at ``path`` as an estimates file at ``output``: its columns, with
    the condition of ``dataset`` and the method (the name of ``path``'s folder) in every row.

    ``ValueError`` naming ``path`` when it cannot be read as CSV, gives a column twice or one
    without a name, does not end with a newline, has no rows, lacks a required column or holds
    a status that is not UTF-8; the estimate columns and every value are checked when the file
    is collected, and a refusal then names ``path`` too, which ``output`` records
    (:func:`jointbench.resultfiles.parquet.read_source`): the file its author can correct.
    """
    try:
        table = pacsv.read_csv(path)
    except (pa.ArrowInvalid, OSError) as error:
        raise ValueError(f"{path}: cannot be read as CSV ({error})") from None
    names = table.column_names
    repeated = next((name for name in names if names.count(name) > 1), None)
    if repeated is not None:
        raise ValueError(f"{path}: column {repeated!r} appears more than once")
    unnamed = next((index for index, name in enumerate(names) if not name.strip()), None)
    if unnamed is not None:
        raise ValueError(
            f"{path}: column {unnamed + 1} has no name (a comma ending the header line?)"
        )
    _check_ends_with_newline(path)
    if not table.num_rows:
        trials = len(read_trial_numbers(dataset))
        raise ValueError(f"{path}: no rows; the dataset has {trials} trials, one row each")
    table = _untyped_as_numbers(table)
    missing = [name for name in ESTIMATE_ROW_COLUMNS if name not in table.column_names]
    if len(table.column_names) == 1 and missing:
        raise ValueError(
            f"{path}: missing column {missing[0]!r}: the header is one column, "
            f"{table.column_names[0]!r}; an estimates CSV separates its columns with commas"
        )
    if missing:
        raise ValueError(
            f"{path}: missing column {missing[0]!r}; an estimates CSV has "
            f"{', '.join(ESTIMATE_ROW_COLUMNS)} and the estimate columns of its study's kind"
        )
    table = table.set_column(
        table.schema.get_field_index("converged"), "converged", _booleans(table, path)
    )
    status = _text(table, "status", path).fill_null("")
    table = table.set_column(table.schema.get_field_index("status"), "status", status)
    condition = read_metadata(dataset)["condition"]
    added = {key: pa.array([value] * table.num_rows) for key, value in condition.items()}
    added["method"] = pa.array([Path(path).parent.name] * table.num_rows, pa.string())
    columns = {**added, **{name: table.column(name) for name in table.column_names}}
    write_table(pa.table(columns), output, provenance, source=path)


def _check_ends_with_newline(path: str | Path) -> None:
    """``ValueError`` naming ``path`` unless its last line ends with a newline: a file whose
    writer stopped inside its last value (``3.25`` cut to ``3.2``) still reads as CSV, and only
    the missing newline tells it from a finished one."""
    found, last = _newlines(path)
    if last in (b"", b"\n"):
        return
    raise ValueError(
        f"{path}: line {found + 1}, the last, ends without a newline: the file was cut short "
        "or its writer did not finish it, and its last value may be cut; a finished estimates "
        "CSV ends every line, the last one too, with a newline"
    )


def _untyped_as_numbers(table: pa.Table) -> pa.Table:
    """Every column but ``status`` and ``converged`` that is missing in every row, which CSV
    leaves without a type, as floats: the estimate of a condition whose every trial failed is
    NaN throughout, and still a number."""
    for index, field in enumerate(table.schema):
        if pa.types.is_null(field.type) and field.name not in ("status", "converged"):
            table = table.set_column(index, field.name, table.column(index).cast(pa.float64()))
    return table


def _text(table: pa.Table, name: str, path: str | Path) -> pa.ChunkedArray:
    """Column ``name`` as text; ``ValueError`` naming ``path`` and the first trial whose value
    is not UTF-8 (CSV keeps such a column as bytes)."""
    column = table.column(name)
    if pa.types.is_binary(column.type) or pa.types.is_large_binary(column.type):
        for row, value in enumerate(column.to_pylist()):
            if value is None:
                continue
            try:
                value.decode()
            except UnicodeDecodeError:
                trial = table.column("trial")[row].as_py()
                raise ValueError(
                    f"{path}: column {name!r} is not UTF-8 text in the row of trial {trial!r} "
                    f"({value!r}): write the file in UTF-8"
                ) from None
    return column.cast(pa.string())


def _booleans(table: pa.Table, path: str | Path) -> pa.Array:
    """``converged`` as booleans, from ``true``/``false`` or ``1``/``0``; an empty cell stays
    missing, for the estimates check to name its trial."""
    column = table.column("converged")
    if pa.types.is_null(column.type):
        return column.cast(pa.bool_())
    if pa.types.is_boolean(column.type):
        return column
    if pa.types.is_integer(column.type):
        if np.isin(column.drop_null().to_numpy(), (0, 1)).all():
            return pc.equal(column, 1)
    raise ValueError(f"{path}: column 'converged' must hold true/false or 1/0, got {column.type}")
