"""The extended ranking: every estimator of a study, the paper's and any added, built-in or
external, ranked by mean error on every condition.

Everything is computed from the collected results of one study (one row per condition, trial
and method); method names need not be known in advance, so a user's estimator appears here as
soon as its estimates files are collected.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from jointbench.configuration import config as jb_config
from jointbench.configuration.studies import get_study
from jointbench.figures.common import (
    display_limits,
    method_styles,
    pyplot,
    study_title,
)
from jointbench.running import landlock
from jointbench.running.scoring import ERROR_COLUMN
from jointbench.running.summary import summarise

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "NO_PAPER",
    "best_headline",
    "best_text",
    "cell_text",
    "condition_label",
    "extended_figure",
    "extended_table",
    "incomplete",
    "mean_ranks",
    "origin_note",
]

#: A study's paper: its letter and the methods it compared (``("", ())`` for none); any other
#: method in a study's results is an addition.
PaperMethods = tuple[str, Sequence[str]]
NO_PAPER: PaperMethods = ("", ())


#: Mean errors equal to this many significant digits tie in the ranking.
TIE_DIGITS = 3


def _mean_column(study: str) -> str:
    """Name of the mean-error column of :func:`summarise` for ``study``, e.g. ``mean_error_mm``."""
    return "mean_" + ERROR_COLUMN[get_study(study).kind]


def _unit(study: str) -> str:
    unit = ERROR_COLUMN[get_study(study).kind].removeprefix("error_")
    return {"deg": "°"}.get(unit, f" {unit}")


def extended_table(
    collected: pd.DataFrame, study: str, paper: PaperMethods = NO_PAPER
) -> pd.DataFrame:
    """Every method on every condition of ``study``, ranked within the condition.

    Columns: the study's condition keys, ``method``, ``source`` (``"paper A"`` or ``"added"``),
    then :func:`summarise`'s ``trials, converged, failed, mean_error_<unit>,
    median_error_<unit>, mean_seconds``, then ``common_trials``, ``common_mean_error_<unit>``,
    ``rank`` and ``best`` (rank 1 with a finite error). Within a condition a method ranks by
    its failed trials first, fewer first, then by its mean error over the trials that every
    method with as many failed trials answered (``common_trials`` of them;
    :func:`_common_means`), lower first: methods are compared on identical trials, so one that
    gives up on the hard ones cannot win on the easy ones, and the mean over the trials a method
    answered (``mean_error``) is shown but does not rank. Where those methods have no trial in
    common (``common_trials`` 0), each one's own mean decides. Means equal to
    :data:`TIE_DIGITS` significant digits tie and share the lower rank; a method with no finite
    error ranks last among those with as many failures. Rows are sorted by condition, then rank.
    """
    keys = list(get_study(study).grid_keys)
    mean = _mean_column(study)
    table = summarise(collected, study)
    letter, methods = paper
    table.insert(
        len(keys) + 1,
        "source",
        np.where(table["method"].isin(methods), f"paper {letter}", "added"),
    )
    # One row of errors per (condition, method), one column per trial, in the summary's order.
    error = ERROR_COLUMN[get_study(study).kind]
    errors = (
        collected.set_index([*keys, "method", "trial"])[error]
        .unstack("trial")
        .reindex(pd.MultiIndex.from_frame(table[[*keys, "method"]]))
        .to_numpy(float)
    )
    failed = table["failed"].to_numpy()
    own = table[mean].to_numpy(float)
    common_mean = np.full(len(table), np.nan)
    common_trials = np.zeros(len(table), dtype=int)
    ranks = np.zeros(len(table), dtype=int)
    for rows in table.groupby(keys, observed=True, sort=False).indices.values():
        common_mean[rows], common_trials[rows] = _common_means(
            errors[rows], failed[rows], own[rows]
        )
        ranks[rows] = _ranks(failed[rows], _rounded(common_mean[rows]))
    table["common_trials"] = common_trials
    table[f"common_{mean}"] = common_mean
    table["rank"] = ranks
    table["best"] = table["rank"].eq(1) & np.isfinite(common_mean)
    return table.sort_values([*keys, "rank", "method"], kind="stable", ignore_index=True)


def _rounded(values: np.ndarray) -> np.ndarray:
    """``values`` ``(n,)`` to :data:`TIE_DIGITS` significant digits: methods that reach the same
    minimum (IS and LM do) differ by rounding noise, which must not decide a rank."""
    return np.array([float(f"{value:.{TIE_DIGITS}g}") for value in values])


def _common_means(
    errors: np.ndarray, failed: np.ndarray, own: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The errors the methods of one condition are ranked by, once their failed trials tie.

    ``errors`` ``(n, trials)``, one row per method (NaN: the trial failed, or the method has no
    row for it); ``failed`` ``(n,)`` their failed trials; ``own`` ``(n,)`` each one's mean over
    the trials it answered. Returns each method's mean error over the trials that every method
    with as many failed trials answered ``(n,)``, and how many those are ``(n,)``. Only methods
    with equal failures are compared on the mean, so only they need common trials: a method
    that fails more does not narrow the trials the others are compared on. Where they have none
    (count 0), each one's ``own`` mean stands in.
    """
    answered = ~np.isnan(errors)
    means = own.astype(float)
    counts = np.zeros(len(errors), dtype=int)
    for count in np.unique(failed):
        group = failed == count
        common = answered[group].all(axis=0)
        counts[group] = int(common.sum())
        if common.any():
            means[group] = errors[group][:, common].mean(axis=1)
    return means, counts


