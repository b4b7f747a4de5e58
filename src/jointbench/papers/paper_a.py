"""Paper A: Chang & Pollard (2007), centre of rotation — Fig 3, Fig 4, Table 2, claims A1–A13.

Each measurement returns the quantity its published entry's typed tolerance compares (see
``paper_a.yaml`` beside this module); drawing lives in :mod:`jointbench.figures.paper_a`.
"""

from __future__ import annotations

import functools
import itertools
from pathlib import Path

import numpy as np
import pandas as pd

from jointbench.comparison.published import Measurements
from jointbench.comparison.tolerance import wilson_interval
from jointbench.configuration.studies import get_study
from jointbench.figures import paper_a as draw
from jointbench.papers.base import (
    Inputs,
    Measured,
    Output,
    Paper,
    PerLevel,
    PublishedTable,
    Table,
)
from jointbench.papers.common import (
    RECORDED_COLUMN,
    Declared,
    NotMeasured,
    at_levels,
    claims_headline,
    claims_output,
    measured_claims,
    one_step_changes,
    require_declared,
    rows_at,
    with_columns,
)
from jointbench.resultfiles.formatting import number
from jointbench.simulate.cmc import LOCAL_MINIMUM, marker_positions

__all__ = ["PAPER", "example_ordering_share", "measure", "radius_errors"]

METHODS = draw.PAPER_METHODS
SPHERE_FITS = ("LS", "NM", "BC", "IS")
CONDITION = draw.CONDITION
FIG3_CONDITION = draw.FIG3_CONDITION

#: The claims whose checks measure one value per level: each check measures at these levels,
#: and the published lists are held to as many when the file is read. A3's levels are those of
#: the conditions Fig 4 draws its bounds at.
A2_LEVELS = PerLevel("A2", "noise_mm", "BC's converged trials at the M set and the smallest RoM")
A3_LEVELS = PerLevel(
    "A3",
    "noise_mm",
    "the lowest of the five methods' means at the M set and ±5° RoM",
    tuple(condition["noise_mm"] for condition in draw.FIG4_STATED["A3"][0]),
)
A7_LEVELS = PerLevel("A7", "rom_deg", "IS's local minima at the M set", (5, 15))


def _wide(means: pd.DataFrame, methods=METHODS) -> pd.DataFrame:
    """Mean error per condition (rows) of each of ``methods`` (columns); :class:`NotMeasured`
    naming those this run lacks."""
    wide = means.pivot_table(index=CONDITION, columns="method", values="mean_error_mm")
    return with_columns(wide, methods, "method")


def _trial_errors(collected: pd.DataFrame, methods=METHODS) -> dict[tuple, pd.DataFrame]:
    """Per condition, the error of each method (columns) in each BC-converged trial (rows)."""
    rows = draw.bc_converged(collected[collected["method"].isin(methods)])
    return {
        condition: part.pivot_table(index="trial", columns="method", values="error_mm")
        for condition, part in rows.groupby(CONDITION, observed=True)
    }


def _excess(trials: pd.DataFrame, method: str, reference: str) -> tuple[float, float]:
    """Mean of ``method``'s error less ``reference``'s over the same trials, and its standard
    error (the noise of a difference of two means over paired trials)."""
    difference = (trials[method] - trials[reference]).dropna()
    if len(difference) < 2:
        return float(difference.mean()), float("nan")
    return float(difference.mean()), float(difference.std(ddof=1) / np.sqrt(len(difference)))


def _tied_best(trials: pd.DataFrame, methods) -> list[str]:
    """The method with the lowest mean error and every method whose mean exceeds it by less
    than the standard error of the difference: a tie within the noise of the means."""
    means = trials[list(methods)].mean()
    best = str(means.idxmin())
    tied = [best]
    for method in methods:
        if method != best:
            excess, noise = _excess(trials, method, best)
            if excess < noise:
                tied.append(method)
    return tied


