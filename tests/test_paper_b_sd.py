"""Paper B Table 1's standard deviations, compared row by row (their cell order is lost)."""

from __future__ import annotations

import pandas as pd
import pytest

from jointbench.comparison.published import load_published
from jointbench.papers.paper_b import PAPER, SPLIT_SD_DEG, table1_sd_rows


def _cells(sds: list[float]) -> pd.DataFrame:
    """One row (knee, radial) of our Table 1: twelve cells with the given SDs [deg]."""
    keys = [(fe, ratio) for fe in (30, 60, 90) for ratio in (0.1, 0.3, 0.5, 0.7)]
    return pd.DataFrame(
        {
            "protocol": "knee",
            "method": "radial",
            "fe_rom_deg": [fe for fe, _ in keys],
            "aa_ratio": [ratio for _, ratio in keys],
            "reproduced_sd": sds,
        }
    )


def test_the_rows_are_compared_without_their_cell_order():
    published = [0.5] * 10 + [18.0, 7.0]
    ours = [1.0] * 5 + [9.0] + [1.0] * 6
    (row,) = table1_sd_rows(_cells(ours), {"knee radial": published}).to_dict("records")
    assert row["published_median_sd"] == 0.5
    assert row["reproduced_median_sd"] == 1.0
    assert row["published_largest_sd"] == 18.0
    assert row["reproduced_largest_sd"] == 9.0
    assert row["reproduced_largest_at"] == "FE 60°, AA/FE 0.3"
    assert (row["published_split_cells"], row["reproduced_split_cells"]) == (2, 1)
    # Shuffling the published SDs changes nothing: only order-free summaries are compared.
    shuffled = table1_sd_rows(_cells(ours), {"knee radial": published[::-1]})
    assert shuffled.to_dict("records") == [row]


def test_a_run_over_part_of_the_grid_summarises_the_cells_it_measured():
    ours = [float("nan")] * 12
    ours[2], ours[7] = 2.0, 6.0
    (row,) = table1_sd_rows(_cells(ours), {"knee radial": [0.5] * 12}).to_dict("records")
    assert row["measured_cells"] == 2
    assert (row["reproduced_median_sd"], row["reproduced_largest_sd"]) == (4.0, 6.0)
    assert row["reproduced_largest_at"] == "FE 60°, AA/FE 0.7"
    assert row["reproduced_split_cells"] == 1
    (none,) = table1_sd_rows(_cells([float("nan")] * 12), {"knee radial": [0.5] * 12}).to_dict(
        "records"
    )
    assert none["measured_cells"] == 0 and none["reproduced_largest_at"] == ""


def test_a_split_cell_starts_at_the_threshold():
    ours = [SPLIT_SD_DEG] + [SPLIT_SD_DEG - 1e-9] * 11
    (row,) = table1_sd_rows(_cells(ours), {"knee radial": [0.1] * 12}).to_dict("records")
    assert row["reproduced_split_cells"] == 1


@pytest.mark.parametrize(
    ("rows", "message"),
    [({}, "no published SDs for the row 'knee radial'"), ({"knee radial": [1.0] * 11}, "11")],
)
def test_a_missing_or_short_published_row_is_refused(rows, message):
    with pytest.raises(ValueError, match=message):
        table1_sd_rows(_cells([1.0] * 12), rows)


def test_the_published_sds_cover_every_row_of_table1():
    rows = load_published(PAPER.published)["table1_sd"]["rows"]
    assert sorted(rows) == sorted(
        f"{protocol} {method}"
        for protocol in ("knee", "mcp")
        for method in ("planar", "radial", "combined")
    )
    assert all(len(sds) == 12 for sds in rows.values())
