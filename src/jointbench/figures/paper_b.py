"""Paper B (Chang & Pollard 2007, dominant axis of rotation): Table 1, Fig 5, Fig 2, claims B1–B6.

Tables and Fig 5 read the collected ``hinge`` results (one row per protocol, FE RoM, AA/FE ratio,
trial and method); Fig 2 fits the three costs to two freshly simulated trials.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

from jointbench.figures.common import method_style

__all__ = ["BREAKDOWN_DEG", "CELL", "PAPER_METHODS", "cell_statistics", "fig2", "fig5", "table1"]

PAPER_METHODS = ("planar", "radial", "combined")
CELL = ["protocol", "method", "fe_rom_deg", "aa_ratio"]
BREAKDOWN_DEG = 20.0


def cell_statistics(collected: pd.DataFrame) -> pd.DataFrame:
    """Mean, SD, min and max angular error per cell, with the count of failed trials."""
    grouped = collected.groupby(CELL, observed=True)
    stats = grouped["error_deg"].agg(mean="mean", sd="std", min="min", max="max", n="size")
    stats["not_converged"] = grouped["converged"].apply(lambda c: int((~c).sum()))
    return stats.reset_index()


def table1(collected: pd.DataFrame, cells: pd.DataFrame) -> pd.DataFrame:
    """Every published Table 1 cell beside our mean and SD.

    ``cells`` has the cell keys (:data:`CELL`), ``published``, and the verdict of the cell's
    tolerance, ``within_tolerance`` and ``margin``.
    """
    ours = cell_statistics(collected[collected["method"].isin(PAPER_METHODS)])
    table = cells.merge(ours, on=CELL, how="left")
    table["difference"] = table["mean"] - table["published"]
    return table.rename(columns={"mean": "reproduced_mean", "sd": "reproduced_sd"})[
        [
            *CELL,
            "published",
            "reproduced_mean",
            "reproduced_sd",
            "difference",
            "within_tolerance",
            "margin",
            "not_converged",
        ]
    ]


def fig5(collected: pd.DataFrame) -> plt.Figure:
    """Mean angular error with min–max bars for every condition: (a) knee, (b) index MCP."""
    stats = cell_statistics(collected[collected["method"].isin(PAPER_METHODS)])
    protocols = [p for p in ("knee", "mcp") if p in set(stats["protocol"])]
    fig, axes = plt.subplots(
        1, len(protocols), figsize=(6.5 * len(protocols), 4.2), sharey=True, squeeze=False
    )
    conditions = (
        stats[["fe_rom_deg", "aa_ratio"]].drop_duplicates().sort_values(["fe_rom_deg", "aa_ratio"])
    )
    labels = [f"{r:g}" for r in conditions["aa_ratio"]]
    for ax, protocol, letter in zip(axes[0], protocols, "ab", strict=False):
        for index, method in enumerate(PAPER_METHODS):
            line = stats[(stats["protocol"] == protocol) & (stats["method"] == method)]
            line = conditions.merge(line, on=["fe_rom_deg", "aa_ratio"], how="left")
            x = np.arange(len(line)) + (index - 1) * 0.12
            style = method_style(method, index)
            for fe in line["fe_rom_deg"].unique():
                part = (line["fe_rom_deg"] == fe).to_numpy()
                ax.errorbar(
                    x[part],
                    line["mean"][part],
                    yerr=[
                        line["mean"][part] - line["min"][part],
                        line["max"][part] - line["mean"][part],
                    ],
                    capsize=2,
                    lw=1.3,
                    ms=4,
                    label=method if fe == line["fe_rom_deg"].iloc[0] else None,
                    **style,
                )
        for boundary in np.flatnonzero(np.diff(conditions["fe_rom_deg"].to_numpy())) + 0.5:
            ax.axvline(boundary, color="0.7", lw=0.8)
        for fe, group in conditions.reset_index(drop=True).groupby("fe_rom_deg"):
            ax.text(group.index.to_numpy().mean(), 92, f"FE RoM {fe:g}°", ha="center", fontsize=8)
        ax.set_xticks(np.arange(len(labels)), labels)
        ax.set_xlabel("AA RoM / FE RoM")
        ax.set_ylim(0, 97)
        ax.grid(True, axis="y", alpha=0.3)
        ax.set_title(f"({letter}) {'knee' if protocol == 'knee' else 'index MCP'}", fontsize=9)
    axes[0, 0].set_ylabel("AoR angular error (°): mean, min–max")
    axes[0, 0].legend(fontsize=8, loc="center left")
    fig.suptitle("Paper B Fig 5 reproduced: AoR error over 30 trials per condition", fontsize=10)
    fig.tight_layout()
    return fig


def _circle_points(point, direction, center_of, radius, n=100):
    """Points of the circle of ``radius`` about the axis, in the plane through ``center_of``."""
    n_hat = direction / np.linalg.norm(direction)
    centre = point + n_hat * (n_hat @ (center_of - point))
    helper = np.eye(3)[np.argmin(np.abs(n_hat))]
    e1 = np.cross(n_hat, helper)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(n_hat, e1)
    angle = np.linspace(0, 2 * np.pi, n)
    return centre + radius * (np.outer(np.cos(angle), e1) + np.outer(np.sin(angle), e2))


def fig2(examples) -> plt.Figure:
    """Best-fitting plane, cylinder and circle on two trials with a known axis.

    ``examples``: list of ``(title, markers, truth, fits)`` with markers
    ``(n_frames, n_markers, 3)`` [mm] and fits ``{method: AxisResult}``.
    For each cost the fitted axis is drawn through its point, and each marker's fitted circle
    (radius = its mean distance from that axis, in the plane through its centroid) shows how well
    the cost's model matches the trajectory.
    """
    fig = plt.figure(figsize=(6 * len(examples), 5))
    for column, (title, markers, truth, fits) in enumerate(examples):
        ax = fig.add_subplot(1, len(examples), column + 1, projection="3d")
        for p in range(markers.shape[1]):
            ax.plot(*markers[:, p].T, ".", ms=2, color="0.3")
        span = np.ptp(markers.reshape(-1, 3), axis=0).max()
        true_point = np.asarray(truth["axis_point"])
        true_dir = np.asarray(truth["axis_direction"])
        ax.plot(
            *np.stack([true_point - span * true_dir, true_point + span * true_dir]).T,
            "k--",
            lw=1.2,
            label="true axis",
        )
        for index, method in enumerate(PAPER_METHODS):
            fit = fits[method]
            style = method_style(method, index)
            error = np.degrees(np.arccos(min(1.0, abs(float(fit.direction @ true_dir)))))
            ends = np.stack([fit.point - span * fit.direction, fit.point + span * fit.direction])
            ax.plot(*ends.T, color=style["color"], lw=1.5, label=f"{method}: {error:.1f}°")
            for p in range(markers.shape[1]):
                centroid = markers[:, p].mean(axis=0)
                offsets = markers[:, p] - fit.point
                radial = offsets - np.outer(offsets @ fit.direction, fit.direction)
                radius = np.linalg.norm(radial, axis=1).mean()
                circle = _circle_points(fit.point, fit.direction, centroid, radius)
                ax.plot(*circle.T, color=style["color"], lw=0.8, alpha=0.8)
        ax.set_title(f"({'ab'[column]}) {title}", fontsize=9)
        ax.legend(fontsize=7, loc="upper left")
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
        ax.set_zlabel("z (mm)")
    fig.suptitle(
        "Paper B Fig 2 reproduced: best-fitting plane (planar), cylinder (radial) and "
        "circle (combined)",
        fontsize=10,
    )
    fig.tight_layout()
    return fig
