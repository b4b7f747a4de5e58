"""A condition's frame count, which the config's check holds against the fewest frames every
listed estimator fits, read from the study's protocol
(:attr:`~jointbench.simulate.Study.frame_count`), without simulating a trial: every study
declares it, one from outside the package too, so that no size typed a few digits too long in
its config is simulated at plan time (a ``MemoryError``, or a simulator looping for hours)."""

from __future__ import annotations

import copy
import dataclasses
import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
import yaml
from snakemake.utils import update_config
from workflow_copy import ROOT

from jointbench.configuration import config as study_config
from jointbench.configuration.studies import get_study, study_names
from jointbench.estimators.batching import ProgrammingError
from jointbench.running import run
from jointbench.simulate import Study

FOURTH = ROOT / "tests" / "data" / "fourth_study"


def _default() -> dict:
    return study_config.load_config(ROOT / "config" / "config.yaml")


def _reduced() -> dict:
    merged = copy.deepcopy(_default())
    # Merged as `--configfile` merges an overlay: key by key, at every depth.
    update_config(merged, yaml.safe_load((ROOT / "tests" / "data" / "reduced.yaml").read_text()))
    return merged


def _fourth() -> dict:
    paths = [ROOT / "config" / "config.yaml", FOURTH / "toy.yaml"]
    return dict(study_config.open_config(study_config.read_configs(paths), FOURTH))


CONFIGS = {"default": _default, "reduced": _reduced, "fourth study": _fourth}


def _simulated_frames(spec, protocol, condition) -> int:
    trials = spec.simulate(condition, protocol, [np.random.default_rng(0)])
    return trials.segments[spec.segments[0]].shape[1]


@pytest.mark.parametrize("study", study_names())
def test_every_study_of_the_package_declares_its_frame_count(study):
    """So that its config's check simulates nothing (a frame count typed a few digits too long
    is refused, not simulated: tests/test_config_validation.py); the count is checked against
    the simulator's below."""
    assert get_study(study).frame_count is not None


@pytest.mark.parametrize("name", CONFIGS)
def test_a_declared_frame_count_is_the_simulated_trials(name, forget_registrations):
    config = CONFIGS[name]()
    for study in study_config.study_names(config):
        spec, settings = get_study(study), config["studies"][study]
        protocol = spec.protocol(settings.get("protocol"))
        for condition in study_config.conditions(config, study):
            simulated = _simulated_frames(spec, protocol, condition)
            counted = study_config.trial_frames(spec, protocol, condition)
            assert counted == simulated, (study, condition)


def test_an_outside_study_declares_its_frame_count(forget_registrations):
    _fourth()
    assert get_study("toy").frame_count is not None


def test_a_study_that_does_not_declare_its_frame_count_is_refused_naming_it_and_what_to_add():
    uncounted = {f.name: getattr(get_study("cmc"), f.name) for f in dataclasses.fields(Study)}
    uncounted.update(name="uncounted", frame_count=None)
    with pytest.raises(ValueError, match=r"study 'uncounted'.*frame_count=.*condition, protocol"):
        Study(**uncounted)


def test_an_extension_whose_study_counts_no_frames_is_refused_naming_its_file(
    tmp_path, forget_registrations
):
    source = (FOURTH / "toy_study.py").read_text()
    declaration = "    frame_count=frame_count,\n"
    assert declaration in source, "the example no longer declares its frame count so"
    (tmp_path / "toy_study.py").write_text(source.replace(declaration, ""))
    shutil.copy(FOURTH / "paper_t.yaml", tmp_path)
    paths = [ROOT / "config" / "config.yaml", FOURTH / "toy.yaml"]
    with pytest.raises(ValueError, match=r"toy_study\.py.*study 'toy'.*frame_count"):
        study_config.open_config(study_config.read_configs(paths), tmp_path)


@pytest.mark.parametrize("frames", [10**13, 10**8])
def test_an_outside_studys_frame_count_typed_too_long_is_refused_without_simulating(
    frames, monkeypatch, forget_registrations
):
    """The toy simulator lays out every frame (``linspace``) and loops over them in Python: at
    1e13 frames that is a ``MemoryError``, at 1e8 minutes of looping; the check reads the count
    the study declares and refuses it naming the protocol, before any trial is simulated."""
    config = study_config.read_configs([ROOT / "config" / "config.yaml", FOURTH / "toy.yaml"])
    config["studies"]["toy"]["protocol"] = {"n_frames": frames}
    monkeypatch.setattr(np, "linspace", _never_called)
    with pytest.raises(ValueError) as raised:
        study_config.open_config(config, FOURTH)
    message = str(raised.value)
    assert message.startswith("config: studies.toy.protocol: condition "), message
    assert f"{frames} frame(s)" in message, message
    # Its frame_count is a function: which fields it reads, only the study can say.
    assert "study 'toy' declares no frame_keys" in message, message


