"""A published list is as long as its check's measurement, refused when the file is read.

An entry whose check measures one value per level of a grid key (paper A's A2: BC's converged
trials at each noise level) is declared so by its paper (a ``PerLevel`` in ``Paper.declares``);
the check measures at those levels and the file's lists are held to as many values when it is
loaded, with the file, the paper, the entry, the key, the count and why, not only when a full
run finally compares them. A list in an entry its paper declares no levels for is refused too:
nothing says how many values its check gives.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest
import yaml

from jointbench.comparison.published import load_published
from jointbench.figures.paper_a import FIG4_STATED
from jointbench.papers import get_paper, paper_a, paper_names
from jointbench.papers.base import Inputs, PerLevel

EXTENSION_PAPERS = sorted(Path(__file__).parent.glob("data/*/paper_*.yaml"))


def _document(name: str) -> dict:
    return yaml.safe_load(get_paper(name).published.read_text())


def _entry(document: dict, entry_id: str) -> dict:
    (entry,) = [
        e for e in [*document.get("values", []), *document["claims"]] if e["id"] == entry_id
    ]
    return entry


def _refused(tmp_path: Path, name: str, change) -> tuple[str, Path]:
    """The error loading paper ``name``'s published values after ``change(document)``."""
    document = _document(name)
    change(document)
    path = tmp_path / get_paper(name).published.name
    path.write_text(yaml.safe_dump(document, allow_unicode=True, sort_keys=False))
    paper = get_paper(name)
    with pytest.raises(ValueError) as raised:
        load_published(path, paper.declares, paper.tables)
    message = str(raised.value)
    assert str(path) in message and "\n" not in message, message
    return message, path


def _edit(entry_id: str, *keys_and_value):
    """A change setting the value at ``keys`` (from the entry) of entry ``entry_id``."""
    *keys, value = keys_and_value

    def change(document):
        node = _entry(document, entry_id)
        for key in keys[:-1]:
            node = node[key]
        node[keys[-1]] = value

    return change


def _both(*changes):
    def change(document):
        for one in changes:
            one(document)

    return change


def _cases(table):
    """Parametrize a test by ``table``'s ``(entry_id, change, key, words)`` rows."""
    return pytest.mark.parametrize(
        ("entry_id", "change", "key", "words"),
        table,
        ids=[f"{entry}-{key}-{words}" for entry, _, key, words in table],
    )


#: (entry, change, the key the error names, words it gives): a list of another length than
#: the entry's check measures, whichever list of the entry it is.
WRONG_LENGTH = [
    (
        "A2",
        _both(
            _edit("A2", "published", [30, 16]),
            _edit("A2", "tolerance", "binomial95", "of_n", [30] * 2),
        ),
        "published",
        "2 values",
    ),
    (
        "A2",
        _both(
            _edit("A2", "published", [30, 16, 9, 4]),
            _edit("A2", "tolerance", "binomial95", "of_n", [30] * 4),
        ),
        "published",
        "4 values",
    ),
    (
        "A7",
        _both(
            _edit("A7", "published", [42, 17, 3]),
            _edit("A7", "tolerance", "binomial95", "of_n", [55, 90, 30]),
        ),
        "published",
        "3 values",
    ),
    (
        "A7",
        _both(_edit("A7", "published", [42]), _edit("A7", "tolerance", "binomial95", "of_n", [55])),
        "published",
        "1 value",
    ),
    ("A3", _edit("A3", "tolerance", "greater_than", [25, 60, 90]), "tolerance.greater_than", "3"),
    ("A3", _edit("A3", "published", [25]), "published", "1 value"),
]


@_cases(WRONG_LENGTH)
def test_a_list_of_another_length_than_the_check_measures_is_refused(
    tmp_path, entry_id, change, key, words
):
    message, _ = _refused(tmp_path, "paper_a", change)
    assert "paper A" in message, message
    per = _per_level(entry_id)
    levels = per.levels or tuple(_document("paper_a")["design"]["grid"][per.axis])
    for part in (f"claim {entry_id} {key}:", words, f"needs {len(levels)}", per.of):
        assert part in message, message
    # why that many: one per level, each named
    assert f"({', '.join(map(str, levels))})" in message, message


def test_a2_needs_one_count_per_noise_level_of_the_design():
    """The count comes from the paper's design grid, the levels A2's check groups by: the
    brief's own example, said in words."""
    document = _document("paper_a")
    assert document["design"]["grid"]["noise_mm"] == [0.5, 1.0, 2.0]
    per = _per_level("A2")
    assert per.axis == "noise_mm" and not per.levels


def test_the_count_follows_the_design_not_a_second_number(tmp_path):
    """Two noise levels in the paper's design: A2's three counts are one too many."""

    def two_levels(document):
        document["design"]["grid"]["noise_mm"] = [0.5, 1.0]

    message, _ = _refused(tmp_path, "paper_a", two_levels)
    assert "claim A2 published: 3 values" in message and "needs 2" in message, message