def _is_worst_beyond_noise(trials: pd.DataFrame, method: str, others) -> bool:
    """Whether ``method``'s mean exceeds every one of ``others`` by more than its noise."""
    for other in others:
        excess, noise = _excess(trials, method, other)
        if not excess > noise:
            return False
    return True


def _a1(collected, means):
    # "for all methods": the trend is read per method, and the least consistent method counts.
    shares = {}
    for method, part in means.groupby("method"):
        by_noise = part.pivot_table(
            index=["marker_set", "rom_deg"], columns="noise_mm", values="mean_error_mm"
        )
        by_rom = part.pivot_table(
            index=["marker_set", "noise_mm"], columns="rom_deg", values="mean_error_mm"
        )
        steps = np.concatenate([one_step_changes(by_noise) > 0, one_step_changes(by_rom) < 0])
        if not steps.size:
            # Two levels on one line of the grid: a lack no name says.
            raise NotMeasured(f"A1 needs two noise levels or two RoMs measured for {method}", {})
        shares[method] = float(np.mean(steps))
    if not shares:
        raise NotMeasured("A1 needs a method of paper A; this run has none", {"method": METHODS})
    weakest = min(shares, key=shares.get)
    text = ", ".join(f"{m} {shares[m]:.0%}" for m in METHODS if m in shares)
    return Measured(
        shares[weakest],
        f"error grows in one-step comparisons: {text}; least consistent {weakest}",
    )


def _a2(collected, means, levels):
    """BC's converged trials at the M set and the smallest RoM, counted at each of ``levels``
    (:data:`A2_LEVELS`' in the paper's design, in their order); :class:`NotMeasured` when the
    run lacks one: counts at other levels would be compared with the paper's as if they were
    its."""
    bc = rows_at(collected, "BC is not in this run at the M set", method="BC", marker_set="M")
    bc = bc[bc["rom_deg"] == collected["rom_deg"].min()]
    converged = bc.groupby(A2_LEVELS.axis)["converged"].sum()
    missing = tuple(level for level in levels if level not in converged.index)
    if missing:
        shown = ", ".join(map(str, missing))
        raise NotMeasured(
            f"this run has no {A2_LEVELS.axis} {shown} for BC at the M set",
            {A2_LEVELS.axis: missing},
        )
    n_trials = collected["trial"].nunique()
    counts = [int(converged[level]) for level in levels]
    value = {"count": counts, "trials": [n_trials] * len(counts)}
    return Measured(value, f"{counts} of {n_trials}")


def _a3_lack(levels) -> str:
    """Why A3 is not measured, its ``levels`` of :data:`A3_LEVELS` without a mean."""
    return f"A3: no mean error at the M set's smallest RoM at noise {list(levels)} mm"


def _a3(collected, means):
    m_set = rows_at(means, _a3_lack(A3_LEVELS.levels), marker_set="M")
    cell = m_set[m_set["rom_deg"] == means["rom_deg"].min()]
    lowest = cell.groupby(A3_LEVELS.axis)["mean_error_mm"].min()
    missing = tuple(
        level for level in A3_LEVELS.levels if not np.isfinite(lowest.get(level, np.nan))
    )
    if missing:
        raise NotMeasured(_a3_lack(missing), {A3_LEVELS.axis: missing})
    values = [float(lowest[level]) for level in A3_LEVELS.levels]
    rows = draw.bc_converged(collected)
    rows = rows[(rows["marker_set"] == "M") & (rows["rom_deg"] == rows["rom_deg"].min())]
    ls = rows.loc[rows["method"] == "LS", "error_mm"]
    nm = rows[(rows["method"] == "NM") & (rows["noise_mm"] == 1.0)]["error_mm"]
    lowest_text = ", ".join(
        f"{value:.1f} mm ({level} mm)"
        for value, level in zip(values, A3_LEVELS.levels, strict=True)
    )
    # The notes on LS and NM are left out where this run has none of their trials.
    notes = [f"lowest mean {lowest_text}"]
    if not ls.empty:
        notes.append(f"LS's largest error in a BC-converged trial {ls.max():.1f} mm")
    if not nm.empty:
        notes.append(f"NM at 1.0 mm: mean {nm.mean():.1f} mm, median {nm.median():.1f} mm")
    return Measured(values, "; ".join(notes))


