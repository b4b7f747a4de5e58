"""Published values and claims beside ours: one comparison for every paper.

A paper's published-values document (``paper_*.yaml`` beside its module) lists ``values`` and
``claims`` in one shape, each with a typed tolerance; the paper measures each one from the
collected results (:class:`~jointbench.papers.base.Measured`), and :func:`comparison_rows`
evaluates every tolerance through :func:`jointbench.comparison.tolerance.evaluate`. Each row shows
the paper's own sentence (``quote``), the criterion derived from it, the reproduced figure and
the margin: how far inside (+) or outside (−) the tolerance it lies, in the tolerance's units.
Where a value is known not to reproduce, its entry carries a ``deviation`` with the reason;
:func:`unexplained` lists the rows that did not reproduce without one, and the check fails on
them.
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd
import yaml

from jointbench.comparison.published_types import entry_problem, is_number, length_problem
from jointbench.comparison.tolerance import describe, evaluate, is_compared
from jointbench.configuration.config import read_yaml, validate_against, verdict_seeds
from jointbench.jobs import require_declared

if TYPE_CHECKING:  # the papers import this module
    from jointbench.papers.base import PerLevel, PublishedTable

__all__ = [
    "COLUMNS",
    "NOT_APPLICABLE",
    "STATUSES",
    "Measurements",
    "claims_rows",
    "comparison_rows",
    "enforce_design",
    "failure_message",
    "load_published",
    "matches_design",
    "reader_order",
    "run_basis",
    "status_legend",
    "unexplained",
]

COLUMNS = [
    "paper",
    "study",
    "entry",
    "id",
    "quantity",
    "quote",
    "criterion",
    "published",
    "reproduced",
    "tolerance",
    "margin",
    "status",
    "reason",
]
CLAIM_COLUMNS = [
    "id",
    "claim",
    "quote",
    "criterion",
    "published",
    "reproduced",
    "status",
    "margin",
    "reason",
]
#: The one word for each status of a published value or claim, and what it means: the tables'
#: notes and the README's summary say it with these words.
STATUSES = {
    "reproduced": "within its tolerance (a claim: its sentence holds as tested)",
    "not reproduced": "outside its tolerance (the reason says why)",
    "not applicable": "given no verdict (the published value is shown beside ours without a "
    "tolerance, or this run could not measure it; the reason says which)",
}
NOT_APPLICABLE = "not applicable"
UNEXPLAINED = "UNEXPLAINED: no deviation recorded in the paper's published values"
OFF_DESIGN = "not enforced: this run's grid or trial count differs from the paper's design"
NOT_IN_RUN = "not measured in this run (method, condition or study not run)"
#: How the reason of an entry starts when the paper said why this run could not measure it.
NOT_IN_RUN_BECAUSE = "not measured in this run: "
#: How the reason of an entry whose tolerance could not be evaluated starts: a failure of the
#: check (:func:`unexplained`), which no recorded deviation explains.
CANNOT_EVALUATE = "cannot evaluate: "
_SCHEMA = resources.files("jointbench.schemas").joinpath("published.schema.yaml")


@dataclass(frozen=True, eq=False)
class Measurements(Mapping):
    """A paper's measurements of one run (:attr:`jointbench.papers.base.Paper.measure`): a
    mapping of entry id to :class:`~jointbench.papers.base.Measured` holding only what the run
    measured, and ``not_measured``, why each claim it could not measure was not (what the run
    lacks, in the words of the check: "this run has no method BC"), which the comparison shows
    as that entry's reason. Equal to any mapping of the same measurements."""

    measured: Mapping[str, object]
    not_measured: Mapping[str, str] = field(default_factory=dict)

    def __getitem__(self, entry_id: str) -> object:
        return self.measured[entry_id]

    def __iter__(self) -> Iterator[str]:
        return iter(self.measured)

    def __len__(self) -> int:
        return len(self.measured)

    def with_values(self, values: Mapping[str, object]) -> Measurements:
        """These measurements with ``values`` (published values measured outside the claims'
        loop, by id) beside them."""
        return Measurements({**values, **self.measured}, self.not_measured)


def _not_in_run(measurements: Mapping, entry_id: str) -> str:
    """Why ``measurements`` hold nothing for ``entry_id``: the reason the paper gave, else
    that the run did not measure it."""
    why = measurements.not_measured if isinstance(measurements, Measurements) else {}
    return NOT_IN_RUN_BECAUSE + why[entry_id] if entry_id in why else NOT_IN_RUN


