"""The README's "What stands out": chosen by a stated rule from the measured tables, every
number in it (and in every generated README block) found in the tables it cites."""

from __future__ import annotations

import re
from pathlib import Path

import pandas as pd
import pytest

from jointbench.comparison.cited_numbers import numbers_in, unfound_numbers
from jointbench.comparison.readme_standout import (
    SOURCES,
    STANDOUT_BLOCK,
    Ensembles,
    read_ensembles,
    standout_block,
    stands_out,
)
from jointbench.comparison.snapshot import (
    SUMMARY_BLOCK,
    VERDICTS_BLOCK,
    readme_blocks,
    readme_summary,
    reproduction_counts,
)
from jointbench.ensembles.verdicts import verdict_counts
from jointbench.papers import get_paper, paper_labels, paper_names

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results"
TABLES = RESULTS / "tables"
COMPARISON = TABLES / "published_comparison.csv"


def _comparison(rows: list[tuple[str, str, str]]) -> pd.DataFrame:
    """Comparison rows ``(id, entry, status)`` of paper X."""
    return pd.DataFrame(
        [
            {
                "paper": "X",
                "entry": entry,
                "id": entry_id,
                "quantity": f"quantity {entry_id}",
                "published": "1.5",
                "reproduced": "2.25 mm",
                "status": status,
                "reason": "the recorded reason. A second sentence."
                if status == "not reproduced"
                else "",
            }
            for entry_id, entry, status in rows
        ]
    )


def _ensemble(shares: dict[str, tuple[int, int]], count: str) -> pd.DataFrame:
    """An ensemble summary: per id, reproduced in ``k`` of ``n`` members."""
    return pd.DataFrame(
        [
            {
                "paper": "X",
                "entry": "claim",
                "id": entry_id,
                count: n,
                "reproduced_in": k,
                "interval_95": f"interval of {entry_id}",
                "verdict": "reproduced" if 2 * k > n else "not reproduced",
                "depends_most_on": "choice_mm",
            }
            for entry_id, (k, n) in shares.items()
        ]
    )


CLAIMS = _comparison(
    [
        ("X1", "claim", "reproduced"),
        ("X2", "claim", "not reproduced"),
        ("X3", "claim", "reproduced"),
        ("X4", "claim", "reproduced"),
        ("X5", "claim", "reproduced"),
        ("X6", "claim", "not applicable"),
        ("X-V1", "value", "not reproduced"),
        ("X-V2", "value", "reproduced"),
    ]
)
ENSEMBLES = Ensembles(
    seeds=_ensemble({"X1": (20, 20), "X2": (0, 20), "X3": (17, 20), "X4": (20, 20)}, "seeds"),
    protocols=_ensemble({"X1": (20, 20), "X2": (0, 20), "X3": (20, 20), "X4": (3, 20)}, "draws"),
    named=pd.DataFrame(
        {
            "paper": ["X"] * 2,
            "id": ["X1", "X5"],
            "default": ["reproduced"] * 2,
            "other-layout": ["reproduced", "not reproduced"],
        }
    ),
)


@pytest.mark.parametrize(
    ("entry_id", "expected", "why"),
    [
        ("X1", False, "reproduced in the default run, every seed, every draw and the named one"),
        ("X2", True, "not reproduced in the default run"),
        ("X3", True, "17 of 20 seeds: not unanimous over seeds"),
        ("X4", True, "the default reproduces it, 3 of 20 drawn protocols do"),
        ("X5", True, "a named protocol changes its status"),
        ("X6", False, "not applicable: no verdict to stand out"),
    ],
)
def test_what_stands_out_follows_the_stated_rule(entry_id, expected, why):
    row = CLAIMS[CLAIMS["id"] == entry_id].iloc[0].to_dict()
    assert stands_out(row, ENSEMBLES) is expected, why


def test_the_block_gives_reasons_shares_and_the_default_protocol():
    text = standout_block(CLAIMS, ENSEMBLES, {"X": "X (a paper)"})
    lines = text.splitlines()
    assert "- **Paper X (a paper)**" in lines
    (x2,) = [line for line in lines if line.startswith("  - **X2**")]
    assert "not reproduced — the recorded reason." in x2 and "second sentence" not in x2
    assert "    - Seeds reproducing it: 17 of 20 (interval of X3)." in lines
    assert "    - Drawn protocols reproducing it: 20 of 20 (interval of X3)." in lines
    (x4,) = [i for i, line in enumerate(lines) if line.startswith("  - **X4**")]
    assert lines[x4 + 3] == (
        "    - Drawn protocols reproducing it: 3 of 20 (interval of X4); the default protocol "
        "reproduces it, most drawn ones do not; depends most on `choice_mm`."
    )
    assert "    - Under the other-layout protocol: not reproduced." in lines
    assert "  - **X-V1** not reproduced: the recorded reason." in lines
    assert "  - Reproduced in the default run, every seed and every drawn protocol: X1." in lines
    assert "X6" not in text and "X-V2" not in text


def test_a_new_claim_is_picked_up_without_an_edit():
    grown = pd.concat([CLAIMS, _comparison([("X99", "claim", "not reproduced")])])
    assert "**X99**" in standout_block(grown, ENSEMBLES, {})