@pytest.mark.parametrize(
    "given",
    [
        '"protocol.n_frames"',
        '(path for path in [("protocol", "n_frames")])',
        "[]",
        "[()]",
    ],
    ids=["text", "generator", "no path", "empty path"],
)
def test_an_outside_studys_frame_keys_giving_no_paths_is_refused_naming_the_study(
    tmp_path, given, forget_registrations
):
    """Its frame_keys must give the paths a refusal of its frames names: a text (as
    frame_keys gave before they were paths), an iterator that checking them would use up, or
    no path at all, is a mistake of the study's, named as such, not a refusal without keys."""
    source = (FOURTH / "toy_study.py").read_text()
    declaration = "    frame_count=frame_count,\n"
    assert declaration in source, "the example no longer declares its frame count so"
    keys = f"    frame_keys=lambda condition, overrides: {given},\n"
    (tmp_path / "toy_study.py").write_text(source.replace(declaration, declaration + keys))
    shutil.copy(FOURTH / "paper_t.yaml", tmp_path)
    config = study_config.read_configs([ROOT / "config" / "config.yaml", FOURTH / "toy.yaml"])
    # Too many frames: the refusal would name the keys.
    config["studies"]["toy"]["protocol"] = {"n_frames": 10**10}
    with pytest.raises(TypeError, match=r"study 'toy': its frame_keys gave .* not a list"):
        study_config.open_config(config, tmp_path)


def _never_called(*args, **kwargs):
    raise AssertionError("a trial was simulated to count its frames")


def test_checking_the_default_config_runs_no_compiled_kernel():
    """The STA study's trials are fitted by a compiled kernel (their pelvis poses), which the
    frame count of a protocol does not need: checking the config loads no compiler."""
    code = (
        "import sys\n"
        "from jointbench.configuration import config\n"
        "config.load_config('config/config.yaml')\n"
        "assert 'numba' not in sys.modules, 'numba imported'\n"
    )
    checked = subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, env=os.environ
    )
    assert checked.returncode == 0, checked.stderr[-2000:]


def test_a_study_whose_trials_miss_its_declared_frame_count_is_refused_when_simulated(monkeypatch):
    """The config's check trusts a declared count without simulating: a study whose simulator
    gives other frames than it declares is a mistake in the study, refused where its trials
    are simulated, naming the study, the condition and both counts."""
    config = _reduced()
    condition = study_config.conditions(config, "hip_sta")[0]
    wrong = dataclasses.replace(
        get_study("hip_sta"), frame_count=lambda condition, protocol: protocol.n_frames + 1
    )
    monkeypatch.setattr(run, "get_study", lambda name: wrong)
    with pytest.raises(ProgrammingError, match=r"hip_sta.*motion-.*declares \d+ frames.*\d+"):
        run.simulate_condition(config, "hip_sta", condition, range(1))


@pytest.mark.parametrize(
    ("count", "shown"),
    [(lambda n: float(n), r"120\.0"), (lambda n: None, "None"), (lambda n: -n, "-120")],
)
def test_a_frame_count_that_is_no_count_is_the_studys_mistake(monkeypatch, count, shown):
    """A count the study gives as 120.0, None (a function that forgot to return) or -120 (a
    sign slip) is a programming error in the study, raised as one naming it, not a refusal of
    the config's protocol, which set no such count."""
    config = _default()
    miscounted = dataclasses.replace(
        get_study("cmc"), frame_count=lambda condition, protocol: count(protocol.n_frames)
    )
    studies = study_config.get_study
    monkeypatch.setattr(
        study_config, "get_study", lambda name: miscounted if name == "cmc" else studies(name)
    )
    with pytest.raises(TypeError, match=rf"study 'cmc'.*frame_count gave {shown}\b.*0 or more"):
        study_config.check_config(config)


