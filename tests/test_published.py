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
import yaml

import jointbench.papers
from jointbench.comparison.cited_numbers import numbers_in
from jointbench.comparison.published import (
    UNEXPLAINED,
    comparison_rows,
    load_published,
    unexplained,
)
from jointbench.comparison.snapshot import (
    compare_snapshot,
    readme_blocks,
    readme_summary,
    reproduction_summary,
    snapshot_table,
    update_readme,
)
from jointbench.comparison.tolerance import describe
from jointbench.configuration.config import study_names
from jointbench.papers import Inputs, get_paper, paper_labels, paper_names
from jointbench.papers import paper_b as paper_b_module
from jointbench.resultfiles.tables import for_people

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"
COMPARISON = RESULTS / "tables" / "published_comparison.csv"
SNAPSHOT = ROOT / "tests" / "snapshots" / "summary.csv"
needs_results = pytest.mark.skipif(
    not COMPARISON.exists(), reason="run `snakemake -j2` first: no results/ to check"
)


@pytest.fixture(scope="module")
def published():
    """Every built-in paper's published values, by letter, schema-checked."""
    return {
        get_paper(key).letter: load_published(get_paper(key).published)
        for key in paper_names()
        if key in ("paper_a", "paper_b", "paper_c")
    }


@pytest.fixture(scope="module")
def comparison():
    return pd.read_csv(COMPARISON, keep_default_na=False)


def expected_ids(published) -> set[str]:
    ids = set()
    for document in published.values():
        ids |= {entry["id"] for entry in [*document.get("values", []), *document["claims"]]}
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
    studies = study_names(yaml.safe_load((ROOT / "config" / "config.yaml").read_text()))
    current = snapshot_table(RESULTS / "collected", studies)
    problems = compare_snapshot(current, pd.read_csv(SNAPSHOT))
    assert not problems, (
        "results moved from tests/snapshots/summary.csv (after an intended change run "
        "`jointbench snapshot` and commit it):\n" + "\n".join(problems[:40])
    )


@needs_results
def test_readme_summary_is_current(comparison):
    assert (
        readme_summary(ROOT / "README.md")
        == reproduction_summary(comparison, paper_labels()).strip()
    ), "README reproduction summary is stale: run `jointbench readme`"


@needs_results
def test_readme_headlines_are_current():
    from jointbench.report import readme_headlines

    headlines = readme_headlines(RESULTS / "tables", readme_blocks(ROOT / "README.md"))
    assert "paper_sta_ranking" in headlines
    for block, text in headlines.items():
        assert readme_summary(ROOT / "README.md", block) == text.strip(), (
            f"README block {block} is stale: run `jointbench readme`"
        )