def _ranks(failed: np.ndarray, mean: np.ndarray) -> np.ndarray:
    """Ranks ``(n,)`` of the methods of one condition by their failed trials, then their
    rounded mean error over common trials (``(n,)`` each; a NaN mean, every trial failed, after
    any number), ties sharing the lower rank."""
    keys = [
        (int(count), bool(np.isnan(value)), 0.0 if np.isnan(value) else float(value))
        for count, value in zip(failed, mean, strict=True)
    ]
    return np.array([1 + sum(other < key for other in keys) for key in keys])


def mean_ranks(table: pd.DataFrame) -> pd.DataFrame:
    """Per method, over the conditions of an :func:`extended_table`: ``mean_rank``,
    ``best_alone`` (conditions where it alone is best), ``best_tied`` (conditions where it
    shares the best mean), ``best_in`` (their sum: best or tied) and ``conditions``; sorted
    best first.

    A tie is reported as shared, not as a win for each method, so two methods tied everywhere
    read "best alone in 0, tied in n" rather than both "best in n".
    """
    best = table["best"].astype(bool)
    keys = list(table.columns[: table.columns.get_loc("method")])
    sharing = best.groupby([table[k] for k in keys], observed=True).transform("sum")
    counted = table.assign(
        _alone=best & (sharing == 1),
        _tied=best & (sharing > 1),
    )
    ranks = counted.groupby("method", observed=True).agg(
        mean_rank=("rank", "mean"),
        best_alone=("_alone", "sum"),
        best_tied=("_tied", "sum"),
        conditions=("rank", "size"),
    )
    ranks["best_alone"] = ranks["best_alone"].astype(int)
    ranks["best_tied"] = ranks["best_tied"].astype(int)
    ranks.insert(3, "best_in", ranks["best_alone"] + ranks["best_tied"])
    return ranks.reset_index().sort_values(["mean_rank", "method"], ignore_index=True)


def best_text(best_alone: int, best_tied: int, conditions: int) -> str:
    """How often a method is best, ties shown as shared: "best in 8 of 18, tied in 2"."""
    text = f"best in {best_alone} of {conditions}"
    return text + (f", tied in {best_tied}" if best_tied else "")


def best_headline(table: pd.DataFrame) -> str:
    """Who is best per condition, each condition counted once: sole winners, then each group
    of methods tied for best with the number of conditions they share.

    Works on an :func:`extended_table` or the CSV read back (``best`` as booleans).
    """
    keys = list(table.columns[: table.columns.get_loc("method")])
    best = table[table["best"].astype(str) == "True"]
    winners = best.groupby(keys, observed=True)["method"].apply(lambda m: tuple(sorted(m)))
    counts = winners.value_counts()
    alone = [(group[0], n) for group, n in counts.items() if len(group) == 1]
    tied = [(" = ".join(group), n) for group, n in counts.items() if len(group) > 1]
    conditions = table[keys].drop_duplicates().shape[0]
    parts = [f"{m} alone in {n}" for m, n in alone] + [f"{m} tied in {n}" for m, n in tied]
    return f"best mean error, out of {conditions} conditions: " + ", ".join(parts) + "."


def origin_note(
    study: str,
    methods: Sequence[str],
    paper: PaperMethods = NO_PAPER,
    config: Mapping | None = None,
) -> str:
    """A sentence naming the paper's methods and the additions among ``methods``, the external
    ones (written by rules of their own, ``external_estimators`` in ``config``) separately,
    and, when there are external ones, what the benchmark does not check of them."""
    letter, paper_methods = paper
    external = set()
    if config is not None and study in config.get("studies", {}):
        external = set(jb_config.estimator_names(config, study, source="external"))
    ours = [m for m in paper_methods if m in methods]
    added = [m for m in methods if m not in paper_methods and m not in external]
    outside = [m for m in methods if m in external and m not in paper_methods]
    parts = [f"Paper {letter}'s methods: {', '.join(ours) or 'none'}." if letter else ""]
    parts.append(f"Added, built in: {', '.join(added) or 'none'}.")
    parts.append(f"Added, external (a rule of their own): {', '.join(outside) or 'none'}.")
    if outside:
        # A reader of the ranking is told what is not checked where the methods are listed.
        parts.append(external_note(landlock.abi_version() > 0))
    return " ".join(p for p in parts if p)


