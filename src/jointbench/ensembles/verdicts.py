"""The verdict over seeds: the members of a seed ensemble (:mod:`jointbench.ensembles.members`)
summarised per published value and claim.

Each value and claim gets the share of seeds in which it reproduces, with its Wilson 95 %
interval (:func:`jointbench.comparison.tolerance.wilson_interval`), and one verdict by the rule
:data:`VERDICT_RULE`, implemented by :func:`seed_verdict` and nowhere else.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import pandas as pd

from jointbench.comparison.published import load_published
from jointbench.comparison.tolerance import wilson_interval
from jointbench.resultfiles.tables import markdown_table, write_tables

__all__ = [
    "PROTOCOL_SHARES",
    "SUMMARY_COLUMNS",
    "VERDICTS",
    "VERDICT_RULE",
    "quantities_of",
    "seed_verdict",
    "share_columns",
    "standout_summary",
    "summarise_members",
    "verdict_counts",
    "write_summary",
]

VERDICTS = ("reproduced", "not reproduced", "seed-dependent")
VERDICT_RULE = (
    "reproduced when the Wilson 95 % interval of the share of seeds in which it reproduces "
    "lies wholly above 1/2, not reproduced when it lies wholly below 1/2, seed-dependent "
    "otherwise (seeds where it cannot be evaluated are left out of the share)"
)
SUMMARY_COLUMNS = [
    "paper",
    "entry",
    "id",
    "quantity",
    "seeds",
    "reproduced_in",
    "share",
    "interval_95",
    "verdict",
    "default_seed",
    "default_reproduced",
]
TESTED = ("reproduced", "not reproduced")
#: Under the results folder: the ``sensitivity`` target's count of drawn protocols in which
#: each value and claim reproduces (columns ``id``, ``reproduced_in`` and ``draws``), read
#: beside the seeds' when it exists.
PROTOCOL_SHARES = "tables/sensitivity.csv"


def seed_verdict(reproduced_in: int, seeds: int) -> str:
    """The verdict over seeds of a value that reproduced in ``reproduced_in`` of ``seeds``
    members where it could be evaluated, by :data:`VERDICT_RULE`; ``"not applicable"`` when
    it could be evaluated in none."""
    if seeds == 0:
        return "not applicable"
    low, high = wilson_interval(reproduced_in, seeds)
    if low > 0.5:
        return "reproduced"
    if high < 0.5:
        return "not reproduced"
    return "seed-dependent"


def share_columns(reproduced_in: int, members: int) -> dict[str, object]:
    """``reproduced_in``, the share of ``members`` it makes and its Wilson 95 % interval as
    text (NaN and empty for no members): the columns an ensemble's summary gives each value."""
    low, high = wilson_interval(reproduced_in, members)
    return {
        "reproduced_in": reproduced_in,
        "share": reproduced_in / members if members else np.nan,
        "interval_95": f"{low:.2f}–{high:.2f}" if members else "",
    }


def summarise_members(members: pd.DataFrame, quantities: Mapping[str, str]) -> pd.DataFrame:
    """Per value and claim, the share of members in which it reproduces, its Wilson 95 %
    interval, the verdict by :data:`VERDICT_RULE` and the default member's own status and
    measurement (columns :data:`SUMMARY_COLUMNS`); ``quantities`` names each entry id."""
    rows = []
    for (paper, entry, entry_id), part in members.groupby(
        ["paper", "entry", "id"], sort=False, observed=True
    ):
        tested = part[part["status"].isin(TESTED)]
        k, n = int((tested["status"] == "reproduced").sum()), len(tested)
        default = part[part["member"] == 0]
        rows.append(
            {
                "paper": paper,
                "entry": entry,
                "id": entry_id,
                "quantity": quantities.get(entry_id, ""),
                "seeds": n,
                **share_columns(k, n),
                "verdict": seed_verdict(k, n),
                "default_seed": default["status"].iloc[0] if len(default) else "",
                "default_reproduced": default["reproduced"].iloc[0] if len(default) else "",
            }
        )
    return pd.DataFrame(rows, columns=SUMMARY_COLUMNS)


