"""Datasets and estimates on disk (parquet).

Dataset files are long format, one row per (segment, trial, frame, marker) with columns
``segment, trial, frame, marker, x, y, z`` [mm], rows in that order; the study, condition,
ground truth, generator parameters and each segment's array shape are JSON in the parquet
metadata under the key ``jointbench``. Trials are written in blocks, one row group per segment
and block, so a condition is read back a block of trials at a time (:func:`iter_dataset`) and
memory does not grow with the number of trials.

A blind dataset file (:func:`write_blind_dataset`) is what an estimator outside the package is
given: the same rows, each trial placed anew by a rigid motion of its own, read by the same
functions, with metadata reduced to :data:`BLIND_KEYS` (its truth reads as ``None``, its
parameters as empty); the benchmark alone scores, and :func:`read_truth` refuses such a file.
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import json
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

from jointbench.estimators.segment_poses import AlteredPoses, SegmentPoses
from jointbench.invocation import snakemake_command
from jointbench.simulate import Trials

if TYPE_CHECKING:
    import pandas as pd

    from jointbench.running.placement import Placements

__all__ = [
    "BLIND_KEYS",
    "iter_dataset",
    "read_dataset",
    "read_metadata",
    "read_poses",
    "read_provenance",
    "read_row_count",
    "read_source",
    "read_table",
    "read_trial_numbers",
    "read_truth",
    "rows_table",
    "trial_digests",
    "write_blind_dataset",
    "write_dataset",
    "write_dataset_blocks",
    "write_poses_blocks",
    "write_table",
]

_META_KEY = b"jointbench"
_PROVENANCE_KEY = b"jointbench.provenance"
_POSES_KEY = b"jointbench.poses"
# The file an estimates file was converted from (an estimates CSV): what its author wrote and
# can correct, and so what a refusal of its rows names.
_SOURCE_KEY = b"jointbench.source"
# Per segment, the arrays a pose fit stores per trial, by the shape of one of them.
_POSE_ARRAYS = {
    "rotation": lambda n_frames, n_markers: (n_frames, 3, 3),
    "translation": lambda n_frames, n_markers: (n_frames, 3),
    "body": lambda n_frames, n_markers: (n_markers, 3),
}
_INDEX = ("trial", "frame", "marker")
_DATASET_COLUMNS = ("segment", *_INDEX, "x", "y", "z")
# Marker coordinates per block of trials: large enough that per-block overheads vanish, small
# enough that a block and the estimators' temporaries stay far below a job's memory.
BLOCK_BYTES = 32 * 2**20


def _unreadable(path, error: Exception) -> ValueError:
    return ValueError(
        f"{path}: cannot be read as parquet ({type(error).__name__}: {error}); the file is "
        "missing, truncated or corrupt. Regenerate it and what depends on it with: "
        + snakemake_command("--forcerun", str(path))
    )


def _names_unreadable_file(read: Callable) -> Callable:
    """Turn pyarrow's errors on a missing, truncated or corrupt file (``ArrowInvalid: Parquet
    magic bytes not found``, which names no file) into a ``ValueError`` naming the file and the
    command that regenerates it, with everything downstream of it."""
    unreadable = (pa.ArrowException, OSError)
    if inspect.isgeneratorfunction(read):

        @functools.wraps(read)
        def reading_blocks(path, *args, **kwargs):
            try:
                yield from read(path, *args, **kwargs)
            except unreadable as error:
                raise _unreadable(path, error) from error

        return reading_blocks

    @functools.wraps(read)
    def reading(path, *args, **kwargs):
        try:
            return read(path, *args, **kwargs)
        except unreadable as error:
            raise _unreadable(path, error) from error

    return reading


# Arrow's own conversions from and to NumPy and Python values ask pandas whether a value is
# one of its objects, and so import it: that would double the start-up of the many jobs that
# need nothing else from it. Numeric columns are therefore converted through their buffers.
_NUMPY_DTYPES = {
    pa.float64(): np.float64,
    pa.float32(): np.float32,
    pa.int64(): np.int64,
    pa.int32(): np.int32,
    pa.int16(): np.int16,
    pa.int8(): np.int8,
    pa.uint64(): np.uint64,
    pa.uint32(): np.uint32,
    pa.uint16(): np.uint16,
    pa.uint8(): np.uint8,
}


def _from_numpy(values: np.ndarray) -> pa.Array:
    """A 1-D numeric NumPy array as an Arrow array of the same type (no missing values)."""
    values = np.asarray(values)
    if values.ndim != 1:
        raise ValueError(f"expected a 1-D array, got shape {values.shape}")
    values = np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("="))
    arrow_type = next((t for t, dtype in _NUMPY_DTYPES.items() if values.dtype == dtype), None)
    if arrow_type is None:
        raise TypeError(f"{values.dtype} arrays are not stored as numbers here")
    return pa.Array.from_buffers(arrow_type, len(values), [None, pa.py_buffer(values)])


def _to_numpy(values: pa.Array | pa.ChunkedArray) -> np.ndarray:
    """A numeric Arrow column as a 1-D NumPy array (fixed-size lists flattened); a missing
    float is NaN."""
    chunks = values.chunks if isinstance(values, pa.ChunkedArray) else [values]
    parts = [_chunk_to_numpy(chunk) for chunk in chunks]
    if not parts:
        return np.empty(0, dtype=_NUMPY_DTYPES.get(values.type, np.float64))
    return parts[0] if len(parts) == 1 else np.concatenate(parts)


def _chunk_to_numpy(chunk: pa.Array) -> np.ndarray:
    if pa.types.is_fixed_size_list(chunk.type) and not chunk.null_count:
        size = chunk.type.list_size
        return _chunk_to_numpy(chunk.values.slice(chunk.offset * size, len(chunk) * size))
    dtype = _NUMPY_DTYPES.get(chunk.type)
    floating = pa.types.is_floating(chunk.type)
    if dtype is None or (chunk.null_count and not floating):
        # Not a plain numeric column: Arrow converts it (and imports pandas to do so).
        return chunk.to_numpy(zero_copy_only=False)
    validity, data = chunk.buffers()
    out = np.frombuffer(data, dtype=dtype, count=len(chunk), offset=chunk.offset * dtype().itemsize)
    if chunk.null_count:
        bits = np.unpackbits(np.frombuffer(validity, dtype=np.uint8), bitorder="little")
        out = np.where(bits[chunk.offset : chunk.offset + len(chunk)].astype(bool), out, np.nan)
    return out


def block_trials(shapes: Mapping[str, tuple[int, ...]], block_bytes: int | None = None) -> int:
    """Trials per block (of ``block_bytes``, default :data:`BLOCK_BYTES`) for segments shaped
    ``(n_trials, n_frames, n_markers, 3)``."""
    block_bytes = BLOCK_BYTES if block_bytes is None else block_bytes
    per_trial = sum(8 * int(np.prod(shape[1:])) for shape in shapes.values())
    return max(1, block_bytes // max(per_trial, 1))


def _segment_block(name: str, markers: np.ndarray, first_trial: int) -> pa.Table:
    """Long rows of trials ``first_trial, ...`` of one segment ``(n, n_frames, n_markers, 3)``."""
    n_trials, n_frames, n_markers, _ = markers.shape
    trial, frame, marker = np.meshgrid(
        np.arange(first_trial, first_trial + n_trials),
        np.arange(n_frames),
        np.arange(n_markers),
        indexing="ij",
    )
    xyz = markers.reshape(-1, 3)
    return pa.table(
        {
            "segment": pa.DictionaryArray.from_arrays(
                _from_numpy(np.zeros(trial.size, dtype=np.int32)), _column([name], "segment")
            ),
            "trial": _from_numpy(trial.ravel()),
            "frame": _from_numpy(frame.ravel()),
            "marker": _from_numpy(marker.ravel()),
            "x": _from_numpy(xyz[:, 0]),
            "y": _from_numpy(xyz[:, 1]),
            "z": _from_numpy(xyz[:, 2]),
        }
    )


def write_dataset(
    path: str | Path,
    trials: Trials,
    *,
    study: str,
    condition: Mapping[str, object],
    provenance: Mapping[str, object] | None = None,
) -> None:
    """Write ``trials`` to ``path`` with study, condition, truth, parameters and provenance (what
    produced the file: see :func:`read_provenance`) as metadata; the file's layout is
    :func:`write_dataset_blocks`'s."""
    write_dataset_blocks(
        path, [trials], trials.n_trials, study=study, condition=condition, provenance=provenance
    )


