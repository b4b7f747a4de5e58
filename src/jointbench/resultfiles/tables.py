"""Tables as files: CSV for machines, Markdown for readers, HTML for the report."""

from __future__ import annotations

from collections.abc import Mapping
from html import escape
from pathlib import Path

import pandas as pd

__all__ = ["html_table", "markdown_table", "output_paths", "write_tables"]


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


def html_table(frame: pd.DataFrame, *, title: str = "", note: str = "") -> str:
    """A small self-contained HTML page of ``frame``: what the report shows inline."""
    body = frame.to_html(index=False, na_rep="–", float_format=_format, border=0)
    return (
        "<!DOCTYPE html><html><head><meta charset='utf-8'><style>"
        "body{font-family:sans-serif;font-size:13px;margin:8px}"
        "table{border-collapse:collapse}th,td{padding:3px 8px;border-bottom:1px solid #ddd;"
        "text-align:left;vertical-align:top}th{background:#f3f3f3;position:sticky;top:0}"
        "p{max-width:60em}</style></head><body>"
        + (f"<h3>{escape(title)}</h3>" if title else "")
        + body
        + (f"<p>{escape(note)}</p>" if note else "")
        + "</body></html>\n"
    )


def write_tables(
    frame: pd.DataFrame, outputs: Mapping[str, str] | object, *, title: str = "", note: str = ""
) -> None:
    """Write ``frame`` as CSV, as Markdown (with an optional title and note) and, where an
    ``html`` output is given, as the HTML page the report shows."""
    csv_path, md_path = output_paths(outputs, ("csv", "md"))
    Path(csv_path).parent.mkdir(parents=True, exist_ok=True)
    frame.to_csv(csv_path, index=False)
    parts = [f"# {title}\n" if title else "", markdown_table(frame), f"\n{note}\n" if note else ""]
    Path(md_path).write_text("\n".join(p for p in parts if p))
    for html_path in output_paths(outputs, ("html",)):
        Path(html_path).write_text(html_table(frame, title=title, note=note))
