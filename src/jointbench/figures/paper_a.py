"""Paper A (Chang & Pollard 2007, centre of rotation): drawing Fig 3 and Fig 4, building Table 2.

Every function takes the collected ``cmc`` results (one row per marker set, RoM, noise, trial
and method) and returns a table or a figure; the paper's declaration, its published values and
claims are in :mod:`jointbench.papers.paper_a`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from jointbench import machine
from jointbench.comparison.published import NOT_APPLICABLE
from jointbench.figures.common import (
    display_limits,
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
    "CONDITION",
    "FIG3_CONDITION",
    "PAPER_METHODS",
    "bc_converged",
    "choose_fig3_trial",
    "condition_means",
    "fig3",
    "fig3_chosen_text",
    "fig4",
    "speed_wording",
    "table2",
    "table2_headline",
    "timing_note",
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


#: Where Fig 4 draws the values paper A states about its Fig 4, by claim id: the conditions
#: each published number belongs to (in the order of its list) and the methods it is about
#: (empty: all five). A3 bounds every method's mean from below, A9 gives LS's mean.
FIG4_STATED = {
    "A3": (
        (
            {"marker_set": "M", "rom_deg": 5, "noise_mm": 1.0},
            {"marker_set": "M", "rom_deg": 5, "noise_mm": 2.0},
        ),
        (),
    ),
    "A9": (({"marker_set": "H", "rom_deg": 15, "noise_mm": 1.0},), ("LS",)),
}


def fig4_stated(published: Mapping | None) -> pd.DataFrame:
    """The values paper A states about its Fig 4, from its typed published values
    (``published``: the paper's YAML as loaded, or None for none): one row per condition and
    claim, columns marker_set, rom_deg, noise_mm, claim, methods (a tuple, empty for all),
    value_mm and bound (True: the paper gives a lower bound, "greater than")."""
    claims = {c["id"]: c for c in (published or {}).get("claims", [])}
    rows = []
    for claim, (conditions, methods) in FIG4_STATED.items():
        if claim not in claims:
            continue
        values = np.atleast_1d(np.asarray(claims[claim]["published"], dtype=float))
        bound = "greater_than" in claims[claim].get("tolerance", {})
        for condition, value in zip(conditions, values, strict=True):
            rows.append(
                {**condition, "claim": claim, "methods": methods, "value_mm": value, "bound": bound}
            )
    columns = [*CONDITION, "claim", "methods", "value_mm", "bound"]
    return pd.DataFrame(rows, columns=columns)


#: Colour of the paper's own values in Fig 4, a black no method uses.
STATED_COLOR = "k"


def _draw_stated(ax, stated: pd.DataFrame, x_of, offset_of) -> None:
    """The paper's stated values on one panel of Fig 4: a lower bound ("all five > 25 mm") as
    a black bar across the condition's methods with an arrow up, a method's value as a black
    star at that method's position. ``x_of(rom, noise)`` and ``offset_of(method)`` place them."""
    for row in stated.itertuples():
        x = x_of(row.rom_deg, row.noise_mm)
        if row.bound:
            ax.plot([x - 0.4, x + 0.4], [row.value_mm] * 2, color=STATED_COLOR, lw=2.2)
            ax.annotate(
                "",
                (x, row.value_mm * 1.6),
                xytext=(x, row.value_mm),
                arrowprops={"arrowstyle": "->", "color": STATED_COLOR, "lw": 1.4},
            )
            who = "all" if not row.methods else ", ".join(row.methods)
            ax.annotate(
                f"paper: {who} > {row.value_mm:g}",
                (x, row.value_mm * 1.6),
                ha="center",
                va="bottom",
                fontsize=9,
                color=STATED_COLOR,
            )
            continue
        for method in row.methods:
            ax.plot(
                x + offset_of(method),
                row.value_mm,
                "*",
                ms=13,
                mfc="none",
                mec=STATED_COLOR,
                mew=1.4,
            )
            ax.annotate(
                f"paper: {method} ≈ {row.value_mm:g}",
                (x + offset_of(method), row.value_mm),
                xytext=(8, 6),
                textcoords="offset points",
                fontsize=9,
                color=STATED_COLOR,
            )


def fig4(collected: pd.DataFrame, published: Mapping | None = None) -> Figure:
    """Mean CoR error per condition in the paper's two panels, (a) M set and (b) H set, with
    the values the paper states about its Fig 4 (:func:`fig4_stated` of ``published``, the
    paper's typed published values) drawn in black where their conditions are.

    Within a panel the conditions run noise level by noise level, RoM increasing within each;
    a method's line joins its RoMs at one noise level. Methods are set slightly apart
    horizontally so lines that coincide (IS, BC and NM on the H set) stay visible. Where BC
    converged in fewer than all trials, the tick label carries the count the mean is over.
    """
    stated = fig4_stated(published)
    means = condition_means(collected)
    sets = sorted(means["marker_set"].unique(), key=lambda s: "MH".find(s))
    noises = sorted(means["noise_mm"].unique())
    roms = sorted(means["rom_deg"].unique())
    n_total = collected["trial"].nunique()
    methods = [m for m in PAPER_METHODS if m in set(means["method"])]
    step, gap = 1.0, 0.8
    fig, axes = pyplot().subplots(
        1, len(sets), figsize=(5.0 * len(sets), 4.6), sharey=True, squeeze=False
    )

    def x_of(rom, noise) -> float:
        return noises.index(noise) * (len(roms) * step + gap) + roms.index(rom) * step

    def offset_of(method) -> float:
        return (methods.index(method) - (len(methods) - 1) / 2) * 0.13

    for panel, (ax, marker_set) in enumerate(zip(axes[0], sets, strict=True)):
        part = means[means["marker_set"] == marker_set]
        ticks, labels = [], []
        for group, noise in enumerate(noises):
            base = x_of(roms[0], noise)
            cell = part[part["noise_mm"] == noise]
            for index, method in enumerate(methods):
                line = cell[cell["method"] == method].sort_values("rom_deg")
                ax.plot(
                    [x_of(r, noise) + offset_of(method) for r in line["rom_deg"]],
                    line["mean_error_mm"],
                    label=method if group == 0 and panel == 0 else None,
                    lw=1.4,
                    ms=5,
                    mfc="white" if index % 2 else None,
                    **method_style(method, index),
                )
            counts = cell.groupby("rom_deg")["n_trials"].max()
            for rom in roms:
                ticks.append(x_of(rom, noise))
                count = int(counts.get(rom, 0))
                # Every label has two lines so both panels' x labels line up.
                labels.append(f"±{rom:g}°\n" + (f"n={count}" if count < n_total else ""))
            group_label(ax, base + (len(roms) - 1) * step / 2, f"noise SD {noise:.1f} mm")
            if group:
                ax.axvline(base - (step + gap) / 2, color="0.75", lw=0.8)
        shown = stated[
            (stated["marker_set"] == marker_set)
            & stated["rom_deg"].isin(roms)
            & stated["noise_mm"].isin(noises)
        ]
        _draw_stated(ax, shown, x_of, offset_of)
        ax.set_xticks(ticks, labels, fontsize=9)
        ax.set_xlim(ticks[0] - 0.5, ticks[-1] + 0.5)
        ax.set_yscale("log")
        ax.grid(True, which="both", axis="y", alpha=0.3)
        ax.set_xlabel("RoM (°), grouped by noise level")
        ax.set_title(f"({'ab'[panel]}) {marker_set} marker set", fontsize=10, pad=18)
    if not stated.empty:
        # Room above the highest stated value for its arrow and label.
        low, high = axes[0, 0].get_ylim()
        axes[0, 0].set_ylim(low, max(high, 4 * stated["value_mm"].max()))
    axes[0, 0].set_ylabel("mean CoR error (mm, log scale)")
    handles, names = axes[0, 0].get_legend_handles_labels()
    if not stated.empty:
        handles.append(
            pyplot().Line2D([], [], color=STATED_COLOR, marker="*", mfc="none", ms=10, lw=2.2)
        )
        names.append("paper A's stated values (§5.1.1, §6)")
    legend_below(fig, handles, names)
    fig.suptitle(
        "Paper A Fig 4 reproduced: mean CoR error over the trials where BC converged\n"
        f"(n = trials averaged, where fewer than {n_total}); black: values the paper states",
        fontsize=10,
    )
    fig.tight_layout(rect=(0, 0.06, 1, 1))
    return fig


#: Paper A's Fig 3 condition: M set, ±5° RoM, 1.0 mm noise.
FIG3_CONDITION = {"marker_set": "M", "rom_deg": 5, "noise_mm": 1.0}


def choose_fig3_trial(collected: pd.DataFrame) -> int:
    """The trial Fig 3 draws: the median trial by NM error at paper A's Fig 3 condition.

    Candidates are the trials of :data:`FIG3_CONDITION` in which BC converged (the paper's
    example has a BC estimate) and every paper method present has a finite error. Sorted by
    NM error (then trial number), the candidate at position ``(n - 1) // 2`` is chosen: the
    median for an odd count, the lower of the two middle ones for an even count, so the
    figure shows a typical trial, not the best or a hand-picked one.
    """
    rows = collected
    for key, value in FIG3_CONDITION.items():
        rows = rows[rows[key] == value]
    rows = rows[rows["method"].isin(PAPER_METHODS)]
    if rows.empty:
        raise ValueError(f"no trials at paper A's Fig 3 condition {FIG3_CONDITION}")
    errors = rows.pivot_table(index="trial", columns="method", values="error_mm", dropna=False)
    usable = errors.notna().all(axis=1)
    if "BC" in errors.columns:
        bc = rows[rows["method"] == "BC"].set_index("trial")["converged"].astype(bool)
        usable &= bc.reindex(errors.index, fill_value=False)
    reference = "NM" if "NM" in errors.columns else errors.columns[0]
    candidates = errors.loc[usable, reference]
    if candidates.empty:
        raise ValueError("no Fig 3 trial where BC converged and every method has an error")
    return median_trial(candidates)


def _label_markers(ax, markers: np.ndarray, avoid: np.ndarray) -> None:
    """Label each trajectory "marker p" on the side with the most room on screen.

    Candidate offsets around the trajectory are compared in the 3-D axes' projected (2-D)
    coordinates; each label takes the one farthest from the estimates, the other
    trajectories and the labels already placed, so labels do not sit on points or each other.
    """
    from mpl_toolkits.mplot3d import proj3d

    def screen(points):
        x, y, _ = proj3d.proj_transform(*np.asarray(points, dtype=float).T, ax.get_proj())
        return np.column_stack([x, y])

    means = screen(markers.mean(axis=0))
    occupied = [screen(avoid), screen(markers.reshape(-1, 3))]
    scale = np.ptp(np.vstack(occupied), axis=0).max()
    angles = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    for p, centre in enumerate(means):
        taken = np.vstack(occupied)
        directions = np.column_stack([np.cos(angles), np.sin(angles)])
        candidates = centre + 0.2 * scale * directions
        room = np.linalg.norm(candidates[:, None] - taken[None], axis=2).min(axis=1)
        choice = int(np.argmax(room))
        best = candidates[choice]
        # The text runs away from its trajectory, not back across it.
        ax.annotate(
            f"marker {p + 1}",
            xy=centre,
            xytext=best,
            fontsize=9,
            ha="left" if directions[choice, 0] >= 0 else "right",
            va="center",
            arrowprops={"arrowstyle": "-", "color": "0.5", "lw": 0.6},
        )
        occupied.append(best[None])


#: Fig 3's 3-D view holds the estimates within this many times the extent of the trajectories
#: and the true centre from the true centre; one farther off is listed in the legend instead.
VIEW_REACH = 10.0


def _in_view(estimates: np.ndarray, data: np.ndarray) -> np.ndarray:
    """Which estimates ``(m, 3)`` [mm] are drawn beside ``data`` ``(n, 3)`` [mm] (markers, then
    the true centre last): finite and within :data:`VIEW_REACH` extents of the true centre."""
    extent = np.ptp(data, axis=0).max()
    offsets = np.abs(estimates - data[-1])
    with np.errstate(invalid="ignore"):
        return np.isfinite(estimates).all(axis=1) & (offsets.max(axis=1) <= VIEW_REACH * extent)


def _mm(value: float) -> str:
    """An error for a label [mm]: one decimal, or 3 significant digits when that is long."""
    return f"{value:.1f}" if abs(value) < 1e5 else f"{value:.3g}"


#: Colours of Fig 3(b)'s legend entries, grey so no method's colour stands for them: our
#: trial's points carry each method's colour, the paper's example is hollow.
THIS_TRIAL_COLOR = "0.25"
PAPER_COLOR = "0.45"


def _error_points(ax, methods: list[str], ours, published: Mapping) -> None:
    """Each method's CoR error [mm] on this trial and in the paper's example, as points on a
    log axis (a bar's length means nothing on one): ours filled in the method's colour and
    marker, the paper's hollow beside it, a thin line between the two. An error beyond the
    scale is drawn at its top as an up-pointing marker with its value printed."""
    from matplotlib.lines import Line2D

    ours = np.asarray(ours, dtype=float)
    paper = np.array([published.get(m, np.nan) for m in methods], dtype=float)
    low, high = display_limits(np.concatenate([ours, paper]))
    x = np.arange(len(methods))
    for position, method, value, theirs in zip(x, methods, ours, paper, strict=True):
        style = method_style(method)
        beyond = value > high
        shown = min(value, high)
        if np.isfinite(theirs):
            ax.plot([position - 0.15, position + 0.15], [shown, theirs], color="0.7", lw=0.8)
            ax.plot(position + 0.15, theirs, style["marker"], ms=8, mfc="white", mec=PAPER_COLOR)
            ax.annotate(
                f"{theirs:g}",
                (position + 0.15, theirs),
                xytext=(7, 0),
                textcoords="offset points",
                va="center",
                fontsize=9,
                color=PAPER_COLOR,
            )
        ax.plot(
            position - 0.15,
            shown,
            "^" if beyond else style["marker"],
            ms=9,
            color=style["color"],
            mec="k",
            mew=0.5,
        )
        ax.annotate(
            _mm(value) + (" (beyond the scale)" if beyond else ""),
            (position - 0.15, shown),
            xytext=(-7, 0),
            textcoords="offset points",
            ha="right",
            va="center",
            fontsize=9,
        )
    handles = [
        Line2D(
            [],
            [],
            ls="",
            marker="o",
            ms=8,
            color=THIS_TRIAL_COLOR,
            mec="k",
            mew=0.5,
            label="this trial (method's colour)",
        ),
        Line2D(
            [],
            [],
            ls="",
            marker="o",
            ms=8,
            mfc="white",
            mec=PAPER_COLOR,
            label="paper's Fig 3 trial",
        ),
    ]
    ax.set_xticks(x, methods)
    ax.set_xlim(-0.7, len(methods) - 0.3)
    ax.set_yscale("log")
    ax.set_ylabel("CoR error (mm, log scale)")
    ax.set_ylim(low / 2, high * 2)
    ax.grid(True, which="both", axis="y", alpha=0.3)
    ax.legend(
        handles=handles,
        fontsize=9,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.08),
        ncol=2,
        frameon=False,
    )
    ax.set_title("(b) CoR error: this trial vs the paper's example", fontsize=10)