def external_note(confined: bool) -> str:
    """What the benchmark does not check of an external estimator: its seconds, and, unless
    its program's reads are ``confined`` (by Landlock, as its job runs on this machine), the
    files its program opens."""
    seconds = "An external estimator's seconds are as its program reports them"
    if confined:
        return (
            f"{seconds}; under results/ its program may open only the blind copies and its "
            "rule's own files, as the kernel confines it (Landlock) "
            "(README, 'Adding an estimator')."
        )
    return (
        f"{seconds}, and the benchmark checks the files its rule declares, not those its "
        "program opens: this kernel has no Landlock to confine it "
        "(README, 'Adding an estimator')."
    )


def condition_label(study: str, values: Sequence[object]) -> str:
    """A row label with units, as the study words its grid keys (:meth:`Study.condition_label`),
    e.g. ``("M", 5, 0.5)`` of ``cmc`` -> "M set, ±5°, 0.5 mm noise"."""
    return get_study(study).condition_label(values)


def incomplete(trials: int, converged: int, failed: int) -> bool:
    """Whether a cell's mean hides trouble: some trials failed (no error) or did not converge
    (an error, but from an estimate the method itself did not stand behind)."""
    return failed > 0 or converged < trials


def cell_text(value: float, flagged: bool) -> str:
    """A heat-map cell: the mean to 3 significant digits (``inf`` beyond the floats), "†"
    when :func:`incomplete`; "failed" when no trial has an error."""
    if np.isnan(value):
        return "failed"
    return f"{value:.3g}" + ("†" if flagged else "")


_BEYOND_COLOR = "#c51b7d"


def _wide(table: pd.DataFrame, keys: list[str], column: str, methods: Sequence[str]):
    """``column`` as a condition × method frame, methods in the given order (NaN where a
    method has no row for a condition)."""
    wide = table.set_index([*keys, "method"])[column].unstack("method")
    return wide.reindex(columns=list(methods))


def _heatmap(ax, table: pd.DataFrame, study: str, methods: Sequence[str], paper: Sequence[str]):
    """Condition × method heat map of mean error (log colour scale), values printed in the
    cells, the best of each condition outlined. Returns the image for a colour bar."""
    from matplotlib.colors import LogNorm
    from matplotlib.patches import Rectangle

    keys = list(get_study(study).grid_keys)
    wide = _wide(table, keys, _mean_column(study), methods)
    flagged = _wide(
        table.assign(
            _flag=[
                incomplete(t, c, f)
                for t, c, f in zip(
                    table["trials"], table["converged"], table["failed"], strict=True
                )
            ]
        ),
        keys,
        "_flag",
        methods,
    )
    flagged = flagged.fillna(False).astype(bool)
    best = _wide(table, keys, "best", methods).fillna(False).astype(bool)
    values = wide.to_numpy(dtype=float)
    low, high = display_limits(values)
    # One far-off cell must not stretch the colours of all the others: the scale ends at twice
    # the 95th percentile, and a cell beyond it takes the "beyond" colour, its value printed.
    finite = values[np.isfinite(values) & (values > 0)]
    if finite.size:
        high = max(min(high, 2 * float(np.percentile(finite, 95))), low * 10)
    beyond = values > high
    # An error of exactly zero (noise-free data) cannot sit on a log scale: floor it. A mean
    # beyond the scale, inf included, takes the colour above its top.
    shown = np.where(np.isnan(values), np.nan, np.clip(values, low, 10 * high))
    plt = pyplot()
    cmap = plt.get_cmap("viridis").with_extremes(bad="0.85", over=_BEYOND_COLOR)
    norm = LogNorm(vmin=low, vmax=high)
    image = ax.imshow(np.ma.masked_invalid(shown), cmap=cmap, norm=norm, aspect="auto")
    size = 8 if len(methods) <= 8 else 6
    for (row, col), value in np.ndenumerate(values):
        dark = beyond[row, col] or (np.isfinite(value) and norm(shown[row, col]) < 0.55)
        ax.text(
            col,
            row,
            cell_text(value, bool(flagged.iat[row, col])),
            ha="center",
            va="center",
            fontsize=size,
            color="white" if dark else "black",
        )
        if best.iat[row, col]:
            ax.add_patch(Rectangle((col - 0.5, row - 0.5), 1, 1, fill=False, ec="#e41a1c", lw=2.2))
    ax.set_xticks(range(len(methods)), [m if m in paper else f"{m}*" for m in methods])
    if len(methods) > 5 or max(map(len, methods)) > 6:
        plt.setp(ax.get_xticklabels(), rotation=40, ha="right", rotation_mode="anchor")
    labels = [condition_label(study, i if isinstance(i, tuple) else (i,)) for i in wide.index]
    ax.set_yticks(range(len(labels)), labels, fontsize=8)
    ax.set_ylabel("condition: " + ", ".join(get_study(study).key_label(k) for k in keys))
    ax.set_xlabel("method (best first; * not in the paper)")
    return image