def _a4(collected, means):
    wide = _wide(means, SPHERE_FITS)
    trials = _trial_errors(collected, SPHERE_FITS)
    others = [m for m in SPHERE_FITS if m != "LS"]
    smallest = wide.index.get_level_values("rom_deg").min()
    # The set whose smallest RoM the sentence excepts, spelt once for the selection and its lack.
    excepted = "M"
    exception = [c for c in wide.index if c[0] == excepted and c[1] == smallest]
    covered = wide.drop(index=exception)
    # LS worse: the largest mean of the sphere fits in every condition the sentence covers.
    worst = covered[list(SPHERE_FITS)].idxmax(axis=1)
    share_worst = float(np.mean(worst == "LS"))
    # Progressively: LS's excess over the best other sphere fit grows with every step of noise
    # up (fixed RoM) and RoM down (fixed noise); a step counts against only if the excess
    # shrinks by more than the noise of the two means.
    excess = {c: _excess(trials[c], "LS", _best_other(trials[c], others)) for c in covered.index}
    roms = sorted(wide.index.get_level_values("rom_deg").unique(), reverse=True)
    noises = sorted(wide.index.get_level_values("noise_mm").unique())
    steps = []
    for marker_set in sorted(wide.index.get_level_values("marker_set").unique()):
        for rom in roms:
            steps += [
                ((marker_set, rom, a), (marker_set, rom, b)) for a, b in itertools.pairwise(noises)
            ]
        for noise in noises:
            steps += [
                ((marker_set, a, noise), (marker_set, b, noise))
                for a, b in itertools.pairwise(roms)
            ]
    steps = [(a, b) for a, b in steps if a in excess and b in excess]
    against = [
        (a, b)
        for a, b in steps
        if excess[a][0] - excess[b][0] > np.hypot(excess[a][1], excess[b][1])
    ]
    # The exception, as the sentence reads: the progression breaks at the M set's smallest RoM,
    # i.e. there LS's excess shrinks beyond the noise at one noise step or more.
    at_exception = [c for c in exception if c in trials]
    if len(at_exception) < 2:
        raise NotMeasured(
            "A4's exception needs two noise levels or more at the M set's smallest RoM",
            {"marker_set": (excepted,)},
        )
    excess_there = {
        c: _excess(trials[c], "LS", _best_other(trials[c], others)) for c in at_exception
    }
    breaks = [
        (a, b)
        for a, b in itertools.pairwise(sorted(excess_there, key=lambda c: c[2]))
        if excess_there[a][0] - excess_there[b][0]
        > np.hypot(excess_there[a][1], excess_there[b][1])
    ]
    # A note, not the criterion: whether LS is still the worst sphere fit there.
    worst_there = [c for c in at_exception if _is_worst_beyond_noise(trials[c], "LS", others)]
    growth = ", ".join(
        f"{excess_there[c][0]:.1f}" for c in sorted(excess_there, key=lambda c: c[2])
    )
    text = (
        f"LS worst sphere fit in {int((worst == 'LS').sum())} of {len(covered)} conditions; "
        f"its excess over the best other grows in {len(steps) - len(against)} of {len(steps)} "
        f"steps; at M, {smallest:g}° its excess ({growth} mm with rising noise) shrinks beyond "
        f"noise at {len(breaks)} of {max(len(excess_there) - 1, 0)} steps. Note: there LS is "
        f"still the worst sphere fit beyond noise at {len(worst_there)} of "
        f"{len(at_exception)} noise levels"
    )
    return Measured(
        {
            "ls_worst_share": share_worst,
            "steps_against_progression": len(against),
            "exception_steps_breaking": len(breaks),
        },
        text,
    )


