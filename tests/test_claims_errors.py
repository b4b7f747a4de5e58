"""A mistake in a claim's check is raised naming the claim, never read as "not measured".

A claim is left out of a run (not measured in this run) only where its check says the run
lacks what its sentence speaks of; a ``KeyError``, ``IndexError``, ``ValueError`` or
``StopIteration`` from anywhere else in the check (a misspelt column, an index off the end, a
bad unpacking) is a mistake of the check, raised as a ``RuntimeError`` naming the claim.
"""

from __future__ import annotations

import claim_worlds
import pytest

from jointbench.figures import paper_a as paper_a_draw
from jointbench.papers import Inputs, Measured, get_paper, paper_a, paper_b, paper_c, paper_sta

#: Per paper: its module and a claim each test replaces by a mistaken check.
PAPERS = {
    "A": (paper_a, "A9"),
    "B": (paper_b, "B5"),
    "C": (paper_c, "C4"),
    "S": (paper_sta, "S2"),
}


documents = claim_worlds.documents_fixture(PAPERS)
worlds = claim_worlds.worlds_fixture(c_trials=20)


def _misspelt_column(table, *_):
    return Measured(float(table["mean_eror_mm"].mean()), "")


def _past_the_end(table, *_):
    return Measured(float(table.iloc[len(table)].iloc[0]), "")


def _bad_unpacking(table, *_):
    (only,) = table.index[:2]
    return Measured(float(only), "")


def _next_of_nothing(table, *_):
    return Measured(next(level for level in table.index if level is None), "")


MISTAKES = {
    KeyError: _misspelt_column,
    IndexError: _past_the_end,
    ValueError: _bad_unpacking,
    StopIteration: _next_of_nothing,
}


def _measure(letter, documents, collected):
    module, _ = PAPERS[letter]
    inputs = Inputs(collected=collected, published=documents[letter], config={"studies": {}})
    return get_paper(module.PAPER.key).measure(inputs)


@pytest.mark.parametrize("letter", PAPERS)
@pytest.mark.parametrize("error", MISTAKES, ids=lambda error: error.__name__)
def test_a_mistake_in_a_claim_is_raised_naming_the_claim(
    documents, worlds, monkeypatch, letter, error
):
    """The full grid holds every cell each claim reads: whatever its check raises there is
    its own mistake, not the run's lack."""
    module, claim = PAPERS[letter]
    monkeypatch.setitem(module._CLAIMS, claim, MISTAKES[error])
    with pytest.raises(RuntimeError, match=rf"^claim {claim}: {error.__name__}") as raised:
        _measure(letter, documents, worlds[letter])
    assert isinstance(raised.value.__cause__, error)


def test_a_mistake_in_paper_a_timing_is_raised(documents, worlds, monkeypatch):
    """Table 2's times and A12 are read only from a run that recorded them; a mistake in
    reading them is raised, not taken for a run without times."""

    def misread(*_):
        raise KeyError("median_seconds")

    monkeypatch.setattr(paper_a_draw, "table2", misread)
    with pytest.raises(KeyError, match="median_seconds"):
        _measure("A", documents, worlds["A"])


def test_paper_a_without_recorded_times_has_no_table2_value_nor_a12(documents, worlds):
    measured = _measure("A", documents, worlds["A"].drop(columns="seconds"))
    assert not [key for key in measured if key.startswith("A-T2-")]
    assert "A12" not in measured and "A11" in measured
