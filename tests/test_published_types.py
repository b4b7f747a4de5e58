"""A published value is read as what its tolerance compares, or refused when the file is loaded.

Each kind of tolerance reads the entry's ``published`` differently
(:mod:`jointbench.comparison.tolerance`): ``abs``, ``rel``, ``max_abs_rel`` and ``factor``
compare the measurement with it, so it is a real number or a list of them; ``binomial95`` reads
it as counts of ``of_n`` trials; the bounds (``at_least`` … ``range``) carry their own numbers
and show the published one as text. A value that the comparison would misread (``true`` as 1,
``"8"`` as 8), or could not read at all (``"8.0 mm"``), is refused with the file, the paper,
the entry and the key; and an entry that still cannot be evaluated when the check runs fails
the check instead of passing as "not applicable".
"""

from __future__ import annotations

from decimal import Decimal
from pathlib import Path

import pandas as pd
import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from jointbench.comparison.published import (
    NOT_APPLICABLE,
    comparison_rows,
    enforce_design,
    failure_message,
    load_published,
    unexplained,
)
from jointbench.comparison.published_types import MIN_RELATIVE_WIDTH, entry_problem
from jointbench.papers import Measured, get_paper, paper_names


def _document(name: str) -> dict:
    return yaml.safe_load(get_paper(name).published.read_text())


def _entry(document: dict, entry_id: str) -> dict:
    entries = [*document.get("values", []), *document["claims"]]
    (entry,) = [e for e in entries if e["id"] == entry_id]
    return entry


def _written(tmp_path: Path, name: str, entry_id: str, change) -> Path:
    """Paper ``name``'s published values with ``change(entry)`` applied to entry ``entry_id``."""
    document = _document(name)
    change(_entry(document, entry_id))
    path = tmp_path / get_paper(name).published.name
    path.write_text(yaml.safe_dump(document, allow_unicode=True, sort_keys=False))
    return path


def _set(key: str, value):
    def change(entry):
        entry[key] = value

    return change


def _set_tolerance(*keys_and_value):
    *keys, value = keys_and_value

    def change(entry):
        node = entry["tolerance"]
        for key in keys[:-1]:
            node = node[key]
        node[keys[-1]] = value

    return change


_MAR = "tolerance.max_abs_rel"
_B, _B_ABS = "B-T1-knee-planar-30-0.3", "tolerance.all[1].abs"