def load_published(
    path: str | Path,
    declares: Iterable[str | PerLevel] = (),
    tables: Iterable[PublishedTable] = (),
) -> dict:
    """A paper's published-values document, schema-checked and holding an entry for each id of
    ``declares`` (:attr:`jointbench.papers.base.Paper.declares`) and each cell of ``tables``
    (:attr:`jointbench.papers.base.Paper.tables`), each cell one number or, for a table whose
    cells list several (:attr:`~jointbench.papers.base.PublishedTable.lists`), a list of that
    many: ``ValueError`` naming the file otherwise, and the missing ids (for a table, the
    paper, the table and its missing cells, or the cell and the position in it). Every entry's
    values are those its tolerance reads (:mod:`jointbench.comparison.published_types`), and
    a declared entry's lists are as long as its check's measurement (one value per level of a
    :class:`~jointbench.papers.base.PerLevel`; no list the tolerance compares in an entry
    declared by its id alone): ``ValueError`` naming the file, the paper, the entry and the key
    otherwise, with how many values the check needs and why. Read by a
    workflow job, ``path`` must be one of its declared inputs
    (:func:`jointbench.jobs.require_declared`)."""
    require_declared(path, "published values")
    try:
        document = read_yaml(Path(path).read_text())
    except yaml.YAMLError as error:
        raise ValueError(f"published values {path}: not valid YAML ({error})") from error
    validate_against(document, _SCHEMA, f"published values {path}")
    listed = {entry["id"]: entry for entry in [*document.get("values", []), *document["claims"]]}
    declares = tuple(declares)
    missing = [i for i in map(_declared_id, declares) if i not in listed]
    if missing:
        raise ValueError(
            f"published values {path}: no entry for {', '.join(missing)}, which the paper "
            "measures; is the file cut short? Restore it from the repository"
        )
    for table in tables:
        absent = [cell for cell in table.cells if cell not in listed]
        if absent:
            raise ValueError(
                f"published values {path}: paper {document['paper']} {table.source} has no "
                f"value for {len(absent)} of its {len(table.cells)} cells: {', '.join(absent)}; "
                "is the file cut short? Restore it from the repository"
            )
        for cell in table.cells:
            wrong = _misshapen_cell(listed[cell]["published"], table.lists)
            if wrong:
                raise ValueError(
                    f"published values {path}: paper {document['paper']} {table.source} cell "
                    f"{cell}: {wrong}; restore it from the repository"
                )
    _check_design_levels(document, path)
    # After the tables: a cell's value is named by its table and position there.
    _check_types(document, path)
    # After the types: a list's length is read once its values are known to be numbers.
    _check_lengths(document, path, declares)
    return document


def _check_design_levels(document: Mapping, path: str | Path) -> None:
    """``ValueError`` naming the file and the key of the first ``design.grid`` list whose
    levels cannot be told apart in order: a per-level check's values are matched to its axis's
    levels as listed, so numbers must be finite and strictly ascending, and names distinct
    words, not numbers written as text."""
    for key, levels in document["design"]["grid"].items():
        problem = _levels_problem(levels)
        if problem:
            raise ValueError(
                f"published values {path}: paper {document['paper']} design.grid.{key}: "
                f"{problem}; list the paper's levels there, from the paper"
            )


def _levels_problem(levels: Sequence) -> str | None:
    """Why ``levels`` (one ``design.grid`` list) cannot be matched in order, or ``None``."""
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in levels):
        if not all(map(is_number, levels)):
            return f"{levels} holds a level that is not a finite number"
        if any(b <= a for a, b in itertools.pairwise(levels)):
            return f"{levels} is not in ascending order without repeats"
        return None
    for level in levels:
        if not isinstance(level, str):
            return f"{level!r} is neither a number nor a name"
        try:
            float(level)
        except ValueError:
            continue
        return f"{level!r} is a number written as text"
    if len(set(levels)) < len(levels):
        return f"{levels} repeats a level"
    return None


def _declared_id(declared: str | PerLevel) -> str:
    return declared if isinstance(declared, str) else declared.entry


def _entries(document: Mapping) -> list[tuple[str, Mapping]]:
    """``(kind, entry)`` of each published value and claim of ``document``, in its order."""
    return [("value", e) for e in document.get("values", [])] + [
        ("claim", e) for e in document["claims"]
    ]


def _check_lengths(document: Mapping, path: str | Path, declares: Sequence) -> None:
    """``ValueError`` naming the file, the paper, the entry and the key of the first list of a
    declared entry whose length is not the number of values its check measures
    (:func:`length_problem`), saying how many it needs and why."""
    by_id = {_declared_id(d): d for d in declares}
    grid = document["design"]["grid"]
    for kind, entry in _entries(document):
        declared = by_id.get(entry["id"])
        if declared is None:
            continue  # a table's cell (held to its table) or a file read without its paper
        if isinstance(declared, str):
            problem, fix = length_problem(entry, None), ""
        elif not declared.levels and declared.axis not in grid:
            raise ValueError(
                f"published values {path}: paper {document['paper']} {kind} {entry['id']} is "
                f"measured per {declared.axis}, but design.grid.{declared.axis} is missing "
                f"(design.grid has {', '.join(grid)}); list the paper's levels there"
            )
        else:
            levels = declared.levels_in(grid)
            problem = length_problem(entry, len(levels), declared.needs(grid))
            fix = "; restore it from the repository"
        if problem:
            key, what = problem
            raise ValueError(
                f"published values {path}: paper {document['paper']} {kind} {entry['id']} "
                f"{key}: {what}{fix}"
            )


