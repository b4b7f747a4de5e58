"""A claim's selection the run lacks is "not measured" only where some run could have it.

A claim asks a run for methods, levels of the grid and recorded columns through
:func:`~jointbench.papers.common.with_columns` and :func:`~jointbench.papers.common.at_levels`.
Where the run lacks one its paper declares (a method of the paper, a level of its design grid)
the claim is not measured in this run, and the claims table says which was missing. Where no
run could hold it (a misspelt method, a level of the wrong type or one the design grid does
not list, a key no study has) the check is mistaken: a ``RuntimeError`` naming the claim.
"""

from __future__ import annotations

import claim_worlds
import pandas as pd
import pytest
from test_claims import paper_c_world

from jointbench.comparison.published import NOT_APPLICABLE, comparison_rows, load_published
from jointbench.papers import Inputs, Measured, paper_a, paper_b, paper_c, paper_sta
from jointbench.papers.common import NotMeasured, at_levels, measured_claims, with_columns

MODULES = {"A": paper_a, "B": paper_b, "S": paper_sta}


documents = claim_worlds.documents_fixture(MODULES)
worlds = claim_worlds.worlds_fixture()


def _a_wide(collected, means):
    return means.pivot_table(index=paper_a.CONDITION, columns="method", values="mean_error_mm")


def _b_by_protocol(means):
    return means.pivot_table(
        index=["method", "fe_rom_deg", "aa_ratio"], columns="protocol", values="mean"
    )


def _selecting(select):
    """A check whose selection is ``select(*data)``: it measures the selection's size."""

    def check(*data):
        return Measured(float(select(*data).size), "")

    return check


#: Per case: the paper, the claim replaced, the mistaken selection, and what the error names.
MISTAKES = {
    "misspelt method": (
        "A",
        "A5",
        lambda collected, means: with_columns(_a_wide(collected, means), ["LS", "Nm"], "method"),
        "method 'Nm'",
    ),
    "misspelt protocol": (
        "B",
        "B5",
        lambda means: with_columns(_b_by_protocol(means), ("knee", "mpc"), "protocol"),
        "protocol 'mpc'",
    ),
    "misspelt method as a level": (
        "S",
        "S2",
        lambda means: at_levels(means, method="score", sta_mm=0.0),
        "method 'score'",
    ),
    "undeclared noise level": (
        "A",
        "A10",
        lambda collected, means: at_levels(_a_wide(collected, means), noise_mm=0.25),
        "noise_mm 0.25",
    ),
    "level of the wrong type": (
        "S",
        "S1",
        lambda means: at_levels(means, rom_deg="45", sta_mm=0.0),
        "rom_deg '45'",
    ),
    "undeclared STA amplitude": (
        "S",
        "S6",
        lambda means: at_levels(means, sta_mm=0.25),
        "sta_mm 0.25",
    ),
}


@pytest.mark.parametrize("case", MISTAKES)
def test_a_selection_no_run_could_hold_is_raised_naming_the_claim(
    documents, worlds, monkeypatch, case
):
    """The full grid holds every method and level each paper declares: a selection that finds
    nothing there asks for what no run of the paper could have."""
    letter, claim, select, named = MISTAKES[case]
    monkeypatch.setitem(MODULES[letter]._CLAIMS, claim, _selecting(select))
    with pytest.raises(RuntimeError, match=rf"^claim {claim}: ") as raised:
        claim_worlds.measure(letter, documents, worlds[letter])
    assert named in str(raised.value)
    assert isinstance(raised.value.__cause__, NotMeasured)


def test_a_key_no_study_has_is_raised_naming_the_claim(documents, worlds, monkeypatch):
    """The protocol mcp is declared, but not as a value of a misspelt key: on a run at the knee
    only, the selection's lack is not read as the run's."""

    def misspelt_key(means):
        return with_columns(_b_by_protocol(means), ("knee", "mcp"), "protocl")

    monkeypatch.setitem(paper_b._CLAIMS, "B5", _selecting(misspelt_key))
    world = worlds["B"]
    with pytest.raises(RuntimeError, match=r"^claim B5: asks for protocl, no key") as raised:
        claim_worlds.measure("B", documents, world[world["protocol"] == "knee"])
    assert isinstance(raised.value.__cause__, NotMeasured)


#: Per case: the paper, the rows the sub-grid keeps, a claim it drops through a selection of
#: a declared method or level, and what the reason names.
ABSENT = {
    "A without BC": ("A", lambda world: world["method"] != "BC", "A5", "method BC"),
    "B without combined": ("B", lambda world: world["method"] != "combined", "B4", "combined"),
    "B at the knee only": ("B", lambda world: world["protocol"] == "knee", "B5", "protocol mcp"),
    "S without SCoRE": ("S", lambda world: world["method"] != "SCoRE", "S2", "method SCoRE"),
    "S without 0 mm STA": ("S", lambda world: world["sta_mm"] > 0, "S1", "sta_mm 0.0"),
    "S at 45 degrees only": ("S", lambda world: world["rom_deg"] == 45.0, "S3", "rom_deg 20.0"),
}


@pytest.mark.parametrize("case", ABSENT)
def test_a_declared_method_or_level_the_run_lacks_is_not_measured_saying_which(
    documents, worlds, case
):
    letter, kept, claim, named = ABSENT[case]
    world = worlds[letter]
    measured = claim_worlds.measure(letter, documents, world[kept(world)])
    assert claim not in measured
    assert named in measured.not_measured[claim]
    # Each reason is read in the claims table: numbers as written, not numpy's reprs.
    assert not [why for why in measured.not_measured.values() if "np." in why]


