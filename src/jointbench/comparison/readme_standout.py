"""The README's "What stands out": per paper, short bullets built from the measured results.

What stands out is chosen by :data:`STANDOUT_RULE`, implemented by :func:`stands_out` and
nowhere else, so a claim added to a paper's published values is picked up without an edit
here. Every number in the block is copied from the tables it cites (:data:`SOURCES`), as those
tables print it; ``tests/test_readme_standout.py`` holds the block to that
(:func:`jointbench.comparison.cited_numbers.unfound_numbers`).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import pandas as pd

from jointbench.comparison.published import NOT_APPLICABLE
from jointbench.ensembles.verdicts import TESTED
from jointbench.resultfiles.formatting import number

__all__ = [
    "SOURCES",
    "STANDOUT_BLOCK",
    "STANDOUT_RULE",
    "Ensembles",
    "first_sentence",
    "paper_bullets",
    "read_ensembles",
    "standout_block",
    "stands_out",
]

#: The README block this module writes, between ``<!-- NAME:start -->`` and ``<!-- NAME:end -->``.
STANDOUT_BLOCK = "what-stands-out"
#: Under the results folder: each table the block reads, and the target that writes it.
SOURCES = {
    "comparison": ("tables/published_comparison.csv", "snakemake -j2"),
    "seeds": ("tables/verdicts.csv", "snakemake -j2 verdicts"),
    "protocols": ("tables/sensitivity.csv", "snakemake -j2 sensitivity"),
    "named": ("tables/sensitivity_named.csv", "snakemake -j2 sensitivity"),
}
STANDOUT_RULE = (
    "a claim stands out when the default run does not reproduce it, when it does not come out "
    "the same in every seed or in every drawn protocol, when the default protocol's status "
    "differs from the verdict of most drawn protocols, or when a named protocol changes its "
    "status; the published values not reproduced in the default run are named with their "
    "reason"
)
#: The columns of the comparison the block reads.
COMPARISON_COLUMNS = (
    "paper",
    "entry",
    "id",
    "quantity",
    "published",
    "reproduced",
    "status",
    "reason",
)


@dataclass(frozen=True)
class Ensembles:
    """The ensemble tables beside the default run's comparison, each ``None`` when its target
    has not run: ``seeds`` (``verdicts.csv``), ``protocols`` (``sensitivity.csv``) and
    ``named`` (``sensitivity_named.csv``: one status column per named protocol and
    ``default``)."""

    seeds: pd.DataFrame | None = None
    protocols: pd.DataFrame | None = None
    named: pd.DataFrame | None = None


def read_ensembles(results: str | Path) -> Ensembles:
    """The ensemble tables under the ``results`` folder, each ``None`` when absent."""
    tables = {}
    for key in ("seeds", "protocols", "named"):
        path = Path(results) / SOURCES[key][0]
        tables[key] = pd.read_csv(path) if path.is_file() else None
    return Ensembles(**tables)


def first_sentence(text: str) -> str:
    """The first sentence of ``text`` (up to a full stop followed by a capital), without its
    full stop."""
    return re.split(r"\.\s+(?=[A-Z])", str(text).strip(), maxsplit=1)[0].rstrip(".")


def _row(table: pd.DataFrame | None, entry_id: str) -> Mapping | None:
    """The row of ``table`` whose id is ``entry_id`` (None when the table or the row is
    missing)."""
    if table is None:
        return None
    rows = table[table["id"] == entry_id]
    return rows.iloc[0].to_dict() if len(rows) else None


def _members(row: Mapping | None, count: str) -> int:
    """How many members of an ensemble judged the entry of ``row`` (``count``: its column)."""
    return int(row[count]) if row is not None and pd.notna(row[count]) else 0


def _unanimous(row: Mapping | None, count: str) -> bool:
    """Whether every member that judged the entry gave it the same status (True when none
    did)."""
    members = _members(row, count)
    return members == 0 or int(row["reproduced_in"]) in (0, members)


def _named_changes(named: pd.DataFrame | None, entry_id: str) -> dict[str, str]:
    """Each named protocol under which the entry's status differs from the default's, with
    that status."""
    row = _row(named, entry_id)
    if row is None:
        return {}
    names = [c for c in named.columns if c not in ("paper", "id", "default")]
    return {name: row[name] for name in names if row[name] != row["default"]}


def _default_against_most(status: str, protocols: Mapping | None) -> bool:
    """Whether the default run's ``status`` differs from what most drawn protocols give."""
    if _members(protocols, "draws") == 0:
        return False
    most_reproduce = 2 * int(protocols["reproduced_in"]) > int(protocols["draws"])
    return (status == "reproduced") != most_reproduce