def fig3(
    markers: np.ndarray,
    truth: np.ndarray,
    errors: pd.DataFrame,
    published: Mapping,
    *,
    chosen: str = "",
) -> Figure:
    """One M-set, ±5°, 1.0 mm trial: trajectories, true CoR, every method's estimate and error.

    ``markers`` ``(n_frames, n_markers, 3)`` [mm]; ``errors`` has columns method, center_x/y/z,
    error_mm for that trial; ``published`` maps method to the paper's example error [mm];
    ``chosen`` says how the trial was chosen (e.g. "trial 12, the median by NM error ..."),
    printed under the title.
    """
    methods = [m for m in PAPER_METHODS if m in set(errors["method"])]
    by_method = errors.set_index("method").loc[methods]
    estimates = by_method[["center_x", "center_y", "center_z"]].to_numpy(dtype=float)
    truth = np.asarray(truth, dtype=float)
    in_view = _in_view(estimates, np.vstack([markers.reshape(-1, 3), truth[None]]))

    fig = pyplot().figure(figsize=(11, 5.0))
    grid = fig.add_gridspec(1, 2, width_ratios=[1.25, 1])
    ax = fig.add_subplot(grid[0, 0], projection="3d", computed_zorder=False)
    for p in range(markers.shape[1]):
        ax.plot(*markers[:, p].T, lw=0.9, color="0.45", zorder=1)
    # Hollow, so an estimate within a few millimetres of it still shows through.
    ax.scatter(
        *truth,
        facecolor="none",
        edgecolor="k",
        marker="*",
        s=260,
        lw=1.2,
        zorder=4,
        label="true CoR",
    )
    for index, (method, row) in enumerate(by_method.iterrows()):
        style = method_style(method, index)
        if not in_view[index]:
            # Listed with its error, not drawn: the view would shrink the data to a point.
            label = f"{method}: {_mm(row['error_mm'])} mm, outside the view"
            ax.scatter([], [], [], color=style["color"], marker=style["marker"], label=label)
            continue
        # Hollow, each method its own shape: estimates a millimetre apart (BC's and NM's,
        # often) both stay visible, one outline through the other.
        ax.scatter(
            row["center_x"],
            row["center_y"],
            row["center_z"],
            facecolor="none",
            edgecolor=style["color"],
            marker=style["marker"],
            s=80,
            linewidth=1.8,
            zorder=3,
            label=f"{method}: {_mm(row['error_mm'])} mm",
        )
    drawn = estimates[in_view]
    equal_3d_limits(ax, np.vstack([markers.reshape(-1, 3), truth[None], drawn]))
    _label_markers(ax, markers, np.vstack([truth[None], drawn]))
    ax.set_xlabel("x (mm)", fontsize=9)
    ax.set_ylabel("y (mm)", fontsize=9)
    ax.set_zlabel("z (mm)", fontsize=9)
    few_3d_ticks(ax)
    ax.tick_params(labelsize=8.5)
    ax.legend(fontsize=8.5, loc="upper left", bbox_to_anchor=(-0.05, 1.0), title="estimate: error")
    ax.set_title("(a) trajectories, true CoR and estimates (equal axis scales)", fontsize=10)

    _error_points(fig.add_subplot(grid[0, 1]), methods, by_method["error_mm"], published)
    title = "Paper A Fig 3 reproduced: M set, ±5° RoM, 1.0 mm noise, one trial"
    fig.suptitle(title + (f"\n{chosen}" if chosen else ""), fontsize=10)
    fig.tight_layout()
    return fig


