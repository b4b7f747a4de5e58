"""Tables as files: CSV for machines, GitHub-flavoured Markdown for readers."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import pandas as pd

__all__ = ["markdown_table", "output_paths", "write_tables"]


def output_paths(outputs: Mapping[str, str] | object, keys: tuple[str, ...]) -> list[str]:
    """The paths among ``outputs`` (a mapping or Snakemake's named list) under ``keys``."""
    if isinstance(outputs, Mapping):
        return [outputs[k] for k in keys if k in outputs]
    return [getattr(outputs, k) for k in keys if hasattr(outputs, k)]


def _format(value: object) -> str:
    if isinstance(value, float):
        if pd.isna(value):
            return "–"
        return f"{value:.4g}" if abs(value) < 1e-2 or abs(value) >= 1e4 else f"{value:.2f}"
    return str(value).replace("|", "\\|").replace("\n", " ")


def markdown_table(frame: pd.DataFrame) -> str:
    """A GitHub-flavoured Markdown table of ``frame`` (floats to 2 decimals or 4 significant)."""
    header = "| " + " | ".join(map(str, frame.columns)) + " |"
    rule = "|" + "|".join("---" for _ in frame.columns) + "|"
    rows = ["| " + " | ".join(_format(v) for v in row) + " |" for row in frame.itertuples(False)]
    return "\n".join([header, rule, *rows]) + "\n"


def write_tables(
    frame: pd.DataFrame, outputs: Mapping[str, str] | object, *, title: str = "", note: str = ""
) -> None:
    """Write ``frame`` as CSV and as Markdown (with an optional title and note)."""
    csv_path, md_path = output_paths(outputs, ("csv", "md"))
    Path(csv_path).parent.mkdir(parents=True, exist_ok=True)
    frame.to_csv(csv_path, index=False)
    parts = [f"# {title}\n" if title else "", markdown_table(frame), f"\n{note}\n" if note else ""]
    Path(md_path).write_text("\n".join(p for p in parts if p))