def _rank_bars(
    ax, ranks: pd.DataFrame, styles: Mapping[str, Mapping], paper: Sequence[str]
) -> None:
    """Horizontal bars of each method's mean rank, best at the top, additions hatched."""
    from matplotlib.patches import Patch

    y = np.arange(len(ranks))
    for position, row in zip(y, ranks.itertuples(), strict=True):
        ax.barh(
            position,
            row.mean_rank,
            color=styles[row.method]["color"],
            hatch=None if row.method in paper else "//",
            edgecolor="0.2",
        )
        # Written beside the axes, not at the bar's end, so the axis can stop at the worst
        # possible rank.
        ax.annotate(
            f"{row.mean_rank:.2f}; {best_text(row.best_alone, row.best_tied, row.conditions)}",
            (1.0, position),
            xycoords=("axes fraction", "data"),
            xytext=(4, 0),
            textcoords="offset points",
            va="center",
            fontsize=7,
        )
    ax.set_yticks(y, list(ranks["method"]))
    ax.invert_yaxis()
    ax.set_xlim(0, len(ranks))
    ax.set_xticks(range(1, len(ranks) + 1, max(1, len(ranks) // 4)))
    ax.set_xlabel("mean rank\nover conditions (1 = best)", fontsize=8)
    ax.set_title("Overall", fontsize=9)
    ax.legend(
        handles=[
            Patch(facecolor="white", edgecolor="0.2", label="paper's method"),
            Patch(facecolor="white", edgecolor="0.2", hatch="//", label="added"),
        ],
        fontsize=7,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.3),
        ncol=2,
    )


_KIND_TITLES = {
    "center": "centre of rotation",
    "axis": "axis of rotation",
    "joint_center": "joint centre",
}


def extended_figure(collected: pd.DataFrame, study: str, paper: PaperMethods = NO_PAPER) -> Figure:
    """One figure per study: the condition × method heat map of mean error with each
    condition's best outlined, beside each method's mean rank.
    """
    table = extended_table(collected, study, paper)
    ranks = mean_ranks(table)
    methods = list(ranks["method"])
    styles = method_styles(methods)
    n_conditions = table[list(get_study(study).grid_keys)].drop_duplicates().shape[0]
    height = max(3.5, 0.3 * n_conditions + 1.8)
    bars_height = min(height, 0.35 * len(methods) + 1.4)
    heat_width = max(3.0, 0.8 * len(methods)) + 2.5
    # The middle column is room for the colour bar, an inset of the map the layout ignores.
    # The right column holds the method names, the bars and the notes written beside them:
    # wide enough that the bars keep room for their rank ticks.
    fig = pyplot().figure(figsize=(heat_width + 7.0, height), layout="constrained")
    outer = fig.add_gridspec(1, 3, width_ratios=[heat_width, 1.0, 6.0])
    heat = fig.add_subplot(outer[0, 0])
    right = outer[0, 2].subgridspec(2, 1, height_ratios=[bars_height, height - bars_height + 1e-3])
    bars = fig.add_subplot(right[0, 0])
    image = _heatmap(heat, table, study, methods, paper[1])
    beyond = bool((table[_mean_column(study)] > image.norm.vmax).any())
    # An inset the map's own height: a colour bar stolen from the grid cell is sized by the
    # layout and ends up shorter than a tall map.
    colorbar = fig.colorbar(
        image,
        cax=heat.inset_axes([1.02, 0.0, 0.035, 1.0]),
        extend="max" if beyond else "neither",
    )
    colorbar.set_label(f"mean error ({_unit(study).strip()}), log scale")
    _rank_bars(bars, ranks, styles, paper[1])
    kind = _KIND_TITLES.get(get_study(study).kind, get_study(study).kind.replace("_", " "))
    fig.suptitle(
        f"{study_title(study)} ({kind}): every estimator's mean error per condition "
        f"({_unit(study).strip()})\nred outline = best (or tied) in the condition; "
        "† = some trials failed or did not converge"
        + ("; magenta = beyond the colour scale (value printed)" if beyond else ""),
        fontsize=10,
    )
    return fig
