"""Paper B: Chang & Pollard (2007), dominant axis of rotation — Table 1, Fig 5, Fig 2, B1–B6.

Each measurement returns the quantity its published entry's typed tolerance compares (see
``paper_b.yaml`` beside this module); drawing lives in :mod:`jointbench.figures.paper_b`.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import numpy as np
import pandas as pd

from jointbench.comparison.published import Measurements, comparison_rows
from jointbench.figures import paper_b as draw
from jointbench.papers.base import Inputs, Measured, Output, Paper, PublishedTable, Table
from jointbench.papers.common import (
    Declared,
    NotMeasured,
    claims_headline,
    claims_output,
    measured_claims,
    one_step_changes,
    rows_at,
    with_columns,
)
from jointbench.resultfiles.formatting import number

__all__ = ["PAPER", "measure"]

METHODS = draw.PAPER_METHODS
CELL = draw.CELL
BREAKDOWN_DEG = draw.BREAKDOWN_DEG
# Fig 2's trials: a large FE range, then a limited FE range with a large AA range.
FIG2_CONDITIONS = (
    {"protocol": "knee", "fe_rom_deg": 90, "aa_ratio": 0.3},
    {"protocol": "knee", "fe_rom_deg": 30, "aa_ratio": 0.5},
)
_CELL_PREFIX = "B-T1-"
#: Table 1 as printed: rows protocol × cost, columns FE RoM [deg] × AA/FE ratio.
TABLE1_ROWS = (("knee", "mcp"), METHODS)
TABLE1_COLUMNS = ((30, 60, 90), (0.1, 0.3, 0.5, 0.7))


def _means(collected: pd.DataFrame) -> pd.DataFrame:
    return draw.cell_statistics(collected[collected["method"].isin(METHODS)])


def _b1(means):
    wide = means.pivot_table(
        index=["protocol", "method", "fe_rom_deg"], columns="aa_ratio", values="mean"
    )
    steps = one_step_changes(wide)
    if not steps.size:
        # Two ratios on one line of the grid, whichever: a lack no name says.
        raise NotMeasured(
            f"B1 needs two measured AA/FE ratios on a line of the grid; this run has ratios "
            f"{list(wide.columns)}",
            {},
        )
    share = float(np.mean(steps > 0))
    return Measured(share, f"error grows in {share:.0%} of one-step ratio increases")


#: The two lowest AA/FE ratios of the paper's grid, which B3 ("up to 0.3") and B4 ("the two
#: lowest") speak of; B2's "only at 0.1" is the lowest.
LOW_RATIOS = (0.1, 0.3)
B2_RATIO = LOW_RATIOS[0]


def _at_low_ratios(cells: pd.DataFrame, claim: str) -> pd.DataFrame:
    """The rows of ``cells`` (of :func:`_means`) at :data:`LOW_RATIOS`; :class:`NotMeasured`
    naming ``claim`` when the run lacks one of them, whose sentence it then has not tested."""
    low = cells[np.isclose(cells["aa_ratio"].to_numpy()[:, None], LOW_RATIOS).any(axis=1)]
    missing = [r for r in LOW_RATIOS if not np.isclose(low["aa_ratio"], r).any()]
    if missing:
        lack = {"aa_ratio": tuple(missing)}
        raise NotMeasured(
            f"{claim} speaks of the ratios {LOW_RATIOS}; this run lacks {missing}", lack
        )
    return low


def _b2(means):
    planar = rows_at(means, method="planar")
    at_ratio = np.isclose(planar["aa_ratio"], B2_RATIO)
    low, rest = planar[at_ratio], planar[~at_ratio]
    # "Only at 0.1" speaks of 0.1 and of every other ratio: both must have been run.
    if low.empty or rest.empty:
        raise NotMeasured(
            f"B2 needs planar cells at ratio {B2_RATIO:g} and at another ratio; this run has "
            f"ratios {sorted(planar['aa_ratio'].unique().tolist())}",
            {"aa_ratio": (B2_RATIO,)},
        )
    wrong = int((low["mean"] >= 5).sum() + (rest["mean"] < 5).sum())
    text = (
        f"ratio {B2_RATIO:g}: max {low['mean'].max():.1f}°; "
        f"other ratios: min {rest['mean'].min():.1f}°"
    )
    return Measured(wrong, text)


def _b3(means):
    combined = rows_at(means, method="combined")
    upto_03 = _at_low_ratios(combined, "B3")
    ratio, fe_roms = 0.5, (30, 60)  # "below 10° at 0.5 for the smaller ranges"
    at_05 = combined[(combined["aa_ratio"] == ratio) & combined["fe_rom_deg"].isin(fe_roms)]
    if at_05.empty:
        raise NotMeasured(
            f"B3 needs a combined cell at ratio {ratio:g} with FE {fe_roms[0]}° or {fe_roms[1]}°",
            {"aa_ratio": (ratio,), "fe_rom_deg": fe_roms},
        )
    wrong = int((upto_03["mean"] >= 5).sum() + (at_05["mean"] >= 10).sum())
    text = (
        f"ratio ≤ 0.3: max {upto_03['mean'].max():.1f}°; "
        f"0.5 at FE 30/60: max {at_05['mean'].max():.1f}°"
    )
    return Measured(wrong, text)


def _b4(means):
    low = _at_low_ratios(means, "B4").pivot_table(
        index=["protocol", "fe_rom_deg", "aa_ratio"], columns="method", values="mean"
    )
    # A cell one of the two costs was not run in compares nothing.
    costs = ("radial", "combined")
    low = with_columns(low, costs, "method").dropna()
    radial, combined = costs
    if low.empty:
        raise NotMeasured(
            f"B4 needs {radial} and {combined} cells at a ratio up to {LOW_RATIOS[-1]:g}",
            {"method": costs, "aa_ratio": LOW_RATIOS},
        )
    holds = low[radial] > low[combined]
    return Measured(
        int((~holds).sum()), f"radial > combined in {int(holds.sum())} of {len(holds)} cells"
    )


def _b5(means):
    wide = means.pivot_table(
        index=["method", "fe_rom_deg", "aa_ratio"], columns="protocol", values="mean"
    )
    protocols = ("knee", "mcp")
    wide = with_columns(wide, protocols, "protocol")
    knee, mcp = protocols
    gap = (wide[knee] - wide[mcp]).abs().dropna()
    if gap.empty:
        raise NotMeasured(
            "B5 needs a (cost, FE RoM, ratio) cell run at both the knee and the MCP",
            {"protocol": protocols},
        )
    method, fe, ratio = gap.idxmax()
    return Measured(
        float(gap.max()),
        f"largest knee–MCP difference {gap.max():.2f}° ({method}, FE {fe:g}°, ratio {ratio:g}); "
        f"below 1.5° in {int((gap < 1.5).sum())} of {len(gap)} cells",
    )


def _b6(means):
    jumps, crossings = 0, []
    for key, line in means.sort_values("aa_ratio").groupby(["protocol", "method", "fe_rom_deg"]):
        for (_r0, before), (r1, after) in itertools.pairwise(
            zip(line["aa_ratio"], line["mean"], strict=True)
        ):
            if before < BREAKDOWN_DEG <= after:
                crossings.append((*key, r1, after))
                jumps += after > 50
    if not crossings:
        # A lack of a crossing, which no name says.
        raise NotMeasured("no mean error crosses 20° in this run", {})
    share = jumps / len(crossings)
    short = [f"{p} {m} FE {fe}° ratio {r:g}: {a:.1f}°" for p, m, fe, r, a in crossings if a <= 50]
    return Measured(
        share,
        f"{jumps} of {len(crossings)} crossings of 20° land above 50° ({share:.0%})"
        + (f"; not: {'; '.join(short)}" if short else ""),
    )


_CLAIMS = {"B1": _b1, "B2": _b2, "B3": _b3, "B4": _b4, "B5": _b5, "B6": _b6}


def _cell_id(protocol, method, fe_rom_deg, aa_ratio) -> str:
    return f"{_CELL_PREFIX}{protocol}-{method}-{fe_rom_deg}-{aa_ratio}"


def _relative_text(mean: float, published: float | None, tolerance) -> str:
    """How far our mean is from the published, relatively, and whether only the floor of a
    ``max_abs_rel`` tolerance (2°) admits it."""
    if published is None or not published:
        return ""
    relative = mean / published - 1
    text = f"; {relative:+.0%} of published"
    spec = tolerance.get("max_abs_rel") if tolerance else None
    if spec and abs(mean - published) > spec[1] * abs(published):
        text += f", within only by the {spec[0]:g}° floor"
    return text


def _cells(means: pd.DataFrame, published=None) -> dict[str, Measured]:
    entries = {e["id"]: e for e in (published or {}).get("values", [])}
    out = {}
    for r in means.itertuples():
        if not np.isfinite(r.mean):
            continue
        key = _cell_id(r.protocol, r.method, r.fe_rom_deg, r.aa_ratio)
        entry = entries.get(key, {})
        relative = _relative_text(float(r.mean), entry.get("published"), entry.get("tolerance"))
        out[key] = Measured(float(r.mean), f"{number(r.mean)} (SD {number(r.sd)}){relative}")
    return out


def measure(inputs: Inputs) -> Measurements:
    """Every Table 1 cell and claim of paper B, measured from the collected hinge results."""
    means = _means(inputs.collected)
    claims = measured_claims(_CLAIMS, means, declared=Declared(PAPER, inputs.published))
    return claims.with_values(_cells(means, inputs.published))


def _table1_cells(inputs: Inputs) -> pd.DataFrame:
    """The published cells with their keys and the verdict of each cell's tolerance."""
    entries = [e for e in inputs.published["values"] if e["id"].startswith(_CELL_PREFIX)]
    verdicts = comparison_rows(
        {**inputs.published, "values": entries, "claims": []}, measure(inputs)
    )
    keys = pd.DataFrame(
        [e["id"].removeprefix(_CELL_PREFIX).split("-") for e in entries], columns=CELL
    )
    keys["fe_rom_deg"] = keys["fe_rom_deg"].astype(int)
    keys["aa_ratio"] = keys["aa_ratio"].astype(float)
    keys["published"] = [e["published"] for e in entries]
    keys["within_tolerance"] = (verdicts["status"] == "reproduced").to_numpy()
    keys["margin"] = verdicts["margin"].to_numpy()
    return keys


