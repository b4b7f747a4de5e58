"""Specifics live on what owns them: a study words its grid keys and names its title and its
truth diagnostics, a paper adds to the report's landing page, a method registers its colour.
A newcomer sets each of its own without editing the package."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from jointbench import papers, report
from jointbench.configuration import studies
from jointbench.estimators import CenterResult, registry
from jointbench.estimators.batching import ProgrammingError
from jointbench.figures import extended
from jointbench.figures.common import method_style, method_styles, study_title
from jointbench.papers import FrontPart, Paper
from jointbench.running import run
from jointbench.simulate import Diagnostic, GridValues, Study, Trials

CENTRE = [1.0, 2.0, 3.0]


@dataclass(frozen=True)
class _Protocol:
    @classmethod
    def from_config(cls, overrides=None):
        return cls()


def _simulate(condition, protocol, rngs):
    markers = np.stack([rng.normal(size=(20, 3, 3)) * 30 for rng in rngs])
    return Trials(segments={"moving": markers}, truth={"center": CENTRE})


def _study(**extra) -> Study:
    return Study(
        name="gh",
        kind="center",
        grid_keys=("rom_deg", "noise_mm"),
        seed_keys=("rom_deg", "noise_mm"),
        segments=("moving",),
        protocol_class=_Protocol,
        simulate=_simulate,
        frame_count=lambda condition, protocol: 20,
        **extra,
    )


@pytest.fixture
def newcomer(forget_registrations):
    """Registries that forget what a test registers."""

    def add(study: Study) -> Study:
        return studies.register_study(study)

    return add


def test_a_newcomer_study_without_wording_reads_by_unit_not_as_another_study(newcomer):
    newcomer(_study())
    # cmc's RoM is a ±tilt; the newcomer's rom_deg is not labelled as one.
    assert extended.condition_label("gh", (20, 0.5)) == "rom 20°, noise 0.5 mm"
    assert studies.get_study("gh").key_label("rom_deg") == "rom"
    assert study_title("gh") == "gh"


def test_a_newcomer_study_words_its_own_keys_and_title(newcomer):
    newcomer(
        _study(
            grid_spec={
                "rom_deg": GridValues(float, minimum=0, label="arc", text="{:g}° arc"),
                "noise_mm": GridValues(float, label="noise", text="σ {:g} mm", names={0: "clean"}),
            },
            title="glenohumeral centre",
        )
    )
    assert extended.condition_label("gh", (20, 0.5)) == "20° arc, σ 0.5 mm"
    assert extended.condition_label("gh", (20, 0)) == "20° arc, clean"
    assert studies.get_study("gh").key_label("noise_mm") == "noise"
    assert study_title("gh") == "glenohumeral centre"


def test_built_in_studies_word_their_keys():
    assert extended.condition_label("cmc", ("H", 5, 0.5)) == "H set, ±5°, 0.5 mm noise"
    assert extended.condition_label("hinge", ("knee", 30, 0.5)) == "knee, FE 30°, AA/FE 0.5"
    assert extended.condition_label("hinge", ("mcp", 30, 0.5)) == "index MCP, FE 30°, AA/FE 0.5"
    assert extended.condition_label("hip", (75,)) == "Nt = 75"
    assert study_title("cmc") == "thumb CMC" and study_title("unknown") == "unknown"


def _centroid(markers):
    return CenterResult(
        center=markers.reshape(-1, 3).mean(axis=0),
        converged=True,
        iterations=0,
        status="ok",
        method="centroid",
    )


def test_a_newcomer_method_draws_in_the_colour_it_registers(newcomer):
    registry.register("center", "mine", color="#123456", marker="*")(_centroid)
    assert method_style("mine") == {"color": "#123456", "marker": "*"}
    assert method_style("LS") == {"color": "#d95f02", "marker": "s"}


def test_a_newcomer_method_without_a_colour_never_takes_a_registered_one(newcomer):
    registry.register("center", "plain")(_centroid)
    registered = {style["color"] for style in registry.styles().values()}
    assert "plain" not in registry.styles()
    assert method_style("plain")["color"] not in registered
    styles = method_styles(["LS", "NM", "plain", "other", "third"])
    assert len({s["color"] for s in styles.values()}) == 5


def _spread(arguments, results, truth):
    (markers,) = arguments
    return [
        {} if result is None else {"spread_mm": float(np.ptp(data))}
        for data, result in zip(markers, results, strict=True)
    ]


def test_a_newcomer_study_runs_its_own_truth_diagnostic(newcomer):
    newcomer(_study(diagnostics={"LS": Diagnostic(("spread_mm",), _spread)}))
    trials = _simulate({}, None, [np.random.default_rng(k) for k in range(3)])
    condition = {"rom_deg": 20.0, "noise_mm": 0.5}
    table = run.estimate_table("gh", "LS", trials, condition).to_pandas()
    assert table["spread_mm"].notna().all() and "local_minimum" not in table
    other = run.estimate_table("gh", "NM", trials, condition).to_pandas()
    assert "spread_mm" not in other


def test_a_diagnostic_names_the_columns_it_records():
    with pytest.raises(ValueError, match=r"'gh': the diagnostics of LS must each be a Diagnostic"):
        _study(diagnostics={"LS": _spread})


def test_a_plain_function_diagnostic_is_told_what_to_write():
    with pytest.raises(ValueError, match=r"write Diagnostic\(columns, diagnose\)"):
        _study(diagnostics={"LS": _spread})


def test_a_diagnostic_s_columns_given_as_one_string_are_refused_naming_it():
    """``Diagnostic("spread_mm", f)`` would declare the columns s, p, r, ...: refused, saying
    how to write one column."""
    with pytest.raises(
        ValueError,
        match=r"'gh': the diagnostic of LS declares its columns as the string 'spread_mm'; "
        r"write them as a tuple of names: \('spread_mm',\)",
    ):
        _study(diagnostics={"LS": Diagnostic("spread_mm", _spread)})


def _spread_sd_in_the_first_row(arguments, results, truth):
    rows = _spread(arguments, results, truth)
    rows[0]["spread_sd_mm"] = 0.0
    return rows


def _overwriting(arguments, results, truth):
    return [{"status": "ok", "error_mm": 0.0} for _ in results]


class _Spreads:
    """A diagnostic that is a callable object, with no ``__name__``."""

    def __call__(self, arguments, results, truth):
        return _spread(arguments, results, truth)


# Diagnostics the estimate job stops at, with what its ProgrammingError says.
_MISTAKEN_DIAGNOSTICS = {
    # What a study records is what its diagnostics declare: a claim selecting spread_mm would
    # be refused as a column no study records, so the job writing it is stopped.
    "writes-an-undeclared-column": (
        Diagnostic(("spread",), _spread),
        r"^gh LS: its diagnostic _spread writes the columns spread_mm, which it does not "
        r"declare \(it declares spread\)",
    ),
    # A declared column is one a claim may select as recorded by the study: declared beside
    # spread_mm and never written, it would be absent from every row.
    "never-writes-a-declared-column": (
        Diagnostic(("spread_mm", "spread_sd_mm"), _spread),
        r"^gh LS: its diagnostic _spread declares the columns spread_sd_mm, which it does not "
        r"write in the row of trial 0",
    ),
    # A row the diagnostic writes holds every column it declares (NaN where it has no value):
    # one left out would read as not measured in that trial, and whether it is left out of
    # every row of a condition, or only of some, depends on the trials.
    "leaves-a-declared-column-out-of-some-rows": (
        Diagnostic(("spread_mm", "spread_sd_mm"), _spread_sd_in_the_first_row),
        r"^gh LS: its diagnostic _spread_sd_in_the_first_row declares the columns spread_sd_mm, "
        r"which it does not write in the row of trial 1 \(it writes spread_mm\)",
    ),
    # Its status or error_mm would replace the estimator's own in each row, silently.
    "declares-the-jobs-own-columns": (
        Diagnostic(("status", "error_mm"), _overwriting),
        r"^gh LS: its diagnostic _overwriting declares the columns status, error_mm, "
        r"which the estimate job writes itself",
    ),
    # A callable object has no __name__: it is named by its repr.
    "callable-object-writes-an-undeclared-column": (
        Diagnostic(("spread",), _Spreads()),
        r"writes the columns spread_mm, which it does not",
    ),
}


@pytest.mark.parametrize("mistake", _MISTAKEN_DIAGNOSTICS)
def test_a_mistaken_diagnostic_stops_the_estimate_job_naming_its_mistake(newcomer, mistake):
    """Study gh with the mistaken diagnostic for LS: its estimate job raises a
    ``ProgrammingError`` saying what is wrong."""
    diagnostic, message = _MISTAKEN_DIAGNOSTICS[mistake]
    newcomer(_study(diagnostics={"LS": diagnostic}))
    trials = _simulate({}, None, [np.random.default_rng(k) for k in range(3)])
    with pytest.raises(ProgrammingError, match=message):
        run.estimate_table("gh", "LS", trials, {"rom_deg": 20.0, "noise_mm": 0.5})


def test_the_cmc_study_owns_paper_a_local_minimum_diagnostic():
    cmc = studies.get_study("cmc")
    assert set(cmc.diagnostics) == {"IS"}
    assert all(not studies.get_study(s).diagnostics for s in ("hinge", "hip_sta"))


def test_the_hip_study_owns_paper_c_checks_of_gauss_markov():
    assert set(studies.get_study("hip").diagnostics) == {"gauss-markov"}


def test_a_newcomer_paper_adds_its_own_finding_and_table(newcomer):
    newcomer(_study())
    shown = pd.DataFrame({"method": ["LS"], "coverage": [0.9]})

    def front_page(tables):
        if "paper_g_coverage" not in tables:
            return FrontPart()
        return FrontPart("LS covers the truth in 90 % of trials.", (("Coverage", "cov", shown),))

    papers.register_paper(
        Paper(
            key="paper_g",
            letter="G",
            title="Paper G: glenohumeral centre",
            citation="Someone (2026)",
            study="gh",
            methods=("LS",),
            outputs=(),
            published=Path("unused.yaml"),
            measure=lambda inputs: {},
            front_page=front_page,
        )
    )
    lines = report.findings({"paper_g_coverage": shown})
    assert any("Paper G" in line and "LS covers the truth in 90 %" in line for line in lines)
    assert not any("Paper G" in line and "covers" in line for line in report.findings({}))
    assert f"of {len(papers.paper_names())} papers" in report.front_intro()
    assert "Someone (2026)" in report.front_intro()


def test_paper_c_adds_its_calibration_to_the_landing_page():
    calibration = pd.DataFrame(
        {
            "method": ["gauss-markov"] * 2,
            "n_frames": [75, 150],
            "trials": [200, 200],
            "inside_95": [0.95, 0.94],
            "status": ["calibrated", "calibrated"],
        }
    )
    part = papers.get_paper("paper_c").front_page({"paper_c_calibration": calibration})
    assert part.finding == "gauss-markov is calibrated at every Nt."
    ((heading, _, frame),) = part.sections
    assert heading.startswith("Calibration") and list(frame.columns)[1] == "Nt"
    assert papers.get_paper("paper_a").front_page is None
