"""Shared figure helpers: one style per method, and saving figures reproducibly."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt

from jointbench.study.tables import output_paths

__all__ = ["method_style", "save_figure"]

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


def save_figure(fig: plt.Figure, outputs: Mapping[str, str] | object) -> None:
    """Save to every path given (``png`` and ``pdf`` keys or attributes) and close the figure."""
    for path in output_paths(outputs, ("png", "pdf")):
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=150, bbox_inches="tight", metadata=_stable_metadata(path))
    plt.close(fig)


def _stable_metadata(path: str) -> dict[str, object]:
    # Dated metadata would make identical results differ byte for byte between runs.
    if str(path).endswith(".pdf"):
        return {"CreationDate": None, "Producer": "jointbench"}
    return {"Software": "jointbench"}
