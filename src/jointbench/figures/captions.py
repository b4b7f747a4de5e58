"""Report captions: a fixed description per output plus its headline agreement from the tables."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path

import pandas as pd
import yaml

__all__ = ["headline", "write_captions"]


def _claims(table: pd.DataFrame) -> str:
    tested = table[table["status"] != "not applicable"]
    return (
        f"{int((tested['status'] == 'reproduced').sum())} of {len(tested)} claims "
        "reproduced (criteria and reasons in the claims table)."
    )


def _table1_b(table: pd.DataFrame) -> str:
    return f"{int(table['within_tolerance'].sum())} of {len(table)} Table 1 cells within tolerance."


def _table2_a(table: pd.DataFrame) -> str:
    speedup = table.set_index("method")["speedup_vs_paper"]
    return (
        "Speed-up over the paper's MATLAB times: "
        + ", ".join(f"{m} {s:.0f}×" for m, s in speedup.items())
        + "."
    )


def _calibration_c(table: pd.DataFrame) -> str:
    parts = []
    for method, part in table.groupby("method", sort=False):
        ok = part[part["calibrated"].astype(str) == "True"]["n_frames"].tolist()
        parts.append(
            f"{method}: share inside {part['inside_95'].min():.2f}–{part['inside_95'].max():.2f}, "
            f"consistent with 95 % at Nt = {', '.join(map(str, ok)) or 'none'}"
        )
    return "; ".join(parts) + "."


def _extended(table: pd.DataFrame) -> str:
    best = table[table["best"].astype(str) == "True"]["method"].value_counts()
    # The condition columns come first, before "method".
    conditions = table.groupby(list(table.columns[: table.columns.get_loc("method")])).ngroups
    leaders = ", ".join(f"{m} ({n})" for m, n in best.items())
    return f"best mean error per condition, out of {conditions} conditions: {leaders}."


def _comparison(table: pd.DataFrame) -> str:
    counts = table["status"].value_counts()
    return (
        ", ".join(
            f"{counts.get(s, 0)} {s}" for s in ("reproduced", "not reproduced", "not applicable")
        )
        + "."
    )


# output name -> (table it summarises, how)
_HEADLINES: dict[str, tuple[str, Callable[[pd.DataFrame], str]]] = {
    "paper_a_fig4": ("paper_a_claims", _claims),
    "paper_a_fig3": ("paper_a_claims", _claims),
    "paper_a_table2": ("paper_a_table2", _table2_a),
    "paper_a_claims": ("paper_a_claims", _claims),
    "paper_b_table1": ("paper_b_table1", _table1_b),
    "paper_b_fig5": ("paper_b_table1", _table1_b),
    "paper_b_fig2": ("paper_b_claims", _claims),
    "paper_b_claims": ("paper_b_claims", _claims),
    "paper_c_table1": ("paper_c_claims", _claims),
    "paper_c_calibration": ("paper_c_calibration", _calibration_c),
    "paper_c_uncertainty": ("paper_c_calibration", _calibration_c),
    "paper_c_claims": ("paper_c_claims", _claims),
    "published_comparison": ("published_comparison", _comparison),
}


def headline(name: str, tables: Mapping[str, pd.DataFrame]) -> str:
    """The headline agreement of output ``name`` from the tables it summarises."""
    if name.startswith("extended_"):
        return _extended(tables[name.removesuffix("_figure")])
    source, summarise = _HEADLINES[name]
    return summarise(tables[source])


def write_captions(descriptions: str | Path, tables: Mapping[str, str], outputs) -> None:
    """One reStructuredText caption per output: description, then the headline agreement."""
    texts = yaml.safe_load(Path(descriptions).read_text())
    loaded = {name: pd.read_csv(path) for name, path in tables.items()}
    for path in outputs:
        name = Path(path).stem
        body = texts[name]["text"].strip()
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        Path(path).write_text(f"{body}\n\n**Headline:** {headline(name, loaded)}\n")
