"""Config mistakes the schema cannot see stop the workflow before any job, naming the key and
the allowed values (issues: inputs that cannot lie; config checked completely before any job).

Estimator options and protocol fields are checked against the types and ranges their own
annotations declare (:mod:`jointbench.declared`)."""

from __future__ import annotations

import copy
import dataclasses
import inspect
import re
import shlex
from pathlib import Path

import numpy as np
import pytest
import yaml
from snakemake.utils import update_config
from workflow_copy import ROOT, copy_workflow, refused_dry_run, run_snakemake

from jointbench import declared, invocation
from jointbench.configuration import bounds
from jointbench.configuration import config as study_config
from jointbench.configuration.studies import get_study, study_names
from jointbench.estimators import registry
from jointbench.papers import get_paper, paper_names
from jointbench.simulate import cmc


@pytest.fixture(scope="module")
def config():
    return study_config.load_config(ROOT / "config" / "config.yaml")


def changed(config, study, path, value):
    """A deep copy of ``config`` with ``studies.<study>.<path...>`` set to ``value``."""
    new = copy.deepcopy(config)
    node = new["studies"][study]
    *parents, last = path
    for key in parents:
        node = node.setdefault(key, {})
    node[last] = value
    return new


def test_shipped_configs_pass(config):
    """The config, and over it each overlay shipped for a run: its variants, the benchmarks'
    grids and the tests' (a check tightened must not refuse one of them)."""
    study_config.check_config(config)
    overlays = [
        *ROOT.glob("config/variants/*.yaml"),
        *ROOT.glob("benchmarks/*.yaml"),
        *ROOT.glob("tests/data/*.yaml"),
    ]
    assert len(overlays) >= 10, overlays
    for path in overlays:
        merged = copy.deepcopy(config)
        # Merged as `--configfile` merges an overlay: key by key, at every depth.
        update_config(merged, yaml.safe_load(path.read_text()))
        study_config.check_config(merged)


