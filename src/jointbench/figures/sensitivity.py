"""Figures of the protocol ensemble (:mod:`jointbench.ensembles.sensitivity`): the papers' results
over plausible protocols, the default protocol drawn on top.

* paper A Fig 4 with bands: per marker set and noise, each method's mean CoR error against the
  RoM in the default protocol, and the band the drawn protocols span;
* paper B: how many of Table 1's cells are within tolerance over the drawn marker layouts, with
  the fitted default and every named layout marked and B2/B3 under each;
* paper C: the coverage of both Gauss–Markov variants against Nt over the drawn rig motions.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from jointbench.figures.common import method_style, pyplot, save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "BAND",
    "FIGURES",
    "coverage_figure",
    "draw_figures",
    "fig4_bands",
    "layout_counts",
    "layouts_figure",
]

#: The band drawn over the drawn protocols: these quantiles of their values at each point.
BAND = (0.1, 0.9)
#: Each study's figure, by output name.
FIGURES = {"cmc": "paper_a_fig4", "hinge": "paper_b_layouts", "hip": "paper_c_coverage"}
DEFAULT = "default"
TABLE1_PREFIX = "B-T1-"
CLAIMS = ("B2", "B3")
_BAND_TEXT = f"{BAND[0]:.0%}–{BAND[1]:.0%} of the drawn protocols"


def _is_draw(members: pd.Series) -> pd.Series:
    return members.astype(str).str.startswith("draw-")


def _band(values: pd.DataFrame, x: str, y: str) -> pd.DataFrame:
    """Per ``x``, the quantiles :data:`BAND` of ``y`` over the drawn members."""
    drawn = values[_is_draw(values["member"])]
    grouped = drawn.groupby(x)[y]
    return pd.DataFrame({"low": grouped.quantile(BAND[0]), "high": grouped.quantile(BAND[1])})


def fig4_bands(curves: pd.DataFrame) -> Figure:
    """Paper A Fig 4 over protocols: one panel per marker set (rows) and noise (columns), each
    method's mean CoR error [mm] against the RoM, the default protocol as a line and the
    :data:`BAND` of the drawn protocols shaded (``curves``: the members' condition means)."""
    plt = pyplot()
    sets, noises = sorted(curves["marker_set"].unique()), sorted(curves["noise_mm"].unique())
    fig, axes = plt.subplots(
        len(sets),
        len(noises),
        figsize=(3.2 * len(noises), 2.8 * len(sets)),
        sharex=True,
        squeeze=False,
        layout="constrained",
    )
    for (row, marker_set), (col, noise) in (
        (r, c) for r in enumerate(sets) for c in enumerate(noises)
    ):
        ax = axes[row][col]
        cell = curves[(curves["marker_set"] == marker_set) & (curves["noise_mm"] == noise)]
        for method, part in cell.groupby("method", sort=True):
            style = method_style(str(method))
            band = _band(part, "rom_deg", "mean_error_mm")
            ax.fill_between(band.index, band["low"], band["high"], color=style["color"], alpha=0.2)
            default = part[part["member"] == DEFAULT].sort_values("rom_deg")
            ax.plot(default["rom_deg"], default["mean_error_mm"], label=str(method), **style)
        ax.set_yscale("log")
        ax.set_title(f"{marker_set} set, noise {noise:g} mm", fontsize=9)
        if row == len(sets) - 1:
            ax.set_xlabel("RoM [°]")
        if col == 0:
            ax.set_ylabel("mean CoR error [mm]")
    axes[0][0].legend(fontsize=7)
    fig.suptitle(f"Paper A Fig 4 over protocols: default (lines), {_BAND_TEXT} (bands)")
    return fig


def layout_counts(rows: pd.DataFrame) -> pd.DataFrame:
    """Per hinge member: how many of Table 1's compared cells are within tolerance, of how
    many, and the status of each of :data:`CLAIMS` (``rows``: the members' comparison rows)."""
    cells = rows[rows["id"].astype(str).str.startswith(TABLE1_PREFIX)]
    compared = cells[cells["status"].isin(("reproduced", "not reproduced"))]
    counts = compared.groupby("member", sort=False)["status"].agg(
        within=lambda s: int((s == "reproduced").sum()), cells="size"
    )
    claims = rows[rows["id"].isin(CLAIMS)].pivot_table(
        index="member", columns="id", values="status", aggfunc="first"
    )
    return counts.join(claims).reset_index()


def _claims_text(row: pd.Series) -> str:
    return ", ".join(f"{claim} {row.get(claim, 'not measured')}" for claim in CLAIMS)


def layouts_figure(counts: pd.DataFrame, named: Sequence[str]) -> Figure:
    """Paper B over marker layouts: a histogram of the cells within tolerance over the drawn
    layouts, split by whether B2 and B3 both reproduce, the default (fitted) layout and each
    of ``named`` marked with B2 and B3 under it."""
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7.0, 3.6), layout="constrained")
    drawn = counts[_is_draw(counts["member"])]
    both = (drawn.get("B2") == "reproduced") & (drawn.get("B3") == "reproduced")
    total = int(counts["cells"].max())
    bins = np.arange(-0.5, total + 1.5, max(1, total // 24))
    ax.hist(
        [drawn.loc[both, "within"], drawn.loc[~both, "within"]],
        bins=bins,
        stacked=True,
        color=["tab:green", "tab:grey"],
        label=["drawn: B2 and B3 reproduced", "drawn: B2 or B3 not reproduced"],
    )
    marked = counts[counts["member"].isin([DEFAULT, *named])]
    for index, row in enumerate(marked.itertuples(index=False)):
        series = pd.Series(row._asdict())
        name = "fitted (default)" if row.member == DEFAULT else str(row.member)
        ax.axvline(row.within, color=f"C{index}", lw=2)
        ax.annotate(
            f"{name}: {row.within}/{row.cells}\n{_claims_text(series)}",
            (row.within, 1.0 - 0.17 * index),
            xycoords=("data", "axes fraction"),
            va="top",
            ha="right",
            fontsize=7,
            color=f"C{index}",
        )
    ax.set_xlabel(f"Table 1 cells within tolerance (of {total})")
    ax.set_ylabel("drawn layouts")
    ax.set_title("Paper B over marker layouts within the anatomical bounds", fontsize=10)
    ax.legend(fontsize=7, loc="upper left")
    return fig


def coverage_figure(curves: pd.DataFrame) -> Figure:
    """Paper C over rig motions: per Gauss–Markov variant, the share of trials whose true
    centre is inside the predicted 95 % ellipsoid against Nt, the default motion as a line and
    the :data:`BAND` of the drawn motions shaded (``curves``: the members' calibration
    tables)."""
    plt = pyplot()
    methods = list(dict.fromkeys(curves["method"]))
    fig, axes = plt.subplots(
        1,
        len(methods),
        figsize=(4.2 * len(methods), 3.4),
        sharey=True,
        squeeze=False,
        layout="constrained",
    )
    for ax, method in zip(axes[0], methods, strict=True):
        part = curves[curves["method"] == method]
        style = method_style(method)
        band = _band(part, "n_frames", "inside_95")
        ax.fill_between(band.index, band["low"], band["high"], color=style["color"], alpha=0.25)
        default = part[part["member"] == DEFAULT].sort_values("n_frames")
        ax.plot(default["n_frames"], default["inside_95"], label="default motion", **style)
        ax.axhline(0.95, color="k", lw=0.8, label="0.95, the nominal coverage")
        ax.set_xscale("log")
        ax.set_xlabel("Nt (frames)")
        ax.set_title(method, fontsize=10)
    axes[0][0].set_ylabel("share inside the 95 % ellipsoid")
    axes[0][0].legend(fontsize=7)
    fig.suptitle(f"Paper C coverage over rig motions: {_BAND_TEXT} shaded")
    return fig


def _read(paths: Sequence[str]) -> pd.DataFrame:
    frames = [pd.read_csv(path) for path in paths]
    return pd.concat([f for f in frames if not f.empty], ignore_index=True)


def draw_figures(
    rows: Sequence[str], curves: Sequence[str], named: Sequence[str], outputs: Mapping
) -> None:
    """Read the members' rows and curves and save each figure of :data:`FIGURES` whose study
    is among them to ``outputs[f"{name}_png"]`` and ``…_pdf``."""
    all_rows, all_curves = _read(rows), _read(curves)
    studies = set(all_rows["study"])
    drawers = {
        "cmc": lambda: fig4_bands(all_curves[all_curves["study"] == "cmc"]),
        "hinge": lambda: layouts_figure(
            layout_counts(all_rows[all_rows["study"] == "hinge"]), named
        ),
        "hip": lambda: coverage_figure(all_curves[all_curves["study"] == "hip"]),
    }
    for study, name in FIGURES.items():
        if study in studies:
            save_figure(
                drawers[study](), {kind: outputs[f"{name}_{kind}"] for kind in ("png", "pdf")}
            )