#: (paper, entry, edit, the key the error names, words it gives): each a value the comparison
#: would misread or could not read.
BAD = [
    ("paper_a", "A9", _set("published", "8.0 mm"), "published", "'8.0 mm' is not a number"),
    ("paper_a", "A9", _set("published", "8"), "published", "'8' is not a number"),
    ("paper_a", "A9", _set("published", True), "published", "True is neither a number"),
    ("paper_a", "A9", _set("published", None), "published", "None is neither a number"),
    # shown beside a bound, published is the paper's numbers or words, not YAML's true or null
    ("paper_a", "A6", _set("published", True), "published", "True is neither a number"),
    ("paper_a", "A12", _set("published", None), "published", "None is neither a number"),
    ("paper_a", "A11", _set("published", {"LS": 10.9, "NM": False}), "published", "False is"),
    ("paper_a", "A9", _set("published", [8.0, "x"]), "published", "position 2"),
    ("paper_a", "A9", _set("published", []), "published", "an empty list"),
    ("paper_a", "A9", _set("published", float("nan")), "published", "nan is not a number"),
    # an ``all`` part without its own published value compares the entry's
    ("paper_a", "A5", _set("published", "40 mm"), "published", "'40 mm' is not a number"),
    # a part's own published value
    (
        "paper_c",
        "C1",
        _set_tolerance("all", 1, "published", "15.2"),
        "tolerance.all[1].published",
        "'15.2' is not a number",
    ),
    # ``factor`` divides by it: a ratio of a positive number
    ("paper_c", "C2", _set("published", 0), "published", "0 is not a number > 0"),
    ("paper_c", "C2", _set("published", -0.2), "published", "-0.2 is not a number > 0"),
    # binomial counts: whole numbers of positive whole numbers of trials
    (
        "paper_a",
        "A2",
        _set_tolerance("binomial95", "of_n", 0),
        "tolerance.binomial95.of_n",
        "0 is not an integer >= 1",
    ),
    (
        "paper_a",
        "A2",
        _set_tolerance("binomial95", "of_n", 30.5),
        "tolerance.binomial95.of_n",
        "30.5 is not an integer >= 1",
    ),
    ("paper_a", "A2", _set("published", [30, 16.5, 9]), "published", "16.5"),
    ("paper_a", "A2", _set("published", [30, -1, 9]), "published", "-1"),
    ("paper_a", "A2", _set("published", [31, 16, 9]), "published", "31 of 30"),
    ("paper_a", "A2", _set("published", "30, 16, 9"), "published", "'30, 16, 9'"),
    ("paper_a", "A7", _set("published", [42, 17, 3]), "published", "3 counts for 2"),
    # one count (one for all is of_n's, not the count's) for a list of numbers of trials
    (
        "paper_a",
        "A7",
        _set("published", 42),
        "published",
        "one count, 42, for 2 numbers of trials in tolerance.binomial95.of_n",
    ),
    ("paper_a", "A7", _set("published", [42]), "published", "1 count for 2 numbers of trials"),
    ("paper_a", "A7", _set("published", [42, 91]), "published", "91 of 90"),
    # bounds: finite numbers; a range two increasing numbers
    ("paper_c", "C3", _set_tolerance("range", [3.46, 1.94]), "tolerance.range", "increasing"),
    ("paper_c", "C3", _set_tolerance("range", [2.0, 2.0]), "tolerance.range", "increasing"),
    (
        "paper_c",
        "C4",
        _set_tolerance("range", [0.8, float("inf")]),
        "tolerance.range",
        "inf",
    ),
    ("paper_a", "A1", _set_tolerance("at_least", float("nan")), "tolerance.at_least", "nan"),
    (
        "paper_a",
        "A8",
        _set_tolerance("all", 1, "at_most", float("nan")),
        "tolerance.all[1].at_most",
        "nan",
    ),
    # the tolerance's own width: finite and above zero, which the schema's minimum cannot say
    ("paper_a", "A9", _set_tolerance("max_abs_rel", [float("nan"), 0.25]), _MAR, "nan"),
    ("paper_a", "A9", _set_tolerance("max_abs_rel", [2.0, float("inf")]), _MAR, "inf"),
    ("paper_a", "A9", _set_tolerance("max_abs_rel", [0.0, 0.25]), _MAR, "0.0 is not a finite"),
    ("paper_a", "A5", _set_tolerance("all", 0, "rel", float("nan")), "tolerance.all[0].rel", "nan"),
    ("paper_a", "A5", _set_tolerance("all", 0, "rel", float("inf")), "tolerance.all[0].rel", "inf"),
    ("paper_c", "C2", _set_tolerance("factor", float("inf")), "tolerance.factor", "inf"),
    ("paper_c", "C2", _set_tolerance("factor", float("nan")), "tolerance.factor", "nan"),
    ("paper_b", _B, _set_tolerance("all", 1, "abs", float("nan")), _B_ABS, "nan is not a finite"),
    ("paper_b", _B, _set_tolerance("all", 1, "abs", 0), _B_ABS, "0 is not a finite number > 0"),
]


