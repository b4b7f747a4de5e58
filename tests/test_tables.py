"""Tables for people: headers in words with units, numbers that never misquote the papers."""

from __future__ import annotations

import re

import pandas as pd
import pytest

from jointbench.comparison.published import STATUSES, load_published, reader_order, status_legend
from jointbench.comparison.snapshot import NONE_TESTED, reproduction_counts, reproduction_summary
from jointbench.comparison.tolerance import describe, evaluate
from jointbench.figures import paper_a
from jointbench.papers import get_paper, paper_c
from jointbench.papers import paper_a as paper_a_paper
from jointbench.resultfiles.formatting import format_column, header, margin_words, number, words
from jointbench.resultfiles.tables import for_people, markdown_table

#: Paper A Table 2's published times (s), as printed in the paper.
PAPER_A_SECONDS = {"MA": 1.2, "LS": 0.0056, "IS": 0.079, "BC": 0.12, "NM": 0.00076}

#: The columns of every table a run writes (see results/README.md).
COLUMNS = [
    "marker_set",
    "rom_deg",
    "noise_mm",
    "fe_rom_deg",
    "aa_ratio",
    "sta_mm",
    "n_frames",
    "mean_error_mm",
    "median_error_mm",
    "mean_error_deg",
    "median_error_deg",
    "mean_seconds",
    "mean_s",
    "median_s",
    "paper_matlab_s",
    "speedup_median",
    "vs_paper_median",
    "reproduced_mean",
    "reproduced_sd",
    "relative_difference",
    "within_tolerance",
    "not_converged",
    "inside_95",
    "mean_validation_index",
    "binomial_low",
    "binomial_high",
    "median_sqrt_trace_cov_mm",
    "rms_error_mm",
    "mean_rank",
]


def _table2() -> pd.DataFrame:
    return pd.DataFrame(
        {
            "method": list(PAPER_A_SECONDS),
            "median_s": [0.00739, 2.234e-05, 0.0115, 0.0002478, 1.664e-05],
            "paper_matlab_s": list(PAPER_A_SECONDS.values()),
        }
    )


def test_published_values_keep_their_digits_and_ours_keep_three_figures():
    rows = markdown_table(_table2()).splitlines()[2:]
    cells = [[c.strip() for c in row.strip("|").split("|")] for row in rows]
    assert [c[2] for c in cells] == ["1.2", "0.0056", "0.079", "0.12", "0.00076"]
    assert [c[1] for c in cells] == ["0.00739", "0.0000223", "0.0115", "0.000248", "0.0000166"]


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (0.845, "0.845"),
        (0.019996, "0.0200"),
        (0.02, "0.02"),
        (3.125e-05, "0.0000313"),
        (556.6, "557"),
        (1500.0, "1500"),
        (0.0, "0"),
    ],
)
def test_ours_is_written_to_three_significant_figures_without_exponents(value, text):
    assert number(value) == text


def test_no_header_a_person_reads_is_a_variable_name():
    frame = pd.DataFrame({c: [1.5] for c in COLUMNS})
    shown = list(for_people(frame).columns)
    assert not [h for h in shown if re.search(r"\w_\w", h)], shown
    assert header("rom_deg") == "RoM (°)" and header("mean_error_mm") == "mean error (mm)"
    assert header("paper_matlab_s").endswith("(s)")


def test_a_table_may_name_its_own_headers():
    frame = pd.DataFrame({"published": [4.3], "difference": [0.24987]})
    shown = for_people(frame, {"published": "published mean (°)"})
    assert list(shown.columns) == ["published mean (°)", "difference"]
    assert shown.iloc[0].tolist() == ["4.3", "0.250"]


def test_truth_is_yes_or_no_and_a_grid_of_whole_numbers_has_no_decimals():
    assert format_column([True, False]) == ["yes", "no"]
    assert format_column([0.0, 10.0, 30.0]) == ["0", "10", "30"]
    assert format_column([float("nan"), 1.25]) == ["–", "1.25"]


def test_two_columns_with_one_header_are_refused():
    with pytest.raises(ValueError, match="same header"):
        for_people(pd.DataFrame({"a_mm": [1.0], "a (mm)": [2.0]}))