BAD = [
    # (study, path, value, words the message must contain)
    ("cmc", ("grid", "noise"), [2.0], ["studies.cmc.grid.noise", "unknown grid key", "noise_mm"]),
    ("cmc", ("grid", "noise_mm"), [-1], ["studies.cmc.grid.noise_mm", "-1", "a number >= 0"]),
    # Its sign kept, -0.0 is below 0 to numpy's normal draws ("scale < 0").
    ("cmc", ("grid", "noise_mm"), [-0.0], ["studies.cmc.grid.noise_mm", "-0.0", "a number >= 0"]),
    ("cmc", ("grid", "rom_deg"), ["five"], ["studies.cmc.grid.rom_deg", "'five'", "> 0"]),
    ("cmc", ("grid", "rom_deg"), [0], ["studies.cmc.grid.rom_deg", "a number > 0 and <= 180"]),
    ("cmc", ("grid", "rom_deg"), [float("nan")], ["studies.cmc.grid.rom_deg", "nan"]),
    ("cmc", ("grid", "rom_deg"), [5, 5], ["studies.cmc.grid.rom_deg", "5 listed more than once"]),
    ("cmc", ("grid", "marker_set"), ["X"], ["studies.cmc.grid.marker_set", "one of M, H"]),
    ("hip", ("grid", "n_frames"), [-10], ["studies.hip.grid.n_frames", "an integer >= 1"]),
    ("hip", ("grid", "n_frames"), [4.5], ["studies.hip.grid.n_frames", "<= 1200"]),
    ("hip", ("grid", "n_frames"), [2400], ["studies.hip.grid.n_frames", "<= 1200"]),
    ("hinge", ("grid", "protocol"), ["elbow"], ["studies.hinge.grid.protocol", "knee, mcp"]),
    ("hinge", ("grid", "aa_ratio"), [True], ["studies.hinge.grid.aa_ratio", "True"]),
    ("cmc", ("trials",), 10**9, ["studies.cmc.trials", "1000000000", "[1, 10000]"]),
    ("cmc", ("estimators",), ["NM", "XX"], ["studies.cmc.estimators", "'XX'", "LS, NM, BC"]),
    ("cmc", ("options",), {"NM": {"tolerance": 1e-3}}, ["options.NM.tolerance", "none"]),
    (
        "cmc",
        ("options",),
        {"BC": {"tolerance": 1e-3}},
        ["options.BC.tolerance", "max_iterations, tol_x, tol_fun"],
    ),
    ("cmc", ("options",), {"XX": {}}, ["studies.cmc.options.XX", "NM, LS, BC"]),
    (
        "cmc",
        ("options",),
        {"BC": {"max_iterations": "many"}},
        ["studies.cmc.options.BC.max_iterations: must be an integer >= 1, got 'many'"],
    ),
    (
        "cmc",
        ("options",),
        {"BC": {"tol_x": True}},
        ["studies.cmc.options.BC.tol_x: must be a number > 0, got True"],
    ),
    ("cmc", ("external_estimators",), ["NM"], ["external_estimators", "'NM'", "built-in"]),
    ("cmc", ("protocol",), {"spiral": 2}, ["studies.cmc.protocol", "spiral"]),
    # Options whose range, or whose type behind a None default, only the annotation declares.
    (
        "cmc",
        ("options",),
        {"BC": {"max_iterations": 0}},
        ["studies.cmc.options.BC.max_iterations: must be an integer >= 1, got 0"],
    ),
    (
        "cmc",
        ("options",),
        {"BC": {"tol_x": -1}},
        ["studies.cmc.options.BC.tol_x: must be a number > 0, got -1"],
    ),
    (
        "cmc",
        ("options",),
        {"IS": {"start": "abc"}},
        ["studies.cmc.options.IS.start: must be 3 numbers or null, got 'abc'"],
    ),
    (
        "cmc",
        ("options",),
        {"MA": {"start": [1, 2, "x"]}},
        ["studies.cmc.options.MA.start[2]: must be a number, got 'x'"],
    ),
    (
        "hinge",
        ("options",),
        {"planar": {"max_iter": "x"}},
        ["studies.hinge.options.planar.max_iter: must be an integer >= 1 or null, got 'x'"],
    ),
    (
        "hinge",
        ("options",),
        {"radial": {"parameterisation": "polar"}},
        ["studies.hinge.options.radial.parameterisation: must be one of angles, vector"],
    ),
    (
        "hip",
        ("options",),
        {"SCoRE": {"noise_mm": "abc"}},
        ["studies.hip.options.SCoRE.noise_mm: must be a number >= 0 or null, got 'abc'"],
    ),
    # Protocol fields.
    (
        "cmc",
        ("protocol",),
        {"spiral_turns": "abc"},
        ["studies.cmc.protocol.spiral_turns: must be a number >= 0, got 'abc'"],
    ),
    (
        "cmc",
        ("protocol",),
        {"n_frames": 0},
        ["studies.cmc.protocol.n_frames: must be an integer >= 1, got 0"],
    ),
    (
        "cmc",
        ("protocol",),
        {"center_mm": [0, 0]},
        [
            "studies.cmc.protocol.center_mm: must be 3 numbers (each >= -100000 and "
            "<= 100000), got [0, 0]"
        ],
    ),
    (
        "cmc",
        ("protocol",),
        {"directions": {"X": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}},
        ["studies.cmc.protocol.distances_mm: has no marker set 'X'"],
    ),
    (
        "cmc",
        ("protocol",),
        {"distances_mm": {"M": [10.0, 20.0]}},
        ["studies.cmc.protocol.distances_mm.M: gives 2 distances for the 3 directions"],
    ),
    (
        "hinge",
        ("protocol",),
        {"all": {"n_frames": 2.5}},
        ["studies.hinge.protocol.all.n_frames: must be an integer >= 4, got 2.5"],
    ),
    (
        "hinge",
        ("protocol",),
        {"knee": {"markers_mm": [[1, 2]]}},
        [
            "studies.hinge.protocol.knee.markers_mm[0]: must be 3 numbers (each >= -2000 and "
            "<= 2000), got [1, 2]"
        ],
    ),
    (
        "hip",
        ("protocol",),
        {"fps": 0},
        ["studies.hip.protocol.fps: must be a number > 0 and <= 100000, got 0"],
    ),
    # Noise beyond the geometry: the farthest marker's distance from the joint centre.
    ("cmc", ("grid", "noise_mm"), [1e200], ["studies.cmc.grid.noise_mm", "<= 69.1"]),
    (
        "hinge",
        ("protocol",),
        {"all": {"noise_sd_mm": 1e200}},
        ["studies.hinge.protocol.all.noise_sd_mm, knee.markers_mm: must be <= 176.458 mm"],
    ),
    (
        "hinge",
        ("protocol",),
        {"knee": {"noise_sd_mm": 1e200}},
        ["studies.hinge.protocol.knee.noise_sd_mm, markers_mm: must be <= 176.458 mm"],
    ),
    # A joint's bound broken by a field written under ``all`` is named there, for that joint.
    (
        "hinge",
        ("protocol",),
        {"all": {"n_frames": 120}},
        ["studies.hinge.protocol.all.n_frames: motion 'grid' needs a square", "(joint 'knee')"],
    ),
    (
        "hinge",
        ("protocol",),
        {"all": {"markers_mm": [[0.0, 0.0, 0.001]] * 3}},
        ["studies.hinge.protocol.all.markers_mm[0]: [0.0, 0.0, 0.001] lies 0.001 mm"],
    ),
    (
        "hinge",
        ("protocol",),
        {"all": {"noise_sd_mm": 100.0}, "mcp": {"markers_mm": [[0, 0, -40]] * 3}},
        ["studies.hinge.protocol.all.noise_sd_mm, mcp.markers_mm: must be <= 40 mm"],
    ),
    (
        "hip",
        ("protocol",),
        {"noise_mm": 1e200},
        ["studies.hip.protocol.noise_mm, proximal_markers_mm, distal_markers_mm: must be <="],
    ),
    # Conditions no listed estimator can fit.
    (
        "hip",
        ("grid", "n_frames"),
        [1],
        ["studies.hip.grid.n_frames: condition n_frames-1 has trials of 1 frame(s)", "SCoRE 3"],
    ),
    (
        "cmc",
        ("protocol",),
        {"n_frames": 2},
        ["studies.cmc.protocol.n_frames: condition marker_set-M__rom_deg-5__noise_mm-0.5", "NM 4"],
    ),
    # A study that runs nothing.
    ("hip", ("estimators",), [], ["studies.hip.estimators: empty, and no external_estimators"]),
    # Bounds from what the papers simulate and from geometry (jointbench.configuration.bounds).
    ("hinge", ("grid", "aa_ratio"), [0.3, 50], ["studies.hinge.grid.aa_ratio: 50", "< 1"]),
    ("hinge", ("grid", "aa_ratio"), [1.0], ["studies.hinge.grid.aa_ratio: 1.0", "< 1"]),
    (
        "hip",
        ("protocol",),
        {"proximal_markers_mm": [[0, 0, 500], [50, 0, 500], [100, 0, 500]]},
        ["studies.hip.protocol.proximal_markers_mm", "collinear (on one line)"],
    ),
    (
        "hip",
        ("protocol",),
        {"distal_markers_mm": [[80, 20, -500], [80, 20, -500], [-30, -90, -530]]},
        ["studies.hip.protocol.distal_markers_mm", "markers 1 and 2 coincide"],
    ),
    (
        "hip",
        ("protocol",),
        {"proximal_markers_mm": [[0, 0, 500], [100, 0, 500], [50, 1, 500]]},
        ["studies.hip.protocol.proximal_markers_mm", "nearly collinear", "noise_mm (1.7 mm)"],
    ),
    (
        "hip",
        ("protocol",),
        {"swing_deg": 0, "cross_swing_deg": 0, "twist_deg": 0},
        ["studies.hip.protocol", "swing_deg, cross_swing_deg, twist_deg", "at least 2 of the axes"],
    ),
    (
        "hip",
        ("protocol",),
        {"cross_swing_deg": 0, "twist_deg": 0},
        ["studies.hip.protocol", "swing_deg, cross_swing_deg, twist_deg", "only swing_deg"],
    ),
    (
        "hip",
        ("protocol",),
        {"swing_hz": -0.75},
        ["studies.hip.protocol.swing_hz, fps: -0.75", "> 0"],
    ),
    ("hip", ("protocol",), {"twist_hz": 0}, ["studies.hip.protocol.twist_hz, fps: 0", "> 0"]),
    (
        "hip",
        ("protocol",),
        {"cross_swing_hz": 45.0},
        ["studies.hip.protocol.cross_swing_hz, fps: 45.0", "< 30 Hz", "half the frame rate"],
    ),
    # A rotation configured yet not seen beside the noise does not count as moving.
    (
        "hip",
        ("protocol",),
        {"cross_swing_deg": 1e-9, "twist_deg": 0},
        [
            "studies.hip.protocol.swing_deg, cross_swing_deg, twist_deg",
            "only swing_deg moving",
            "cross_swing_deg 9.25e-09 mm",
            "noise_mm (1.7 mm)",
        ],
    ),
    # Without noise, a rotation turning no marker by HIP_RESOLUTION_MM (0.01 mm) is not seen.
    (
        "hip",
        ("protocol",),
        {"noise_mm": 0.0, "cross_swing_deg": 5e-4, "twist_deg": 0},
        [
            "studies.hip.protocol.swing_deg, cross_swing_deg, twist_deg",
            "only swing_deg moving",
            "cross_swing_deg 0.00",
            "HIP_RESOLUTION_MM (0.01 mm)",
        ],
    ),
    (
        "hip",
        ("protocol",),
        {"cross_swing_rise_s": 1e9, "twist_deg": 0},
        [
            "studies.hip.protocol.swing_deg, cross_swing_deg, twist_deg",
            "only swing_deg moving",
            "cross_swing_rise_s",
        ],
    ),
    (
        "hip",
        ("protocol",),
        {"swing_hz": 1e-9, "twist_deg": 0},
        [
            "studies.hip.protocol.swing_deg, cross_swing_deg, twist_deg",
            "only cross_swing_deg",
            "swing_deg 2.59e-12 mm",
        ],
    ),
    # The skin-marker hip study's clusters and sway frequencies, bounded as the rig's.
    (
        "hip_sta",
        ("protocol",),
        {"thigh_markers_mm": [[40, -95, -150], [40, -95, -250], [40, -95, -350]]},
        ["studies.hip_sta.protocol.thigh_markers_mm", "collinear (on one line)"],
    ),
    (
        "hip_sta",
        ("protocol",),
        {"pelvis_markers_mm": [[52.8, -33.6, 72], [52.8, -33.6, 72], [-107.2, 41.4, 85]]},
        ["studies.hip_sta.protocol.pelvis_markers_mm", "markers 1 and 2 coincide"],
    ),
    (
        "hip_sta",
        ("protocol",),
        {"thigh_markers_mm": [[0, -90, -150], [0, -90, -350], [1, -90, -250]]},
        ["studies.hip_sta.protocol.thigh_markers_mm", "nearly collinear", "noise_mm (1.7 mm)"],
    ),
    (
        "hip_sta",
        ("protocol",),
        {"pelvis_sway_hz": [0.13, 40.0, 0.17]},
        ["studies.hip_sta.protocol.pelvis_sway_hz, fps: 40.0", "< 25 Hz", "half the frame rate"],
    ),
    # A hip moved about one axis only: its centre lies anywhere on that axis. At 1e-300
    # circumduction turns the thigh swung in one plane, and the centre methods answered 17 to
    # 70 mm off, each with status ok.
    (
        "hip_sta",
        ("protocol",),
        {"circumduction_turns": 1e-300},
        ["studies.hip_sta.protocol.circumduction_turns, noise_mm: ", "circumduction at rom_deg 20"],
    ),
    ("hip_sta", ("grid", "rom_deg"), [1e-6], ["studies.hip_sta.grid.rom_deg: ", "about 0 axis"]),
    (
        "hip_sta",
        ("protocol",),
        {"star_azimuths_deg": [0.0], "arc_turns": 1e-12},
        ["studies.hip_sta.protocol.star_azimuths_deg, arc_turns, noise_mm: ", "about 1 axis"],
    ),
    (
        "hip_sta",
        ("protocol",),
        {"pelvis_sway_hz": [0.0, 0.21, 0.17]},
        ["studies.hip_sta.protocol.pelvis_sway_hz, fps: 0.0", "> 0"],
    ),
    # Periodic motions faster than their frames show, and an artefact beyond the segment.
    (
        "cmc",
        ("protocol",),
        {"spiral_turns": 1e13},
        ["studies.cmc.protocol.spiral_turns, n_frames: 10000000000000.0 spiral turns"],
    ),
    # A spiral that circles out only in the trial's last frames (paper A: "circling out").
    (
        "cmc",
        ("protocol",),
        {"tilt_power": 82},
        ["studies.cmc.protocol.tilt_power: 82", "by the middle of the trial"],
    ),
    (
        "hinge",
        ("protocol",),
        {"all": {"motion": "lissajous", "fe_cycles": 100}},
        ["studies.hinge.protocol.all.fe_cycles, knee.n_frames: 100 knee lissajous cycles over"],
    ),
    # A wave that never reaches an end of the excursion its condition names: at 1e-300 FE
    # cycles the knee does not flex, and every axis method found the AA axis, status "ok".
    (
        "hinge",
        ("protocol",),
        {"all": {"motion": "lissajous", "fe_cycles": 1e-300}},
        ["studies.hinge.protocol.all.fe_cycles: 1e-300 knee lissajous FE cycles", "both ends"],
    ),
    (
        "hinge",
        ("protocol",),
        {"all": {"motion": "superimposed", "aa_cycles": 0.25}},
        ["studies.hinge.protocol.all.aa_cycles, knee.aa_phase_deg: 0.25 knee superimposed AA"],
    ),
    (
        "hinge",
        ("protocol",),
        {"all": {"motion": "lissajous", "fe_cycles": 30}, "knee": {"n_frames": 50}},
        ["studies.hinge.protocol.all.fe_cycles, knee.n_frames: 30 knee lissajous cycles over 50"],
    ),
    (
        "hip",
        ("protocol",),
        {"hand_rotation_hz": [0.17, 0.29, 1e13]},
        ["studies.hip.protocol.hand_rotation_hz, fps: 10000000000000.0", "< 30 Hz"],
    ),
    # No frames left for the arc: its phase would be 0 / 0 (NaN markers).
    (
        "hip_sta",
        ("protocol",),
        {"star_fraction": 1.0},
        [
            "studies.hip_sta.protocol.arc_turns, star_fraction, duration_s, fps: 1.0 arc turns",
            # The values of the fields named, each the count depends on.
            "over 0 frames (1 - star_fraction 1.0 of the 600 from duration_s 12.0, fps 50.0)",
        ],
    ),
    (
        "hip_sta",
        ("protocol",),
        {"circumduction_turns": 300, "duration_s": 11.0},
        [
            "studies.hip_sta.protocol.circumduction_turns, duration_s, fps: 300 circumduction",
            "over 550 frames (from duration_s 11.0, fps 50.0)",
        ],
    ),
    (
        "hip_sta",
        ("protocol",),
        {"star_azimuths_deg": [0.0, 45.0, 90.0, 135.0], "duration_s": 0.2},
        [
            "studies.hip_sta.protocol.star_azimuths_deg, star_fraction, duration_s, fps: 4 star",
            "over 7 frames (star_fraction 0.7 of the 10 from duration_s 0.2, fps 50.0)",
        ],
    ),
    (
        "hip_sta",
        ("protocol",),
        {"sta_reference_deg": 1e-300},
        ["studies.hip_sta.protocol.sta_reference_deg: 1e-300", "further than the farthest"],
    ),
    # A study of two kinds: names and options of both are checked, each against its own kind.
    (
        "hip_sta",
        ("estimators",),
        ["LS", "planar"],
        ["studies.hip_sta.estimators", "joint_center or center estimator 'planar'", "NM", "SCoRE"],
    ),
    (
        "hip_sta",
        ("options",),
        {"BC": {"tol_x": -1.0}},
        ["studies.hip_sta.options.BC.tol_x", "-1"],
    ),
]