def write_dataset_blocks(
    path: str | Path,
    blocks: Iterable[Trials],
    n_trials: int,
    *,
    study: str,
    condition: Mapping[str, object],
    provenance: Mapping[str, object] | None = None,
) -> None:
    """Write a condition's ``n_trials`` trials, given as consecutive ``blocks`` (one
    :class:`Trials` each, sharing truth and parameters), to ``path``; only one block is in
    memory at a time.

    Rows are grouped by segment, then by blocks of trials (one row group each): the first
    segment's rows go to the file as each block arrives, the others' to a temporary file beside
    it that is appended at the end. No table of the whole condition is built.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    writers: dict[str, pq.ParquetWriter] = {}
    spills: dict[str, Path] = {}
    first_trial, metadata = 0, None
    try:
        for trials in blocks:
            shapes = {name: markers.shape for name, markers in trials.segments.items()}
            if metadata is None:
                metadata = _dataset_metadata(trials, n_trials, study, condition, provenance)
                names = list(shapes)
                spills = {name: path.with_name(f".{path.name}.{name}.tmp") for name in names[1:]}
            step = block_trials(shapes)
            for name, markers in trials.segments.items():
                for first in range(0, markers.shape[0], step):
                    table = _segment_block(name, markers[first : first + step], first_trial + first)
                    schema = table.schema.with_metadata({_META_KEY: json.dumps(metadata).encode()})
                    if name not in writers:
                        writers[name] = pq.ParquetWriter(spills.get(name, path), schema)
                    writers[name].write_table(table.replace_schema_metadata(schema.metadata))
            first_trial += trials.n_trials
        if first_trial != n_trials:
            raise ValueError(f"{path}: blocks hold {first_trial} trials, expected {n_trials}")
        for name, spill in spills.items():
            writers.pop(name).close()
            spilled = pq.ParquetFile(spill)
            for group in range(spilled.num_row_groups):
                table = spilled.read_row_group(group)
                writers[names[0]].write_table(table.replace_schema_metadata(schema.metadata))
    finally:
        for writer in writers.values():
            writer.close()
        for spill in spills.values():
            spill.unlink(missing_ok=True)


def _dataset_metadata(trials: Trials, n_trials: int, study, condition, provenance) -> dict:
    """The file's metadata: study, condition, truth, parameters, shapes and provenance."""
    return {
        "study": study,
        "condition": dict(condition),
        "truth": trials.truth,
        "parameters": trials.parameters,
        "shapes": {
            name: [n_trials, *markers.shape[1:]] for name, markers in trials.segments.items()
        },
        "provenance": dict(provenance or {}),
    }