def fig3_chosen_text(collected: pd.DataFrame, trial: int) -> str:
    """The sentence under Fig 3's title saying which trial it is and why."""
    rows = collected
    for key, value in FIG3_CONDITION.items():
        rows = rows[rows[key] == value]
    n_trials = rows["trial"].nunique()
    return (
        f"trial {trial} of {n_trials}: the median trial by NM error among those where BC converged"
    )


def speed_wording(ours_s: float, paper_s: float) -> str:
    """Our time against the paper's, in words: "650× faster", "2.2× slower" or "as fast".

    The ratio is always written as a number above 1 with the direction in the word, so a
    method that takes twice the paper's time never reads as "0.5× faster" (or, rounded, "0×").
    """
    if not (np.isfinite(ours_s) and np.isfinite(paper_s)) or ours_s <= 0 or paper_s <= 0:
        return NOT_APPLICABLE
    ratio = paper_s / ours_s
    if 1 / 1.05 <= ratio <= 1.05:
        return "as fast (within 5 %)"
    factor = ratio if ratio > 1 else 1 / ratio
    number = f"{factor:.0f}" if factor >= 10 else f"{factor:.1f}"
    return f"{number}× {'faster' if ratio > 1 else 'slower'}"


#: Our statistics of time per trial that Table 2 sets against the paper's means, the robust one
#: (which words the headline) first.
TABLE2_STATISTICS = ("median", "mean")