@pytest.mark.parametrize(("study", "path", "value", "words"), BAD, ids=lambda v: str(v))
def test_mistake_names_key_and_allowed_values(config, study, path, value, words):
    with pytest.raises(ValueError) as error:
        study_config.check_config(changed(config, study, path, value))
    for word in words:
        assert word in str(error.value), str(error.value)


@pytest.mark.parametrize(
    "waves",
    [
        {"fe_cycles": 0.5, "aa_cycles": 0.75, "aa_phase_deg": 90.0},
        {"fe_cycles": 0.5, "aa_cycles": 1.0},
        {"fe_cycles": 3.0, "aa_cycles": 0.5, "aa_phase_deg": -90.0},
    ],
)
def test_a_hinge_wave_reaching_both_ends_of_its_excursion_passes(config, waves):
    """Half an FE cycle reaches full flexion from full extension; an AA wave reaches both its
    ends within a cycle, or within half of one from an end."""
    hinge = {**config["studies"]["hinge"], "protocol": {"all": {"motion": "lissajous", **waves}}}
    study_config.check_config({**config, "studies": {**config["studies"], "hinge": hinge}})


# A protocol field written in the config that the chosen motion does not read changes no data:
# (study, grid changes, protocol overrides, words the refusal has).
_UNREAD = [
    (
        "hinge",
        {},
        {"all": {"fe_cycles": 3}},
        ["config: studies.hinge.protocol.all.fe_cycles: 3 is not read by motion 'grid'"],
    ),
    (
        "hinge",
        {},
        {"knee": {"aa_phase_deg": 30.0}},
        ["config: studies.hinge.protocol.knee.aa_phase_deg: 30.0 ", "motion 'grid' (joint 'knee')"],
    ),
    (
        "hinge",
        {},
        {"all": {"motion": "superimposed", "fe_cycles": 2.0}},
        ["config: studies.hinge.protocol.all.fe_cycles: ", "motion 'superimposed'", "lissajous"],
    ),
    (
        "hinge",
        {},
        {"all": {"motion": "sequential", "aa_cycles": 2.0}},
        ["config: studies.hinge.protocol.all.aa_cycles: ", "motion 'sequential'"],
    ),
    # Written under all, it is refused when no joint the grid runs that takes it from all
    # reads it: set again by every such joint, or read only by a joint the grid does not run.
    (
        "hinge",
        {},
        {
            "all": {"motion": "lissajous", "fe_cycles": 2.0},
            "knee": {"fe_cycles": 3.0},
            "mcp": {"fe_cycles": 4.0},
        },
        [
            "config: studies.hinge.protocol.all.fe_cycles: 2.0 ",
            "set again by every joint",
            "knee.fe_cycles, mcp.fe_cycles",
        ],
    ),
    (
        "hinge",
        {},
        {"all": {"aa_phase_deg": 10.0}, "knee": {"motion": "lissajous", "aa_phase_deg": 20.0}},
        ["config: studies.hinge.protocol.all.aa_phase_deg: 10.0 ", "motion 'grid' (joint 'mcp')"],
    ),
    # Any field under all: one that every joint the grid runs sets again changes no data.
    (
        "hinge",
        {},
        {"all": {"noise_sd_mm": 0.5}, "knee": {"noise_sd_mm": 1.0}, "mcp": {"noise_sd_mm": 2.0}},
        [
            "config: studies.hinge.protocol.all.noise_sd_mm: 0.5 ",
            "knee.noise_sd_mm, mcp.noise_sd_mm",
        ],
    ),
    (
        "hip_sta",
        {"motion": ["star_arc"]},
        {"circumduction_turns": 4.0},
        ["config: studies.hip_sta.protocol.circumduction_turns: 4.0 ", "grid.motion star_arc"],
    ),
    (
        "hip_sta",
        {"motion": ["circumduction"]},
        {"star_fraction": 0.5},
        ["config: studies.hip_sta.protocol.star_fraction: ", "grid.motion circumduction"],
    ),
    (
        "hip_sta",
        {"motion": ["circumduction"]},
        {"arc_turns": 2.0},
        ["config: studies.hip_sta.protocol.arc_turns: ", "grid.motion circumduction"],
    ),
]


