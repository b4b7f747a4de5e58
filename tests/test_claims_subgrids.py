"""Every claim on every sub-grid a configuration can make: measured, or not measured in this run.

A run's grid may hold one or two levels of a key, leave a method out or run one or two trials.
Each claim then either measures what its sentence speaks of, or raises so that it reads "not
measured in this run": never a NaN in its text, a verdict drawn from an empty selection, or a
numpy/pandas RuntimeWarning.
"""

from __future__ import annotations

import math
import warnings

import pandas as pd
import pytest
from test_claims import paper_b_world

from jointbench.comparison.published import load_published
from jointbench.papers import Inputs, get_paper

PAPERS = {"A": "paper_a", "B": "paper_b", "C": "paper_c", "S": "paper_sta"}


@pytest.fixture(scope="module")
def documents():
    return {letter: load_published(get_paper(PAPERS[letter]).published) for letter in PAPERS}


def _finite(value) -> bool:
    if isinstance(value, dict):
        return all(_finite(v) for v in value.values())
    if isinstance(value, list | tuple):
        return all(_finite(v) for v in value)
    return not isinstance(value, float) or math.isfinite(value)


def _measured_cleanly(paper_key: str, document, collected: pd.DataFrame, grid: str):
    """The paper's measurements of ``collected`` with RuntimeWarnings as errors; each finite
    and its text free of NaN and inf."""
    paper = get_paper(paper_key)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        measured = paper.measure(
            Inputs(collected=collected, published=document, config={"studies": {}})
        )
    for key, found in measured.items():
        assert _finite(found.value), (grid, key, found)
        words = found.text.lower().replace(",", " ").replace(";", " ").split()
        assert not {"nan", "nan°", "nan%", "inf", "inf°"} & set(words), (grid, key, found.text)
        assert "nan" not in found.text.lower().split("(")[0].split(), (grid, key, found.text)
    return measured


def test_b1_and_b2_are_not_measured_at_one_ratio(documents):
    """At the one ratio 0.1 no ratio increase and no other ratio was run."""
    world = paper_b_world(documents)
    only = world[world["aa_ratio"] == 0.1]
    measured = _measured_cleanly("paper_b", documents["B"], only, "aa_ratio=[0.1]")
    assert "B1" not in measured and "B2" not in measured


def test_b2_needs_ratio_0_1(documents):
    """'< 5° only at 0.1' says nothing of a run whose lowest ratio is 0.3."""
    world = paper_b_world(documents)
    measured = _measured_cleanly(
        "paper_b", documents["B"], world[world["aa_ratio"] >= 0.3], "aa_ratio>=0.3"
    )
    assert "B2" not in measured