#: The metadata a blind dataset keeps, each public or read off its rows: the study's name, the
#: condition's grid values (the public protocol of the cell, as the file name lists them), each
#: segment's array shape (the trials, frames and markers its rows hold), and ``blind`` (true).
#: Left out: the truth, and every generator parameter, since the protocol's constants (the
#: centre, the joint's position, the markers' positions relative to it) place the truth.
BLIND_KEYS = ("study", "condition", "shapes", "blind")


@_names_unreadable_file
def write_blind_dataset(
    dataset: str | Path,
    output: str | Path,
    placements: Placements,
    provenance: Mapping[str, object] | None = None,
) -> None:
    """Copy the rows of the dataset file ``dataset`` to ``output``, row group by row group, each
    trial's markers placed anew, with only the :data:`BLIND_KEYS` of its metadata and
    ``provenance`` (what made the copy, which must hold no protocol value: see
    :data:`BLIND_KEYS`).

    ``placements`` (:class:`jointbench.running.placement.Placements`): every marker of every
    segment of a trial is written as ``R x + p`` with its trial's rotation ``R`` and
    translation ``p`` [mm], so that no constant answer matches the truth; ``ValueError``
    naming the file for a trial without one. The placements are not written to
    the copy."""
    metadata = read_metadata(dataset)
    blind = {
        "study": metadata["study"],
        "condition": metadata["condition"],
        "shapes": {name: list(shape) for name, shape in _shapes(dataset, metadata).items()},
        "blind": True,
        "provenance": dict(provenance or {}),
    }
    # Every key of the source's metadata goes, Arrow's copy of the schema among them.
    schema = pq.read_schema(dataset).with_metadata({_META_KEY: json.dumps(blind).encode()})
    Path(output).parent.mkdir(parents=True, exist_ok=True)
    with pq.ParquetWriter(output, schema) as writer:
        for table in _blind_rows(dataset, placements):
            writer.write_table(table.replace_schema_metadata(schema.metadata))


def _blind_rows(dataset: str | Path, placements: Placements) -> Iterator[pa.Table]:
    """The rows of the blind copy of the dataset file ``dataset``, a row group of it at a time
    (the copy never holds the whole file in memory), each trial's markers placed."""
    source = pq.ParquetFile(dataset)
    for group in range(source.num_row_groups):
        yield _placed_rows(source.read_row_group(group), placements, dataset)


def check_blind_copy(blind: str | Path, dataset: str | Path, placements: Placements) -> None:
    """``ValueError`` naming ``blind``, the first trial and column that differ, unless its rows
    are those :func:`write_blind_dataset` wrote from ``dataset`` and ``placements``: a program
    that rewrote the copy it was given in place (cleaning it, or spoiling it) made every
    external estimator that read it after fit other markers than the built-in ones, which read
    the dataset itself. Read a row group of the dataset at a time, as it was written."""
    held = pq.ParquetFile(blind)
    if held.metadata.num_rows != read_row_count(dataset):
        raise ValueError(
            f"{blind}: {held.metadata.num_rows} rows, where the blind copy of {dataset} has "
            f"{read_row_count(dataset)}: " + _blind_changed(blind)
        )
    found = held.iter_batches(batch_size=2**16)
    pending = pa.Table.from_batches([], schema=held.schema_arrow)
    for expected in _blind_rows(dataset, placements):
        while pending.num_rows < expected.num_rows:
            pending = pa.concat_tables([pending, pa.Table.from_batches([next(found)])])
        _compare_rows(pending.slice(0, expected.num_rows), expected, blind, dataset)
        pending = pending.slice(expected.num_rows)


