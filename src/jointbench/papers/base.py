"""What a reproduced paper is: its outputs, their inputs, and its measured published values.

A :class:`Paper` names its study, the methods it compared, its outputs (figures and tables, each
with the function that renders it, the simulated conditions it draws and its report caption),
its published values (a YAML file of typed tolerances, package data beside the module) and the
function that measures every published value and claim from the collected results.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import pandas as pd

from jointbench.resultfiles.formatting import words
from jointbench.simulate import Trials

__all__ = [
    "FrontPart",
    "Inputs",
    "Measured",
    "Output",
    "Paper",
    "PerLevel",
    "PublishedTable",
    "Table",
]


@dataclass(frozen=True)
class Table:
    """A rendered table: its rows, the title and note of its Markdown form, and ``headers``,
    the table's own headers for people by column name (others are written by
    :func:`jointbench.resultfiles.formatting.header`)."""

    frame: pd.DataFrame
    title: str = ""
    note: str = ""
    headers: Mapping[str, str] = field(default_factory=dict)


@dataclass(frozen=True)
class Measured:
    """One published value or claim as reproduced: ``value`` is what its tolerance compares (a
    number, a list, or a mapping of named parts for ``all`` and ``binomial95``); ``text`` says it
    in words for the tables."""

    value: object
    text: str


@dataclass(frozen=True)
class Inputs:
    """What an output is rendered from.

    ``collected`` the study's collected results; ``published`` the paper's published-values
    document; ``datasets`` the simulated trials (and file metadata) of the output's conditions,
    by condition in :attr:`Output.conditions` order (absent conditions are left out); ``config``
    the run's configuration.
    """

    collected: pd.DataFrame
    published: Mapping
    config: Mapping
    datasets: Sequence[tuple[Trials, Mapping]] = ()


@dataclass(frozen=True)
class Output:
    """One figure or table of a paper.

    ``name`` is the file stem and rule name (``results/figures/<name>.{png,pdf}`` or
    ``results/tables/<name>.{html,csv,md}``); ``render`` draws it from :class:`Inputs` (a figure
    returns a matplotlib ``Figure``, a table a :class:`Table`); ``conditions`` are the simulated
    conditions whose trials it draws; ``caption`` says what it shows (reStructuredText);
    ``headline`` summarises the tables named in ``summarises`` for its caption; ``in_readme``
    puts that headline in the README too, between ``<!-- name:start -->`` and
    ``<!-- name:end -->`` (``jointbench readme`` writes it; a test holds it to the results).
    """

    name: str
    kind: Literal["figure", "table"]
    render: Callable[[Inputs], object]
    caption: str
    conditions: tuple[Mapping[str, object], ...] = ()
    summarises: tuple[str, ...] = ()
    headline: Callable[..., str] | None = None
    in_readme: bool = False

    @property
    def files(self) -> dict[str, str]:
        """The output's files by extension; the first is the one the report shows."""
        folder, extensions = (
            ("figures", ("png", "pdf"))
            if self.kind == "figure"
            else ("tables", ("html", "csv", "md"))
        )
        return {ext: f"results/{folder}/{self.name}.{ext}" for ext in extensions}


@dataclass(frozen=True)
class FrontPart:
    """What a paper adds to the report's landing page from the run's tables: ``finding``, a
    sentence after the paper's line of findings; ``sections``, each a heading, a table title
    and the table's rows, shown after the rankings."""

    finding: str = ""
    sections: tuple[tuple[str, str, pd.DataFrame], ...] = ()


@dataclass(frozen=True)
class PublishedTable:
    """A table of the paper whose cells are published values: ``source`` names it as its
    entries' ``source`` does (``"Table 1"``), ``cells`` the ids of its cells, ``lists`` the
    labels, in order, of the numbers each cell lists (a printed row's columns kept in one entry:
    paper A's marker set and its three distances), none when each cell is one number. They
    come from the paper's own rows and columns, not from its published-values file, so a cell
    deleted from the file, or a number deleted from a cell, is found missing
    (:func:`jointbench.comparison.published.load_published`) instead of leaving one comparison
    fewer or a shorter list."""

    source: str
    cells: tuple[str, ...]
    lists: tuple[str, ...] = ()

    @classmethod
    def grid(
        cls,
        source: str,
        cell_id: Callable[..., str],
        *axes: Iterable[object],
        empty: Collection[tuple] = (),
        lists: tuple[str, ...] = (),
    ) -> PublishedTable:
        """The table whose cells are every combination of ``axes`` (its rows' and columns'
        labels, as printed) but those ``empty`` (left blank in the paper); ``cell_id(*labels)``
        is a cell's id; each cell lists the numbers labelled ``lists``, or is one number."""
        labels = (key for key in itertools.product(*axes) if key not in empty)
        return cls(source, tuple(cell_id(*key) for key in labels), lists)