def test_margins_and_part_names_are_words():
    assert margin_words(1.7) == "1.7 inside"
    assert margin_words(-3, " trials") == "3 trials outside"
    assert margin_words(0.0) == "on the edge"
    assert words("ls_worst_share") == "LS worst share"
    assert words("share_within_0_5_mm") == "share within 0.5 (mm)"


def test_a_compound_margin_names_its_parts_in_words():
    tolerance = {
        "all": [
            {"of": "ls_worst_share", "at_least": 1.0},
            {"of": "h_excess_mm", "rel": 0.5, "published": 40},
        ]
    }
    verdict = evaluate(tolerance, None, {"ls_worst_share": 1.0, "h_excess_mm": 45.7})
    assert verdict.margin_text == "LS worst share: on the edge; H excess (mm): 14.3 inside"
    assert "_" not in describe(tolerance)


def _comparison() -> pd.DataFrame:
    """A comparison as the check writes it: paper A's values all shown beside ours."""
    rows = [
        ("A", "value", "A-T2-IS", "not applicable"),
        ("A", "claim", "A1", "reproduced"),
        ("A", "claim", "A2", "not reproduced"),
        ("B", "value", "B-T1", "reproduced"),
        ("B", "claim", "B1", "not applicable"),
        ("B", "claim", "B2", "reproduced"),
    ]
    return pd.DataFrame(rows, columns=["paper", "entry", "id", "status"])


def test_every_status_is_one_of_three_words_defined_once():
    assert list(STATUSES) == ["reproduced", "not reproduced", "not applicable"]
    legend = status_legend()
    assert all(f"{word}: {meaning}" in legend for word, meaning in STATUSES.items())
    counts = reproduction_counts(_comparison(), {})
    assert list(counts.columns)[-1] == "not applicable"
    said = " ".join(
        [
            reproduction_summary(_comparison(), {}),
            describe({"shown_only": True}),
            paper_a.speed_wording(0.0, 0.079),
        ]
    )
    assert "comparable" not in said and "not compared" not in said


def test_a_paper_with_nothing_tested_says_so_instead_of_zero_of_zero():
    counts = reproduction_counts(_comparison(), {}).set_index("paper")
    assert counts.loc["A", "published values reproduced"] == NONE_TESTED
    assert counts.loc["A", "claims reproduced"] == "1 / 2"
    assert "0 / 0" not in reproduction_summary(_comparison(), {})


def test_the_comparison_opens_on_its_verdicts():
    ordered = reader_order(_comparison())
    assert list(ordered["id"]) == ["A1", "A2", "B2", "B-T1", "B1", "A-T2-IS"]


def test_the_landing_page_and_the_table_print_a_coverage_alike():
    table = pd.DataFrame(
        {
            "method": ["f0"] * 2,
            "n_frames": [4, 8],
            "inside_95": [0.845, 0.955],
            "status": ["overconfident", "calibrated"],
        }
    )
    sentence = paper_c.calibration_sentence(table)
    assert "(coverage 0.845)" in sentence
    assert "| 0.845 |" in markdown_table(table)


def test_table2_quotes_a_small_time_as_its_table_does():
    rows = []
    for method, seconds in (("LS", 2.377e-05), ("IS", 0.0039)):
        for trial in range(3):
            rows.append(
                {
                    "marker_set": "M",
                    "rom_deg": 5,
                    "noise_mm": 0.5,
                    "trial": trial,
                    "method": method,
                    "seconds": seconds,
                    "converged": True,
                    "error_mm": 1.0,
                }
            )
    collected = pd.DataFrame(rows)
    published = load_published(get_paper("paper_a").published)
    texts = paper_a_paper._timings(collected, published)
    assert texts["A-T2-LS"].text.startswith("0.0000238 s")
    assert "0.0000238" in markdown_table(paper_a.table2(collected, PAPER_A_SECONDS))


def test_a_grid_and_exact_shares_are_written_as_given():
    assert format_column([0.5, 1.0, 2.0]) == ["0.5", "1", "2"]
    assert format_column([0.845, 0.14]) == ["0.845", "0.14"]
    assert format_column([0.02, 3.125e-05]) == ["0.02", "0.0000313"]