def _compare_rows(found: pa.Table, expected: pa.Table, blind, dataset) -> None:
    """``ValueError`` naming ``blind``, the trial and the column of the first row where
    ``found`` (rows of the blind copy) differs from ``expected`` (those it was written with);
    a missing marker (NaN) in both is no difference."""
    for name in expected.column_names:
        mine = found.column(name).to_numpy(zero_copy_only=False)
        theirs = expected.column(name).to_numpy(zero_copy_only=False)
        same = mine == theirs
        if same.dtype == bool and theirs.dtype.kind == "f" and mine.dtype.kind == "f":
            same |= np.isnan(mine) & np.isnan(theirs)
        if np.all(same):
            continue
        row = int(np.argmin(same))
        raise ValueError(
            f"{blind}: trial {expected.column('trial')[row].as_py()}: column {name!r} is not "
            f"what the blind copy of {dataset} holds ({found.column(name)[row].as_py()!r} "
            f"where it has {expected.column(name)[row].as_py()!r}): " + _blind_changed(blind)
        )


def _blind_changed(blind: str | Path) -> str:
    """How a refusal of the changed blind copy ``blind`` ends: what the change means, and the
    command that writes it anew with everything made from it."""
    return (
        "the file was changed after it was written, and every external estimator that read it "
        "after the change fit other markers than the dataset's. Regenerate it and what depends "
        "on it with: " + snakemake_command("--forcerun", str(blind))
    )


def _placed_rows(table: pa.Table, placements: Placements, dataset) -> pa.Table:
    """Dataset rows with ``x, y, z`` [mm] moved by their trial's placement: ``R x + p``."""
    try:
        rotations, translations = placements.rows(_to_numpy(table.column("trial")))
    except ValueError as error:
        raise ValueError(f"{dataset}: {error}") from None
    xyz = np.column_stack([_to_numpy(table.column(axis)) for axis in "xyz"])
    placed = np.einsum("nij,nj->ni", rotations, xyz) + translations
    for column, axis in enumerate("xyz"):
        at = table.schema.get_field_index(axis)
        table = table.set_column(at, axis, _from_numpy(placed[:, column]))
    return table


@_names_unreadable_file
def read_truth(path: str | Path) -> dict:
    """The ground truth of a dataset file, to score estimates against; ``ValueError`` naming
    the file for a blind one (:func:`write_blind_dataset`), which has none."""
    metadata = read_metadata(path)
    if metadata.get("blind") or "truth" not in metadata:
        raise ValueError(
            f"{path} is a blind dataset file: it holds no truth, and estimates are scored "
            "against the condition's full dataset file (results/datasets/)"
        )
    return metadata["truth"]


@_names_unreadable_file
def read_metadata(path: str | Path) -> dict:
    """The ``jointbench`` metadata of a dataset file."""
    metadata = pq.read_schema(path).metadata or {}
    if _META_KEY not in metadata:
        raise ValueError(f"{path} is not a jointbench dataset (no 'jointbench' metadata)")
    return json.loads(metadata[_META_KEY])


def _shapes(path: str | Path, metadata: Mapping) -> dict[str, tuple[int, ...]]:
    """Each segment's ``(n_trials, n_frames, n_markers, 3)``, from the metadata or, for files
    written before it was recorded there, from the index columns."""
    if "shapes" in metadata:
        return {name: tuple(shape) for name, shape in metadata["shapes"].items()}
    import pyarrow.compute as pc  # only files without recorded shapes need it

    table = pq.read_table(path, columns=["segment", *_INDEX])
    shapes = {}
    for name in table.column("segment").unique().to_pylist():
        part = table.filter(pc.equal(table.column("segment").cast(pa.string()), pa.scalar(name)))
        sizes = [pc.max(part.column(key)).as_py() + 1 for key in _INDEX]
        shapes[str(name)] = (*sizes, 3)
    return shapes


def _labels(column: pa.ChunkedArray) -> set[str]:
    """The distinct values of a text column, as a dataset's dictionary-encoded ``segment``
    column stores them: from each chunk's dictionary and indices, without Arrow's compute
    module (see :func:`_to_numpy`)."""
    labels: set[str] = set()
    for chunk in column.chunks:
        if not isinstance(chunk, pa.DictionaryArray):
            labels.update(chunk.to_pylist())
            continue
        if chunk.null_count:
            labels.add(None)
        valid = chunk.indices if not chunk.null_count else chunk.indices.drop_null()
        dictionary = chunk.dictionary.to_pylist()
        labels.update(dictionary[index] for index in np.unique(_to_numpy(valid)))
    return labels


def _read_rows(
    dataset: pq.ParquetFile, first_row: int, n_rows: int, columns: Sequence[str]
) -> pa.Table:
    """Rows ``first_row .. first_row + n_rows`` of a parquet file's ``columns``, reading only
    the row groups that hold them."""
    meta = dataset.metadata
    groups, offsets, start = [], [], 0
    for index in range(meta.num_row_groups):
        size = meta.row_group(index).num_rows
        if start < first_row + n_rows and start + size > first_row:
            groups.append(index)
            offsets.append(start)
        start += size
    table = dataset.read_row_groups(groups, columns=list(columns))
    return table.slice(first_row - offsets[0], n_rows)


