"""Shared output helpers: figure saving, tables as CSV + Markdown, method styles."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import yaml

__all__ = [
    "equal_3d_limits",
    "evaluate_claims",
    "markdown_table",
    "median_trial",
    "method_style",
    "read_published",
    "save_figure",
    "write_tables",
]

# Fixed colours per method so every figure of the benchmark reads the same way.
_STYLES = {
    "NM": ("#1b9e77", "o"),
    "LS": ("#d95f02", "s"),
    "BC": ("#7570b3", "^"),
    "MA": ("#e7298a", "D"),
    "IS": ("#66a61e", "v"),
    "SCoRE": ("#a6761d", "P"),
    "planar": ("#d95f02", "s"),
    "radial": ("#7570b3", "^"),
    "combined": ("#1b9e77", "o"),
    "SARA": ("#a6761d", "P"),
    "gauss-markov": ("#1b9e77", "o"),
    "analytic": ("#d95f02", "s"),
}


def method_style(method: str, index: int = 0) -> dict[str, object]:
    """Matplotlib line style for a method; unknown (user) methods cycle through the palette."""
    if method in _STYLES:
        color, marker = _STYLES[method]
    else:
        color, marker = plt.get_cmap("tab10")(index % 10), "X"
    return {"color": color, "marker": marker}


def equal_3d_limits(ax, points: np.ndarray, margin: float = 0.08) -> None:
    """Same scale on x, y and z of a 3-D axes spanning ``points`` ``(n, 3)``, so distances
    and angles in the plot are true ones (matplotlib otherwise stretches each axis to fill)."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    low, high = np.nanmin(points, axis=0), np.nanmax(points, axis=0)
    centre, half = (low + high) / 2, (high - low).max() / 2 * (1 + margin)
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1))


def median_trial(errors: pd.Series) -> int:
    """The trial (index of ``errors``) with the median error; for an even count the lower of
    the two middle ones, so it is a real trial. Equal errors are ordered by trial number.
    NaN errors are left out."""
    finite = errors.dropna()
    if finite.empty:
        raise ValueError("no trial with a finite error to choose from")
    ordered = sorted(zip(finite.to_numpy(), finite.index, strict=True))
    return int(ordered[(len(ordered) - 1) // 2][1])


def save_figure(fig: plt.Figure, outputs: Mapping[str, str] | object) -> None:
    """Save to every path given (``png`` and ``pdf`` keys or attributes) and close the figure."""
    for path in _paths(outputs, ("png", "pdf")):
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=150, bbox_inches="tight", metadata=_stable_metadata(path))
    plt.close(fig)


def _stable_metadata(path: str) -> dict[str, object]:
    # Dated metadata would make identical results differ byte for byte between runs.
    if str(path).endswith(".pdf"):
        return {"CreationDate": None, "Producer": "jointbench"}
    return {"Software": "jointbench"}


def _paths(outputs, keys) -> list[str]:
    if isinstance(outputs, Mapping):
        return [outputs[k] for k in keys if k in outputs]
    return [getattr(outputs, k) for k in keys if hasattr(outputs, k)]


def _format(value: object) -> str:
    if isinstance(value, float):
        if pd.isna(value):
            return "–"
        return f"{value:.4g}" if abs(value) < 1e-2 or abs(value) >= 1e4 else f"{value:.2f}"
    return str(value).replace("|", "\\|")


def markdown_table(frame: pd.DataFrame) -> str:
    """A GitHub-flavoured Markdown table of ``frame`` (floats to 2 decimals or 4 significant).

    Column headers are ``frame.attrs["labels"][column]`` where a table builder gave readable
    ones, so the Markdown reads well while the CSV keeps short, stable keys for programs.
    """
    labels = frame.attrs.get("labels", {})
    header = "| " + " | ".join(str(labels.get(c, c)) for c in frame.columns) + " |"
    rule = "|" + "|".join("---" for _ in frame.columns) + "|"
    rows = ["| " + " | ".join(_format(v) for v in row) + " |" for row in frame.itertuples(False)]
    return "\n".join([header, rule, *rows]) + "\n"


def write_tables(
    frame: pd.DataFrame, outputs: Mapping[str, str] | object, *, title: str = "", note: str = ""
) -> None:
    """Write ``frame`` as CSV and as Markdown (with an optional title and note)."""
    csv_path, md_path = _paths(outputs, ("csv", "md"))
    Path(csv_path).parent.mkdir(parents=True, exist_ok=True)
    frame.to_csv(csv_path, index=False)
    parts = [f"# {title}\n" if title else "", markdown_table(frame), f"\n{note}\n" if note else ""]
    Path(md_path).write_text("\n".join(p for p in parts if p))


def read_published(path: str | Path) -> dict:
    """A paper's published values and claims (``config/published/*.yaml``), schema-checked."""
    from jointbench.study.published import validate_published

    document = yaml.safe_load(Path(path).read_text())
    validate_published(document)
    return document


def _published_text(value: object) -> str:
    if isinstance(value, Mapping):
        return ", ".join(f"{k} {v}" for k, v in value.items())
    return str(value)


def evaluate_claims(specs, evaluators: Mapping, *data) -> pd.DataFrame:
    """One row per published claim: id, claim, published, reproduced, status, criterion.

    ``evaluators[id](*data, spec)`` returns ``(reproduced_text, holds)``. A claim whose data are
    missing from the run (e.g. a method switched off) is ``not applicable``.
    """
    rows = []
    for spec in specs:
        try:
            reproduced, holds = evaluators[spec["id"]](*data, spec)
            status = "reproduced" if holds else "not reproduced"
        except (KeyError, IndexError, ValueError) as missing:
            reproduced, status = f"cannot evaluate: {missing}", "not applicable"
        rows.append(
            {
                "id": spec["id"],
                "claim": spec["claim"],
                "published": _published_text(spec["published"]),
                "reproduced": reproduced,
                "status": status,
                "criterion": spec["criterion"],
            }
        )
    return pd.DataFrame(rows)
