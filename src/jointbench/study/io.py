"""Datasets and estimates on disk (parquet).

Dataset files are long format, one row per (segment, trial, frame, marker) with columns
``segment, trial, frame, marker, x, y, z`` [mm]; the study, condition, ground truth and generator
parameters are JSON in the parquet metadata under the key ``jointbench``.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from jointbench.simulate import Trials

__all__ = [
    "read_dataset",
    "read_metadata",
    "read_table",
    "read_trial_numbers",
    "write_dataset",
    "write_table",
]

_META_KEY = b"jointbench"


def _names_unreadable_file(read: Callable) -> Callable:
    """Turn pyarrow's errors on a missing, truncated or corrupt file (``ArrowInvalid: Parquet
    magic bytes not found``, which names no file) into a ``ValueError`` naming the file and the
    command that regenerates it, with everything downstream of it."""

    @functools.wraps(read)
    def reading(path, *args, **kwargs):
        try:
            return read(path, *args, **kwargs)
        except (pa.ArrowException, OSError) as error:
            raise ValueError(
                f"{path}: cannot be read as parquet ({type(error).__name__}: {error}); the file "
                f"is missing, truncated or corrupt. Regenerate it and what depends on it with: "
                f"snakemake -j2 --forcerun {path}"
            ) from error

    return reading


def _long_table(trials: Trials) -> pa.Table:
    columns: dict[str, list[np.ndarray]] = {k: [] for k in ("segment", "trial", "frame", "marker")}
    coords: list[np.ndarray] = []
    for name, markers in trials.segments.items():
        n_trials, n_frames, n_markers, _ = markers.shape
        trial, frame, marker = np.meshgrid(
            np.arange(n_trials), np.arange(n_frames), np.arange(n_markers), indexing="ij"
        )
        columns["segment"].append(np.full(trial.size, name))
        columns["trial"].append(trial.ravel())
        columns["frame"].append(frame.ravel())
        columns["marker"].append(marker.ravel())
        coords.append(markers.reshape(-1, 3))
    xyz = np.concatenate(coords)
    data = {key: np.concatenate(parts) for key, parts in columns.items()}
    data["segment"] = pa.array(data["segment"]).dictionary_encode()
    for axis, name in enumerate("xyz"):
        data[name] = xyz[:, axis]
    return pa.table(data)


def write_dataset(
    path: str | Path, trials: Trials, *, study: str, condition: Mapping[str, object]
) -> None:
    """Write ``trials`` to ``path`` with study, condition, truth and parameters as metadata."""
    table = _long_table(trials)
    metadata = {
        "study": study,
        "condition": dict(condition),
        "truth": trials.truth,
        "parameters": trials.parameters,
    }
    table = table.replace_schema_metadata({_META_KEY: json.dumps(metadata).encode()})
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    pq.write_table(table, path)


@_names_unreadable_file
def read_metadata(path: str | Path) -> dict:
    """The ``jointbench`` metadata of a dataset file."""
    metadata = pq.read_schema(path).metadata or {}
    if _META_KEY not in metadata:
        raise ValueError(f"{path} is not a jointbench dataset (no 'jointbench' metadata)")
    return json.loads(metadata[_META_KEY])


@_names_unreadable_file
def read_trial_numbers(path: str | Path) -> np.ndarray:
    """The sorted trial numbers of a dataset file (reads the ``trial`` column only)."""
    trials = pq.read_table(path, columns=["trial"]).column("trial")
    return np.sort(pc.unique(trials).to_numpy())


@_names_unreadable_file
def read_dataset(path: str | Path) -> tuple[Trials, dict]:
    """Read a dataset file back into :class:`Trials` and its metadata."""
    metadata = read_metadata(path)
    frame = pq.read_table(path).to_pandas()
    segments = {}
    for name, part in frame.groupby("segment", observed=True, sort=False):
        part = part.sort_values(["trial", "frame", "marker"])
        shape = (part["trial"].nunique(), part["frame"].nunique(), part["marker"].nunique(), 3)
        segments[str(name)] = part[["x", "y", "z"]].to_numpy().reshape(shape)
    trials = Trials(segments=segments, truth=metadata["truth"], parameters=metadata["parameters"])
    return trials, metadata


@_names_unreadable_file
def read_table(path: str | Path) -> pd.DataFrame:
    """A results table (estimates, collected results) written by :func:`write_table`."""
    return pd.read_parquet(path)


def write_table(frame: pd.DataFrame, path: str | Path) -> None:
    """Write a results table to parquet, creating the directory."""
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    frame.to_parquet(path, index=False)