def _table1(inputs: Inputs) -> Table:
    table = draw.table1(inputs.collected, _table1_cells(inputs))
    # The relative miss beside the margin: a small cell can be far off relatively and still
    # within the 2° floor of max(2°, 25 %).
    table.insert(
        table.columns.get_loc("difference") + 1,
        "relative_difference",
        table["difference"] / table["published"],
    )
    floor_only = (table["published"] < BREAKDOWN_DEG) & (
        table["difference"].abs() > 0.25 * table["published"].abs()
    )
    within = int(table["within_tolerance"].sum())
    floor_within = int((floor_only & table["within_tolerance"]).sum())
    return Table(
        table,
        title="Paper B Table 1: mean AoR angular error (degrees), published vs reproduced",
        headers=TABLE1_HEADERS,
        note=f"{within} of {len(table)} cells within tolerance, {floor_within} of them only "
        "through the 2° floor (more than 25 % off the published mean). Tolerance: below 20° "
        "within max(2°, 25 % of published); from 20° (the method has broken down) at least 20° "
        "and within 15°. Margin: how far inside or outside the tolerance, in degrees; "
        "relative difference: (ours − published) / published. "
        f"{inputs.published['notes']['table1']}",
    )


#: Table 1's headers for people, with units.
TABLE1_HEADERS = {
    "published": "published mean (°)",
    "reproduced_mean": "our mean (°)",
    "reproduced_sd": "our SD (°)",
    "difference": "difference (°)",
    "relative_difference": "relative difference",
    "margin": "margin (°)",
}