def _with_grid(config, study, grid, overrides):
    new = changed(config, study, ("protocol",), overrides)
    new["studies"][study]["grid"].update(grid)
    return new


@pytest.mark.parametrize(
    ("study", "grid", "overrides"),
    [
        ("hinge", {}, {"knee": {"motion": "lissajous", "fe_cycles": 2.0}}),
        ("hinge", {}, {"all": {"motion": "superimposed", "aa_cycles": 3.0}}),
        ("hinge", {}, {"all": {"motion": "lissajous", "aa_phase_deg": 90.0}}),
        ("hinge", {}, {"all": {"motion": "lissajous", "fe_cycles": 2.0}}),
        # Under all, a field changes data where one joint the grid runs reads it from there.
        ("hinge", {}, {"all": {"fe_cycles": 2.0}, "knee": {"motion": "lissajous"}}),
        (
            "hinge",
            {},
            {"all": {"motion": "lissajous", "fe_cycles": 2.0}, "mcp": {"motion": "superimposed"}},
        ),
        (
            "hinge",
            {},
            {"all": {"motion": "lissajous", "fe_cycles": 2.0}, "knee": {"fe_cycles": 3.0}},
        ),
        ("hip_sta", {}, {"circumduction_turns": 2.0, "arc_turns": 2.0}),
        ("hip_sta", {"motion": ["star_arc"]}, {"star_fraction": 0.5, "arc_turns": 2.0}),
        ("hip_sta", {"motion": ["circumduction"]}, {"circumduction_turns": 2.0}),
    ],
    ids=str,
)
def test_a_field_the_chosen_motion_reads_passes(config, study, grid, overrides):
    study_config.check_config(_with_grid(config, study, grid, overrides))


# A field that shapes the trials only through a grid amplitude, written under a grid whose
# every value of that amplitude is 0, changes no data: (study, grid changes, protocol
# overrides, words the refusal has).
_UNREAD_WITHOUT_AMPLITUDE = [
    (
        "hinge",
        {"aa_ratio": [0.0]},
        {"all": {"motion": "lissajous", "aa_cycles": 3.0}},
        [
            "config: studies.hinge.protocol.all.aa_cycles: 3.0 is not read",
            "every aa_ratio of the grid is 0 (grid.aa_ratio [0.0])",
        ],
    ),
    (
        "hinge",
        {"aa_ratio": [0.0]},
        {"all": {"motion": "superimposed"}, "mcp": {"aa_phase_deg": 30.0}},
        ["config: studies.hinge.protocol.mcp.aa_phase_deg: 30.0 ", "every aa_ratio"],
    ),
    (
        "hinge",
        {"aa_ratio": [0.0]},
        {"knee": {"rotation_order": "aa_fe"}},
        ["config: studies.hinge.protocol.knee.rotation_order: 'aa_fe' ", "every aa_ratio"],
    ),
    # Under all too where one joint takes it from there: no joint reads it from anywhere.
    (
        "hinge",
        {"aa_ratio": [0.0]},
        {"all": {"motion": "lissajous", "aa_phase_deg": 10.0}, "knee": {"aa_phase_deg": 20.0}},
        ["config: studies.hinge.protocol.knee.aa_phase_deg: 20.0 ", "every aa_ratio"],
    ),
    (
        "hip_sta",
        {"sta_mm": [0.0]},
        {"sta_rigid_share": 0.5},
        [
            "config: studies.hip_sta.protocol.sta_rigid_share: 0.5 is not read",
            "every sta_mm of the grid is 0 (grid.sta_mm [0.0])",
        ],
    ),
    (
        "hip_sta",
        {"sta_mm": [0.0]},
        {"pelvis_sta_ratio": 0.3},
        ["config: studies.hip_sta.protocol.pelvis_sta_ratio: 0.3 ", "every sta_mm"],
    ),
    (
        "hip_sta",
        {"sta_mm": [0.0], "motion": ["circumduction"]},
        {"sta_reference_deg": 20.0},
        ["config: studies.hip_sta.protocol.sta_reference_deg: 20.0 ", "every sta_mm"],
    ),
]


@pytest.mark.parametrize(
    ("study", "grid", "overrides", "words"), _UNREAD + _UNREAD_WITHOUT_AMPLITUDE, ids=str
)
def test_a_field_no_trial_reads_is_refused_naming_it(config, study, grid, overrides, words):
    """By the motions the grid runs, or through an amplitude the grid sets to 0."""
    with pytest.raises(ValueError) as error:
        study_config.check_config(_with_grid(config, study, grid, overrides))
    message = str(error.value)
    assert message.startswith(words[0]), message
    for word in words[1:]:
        assert word in message, message