def _best_other(trials: pd.DataFrame, others) -> str:
    """The method of ``others`` with the lowest mean error over ``trials``."""
    return str(trials[list(others)].mean().idxmin())


def _a5(collected, means):
    wide = _wide(means)
    others = wide[[m for m in METHODS if m != "MA"]].min(axis=1)
    excess_h = float(at_levels(wide["MA"] - others, marker_set="H").max())
    # "Compared well to the four sphere-fitting solutions": MA's mean lies within their range.
    m_set = at_levels(wide, marker_set="M")
    spheres = m_set[list(SPHERE_FITS)]
    inside = (m_set["MA"] >= spheres.min(axis=1)) & (m_set["MA"] <= spheres.max(axis=1))
    below_ls = m_set["MA"] < m_set["LS"]
    ratio_m = float(at_levels(wide["MA"] / others, marker_set="M").median())
    return Measured(
        {"h_excess_mm": excess_h, "m_share_within_sphere_fits": float(inside.mean())},
        f"H: up to {excess_h:.1f} mm worse than the best other; M: within the range of the four "
        f"sphere fits in {int(inside.sum())} of {len(inside)} conditions, below LS in "
        f"{int(below_ls.sum())} of {len(below_ls)}; note: median ratio to the best method "
        f"{ratio_m:.2f}",
    )


def _a6(collected, means):
    trials = _trial_errors(collected)
    lowest = {c: str(with_columns(t, METHODS, "method").mean().idxmin()) for c, t in trials.items()}
    wins = [c for c, best in lowest.items() if best == "IS"]
    n = len(trials)
    share = len(wins) / n
    # A note, not the criterion: ties within the noise of the means (a method whose mean
    # exceeds the lowest by less than the standard error of the paired difference shares it;
    # a k-way tie gives each 1/k), and the wins that are clear of every such tie.
    tied = {c: _tied_best(t, METHODS) for c, t in trials.items()}
    credit = sum(1 / len(best) for best in tied.values() if "IS" in best)
    clear = sum(1 for best in tied.values() if best == ["IS"])
    narrow = sum(1 for c in wins if tied[c] != ["IS"])
    text = (
        f"IS lowest mean in {len(wins)} of {n} ({share:.1%}; "
        f"{len(wins) - 0.55 * n:+.1f} conditions from 55 %). Note: {narrow} of those wins are "
        f"within the noise of the means; with ties split {credit:.1f} of {n} "
        f"({credit / n:.1%}); clear wins {clear} of {n}"
    )
    return Measured(share, text)


def _a7(collected, means):
    if LOCAL_MINIMUM not in collected.columns:
        lack = {RECORDED_COLUMN: (LOCAL_MINIMUM,)}
        raise NotMeasured("local minima not recorded in this run", lack)
    low, high = A7_LEVELS.levels
    lacking = f"IS at the M set is not in this run at both {low}° and {high}°"
    # The paper counts at 5° among the BC-converged trials, at 15° among all trials.
    is_m = {"method": "IS", "marker_set": "M"}
    at_low = rows_at(draw.bc_converged(collected), lacking, **is_m, **{A7_LEVELS.axis: low})
    at_high = rows_at(collected, lacking, **is_m, **{A7_LEVELS.axis: high})
    counts = [int(at_low[LOCAL_MINIMUM].sum()), int(at_high[LOCAL_MINIMUM].sum())]
    sizes = [len(at_low), len(at_high)]
    return Measured(
        {"count": counts, "trials": sizes},
        f"{counts[0]} of {sizes[0]} at {low}°, {counts[1]} of {sizes[1]} at {high}°",
    )


def _nm_gaps(wide: pd.DataFrame) -> pd.Series:
    """NM's mean less the best of the five (zero where NM is best)."""
    return wide["NM"] - wide[list(METHODS)].min(axis=1)