def table2(collected: pd.DataFrame, published_seconds: Mapping[str, float]) -> pd.DataFrame:
    """Seconds per trial per method over BC-converged trials, beside paper A Table 2.

    The paper gives each method's mean time per trial [s] (``paper_matlab_s``). Ours are set
    against it by median and by mean: ``speedup_<statistic>`` is paper_matlab_s / ours (above
    1: ours is faster) and ``vs_paper_<statistic>`` says the same in words
    (:func:`speed_wording`). The median is the robust comparison: a few slow calls (a busy CPU,
    a page fault) move our mean, not our median.
    """
    rows = bc_converged(collected[collected["method"].isin(PAPER_METHODS)])
    timing = rows.groupby("method")["seconds"].agg(["mean", "median", "size"])
    # The paper's methods this run estimated, in the paper's order.
    methods = [m for m in PAPER_METHODS if m in timing.index]
    table = pd.DataFrame(
        {
            "method": methods,
            "mean_s": [timing.loc[m, "mean"] for m in methods],
            "median_s": [timing.loc[m, "median"] for m in methods],
            "trials": [int(timing.loc[m, "size"]) for m in methods],
            "paper_matlab_s": [published_seconds[m] for m in methods],
        }
    )
    for statistic in TABLE2_STATISTICS:
        ours = table[f"{statistic}_s"]
        table[f"speedup_{statistic}"] = table["paper_matlab_s"] / ours
        table[f"vs_paper_{statistic}"] = [
            speed_wording(our, paper)
            for our, paper in zip(ours, table["paper_matlab_s"], strict=True)
        ]
    return table