@pytest.mark.parametrize(
    ("study", "grid", "overrides"),
    [
        # One value above 0 of the amplitude, and the field is read.
        ("hinge", {"aa_ratio": [0.0, 0.1]}, {"all": {"motion": "lissajous", "aa_cycles": 3.0}}),
        ("hinge", {"aa_ratio": [0.0, 0.3]}, {"knee": {"rotation_order": "aa_fe"}}),
        ("hip_sta", {"sta_mm": [0.0, 10.0]}, {"sta_rigid_share": 0.5, "pelvis_sta_ratio": 0.3}),
        ("hip_sta", {"sta_mm": [0.0, 10.0]}, {"sta_reference_deg": 20.0}),
        # A joint the grid does not run: its whole entry is unread, and not refused.
        (
            "hinge",
            {"aa_ratio": [0.0], "protocol": ["mcp"]},
            {"knee": {"motion": "lissajous", "aa_cycles": 3.0}},
        ),
        # Without the amplitude, the fields it does not touch are read as before.
        ("hinge", {"aa_ratio": [0.0]}, {"all": {"motion": "lissajous", "fe_cycles": 2.0}}),
        ("hip_sta", {"sta_mm": [0.0]}, {"noise_mm": 1.0, "arc_turns": 2.0}),
    ],
    ids=str,
)
def test_a_field_read_through_an_amplitude_the_grid_sets_above_0_passes(
    config, study, grid, overrides
):
    study_config.check_config(_with_grid(config, study, grid, overrides))


@pytest.mark.parametrize("motion", ["lissajous", "superimposed"])
def test_an_aa_wave_no_trial_runs_is_not_held_to_its_frames(config, motion):
    """Where every aa_ratio of the grid is 0 no trial runs the AA wave: at 4 frames its default
    2 cycles were refused as too fast for them, naming ``aa_cycles`` as the fix, while the
    check refuses any ``aa_cycles`` written there as unread. The FE wave, which every trial
    runs, is still held to the frames, and so is the AA wave once a condition runs it."""
    short = {"motion": motion, "n_frames": 4}

    def check(ratios, **fields):
        overrides = {"all": {**short, **fields}}
        study_config.check_config(_with_grid(config, "hinge", {"aa_ratio": ratios}, overrides))

    check([0.0])
    with pytest.raises(ValueError, match=r"all\.aa_cycles: 1\.0 is not read"):
        check([0.0], aa_cycles=1.0)
    if motion == "lissajous":
        with pytest.raises(ValueError, match=r"all\.fe_cycles, n_frames: 2\.0 knee lissajous"):
            check([0.0], fe_cycles=2.0)
    with pytest.raises(ValueError, match=r"knee\.aa_cycles, all\.n_frames: 2\.0 knee"):
        check([0.0, 0.1])


def _tilt_at_the_middle(tilt_power: float, frame: int = 60) -> float:
    """The share of its RoM the thumb's simulated tilt reaches at the middle frame (of 121,
    whose middle is half-way through the trial), or at ``frame``."""
    rotations = cmc.spiral_rotations(40.0, 121, 2.0, tilt_power)
    # The tilt: the angle between the mean long axis z and where the rotation carries it.
    return float(np.degrees(np.arccos(np.clip(rotations[frame, 2, 2], -1.0, 1.0))) / 40.0)


@pytest.mark.parametrize("tilt_power", [82.0, 1e300, "just above"])
def test_a_tilt_that_leaves_the_thumb_still_past_the_middle_is_refused(config, tilt_power):
    """At tilt_power 82 the thumb barely leaves its mean position before the trial's last
    frames: it does not circle out over the recording (paper A), whatever RoM labels it."""
    if tilt_power == "just above":
        tilt_power = bounds.CMC_LATEST_TILT_POWER * (1 + 1e-9)
    assert _tilt_at_the_middle(tilt_power) < bounds.CMC_TILT_SHARE_BY_MIDDLE
    with pytest.raises(ValueError) as error:
        study_config.check_config(changed(config, "cmc", ("protocol",), {"tilt_power": tilt_power}))
    message = str(error.value)
    assert message.startswith(f"config: studies.cmc.protocol.tilt_power: {tilt_power!r}"), message
    assert "middle" in message and "circling out" in message, message


@pytest.mark.parametrize("tilt_power", [0.5, 1.0, 2.0, "the latest"])
def test_a_tilt_reaching_its_share_of_the_rom_by_the_middle_passes(config, tilt_power):
    if tilt_power == "the latest":
        tilt_power = bounds.CMC_LATEST_TILT_POWER * (1 - 1e-9)
    assert _tilt_at_the_middle(tilt_power) >= bounds.CMC_TILT_SHARE_BY_MIDDLE
    study_config.check_config(changed(config, "cmc", ("protocol",), {"tilt_power": tilt_power}))


@pytest.mark.parametrize("tilt_power", [3.322, 3.3219281, 82.0])
def test_a_refused_tilt_states_a_share_below_its_bound_and_a_largest_tilt_power_that_passes(
    config, tilt_power
):
    """Just past the bound, a share rounded to a few digits reads as the bound itself ("0.1
    of its RoM, less than 0.1"), and a largest tilt_power rounded up (3.322) is refused when
    typed back: the numbers the refusal gives must be what the check compares."""
    with pytest.raises(ValueError) as error:
        study_config.check_config(changed(config, "cmc", ("protocol",), {"tilt_power": tilt_power}))
    message = str(error.value)
    number = r"([0-9][0-9.e+-]*)"
    share = float(re.search(rf"tilt at {number} of its RoM", message).group(1))
    assert share < bounds.CMC_TILT_SHARE_BY_MIDDLE, message
    largest = float(re.search(rf"at most {number}", message).group(1))
    study_config.check_config(changed(config, "cmc", ("protocol",), {"tilt_power": largest}))


@pytest.mark.parametrize("tilt_power", [1e-6, 1e-300, 0.1, "just below"])
def test_a_tilt_that_leaves_the_thumb_at_its_rom_from_the_start_is_refused(config, tilt_power):
    """At tilt_power 1e-6 the thumb jumps to its full RoM at the first frame after the start
    and stays there: it does not begin from its mean position and circle out (paper A),
    whatever RoM labels it."""
    if tilt_power == "just below":
        tilt_power = bounds.CMC_EARLIEST_TILT_POWER * (1 - 1e-9)
    assert _tilt_at_the_middle(tilt_power) > 1 - bounds.CMC_TILT_SHARE_BY_MIDDLE
    if tilt_power == 1e-6:
        assert _tilt_at_the_middle(tilt_power, frame=1) > 0.999
    with pytest.raises(ValueError) as error:
        study_config.check_config(changed(config, "cmc", ("protocol",), {"tilt_power": tilt_power}))
    message = str(error.value)
    assert message.startswith(f"config: studies.cmc.protocol.tilt_power: {tilt_power!r}"), message
    assert "middle" in message and "circling out" in message, message
    assert f"at least {bounds.CMC_EARLIEST_TILT_POWER!r}" in message, message