def _a8(collected, means):
    # The paper's reading: "for the conditions for which all trials converged (Fig. 4)", the
    # conditions in which BC converged in every trial. The other reading, all 18 conditions of
    # Fig 4 each over its BC-converged trials (83 % is 15/18, not k/16), is shown beside it.
    wide = _wide(means)
    gap = _nm_gaps(wide)
    n_trials = collected["trial"].nunique()
    complete = means.groupby(CONDITION)["n_trials"].min() == n_trials
    converged = gap.loc[complete[complete].index]
    if converged.empty:
        # A lack of a condition complete in BC's convergence, which no name the check selects
        # by says (BC's converged trials are counted by condition_means).
        raise NotMeasured("no condition in which BC converged in every trial", {})
    share, largest = float(np.mean(converged < 0.5)), float(converged.max())
    where = gap.idxmax()
    text = (
        f"the {len(converged)} conditions where BC converged in every trial: within 0.5 mm in "
        f"{int((converged < 0.5).sum())} of {len(converged)} ({share:.0%}); largest gap "
        f"{largest:.2f} mm. Other reading, all {len(gap)} conditions (BC-converged trials): "
        f"within 0.5 mm in {int((gap < 0.5).sum())} of {len(gap)} ({np.mean(gap < 0.5):.0%}); "
        f"largest gap {gap.max():.1f} mm at {where[0]}, {where[1]:g}°, {where[2]:g} mm "
        f"(NM {wide.loc[where, 'NM']:.1f} mm, best {wide.loc[where, list(METHODS)].min():.1f} mm)"
    )
    return Measured({"share_within_0_5_mm": share, "largest_gap_mm": largest}, text)


def _a9(collected, means):
    cell = rows_at(
        means[np.isfinite(means["mean_error_mm"])],
        "A9: no LS mean at the H set, 15° and 1.0 mm in this run",
        marker_set="H",
        rom_deg=15,
        noise_mm=1.0,
        method="LS",
    )
    value = float(cell["mean_error_mm"].iloc[0])
    return Measured(value, f"{value:.1f} mm")


def _a10(collected, means):
    wide = _wide(means)
    by_cell = at_levels(wide, marker_set="H") / at_levels(wide, marker_set="M")
    # A (RoM, noise) cell with no mean at one set (BC converged in none of its trials there)
    # has no ratio: the medians are over the cells that have one, and the ranges without any
    # are named, not printed as NaN.
    ratio = by_cell.median()
    unmeasured = tuple(m for m in METHODS if not np.isfinite(ratio[m]))
    if unmeasured:
        raise NotMeasured(
            f"no (RoM, noise) cell has a mean of {', '.join(unmeasured)} at both marker sets",
            {"method": unmeasured},
        )
    better_h, worse_h = ("IS", "BC", "NM"), ("LS", "MA")
    wrong = sum(ratio[m] >= 1 for m in better_h) + sum(ratio[m] <= 1 for m in worse_h)
    text = ", ".join(f"{m} {ratio[m]:.2f}" for m in METHODS)
    ls = by_cell["LS"].groupby(level="rom_deg").median()
    by_rom = ", ".join(f"{rom:g}° {value:.2f}" for rom, value in ls.dropna().items())
    missing = ", ".join(f"{rom:g}°" for rom, value in ls.items() if not np.isfinite(value))
    none_at = f"; no cell with a mean at both sets at {missing}" if missing else ""
    return Measured(int(wrong), f"median H/M error ratio: {text}; LS by RoM: {by_rom}{none_at}")


def example_ordering_share(collected: pd.DataFrame) -> tuple[int, int]:
    """``(k, n)``: of the ``n`` trials at Fig 3's condition in which BC converged and every
    paper method has an error, the ``k`` in which LS errs most and NM least, the ordering of
    paper A's Fig 3 example; :class:`NotMeasured` when the run has no such trial."""
    lacking = f"no trial at paper A's Fig 3 condition {FIG3_CONDITION}"
    rows = rows_at(draw.bc_converged(collected), lacking, **FIG3_CONDITION)
    errors = rows[rows["method"].isin(METHODS)].pivot_table(
        index="trial", columns="method", values="error_mm"
    )
    errors = errors.dropna()
    ordering = ("LS", "NM")  # the example's largest error and its smallest
    if errors.empty or not set(ordering) <= set(errors.columns):
        raise NotMeasured(lacking, {"method": ordering})
    largest, smallest = ordering
    example = (errors.idxmax(axis=1) == largest) & (errors.idxmin(axis=1) == smallest)
    return int(example.sum()), len(example)