def table2_headline(table: pd.DataFrame) -> str:
    """One sentence for a caption, worded from :func:`table2`'s own ratios: by median, with the
    mean's beside each."""
    parts = [
        f"{method} {by_median} (by mean: {by_mean})"
        for method, by_median, by_mean in zip(
            table["method"], table["vs_paper_median"], table["vs_paper_mean"], strict=True
        )
    ]
    return (
        "Median time per trial against the paper's MATLAB times (the paper reports means; the "
        "median is the robust comparison, unmoved by a few slow calls): " + ", ".join(parts) + "."
    )


def timing_note(environment: str | None = None) -> str:
    """How Table 2's times were measured, for the note under the table.

    ``environment`` describes the machine; by default the one running this process, which is
    the run's machine when the table is built in the same run as the estimates.
    """
    environment = environment or machine.describe()
    how = (
        "every method timed the same way: all trials of a condition fitted in one batched call "
        "of the method's many-trial form (its own, or its one-trial function trial by trial), "
        "whose time is divided by its trials"
    )
    return (
        f"Ours: wall-clock time per trial, measured inside the estimate job ({how}; simulation "
        "and file I/O excluded; a first fit before the timed ones pays for compilation and "
        f"first-call imports, its time in the job's log), on this run's machine ({environment}). "
        "Other jobs of the run (snakemake -j) may have shared the CPUs, so times are indicative. "
        "Paper: mean times, MATLAB 6.5 on a 3 GHz Pentium 4. Speed-up: the paper's time over "
        "ours (by our median or mean); above 1 ours is faster. The median is the robust "
        "comparison."
    )