def _block(path, dataset, shapes, offsets, first: int, count: int) -> dict[str, np.ndarray]:
    """Segments' markers ``(count, n_frames, n_markers, 3)`` of trials ``first ..``, checked
    against the expected row order (``ValueError`` naming the file and the first bad row)."""
    segments = {}
    for name, shape in shapes.items():
        _, n_frames, n_markers, _ = shape
        per_trial = n_frames * n_markers
        rows = _read_rows(
            dataset, offsets[name] + first * per_trial, count * per_trial, _DATASET_COLUMNS
        )
        expected = np.meshgrid(
            np.arange(first, first + count),
            np.arange(n_frames),
            np.arange(n_markers),
            indexing="ij",
        )
        if _labels(rows.column("segment")) != {name}:
            raise ValueError(
                f"{path}: expected segment {name!r} for trials {first}..{first + count - 1}; "
                "rows are not grouped by segment, then trial, frame and marker"
            )
        for key, want in zip(_INDEX, expected, strict=True):
            got = _to_numpy(rows.column(key))
            if not np.array_equal(got, want.ravel()):
                bad = int(np.argmax(got != want.ravel()))
                raise ValueError(
                    f"{path}: rows of segment {name!r} are not in (trial, frame, marker) order "
                    f"(expected trial {first + bad // per_trial}, frame "
                    f"{bad % per_trial // n_markers}, marker {bad % n_markers} at the "
                    f"{bad}-th row of the block); rewrite it with write_dataset"
                )
        out = np.empty((count, n_frames, n_markers, 3))
        for axis, column in enumerate("xyz"):
            out[..., axis] = _to_numpy(rows.column(column)).reshape(count, n_frames, n_markers)
        segments[name] = out
    return segments


@_names_unreadable_file
def iter_dataset(
    path: str | Path, *, block_bytes: int | None = None
) -> Iterator[tuple[int, Trials]]:
    """A dataset file as ``(first_trial, Trials)`` blocks of consecutive trials.

    Only one block is in memory at a time; its trials are numbered from 0 within the block. A
    blind file's trials have truth ``None`` and no parameters.
    """
    metadata = read_metadata(path)
    shapes = _shapes(path, metadata)
    dataset = pq.ParquetFile(path)
    offsets, start = {}, 0
    for name, shape in shapes.items():
        offsets[name] = start
        start += int(np.prod(shape[:3]))
    if start != dataset.metadata.num_rows:
        raise ValueError(
            f"{path}: {dataset.metadata.num_rows} rows, but its segments "
            f"{ {name: list(shape) for name, shape in shapes.items()} } need {start}"
        )
    n_trials = next(iter(shapes.values()))[0]
    step = block_trials(shapes, block_bytes)
    for first in range(0, n_trials, step):
        count = min(step, n_trials - first)
        segments = _block(path, dataset, shapes, offsets, first, count)
        yield (
            first,
            Trials(
                segments=segments,
                truth=metadata.get("truth"),
                parameters=metadata.get("parameters", {}),
            ),
        )


@_names_unreadable_file
def read_dataset(path: str | Path) -> tuple[Trials, dict]:
    """Read a dataset file back into :class:`Trials` and its metadata (a blind file's trials:
    truth ``None``, no parameters)."""
    metadata = read_metadata(path)
    shapes = _shapes(path, metadata)
    segments = {name: np.empty(shape) for name, shape in shapes.items()}
    for first, block in iter_dataset(path):
        for name, markers in block.segments.items():
            segments[name][first : first + markers.shape[0]] = markers
    trials = Trials(
        segments=segments, truth=metadata.get("truth"), parameters=metadata.get("parameters", {})
    )
    return trials, metadata


@_names_unreadable_file
def read_trial_numbers(path: str | Path) -> np.ndarray:
    """The trial numbers of a dataset file, ``0 .. n_trials - 1``."""
    shapes = _shapes(path, read_metadata(path))
    return np.arange(next(iter(shapes.values()))[0])


@_names_unreadable_file
def trial_digests(path: str | Path) -> dict[int, bytes]:
    """Per trial of the dataset file ``path``: the SHA-256 digest of its marker coordinates,
    ``x, y, z`` of every row of the trial as little-endian float64 in the file's order, read a
    row group at a time. Simulated noise makes each trial's digest its own, and only a file
    holding the trial's markers as simulated (the dataset, not its blind copy) gives it."""
    hashes = {}
    source = pq.ParquetFile(path)
    for group in range(source.num_row_groups):
        table = source.read_row_group(group, columns=["trial", "x", "y", "z"])
        trials = table.column("trial").to_numpy()
        coordinates = np.column_stack(
            # Little-endian whatever the host's: the placements drawn from the digests, and
            # so the blind copies and external estimates, are the same on every machine.
            [table.column(axis).to_numpy().astype("<f8") for axis in "xyz"]
        )
        order = np.argsort(trials, kind="stable")
        found, first = np.unique(trials[order], return_index=True)
        for trial, rows in zip(found.tolist(), np.split(order, first[1:]), strict=True):
            hashes.setdefault(trial, hashlib.sha256()).update(
                np.ascontiguousarray(coordinates[rows]).tobytes()
            )
    return {trial: digest.digest() for trial, digest in sorted(hashes.items())}