#: (entry, change, the key the error names): one value where the entry's check measures one per
#: level, which the comparison would hold every level to, or a single range (one interval for
#: every level).
SINGLE = [
    (
        "A2",
        _both(_edit("A2", "published", 30), _edit("A2", "tolerance", "binomial95", "of_n", 30)),
        "published",
    ),
    ("A2", _edit("A2", "tolerance", "binomial95", "of_n", 30), "tolerance.binomial95.of_n"),
    ("A7", _edit("A7", "tolerance", "binomial95", "of_n", 55), "tolerance.binomial95.of_n"),
    (
        "A7",
        _both(_edit("A7", "published", 42), _edit("A7", "tolerance", "binomial95", "of_n", 55)),
        "published",
    ),
    ("A3", _edit("A3", "tolerance", "greater_than", 25), "tolerance.greater_than"),
    ("A3", _edit("A3", "published", 25), "published"),
    ("A3", _edit("A3", "tolerance", {"range": [25, 60]}), "tolerance.range"),
]


@_cases([(entry, change, key, "") for entry, change, key in SINGLE])
def test_one_value_where_the_check_measures_one_per_level_is_refused(
    tmp_path, entry_id, change, key, words
):
    message, _ = _refused(tmp_path, "paper_a", change)
    per = _per_level(entry_id)
    levels = per.levels or tuple(_document("paper_a")["design"]["grid"][per.axis])
    assert f"paper A claim {entry_id} {key}: " in message, message
    assert "a single" in message and f"needs {len(levels)}" in message, message
    assert f"({', '.join(map(str, levels))})" in message, message


#: (change of the design grid, the key the error names, words it gives): a design grid whose
#: levels a check measures at is a non-empty list for each key.
DESIGN = [
    (lambda grid: grid.update(noise_mm=1.0), "design/grid/noise_mm", "is not of type 'array'"),
    (lambda grid: grid.update(noise_mm=[]), "design/grid/noise_mm", "should be non-empty"),
    (lambda grid: grid.pop("noise_mm"), "design.grid.noise_mm", "missing"),
    # A per-level list's values are matched to the levels in order: a reordered, repeated or
    # unreadable level would compare one level's count with another's.
    (lambda grid: grid.update(noise_mm=[2.0, 1.0, 0.5]), "design.grid.noise_mm", "ascending"),
    (lambda grid: grid.update(noise_mm=[0.5, 0.5, 2.0]), "design.grid.noise_mm", "ascending"),
    (lambda grid: grid.update(noise_mm=[0.5, float("nan"), 2.0]), "design.grid.noise_mm", "nan"),
    (lambda grid: grid.update(noise_mm=["0.5", "1.0", "2.0"]), "design.grid.noise_mm", "'0.5'"),
]


@pytest.mark.parametrize(
    ("change", "key", "words"),
    DESIGN,
    ids=["scalar", "empty", "missing", "reordered", "repeated", "nan", "text"],
)
def test_the_design_grid_a_check_measures_at_is_a_list_per_key(tmp_path, change, key, words):
    message, _ = _refused(tmp_path, "paper_a", lambda document: change(document["design"]["grid"]))
    assert key in message and words in message, message


#: (entry, change, key, words): malformed lists of an entry measured per level, refused by the
#: typed checks, which name the paper, the entry and the key.
MALFORMED = [
    ("A2", _edit("A2", "published", []), "published", "an empty list"),
    ("A2", _edit("A2", "published", [[30], 16, 9]), "published", "[30] is not a count"),
    ("A2", _edit("A2", "published", [30, "16", 9]), "published", "'16' is not a count"),
    ("A2", _edit("A2", "published", [30, 16, None]), "published", "None is neither"),
    ("A7", _edit("A7", "published", [[42, 17]]), "published", "[42, 17] is not a count"),
    ("A7", _edit("A7", "published", [42, "17 trials"]), "published", "'17 trials'"),
    ("A3", _edit("A3", "published", []), "published", "an empty list"),
    ("A3", _edit("A3", "published", [[25], 60]), "published", "position 1 holds [25]"),
    ("A3", _edit("A3", "published", [25, "60 mm"]), "published", "position 2 holds '60 mm'"),
]


@_cases(MALFORMED)
def test_a_malformed_list_is_refused_when_the_file_is_read(tmp_path, entry_id, change, key, words):
    message, _ = _refused(tmp_path, "paper_a", change)
    assert f"paper A claim {entry_id} {key}: " in message and words in message, message


#: (entry, change, key, words): malformed lists of a tolerance, refused by the schema, which
#: names the entry by its position in the file and the key as a path.
MALFORMED_TOLERANCE = [
    ("A7", _edit("A7", "tolerance", "binomial95", "of_n", []), "binomial95/of_n", "non-empty"),
    ("A3", _edit("A3", "tolerance", "greater_than", []), "greater_than", "non-empty"),
    ("A3", _edit("A3", "tolerance", "greater_than", [[25], 60]), "greater_than", "[25]"),
    ("A3", _edit("A3", "tolerance", "greater_than", [25, "60"]), "greater_than/1", "'60'"),
]


