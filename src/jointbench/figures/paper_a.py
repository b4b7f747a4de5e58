"""Paper A (Chang & Pollard 2007, centre of rotation): drawing Fig 3 and Fig 4, building Table 2.

Every function takes the collected ``cmc`` results (one row per marker set, RoM, noise, trial
and method) and returns a table or a figure; the paper's declaration, its published values and
claims are in :mod:`jointbench.papers.paper_a`.
"""

from __future__ import annotations

from collections.abc import Mapping

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from jointbench.figures.common import method_style

__all__ = [
    "CONDITION",
    "PAPER_METHODS",
    "bc_converged",
    "condition_means",
    "fig3",
    "fig4",
    "table2",
]

PAPER_METHODS = ("MA", "LS", "IS", "BC", "NM")
SPHERE_FITS = ("LS", "NM", "BC", "IS")
CONDITION = ["marker_set", "rom_deg", "noise_mm"]


def bc_converged(collected: pd.DataFrame) -> pd.DataFrame:
    """Rows of the trials in which BC converged, as paper A averaged (Fig 4 caption).

    Without BC in the run there is nothing to filter by and every trial is kept.
    """
    if "BC" not in set(collected["method"]):
        return collected
    bc = collected[(collected["method"] == "BC") & collected["converged"]]
    keep = bc[[*CONDITION, "trial"]].drop_duplicates()
    return collected.merge(keep, on=[*CONDITION, "trial"], how="inner")


def condition_means(collected: pd.DataFrame, methods=PAPER_METHODS) -> pd.DataFrame:
    """Mean error per condition and method over BC-converged trials, with the trial count.

    Columns: marker_set, rom_deg, noise_mm, method, mean_error_mm, n_trials.
    """
    rows = bc_converged(collected[collected["method"].isin(methods)])
    grouped = rows.groupby([*CONDITION, "method"], observed=True)["error_mm"]
    return grouped.agg(mean_error_mm="mean", n_trials="size").reset_index()


def _wide(means: pd.DataFrame) -> pd.DataFrame:
    return means.pivot_table(index=CONDITION, columns="method", values="mean_error_mm")


def fig4(collected: pd.DataFrame) -> plt.Figure:
    """Mean CoR error vs RoM, one panel per marker set (rows) and noise level (columns)."""
    means = condition_means(collected)
    sets = sorted(means["marker_set"].unique(), key=lambda s: "MH".find(s))
    noises = sorted(means["noise_mm"].unique())
    n_total = collected["trial"].nunique()
    fig, axes = plt.subplots(
        len(sets),
        len(noises),
        figsize=(3.4 * len(noises), 3.0 * len(sets)),
        sharex=True,
        sharey=True,
        squeeze=False,
    )
    for row, marker_set in enumerate(sets):
        for col, noise in enumerate(noises):
            ax = axes[row, col]
            cell = means[(means["marker_set"] == marker_set) & (means["noise_mm"] == noise)]
            for index, method in enumerate(PAPER_METHODS):
                line = cell[cell["method"] == method].sort_values("rom_deg")
                if line.empty:
                    continue
                ax.plot(
                    line["rom_deg"],
                    line["mean_error_mm"],
                    label=method,
                    lw=1.5,
                    ms=5,
                    **method_style(method, index),
                )
            counts = cell.groupby("rom_deg")["n_trials"].max()
            for rom, count in counts.items():
                if count < n_total:
                    top = cell[cell["rom_deg"] == rom]["mean_error_mm"].max()
                    ax.annotate(
                        f"n={count}",
                        (rom, top),
                        textcoords="offset points",
                        xytext=(4, 4),
                        fontsize=7,
                    )
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.set_xticks(sorted(means["rom_deg"].unique()))
            ax.xaxis.set_major_formatter(plt.FuncFormatter(lambda v, _: f"±{v:g}°"))
            ax.xaxis.set_minor_formatter(plt.NullFormatter())
            ax.grid(True, which="both", alpha=0.3)
            ax.set_title(f"({'ab'[row]}) {marker_set} set, noise SD {noise:g} mm", fontsize=9)
            if col == 0:
                ax.set_ylabel("mean CoR error (mm)")
            if row == len(sets) - 1:
                ax.set_xlabel("RoM")
    axes[0, -1].legend(fontsize=8, loc="upper right")
    fig.suptitle(
        "Paper A Fig 4 reproduced: mean CoR error over the trials where BC converged "
        f"(n shown where fewer than {n_total})",
        fontsize=10,
    )
    fig.tight_layout()
    return fig


