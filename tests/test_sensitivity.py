"""Protocol ensembles: the priors over unpublished choices, the summary over drawn protocols,
and `snakemake sensitivity`."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest
from workflow_copy import ROOT, copy_workflow, run_snakemake

from jointbench.configuration.config import check_config, load_config
from jointbench.ensembles.members import MEMBER_COLUMNS
from jointbench.ensembles.sensitivity import (
    DEPENDENCE_MEASURE,
    PRIORS,
    SUMMARY_COLUMNS,
    depends_most_on,
    draw_seed,
    member_names,
    member_protocol,
    member_values,
    protocol_verdict,
    split_half_effects,
    summarise,
)
from jointbench.simulate import cmc, hinge, hinge_study, hip
from jointbench.simulate.prior import Choice, Prior, default_values, draw_values

CONFIG = load_config(ROOT / "config" / "config.yaml")


@pytest.mark.parametrize("study", sorted(PRIORS))
def test_draws_lie_within_the_bounds_and_are_fixed_by_their_seed(study):
    prior = PRIORS[study]
    draws = [draw_values(prior, seed) for seed in range(40)]
    for values in draws:
        for choice in prior.choices:
            assert choice.low <= values[choice.name] <= choice.high, choice.name
        assert prior.accept(values)
    assert draws[7] == draw_values(prior, 7)
    # Every choice is drawn: no two draws agree on any of them.
    for choice in prior.choices:
        assert len({values[choice.name] for values in draws}) == len(draws), choice.name


@pytest.mark.parametrize("study", sorted(PRIORS))
def test_every_protocol_a_prior_may_draw_passes_the_configs_check(study):
    """A drawn protocol runs inside a job, past the config's check: a value the check would
    refuse (a range of :mod:`jointbench.simulate.ranges` or a bound across fields narrower than
    the prior's) must never be drawn. At every bound of every choice and in draws."""
    prior = PRIORS[study]
    default = default_values(prior)
    members = [{**default, c.name: end} for c in prior.choices for end in (c.low, c.high)]
    members += [{c.name: c.low for c in prior.choices}, {c.name: c.high for c in prior.choices}]
    members += [draw_values(prior, seed) for seed in range(20)]
    for values in members:
        if not prior.accept(values):
            continue
        # Merged into the config's own protocol as a member's is (the overlay's route).
        overlay = {"studies": {study: {"protocol": prior.build(values)}}}
        settings = dict(CONFIG["studies"][study])
        settings["protocol"] = member_protocol(CONFIG, study, "at-bounds", overlay)
        check_config({**CONFIG, "studies": {**CONFIG["studies"], study: settings}})


def test_log_uniform_choices_fill_their_decades_evenly():
    choice = Choice("x", 10.0, 1000.0, 100.0, "a sentence", "a reason", log=True)
    rng = np.random.default_rng(0)
    below = np.mean([choice.draw(rng) < 100.0 for _ in range(4000)])
    assert below == pytest.approx(0.5, abs=0.03)


def test_hinge_draws_keep_their_markers_apart():
    for seed in range(40):
        overrides = hinge_study.PRIOR.build(draw_values(hinge_study.PRIOR, seed))
        for joint, spacing in (("knee", 30.0), ("mcp", 10.0)):
            markers = overrides[joint]["markers_mm"]
            gaps = [math.dist(a, b) for i, a in enumerate(markers) for b in markers[i + 1 :]]
            assert min(gaps) >= spacing


def test_a_choice_rejects_a_default_outside_its_bounds_and_a_prior_its_own_defaults():
    with pytest.raises(ValueError, match=r"default 5\.0 is outside"):
        Choice("turns", 1.0, 4.0, 5.0, "a sentence", "a reason")
    with pytest.raises(ValueError, match="log-uniform range needs low > 0"):
        Choice("turns", 0.0, 4.0, 2.0, "a sentence", "a reason", log=True)
    choice = Choice("turns", 1.0, 4.0, 2.0, "a sentence", "a reason")
    with pytest.raises(ValueError, match="rejects its own defaults"):
        Prior("toy", (choice,), build=dict, accept=lambda values: values["turns"] > 3)
    impossible = Prior("toy", (choice,), build=dict, accept=lambda values: values["turns"] != 9)
    assert draw_values(impossible, 1)["turns"] != 9


def test_the_default_protocol_is_a_member_of_each_prior():
    def built(study):
        return PRIORS[study].build(default_values(PRIORS[study]))

    drawn, default = cmc.CmcProtocol.from_config(built("cmc")), cmc.CmcProtocol()
    assert tuple(drawn.center_mm) == default.center_mm
    assert (drawn.spiral_turns, drawn.tilt_power) == (default.spiral_turns, default.tilt_power)
    for marker_set in default.directions:
        np.testing.assert_allclose(
            cmc.marker_positions(drawn, marker_set),
            cmc.marker_positions(default, marker_set),
            atol=1e-12,
        )
    joints = hinge_study.HingeStudyProtocol.from_config(built("hinge")).joints
    for name, joint in joints.items():
        np.testing.assert_allclose(joint.markers, hinge.HINGE_PROTOCOLS[name].markers, atol=1e-12)
    assert hip.HipProtocol.from_config(built("hip")) == hip.HipProtocol()


@pytest.mark.parametrize("study", sorted(PRIORS))
def test_the_default_member_runs_the_configs_own_protocol(study):
    own = CONFIG["studies"][study].get("protocol") or {}
    assert member_protocol(CONFIG, study, "default", None) == own
    assert member_values(CONFIG["base_seed"], study, "default") == default_values(PRIORS[study])


def test_a_draw_is_fixed_by_the_base_seed_the_study_and_its_number():
    base = CONFIG["base_seed"]
    assert member_values(base, "hip", "draw-3") == member_values(base, "hip", "draw-3")
    assert member_values(base, "hip", "draw-3") != member_values(base, "hip", "draw-4")
    assert member_values(base, "hip", "draw-3") != member_values(base + 1, "hip", "draw-3")
    assert draw_seed(base, "hip", 3) != draw_seed(base, "cmc", 3)
    # A drawn member changes the drawn fields and keeps the config's others.
    config = {
        **CONFIG,
        "studies": {
            **CONFIG["studies"],
            "hip": {**CONFIG["studies"]["hip"], "protocol": {"fps": 50}},
        },
    }
    protocol = member_protocol(config, "hip", "draw-3", None)
    assert protocol["fps"] == 50
    assert protocol["swing_deg"] == member_values(base, "hip", "draw-3")["swing_deg"]
    with pytest.raises(ValueError, match="neither 'default' nor 'draw-<k>'"):
        member_values(base, "hip", "draw-x")


def test_a_named_member_takes_its_overlays_protocol_and_needs_one():
    overlay = {"studies": {"hinge": {"protocol": {"knee": {"markers_mm": [[50, 25, -130]] * 3}}}}}
    protocol = member_protocol(CONFIG, "hinge", "anatomical-knee", overlay)
    assert protocol["knee"]["markers_mm"] == [[50, 25, -130]] * 3
    with pytest.raises(ValueError, match="sets no protocol of study 'cmc'"):
        member_protocol(CONFIG, "cmc", "anatomical-knee", overlay)


@pytest.mark.parametrize(
    ("reproduced_in", "draws", "verdict"),
    [(20, 20, "reproduced"), (10, 20, "protocol-dependent"), (0, 20, "not reproduced")],
)
def test_the_verdict_over_protocols_is_the_rule_over_seeds(reproduced_in, draws, verdict):
    assert protocol_verdict(reproduced_in, draws) == verdict


# Eight draws of two choices: the value reproduces exactly when ``a`` is in its upper half, and
# ``b`` splits the draws so that each of its halves holds two that reproduce.
VALUES = pd.DataFrame({"a": np.arange(8.0), "b": [0.0, 4.0, 1.0, 5.0, 2.0, 6.0, 3.0, 7.0]})


def test_split_half_effects_are_the_share_above_the_median_minus_below():
    reproduced = pd.Series(VALUES["a"] >= 4)
    effects = split_half_effects(reproduced, VALUES)
    assert effects.to_dict() == {"a": 1.0, "b": 0.0}
    assert depends_most_on(reproduced, VALUES) == ("a", 1.0)
    assert depends_most_on(~reproduced, VALUES) == ("a", -1.0)
    # Reproduced exactly when b is in its lower half: b, the sign saying which way.
    assert depends_most_on(pd.Series(VALUES["b"] < 4), VALUES) == ("b", -1.0)
    assert depends_most_on(pd.Series([True] * 8), VALUES) == ("", 0.0)
    # A choice drawn once (every value the median) cannot be split: no effect.
    constant = VALUES.assign(a=1.0)
    assert split_half_effects(reproduced, constant)["a"] == 0.0


def test_summary_over_draws_leaves_the_default_and_named_members_out_of_the_share():
    statuses = ["reproduced" if a >= 4 else "not reproduced" for a in VALUES["a"]]
    members = [f"draw-{k}" for k in range(1, 9)]
    rows = pd.DataFrame(
        {
            "member": [*members, "default", "anatomical-knee", "draw-9"],
            "study": "hinge",
            "paper": "B",
            "entry": "claim",
            "id": "B2",
            "status": [*statuses, "reproduced", "not reproduced", "not applicable"],
            "margin": [*[str(float(a) - 4) for a in VALUES["a"]], "1.5", "-2", ""],
            "reproduced": "",
        }
    )
    assert set(MEMBER_COLUMNS) - {"base_seed"} <= set(rows.columns)
    values = pd.concat(
        [
            VALUES.assign(member=members, study="hinge"),
            pd.DataFrame({"member": ["draw-9"], "study": "hinge", "a": 1.0, "b": 1.0}),
            pd.DataFrame({"member": ["draw-1"], "study": "hip", "c": 0.0}),
        ],
        ignore_index=True,
    )
    (row,) = summarise(rows, values, {"B2": "a claim"}).to_dict("records")
    assert list(row) == SUMMARY_COLUMNS
    assert (row["draws"], row["reproduced_in"], row["share"]) == (8, 4, 0.5)
    assert row["verdict"] == "protocol-dependent"
    assert (row["default"], row["default_margin"]) == ("reproduced", 1.5)
    # Margins of the draws: -4 … 3; six of the eight lie below the default's 1.5.
    assert row["draws_below_default"] == 0.75
    assert (row["depends_most_on"], row["difference"]) == ("a", 1.0)


def test_the_default_run_does_not_run_the_protocol_ensemble(tmp_path):
    workdir = copy_workflow(tmp_path)
    dry = run_snakemake(workdir, "--dry-run")
    assert dry.returncode == 0, dry.stderr[-4000:]
    assert "sensitivity" not in dry.stdout + dry.stderr


@pytest.mark.pipeline
def test_sensitivity_target_runs_the_protocol_ensemble(tmp_path):
    workdir = copy_workflow(tmp_path)
    reduced = ROOT / "tests" / "data" / "sensitivity.yaml"
    run = run_snakemake(workdir, "sensitivity", "--configfile", str(reduced))
    assert run.returncode == 0, run.stderr[-4000:]
    tables, figures = workdir / "results" / "tables", workdir / "results" / "figures"
    summary = pd.read_csv(tables / "sensitivity.csv")
    assert list(summary.columns) == SUMMARY_COLUMNS
    assert set(summary["paper"]) == {"A", "B", "C"}
    tested = summary[summary["draws"] > 0]
    assert not tested.empty and (tested["draws"] <= 2).all()
    named = pd.read_csv(tables / "sensitivity_named.csv").set_index("id")
    assert {"default", "anatomical-knee"} <= set(named.columns)
    assert {"B2", "B3"} <= set(named.index)
    prior = pd.read_csv(tables / "sensitivity_prior.csv")
    assert set(prior["study"]) == set(PRIORS)
    for name in ("paper_a_fig4", "paper_b_layouts", "paper_c_coverage"):
        assert (figures / f"sensitivity_{name}.png").stat().st_size > 0
    # Each member's timing, for the target's duration.
    assert (workdir / "results" / "benchmarks" / "sensitivity" / "hip" / "draw-1.tsv").exists()
    again = run_snakemake(workdir, "sensitivity", "--dry-run", "--configfile", str(reduced))
    assert "Nothing to be done" in again.stdout + again.stderr


def test_the_readme_states_the_measure_the_code_applies():
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert DEPENDENCE_MEASURE in readme


def test_members_are_the_default_the_draws_and_the_named_protocols_of_the_study():
    overlays = {"anatomical-knee": {"studies": {"hinge": {"protocol": {"knee": {}}}}}}
    assert member_names("hinge", 2, overlays) == [
        "default",
        "draw-1",
        "draw-2",
        "anatomical-knee",
    ]
    assert member_names("hip", 1, overlays) == ["default", "draw-1"]
    with pytest.raises(ValueError, match="takes the name of a default or drawn one"):
        member_names("hinge", 1, {"draw-2": overlays["anatomical-knee"]})


@pytest.mark.parametrize(
    ("tilt_power", "halfway_share"), [(1.0, 0.5), (2.0, 0.25), (0.5, 0.5**0.5)]
)
def test_the_circumduction_tilt_grows_as_the_trials_fraction_to_its_power(
    tilt_power, halfway_share
):
    rotations = cmc.spiral_rotations(40.0, 121, 2.0, tilt_power)
    # The tilt is the angle between the mean long axis z and where the rotation carries it.
    tilt_deg = np.degrees(np.arccos(np.clip(rotations[:, 2, 2], -1.0, 1.0)))
    assert tilt_deg[60] == pytest.approx(40.0 * halfway_share)
    assert (tilt_deg[0], tilt_deg[-1]) == pytest.approx((0.0, 40.0))