def _check_types(document: Mapping, path: str | Path) -> None:
    """``ValueError`` naming the file, the paper, the entry and the key of the first value of
    ``document`` that its tolerance cannot read (:func:`entry_problem`)."""
    for kind, entry in _entries(document):
        problem = entry_problem(entry)
        if problem:
            key, what = problem
            raise ValueError(
                f"published values {path}: paper {document['paper']} {kind} {entry['id']} "
                f"{key}: {what}; write it as its tolerance "
                f"({describe(entry['tolerance'])}) reads it, from the paper"
            )


def _misshapen_cell(published: object, lists: Sequence[str] = ()) -> str | None:
    """What is wrong with a table cell's ``published`` value, in words naming the position, or
    None: with ``lists`` (the labels of the numbers the cell lists, in order) it must be a list
    of that many numbers, without, one number."""
    if not lists:
        return None if is_number(published) else f"{published!r} is not a number"
    labels = ", ".join(lists)
    if not isinstance(published, list):
        return f"{published!r} is not a list of its {len(lists)} numbers ({labels})"
    count = f"lists {len(published)} values where the paper prints {len(lists)} ({labels})"
    for position, value in enumerate(published, start=1):
        if position > len(lists):
            return f"{count}: an extra value at position {position} ({value!r})"
        if not is_number(value):
            return f"position {position} ({lists[position - 1]}) holds {value!r}, not a number"
    if len(published) < len(lists):
        return f"{count}: nothing at position {len(published) + 1}"
    return None


def _published_text(value: object) -> str:
    if isinstance(value, Mapping):
        return ", ".join(f"{k} {v}" for k, v in value.items())
    return str(value)


def _value_criterion(entry: Mapping) -> str:
    """A published value's criterion when its entry states none: its tolerance in words."""
    if not is_compared(entry["tolerance"]):
        return "none: the published value is shown beside ours"
    return f"reproduced value {describe(entry['tolerance'])} of the published"


def _verdict(entry: Mapping, measured, not_in_run: str) -> tuple[str, str, str]:
    """``(status, margin, reason)`` of one entry given its measurement (or None, and then
    ``not_in_run``, why the run did not measure it)."""
    tolerance = entry["tolerance"]
    if not is_compared(tolerance):
        return NOT_APPLICABLE, "", entry.get("not_applicable", entry["tolerance_reason"])
    if measured is None:
        return NOT_APPLICABLE, "", entry.get("not_applicable", not_in_run)
    try:
        verdict = evaluate(tolerance, entry["published"], measured.value)
    except KeyError as error:
        # A compound measurement without the part an ``all`` tolerance reads.
        return "not reproduced", "", f"{CANNOT_EVALUATE}the measurement has no {error}"
    except (ValueError, TypeError) as error:
        # Not a verdict this run may pass on: the file's values are typed when it is read
        # (load_published), so what is left is a measurement of another shape, whatever its
        # recorded deviation says.
        return "not reproduced", "", f"{CANNOT_EVALUATE}{error}"
    if verdict.holds:
        return "reproduced", verdict.margin_text, ""
    return "not reproduced", verdict.margin_text, entry.get("deviation", UNEXPLAINED)


def comparison_rows(document: Mapping, measurements: Mapping) -> pd.DataFrame:
    """One row per published value and claim of ``document`` (columns :data:`COLUMNS`).

    ``measurements`` maps entry ids to :class:`~jointbench.papers.base.Measured`; an entry
    without one is not applicable in this run, for the reason :class:`Measurements` give.
    """
    rows = []
    for kind, entry in _entries(document):
        measured = measurements.get(entry["id"])
        status, margin, reason = _verdict(entry, measured, _not_in_run(measurements, entry["id"]))
        rows.append(
            {
                "paper": document["paper"],
                "study": document["study"],
                "entry": kind,
                "id": entry["id"],
                "quantity": entry.get("quantity", entry.get("claim")),
                "quote": entry.get("quote", ""),
                "criterion": entry.get("criterion", _value_criterion(entry)),
                "published": _published_text(entry["published"]),
                "reproduced": "" if measured is None else measured.text,
                "tolerance": describe(entry["tolerance"]),
                "margin": margin,
                "status": status,
                "reason": reason,
            }
        )
    return pd.DataFrame(rows, columns=COLUMNS)


