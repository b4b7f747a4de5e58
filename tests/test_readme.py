"""The README's top: a one-minute read that names everything before it is used."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
#: Where the README explains its names, and where its top ends.
NAMES = README.index("**Names used below**")
TOP_END = README.index("## Quick start")

#: Every short name the README's top uses, explained once in its list of names.
SHORT_NAMES = [
    "CoR",
    "AoR",
    "CMC",
    "MCP",
    "RoM",
    "FE",
    "AA",
    "STA",
    "Nt",
    "cmc",
    "hinge",
    "hip_sta",
    "NM",
    "LS",
    "BC",
    "MA",
    "IS",
    "LM",
    "GM",
    "GM-f0",
    "SCoRE",
    "SARA",
    "gauss-markov-frame0",
]


def _first_use(name: str) -> int:
    found = re.search(rf"(?<![\w-]){re.escape(name)}(?![\w-])", README)
    assert found, f"{name} is not in the README"
    return found.start()


@pytest.mark.parametrize("name", SHORT_NAMES)
def test_every_short_name_is_explained_before_it_is_used(name):
    names_end = README.index("\n\n", README.index("\n- ", NAMES))
    assert NAMES < _first_use(name) < names_end, name


def test_outputs_are_regenerated_and_verdicts_reproduced():
    header = next(line for line in README[:TOP_END].splitlines() if line.startswith("| paper |"))
    assert "regenerated" in header and "reproduced" not in header


@pytest.mark.parametrize(
    "part",
    ["§5.2", "Fig 5 and Table 3", "Figs 6–8", "the physical rig"],
)
def test_the_experimental_parts_not_reproduced_are_named(part):
    top = " ".join(README[:TOP_END].split())
    assert part in top and "not regenerated at all" in top


def test_the_summary_has_no_cryptic_counts():
    start = README.index("<!-- reproduction-summary:start -->")
    summary = README[start : README.index("<!-- reproduction-summary:end -->")]
    assert "0 / 0" not in summary
    assert "not comparable" not in summary


def test_the_quick_start_and_test_commands_are_intact():
    assert ".venv/bin/pip install -e . && .venv/bin/snakemake -j2" in README
    assert ".venv/bin/pip install -e '.[test]' && .venv/bin/pytest" in README
