"""A claim's recorded column is "not measured" only where its paper's study records it.

The columns a study's estimate and collect jobs write have one home,
:func:`~jointbench.resultfiles.schema.recorded_columns` (the estimates file's columns by kind,
the scores the benchmark computes, each diagnostic's declared columns). A claim that selects a
column no study of its paper records (a misspelt one) is mistaken: a ``RuntimeError`` naming
the claim. A column the study records but this run did not (a synthetic world, a reduced run,
a method that does not fit radii) still leaves the claim not measured, saying which.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from test_claims import A_SPEEDS, _timed, paper_a_world, paper_c_world

from jointbench.comparison.published import load_published
from jointbench.configuration.config import load_config
from jointbench.configuration.studies import get_study
from jointbench.papers import Inputs, Measured, paper_a, paper_c
from jointbench.papers.common import RECORDED_COLUMN, NotMeasured, with_columns
from jointbench.resultfiles.schema import recorded_columns
from jointbench.running import run
from jointbench.simulate.hip import EXACT_FRAME0_COLUMNS, POSE_FIT_COLUMNS

MODULES = {"A": paper_a, "C": paper_c}
CONFIG = Path(__file__).resolve().parents[1] / "config" / "config.yaml"


@pytest.fixture(scope="module")
def documents():
    return {letter: load_published(module.PAPER.published) for letter, module in MODULES.items()}


@pytest.fixture(scope="module")
def worlds():
    return {"A": _timed(paper_a_world(), A_SPEEDS), "C": paper_c_world(trials=5)}


def _measure(letter, documents, collected):
    inputs = Inputs(collected=collected, published=documents[letter], config={"studies": {}})
    return MODULES[letter].measure(inputs)


#: Where each paper's checks are given the collected results among their arguments.
COLLECTED_ARGUMENT = {"A": 0, "C": 2}


def _selecting_columns(letter, names):
    """A check of paper ``letter`` that selects the recorded columns ``names`` from the
    collected results."""

    def check(*data):
        collected = data[COLLECTED_ARGUMENT[letter]]
        return Measured(float(with_columns(collected, names, RECORDED_COLUMN).size), "")

    return check


#: Per case: the paper, the claim replaced, the columns it selects, and what the error names.
MISSPELT = {
    "paper A's error": ("A", "A13", ["eror_mm"], "recorded column 'eror_mm'"),
    "paper A's radius error": ("A", "A13", ["radius_eror_mm"], "'radius_eror_mm'"),
    "paper C's pose fit": ("C", "C5", ["pose_iterations_proximl"], "'pose_iterations_proximl'"),
}


@pytest.mark.parametrize("case", MISSPELT)
def test_a_misspelt_recorded_column_is_raised_naming_the_claim(
    documents, worlds, monkeypatch, case
):
    letter, claim, names, named = MISSPELT[case]
    monkeypatch.setitem(MODULES[letter]._CLAIMS, claim, _selecting_columns(letter, names))
    with pytest.raises(RuntimeError, match=rf"^claim {claim}: asks for ") as raised:
        _measure(letter, documents, worlds[letter])
    assert named in str(raised.value)
    assert "none of the columns its study records" in str(raised.value)
    assert isinstance(raised.value.__cause__, NotMeasured)


#: Per case: the paper, the columns the run leaves out, a claim that reads one of them, and
#: its reason. The synthetic worlds record no radii and no pose fits, as a run whose methods
#: fit none would not.
UNRECORDED = {
    "radii": ("A", (), "A13", "this run has no recorded column radius_error_mm"),
    "local minima": ("A", ("local_minimum",), "A7", "local minima not recorded in this run"),
    "times": ("A", ("seconds",), "A12", "this run has no recorded column seconds"),
    "pose fits": ("C", (), "C5", f"this run has no recorded column {POSE_FIT_COLUMNS[0]}"),
}


@pytest.mark.parametrize("case", UNRECORDED)
def test_a_recorded_column_this_run_lacks_is_not_measured_saying_which(documents, worlds, case):
    letter, dropped, claim, reason = UNRECORDED[case]
    measured = _measure(letter, documents, worlds[letter].drop(columns=list(dropped)))
    assert claim not in measured
    assert measured.not_measured[claim].startswith(reason)


def test_each_study_records_the_columns_its_papers_read():
    """What the claims select by name, each in its study's one list."""
    cmc = recorded_columns(get_study("cmc"))
    assert {"seconds", "error_mm", "radius_error_mm", "local_minimum", "f1_gap"} <= set(cmc)
    hip = recorded_columns(get_study("hip"))
    assert {*POSE_FIT_COLUMNS, *EXACT_FRAME0_COLUMNS.values(), "validation_index"} <= set(hip)
    # hip_sta also runs the one-segment centre methods, whose scores it records too.
    assert "radius_error_mm" in recorded_columns(get_study("hip_sta"))
    assert "error_deg" not in cmc and "local_minimum" not in hip


#: Per study, a condition and every method the config runs there: the estimate job's columns
#: of each (its kind's and, for IS and gauss-markov, its diagnostic's).
ESTIMATED = {
    "cmc": {"marker_set": "M", "rom_deg": 15, "noise_mm": 1.0},
    "hinge": {"protocol": "knee", "fe_rom_deg": 60, "aa_ratio": 0.3},
    "hip": {"n_frames": 16},
    "hip_sta": {"motion": "star_arc", "rom_deg": 20.0, "sta_mm": 10.0},
}


@pytest.mark.parametrize("study", ESTIMATED)
def test_the_estimate_job_writes_only_columns_its_study_records(study):
    config = load_config(CONFIG)
    condition = ESTIMATED[study]
    trials = run.simulate_condition(config, study, condition, range(2))
    recorded = set(recorded_columns(get_study(study)))
    for method in config["studies"][study]["estimators"]:
        table = run.estimate_table(study, method, trials, condition, warm_up=False)
        assert set(table.column_names) <= recorded, (method, set(table.column_names) - recorded)
