"""Tables as files: CSV for machines, Markdown for readers, HTML for the report.

The CSV keeps each column's name and full precision, for the programs (and the report's
headlines) that read it; the Markdown and the HTML are for people: headers in words with units
and every cell written by :mod:`jointbench.resultfiles.formatting`, the one formatting of the
project.
"""

from __future__ import annotations

from collections.abc import Mapping
from html import escape
from pathlib import Path

import pandas as pd

from jointbench.resultfiles.formatting import format_column, header, is_published_column

__all__ = ["for_people", "html_table", "markdown_table", "output_paths", "write_tables"]


def output_paths(outputs: Mapping[str, str] | object, keys: tuple[str, ...]) -> list[str]:
    """The paths among ``outputs`` (a mapping or Snakemake's named list) under ``keys``."""
    if isinstance(outputs, Mapping):
        return [outputs[k] for k in keys if k in outputs]
    return [getattr(outputs, k) for k in keys if hasattr(outputs, k)]


def for_people(frame: pd.DataFrame, headers: Mapping[str, str] | None = None) -> pd.DataFrame:
    """``frame`` as people read it: every cell as text (:func:`format_column`, published
    columns exactly as published) under headers in words with units (:func:`header`;
    ``headers`` gives a table's own); ``ValueError`` when two columns would share a header."""
    shown = {
        header(column, headers): format_column(
            frame[column].tolist(), published=is_published_column(column)
        )
        for column in frame.columns
    }
    if len(shown) != len(frame.columns):
        raise ValueError(f"columns {list(frame.columns)} give the same header twice")
    return pd.DataFrame(shown, index=frame.index)


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def markdown_table(frame: pd.DataFrame, headers: Mapping[str, str] | None = None) -> str:
    """A GitHub-flavoured Markdown table of ``frame`` as people read it (:func:`for_people`)."""
    shown = for_people(frame, headers)
    head = "| " + " | ".join(_cell(c) for c in shown.columns) + " |"
    rule = "|" + "|".join("---" for _ in shown.columns) + "|"
    rows = ["| " + " | ".join(_cell(v) for v in row) + " |" for row in shown.itertuples(False)]
    return "\n".join([head, rule, *rows]) + "\n"


def html_table(
    frame: pd.DataFrame,
    *,
    title: str = "",
    note: str = "",
    headers: Mapping[str, str] | None = None,
) -> str:
    """A small self-contained HTML page of ``frame`` as people read it: what the report shows
    inline."""
    body = for_people(frame, headers).to_html(index=False, border=0)
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
    frame: pd.DataFrame,
    outputs: Mapping[str, str] | object,
    *,
    title: str = "",
    note: str = "",
    headers: Mapping[str, str] | None = None,
) -> None:
    """Write ``frame`` as CSV, as Markdown (with an optional title and note) and, where an
    ``html`` output is given, as the HTML page the report shows; ``headers`` maps column names
    to a table's own headers for people."""
    csv_path, md_path = output_paths(outputs, ("csv", "md"))
    Path(csv_path).parent.mkdir(parents=True, exist_ok=True)
    frame.to_csv(csv_path, index=False)
    parts = [
        f"# {title}\n" if title else "",
        markdown_table(frame, headers),
        f"\n{note}\n" if note else "",
    ]
    Path(md_path).write_text("\n".join(p for p in parts if p))
    for html_path in output_paths(outputs, ("html",)):
        Path(html_path).write_text(html_table(frame, title=title, note=note, headers=headers))