def _a11(collected, means):
    k, n = example_ordering_share(collected)
    low, high = wilson_interval(k, n)
    sample = draw.choose_fig3_trial(collected)
    errors = collected[collected["trial"] == sample]
    for key, value in FIG3_CONDITION.items():
        errors = errors[errors[key] == value]
    errors = errors[errors["method"].isin(METHODS)].set_index("method")["error_mm"]
    shown = ", ".join(f"{m} {errors[m]:.1f}" for m in METHODS if m in errors)
    return Measured(
        k / n,
        f"the example's ordering (LS largest, NM smallest) in {k} of {n} BC-converged trials "
        f"({k / n:.0%}, 95 % interval {low:.0%}–{high:.0%}); Fig 3's trial {sample}: {shown} mm",
    )


def radius_errors(collected: pd.DataFrame, methods=("LS", "NM")) -> pd.DataFrame:
    """Mean signed radius error [mm] (``radius_error_mm``: fitted less true, negative for an
    underestimate) per condition (rows, :data:`CONDITION`) and method (columns), over the
    trials that fitted radii; :class:`NotMeasured` when the run fitted none of one of
    ``methods``."""
    with_columns(collected, ["radius_error_mm"], RECORDED_COLUMN)
    rows = collected[collected["method"].isin(methods)]
    errors = rows.pivot_table(index=CONDITION, columns="method", values="radius_error_mm")
    return with_columns(errors, methods, "method", "method with fitted radii")


def _a13(collected, means):
    errors = radius_errors(collected)
    roms = errors.index.get_level_values("rom_deg")
    smallest, largest = roms.min(), roms.max()
    if smallest == largest:
        # Two RoMs, whichever: a lack no name says.
        raise NotMeasured("one RoM in this run: reduced RoM cannot be told from the others", {})
    small, large = errors.xs(smallest, level="rom_deg"), errors.xs(largest, level="rom_deg")
    holds = (
        (small["LS"] < 0)
        & (small["NM"] > small["LS"])
        & (small["LS"] < large["LS"].reindex(small.index))
    )
    by_rom = errors.groupby(level="rom_deg").mean()
    shown = "; ".join(
        f"±{rom:g}°: LS {row.LS:+.2f}, NM {row.NM:+.2f}" for rom, row in by_rom.iterrows()
    )
    failing = ", ".join(f"{m} set {n:g} mm" for m, n in small.index[~holds])
    return Measured(
        int((~holds).sum()),
        f"mean signed radius error over the marker sets and noise levels, mm: {shown}; "
        f"{int(holds.sum())} of {len(holds)} cells as stated"
        + (f" (not at {failing})" if failing else ""),
    )


_CLAIMS = {
    "A1": _a1,
    "A3": _a3,
    "A4": _a4,
    "A5": _a5,
    "A6": _a6,
    "A7": _a7,
    "A8": _a8,
    "A9": _a9,
    "A10": _a10,
    "A11": _a11,
    "A13": _a13,
}


def _marker_distances(config) -> dict[str, Measured]:
    settings = config["studies"].get("cmc", {})
    protocol = get_study("cmc").protocol(settings.get("protocol"))
    out = {}
    for name in protocol.directions:
        distances = np.linalg.norm(marker_positions(protocol, name), axis=1)
        out[f"A-T1-{name}"] = Measured(
            distances.tolist(), str([round(float(d), 3) for d in distances])
        )
    return out