def claims_rows(document: Mapping, measurements: Mapping) -> pd.DataFrame:
    """The claims of ``document`` with what we measured (columns :data:`CLAIM_COLUMNS`); a
    claim not measured says why in place of the reproduced value: why no run of ours measures
    it (the entry's ``not_applicable``), else what this run lacks."""
    rows = comparison_rows({**document, "values": []}, measurements)
    rows["claim"] = rows["quantity"]
    missing = rows["reproduced"] == ""
    claims = {entry["id"]: entry for entry in document["claims"]}
    rows.loc[missing, "reproduced"] = [
        CANNOT_EVALUATE
        + claims[entry_id].get("not_applicable", _not_in_run(measurements, entry_id))
        for entry_id in rows.loc[missing, "id"]
    ]
    return rows[CLAIM_COLUMNS]


def run_basis(config: Mapping, studies: Sequence[str]) -> str:
    """What every status of one run's comparison rests on, for its note: the run's one base
    seed and the trials per condition of each of ``studies``, and where the verdicts over
    seeds are (``snakemake -j2 verdicts``, the config's ``verdicts.seeds``): a status
    reproduced in one seed may not be in others."""
    trials = ", ".join(f"{study} {config['studies'][study]['trials']}" for study in studies)
    trials = trials or "(no study compared)"
    return (
        f"Every status is this run's: one base seed ({config['base_seed']}), trials per "
        f"condition {trials}. How often each holds over {verdict_seeds(config)} base seeds: "
        "results/tables/verdicts.md (`snakemake -j2 verdicts`)"
    )


def status_legend() -> str:
    """Every status in its one word and what it means, for a table's note."""
    return "Status — " + "; ".join(f"{word}: {meaning}" for word, meaning in STATUSES.items())


def reader_order(comparison: pd.DataFrame) -> pd.DataFrame:
    """``comparison`` in the order a reader wants it: the claims with a verdict, then the values
    with a verdict, then the rows without one (:data:`NOT_APPLICABLE`), claims before values;
    each part in the papers' order."""
    key = 2 * (comparison["status"] == NOT_APPLICABLE) + (comparison["entry"] != "claim")
    return comparison.iloc[key.argsort(kind="stable")].reset_index(drop=True)


def unexplained(comparison: pd.DataFrame) -> pd.DataFrame:
    """Rows that did not reproduce and carry no recorded deviation, or could not be evaluated
    (whatever deviation they record)."""
    reason = comparison["reason"].astype(str)
    failing = (reason == UNEXPLAINED) | reason.str.startswith(CANNOT_EVALUATE)
    return comparison[(comparison["status"] == "not reproduced") & failing]


def matches_design(config: Mapping, document: Mapping) -> bool:
    """Whether the run's study has the paper's whole grid and at least its number of trials."""
    settings = config["studies"].get(document["study"])
    if settings is None:
        return False
    design = document["design"]
    grid = settings["grid"]
    same_grid = all(
        sorted(map(float, grid.get(key, []))) == sorted(map(float, values))
        if all(isinstance(v, int | float) for v in values)
        else sorted(grid.get(key, [])) == sorted(values)
        for key, values in design["grid"].items()
    )
    return same_grid and int(settings["trials"]) >= int(design["min_trials"])


def enforce_design(comparison: pd.DataFrame, document: Mapping, config: Mapping) -> pd.DataFrame:
    """Mark unexplained deviations of a study run off the paper's design as not enforced.

    A reduced run (fewer trials, part of the grid) still tabulates every comparison, but its
    statistics cannot be held to the published values; nor can the entries its grid measures
    only in part (fewer noise levels than published counts), which could not be evaluated:
    their reason keeps why.
    """
    if matches_design(config, document):
        return comparison
    comparison = comparison.copy()
    comparison.loc[comparison["reason"] == UNEXPLAINED, "reason"] = OFF_DESIGN
    partial = comparison["reason"].astype(str).str.startswith(CANNOT_EVALUATE)
    comparison.loc[partial, "reason"] = OFF_DESIGN + "; " + comparison.loc[partial, "reason"]
    return comparison


def failure_message(comparison: pd.DataFrame) -> str | None:
    """The error naming every value that no longer reproduces without a recorded reason, and
    every value that could not be evaluated, with why."""
    missing = unexplained(comparison)
    if missing.empty:
        return None
    lines = [
        f"  {r.study} {r.id}: published {r.published}, reproduced {r.reproduced} "
        + (f"({r.reason})" if r.reason.startswith(CANNOT_EVALUATE) else f"(margin {r.margin})")
        for r in missing.itertuples()
    ]
    return (
        f"{len(missing)} published value(s) no longer reproduce without a recorded deviation "
        "in the paper's published values, or cannot be evaluated:\n" + "\n".join(lines)
    )