def _table1_headline(tables) -> str:
    (table,) = tables.values()
    return f"{int(table['within_tolerance'].sum())} of {len(table)} Table 1 cells within tolerance."


#: An SD this large [deg] in a Table 1 cell means its trials did not agree on one solution: the
#: within-solution spread of every cell is a few degrees at most, in the paper's and ours.
SPLIT_SD_DEG = 5.0


def table1_sd_rows(table1: pd.DataFrame, published_rows: dict[str, list[float]]) -> pd.DataFrame:
    """Table 1's standard deviations row by row: ``published_rows`` maps ``"<protocol>
    <method>"`` to the row's twelve published SDs [deg] (their cell order is lost, so only
    order-free summaries are compared); ``table1`` holds our ``reproduced_sd`` per cell with
    its keys (NaN for a cell this run did not measure). One row per (protocol, method): how
    many cells this run measured, the median and largest SD of each side (ours over the
    measured cells), where ours is largest, and how many cells of each have an SD of at least
    :data:`SPLIT_SD_DEG`."""
    rows = []
    for (protocol, method), cells in table1.groupby(["protocol", "method"], sort=False):
        key = f"{protocol} {method}"
        if key not in published_rows:
            raise ValueError(f"table1_sd: no published SDs for the row {key!r}")
        published = np.asarray(published_rows[key], dtype=float)
        ours = cells["reproduced_sd"].to_numpy(dtype=float)
        if len(published) != len(ours):
            raise ValueError(
                f"table1_sd: row {key!r} has {len(published)} published SDs for {len(ours)} cells"
            )
        measured = np.isfinite(ours)
        largest_at = ""
        if measured.any():
            largest = cells.iloc[int(np.nanargmax(ours))]
            largest_at = f"FE {largest['fe_rom_deg']:g}°, AA/FE {largest['aa_ratio']:g}"
        rows.append(
            {
                "protocol": protocol,
                "method": method,
                "measured_cells": int(measured.sum()),
                "published_median_sd": float(np.median(published)),
                "reproduced_median_sd": float(np.median(ours[measured]))
                if measured.any()
                else np.nan,
                "published_largest_sd": float(published.max()),
                "reproduced_largest_sd": float(ours[measured].max()) if measured.any() else np.nan,
                "reproduced_largest_at": largest_at,
                "published_split_cells": int((published >= SPLIT_SD_DEG).sum()),
                "reproduced_split_cells": int((ours >= SPLIT_SD_DEG).sum()),
            }
        )
    return pd.DataFrame(rows)