@dataclass(frozen=True)
class PerLevel:
    """A published value or claim whose check measures one value per level of the grid key
    ``axis``, in order: those of ``levels`` (the levels the paper's sentence names, which the
    check selects), or with none every level of the paper's design grid (``design: grid`` of
    its published values), which the check groups by. ``of`` says what is measured at each,
    in words ("BC's converged trials at the M set and the smallest RoM"). Declared by the
    paper (:attr:`Paper.declares`), it is the one place the check and the file's lists take
    their length from: a list in the entry of any other length is refused when the file is
    read (:func:`jointbench.comparison.published.load_published`), not when a full run
    finally compares it."""

    entry: str
    axis: str
    of: str
    levels: tuple[float, ...] = ()

    def levels_in(self, design_grid: Mapping[str, Sequence]) -> tuple:
        """The levels the check measures at, given the paper's design grid."""
        if self.levels:
            return self.levels
        if self.axis not in design_grid:
            raise ValueError(
                f"{self.entry} is measured per {self.axis}, which the paper's design grid "
                f"lacks (it has {', '.join(design_grid)})"
            )
        return tuple(design_grid[self.axis])

    def needs(self, design_grid: Mapping[str, Sequence]) -> str:
        """How many values the check measures and why, in words: ``3, one per noise (mm)
        level of the paper's design (0.5, 1.0, 2.0) for …``."""
        levels = self.levels_in(design_grid)
        named = "the sentence names" if self.levels else "of the paper's design"
        shown = ", ".join(map(str, levels))
        return f"{len(levels)}, one per {words(self.axis)} level {named} ({shown}) for {self.of}"


@dataclass(frozen=True)
class Paper:
    """One reproduced paper (see the module doc). ``key`` prefixes its outputs' names;
    ``also_measures`` names the study's estimators beyond ``methods`` that ``measure`` reads
    (beside the paper's own, never in its place); ``declares`` the ids of the published values
    and claims ``measure`` computes from the results whatever the grid, which its published
    values must therefore all list (a file cut short is refused, not read as fewer claims),
    each a :class:`PerLevel` where its check measures one value per level (an id alone: the
    entry's tolerance reads no list);
    ``front_page`` gives what the paper adds to
    the report's landing page (:class:`FrontPart`) from the run's tables by name (those of
    its outputs absent from a run are absent from the mapping); ``tables`` its tables of
    published values (:class:`PublishedTable`), each of whose cells its published values must
    list."""

    key: str
    letter: str
    title: str
    citation: str
    study: str
    methods: tuple[str, ...]
    outputs: tuple[Output, ...]
    published: Path
    measure: Callable[[Inputs], Mapping[str, Measured]]
    also_measures: tuple[str, ...] = ()
    declares: tuple[str | PerLevel, ...] = ()
    front_page: Callable[[Mapping[str, pd.DataFrame]], FrontPart] | None = None
    tables: tuple[PublishedTable, ...] = ()

    def __post_init__(self) -> None:
        names = [o.name for o in self.outputs]
        stray = [n for n in names if not n.startswith(f"{self.key}_")]
        if stray or len(set(names)) != len(names):
            raise ValueError(
                f"paper {self.key!r}: output names must be unique and start with "
                f"'{self.key}_' (got {names})"
            )

    def output(self, name: str) -> Output:
        """The output called ``name``; ``ValueError`` listing the paper's outputs otherwise."""
        for candidate in self.outputs:
            if candidate.name == name:
                return candidate
        known = ", ".join(o.name for o in self.outputs)
        raise ValueError(f"paper {self.key!r} has no output {name!r}; it has {known}")
