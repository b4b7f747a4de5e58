"""The README's top: a one-minute read that names everything before it is used."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
import yaml

from jointbench.configuration import config as study_config

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


def _yaml_after(marker: str) -> dict:
    """The first YAML block of the README after ``marker``."""
    start = README.index("```yaml\n", README.index(marker)) + len("```yaml\n")
    return yaml.safe_load(README[start : README.index("```", start)])


def test_listing_a_new_estimator_keeps_the_studys_own():
    """Copied as written, the list that adds a built-in estimator to the cmc study keeps every
    estimator the shipped config lists there: a list that left one out (SCoRE) would drop it
    from the ranking the newcomer is to be compared in."""
    shipped = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    listed = _yaml_after("meets them")["studies"]["cmc"]["estimators"]
    own = shipped["studies"]["cmc"]["estimators"]
    assert listed[: len(own)] == own and listed[len(own) :] == ["sphere-mean"]


def test_listing_an_external_estimator_keeps_the_studys_own():
    """Likewise the list that adds an external estimator to the cmc study."""
    shipped = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    listed = _yaml_after("### Any language: one rule")["studies"]["cmc"]["external_estimators"]
    own = shipped["studies"]["cmc"]["external_estimators"]
    assert listed[: len(own)] == own and listed[len(own) :] == ["centroid"]


#: The texts that list the run's files: the README, the results folder's own and the docs.
LISTINGS = [
    ROOT / "README.md",
    ROOT / "results" / "README.md",
    *sorted((ROOT / "docs").glob("*.md")),
]


@pytest.mark.parametrize("path", LISTINGS, ids=lambda path: path.name)
def test_every_table_listed_names_its_html_page(path):
    """Every table a run writes as CSV and Markdown it writes as an HTML page too (the report
    shows that page): a listing of ``tables/NAME.{csv,md}`` sent a reader of the results
    folder to two of its three files."""
    listed = re.findall(r"tables/[\w*{}]+\.\{([a-z,]+)\}", path.read_text())
    assert all("html" in forms.split(",") for forms in listed if "csv" in forms), listed


#: The README and the docs, whose config snippets a reader copies into a file.
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


@pytest.mark.parametrize("doc", DOCS, ids=lambda path: path.name)
def test_every_config_block_shown_is_read_as_written(doc, tmp_path):
    # Read as Snakemake reads a --configfile, with the checks that refuse a number YAML 1.1
    # reads otherwise than written: a block copied from the docs runs.
    for block in re.findall(r"```ya?ml\n(.*?)```", doc.read_text(), re.S):
        path = tmp_path / "shown.yaml"
        path.write_text(block)
        study_config.read_config_file(path, f"a config block of {doc.name}")


@pytest.mark.parametrize("doc", DOCS, ids=lambda path: path.name)
def test_every_config_value_with_an_exponent_shown_reads_as_a_number(doc):
    # `fe_cycles: 1e-300` copied into a config file is the text '1e-300' to YAML 1.1.
    for key, value in re.findall(r"`([a-z_]+): ([-+.0-9][-+.0-9eE]*)`", doc.read_text()):
        if "e" in value.lower():
            read = study_config.read_yaml(f"{key}: {value}")[key]
            assert isinstance(read, float), f"{doc.name}: `{key}: {value}` reads as {read!r}"