def test_without_the_ensembles_the_block_names_the_targets_that_write_them():
    text = standout_block(CLAIMS, Ensembles(), {})
    for key in ("seeds", "protocols", "named"):
        path, target = SOURCES[key]
        assert f"No `results/{path}`: `{target}` writes it." in text
    assert "Seeds reproducing" not in text
    assert "  - Reproduced in the default run: X1, X3, X4, X5." in text


def test_a_number_not_in_the_cited_tables_is_found():
    table = pd.DataFrame({"share": [0.4567], "text": ["error 6.83 mm in 12 of 20"], "n_95": [3]})
    assert unfound_numbers("0.457, 0.46, 6.83 mm, 12 of 20, 3, 95 %", [table]) == []
    # a typed number, a share turned into a percentage, and a value left from another run
    assert unfound_numbers("about 7 mm; 46%; 0.4568", [table]) == ["0.4568", "46", "7"]
    assert numbers_in("frame-0, eq. 2, B-T1-knee, −3.5") == {"3.5"}


def _read(name: str) -> pd.DataFrame:
    return pd.read_csv(TABLES / f"{name}.csv")


def _block(name: str) -> str:
    return readme_summary(ROOT / "README.md", name)


def _missing_citations(text: str) -> list[str]:
    """The result tables ``text`` says it is generated from that this checkout lacks."""
    cited = re.findall(r"`(results/tables/[\w.]+\.csv)`", text)
    return [path for path in cited if not (ROOT / path).is_file()]


def _cited_tables() -> dict[str, list[pd.DataFrame]]:
    """Each generated README block and the tables it cites (with the per-paper counts it
    shows, as the tables' own Markdown notes count them); a paper output's headline cites the
    tables it summarises."""
    comparison = _read("published_comparison")
    ensembles = read_ensembles(RESULTS)
    present = [t for t in (ensembles.seeds, ensembles.protocols, ensembles.named) if t is not None]
    cited = {
        SUMMARY_BLOCK: [comparison, reproduction_counts(comparison, paper_labels())],
        STANDOUT_BLOCK: [comparison, *present],
        **{
            output.name: [_read(name) for name in output.summarises]
            for key in paper_names()
            for output in get_paper(key).outputs
            if output.in_readme
        },
    }
    if ensembles.seeds is not None:
        cited[VERDICTS_BLOCK] = [ensembles.seeds, verdict_counts(ensembles.seeds), *present]
    return cited


needs_results = pytest.mark.skipif(
    not COMPARISON.is_file(), reason="run `snakemake -j2` first: no results/tables to check"
)


@needs_results
@pytest.mark.parametrize("block", readme_blocks(ROOT / "README.md"))
def test_every_number_of_every_readme_block_is_in_the_tables_it_cites(block):
    missing = _missing_citations(_block(block))
    if missing:
        pytest.skip(f"README block {block} cites {', '.join(missing)}, not in this checkout")
    cited = _cited_tables()
    assert block in cited, f"README block {block}: the tables it cites are not known"
    stray = unfound_numbers(_block(block), cited[block])
    assert not stray, f"README block {block}: {stray} are in none of the tables it cites"


def test_the_readme_has_the_generated_blocks():
    assert {SUMMARY_BLOCK, VERDICTS_BLOCK, STANDOUT_BLOCK} <= set(readme_blocks(ROOT / "README.md"))


@needs_results
def test_the_readme_standout_block_is_current():
    missing = _missing_citations(_block(STANDOUT_BLOCK))
    if missing:
        targets = sorted({t for path, t in SOURCES.values() if f"results/{path}" in missing})
        pytest.skip(f"run {' and '.join(targets)} first: no {', '.join(missing)}")
    comparison = _read("published_comparison")
    expected = standout_block(comparison, read_ensembles(RESULTS), paper_labels())
    assert _block(STANDOUT_BLOCK) == expected.strip(), (
        "README 'What stands out' is stale: run `jointbench readme`"
    )


def test_a_comparison_without_a_column_the_block_reads_is_refused():
    with pytest.raises(ValueError, match=r"published_comparison\.csv: no column reason"):
        standout_block(CLAIMS.drop(columns="reason"), ENSEMBLES, {})


def test_jointbench_readme_writes_the_block_where_the_readme_has_it(tmp_path, monkeypatch, capsys):
    from jointbench.cli import main

    tables = tmp_path / "results" / "tables"
    tables.mkdir(parents=True)
    CLAIMS.to_csv(tables / "published_comparison.csv", index=False)
    readme = tmp_path / "README.md"
    readme.write_text(
        "<!-- reproduction-summary:start -->\n<!-- reproduction-summary:end -->\n"
        f"<!-- {STANDOUT_BLOCK}:start -->\ntyped by hand\n<!-- {STANDOUT_BLOCK}:end -->\n"
    )
    monkeypatch.chdir(ROOT)
    assert main(["readme", "--results", str(tmp_path / "results"), "--readme", str(readme)]) == 0
    assert "what stands out updated" in capsys.readouterr().out
    written = readme_summary(readme, STANDOUT_BLOCK)
    assert written == standout_block(CLAIMS, Ensembles(), paper_labels()).strip()
    assert "typed by hand" not in written
