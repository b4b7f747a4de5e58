"""Every claim on every sub-grid a configuration can make: measured, or not measured in this run.

A run's grid may hold one or two levels of a key, leave a method out or run one or two trials.
Each claim then either measures what its sentence speaks of, or raises so that it reads "not
measured in this run": never a NaN in its text, a verdict drawn from an empty selection, or a
numpy/pandas RuntimeWarning.

``tests/snapshots/subgrid_claims.json`` holds, for every sub-grid, the claims measured on it
when it was written: a change to how claims select their data must measure the same ones.
``python tests/test_claims_subgrids.py`` rewrites the file, for a deliberate change of what a
claim needs only.
"""

from __future__ import annotations

import itertools
import json
import math
import re
import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from test_claims import (
    A_METHODS,
    A_SPEEDS,
    C_FRAMES,
    _timed,
    paper_a_world,
    paper_b_world,
    paper_c_world,
)

from jointbench.comparison.published import load_published
from jointbench.papers import Inputs, Measured, get_paper
from jointbench.papers.common import NotMeasured, measured_claims
from jointbench.papers.paper_sta import MEASURED

PAPERS = {"A": "paper_a", "B": "paper_b", "C": "paper_c", "S": "paper_sta"}
PINNED = Path(__file__).parent / "snapshots" / "subgrid_claims.json"


def _documents() -> dict:
    return {letter: load_published(get_paper(PAPERS[letter]).published) for letter in PAPERS}


@pytest.fixture(scope="module")
def documents():
    return _documents()


#: Each paper's synthetic grid: its keys' levels, and its methods.
GRIDS = {
    "A": (
        {"marker_set": ("M", "H"), "rom_deg": (5, 15, 45), "noise_mm": (0.5, 1.0, 2.0)},
        A_METHODS,
    ),
    "B": (
        {"protocol": ("knee", "mcp"), "fe_rom_deg": (30, 60, 90), "aa_ratio": (0.1, 0.3, 0.5, 0.7)},
        ("planar", "radial", "combined"),
    ),
    "C": ({"n_frames": C_FRAMES}, ("gauss-markov",)),
    "S": (
        {
            "motion": ("star_arc", "circumduction"),
            "rom_deg": (20.0, 45.0),
            "sta_mm": (0.0, 10.0, 20.0, 30.0),
        },
        MEASURED,
    ),
}


def _subgrids(letter: str):
    """``(letter, what, how)`` for every sub-grid of a paper's grid: each key at one level and
    at two, each method left out, one and two trials."""
    grid, methods = GRIDS[letter]
    for key, levels in grid.items():
        for size in (1, 2):
            for chosen in itertools.combinations(levels, size):
                yield letter, key, chosen
    for method in methods:
        yield letter, "without", method
    for trials in (1, 2):
        yield letter, "trials", trials


def _restricted(collected: pd.DataFrame, what: str, how) -> pd.DataFrame:
    if what == "without":
        return collected[collected["method"] != how]
    if what == "trials":
        return collected[collected["trial"] < how]
    return collected[collected[what].isin(how)]


def _finite(value) -> bool:
    if isinstance(value, dict):
        return all(_finite(v) for v in value.values())
    if isinstance(value, list | tuple):
        return all(_finite(v) for v in value)
    return not isinstance(value, float) or math.isfinite(value)


def _measured_cleanly(paper_key: str, document, collected: pd.DataFrame, grid: str):
    """The paper's measurements of ``collected`` with RuntimeWarnings as errors; each finite
    and its text free of NaN and inf."""
    paper = get_paper(paper_key)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        measured = paper.measure(
            Inputs(collected=collected, published=document, config={"studies": {}})
        )
    for key, found in measured.items():
        assert _finite(found.value), (grid, key, found)
        words = found.text.lower().replace(",", " ").replace(";", " ").split()
        assert not {"nan", "nan°", "nan%", "inf", "inf°"} & set(words), (grid, key, found.text)
        # A count out of none is a verdict from an empty selection.
        assert not re.search(r"\b0 of 0\b", found.text), (grid, key, found.text)
    return measured


