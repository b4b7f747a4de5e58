"""Config mistakes the schema cannot see stop the workflow before any job, naming the key and
the allowed values (issue: inputs that cannot lie)."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest
import yaml
from snakemake.utils import update_config
from workflow_copy import ROOT, copy_workflow, run_snakemake

from jointbench.papers import get_paper, paper_names
from jointbench.study import config as study_config
from jointbench.study.studies import get_study, study_names


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
    study_config.check_config(config)
    data = ROOT / "tests" / "data"
    for path in [data / "reduced.yaml", data / "grains.yaml", *ROOT.glob("config/variants/*.yaml")]:
        merged = copy.deepcopy(config)
        # Merged as `--configfile` merges an overlay: key by key, at every depth.
        update_config(merged, yaml.safe_load(path.read_text()))
        study_config.check_config(merged)


BAD = [
    # (study, path, value, words the message must contain)
    ("cmc", ("grid", "noise"), [2.0], ["studies.cmc.grid.noise", "unknown grid key", "noise_mm"]),
    ("cmc", ("grid", "noise_mm"), [-1], ["studies.cmc.grid.noise_mm", "-1", "a number >= 0"]),
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
        ["options.BC.max_iterations: 'many' is not an integer (the default is 600)"],
    ),
    (
        "cmc",
        ("options",),
        {"BC": {"tol_x": True}},
        ["options.BC.tol_x: True is not a number (the default is 0.0001)"],
    ),
    ("cmc", ("external_estimators",), ["NM"], ["external_estimators", "'NM'", "built-in"]),
    ("cmc", ("protocol",), {"spiral": 2}, ["studies.cmc.protocol", "spiral"]),
]


@pytest.mark.parametrize(("study", "path", "value", "words"), BAD, ids=lambda v: str(v))
def test_mistake_names_key_and_allowed_values(config, study, path, value, words):
    with pytest.raises(ValueError) as error:
        study_config.check_config(changed(config, study, path, value))
    for word in words:
        assert word in str(error.value), str(error.value)


def test_missing_grid_key_is_named(config):
    bad = copy.deepcopy(config)
    del bad["studies"]["cmc"]["grid"]["noise_mm"]
    with pytest.raises(ValueError, match=r"studies\.cmc\.grid\.noise_mm: missing"):
        study_config.check_config(bad)


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


def test_every_study_declares_the_values_of_each_grid_key():
    for name in study_names():
        spec = get_study(name)
        assert tuple(spec.grid_spec) == spec.grid_keys


@pytest.mark.pipeline
def test_dry_run_stops_before_any_job_naming_the_key(tmp_path):
    copy_workflow(tmp_path)
    overlay = tmp_path / "bad.yaml"
    overlay.write_text(yaml.safe_dump({"studies": {"cmc": {"estimators": ["NM", "XX"]}}}))
    run = run_snakemake(tmp_path, "--configfile", str(overlay), "--dry-run", timeout=300)
    message = run.stdout + run.stderr
    assert run.returncode != 0
    assert "studies.cmc.estimators: unknown center estimator 'XX'" in message, message[-2000:]
    assert not (tmp_path / "results").exists()


def test_yaml_is_read_as_the_safe_loader_reads_it():
    """read_yaml may use PyYAML's C loader: same documents, and still no arbitrary objects."""
    for name in paper_names():
        text = Path(get_paper(name).published).read_text()
        assert study_config.read_yaml(text) == yaml.safe_load(text)
    with pytest.raises(yaml.YAMLError):
        study_config.read_yaml("!!python/object/apply:os.system ['true']")