@_names_unreadable_file
def read_row_count(path: str | Path) -> int:
    """The number of rows of a parquet file (of a dataset file: its marker samples, one per
    segment, trial, frame and marker), from its footer, without reading them."""
    return pq.ParquetFile(path).metadata.num_rows


@_names_unreadable_file
def read_table(path: str | Path) -> pd.DataFrame:
    """A results table (estimates, collected results) written by :func:`write_table`."""
    import pandas as pd  # the jobs that only write tables never import pandas

    return pd.read_parquet(path)


def write_table(
    table: pa.Table | pd.DataFrame,
    path: str | Path,
    provenance: Mapping[str, object] | None = None,
    source: str | Path | None = None,
) -> None:
    """Write a results table (Arrow or pandas) to parquet, creating the directory, with its
    provenance (what produced it: see :func:`read_provenance`) in the file's metadata, and
    ``source``, the file it was converted from (see :func:`read_source`), when given."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    if not isinstance(table, pa.Table):
        table = pa.Table.from_pandas(table, preserve_index=False)
    metadata = {**(table.schema.metadata or {}), _PROVENANCE_KEY: json.dumps(provenance or {})}
    if source is not None:
        metadata[_SOURCE_KEY] = str(source).encode()
    pq.write_table(table.replace_schema_metadata(metadata), path)


@_names_unreadable_file
def read_source(path: str | Path) -> str:
    """The file a refusal of the results table at ``path`` names: the file it was converted
    from, as :func:`write_table` recorded it (an external estimator's estimates CSV), else
    ``path`` itself (a file an estimator wrote as parquet)."""
    metadata = pq.read_schema(path).metadata or {}
    return metadata[_SOURCE_KEY].decode() if _SOURCE_KEY in metadata else str(path)


def rows_table(rows: Sequence[Mapping[str, object]]) -> pa.Table:
    """Rows (mappings of column name to a Python or NumPy scalar) as an Arrow table.

    Columns come in the order their names first appear. Each column holds one kind of value:
    booleans, integers (64-bit), numbers (64-bit floats; integers mixed with floats become
    floats) or text. ``None``, a key a row lacks, and a float NaN are missing values (NaN is
    stored as missing, as ``pyarrow.Table.from_pandas`` stores it). Unlike a pandas frame, an
    integer column with a missing value stays integer, and a missing value in a text or boolean
    column must be ``None``. Any other value, or a column mixing kinds, raises ``TypeError``
    naming its column.

    The columns are assembled from their buffers: converting Python or NumPy values with
    ``pyarrow.array`` imports pandas, which would double the start-up of a job that needs
    nothing else from it.
    """
    names = list(dict.fromkeys(name for row in rows for name in row))
    return pa.table({name: _column([row.get(name) for row in rows], name) for name in names})


def _column(values: list, name: str) -> pa.Array:
    """One column of :func:`rows_table` from its values, ``None`` where missing."""
    present = [value for value in values if value is not None]
    kinds = {_kind(value, name) for value in present}
    if not kinds:
        return pa.nulls(len(values))
    if len(kinds) > 1 and kinds != {"integer", "float"}:
        raise TypeError(f"column {name!r} mixes {' and '.join(sorted(kinds))} values")
    present_mask = [value is not None for value in values]
    if kinds == {"text"}:
        encoded = [b"" if value is None else value.encode() for value in values]
        offsets = np.zeros(len(values) + 1, dtype=np.int64)
        np.cumsum([len(text) for text in encoded], out=offsets[1:])
        # Arrow's plain strings have 32-bit offsets; beyond 2 GiB of text, large strings.
        large = offsets[-1] > np.iinfo(np.int32).max
        offsets = offsets if large else offsets.astype(np.int32)
        data = [pa.py_buffer(offsets), pa.py_buffer(b"".join(encoded))]
        return _from_buffers(pa.large_string() if large else pa.string(), data, present_mask)
    if kinds == {"boolean"}:
        bits = np.packbits([bool(value) for value in values], bitorder="little")
        return _from_buffers(pa.bool_(), [pa.py_buffer(bits)], present_mask)
    integers = kinds == {"integer"}
    numbers = np.array(
        [0 if value is None else value for value in values],
        dtype=np.int64 if integers else np.float64,
    )
    valid = np.array(present_mask) & ~np.isnan(numbers)
    arrow_type = pa.int64() if integers else pa.float64()
    return _from_buffers(arrow_type, [pa.py_buffer(numbers)], valid)


def _kind(value: object, name: str) -> str:
    if isinstance(value, bool | np.bool_):
        return "boolean"
    if isinstance(value, int | np.integer):
        return "integer"
    if isinstance(value, float | np.floating):
        return "float"
    if isinstance(value, str):
        return "text"
    raise TypeError(f"column {name!r}: {type(value).__name__} values cannot be stored ({value!r})")


def _from_buffers(arrow_type, data: list, valid) -> pa.Array:
    """An Arrow array from its data buffers and whether each value is present."""
    valid = np.asarray(valid, dtype=bool)
    missing = int(len(valid) - np.count_nonzero(valid))
    validity = pa.py_buffer(np.packbits(valid, bitorder="little")) if missing else None
    return pa.Array.from_buffers(arrow_type, len(valid), [validity, *data], null_count=missing)


@_names_unreadable_file
def read_provenance(path: str | Path) -> dict:
    """What produced a results or dataset file: package version, the fingerprint of the code
    that wrote it, the rule, and the config values it depends on (empty for older files)."""
    metadata = pq.read_schema(path).metadata or {}
    if _PROVENANCE_KEY in metadata:
        return json.loads(metadata[_PROVENANCE_KEY])
    if _META_KEY in metadata:
        return json.loads(metadata[_META_KEY]).get("provenance", {})
    return {}


TrialPoses = dict[str, SegmentPoses] | ValueError


def _poses_block(
    outcomes: Sequence[TrialPoses], first_trial: int, shapes: Mapping[str, tuple[int, int]]
) -> pa.Table:
    """Rows of trials ``first_trial, ...``: the trial, its error (null when fitted) and, per
    segment, its stored arrays (NaN for a trial that failed) and residual sum of squares."""
    errors = [str(o) if isinstance(o, ValueError) else None for o in outcomes]
    columns: dict[str, pa.Array] = {
        "trial": _from_numpy(np.arange(first_trial, first_trial + len(outcomes))),
        # Text even when no trial failed, so every block of a file has one schema.
        "error": _column(errors, "error")
        if any(error is not None for error in errors)
        else pa.nulls(len(errors), pa.string()),
    }
    for name, (n_frames, n_markers) in shapes.items():
        fitted = [None if isinstance(o, ValueError) else o[name] for o in outcomes]
        for field, shape_of in _POSE_ARRAYS.items():
            shape = shape_of(n_frames, n_markers)
            values = np.full((len(outcomes), *shape), np.nan)
            for trial, poses in enumerate(fitted):
                if poses is not None:
                    values[trial] = getattr(poses, field)
            size = int(np.prod(shape))
            columns[f"{name}/{field}"] = pa.FixedSizeListArray.from_arrays(
                _from_numpy(values.ravel()), size
            )
        columns[f"{name}/residual_ss"] = _from_numpy(
            np.array([np.nan if poses is None else poses.residual_ss for poses in fitted])
        )
        # How each fit ended, so that poses read back say whether they converged as the fit
        # did: 0 and NaN where nothing is recorded (a failed trial, poses built by hand).
        ended = [(0, np.nan) if p is None or p.iterations is None else _fit_end(p) for p in fitted]
        columns[f"{name}/iterations"] = _from_numpy(np.array([i for i, _ in ended], dtype=np.int64))
        columns[f"{name}/change_mm"] = _from_numpy(np.array([c for _, c in ended], dtype=float))
    return pa.table(columns)


def _fit_end(poses: SegmentPoses) -> tuple[int, float]:
    return int(poses.iterations), float(poses.change_mm)


def write_poses_blocks(
    path: str | Path,
    blocks: Iterable[Sequence[TrialPoses]],
    *,
    shapes: Mapping[str, tuple[int, ...]],
    provenance: Mapping[str, object] | None = None,
) -> None:
    """Write the pose fits of a condition's trials (from
    :func:`jointbench.estimators.segment_poses.trial_poses`), given as consecutive ``blocks``, to
    ``path``: one row per trial, one row group per block, so they are read back a block at a
    time (:func:`read_poses`). ``shapes`` are the dataset's, ``(n_trials, n_frames,
    n_markers, 3)`` per segment fitted. Values are stored exactly (float64)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    sizes = {name: (int(shape[1]), int(shape[2])) for name, shape in shapes.items()}
    metadata = {
        _POSES_KEY: json.dumps({"shapes": {k: list(v) for k, v in shapes.items()}}),
        _PROVENANCE_KEY: json.dumps(dict(provenance or {})),
    }
    writer, first_trial = None, 0
    try:
        for outcomes in blocks:
            table = _poses_block(outcomes, first_trial, sizes)
            table = table.replace_schema_metadata(metadata)
            if writer is None:
                writer = pq.ParquetWriter(path, table.schema)
            writer.write_table(table)
            first_trial += len(outcomes)
    finally:
        if writer is not None:
            writer.close()


