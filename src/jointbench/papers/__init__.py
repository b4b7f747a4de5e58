"""The papers the benchmark reproduces: one module per paper, each exporting one ``PAPER``.

The registry below collects the built-in papers by importing every module of this package that
exports a ``PAPER`` (in module name order); a paper outside the package joins by
:func:`register_paper` (the workflow does this for the modules listed under ``extensions`` in
the config). The workflow derives its rules, targets, captions and report categories from it.
"""

from __future__ import annotations

import importlib

from jointbench.papers.base import FrontPart, Inputs, Measured, Output, Paper, Table
from jointbench.registries import Registry, exported, submodules

__all__ = [
    "FrontPart",
    "Inputs",
    "Measured",
    "Output",
    "Paper",
    "Table",
    "get_paper",
    "paper_labels",
    "paper_names",
    "papers_of_study",
    "register_paper",
]

_PAPERS: Registry[Paper] = Registry("paper", lambda paper: paper.key)
register_paper = _PAPERS.register
get_paper = _PAPERS.get
paper_names = _PAPERS.names


def paper_labels() -> dict[str, str]:
    """Each registered paper's label for summaries, by letter: ``"A (centre of rotation)"``."""
    labels = {}
    for paper in _PAPERS.values():
        subject = paper.title.split(":", 1)[-1].strip()
        labels[paper.letter] = f"{paper.letter} ({subject})"
    return labels


def papers_of_study(study: str) -> tuple[Paper, ...]:
    """The registered papers that reproduce ``study`` (none for a study without a paper)."""
    return tuple(p for p in _PAPERS.values() if p.study == study)


_MODULES = [importlib.import_module(name) for name in submodules("jointbench.papers")]
for _paper in exported(_MODULES, "PAPER"):
    register_paper(_paper)