def verdict_counts(summary: pd.DataFrame) -> pd.DataFrame:
    """Per paper, how many compared values and claims have each verdict over seeds."""
    compared = summary[summary["verdict"] != "not applicable"]
    counts = compared.groupby(["paper", "verdict"]).size().unstack(fill_value=0)
    return counts.reindex(columns=list(VERDICTS), fill_value=0).reset_index()


def quantities_of(documents: Sequence[Mapping]) -> dict[str, str]:
    """Each entry id of the published-values ``documents`` with its quantity or claim."""
    return {
        entry["id"]: entry.get("quantity", entry.get("claim", ""))
        for document in documents
        for entry in [*document.get("values", []), *document["claims"]]
    }


def write_summary(members: Sequence[str], published: Sequence[str], outputs) -> pd.DataFrame:
    """Read the members' verdict files, write the summary over seeds as CSV, Markdown and HTML
    (with the counts of verdicts per paper and the rule in the note) and return it."""
    frame = pd.concat([pd.read_csv(path) for path in members], ignore_index=True)
    documents = [load_published(path) for path in published]
    summary = summarise_members(frame, quantities_of(documents))
    seeds = frame["member"].nunique()
    note = (
        f"Over {seeds} base seeds (member 0 is the default run's). Verdict over seeds: "
        f"{VERDICT_RULE}.\n\n## Verdicts by paper\n\n" + markdown_table(verdict_counts(summary))
    )
    write_tables(
        summary,
        outputs,
        title=f"Published values and claims over {seeds} seeds",
        note=note,
    )
    return summary


def _closest_calls(summary: pd.DataFrame, count: int) -> pd.DataFrame:
    """The ``count`` compared entries whose share of seeds lies nearest 1/2, in that order."""
    compared = summary[summary["verdict"] != "not applicable"]
    distance = (compared["share"] - 0.5).abs()
    return compared.assign(_distance=distance).sort_values("_distance", kind="stable").head(count)


def standout_summary(
    summary: pd.DataFrame, protocols: pd.DataFrame | None = None, closest: int = 5
) -> str:
    """The README's verdicts over seeds, as Markdown, from the summary :func:`write_summary`
    returns (or its CSV read back): the counts of each verdict per paper, and the ``closest``
    entries whose share of seeds lies nearest 1/2 with their intervals. ``protocols``, the
    ``sensitivity`` target's per-entry counts (columns ``id``, ``reproduced_in`` and
    ``draws``), adds how many of the drawn protocols reproduce each."""
    seeds = int(summary["seeds"].max()) if len(summary) else 0
    counts = verdict_counts(summary)
    calls = _closest_calls(summary, closest)
    table = pd.DataFrame(
        {
            "id": calls["id"],
            "value or claim": calls["quantity"],
            "seeds reproducing": [
                f"{k} of {n}" for k, n in zip(calls["reproduced_in"], calls["seeds"], strict=True)
            ],
            "95 % interval": calls["interval_95"],
            "verdict": calls["verdict"],
        }
    )
    if protocols is not None:
        drawn = protocols.set_index("id")
        table["protocols reproducing"] = [
            f"{drawn.at[i, 'reproduced_in']} of {drawn.at[i, 'draws']}"
            if i in drawn.index and drawn.at[i, "draws"] > 0
            else ""
            for i in calls["id"]
        ]
    return (
        f"**Verdicts over {seeds} base seeds** (generated from `results/tables/verdicts.csv`, "
        f"`snakemake -j2 verdicts`; {VERDICT_RULE}):\n\n"
        + markdown_table(counts)
        + f"\n\nThe {len(table)} closest calls (share of seeds nearest 1/2):\n\n"
        + markdown_table(table)
    )