def _our_times(collected: pd.DataFrame, published: dict) -> pd.DataFrame:
    """Table 2 of our times per trial by method (:func:`jointbench.figures.paper_a.table2`);
    :class:`NotMeasured` when the run recorded no times."""
    with_columns(collected, ["seconds"], RECORDED_COLUMN)
    return draw.table2(collected, _published_seconds(published)).set_index("method")


def _timings(collected: pd.DataFrame, published: dict) -> dict[str, Measured]:
    ours = _our_times(collected, published)
    return {
        # The paper's value is a mean, so ours is too; the words compare medians (robust).
        f"A-T2-{method}": Measured(
            float(row.mean_s),
            f"{number(row.mean_s)} s (median {number(row.median_s)} s: {row.vs_paper_median})",
        )
        for method, row in ours.iterrows()
    }


def _fastest(collected: pd.DataFrame, means: pd.DataFrame, published: dict) -> Measured:
    """Claim A12: how many of the other methods are at least as fast as NM by median time per
    trial over the BC-converged trials (:func:`jointbench.figures.paper_a.table2`); ``means``
    unread, as every claim check is given them."""
    ours = _our_times(collected, published)
    fastest = "NM"  # the sentence's, whose speed every other method's is set against
    if fastest not in ours.index or len(ours) < 2:
        lack = {"method": (fastest,)}
        raise NotMeasured(f"{fastest} and at least one other method are needed to rank speed", lack)
    medians = ours["median_s"].sort_values(kind="stable")
    others = medians.drop(fastest)
    as_fast = int((others <= medians[fastest]).sum())
    order = " < ".join(f"{method} {seconds:.2g} s" for method, seconds in medians.items())
    text = f"by median: {order}; {as_fast} of {len(others)} as fast as {fastest}"
    return Measured(as_fast, text)


def _published_seconds(published) -> dict[str, float]:
    return {
        entry["id"].removeprefix("A-T2-"): entry["published"]
        for entry in published["values"]
        if entry["id"].startswith("A-T2-")
    }


def measure(inputs: Inputs) -> Measurements:
    """Every published value and claim of paper A, measured from the collected cmc results.

    A claim whose data are absent from the run (a method switched off, a condition not in the
    grid) is left out, and so is reported as not applicable, saying which were absent.
    """
    collected = inputs.collected
    means = draw.condition_means(collected)
    out = _marker_distances(inputs.config)
    declared = Declared(PAPER, inputs.published)
    try:
        out.update(_timings(collected, inputs.published))
    except NotMeasured as lack:
        # No times recorded in this run: Table 2 is not measured, unless the check misread.
        require_declared("Table 2 (A-T2)", lack, declared)
    # A2 counts at the levels of the paper's design its published counts belong to.
    a2_levels = A2_LEVELS.levels_in(inputs.published["design"]["grid"])
    claims = {
        **_CLAIMS,
        "A2": functools.partial(_a2, levels=a2_levels),
        "A12": functools.partial(_fastest, published=inputs.published),
    }
    return measured_claims(claims, collected, means, declared=declared).with_values(out)


def _fig4(inputs: Inputs):
    return draw.fig4(inputs.collected, inputs.published)


def _fig3(inputs: Inputs):
    ((trials, metadata),) = inputs.datasets
    sample = draw.choose_fig3_trial(inputs.collected)
    rows = inputs.collected[
        (inputs.collected["marker_set"] == FIG3_CONDITION["marker_set"])
        & (inputs.collected["rom_deg"] == FIG3_CONDITION["rom_deg"])
        & (inputs.collected["noise_mm"] == FIG3_CONDITION["noise_mm"])
        & (inputs.collected["trial"] == sample)
        & inputs.collected["method"].isin(METHODS)
    ]
    example = next(c for c in inputs.published["claims"] if c["id"] == "A11")["published"]
    return draw.fig3(
        trials.segments["moving"][sample],
        np.asarray(metadata["truth"]["center"]),
        rows,
        example,
        chosen=draw.fig3_chosen_text(inputs.collected, sample),
    )