@pytest.mark.parametrize("tilt_power", ["the earliest", 0.2, 0.5])
def test_a_tilt_still_short_of_its_rom_by_the_middle_passes(config, tilt_power):
    if tilt_power == "the earliest":
        tilt_power = bounds.CMC_EARLIEST_TILT_POWER * (1 + 1e-9)
    assert _tilt_at_the_middle(tilt_power) <= 1 - bounds.CMC_TILT_SHARE_BY_MIDDLE
    study_config.check_config(changed(config, "cmc", ("protocol",), {"tilt_power": tilt_power}))


@pytest.mark.parametrize("tilt_power", [0.152, 0.15200309, 1e-6])
def test_a_refused_early_tilt_states_a_share_above_its_bound_and_a_least_tilt_power_that_passes(
    config, tilt_power
):
    """Just below the bound, a share rounded to a few digits reads as the bound itself, and a
    least tilt_power rounded down (0.152) is refused when typed back: the numbers the refusal
    gives must be what the check compares."""
    with pytest.raises(ValueError) as error:
        study_config.check_config(changed(config, "cmc", ("protocol",), {"tilt_power": tilt_power}))
    message = str(error.value)
    number = r"([0-9][0-9.e+-]*)"
    share = float(re.search(rf"tilt to {number} of its RoM", message).group(1))
    assert share > 1 - bounds.CMC_TILT_SHARE_BY_MIDDLE, message
    least = float(re.search(rf"at least {number}", message).group(1))
    study_config.check_config(changed(config, "cmc", ("protocol",), {"tilt_power": least}))


@pytest.mark.parametrize("value", [float("nan"), float("inf"), 1e30, 1e-12, 99.0, 1.000001e5])
def test_a_blind_placement_translation_out_of_its_bounds_is_refused(config, value):
    """NaN and inf pass the schema (no comparison with NaN is true) and failed inside jobs;
    1e30 mm rounds a centre at (10, 20, 30) to 0 on its way back; 1e-12 mm leaves a truth at the
    origin where a contestant answering the origin finds it."""
    bad = copy.deepcopy(config)
    bad["blind_placement"] = {"translation_mm": value}
    study_config.check_schema(bad)  # the schema alone lets it through
    with pytest.raises(ValueError) as error:
        study_config.check_config(bad)
    message = str(error.value)
    assert message.startswith("config: blind_placement.translation_mm: "), message
    assert repr(value) in message and "[100, 100000] mm" in message, message


@pytest.mark.parametrize("value", [100, 250.0, 500.0, 1e5])
def test_a_blind_placement_translation_within_its_bounds_passes(config, value):
    good = copy.deepcopy(config)
    good["blind_placement"] = {"translation_mm": value}
    study_config.check_config(good)


def test_a_run_of_no_study_is_refused_in_one_line(config):
    bad = copy.deepcopy(config)
    for settings in bad["studies"].values():
        settings["enabled"] = False
    with pytest.raises(ValueError, match=r"^config: studies: every study has enabled: false"):
        study_config.check_config(bad)


def test_a_disabled_study_may_list_no_estimator(config):
    good = changed(config, "hip", ("estimators",), [])
    good["studies"]["hip"]["enabled"] = False
    study_config.check_config(good)


@pytest.mark.parametrize("study", ["cmc", "hinge", "hip"])
def test_a_study_of_external_estimators_only_is_refused_before_any_job(config, study):
    # Its papers' figures, tables and checks compare its built-in estimators: with none, the
    # default run would fail in them (an empty figure, a claim divided by no method) after the
    # external estimators had run.
    bad = changed(config, study, ("estimators",), [])
    bad["studies"][study]["external_estimators"] = ["mine"]
    with pytest.raises(ValueError) as error:
        study_config.check_config(bad)
    message = str(error.value)
    assert message.startswith(f"config: studies.{study}.estimators: empty"), message
    assert "external_estimators" in message and "'mine'" in message, message


def test_a_condition_some_listed_estimator_can_fit_is_run(config):
    """Three frames: the pose-based estimators fit them, the sphere fits do not (their rows
    fail, each saying so); only a condition no listed estimator fits is refused."""
    # One spiral turn: the frames show fewer turns than half their count (bounds.py).
    three = {"n_frames": 3, "spiral_turns": 1.0}
    study_config.check_config(changed(config, "cmc", ("protocol",), three))
    only_spheres = changed(config, "cmc", ("protocol",), three)
    only_spheres["studies"]["cmc"]["estimators"] = ["NM", "LS"]
    with pytest.raises(ValueError, match=r"studies\.cmc\.protocol\.n_frames: .* 3 frame"):
        study_config.check_config(only_spheres)


def _declarations():
    """``(where, annotation)`` of every built-in estimator option and protocol field."""
    for kind in registry.KINDS:
        n_arrays = 2 if kind == "joint_center" else 1
        for name in registry.methods(kind):
            options = declared.keyword_types(registry.get(kind, name), n_arrays)
            assert options is not None, f"{kind} {name} takes **options: they cannot be checked"
            yield from ((f"{kind} {name}.{o}", a) for o, a in options.items())
    for study in study_names():
        cls = get_study(study).protocol_class
        yield from ((f"{cls.__name__}.{f}", a) for f, a in declared.field_types(cls).items())


def test_every_option_and_protocol_field_declares_its_type():
    for where, annotation in _declarations():
        assert annotation is not inspect.Parameter.empty, f"{where} declares no type"
        assert not declared.describe(annotation).startswith("a <"), where


@pytest.mark.parametrize("name", study_names())
def test_each_study_protocol_fits_its_own_declarations(name):
    protocol = get_study(name).protocol()
    fields = {f.name: getattr(protocol, f.name) for f in dataclasses.fields(protocol)}
    declared.check_fields(type(protocol), fields)


@pytest.mark.parametrize(
    ("value", "annotation", "words"),
    [
        (True, int, "a: must be an integer, got True"),
        (float("inf"), float, "a: must be a number, got inf"),
        (3, str, "a: must be text, got 3"),
        ([[1, 2, 3], [1, 2]], tuple[declared.Vector3, ...], "a[1]: must be 3 numbers"),
        ({"M": 5}, dict[str, declared.Vector3], "a.M: must be 3 numbers, got 5"),
    ],
)
def test_declared_checks_tell_types_apart_as_yaml_gives_them(value, annotation, words):
    with pytest.raises(declared.DeclarationError, match=re.escape(words)):
        declared.check(value, annotation, ("a",))


def test_missing_grid_key_is_named(config):
    bad = copy.deepcopy(config)
    del bad["studies"]["cmc"]["grid"]["noise_mm"]
    with pytest.raises(ValueError, match=r"studies\.cmc\.grid\.noise_mm: missing"):
        study_config.check_config(bad)


def _overlaid(config, overlay: dict) -> dict:
    merged = copy.deepcopy(config)
    update_config(merged, overlay)
    return merged


def test_a_misspelt_study_is_named_unknown_before_its_missing_keys(config):
    """An overlay meant for cmc's trials, under a misspelt name, is a study of no grid: the
    mistake is the name, which the message says with the known ones."""
    bad = _overlaid(config, {"studies": {"cmx": {"trials": 5}}})
    with pytest.raises(ValueError) as raised:
        study_config.open_config(bad)
    message = str(raised.value)
    assert "unknown studies ['cmx']" in message, message
    assert all(name in message for name in study_names()), message
    assert "required property" not in message, message