@_cases(MALFORMED_TOLERANCE)
def test_a_malformed_list_of_a_tolerance_is_refused_by_the_schema(
    tmp_path, entry_id, change, key, words
):
    message, _ = _refused(tmp_path, "paper_a", change)
    position = [e["id"] for e in _document("paper_a")["claims"]].index(entry_id)
    assert f"claims/{position}/tolerance/{key}" in message and words in message, message


#: (paper, entry, change, key): a list in an entry its paper declares no levels for.
UNDECLARED = [
    ("paper_a", "A9", _edit("A9", "published", [8.0, 9.0]), "published"),
    ("paper_a", "A1", _edit("A1", "tolerance", "at_least", [0.8, 0.9]), "tolerance.at_least"),
    ("paper_a", "A5", _edit("A5", "published", [40, 30]), "published"),
    ("paper_c", "C5", _edit("C5", "tolerance", "less_than", [5, 6]), "tolerance.less_than"),
]


@pytest.mark.parametrize(
    ("name", "entry_id", "change", "key"), UNDECLARED, ids=[u[1] for u in UNDECLARED]
)
def test_a_list_where_the_paper_declares_no_levels_is_refused(
    tmp_path, name, entry_id, change, key
):
    message, _ = _refused(tmp_path, name, change)
    assert f"paper {get_paper(name).letter}" in message, message
    assert f"{entry_id} {key}:" in message and "declares no levels" in message, message


@pytest.mark.parametrize("name", paper_names())
def test_every_list_of_the_shipped_files_loads(name):
    paper = get_paper(name)
    load_published(paper.published, paper.declares, paper.tables)


@pytest.mark.parametrize("path", EXTENSION_PAPERS, ids=lambda p: p.parent.name)
def test_the_extension_papers_published_values_load(path):
    assert load_published(path)["paper"] == "T"


def _per_level(entry_id: str) -> PerLevel:
    (per,) = [
        d for d in get_paper("paper_a").declares if isinstance(d, PerLevel) and d.entry == entry_id
    ]
    return per


def test_paper_a_declares_its_lists_per_level():
    listed = {d.entry for d in get_paper("paper_a").declares if isinstance(d, PerLevel)}
    assert listed == {"A2", "A3", "A7"}


def test_a3_is_measured_where_fig4_draws_it():
    """A3's levels are those of the conditions Fig 4 draws its bounds at, not typed again."""
    (conditions, _) = FIG4_STATED["A3"]
    assert _per_level("A3").levels == tuple(c["noise_mm"] for c in conditions)


def _bc_rows(noise_levels, converged=lambda noise, trial: trial < 2) -> pd.DataFrame:
    """BC's rows at the M set and 5° RoM, three trials at each of ``noise_levels``."""
    return pd.DataFrame(
        [
            {
                "method": "BC",
                "marker_set": "M",
                "rom_deg": 5,
                "noise_mm": noise,
                "trial": trial,
                "converged": converged(noise, trial),
                "error_mm": 1.0,
            }
            for noise in noise_levels
            for trial in range(3)
        ]
    )


def _measured_a2(collected: pd.DataFrame):
    published = load_published(get_paper("paper_a").published)
    inputs = Inputs(collected=collected, published=published, config={"studies": {}})
    return paper_a.measure(inputs).get("A2")


def test_a2_counts_at_the_declared_levels_whatever_else_the_run_has():
    """A run with a noise level beyond the design's: A2 counts at the design's three, in their
    order, not at the four the run has."""
    design = _document("paper_a")["design"]["grid"]["noise_mm"]

    def converged(noise, trial):
        return noise in design and trial <= design.index(noise)

    measured = _measured_a2(_bc_rows([4.0, *design], converged))
    assert measured.value == {"count": [1, 2, 3], "trials": [3, 3, 3]}


def test_a2_is_not_measured_when_the_run_lacks_a_declared_level():
    """Three noise levels, one not the design's: three counts, one at the wrong level, would be
    compared with the paper's three; the claim is left unmeasured instead."""
    design = _document("paper_a")["design"]["grid"]["noise_mm"]
    assert _measured_a2(_bc_rows([*design[:2], 4.0])) is None
    assert _measured_a2(_bc_rows(design)) is not None


def test_a2_counts_at_each_level_its_declaration_names():
    """A2's check gives one count per noise level its declaration names: on the paper's
    design, as many as the published list holds."""
    design = _document("paper_a")["design"]["grid"][_per_level("A2").axis]
    measured = _measured_a2(_bc_rows(design))
    assert measured.value["count"] == [2, 2, 2]
    assert len(measured.value["count"]) == len(_entry(_document("paper_a"), "A2")["published"])