def stands_out(row: Mapping, ensembles: Ensembles) -> bool:
    """Whether the claim of comparison ``row`` stands out by :data:`STANDOUT_RULE`."""
    if row["status"] not in TESTED:
        return False
    seeds = _row(ensembles.seeds, row["id"])
    protocols = _row(ensembles.protocols, row["id"])
    return (
        row["status"] == "not reproduced"
        or not _unanimous(seeds, "seeds")
        or not _unanimous(protocols, "draws")
        or _default_against_most(row["status"], protocols)
        or bool(_named_changes(ensembles.named, row["id"]))
    )


def _share(row: Mapping | None, count: str, members: str) -> str:
    """``"seeds: 19 of 20 (0.76–0.99)"``: the members reproducing an entry and the Wilson
    interval of their share; empty when no member judged it."""
    if _members(row, count) == 0:
        return ""
    return f"{members}: {int(row['reproduced_in'])} of {int(row[count])} ({row['interval_95']})"


def _where_default(protocols: Mapping | None, status: str) -> list[str]:
    """Where the default protocol sits among the drawn ones, and the choice the entry depends
    on most, in words."""
    if protocols is None:
        return []
    parts = []
    if _default_against_most(status, protocols):
        parts.append(
            "the default protocol reproduces it, most drawn ones do not"
            if status == "reproduced"
            else "the default protocol does not reproduce it, most drawn ones do"
        )
    below = protocols.get("draws_below_default")
    if below is not None and pd.notna(below):
        parts.append(f"share of drawn protocols with a smaller margin: {number(below)}")
    choice = protocols.get("depends_most_on")
    if isinstance(choice, str) and choice and not _unanimous(protocols, "draws"):
        parts.append(f"depends most on `{choice}`")
    return parts


def _claim_lines(row: Mapping, ensembles: Ensembles) -> list[str]:
    """One standing-out claim as a bullet and its sub-bullets: its verdict in the default run
    (with the recorded reason when not reproduced); the paper's value beside ours; its share
    of seeds; its share of drawn protocols, with where the default protocol sits among them
    and the choice it depends on most; each named protocol that changes it."""
    seeds = _row(ensembles.seeds, row["id"])
    protocols = _row(ensembles.protocols, row["id"])
    verdict = row["status"]
    if verdict == "not reproduced" and isinstance(row.get("reason"), str) and row["reason"]:
        verdict += f" — {first_sentence(row['reason'])}"
    drawn = "; ".join(
        [_share(protocols, "draws", "Drawn protocols reproducing it")]
        + (_where_default(protocols, row["status"]) if _members(protocols, "draws") else [])
    )
    details = [
        f"Paper: {row['published']}; ours: {row['reproduced']}.",
        _share(seeds, "seeds", "Seeds reproducing it"),
        drawn,
        *(
            f"Under the {name} protocol: {status}"
            for name, status in _named_changes(ensembles.named, row["id"]).items()
        ),
    ]
    lines = [f"**{row['id']}** ({row['quantity']}): {verdict}."]
    lines += [f"  - {d if d.endswith('.') else d + '.'}" for d in details if d]
    return lines


def _values_bullets(rows: pd.DataFrame) -> list[str]:
    """The published values not reproduced in the default run, those with one reason
    together."""
    failed = rows[(rows["entry"] == "value") & (rows["status"] == "not reproduced")]
    bullets = []
    for reason, group in failed.groupby(failed["reason"].fillna(""), sort=False):
        ids = ", ".join(f"**{i}**" for i in group["id"])
        because = f": {first_sentence(reason)}" if reason else ""
        bullets.append(f"{ids} not reproduced{because}.")
    return bullets