def test_a_study_an_extension_may_register_is_named_beside_its_schema_error(config, tmp_path):
    """With extensions listed, a study not built in may be theirs, and no extension is imported
    from a config that fails the schema: the schema's error is given, naming the study as not
    built in."""
    bad = _overlaid(config, {"studies": {"cmx": {"trials": 5}}, "extensions": ["mine.py"]})
    with pytest.raises(ValueError) as raised:
        study_config.open_config(bad, tmp_path)
    message = str(raised.value)
    for words in ("studies/cmx", "'grid' is a required property", "'cmx' is not a built-in"):
        assert words in message, message


@pytest.mark.pipeline
def test_dry_run_names_a_misspelt_study_in_one_line(tmp_path):
    """The project's own check runs before Snakemake's schema validation, whose error leads
    with a dump of the schema."""
    copy_workflow(tmp_path)
    overlay = tmp_path / "bad.yaml"
    overlay.write_text(yaml.safe_dump({"studies": {"cmx": {"trials": 5}}}))
    run = run_snakemake(tmp_path, "--configfile", str(overlay), "--dry-run", timeout=300)
    message = run.stdout + run.stderr
    assert run.returncode != 0
    assert "config error at studies: unknown studies ['cmx']" in message, message[-2000:]
    assert "$schema" not in message and "required property" not in message, message[-3000:]
    assert not (tmp_path / "results").exists()


def _listed_otherwise(settings: dict) -> dict:
    """A study's ``settings`` with its keys, its grid's and its estimators' options listed in
    reverse order."""
    reordered = {key: settings[key] for key in reversed(settings)}
    reordered["grid"] = dict(reversed(settings["grid"].items()))
    if "options" in settings:
        options = settings["options"]
        reordered["options"] = {m: dict(reversed(options[m].items())) for m in reversed(options)}
    return reordered


def test_a_study_opens_in_one_order_however_its_keys_are_listed(config):
    """The jobs' parameters carry the studies' settings, whose repr follows the key order."""
    options = {"BC": {"tol_x": 1e-3, "tol_fun": 1e-3}, "NM": {}}
    listed = changed(config, "cmc", ("options",), options)
    study_config.open_config(listed)
    reordered = copy.deepcopy(listed)
    for study, settings in listed["studies"].items():
        reordered["studies"][study] = _listed_otherwise(settings)
        assert repr(reordered["studies"][study]) != repr(settings)
    study_config.open_config(reordered)
    for study, settings in reordered["studies"].items():
        assert repr(settings) == repr(listed["studies"][study])
        # The grid in the study's own order, which names and orders its conditions.
        assert tuple(settings["grid"]) == get_study(study).grid_keys
        assert study_config.conditions(reordered, study) == study_config.conditions(config, study)


def test_a_lists_order_and_the_protocols_are_kept(config):
    """A grid key's values order the conditions; a paper lists added marker sets as given."""
    values = config["studies"]["cmc"]["grid"]["rom_deg"]
    listed = changed(config, "cmc", ("grid", "rom_deg"), values[::-1])
    protocol = dict(reversed(config["studies"]["cmc"]["protocol"].items()))
    listed["studies"]["cmc"]["protocol"] = protocol
    study_config.open_config(listed)
    assert listed["studies"]["cmc"]["grid"]["rom_deg"] == values[::-1]
    assert list(listed["studies"]["cmc"]["protocol"]) == list(protocol)