def _table1_sd(inputs: Inputs) -> Table:
    sd = inputs.published["table1_sd"]
    return Table(
        table1_sd_rows(_table1(inputs).frame, sd["rows"]),
        title="Paper B Table 1: standard deviations of the AoR error (degrees), row by row",
        headers=TABLE1_SD_HEADERS,
        note=f"{sd['note']} A cell whose SD is at least {SPLIT_SD_DEG:g}° has trials at more "
        "than one solution.",
    )


#: The SD table's headers for people, with units.
TABLE1_SD_HEADERS = {
    "measured_cells": "cells measured (of 12)",
    "published_median_sd": "published median SD (°)",
    "reproduced_median_sd": "our median SD (°)",
    "published_largest_sd": "published largest SD (°)",
    "reproduced_largest_sd": "our largest SD (°)",
    "reproduced_largest_at": "our largest at",
    "published_split_cells": f"published cells with SD ≥ {SPLIT_SD_DEG:g}°",
    "reproduced_split_cells": f"our cells with SD ≥ {SPLIT_SD_DEG:g}°",
}


def _table1_sd_headline(tables) -> str:
    (table,) = tables.values()
    same = int((table["published_split_cells"] == table["reproduced_split_cells"]).sum())
    return (
        f"Cells with trials at more than one solution (SD ≥ {SPLIT_SD_DEG:g}°): the same count "
        f"as published in {same} of {len(table)} rows."
    )


def _fig5(inputs: Inputs):
    return draw.fig5(inputs.collected, _table1_cells(inputs))


