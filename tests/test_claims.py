"""Every claim read as its paper wrote it, and each claim check able to tell methods apart.

The first tests check the shape of the published-values documents and of the comparison: every
claim quotes the paper's sentence, and the comparison shows the quote, the criterion and the
margin. Then, claim by claim, a deliberately wrong implementation (methods swapped, a method
biased, a covariance scaled) must fail the check that the right one passes. Those tests build
small synthetic collected tables; the last ones read the real collected results when a
``snakemake -j2`` run left them in ``results/collected/`` and are skipped otherwise.
"""

from __future__ import annotations

import copy
from pathlib import Path

import pandas as pd
import pytest
import yaml

from jointbench.papers import Inputs, get_paper
from jointbench.study.published import (
    CLAIM_COLUMNS,
    COLUMNS,
    claims_rows,
    comparison_rows,
    load_published,
)

ROOT = Path(__file__).resolve().parents[1]
COLLECTED = ROOT / "results" / "collected"


@pytest.fixture(scope="module")
def documents():
    return {
        letter: load_published(get_paper(f"paper_{letter.lower()}").published)
        for letter in "ABC"
    }


# ------------------------------------------------------------------ quotes, criteria, margins


def test_every_claim_quotes_the_paper(documents):
    for document in documents.values():
        for claim in document["claims"]:
            assert len(claim.get("quote", "")) >= 20, claim["id"]


def test_a_claim_without_its_quote_is_rejected(documents, tmp_path):
    broken = copy.deepcopy(documents["A"])
    del broken["claims"][0]["quote"]
    path = tmp_path / "broken.yaml"
    path.write_text(yaml.safe_dump(broken))
    with pytest.raises(ValueError, match="quote"):
        load_published(path)


def test_comparison_and_claims_tables_show_quote_criterion_and_margin(documents):
    for column in ("quote", "criterion", "margin"):
        assert column in COLUMNS and column in CLAIM_COLUMNS
    document = documents["A"]
    rows = comparison_rows(document, {})
    claim = rows.set_index("id").loc["A6"]
    assert "55%" in claim["quote"] and claim["criterion"]
    claims = claims_rows(document, {})
    assert list(claims.columns) == CLAIM_COLUMNS
