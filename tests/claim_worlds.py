"""The papers' documents and the full synthetic grids their claims are measured on, shared by
the tests of a claim check's selections and mistakes: a test module takes them as its
fixtures ``documents = documents_fixture(letters)`` and ``worlds = worlds_fixture()``."""

from __future__ import annotations

import pytest
from test_claims import A_SPEEDS, _timed, paper_a_world, paper_b_world, paper_c_world
from test_claims_subgrids import paper_sta_world

from jointbench.comparison.published import load_published
from jointbench.papers import Inputs, paper_a, paper_b, paper_c, paper_sta

#: Each paper's module, by its letter.
PAPERS = {"A": paper_a, "B": paper_b, "C": paper_c, "S": paper_sta}


def documents(letters) -> dict:
    """The published document of each paper ``letters`` name, by letter."""
    return {letter: load_published(PAPERS[letter].PAPER.published) for letter in letters}


def worlds(documents: dict, c_trials: int = 5) -> dict:
    """A full synthetic grid for each paper of ``documents`` (:func:`documents`), by letter;
    paper C's with ``c_trials`` trials per condition."""
    make = {
        "A": lambda: _timed(paper_a_world(), A_SPEEDS),
        "B": lambda: paper_b_world(documents),
        "C": lambda: paper_c_world(trials=c_trials),
        "S": paper_sta_world,
    }
    return {letter: make[letter]() for letter in documents}


def measure(letter: str, documents: dict, collected):
    """Paper ``letter``'s claims measured on the run ``collected`` (a DataFrame) against its
    document in ``documents``."""
    inputs = Inputs(collected=collected, published=documents[letter], config={"studies": {}})
    return PAPERS[letter].measure(inputs)


def documents_fixture(letters):
    """A module-scoped fixture ``documents``: :func:`documents` of the papers ``letters``
    name."""

    @pytest.fixture(scope="module", name="documents")
    def documents_of_papers():
        return documents(letters)

    return documents_of_papers


def worlds_fixture(c_trials: int = 5):
    """A module-scoped fixture ``worlds``: :func:`worlds` of the module's ``documents``
    fixture, paper C's with ``c_trials`` trials per condition."""

    @pytest.fixture(scope="module", name="worlds")
    def worlds_of_papers(documents):
        return worlds(documents, c_trials)

    return worlds_of_papers
