"""Paper B (Chang & Pollard 2007, dominant axis of rotation): Table 1, Fig 5, Fig 2, claims B1–B6.

Tables and Fig 5 read the collected ``hinge`` results (one row per protocol, FE RoM, AA/FE ratio,
trial and method); Fig 2 draws the three costs' fits on two already-simulated trials.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from jointbench.figures.common import (
    equal_3d_limits,
    few_3d_ticks,
    group_label,
    legend_below,
    median_trial,
    method_style,
    pyplot,
)

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "BREAKDOWN_DEG",
    "CELL",
    "PAPER_METHODS",
    "axis_error_deg",
    "cell_statistics",
    "choose_fig2_trial",
    "fig2",
    "fig5",
    "protocol_name",
    "table1",
]

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


#: How the protocols are called in titles.
PROTOCOL_NAMES = {"knee": "knee", "mcp": "index MCP"}


def protocol_name(protocol: str) -> str:
    """A protocol's name for people ("index MCP" for ``mcp``); an unknown one keeps its name."""
    return PROTOCOL_NAMES.get(protocol, protocol)


#: Colours of the paper's values in Fig 5 and of a cell outside its tolerance; neither is a
#: method's colour.
PUBLISHED_COLOR = "k"
MISSED_COLOR = "red"


def fig5(collected: pd.DataFrame, cells: pd.DataFrame | None = None) -> Figure:
    """Mean angular error with min–max bars for every condition: (a) knee, (b) index MCP.

    ``cells`` (optional): the published Table 1 cells, columns :data:`CELL`, ``published``
    (the paper's mean [°]) and ``within_tolerance``; each is drawn as a black dash at its
    cell, and our mean of a cell outside its tolerance is ringed in red.
    """
    stats = cell_statistics(collected[collected["method"].isin(PAPER_METHODS)])
    if cells is not None:
        stats = stats.merge(cells[[*CELL, "published", "within_tolerance"]], on=CELL, how="left")
    protocols = [p for p in ("knee", "mcp") if p in set(stats["protocol"])]
    fig, axes = pyplot().subplots(
        1, len(protocols), figsize=(5.5 * len(protocols), 4.4), sharey=True, squeeze=False
    )
    conditions = (
        stats[["fe_rom_deg", "aa_ratio"]].drop_duplicates().sort_values(["fe_rom_deg", "aa_ratio"])
    )
    labels = [f"{r:g}" for r in conditions["aa_ratio"]]
    for ax, protocol, letter in zip(axes[0], protocols, "ab", strict=False):
        for index, method in enumerate(PAPER_METHODS):
            line = stats[(stats["protocol"] == protocol) & (stats["method"] == method)]
            line = conditions.merge(line, on=["fe_rom_deg", "aa_ratio"], how="left")
            x = np.arange(len(line)) + (index - 1) * 0.17
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
            if "published" in line:
                ax.plot(x, line["published"], "_", ms=9, mew=2.0, color=PUBLISHED_COLOR, zorder=4)
                # A cell the paper has no value for (NaN) is not ringed.
                missed = line["within_tolerance"].eq(False).to_numpy()
                ax.plot(
                    x[missed],
                    line["mean"][missed],
                    "o",
                    ms=10,
                    mfc="none",
                    mec=MISSED_COLOR,
                    mew=1.4,
                    zorder=5,
                )
        for boundary in np.flatnonzero(np.diff(conditions["fe_rom_deg"].to_numpy())) + 0.5:
            ax.axvline(boundary, color="0.7", lw=0.8)
        for fe, group in conditions.reset_index(drop=True).groupby("fe_rom_deg"):
            group_label(ax, group.index.to_numpy().mean(), f"FE RoM {fe:g}°")
        ax.set_xticks(np.arange(len(labels)), labels)
        ax.set_xlabel("AA RoM / FE RoM (ratio)")
        # An axis error is at most 90°.
        ax.set_ylim(0, 92)
        ax.grid(True, axis="y", alpha=0.3)
        ax.set_title(f"({letter}) {protocol_name(protocol)}", fontsize=10, pad=18)
    axes[0, 0].set_ylabel("AoR angular error (°): mean, min–max")
    handles, names = axes[0, 0].get_legend_handles_labels()
    title = "Paper B Fig 5 reproduced: AoR error over {} trials per condition".format(
        collected["trial"].nunique()
    )
    if cells is not None:
        handles += [
            pyplot().Line2D([], [], ls="", marker="_", ms=9, mew=2.0, color=PUBLISHED_COLOR),
            pyplot().Line2D([], [], ls="", marker="o", ms=9, mfc="none", mec=MISSED_COLOR),
        ]
        names += ["paper B Table 1 mean", "outside the cell's tolerance"]
        within = int(cells["within_tolerance"].sum())
        title += f"; {within} of {len(cells)} Table 1 means within tolerance"
    # Below the panels: inside, it would cover curves (planar's rise from ratio 0.1 to 0.3).
    legend_below(fig, handles, names)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout(rect=(0, 0.07, 1, 1))
    return fig