def _steady_bullet(rows: pd.DataFrame, ensembles: Ensembles) -> str:
    """The claims reproduced with no reason to stand out, named in one bullet."""
    claims = rows[(rows["entry"] == "claim") & (rows["status"] == "reproduced")]
    steady = [row["id"] for row in claims.to_dict("records") if not stands_out(row, ensembles)]
    if not steady:
        return ""
    judged = ["the default run"]
    for table, count, members in (
        (ensembles.seeds, "seeds", "every seed"),
        (ensembles.protocols, "draws", "every drawn protocol"),
    ):
        if any(_members(_row(table, entry_id), count) for entry_id in steady):
            judged.append(members)
    where = ", ".join(judged[:-1]) + " and " + judged[-1] if len(judged) > 1 else judged[0]
    return f"Reproduced in {where}: {', '.join(steady)}."


def _protocol_counts(protocols: pd.DataFrame | None, paper: str) -> str:
    """The paper's values and claims per verdict over drawn protocols (as the ``sensitivity``
    table counts them), in words."""
    if protocols is None:
        return ""
    part = protocols[(protocols["paper"] == paper) & (protocols["verdict"] != NOT_APPLICABLE)]
    if part.empty:
        return ""
    counts = part.groupby("verdict").size()
    draws = int(part["draws"].max())
    text = ", ".join(f"{int(n)} {verdict}" for verdict, n in counts.items())
    return f"Over {draws} drawn protocols, values and claims: {text}."


def _missing(ensembles: Ensembles) -> list[str]:
    """A line per ensemble table not present, naming the target that writes it."""
    lines = []
    for key in ("seeds", "protocols", "named"):
        if getattr(ensembles, key) is None:
            path, target = SOURCES[key]
            lines.append(f"No `results/{path}`: `{target}` writes it.")
    return lines


def paper_bullets(rows: pd.DataFrame, ensembles: Ensembles) -> list[list[str]]:
    """The bullets of one paper's comparison ``rows``, each a line and its sub-bullets, in
    this order: claims that stand out, values not reproduced, the verdicts over drawn
    protocols, the steady claims."""
    paper = rows["paper"].iloc[0]
    claims = rows[rows["entry"] == "claim"].to_dict("records")
    bullets = [_claim_lines(row, ensembles) for row in claims if stands_out(row, ensembles)]
    bullets += [[line] for line in _values_bullets(rows)]
    for line in (_protocol_counts(ensembles.protocols, paper), _steady_bullet(rows, ensembles)):
        if line:
            bullets.append([line])
    return bullets


def standout_block(
    comparison: pd.DataFrame, ensembles: Ensembles, titles: Mapping[str, str]
) -> str:
    """The README's "What stands out", as Markdown: per paper (``titles`` maps its letter to
    the label shown) the bullets of :func:`paper_bullets`, under the rule that chose them."""
    missing = sorted(set(COMPARISON_COLUMNS) - set(comparison.columns))
    if missing:
        raise ValueError(f"{SOURCES['comparison'][0]}: no column {', '.join(missing)}")
    sources = ", ".join(
        f"`results/{SOURCES[key][0]}`"
        for key in ("comparison", "seeds", "protocols", "named")
        if key == "comparison" or getattr(ensembles, key) is not None
    )
    lines = [
        f"**What stands out** (generated from {sources}; {STANDOUT_RULE}):",
        "",
        *_missing(ensembles),
    ]
    if lines[-1]:
        lines.append("")
    for paper, rows in comparison.groupby("paper", sort=True):
        bullets = paper_bullets(rows, ensembles)
        if not bullets:
            continue
        lines.append(f"- **Paper {titles.get(paper, paper)}**")
        for first, *more in bullets:
            lines.append(f"  - {first}")
            lines += [f"  {line}" for line in more]
    return "\n".join(lines)