def test_readme_blocks_are_replaced_by_name_and_a_missing_one_is_named(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(
        "top\n<!-- a:start -->\nold a\n<!-- a:end -->\nmiddle\n"
        "<!-- b:start -->\nold b\n<!-- b:end -->\nend\n"
    )
    assert update_readme(readme, "new b", block="b")
    assert not update_readme(readme, "new b", block="b")
    assert readme_summary(readme, "a") == "old a"
    assert readme_summary(readme, "b") == "new b"
    with pytest.raises(ValueError, match="no <!-- c:start -->"):
        update_readme(readme, "text", block="c")


def test_published_files_match_their_schema(published, tmp_path):
    assert set(published) == {"A", "B", "C"}
    assert len(published["B"]["values"]) == 72
    for broken_tolerance in ({}, {"abs": 1.0, "rel": 0.1}, "within 2 mm", {"roughly": 2}):
        broken = copy.deepcopy(published["B"])
        broken["values"][0]["tolerance"] = broken_tolerance
        path = tmp_path / "broken.yaml"
        path.write_text(yaml.safe_dump(broken))
        with pytest.raises(ValueError, match="values/0/tolerance"):
            load_published(path)


# ------------------------------------------------------------- the checks can fail


@pytest.fixture
def pristine(published):
    """Paper B's published values with every recorded deviation removed."""
    document = copy.deepcopy(published["B"])
    for entry in [*document["values"], *document["claims"]]:
        entry.pop("deviation", None)
    return document


def exact_paper_b_results(document) -> pd.DataFrame:
    """Collected hinge rows whose every Table 1 cell has its published mean exactly."""
    rows = []
    for entry in document["values"]:
        protocol, method, fe, ratio = entry["id"].removeprefix("B-T1-").split("-")
        for trial, offset in enumerate((-0.1, 0.0, 0.1)):
            rows.append(
                {
                    "protocol": protocol,
                    "method": method,
                    "fe_rom_deg": int(fe),
                    "aa_ratio": float(ratio),
                    "trial": trial,
                    "error_deg": entry["published"] + offset,
                    "converged": True,
                }
            )
    return pd.DataFrame(rows)


def _comparison(document, collected) -> pd.DataFrame:
    inputs = Inputs(collected=collected, published=document, config={})
    return comparison_rows(document, paper_b_module.measure(inputs))


def test_exact_reproduction_passes(pristine):
    comparison = _comparison(pristine, exact_paper_b_results(pristine))
    values = comparison[comparison["id"].str.startswith("B-T1-")]
    assert len(values) == 72
    assert (values["status"] == "reproduced").all()
    assert unexplained(values).empty


def test_perturbed_published_value_is_reported(pristine):
    collected = exact_paper_b_results(pristine)
    pristine["values"][5]["published"] += 30.0
    moved = unexplained(_comparison(pristine, collected))
    assert pristine["values"][5]["id"] in set(moved["id"])
    assert not any(i.startswith("B-T1-") and i != pristine["values"][5]["id"] for i in moved["id"])


def test_perturbed_reproduced_mean_is_reported(pristine):
    collected = exact_paper_b_results(pristine)
    first = pristine["values"][0]["id"].removeprefix("B-T1-").split("-")
    cell = (collected["protocol"] == first[0]) & (collected["method"] == first[1])
    cell &= (collected["fe_rom_deg"] == int(first[2])) & (collected["aa_ratio"] == float(first[3]))
    collected.loc[cell, "error_deg"] += 5.0
    moved = unexplained(_comparison(pristine, collected))
    assert pristine["values"][0]["id"] in set(moved["id"])
    row = moved.set_index("id").loc[pristine["values"][0]["id"]]
    assert row["margin"].endswith(" outside"), row["margin"]


def test_a_recorded_deviation_explains_a_miss(pristine):
    collected = exact_paper_b_results(pristine)
    pristine["values"][5]["published"] += 30.0
    pristine["values"][5]["deviation"] = "a recorded reason for the test"
    comparison = _comparison(pristine, collected)
    row = comparison.set_index("id").loc[pristine["values"][5]["id"]]
    assert row["status"] == "not reproduced" and row["reason"] == "a recorded reason for the test"
    assert pristine["values"][5]["id"] not in set(unexplained(comparison)["id"])


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


def _numbers(text: str) -> set[str]:
    return numbers_in(text)


@pytest.mark.parametrize("letter", ["a", "b", "c"])
def test_reasons_carry_no_typed_measurement(letter):
    """A recorded reason may quote the paper, its criterion and its tolerance, never a number
    of ours: those come from the measurement, in the row's reproduced column."""
    document = load_published(Path(jointbench.papers.__file__).with_name(f"paper_{letter}.yaml"))
    entries = [*document.get("values", []), *document["claims"]]
    # The paper's own numbers, wherever quoted, are not ours.
    paper = set().union(*(_numbers(e.get(k, "")) for e in entries for k in ("quote", "published")))
    for entry in entries:
        allowed = set(paper) | _numbers(describe(entry["tolerance"]))
        for key in ("criterion", "tolerance", "tolerance_reason", "claim"):
            allowed |= _numbers(entry.get(key, ""))
        for key in ("deviation", "note", "not_applicable"):
            stray = _numbers(entry.get(key, "")) - allowed
            assert not stray, (entry["id"], key, sorted(stray))


COMPARISON = Path(__file__).resolve().parents[1] / "results" / "tables" / "published_comparison.csv"


@pytest.mark.skipif(not COMPARISON.exists(), reason="run `snakemake -j2` first")
def test_every_number_of_a_reason_is_in_its_row():
    """Each number the reason of a value or claim gives (not reproduced, or not applicable) is
    in that row's results or the paper's text."""
    table = pd.read_csv(COMPARISON, dtype=str).fillna("")
    # The paper's own numbers, wherever quoted in its rows, are not ours.
    paper = {
        letter: _numbers(" ".join([*rows["quote"], *rows["published"]]))
        for letter, rows in table.groupby("paper")
    }
    for row in table[table["reason"] != ""].itertuples():
        shown = " ".join([row.reproduced, row.criterion, row.tolerance, row.margin])
        stray = _numbers(row.reason) - _numbers(shown) - paper[row.paper]
        assert not stray, (row.id, sorted(stray))


def test_a_cell_is_quoted_in_the_comparison_as_table_1_prints_it(pristine):
    collected = exact_paper_b_results(pristine)
    collected["error_deg"] *= 1.00123  # digits beyond three significant figures
    inputs = Inputs(collected=collected, published=pristine, config={})
    measured = paper_b_module.measure(inputs)
    table = paper_b_module._table1(inputs)
    shown = for_people(table.frame, table.headers)
    for i in (0, 5, 40):
        cell = pristine["values"][i]["id"]
        mean, sd = shown.iloc[i][["our mean (°)", "our SD (°)"]]
        assert measured[cell].text.startswith(f"{mean} (SD {sd})"), (cell, measured[cell].text)