def _frame(direction: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unit axis ``n`` and two unit vectors spanning the plane orthogonal to it."""
    n_hat = np.asarray(direction, dtype=float)
    n_hat = n_hat / np.linalg.norm(n_hat)
    helper = np.eye(3)[np.argmin(np.abs(n_hat))]
    e1 = np.cross(n_hat, helper)
    e1 /= np.linalg.norm(e1)
    return n_hat, e1, np.cross(n_hat, e1)


def _circle_points(point, direction, center_of, radius, n=100):
    """Points of the circle of ``radius`` about the axis, in the plane through ``center_of``."""
    n_hat, e1, e2 = _frame(direction)
    centre = point + n_hat * (n_hat @ (center_of - point))
    angle = np.linspace(0, 2 * np.pi, n)
    return centre + radius * (np.outer(np.cos(angle), e1) + np.outer(np.sin(angle), e2))


def _line(fit) -> tuple[np.ndarray, np.ndarray]:
    """``(point, unit direction)`` of a fit given as an AxisResult or a ``(point, direction)``
    pair."""
    point, direction = (fit.point, fit.direction) if hasattr(fit, "point") else fit
    direction = np.asarray(direction, dtype=float)
    return np.asarray(point, dtype=float), direction / np.linalg.norm(direction)


def _draw_planes(ax, trajectory, point, direction, color) -> np.ndarray:
    """The best-fitting plane of one marker: orthogonal to the axis through the trajectory's
    centroid, a square the size of the trajectory. Returns the points drawn."""
    _, e1, e2 = _frame(direction)
    centroid = trajectory.mean(axis=0)
    offsets = trajectory - centroid
    half = np.abs(offsets @ np.stack([e1, e2]).T).max() * 1.1
    s, t = np.meshgrid([-half, half], [-half, half])
    surface = centroid + s[..., None] * e1 + t[..., None] * e2
    ax.plot_surface(
        *np.moveaxis(surface, -1, 0), color=color, alpha=0.25, lw=0, shade=False, zorder=2
    )
    return surface.reshape(-1, 3)


def _draw_cylinder(ax, trajectory, point, direction, color) -> np.ndarray:
    """The best-fitting cylinder of one marker: about the axis, radius its mean distance from
    it, as long as the trajectory's extent along the axis and around the arc it covers.
    Returns the points drawn."""
    n_hat, e1, e2 = _frame(direction)
    offsets = trajectory - point
    along = offsets @ n_hat
    radial = offsets - np.outer(along, n_hat)
    radius = np.linalg.norm(radial, axis=1).mean()
    angles = np.unwrap(np.arctan2(radial @ e2, radial @ e1))
    theta = np.linspace(angles.min() - 0.15, angles.max() + 0.15, 30)
    length = np.linspace(along.min() - 0.1 * radius, along.max() + 0.1 * radius, 6)
    a, h = np.meshgrid(theta, length)
    surface = (
        point
        + h[..., None] * n_hat
        + radius * (np.cos(a)[..., None] * e1 + np.sin(a)[..., None] * e2)
    )
    ax.plot_surface(
        *np.moveaxis(surface, -1, 0), color=color, alpha=0.25, lw=0, shade=False, zorder=2
    )
    return surface.reshape(-1, 3)


def _draw_circle(ax, trajectory, point, direction, color) -> np.ndarray:
    """The best-fitting circle of one marker: about the axis, in the plane through the
    trajectory's centroid, radius its mean distance from the axis. Returns the points drawn."""
    n_hat, _, _ = _frame(direction)
    offsets = trajectory - point
    radius = np.linalg.norm(offsets - np.outer(offsets @ n_hat, n_hat), axis=1).mean()
    circle = _circle_points(point, n_hat, trajectory.mean(axis=0), radius)
    ax.plot(*circle.T, color=color, lw=1.4, zorder=2)
    return circle


# The model each cost fits (paper B Fig 2): one drawing per method.
_MODELS = {
    "planar": ("best-fitting planes", _draw_planes),
    "radial": ("best-fitting cylinders", _draw_cylinder),
    "combined": ("best-fitting circles", _draw_circle),
}


def axis_error_deg(direction: np.ndarray, true_direction: np.ndarray) -> float:
    """Angle [°] between two axis directions, sign-free (an axis has no arrow)."""
    a = np.asarray(direction, dtype=float)
    b = np.asarray(true_direction, dtype=float)
    cosine = abs(float(a @ b)) / (np.linalg.norm(a) * np.linalg.norm(b))
    return float(np.degrees(np.arccos(min(1.0, cosine))))


def fig2(examples) -> Figure:
    """Best-fitting plane, cylinder and circle on two trials with a known axis (paper B Fig 2).

    ``examples``: list of ``(title, markers, truth, fits)``: markers ``(n_frames, n_markers,
    3)`` [mm] of one already-simulated trial, truth ``{"axis_point", "axis_direction"}`` and
    fits ``{method: AxisResult or (point, direction)}`` for planar, radial and combined.
    One row per example, one panel per cost: the model that cost fits to each marker's
    trajectory (planes, cylinders, circles), its axis, and the true axis drawn on top.
    """
    methods = [m for m in PAPER_METHODS if all(m in e[3] for e in examples)]
    fig = pyplot().figure(figsize=(3.6 * len(methods), 3.9 * len(examples)))
    for row, (title, markers, truth, fits) in enumerate(examples):
        true_point = np.asarray(truth["axis_point"], dtype=float)
        true_dir = np.asarray(truth["axis_direction"], dtype=float)
        true_dir = true_dir / np.linalg.norm(true_dir)
        points = markers.reshape(-1, 3)
        span = np.ptp(points, axis=0).max()
        centre = points.mean(axis=0)
        # Axis lines are drawn through the point on them nearest the markers, as long as
        # the data are wide, so they cross the picture instead of leaving it.
        row_axes, row_drawn = [], []
        for column, method in enumerate(methods):
            ax = fig.add_subplot(
                len(examples),
                len(methods),
                row * len(methods) + column + 1,
                projection="3d",
                computed_zorder=False,
            )
            point, direction = _line(fits[method])
            style = method_style(method, column)
            label, draw = _MODELS.get(method, ("fitted circles", _draw_circle))
            drawn = [points]
            for p in range(markers.shape[1]):
                drawn.append(draw(ax, markers[:, p], point, direction, style["color"]))
                ax.plot(*markers[:, p].T, ".", ms=1.5, color="0.25", zorder=3)
            near = point + direction * (direction @ (centre - point))
            fitted = np.stack([near - 0.7 * span * direction, near + 0.7 * span * direction])
            ax.plot(*fitted.T, color=style["color"], lw=2.0, zorder=4, label=f"{method} axis")
            near = true_point + true_dir * (true_dir @ (centre - true_point))
            true_line = np.stack([near - 0.7 * span * true_dir, near + 0.7 * span * true_dir])
            ax.plot(*true_line.T, "k--", lw=1.6, zorder=5, label="true axis")
            row_axes.append(ax)
            row_drawn += [*drawn, true_line, fitted]
            few_3d_ticks(ax)
            ax.tick_params(labelsize=9, pad=0)
            ax.set_xlabel("x (mm)", fontsize=9, labelpad=2)
            ax.set_ylabel("y (mm)", fontsize=9, labelpad=2)
            ax.set_zlabel("z (mm)", fontsize=9, labelpad=2)
            error = axis_error_deg(direction, true_dir)
            ax.set_title(
                f"({'ab'[row]}) {title}\n{method} cost: {label}; axis error {error:.1f}°",
                fontsize=9,
            )
        # One trial, three costs: the same limits across the row, so the models compare at
        # a glance. 3-D lines are not clipped to the axes: every drawn model must fit inside.
        for ax in row_axes:
            equal_3d_limits(ax, np.vstack(row_drawn), margin=0.02)
    fig.suptitle(
        "Paper B Fig 2 reproduced: best-fitting plane (planar cost), cylinder (radial) and "
        "circle (combined)\ncoloured line = the cost's fitted axis, black dashed = true axis, "
        "grey dots = marker positions; equal axis scales",
        fontsize=10,
    )
    fig.tight_layout(h_pad=3.0)
    return fig


def choose_fig2_trial(collected: pd.DataFrame, condition: Mapping[str, object]) -> int:
    """The trial Fig 2 draws for ``condition``: the median trial by the combined cost's error
    (the paper's proposed method), so the example is typical rather than picked."""
    rows = collected[collected["method"] == "combined"]
    for key, value in condition.items():
        rows = rows[rows[key] == value]
    return median_trial(rows.set_index("trial")["error_deg"])