def test_a_marker_set_added_by_the_protocol_may_be_used(config):
    """Choices come from the protocol: a config that defines a marker set can grid over it."""
    protocol = {"directions": {"X": [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}}
    protocol["distances_mm"] = {"X": [20.0, 30.0, 40.0]}
    good = changed(config, "cmc", ("protocol",), protocol)
    good["studies"]["cmc"]["grid"]["marker_set"] = ["M", "X"]
    study_config.check_config(good)


def test_every_option_the_estimators_take_is_accepted(config):
    good = changed(config, "cmc", ("options",), {"BC": {"max_iterations": 10, "tol_x": 1}})
    study_config.check_config(good)
    hip = changed(config, "hip", ("options",), {"gauss-markov": {"noise_mm": 1.7}})
    study_config.check_config(hip)
    start = changed(config, "cmc", ("options",), {"IS": {"start": [20, -25, -30.5]}})
    study_config.check_config(start)
    axis = {"planar": {"point": None, "parameterisation": "vector", "max_iter": 400}}
    study_config.check_config(changed(config, "hinge", ("options",), axis))


def test_every_study_declares_the_values_of_each_grid_key():
    for name in study_names():
        spec = get_study(name)
        assert tuple(spec.grid_spec) == spec.grid_keys


@pytest.mark.pipeline
def test_dry_run_stops_before_any_job_naming_the_key(tmp_path):
    message = refused_dry_run(tmp_path, {"studies": {"cmc": {"options": {"BC": {"tol_x": -1}}}}})
    expected = "config: studies.cmc.options.BC.tol_x: must be a number > 0, got -1"
    assert expected in message, message[-2000:]


# A count or a seed written as a whole float: a decimal point left in, or what Snakemake's
# --config makes of 1e3. The grid's and the protocol's integers refuse it; so do these.
@pytest.mark.parametrize(
    ("path", "value", "where"),
    [
        (("base_seed",), 1000.0, "base_seed"),
        (("studies", "cmc", "trials"), 3.0, "studies/cmc/trials"),
        (("verdicts", "seeds"), 2.0, "verdicts/seeds"),
        (("sensitivity", "draws"), 2.0, "sensitivity/draws"),
    ],
)
def test_a_whole_float_where_an_integer_is_meant_is_refused_naming_the_key(
    config, path, value, where
):
    new = copy.deepcopy(config)
    node = new
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    with pytest.raises(ValueError, match=f"config error at {where}: {value!r} is not of type"):
        study_config.validate_config(new)


def test_dry_run_refuses_a_seed_the_command_line_types_as_a_float(tmp_path):
    folder = copy_workflow(tmp_path)
    run = run_snakemake(folder, "-n", "--config", "base_seed=1e3")
    message = run.stdout + run.stderr
    assert run.returncode != 0
    assert "Job stats" not in message
    assert "config error at base_seed: 1000.0 is not of type 'integer'" in message, message[-2000:]


def test_yaml_is_read_as_the_safe_loader_reads_it():
    """read_yaml may use PyYAML's C loader: same documents, and still no arbitrary objects."""
    for name in paper_names():
        text = Path(get_paper(name).published).read_text()
        assert study_config.read_yaml(text) == yaml.safe_load(text)
    with pytest.raises(yaml.YAMLError):
        study_config.read_yaml("!!python/object/apply:os.system ['true']")


@pytest.mark.parametrize(
    ("overlay", "words"),
    [
        (None, ["sensitivity.named.mine", "no such file"]),
        ("- a list\n", ["sensitivity.named.mine", "not a mapping"]),
        ("studies: {hinge: {protocol: {kneee: {noise_sd_mm: 2.0}}}}\n", ["named.mine", "kneee"]),
        ("studies: {cmc: {trials: 0}}\n", ["sensitivity.named.mine", "studies/cmc/trials"]),
        ("studis: {}\n", ["sensitivity.named.mine", "studis"]),
        ("studies:\n\thip: {}\n", ["sensitivity.named.mine", "line 2, column 1", "a tab"]),
        ("# studies: {}\n", ["sensitivity.named.mine", "empty"]),
    ],
    ids=["missing", "not a mapping", "misspelt joint", "bad value", "misspelt key", "tab", "empty"],
)
def test_a_named_protocols_overlay_is_checked_naming_its_key(config, tmp_path, overlay, words):
    path = tmp_path / "mine.yaml"
    if overlay is not None:
        path.write_text(overlay)
    new = copy.deepcopy(config)
    new["sensitivity"] = {"named": {"mine": str(path)}}
    with pytest.raises(ValueError) as raised:
        study_config.named_overlays(new)
    for word in words:
        assert word in str(raised.value), str(raised.value)


def test_the_shipped_named_protocols_pass(config):
    overlays = study_config.named_overlays(config, ROOT)
    assert set(overlays) == set(config["sensitivity"]["named"])


def test_a_missing_overlay_stops_the_workflow_before_any_job_naming_it(tmp_path):
    folder = copy_workflow(tmp_path)
    overlay = tmp_path / "overlay.yaml"
    overlay.write_text("sensitivity: {named: {gone: config/variants/gone.yaml}}\n")
    result = run_snakemake(folder, "-n", "--configfile", str(overlay))
    assert result.returncode != 0
    assert "sensitivity.named.gone" in result.stdout + result.stderr
    assert "no such file" in result.stdout + result.stderr


def test_a_rotations_largest_turn_is_the_chord_at_the_farthest_marker_from_its_axis():
    from jointbench.configuration.bounds import largest_turn_mm

    markers = [[0.0, 0.0, -500.0], [100.0, 0.0, -400.0]]
    rotation = [[0.0, 0.0, 0.0], [np.pi / 2, -0.1, 2 * np.pi], [-0.2, 0.0, 0.0]]
    turns = largest_turn_mm(rotation, markers)
    # About x: 500 mm from it, a quarter turn; about y: 500 mm, 0.1 rad; about z: 100 mm, a
    # full turn, which passed a half turn on its way, the farthest a turn moves a marker.
    np.testing.assert_allclose(turns, [2 * 500 * np.sin(np.pi / 4), 2 * 500 * np.sin(0.05), 200.0])


def test_a_noise_free_rotation_turning_a_marker_beyond_the_resolution_counts(config):
    """At noise_mm 0 the floor is HIP_RESOLUTION_MM: a cross swing turning the farthest distal
    marker by about 0.02 mm moves, one by 0.005 mm does not (the case in BAD)."""
    quiet = {"noise_mm": 0.0, "cross_swing_deg": 2e-3, "twist_deg": 0}
    study_config.check_config(changed(config, "hip", ("protocol",), quiet))


def test_checking_a_config_and_its_named_overlays_simulates_no_trial(config, monkeypatch):
    """Every study declares its frame count: opening a config checks it and each named
    protocol's overlay over it without simulating a trial of any study."""
    _simulating_is_an_error(monkeypatch)
    study_config.check_config(config)
    assert config["sensitivity"]["named"], "no named overlay to check over the config"
    study_config.named_overlays(config, ROOT)


def _simulating_is_an_error(monkeypatch) -> None:
    """The config's check sees every study with a simulator that raises ``AssertionError``."""
    studies = study_config.get_study
    monkeypatch.setattr(
        study_config,
        "get_study",
        lambda name: dataclasses.replace(studies(name), simulate=_never_simulated),
    )


def _never_simulated(condition, protocol, rngs):
    raise AssertionError("a trial was simulated to check the config")


# Protocols whose trials would not fit in memory: a few digits too many in the frame count.
# (study, protocol overrides, the key the refusal names, the frames it names)
_TOO_LONG = [
    (
        "cmc",
        {"n_frames": 10**13},
        "config: studies.cmc.protocol.n_frames: ",
        "10000000000000 frame(s)",
    ),
    (
        "hip",
        {"n_frames": 10**13},
        "config: studies.hip.protocol.n_frames: ",
        "10000000000000 frame(s)",
    ),
    (
        "hinge",
        {"all": {"n_frames": 10**12}},
        "config: studies.hinge.protocol.all.n_frames: ",
        "1000000000000 frame(s)",
    ),
    # Each hip trial keeps its first Nt frames of one recording it draws whole: 200 trials of
    # two million recorded frames each, whatever Nt the grid asks for.
    ("hip", {"n_frames": 2 * 10**6}, "config: studies.hip.protocol.n_frames: ", "2000000 frame(s)"),
]


@pytest.mark.parametrize(("study", "overrides", "key", "frames"), _TOO_LONG)
def test_trials_too_long_to_hold_are_refused_naming_their_frames_before_any_simulation(
    config, monkeypatch, study, overrides, key, frames
):
    """Every study of the package counts its trials' frames from its protocol: the check
    simulates nothing (here, a simulation is an error), and refuses the protocol as a
    mistake rather than ending in a MemoryError or an allocation of gigabytes."""
    _simulating_is_an_error(monkeypatch)
    bad = changed(config, study, ("protocol",), overrides)
    with pytest.raises(ValueError) as raised:
        study_config.check_config(bad)
    message = str(raised.value)
    assert message.startswith(key), message
    assert frames in message and "what one job can hold" in message, message


# Snakemake keeps the last of an option given twice: the first file, or the first values, would
# be dropped without a word (here the first alone would be refused: the run would not be the
# one meant).
@pytest.mark.parametrize(
    ("first", "second", "option"),
    [
        (["--configfile", "first.yaml"], ["--configfile", "second.yaml"], "--configfile"),
        (["--config", "verdicts={'seeds': 0}"], ["--config", "base_seed=3"], "--config"),
    ],
    ids=["configfile", "config"],
)
def test_dry_run_refuses_an_option_snakemake_would_drop_naming_it(tmp_path, first, second, option):
    folder = copy_workflow(tmp_path)
    (folder / "first.yaml").write_text("studies: {cmc: {trials: 0}}\n")
    (folder / "second.yaml").write_text("base_seed: 3\n")
    # Snakemake reads the files from the folder it is started in, not its --directory.
    first, second = (
        [str(folder / v) if v.endswith(".yaml") else v for v in o] for o in (first, second)
    )
    run = run_snakemake(folder, "-n", *first, *second)
    message = run.stdout + run.stderr
    assert run.returncode != 0
    assert "Job stats" not in message
    assert f"{option} is given 2 times" in message, message[-2000:]
    assert shlex.join(first[1:]) in message


def test_several_config_files_after_one_option_are_read():
    argv = ["-n", "--configfile", "a.yaml", "b.yaml", "--config", "x=1", "y=2"]
    assert invocation.repeated_options(argv) == []
    twice = ["--configfile", "a.yaml", "--configfiles", "b.yaml", "-C", "x=1", "--config=y=2"]
    assert invocation.repeated_options(twice) == [
        ("--configfile", [["a.yaml"], ["b.yaml"]]),
        ("--config", [["x=1"], ["y=2"]]),
    ]