def _poses_shapes(path: str | Path) -> dict[str, tuple[int, ...]]:
    metadata = pq.read_schema(path).metadata or {}
    if _POSES_KEY not in metadata:
        raise ValueError(f"{path} is not a jointbench poses file (no 'jointbench.poses' metadata)")
    shapes = json.loads(metadata[_POSES_KEY])["shapes"]
    return {name: tuple(shape) for name, shape in shapes.items()}


def _stored_poses(
    path: str | Path,
    trial: int,
    name: str,
    markers: np.ndarray,
    parts: tuple[np.ndarray, np.ndarray, np.ndarray],
    residual_ss: float,
    fit_end: tuple[int, float],
) -> SegmentPoses:
    """Segment ``name``'s poses of ``trial`` from their stored ``parts`` (``rotation``,
    ``translation``, ``body``) and residual sum of squares ``residual_ss`` [mm^2] on the
    dataset's ``markers`` ``(N, n, 3)`` [mm]; ``ValueError`` naming ``path``, the trial and the
    segment when they do not leave that residual on these markers: poses of other markers of
    the same shapes (another seed's dataset, say), which the shapes alone cannot tell.
    ``fit_end`` is how the fit ended, its iterations and last change [mm] (0 and NaN: not
    recorded)."""
    iterations, change_mm = fit_end
    recorded = {} if iterations == 0 else {"iterations": iterations, "change_mm": change_mm}
    try:
        return SegmentPoses(markers, *parts, residual_ss=residual_ss, **recorded)
    except AlteredPoses as error:
        raise ValueError(
            f"{path}: the poses of trial {trial}, segment {name!r}, leave a residual "
            f"of {error.found:.6g} mm^2 on the dataset's markers, not the "
            f"{error.stored:.6g} mm^2 they were stored with: they were fitted to other "
            "markers (a poses file of another dataset)"
        ) from error