# A protocol's frame fields given values no recording has, in every built-in study: (study,
# protocol overrides, the key the refusal names). Negative, zero and non-integer values are
# refused by the fields' declarations; a count too large to hold or too small for any listed
# estimator by the check of each condition's frames, which names the same fields.
_FRAME_MISTAKES = [
    ("cmc", {"n_frames": 10**13}, "studies.cmc.protocol.n_frames"),
    ("cmc", {"n_frames": 2}, "studies.cmc.protocol.n_frames"),
    ("cmc", {"n_frames": 0}, "studies.cmc.protocol.n_frames"),
    ("cmc", {"n_frames": -120}, "studies.cmc.protocol.n_frames"),
    ("cmc", {"n_frames": 120.5}, "studies.cmc.protocol.n_frames"),
    ("hinge", {"all": {"n_frames": 10**12}}, "studies.hinge.protocol.all.n_frames"),
    ("hinge", {"mcp": {"n_frames": 10**12}}, "studies.hinge.protocol.mcp.n_frames"),
    (
        "hinge",
        {"all": {"n_frames": 121}, "knee": {"n_frames": 10**12}},
        "studies.hinge.protocol.knee.n_frames",
    ),
    ("hinge", {"all": {"n_frames": 0}}, "studies.hinge.protocol.all.n_frames"),
    ("hinge", {"knee": {"n_frames": -121}}, "studies.hinge.protocol.knee.n_frames"),
    ("hip", {"n_frames": 2 * 10**6}, "studies.hip.protocol.n_frames"),
    ("hip", {"n_frames": 0}, "studies.hip.protocol.n_frames"),
    ("hip", {"n_frames": 1200.5}, "studies.hip.protocol.n_frames"),
    ("hip_sta", {"duration_s": 1e-300}, "studies.hip_sta.protocol.duration_s, fps"),
    ("hip_sta", {"fps": 1e-300}, "studies.hip_sta.protocol.duration_s, fps"),
    ("hip_sta", {"duration_s": 0.02}, "studies.hip_sta.protocol.duration_s, fps"),
    ("hip_sta", {"duration_s": 86400, "fps": 1e5}, "studies.hip_sta.protocol.duration_s, fps"),
    ("hip_sta", {"duration_s": -12.0}, "studies.hip_sta.protocol.duration_s"),
    ("hip_sta", {"fps": 0}, "studies.hip_sta.protocol.fps"),
]


@pytest.mark.parametrize(("study", "overrides", "key"), _FRAME_MISTAKES, ids=str)
def test_a_frame_count_mistake_is_refused_naming_the_fields_it_comes_from(
    study, overrides, key, monkeypatch
):
    """Whatever bound the count breaks, the refusal names the protocol field(s) the study's
    count is read from (as the config writes them: a hinge joint's under its own entry or
    ``all``), before any trial is simulated."""
    config = _default()
    config["studies"][study]["protocol"] = overrides
    monkeypatch.setattr(np, "linspace", _never_called)
    with pytest.raises(ValueError) as raised:
        study_config.check_config(config)
    message = str(raised.value)
    assert message.startswith(f"config: {key}: "), message


# The skin-marker study's frames are read from two fields, round(duration_s * fps): a count
# refused gives both values, written or default: (protocol overrides, the words it has).
_HIP_STA_FRAME_VALUES = [
    ({"duration_s": 1e-300}, "trials of 0 frame(s) (from duration_s 1e-300, fps 50.0), fewer"),
    ({"fps": 0.1}, "trials of 1 frame(s) (from duration_s 12.0, fps 0.1), fewer"),
    (
        {"duration_s": 86400, "fps": 1e5},
        "trials of 8640000000 frame(s) (from duration_s 86400, fps 100000.0), 60 trials",
    ),
]


@pytest.mark.parametrize(("overrides", "words"), _HIP_STA_FRAME_VALUES, ids=str)
def test_a_frame_count_read_from_two_fields_is_refused_giving_both_values(overrides, words):
    """The count alone (0 frames) does not say which of duration_s and fps is the mistake, nor
    by how much: the refusal gives the value of each, as it names each."""
    config = _default()
    config["studies"]["hip_sta"]["protocol"] = overrides
    with pytest.raises(ValueError) as raised:
        study_config.check_config(config)
    message = str(raised.value)
    assert message.startswith("config: studies.hip_sta.protocol.duration_s, fps: "), message
    assert words in message, message