#: (paper, entry, edit, the key the error names, words it gives): a tolerance so narrow that only
#: the paper's rounded number itself, or a measurement within rounding of it, passes: below
#: ``MIN_RELATIVE_WIDTH`` (1e-9) of the published value, or a factor below 1 + 1e-9.
NARROW = [
    ("paper_c", "C2", _set_tolerance("factor", 1), "tolerance.factor", "1 is not >= 1 + 1e-09"),
    ("paper_c", "C2", _set_tolerance("factor", 1 + 1e-12), "tolerance.factor", ">= 1 + 1e-09"),
    ("paper_c", "C2", _set_tolerance("factor", 0.5), "tolerance.factor", "0.5 is not >= 1 + "),
    ("paper_b", _B, _set_tolerance("all", 1, "abs", 5e-8), _B_ABS, "1e-09 x 76.1"),
    ("paper_a", "A9", _set_tolerance("max_abs_rel", [1e-12, 0.25]), _MAR, "1e-09 x 8.0"),
    ("paper_a", "A9", _set_tolerance("max_abs_rel", [2.0, 1e-12]), _MAR, "1e-12 is not >= 1e-09"),
    ("paper_a", "A5", _set_tolerance("all", 0, "rel", 1e-12), "tolerance.all[0].rel", "1e-09"),
]


@pytest.mark.parametrize(
    ("name", "entry_id", "change", "key", "words"),
    [*BAD, *NARROW],
    ids=[f"{entry}-{key}-{words}" for _, entry, _, key, words in [*BAD, *NARROW]],
)
def test_a_value_its_tolerance_cannot_read_is_refused_naming_where(
    tmp_path, name, entry_id, change, key, words
):
    paper = get_paper(name)
    path = _written(tmp_path, name, entry_id, change)
    with pytest.raises(ValueError) as raised:
        load_published(path, paper.declares, paper.tables)
    message = str(raised.value)
    for part in (str(path), f"paper {paper.letter}", entry_id, f"{key}:", words):
        assert part in message, message
    assert "\n" not in message, message


def test_a_width_at_the_floor_loads(tmp_path):
    """The floor itself is allowed: 1e-9 of the published 76.1, a factor of 1 + 1e-9."""
    for name, entry_id, change in [
        ("paper_b", _B, _set_tolerance("all", 1, "abs", MIN_RELATIVE_WIDTH * 76.1)),
        ("paper_c", "C2", _set_tolerance("factor", 1 + MIN_RELATIVE_WIDTH)),
    ]:
        paper = get_paper(name)
        load_published(_written(tmp_path, name, entry_id, change), paper.declares, paper.tables)


def _written_floor(published: float) -> float:
    """:data:`MIN_RELATIVE_WIDTH` of ``published`` worked out in decimals and read back as a
    file gives it (the double nearest ``1.23456e-07`` for 123.456), not the product of the two
    doubles, which may round one unit of the last place above it."""
    return float(Decimal(repr(MIN_RELATIVE_WIDTH)) * Decimal(repr(published)))


def _abs_problem(width: float, published: object, kind: str):
    tolerance = {"abs": width} if kind == "abs" else {"max_abs_rel": [width, 0.25]}
    return entry_problem({"published": published, "tolerance": tolerance})


@pytest.mark.parametrize("kind", ["abs", "max_abs_rel"])
@pytest.mark.parametrize("published", [1e-3, 1.0, 123.456, 1e6, 7.7, 12.3])
def test_an_absolute_width_at_the_floor_is_allowed_at_any_magnitude(published, kind):
    """At the floor as written and as computed, for the value alone, negated, or the largest of
    a list; a millionth narrower is refused, so the floor still holds."""
    for value in (published, -published, [published / 3, published]):
        for width in (_written_floor(published), MIN_RELATIVE_WIDTH * published):
            assert _abs_problem(width, value, kind) is None, (value, width)
        problem = _abs_problem(_written_floor(published) * (1 - 1e-6), value, kind)
        assert problem is not None and "is narrower than 1e-09 x" in problem[1], problem


@given(published=st.floats(min_value=1e-6, max_value=1e9))
def test_an_absolute_width_written_at_the_floor_of_any_published_value_is_allowed(published):
    assert _abs_problem(_written_floor(published), published, "abs") is None