@_names_unreadable_file
def read_poses(
    path: str | Path, first_trial: int, segments: Mapping[str, np.ndarray]
) -> list[TrialPoses]:
    """The stored pose fits of trials ``first_trial ..`` for a block of a dataset's
    ``segments`` (name -> markers ``(count, n_frames, n_markers, 3)`` [mm]): per trial, each
    segment's :class:`SegmentPoses`, or the ``ValueError`` its fit raised.

    ``ValueError`` naming the file when it holds other segments, shapes or trials than the
    block's (a poses file of another dataset).
    """
    shapes = _poses_shapes(path)
    count = next(iter(segments.values())).shape[0]
    for name, markers in segments.items():
        if name not in shapes or tuple(shapes[name][1:]) != markers.shape[1:]:
            raise ValueError(
                f"{path}: holds poses of {{name: shape}} = "
                f"{ {k: list(v) for k, v in shapes.items()} }, not of segment {name!r} shaped "
                f"{list(markers.shape[1:])} per trial: it was written for another dataset"
            )
    n_trials = next(iter(shapes.values()))[0]
    if first_trial + count > n_trials:
        raise ValueError(
            f"{path}: holds the poses of {n_trials} trials, not of trials "
            f"{first_trial}..{first_trial + count - 1}"
        )
    stored = pq.ParquetFile(path)
    rows = _read_rows(stored, first_trial, count, stored.schema_arrow.names)
    trials = _to_numpy(rows.column("trial"))
    if not np.array_equal(trials, np.arange(first_trial, first_trial + count)):
        raise ValueError(f"{path}: rows are not trials {first_trial}..{first_trial + count - 1}")
    arrays = {
        (name, field): _to_numpy(rows.column(f"{name}/{field}")).reshape(
            count, *shape_of(*markers.shape[1:3])
        )
        for name, markers in segments.items()
        for field, shape_of in _POSE_ARRAYS.items()
    }
    residuals = {name: _to_numpy(rows.column(f"{name}/residual_ss")) for name in segments}
    missing = [
        f"{name}/{field}"
        for name in segments
        for field in ("iterations", "change_mm")
        if f"{name}/{field}" not in rows.column_names
    ]
    if missing:
        raise ValueError(
            f"{path}: has no column {missing[0]!r}: it does not say how its pose fits ended "
            "(a file from an older jointbench); delete it and run again to refit"
        )
    ends = {
        name: (
            _to_numpy(rows.column(f"{name}/iterations")).tolist(),
            _to_numpy(rows.column(f"{name}/change_mm")).tolist(),
        )
        for name in segments
    }
    errors = rows.column("error").to_pylist()
    return [
        ValueError(error)
        if error is not None
        else {
            name: _stored_poses(
                path,
                first_trial + trial,
                name,
                markers[trial],
                tuple(arrays[name, field][trial] for field in _POSE_ARRAYS),
                residuals[name][trial],
                (ends[name][0][trial], ends[name][1][trial]),
            )
            for name, markers in segments.items()
        }
        for trial, error in enumerate(errors)
    ]
