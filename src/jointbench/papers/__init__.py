"""The papers the benchmark reproduces: one module per paper, each exporting one ``PAPER``.

The registry below collects the built-in papers by import; a paper outside the package joins by
:func:`register_paper` (the workflow does this for the modules listed under ``extensions`` in
the config). The workflow derives its rules, targets, captions and report categories from it.
"""

from __future__ import annotations

from jointbench.papers import paper_a, paper_b, paper_c
from jointbench.papers.base import Inputs, Measured, Output, Paper, Table

__all__ = [
    "Inputs",
    "Measured",
    "Output",
    "Paper",
    "Table",
    "get_paper",
    "paper_names",
    "papers_of_study",
    "register_paper",
]

_PAPERS: dict[str, Paper] = {}


def register_paper(paper: Paper) -> Paper:
    """Add ``paper`` to the registry; registering the same value twice is harmless."""
    known = _PAPERS.get(paper.key)
    if known is not None and known is not paper:
        raise ValueError(f"a different paper {paper.key!r} is already registered")
    _PAPERS[paper.key] = paper
    return paper


def get_paper(key: str) -> Paper:
    """The paper called ``key`` (e.g. ``paper_a``); ``ValueError`` listing the known ones."""
    try:
        return _PAPERS[key]
    except KeyError:
        raise ValueError(f"unknown paper {key!r}; known: {', '.join(_PAPERS)}") from None


def paper_names() -> tuple[str, ...]:
    """Keys of the registered papers, built-ins first."""
    return tuple(_PAPERS)


def papers_of_study(study: str) -> tuple[Paper, ...]:
    """The registered papers that reproduce ``study`` (none for a study without a paper)."""
    return tuple(p for p in _PAPERS.values() if p.study == study)


for _paper in (paper_a.PAPER, paper_b.PAPER, paper_c.PAPER):
    register_paper(_paper)