def test_b1_and_b2_are_not_measured_at_one_ratio(documents):
    """At the one ratio 0.1 no ratio increase and no other ratio was run."""
    world = paper_b_world(documents)
    only = world[world["aa_ratio"] == 0.1]
    measured = _measured_cleanly("paper_b", documents["B"], only, "aa_ratio=[0.1]")
    assert "B1" not in measured and "B2" not in measured


def test_b2_needs_ratio_0_1(documents):
    """'< 5° only at 0.1' says nothing of a run whose lowest ratio is 0.3."""
    world = paper_b_world(documents)
    measured = _measured_cleanly(
        "paper_b", documents["B"], world[world["aa_ratio"] >= 0.3], "aa_ratio>=0.3"
    )
    assert "B2" not in measured


def test_a10_reads_the_cells_both_marker_sets_have_and_names_the_others(documents):
    """One noise level and one trial: at the M set and 5 degrees BC converged in no trial, so
    that cell has no mean and no H/M ratio; A10 is measured over the cells that have one, and
    its text names the range without any rather than print a NaN for it."""
    world = _timed(paper_a_world(), A_SPEEDS)
    sub = world[(world["noise_mm"] == 1.0) & (world["trial"] < 1)]
    measured = _measured_cleanly("paper_a", documents["A"], sub, "noise_mm=[1.0], trials=1")
    assert measured["A10"].text.endswith("; no cell with a mean at both sets at 5°")


def paper_sta_world(trials: int = 3) -> pd.DataFrame:
    """Collected hip_sta rows of the measured methods: an error that grows with the STA and
    falls with the range, lower on the star-arc, SCoRE second best."""
    rank = {method: index for index, method in enumerate(MEASURED)}
    rows = []
    grid, methods = GRIDS["S"]
    for motion, rom, sta in itertools.product(*grid.values()):
        for method, trial in itertools.product(methods, range(trials)):
            error = (1.0 + 0.1 * rank[method]) * (1 + sta / 5) * (20 / rom) ** 0.5
            error *= 1.0 if motion == "star_arc" else 1.3
            rows.append(
                {
                    "motion": motion,
                    "rom_deg": rom,
                    "sta_mm": sta,
                    "method": method,
                    "trial": trial,
                    "error_mm": error + 0.01 * trial,
                    "converged": True,
                }
            )
    return pd.DataFrame(rows)


def _worlds(documents) -> dict:
    return {
        "A": _timed(paper_a_world(), A_SPEEDS),
        "B": paper_b_world(documents),
        "C": paper_c_world(trials=20),
        "S": paper_sta_world(),
    }


@pytest.fixture(scope="module")
def worlds(documents):
    return _worlds(documents)


SUBGRIDS = [case for letter in GRIDS for case in _subgrids(letter)]


def _case_name(letter: str, what: str, how) -> str:
    return f"{letter} {what}={how}"


def _claims_measured(documents, worlds, letter: str, what: str, how) -> list[str]:
    """The ids of the claims measured on the sub-grid, in the published file's order."""
    collected = _restricted(worlds[letter], what, how)
    measured = _measured_cleanly(PAPERS[letter], documents[letter], collected, f"{what}={how}")
    return [c["id"] for c in documents[letter]["claims"] if c["id"] in measured]


@pytest.fixture(scope="module")
def pinned():
    return json.loads(PINNED.read_text())


def test_the_pinned_claims_name_every_subgrid(pinned):
    assert set(pinned) == {_case_name(*case) for case in SUBGRIDS}


@pytest.mark.parametrize(("letter", "what", "how"), SUBGRIDS, ids=lambda part: str(part))
def test_every_claim_on_every_subgrid_is_measured_or_not_in_this_run(
    documents, worlds, pinned, letter, what, how
):
    """Every measurement on the sub-grid is finite, says no NaN and counts out of something;
    the rest are left out (not measured in this run): the same claims as pinned."""
    found = _claims_measured(documents, worlds, letter, what, how)
    assert found == pinned[_case_name(letter, what, how)]


#: The claims each full synthetic grid measures (A13 reads fitted radii,
#: C5 pose fits, S5 covariances, which the synthetic rows do not hold).
FULL = {
    "A": [f"A{i}" for i in range(1, 13)],
    "B": [f"B{i}" for i in range(1, 7)],
    "C": ["C1", "C2", "C3", "C4"],
    "S": ["S1", "S2", "S3", "S4", "S6", "S7"],
}


