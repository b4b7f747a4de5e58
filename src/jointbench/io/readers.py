"""Readers for C3D, TRC and the long CSV ``frame,marker,x,y,z``; all give a :class:`Recording`."""

from __future__ import annotations

from pathlib import Path

import ezc3d
import numpy as np
import pandas as pd

from jointbench.io.recording import Recording

__all__ = ["UNIT_TO_MM", "read", "read_c3d", "read_csv", "read_trc"]

UNIT_TO_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "meters": 1000.0, "millimeters": 1.0}


def _to_mm(unit: str, path: Path) -> float:
    key = unit.strip().lower()
    if key not in UNIT_TO_MM:
        raise ValueError(
            f"{path}: unknown point unit {unit!r}; known: {', '.join(sorted(UNIT_TO_MM))}"
        )
    return UNIT_TO_MM[key]


def _check_file(path: str | Path) -> Path:
    path = Path(path)
    if not path.exists():
        raise ValueError(f"{path}: no such file")
    if not path.is_file():
        raise ValueError(f"{path}: is a directory, not a marker file")
    return path


def read(path: str | Path) -> Recording:
    """Read a recording by its extension: ``.c3d``, ``.trc`` or ``.csv``."""
    path = _check_file(path)
    readers = {".c3d": read_c3d, ".trc": read_trc, ".csv": read_csv}
    reader = readers.get(path.suffix.lower())
    if reader is None:
        raise ValueError(
            f"{path}: unknown file type {path.suffix!r}; jointbench reads .c3d, .trc and .csv"
        )
    return reader(path)


def read_c3d(path: str | Path) -> Recording:
    """A C3D file via ``ezc3d``: POINT labels, rate and units; negative residuals are gaps."""
    path = _check_file(path)
    try:
        c3d = ezc3d.c3d(str(path))
    except Exception as error:  # ezc3d raises bare RuntimeError/IOError for any bad file
        raise ValueError(f"{path}: not a readable C3D file ({error})") from None
    point = c3d["parameters"]["POINT"]
    labels = list(point["LABELS"]["value"])
    for extra in ("LABELS2", "LABELS3"):
        if extra in point:
            labels += list(point[extra]["value"])
    points = c3d["data"]["points"]
    labels = [label.strip() for label in labels[: points.shape[1]]]
    units = point["UNITS"]["value"][0] if "UNITS" in point and point["UNITS"]["value"] else "mm"
    markers = np.transpose(points[:3], (2, 1, 0)) * _to_mm(units, path)
    residuals = c3d["data"]["meta_points"]["residuals"]
    if residuals.size:
        markers[np.transpose(residuals[0]) < 0] = np.nan
    rate = float(c3d["header"]["points"]["frame_rate"])
    return Recording(tuple(labels), markers, rate if rate > 0 else None, str(path))


def read_trc(path: str | Path) -> Recording:
    """A TRC file (OpenSim / Motion Analysis): header keys ``DataRate``, ``Units``, then
    ``Frame#  Time  label  …`` with one ``X Y Z`` triple per label; empty fields are gaps."""
    path = _check_file(path)
    lines = path.read_text(errors="replace").splitlines()
    if len(lines) < 6:
        raise ValueError(f"{path}: too short for a TRC file (needs 5 header lines and data)")
    keys, values = lines[1].split("\t"), lines[2].split("\t")
    header = {key.strip(): value.strip() for key, value in zip(keys, values, strict=False)}
    if "Units" not in header:
        raise ValueError(f"{path}: TRC header has no 'Units' (line 2 keys: {keys})")
    names = [name.strip() for name in lines[3].split("\t")[2:]]
    labels = [name for name in names if name]
    rows = [line.split("\t") for line in lines[5:] if line.strip()]
    width = 2 + 3 * len(labels)
    markers = np.full((len(rows), len(labels) * 3), np.nan)
    for i, row in enumerate(rows):
        fields = row[2:width]
        for j, text in enumerate(fields):
            text = text.strip()
            if text:
                try:
                    markers[i, j] = float(text)
                except ValueError:
                    raise ValueError(
                        f"{path}: frame {i}, marker {labels[j // 3]}: {text!r} is not a number"
                    ) from None
    markers = markers.reshape(len(rows), len(labels), 3) * _to_mm(header["Units"], path)
    rate = header.get("DataRate")
    return Recording(tuple(labels), markers, float(rate) if rate else None, str(path))


def read_csv(path: str | Path) -> Recording:
    """The long CSV ``frame,marker,x,y,z`` [mm], one row per sample, rows in any order.

    A sample absent from the file is a gap; a (frame, marker) pair given twice is an error.
    """
    path = _check_file(path)
    try:
        table = pd.read_csv(path)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as error:
        raise ValueError(f"{path}: not a readable CSV file ({error})") from None
    missing = {"frame", "marker", "x", "y", "z"} - set(table.columns)
    if missing:
        raise ValueError(f"{path}: missing columns {sorted(missing)}")
    table["marker"] = table["marker"].astype(str)
    twice = table.duplicated(["frame", "marker"], keep=False)
    if twice.any():
        first = table[twice].iloc[0]
        raise ValueError(
            f"{path}: frame {first['frame']}, marker {first['marker']} has {int(twice.sum())} "
            "rows for the same (frame, marker); each sample must appear once"
        )
    frames = np.sort(table["frame"].unique())
    labels = sorted(table["marker"].unique(), key=_natural)
    row = np.searchsorted(frames, table["frame"].to_numpy())
    column = {label: i for i, label in enumerate(labels)}
    markers = np.full((len(frames), len(labels), 3), np.nan)
    markers[row, table["marker"].map(column).to_numpy()] = table[["x", "y", "z"]].to_numpy(float)
    return Recording(tuple(labels), markers, None, str(path))


def _natural(label: str) -> tuple:
    """Sort key placing ``"2"`` before ``"10"`` (marker names written as integers)."""
    return (0, int(label), "") if label.lstrip("-").isdigit() else (1, 0, label)
