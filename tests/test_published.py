"""The comparison with the published values, the regression snapshot and the README summary.

Tests on ``results/`` need a full ``snakemake -j2`` run first (CI does that); without one they
are skipped. The perturbation tests at the end need no results: they prove that each check fails
when a published value or a reproduced mean moves.
"""

from __future__ import annotations

import copy
from pathlib import Path

import pandas as pd
import pytest

from jointbench.figures.paper_b import table1, within_tolerance
from jointbench.study.published import (
    UNEXPLAINED,
    comparison_table,
    load_published,
    unexplained,
    validate_published,
)
from jointbench.study.snapshot import (
    compare_snapshot,
    readme_summary,
    reproduction_summary,
    snapshot_table,
)

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"
COMPARISON = RESULTS / "tables" / "published_comparison.csv"
SNAPSHOT = ROOT / "tests" / "snapshots" / "summary.csv"
needs_results = pytest.mark.skipif(
    not COMPARISON.exists(), reason="run `snakemake -j2` first: no results/ to check"
)


@pytest.fixture(scope="module")
def published():
    return load_published()


@pytest.fixture(scope="module")
def comparison():
    return pd.read_csv(COMPARISON, keep_default_na=False)


def expected_ids(published) -> set[str]:
    ids = set()
    for document in published.values():
        ids |= {entry["id"] for entry in document.get("values", [])}
        ids |= {claim["id"] for claim in document["claims"]}
        for cell in document.get("table1", {}).get("cells", []):
            ids.add("B-T1-{protocol}-{method}-{fe_rom_deg}-{aa_ratio}".format(**cell))
        for row in document.get("table1", {}).get("rows", []):
            ids |= {
                f"C-T1-{column}-{row['n_frames']}"
                for column in ("sqrt_trace_cov_mm", "validation_index")
                if row[column] is not None
            }
    return ids


@needs_results
def test_comparison_has_a_row_for_every_published_value(published, comparison):
    missing = expected_ids(published) - set(comparison["id"])
    assert not missing, f"published values missing from the comparison: {sorted(missing)}"


@needs_results
def test_every_deviation_has_a_recorded_reason(comparison):
    bad = comparison[
        (comparison["status"] == "not reproduced")
        & ((comparison["reason"] == UNEXPLAINED) | (comparison["reason"] == ""))
    ]
    assert bad.empty, "not reproduced without a recorded reason:\n" + bad.to_string()


@needs_results
def test_statuses_are_known(comparison):
    assert set(comparison["status"]) <= {"reproduced", "not reproduced", "not applicable"}


@needs_results
def test_results_match_the_regression_snapshot():
    problems = compare_snapshot(snapshot_table(RESULTS / "collected"), pd.read_csv(SNAPSHOT))
    assert not problems, (
        "results moved from tests/snapshots/summary.csv (after an intended change run "
        "`jointbench snapshot` and commit it):\n" + "\n".join(problems[:40])
    )


@needs_results
def test_readme_summary_is_current(comparison):
    assert readme_summary(ROOT / "README.md") == reproduction_summary(comparison).strip(), (
        "README reproduction summary is stale: run `jointbench readme`"
    )


def test_published_files_match_their_schema(published):
    assert set(published) == {"A", "B", "C"}
    broken = copy.deepcopy(published["B"])
    del broken["table1"]["cells"][0]
    with pytest.raises(ValueError, match="table1/cells"):
        validate_published(broken)


# ------------------------------------------------------------- the checks can fail


@pytest.fixture
def pristine(published):
    """The published values with every recorded deviation removed: nothing is pre-explained."""
    documents = copy.deepcopy(published)
    for entry in [*documents["B"]["table1"]["cells"], *documents["B"]["claims"]]:
        entry.pop("deviation", None)
    return documents


def synthetic_paper_b_tables(published) -> dict[str, pd.DataFrame]:
    """Paper B tables whose every cell reproduces its published mean exactly."""
    rows = []
    for cell in published["B"]["table1"]["cells"]:
        for trial, offset in enumerate((-0.1, 0.0, 0.1)):
            rows.append(
                {key: cell[key] for key in ("protocol", "method", "fe_rom_deg", "aa_ratio")}
                | {"trial": trial, "error_deg": cell["published"] + offset, "converged": True}
            )
    cells = table1(pd.DataFrame(rows), published["B"])
    claims = pd.DataFrame(
        {
            "id": [c["id"] for c in published["B"]["claims"]],
            "published": "x",
            "reproduced": "x",
            "status": "reproduced",
        }
    )
    return {"paper_b_table1": cells, "paper_b_claims": claims}


def test_exact_reproduction_passes(pristine):
    published = pristine
    comparison = comparison_table({"B": published["B"]}, synthetic_paper_b_tables(published))
    assert len(comparison) == 72 + 6
    assert unexplained(comparison).empty


def test_perturbed_published_value_is_reported(pristine):
    published = pristine
    document = copy.deepcopy(published["B"])
    cell = document["table1"]["cells"][5]
    tables = synthetic_paper_b_tables(published)
    cell["published"] += 30.0
    cell.pop("deviation", None)
    tables["paper_b_table1"] = table1(_rows_from(tables["paper_b_table1"]), document)
    moved = unexplained(comparison_table({"B": document}, tables))
    expected = "B-T1-{protocol}-{method}-{fe_rom_deg}-{aa_ratio}".format(**cell)
    assert list(moved["id"]) == [expected]


def test_perturbed_reproduced_mean_is_reported(pristine):
    published = pristine
    tables = synthetic_paper_b_tables(published)
    table = tables["paper_b_table1"]
    table.loc[0, "reproduced_mean"] += 5.0
    table.loc[0, "within_tolerance"] = within_tolerance(
        table.loc[0, "published"], table.loc[0, "reproduced_mean"]
    )
    moved = unexplained(comparison_table({"B": published["B"]}, tables))
    assert len(moved) == 1 and moved.iloc[0]["id"].startswith("B-T1-knee-planar-30-0.1")


def test_a_claim_that_stops_reproducing_is_reported(pristine):
    published = pristine
    tables = synthetic_paper_b_tables(published)
    tables["paper_b_claims"].loc[2, "status"] = "not reproduced"
    document = copy.deepcopy(published["B"])
    document["claims"][2].pop("deviation", None)
    moved = unexplained(comparison_table({"B": document}, tables))
    assert list(moved["id"]) == [document["claims"][2]["id"]]


def test_snapshot_comparison_catches_a_moved_mean():
    snapshot = pd.DataFrame(
        {
            "study": ["cmc"] * 2,
            "condition": ["a", "b"],
            "method": ["NM", "NM"],
            "statistic": ["mean_error_mm"] * 2,
            "value": [1.0, 2.0],
        }
    )
    assert compare_snapshot(snapshot.copy(), snapshot) == []
    moved = snapshot.copy()
    moved.loc[1, "value"] = 2.0 * (1 + 1e-4)
    problems = compare_snapshot(moved, snapshot)
    assert len(problems) == 1 and "cmc NM b mean_error_mm" in problems[0]
    assert compare_snapshot(snapshot.iloc[:1], snapshot) == [
        "cmc NM b mean_error_mm: in the snapshot but not in the results"
    ]


def _rows_from(cells: pd.DataFrame) -> pd.DataFrame:
    """Trial rows whose cell means are ``cells['reproduced_mean']``."""
    keys = ["protocol", "method", "fe_rom_deg", "aa_ratio"]
    return cells[keys].assign(trial=0, error_deg=cells["reproduced_mean"], converged=True)