def _paper_a_without_bc(documents, worlds) -> Inputs:
    world = worlds["A"]
    return Inputs(
        collected=world[world["method"] != "BC"],
        published=documents["A"],
        config={"studies": {}},
    )


def test_the_claims_table_of_a_run_without_bc_names_bc(documents, worlds):
    inputs = _paper_a_without_bc(documents, worlds)
    table = paper_a.PAPER.output("paper_a_claims").render(inputs).frame.set_index("id")
    for claim in ("A4", "A5", "A6", "A8", "A10"):
        row = table.loc[claim]
        assert row["status"] == NOT_APPLICABLE, claim
        assert row["reason"] == "not measured in this run: this run has no method BC", claim
        assert row["reproduced"] == "cannot evaluate: " + row["reason"], claim
    assert (
        table.loc["A2", "reason"] == "not measured in this run: BC is not in this run at the M set"
    )


def test_a2_at_a_run_lacking_its_noise_levels_names_them_not_bc(documents, worlds):
    """BC ran: what A2 lacks is the levels it counts at, and its reason says which."""
    world = worlds["A"]
    axis = paper_a.A2_LEVELS.axis
    kept = sorted(world[axis].unique())[1:2]
    measured = claim_worlds.measure("A", documents, world[world[axis].isin(kept)])
    design = documents["A"]["design"]["grid"]
    lacking = [level for level in paper_a.A2_LEVELS.levels_in(design) if level not in kept]
    assert lacking
    shown = ", ".join(map(str, lacking))
    assert measured.not_measured["A2"] == f"this run has no {axis} {shown} for BC at the M set"


def test_the_published_comparison_of_a_run_without_bc_names_bc(documents, worlds):
    inputs = _paper_a_without_bc(documents, worlds)
    rows = comparison_rows(documents["A"], paper_a.measure(inputs)).set_index("id")
    assert rows.loc["A5", "status"] == NOT_APPLICABLE
    assert rows.loc["A5", "reason"] == "not measured in this run: this run has no method BC"


def test_paper_c_without_its_method_says_so_of_every_claim():
    world = paper_c_world(trials=5)
    inputs = Inputs(
        collected=world[world["method"] != "gauss-markov"],
        published=load_published(paper_c.PAPER.published),
        config={"studies": {}},
    )
    measured = paper_c.measure(inputs)
    assert not measured
    assert set(measured.not_measured) == set(paper_c._CLAIMS)
    assert set(measured.not_measured.values()) == {"this run has no method gauss-markov"}


def test_a_claim_whose_value_is_not_finite_says_so():
    measured = measured_claims({"X1": lambda _: Measured(float("nan"), "nan")}, 0)
    assert not measured
    assert "not finite" in measured.not_measured["X1"]


def test_the_selections_say_what_the_run_lacks_by_key():
    """What :func:`measured_claims` holds to the paper's declared methods and levels."""
    index = pd.MultiIndex.from_tuples([("M", 5), ("H", 5)], names=["marker_set", "rom_deg"])
    table = pd.DataFrame({"LS": [1.0, 2.0]}, index=index)
    with pytest.raises(NotMeasured, match="this run has no method NM") as raised:
        with_columns(table, ["LS", "NM"], "method")
    assert raised.value.lacks == {"method": ("NM",)}
    with pytest.raises(NotMeasured, match="this run has no cell at marker_set M, rom_deg 15"):
        at_levels(table, marker_set="M", rom_deg=15)
    with pytest.raises(NotMeasured) as raised:
        at_levels(table, marker_set="M", rom_deg=15)
    assert raised.value.lacks == {"marker_set": ("M",), "rom_deg": (15,)}


def test_a_reason_lists_the_run_s_levels_as_the_config_writes_them(documents, worlds):
    """Paper B's grid at ratios 0.3 and 0.5 (the reduced run's): B2's reason, which the claims
    table and the published comparison show, lists them as numbers, not numpy's reprs."""
    world = worlds["B"]
    measured = claim_worlds.measure("B", documents, world[world["aa_ratio"].isin([0.3, 0.5])])
    assert measured.not_measured["B2"].endswith("this run has ratios [0.3, 0.5]")


def test_a_claim_no_run_of_ours_measures_says_why_not_that_this_run_did_not(documents, worlds):
    """S5 (Begon et al.'s protocol and STA model, none of our conditions): its claims-table row
    gives the paper's reason, not "not measured in this run", which a fuller run would mend."""
    inputs = Inputs(
        collected=worlds["S"],
        published=load_published(paper_sta.PAPER.published),
        config={"studies": {}},
    )
    row = paper_sta.PAPER.output("paper_sta_claims").render(inputs).frame.set_index("id").loc["S5"]
    assert row["status"] == NOT_APPLICABLE
    assert row["reason"].startswith("Begon et al. drew their noise")
    assert row["reproduced"] == "cannot evaluate: " + row["reason"]


def test_a_claim_shown_only_that_this_run_did_not_measure_says_what_it_lacks(documents, worlds):
    """A12 (the order of speeds, shown beside the paper's) on a run that recorded no times."""
    inputs = Inputs(
        collected=worlds["A"].drop(columns="seconds"),
        published=documents["A"],
        config={"studies": {}},
    )
    row = paper_a.PAPER.output("paper_a_claims").render(inputs).frame.set_index("id").loc["A12"]
    assert row["reproduced"] == (
        "cannot evaluate: not measured in this run: this run has no recorded column seconds"
    )