def _table2(inputs: Inputs) -> Table:
    return Table(
        draw.table2(inputs.collected, _published_seconds(inputs.published)),
        title="Paper A Table 2: computation time per trial (trials where BC converged)",
        note=draw.timing_note(),
        headers=TABLE2_HEADERS,
    )


#: Table 2's headers for people, with units.
TABLE2_HEADERS = {
    "mean_s": "our mean time per trial (s)",
    "median_s": "our median time per trial (s)",
    "paper_matlab_s": "paper's mean MATLAB time per trial (s)",
    "speedup_median": "speed-up by median (×)",
    "speedup_mean": "speed-up by mean (×)",
    "vs_paper_median": "against the paper, by median",
    "vs_paper_mean": "against the paper, by mean",
}


def _speedups(tables) -> str:
    return draw.table2_headline(tables["paper_a_table2"])


PAPER = Paper(
    key="paper_a",
    letter="A",
    title="Paper A: centre of rotation",
    citation="Chang & Pollard (2007), Constrained least-squares optimization for robust "
    "estimation of center of rotation, J Biomech 40:1392",
    study="cmc",
    methods=METHODS,
    published=Path(__file__).with_name("paper_a.yaml"),
    measure=measure,
    # claims A1–A13, each measured per level with its levels
    declares=(
        "A1",
        A2_LEVELS,
        A3_LEVELS,
        *("A4", "A5", "A6"),
        A7_LEVELS,
        *(f"A{number}" for number in range(8, 14)),
    ),
    tables=(
        # Table 1's rows: the marker sets, each cell the set's row of three distances under
        # "Marker number 1 2 3"; Table 2's columns: the five methods, as printed.
        PublishedTable.grid(
            "Table 1", "A-T1-{}".format, ("M", "H"), lists=("marker 1", "marker 2", "marker 3")
        ),
        PublishedTable.grid("Table 2", "A-T2-{}".format, METHODS),
    ),
    outputs=(
        Output(
            "paper_a_fig4",
            "figure",
            _fig4,
            caption="Reproduces paper A Fig 4 (Chang & Pollard 2007, J Biomech 40:1392): mean "
            "CoR error of MA, LS, IS, BC and NM in the paper's two panels, (a) M marker set, "
            "(b) H marker set, conditions grouped by noise level (0.5, 1.0, 2.0 mm) with the "
            "range of motion increasing; log error scale. As in the paper, means are over the "
            "trials in which BC converged; n= under a tick gives the count where it is fewer "
            "than all trials. In black, the values the paper states about its Fig 4 where "
            "their conditions are: the lower bounds on every method's mean at M set, ±5° (§5.1.1) "
            "and LS's mean at H set, ±15°, 1.0 mm (§6).",
            summarises=("paper_a_claims",),
            headline=claims_headline,
        ),
        Output(
            "paper_a_fig3",
            "figure",
            _fig3,
            caption="Reproduces paper A Fig 3: one synthetic M-set trial at ±5° RoM and 1.0 mm "
            "noise, the median trial by NM error among the trials where BC converged (chosen "
            "by rule, stated on the figure), with the marker trajectories, the true CoR and each "
            "method's estimate on equal axis scales; the points on the right set each method's "
            "error on this trial (filled) beside the paper's example trial (hollow).",
            conditions=(FIG3_CONDITION,),
            summarises=("paper_a_claims",),
            headline=claims_headline,
        ),
        Output(
            "paper_a_table2",
            "table",
            _table2,
            caption="Reproduces paper A Table 2: mean and median computation time per trial "
            "and method over the BC-converged trials, beside the paper's MATLAB 6.5 mean times "
            "on a 3 GHz Pentium 4, compared by median (robust) and by mean; how and on which "
            "machine ours were timed is in the note.",
            summarises=("paper_a_table2",),
            headline=_speedups,
        ),
        claims_output(
            "paper_a",
            measure,
            "Claims A1–A11 of paper A §5.1.1, §6 and the figure captions, each recomputed from "
            "our results with the criterion stated in the table.",
        ),
    ),
)