def fig3(
    markers: np.ndarray, truth: np.ndarray, errors: pd.DataFrame, published: Mapping
) -> plt.Figure:
    """One M-set, ±5°, 1.0 mm trial: trajectories, true CoR, every method's estimate and error.

    ``markers`` ``(n_frames, n_markers, 3)`` [mm]; ``errors`` has columns method, center_x/y/z,
    error_mm for that trial; ``published`` maps method to the paper's example error [mm].
    """
    fig = plt.figure(figsize=(10, 4.2))
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    for p in range(markers.shape[1]):
        ax.plot(*markers[:, p].T, lw=0.8, color="0.4")
        ax.text(*markers[-1, p], f"M{p + 1}", fontsize=8)
    ax.scatter(*truth, color="k", marker="*", s=120, label="true CoR")
    for index, row in enumerate(errors.itertuples()):
        style = method_style(row.method, index)
        ax.scatter(
            row.center_x,
            row.center_y,
            row.center_z,
            color=style["color"],
            marker=style["marker"],
            s=40,
            label=f"{row.method}: {row.error_mm:.1f} mm",
        )
    ax.set_xlabel("x (mm)")
    ax.set_ylabel("y (mm)")
    ax.set_zlabel("z (mm)")
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title("Trajectories and CoR estimates", fontsize=9)

    bars = fig.add_subplot(1, 2, 2)
    methods = [m for m in PAPER_METHODS if m in set(errors["method"])]
    ours = errors.set_index("method").loc[methods, "error_mm"].to_numpy()
    paper = np.array([published.get(m, np.nan) for m in methods], dtype=float)
    x = np.arange(len(methods))
    bars.bar(
        x - 0.2, ours, 0.4, label="this trial", color=[method_style(m)["color"] for m in methods]
    )
    bars.bar(x + 0.2, paper, 0.4, label="paper's example trial", color="0.75")
    bars.set_xticks(x, methods)
    bars.set_yscale("log")
    bars.set_ylabel("CoR error (mm)")
    bars.legend(fontsize=8)
    bars.set_title("CoR error: this trial vs paper A's Fig 3 trial", fontsize=9)
    fig.suptitle("Paper A Fig 3 reproduced: M set, ±5° RoM, 1.0 mm noise, one trial", fontsize=10)
    fig.tight_layout()
    return fig


def table2(collected: pd.DataFrame, published_seconds: Mapping[str, float]) -> pd.DataFrame:
    """Seconds per trial per method over BC-converged trials, beside paper A Table 2."""
    rows = bc_converged(collected[collected["method"].isin(PAPER_METHODS)])
    timing = rows.groupby("method")["seconds"].agg(["mean", "median", "size"])
    table = pd.DataFrame(
        {
            "method": list(PAPER_METHODS),
            "mean_s": [timing.loc[m, "mean"] for m in PAPER_METHODS],
            "median_s": [timing.loc[m, "median"] for m in PAPER_METHODS],
            "trials": [int(timing.loc[m, "size"]) for m in PAPER_METHODS],
            "paper_matlab_s": [published_seconds[m] for m in PAPER_METHODS],
        }
    )
    table["speedup_vs_paper"] = table["paper_matlab_s"] / table["mean_s"]
    return table