@pytest.mark.parametrize("letter", GRIDS)
def test_the_full_grid_measures_every_claim_it_holds_data_for(documents, worlds, letter):
    """The guards leave no claim of a full grid unmeasured."""
    measured = _measured_cleanly(PAPERS[letter], documents[letter], worlds[letter], "full")
    claims = [c["id"] for c in documents[letter]["claims"]]
    assert [c for c in claims if c in measured] == FULL[letter]


def test_a_claim_without_its_data_is_left_out_and_a_warning_is_an_error():
    """The one loop every paper runs its claims through: a claim whose data are absent (it
    raises NotMeasured, or its value is not finite) is not measured; anything else it raises,
    and numpy arithmetic on nothing, is a mistake of the check, raised with the claim's id,
    never a number nor "not measured"."""

    def nan_share(_):
        return Measured(float("nan"), "nan")

    def empty_mean(_):
        return Measured(float(np.mean(np.array([]))), "mean of nothing")

    def absent(_):
        raise NotMeasured("this run has no method radial")

    def misread(_):
        raise KeyError("radial")

    claims = {"X1": lambda n: Measured(n, f"{n}"), "X2": nan_share, "X3": absent}
    measured = measured_claims(claims, 2.0)
    assert list(measured) == ["X1"] and measured["X1"].value == 2.0
    nested = {"X4": lambda _: Measured({"share": [1.0, float("inf")]}, "inf")}
    assert measured_claims(nested, 0) == {}
    with pytest.raises(RuntimeError, match=r"claim X5: Mean of empty slice"):
        measured_claims({"X5": empty_mean}, 0)
    with pytest.raises(RuntimeError, match=r"claim X6: KeyError: 'radial'") as raised:
        measured_claims({"X6": misread}, 0)
    assert isinstance(raised.value.__cause__, KeyError)


@pytest.mark.parametrize("frames", [(8, 75), (16, 150), (75, 600)])
def test_paper_c_reads_nothing_against_another_reference_than_1200_frames(documents, frames):
    """C2 is the accuracy at Nt = 1200, and v (C3, Table 1's row) is against each trial's
    1200-frame estimate: a run whose longest sequence is shorter measures neither."""
    world = paper_c_world(trials=20)
    collected = world[world["n_frames"].isin(frames)]
    measured = _measured_cleanly("paper_c", documents["C"], collected, f"n_frames={frames}")
    assert not {"C2", "C3"} & set(measured)
    assert not [key for key in measured if "validation_index" in key]
    assert f"C-T1-sqrt_trace_cov_mm-{frames[0]}" in measured
    with_reference = world[world["n_frames"].isin((*frames, 1200))]
    measured = _measured_cleanly("paper_c", documents["C"], with_reference, "with 1200")
    assert {"C2", "C3", f"C-T1-validation_index-{frames[0]}"} <= set(measured)


@pytest.mark.parametrize(
    ("ratios", "claim"), [((0.1,), "B4"), ((0.3, 0.5), "B4"), ((0.1, 0.5), "B3")]
)
def test_b3_and_b4_need_both_lowest_ratios(documents, ratios, claim):
    """B4 speaks of the two lowest ratios, 0.1 and 0.3, and B3 of every ratio up to 0.3: a run
    without one of them has not tested the sentence."""
    world = paper_b_world(documents)
    collected = world[world["aa_ratio"].isin(ratios)]
    measured = _measured_cleanly("paper_b", documents["B"], collected, f"aa_ratio={ratios}")
    assert claim not in measured


def _write() -> None:
    # A case to a line: the file stays small and a change shows case by case.
    documents = _documents()
    worlds = _worlds(documents)
    lines = [
        f"{json.dumps(_case_name(*case))}: {json.dumps(_claims_measured(documents, worlds, *case))}"
        for case in SUBGRIDS
    ]
    PINNED.write_text("{\n" + ",\n".join(lines) + "\n}\n")


if __name__ == "__main__":
    _write()