@pytest.mark.parametrize(
    ("tolerance", "below"),
    [
        ({"rel": 1e-9}, {"rel": 1e-9 * (1 - 1e-6)}),
        ({"factor": 1.000000001}, {"factor": 1.0000000009}),
    ],
    ids=["rel", "factor"],
)
def test_a_relative_width_or_factor_written_at_the_floor_is_allowed(tolerance, below):
    assert entry_problem({"published": 123.456, "tolerance": tolerance}) is None
    assert entry_problem({"published": 123.456, "tolerance": below}) is not None


@pytest.mark.parametrize("name", paper_names())
def test_the_shipped_published_values_are_typed(name):
    paper = get_paper(name)
    load_published(paper.published, paper.declares, paper.tables)


def test_text_is_allowed_where_the_tolerance_carries_its_own_numbers(tmp_path):
    """A bound's entry shows the published sentence as text (``generally``, a list of the
    paper's numbers): its number is the tolerance's, and the text is the paper's words."""
    paper = get_paper("paper_a")
    path = _written(tmp_path, "paper_a", "A6", _set("published", "more than 55 %"))
    document = load_published(path, paper.declares, paper.tables)
    assert _entry(document, "A6")["published"] == "more than 55 %"


# ------------------------------------------------ an entry that cannot be evaluated fails


def _a2_rows(counts: list[int], config: dict | None = None) -> pd.DataFrame:
    """Paper A's comparison with A2 measured as ``counts`` of 30 (and nothing else measured)."""
    paper = get_paper("paper_a")
    document = load_published(paper.published, paper.declares, paper.tables)
    measured = {"A2": Measured({"count": counts, "trials": [30] * len(counts)}, str(counts))}
    rows = comparison_rows(document, measured)
    if config is not None:
        rows = enforce_design(rows, document, config)
    return rows.set_index("id")


def test_a_measurement_of_another_length_fails_the_check_despite_a_deviation():
    """A2 lists three published counts and carries a recorded deviation; two measured counts
    cannot be compared with three: that is a failure, not a reason to pass."""
    rows = _a2_rows([30, 16])
    row = rows.loc["A2"]
    assert row["status"] != NOT_APPLICABLE
    assert row["reason"].startswith("cannot evaluate: "), row["reason"]
    assert "A2" in set(unexplained(rows.reset_index())["id"])
    message = failure_message(rows.reset_index())
    assert message is not None and "A2" in message and "cannot evaluate" in message, message


def test_a_whole_measurement_is_still_judged():
    rows = _a2_rows([30, 16, 9])
    assert rows.loc["A2", "status"] == "reproduced"
    assert failure_message(rows.reset_index()) is None


def test_a_run_off_the_design_is_not_held_to_it_but_says_it_could_not_evaluate():
    """A reduced grid measures A2 at fewer noise levels: like every miss of such a run, it is
    not enforced, and the row says why it could not be judged."""
    config = {"studies": {"cmc": {"trials": 3, "grid": {"noise_mm": [1.0]}}}}
    rows = _a2_rows([16], config)
    row = rows.loc["A2"]
    assert row["status"] == "not reproduced"
    assert "not enforced" in row["reason"] and "cannot evaluate" in row["reason"], row["reason"]
    assert failure_message(rows.reset_index()) is None


def test_a_measurement_the_tolerance_cannot_read_fails_the_check():
    """A compound measurement without the part an ``all`` tolerance reads (a KeyError inside
    the comparison) is a failure too, not an error that stops the table."""
    paper = get_paper("paper_a")
    document = load_published(paper.published, paper.declares, paper.tables)
    rows = comparison_rows(document, {"A8": Measured({"largest_gap_mm": 1.0}, "part")})
    row = rows.set_index("id").loc["A8"]
    assert row["status"] == "not reproduced" and row["reason"].startswith("cannot evaluate: ")
    assert "share_within_0_5_mm" in row["reason"]
    assert failure_message(rows) is not None