def _collected_answers(collected: pd.DataFrame, condition, trial: int) -> dict:
    """``{method: (point, direction)}`` [mm, unit]: the answer of each of :data:`METHODS` the
    study collected for ``trial`` of ``condition``, which it is scored and ranked by. Not
    fitted again through the public call, which screens the markers as a recording's: a fast
    trial's grid motion steps farther in one frame than its jump test allows a marker."""
    rows = collected[collected["trial"] == trial]
    for key, value in condition.items():
        rows = rows[rows[key] == value]
    answers = {}
    for method in METHODS:
        found = list(rows[rows["method"] == method].itertuples(index=False))
        if not found:
            continue  # a method the study does not list
        (row,) = found
        point = np.array([row.point_x, row.point_y, row.point_z])
        answers[method] = (point, np.array([row.direction_x, row.direction_y, row.direction_z]))
    return answers


def _fig2(inputs: Inputs):
    examples = []
    for condition, (trials, metadata) in zip(FIG2_CONDITIONS, inputs.datasets, strict=True):
        trial = draw.choose_fig2_trial(inputs.collected, condition)
        markers = trials.segments["moving"][trial]
        fits = _collected_answers(inputs.collected, condition, trial)
        title = (
            f"{draw.protocol_name(condition['protocol'])}, FE RoM {condition['fe_rom_deg']}°, "
            f"AA/FE {condition['aa_ratio']}, trial {trial}"
        )
        examples.append((title, markers, metadata["truth"], fits))
    return draw.fig2(examples)


PAPER = Paper(
    key="paper_b",
    letter="B",
    title="Paper B: axis of rotation",
    citation="Chang & Pollard (2007), Robust estimation of dominant axis of rotation, "
    "J Biomech 40:2707",
    study="hinge",
    methods=METHODS,
    published=Path(__file__).with_name("paper_b.yaml"),
    measure=measure,
    declares=tuple(_CLAIMS),
    tables=(PublishedTable.grid("Table 1", _cell_id, *TABLE1_ROWS, *TABLE1_COLUMNS),),
    outputs=(
        Output(
            "paper_b_table1",
            "table",
            _table1,
            caption="Reproduces paper B Table 1 (Chang & Pollard 2007, J Biomech 40:2707): mean "
            "AoR angular error of the planar, radial and combined costs over 30 trials for the "
            "knee and index-MCP protocols at every FE RoM and AA/FE ratio, published beside "
            "reproduced, with the tolerance verdict and its margin.",
            summarises=("paper_b_table1",),
            headline=_table1_headline,
        ),
        Output(
            "paper_b_table1_sd",
            "table",
            _table1_sd,
            caption="Compares paper B Table 1's standard deviations with ours row by row "
            "(protocol and cost): their cell order is lost in the text, so each row's median, "
            "largest and count of split cells are compared, with no verdict.",
            summarises=("paper_b_table1_sd",),
            headline=_table1_sd_headline,
        ),
        Output(
            "paper_b_fig5",
            "figure",
            _fig5,
            caption="Reproduces paper B Fig 5: mean AoR angular error with minimum–maximum bars "
            "for every condition, (a) knee, (b) index MCP; the paper's Table 1 mean of each "
            "condition as a black dash, and our mean ringed in red where it is outside that "
            "cell's tolerance.",
            summarises=("paper_b_table1",),
            headline=_table1_headline,
        ),
        Output(
            "paper_b_fig2",
            "figure",
            _fig2,
            caption="Reproduces paper B Fig 2: the best-fitting planes (planar cost), cylinders "
            "(radial cost) and circles (combined cost), one per marker, on two simulated knee "
            "conditions with a known axis, each the median trial by the combined cost's error "
            "(chosen by rule); the true axis dashed; equal axis scales.",
            conditions=FIG2_CONDITIONS,
            summarises=("paper_b_claims",),
            headline=claims_headline,
        ),
        claims_output(
            "paper_b",
            measure,
            "Claims B1–B6 of paper B §3.1, each recomputed from our results with the criterion "
            "stated in the table.",
        ),
    ),
)
