"""External estimators are blind: the file they read holds the markers and the condition's grid
values, never the truth nor a generator parameter that places it; only the benchmark scores.
"""

from __future__ import annotations

import base64
import dataclasses
import json
import os
import re
import shlex

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import yaml
from workflow_copy import ROOT, copy_workflow, run_snakemake

from jointbench.configuration.config import estimator_names
from jointbench.configuration.studies import get_study, method_kind
from jointbench.resultfiles.interchange import read_estimates_csv, write_dataset_csv
from jointbench.resultfiles.parquet import (
    BLIND_KEYS,
    read_dataset,
    read_metadata,
    read_truth,
    write_blind_dataset,
    write_dataset,
)
from jointbench.running import landlock
from jointbench.running.collected import collect
from jointbench.running.placement import dataset_placements
from jointbench.running.run import estimate, simulate_condition
from jointbench.running.scoring import ESTIMATE_COLUMNS, score_columns

CONFIG = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())


def _config(study: str, trials: int = 2) -> dict:
    config = json.loads(json.dumps(CONFIG))
    config["studies"][study]["trials"] = trials
    return config


def _first_condition(study: str) -> dict:
    """The first cell of the study's default grid."""
    grid = CONFIG["studies"][study]["grid"]
    return {key: values[0] for key, values in grid.items()}


def _numbers(value) -> list[float]:
    """Every number in a JSON value, depth first."""
    if isinstance(value, dict):
        return [n for item in value.values() for n in _numbers(item)]
    if isinstance(value, list):
        return [n for item in value for n in _numbers(item)]
    if isinstance(value, bool) or not isinstance(value, int | float):
        return []
    return [float(value)]


def _write(tmp_path, study: str):
    """A simulated condition of ``study`` written as its dataset file and its blind file."""
    config = _config(study)
    condition = _first_condition(study)
    dataset = tmp_path / "datasets" / study / "c.parquet"
    blind = tmp_path / "blind" / study / "c.parquet"
    trials = simulate_condition(config, study, condition)
    write_dataset(dataset, trials, study=study, condition=condition, provenance={"x": 1})
    placements = dataset_placements(dataset, CONFIG["base_seed"])
    write_blind_dataset(dataset, blind, placements, provenance={"rule": "blind_dataset"})
    return dataset, blind, trials


def _unplaced(dataset, markers):
    """``markers`` ``(n_trials, n_frames, n_markers, 3)`` of the blind copy of ``dataset``
    moved back by each trial's placement."""
    placements = dataset_placements(dataset, CONFIG["base_seed"])
    offsets = markers - placements.translations[:, None, None, :]
    return np.einsum("nji,nfmj->nfmi", placements.rotations, offsets)


STUDIES = ("cmc", "hinge", "hip", "hip_sta")


@pytest.mark.parametrize("study", STUDIES)
def test_a_blind_file_holds_the_markers_and_nothing_that_places_the_truth(tmp_path, study):
    dataset, blind, trials = _write(tmp_path, study)
    read, metadata = read_dataset(blind)
    for name, markers in trials.segments.items():
        np.testing.assert_allclose(_unplaced(dataset, read.segments[name]), markers, atol=1e-9)
    assert read.truth is None and read.parameters == {}
    assert set(metadata) == {*BLIND_KEYS, "provenance"}
    assert metadata["condition"] == read_metadata(dataset)["condition"]
    # The footer holds the blind metadata and Arrow's copy of the schema, which holds it again.
    footer = pq.ParquetFile(blind).metadata.metadata
    assert set(footer) == {b"jointbench", b"ARROW:schema"}
    arrow = pa.ipc.read_schema(pa.py_buffer(base64.b64decode(footer[b"ARROW:schema"])))
    assert arrow.metadata == {b"jointbench": footer[b"jointbench"]}
    text = footer[b"jointbench"].decode()
    for word in ("truth", "parameters", "center", "axis", "joint_mm", "markers_mm"):
        assert word not in text
    # No number of the truth or of the parameters is stored, but the grid values and shapes.
    public = set(_numbers(metadata["condition"])) | set(_numbers(metadata["shapes"]))
    secret = set(_numbers(trials.truth)) | set(_numbers(trials.parameters))
    assert not (secret - public) & set(_numbers(json.loads(text)))


@pytest.mark.parametrize("study", STUDIES)
def test_the_csv_of_a_blind_file_is_the_csv_of_its_placed_markers(tmp_path, study):
    """The CSV holds the blind file's markers, as a dataset file of the same markers gives
    them: nothing of the metadata."""
    _, blind, trials = _write(tmp_path, study)
    placed, _ = read_dataset(blind)
    same = tmp_path / "placed.parquet"
    write_dataset(
        same, dataclasses.replace(trials, segments=placed.segments), study=study, condition={}
    )
    write_dataset_csv(same, tmp_path / "placed.csv")
    write_dataset_csv(blind, tmp_path / "blind.csv")
    assert (tmp_path / "placed.csv").read_bytes() == (tmp_path / "blind.csv").read_bytes()


def test_an_estimates_csv_is_read_against_the_blind_file(tmp_path):
    _, blind, _ = _write(tmp_path, "cmc")
    source = tmp_path / "LS-C" / "c.csv"
    source.parent.mkdir()
    header = "trial,center_x,center_y,center_z,converged,iterations,seconds,status\n"
    source.write_text(header + "0,1,2,3,true,0,0,ok\n1,1,2,3,true,0,0,ok\n")
    read_estimates_csv(source, blind, tmp_path / "out.parquet")
    frame = pd.read_parquet(tmp_path / "out.parquet")
    assert set(_first_condition("cmc").items()) <= set(frame.iloc[0].to_dict().items())


def test_the_benchmark_refuses_to_score_against_a_blind_file(tmp_path):
    dataset, blind, trials = _write(tmp_path, "cmc")
    assert read_truth(dataset) == trials.truth
    with pytest.raises(ValueError, match="blind") as error:
        read_truth(blind)
    assert str(blind) in str(error.value)
    estimates = {"center_x": [0.0], "center_y": [0.0], "center_z": [0.0]}
    with pytest.raises(ValueError, match="blind"):
        score_columns("center", estimates, None)
    path = tmp_path / "estimates" / "cmc" / "LS" / "c.parquet"
    path.parent.mkdir(parents=True)
    frame = pd.DataFrame(
        {
            **{k: [v, v] for k, v in _first_condition("cmc").items()},
            "trial": [0, 1],
            "method": "LS",
            **{c: [0.0, 0.0] for c in ("center_x", "center_y", "center_z")},
            "converged": True,
            "iterations": 0,
            "seconds": 0.0,
            "status": "ok",
        }
    )
    frame.to_parquet(path, index=False)
    with pytest.raises(ValueError, match="blind"):
        collect("cmc", [path], str(tmp_path / "collected.parquet"), [blind])


def _shifted(value):
    """A JSON value with every number moved by 37."""
    if isinstance(value, dict):
        return {key: _shifted(item) for key, item in value.items()}
    if isinstance(value, list):
        return [_shifted(item) for item in value]
    return value + 37.0


@pytest.mark.parametrize("study", STUDIES)
def test_built_in_estimates_do_not_depend_on_the_truth(study):
    """The built-in estimate jobs read the full dataset to score and diagnose; every built-in
    estimator's estimate is the same whatever truth the file holds."""
    config = _config(study)
    condition = _first_condition(study)
    trials = simulate_condition(config, study, condition)
    moved = dataclasses.replace(trials, truth=_shifted(trials.truth))
    spec = get_study(study)
    for method in estimator_names(config, study, source="builtin"):
        kind = method_kind(spec, method)
        columns = [*ESTIMATE_COLUMNS[kind], "converged", "iterations", "status"]
        ours = estimate(study, method, trials, condition)[columns]
        other = estimate(study, method, moved, condition)[columns]
        pd.testing.assert_frame_equal(ours, other)


# An external rule that tries to read the truth from everything it is given: every key-value
# metadata of its input, every file beside it, every config value its script sees. Where it
# finds a centre it returns it; otherwise it returns the markers' centroid.
ORACLE = '''
import json
import os
from pathlib import Path

import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq

dataset, estimates = snakemake.input[0], snakemake.output[0]


def centres(value):
    """Every three-number list under a key that names a centre, anywhere in a JSON value."""
    if isinstance(value, dict):
        for key, item in value.items():
            if key in ("center", "center_mm", "joint_mm", "axis_point") and len(item) == 3:
                yield [float(x) for x in item]
            yield from centres(item)
    elif isinstance(value, list):
        for item in value:
            yield from centres(item)


found = []
sources = dict(pq.read_schema(dataset).metadata or {})
sources.update(pq.ParquetFile(dataset).metadata.metadata or {})
for raw in sources.values():
    try:
        found += centres(json.loads(raw))
    except ValueError:
        pass
for sidecar in Path(dataset).parent.iterdir():
    if sidecar.suffix in (".json", ".yaml", ".txt"):
        found += centres(json.loads(sidecar.read_text()))
found += centres(dict(snakemake.config))
meta = json.loads(pq.read_schema(dataset).metadata[b"jointbench"])
rows = []
for trial, markers in pd.read_parquet(dataset).groupby("trial"):
    center = found[0] if found else markers[["x", "y", "z"]].to_numpy().mean(axis=0)
    rows.append(
        {
            **meta["condition"],
            "trial": trial,
            "method": "oracle",
            "center_x": center[0],
            "center_y": center[1],
            "center_z": center[2],
            "converged": True,
            "iterations": 0,
            "seconds": 0.0,
            "status": "ok",
        }
    )
pd.DataFrame(rows).to_parquet(estimates, index=False)
'''


def _run_with(tmp_path, name: str, script: str, external: list[str], *arguments, jobs=2):
    """The run collecting cmc with an external rule ``name``, the shipped template's with its
    own ``script``, beside LS and the ``external`` estimators listed (``jobs`` at a time, with
    Snakemake's ``arguments``)."""
    copy_workflow(tmp_path)
    rules = tmp_path / "workflow" / "rules" / "estimators"
    template = (rules / "centroid.smk").read_text()
    (rules / f"{name}.smk").write_text(
        template.replace("estimate_centroid", f"estimate_{name}").replace("centroid", name)
    )
    (tmp_path / "workflow" / "external" / f"{name}.py").write_text(script)
    overlay = _cmc_only(tmp_path, estimators=["LS"], external_estimators=external)
    target = "results/collected/cmc.parquet"
    return run_snakemake(tmp_path, target, *arguments, "--configfile", overlay, jobs=jobs)


def _collected_with(tmp_path, name: str, script: str, external: list[str]) -> pd.Series:
    """The cmc errors by method and trial of a run with :func:`_run_with`."""
    run = _run_with(tmp_path, name, script, external)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    collected = pd.read_parquet(tmp_path / "results" / "collected" / "cmc.parquet")
    return collected.set_index(["method", "trial"])["error_mm"]


@pytest.mark.pipeline
def test_an_oracle_rule_finds_no_truth_and_ranks_as_the_centroid(tmp_path):
    """The oracle's rule is the shipped template's with its own script: it reads what every
    external rule is given and ranks where the centroid, which it falls back to, ranks."""
    error = _collected_with(tmp_path, "oracle", ORACLE, ["centroid", "oracle"])
    assert (error["oracle"] > 1.0).all(), error["oracle"]
    # Both mapped back from the same placements: equal to rounding.
    np.testing.assert_allclose(error["oracle"], error["centroid"], rtol=0, atol=1e-9)


# A cheat: a script that answers the cmc protocol's centre, the truth of every trial, read from
# the package as any program in the workflow's environment can.
CHEAT = """
import json
import os

import pandas as pd
import pyarrow.parquet as pq

from jointbench.simulate.cmc import CmcProtocol

dataset, estimates = snakemake.input[0], snakemake.output[0]
meta = json.loads(pq.read_schema(dataset).metadata[b"jointbench"])
centre = CmcProtocol().center_mm
rows = [
    {
        **meta["condition"],
        "trial": trial,
        "method": "cheat",
        "center_x": centre[0],
        "center_y": centre[1],
        "center_z": centre[2],
        "converged": True,
        "iterations": 0,
        "seconds": 0.0,
        "status": "ok",
    }
    for trial in sorted(pd.read_parquet(dataset)["trial"].unique())
]
pd.DataFrame(rows).to_parquet(estimates, index=False)
"""


@pytest.mark.pipeline
def test_a_rule_answering_the_protocols_centre_ranks_last(tmp_path):
    """Every trial of a study has the same truth, but each is placed anew in the blind copy and
    the answers are mapped back: the constant is scored where a random placement moved it."""
    error = _collected_with(tmp_path, "cheat", CHEAT, ["cheat", "LM"])
    assert (error["cheat"] > 20.0).all(), error["cheat"]
    # LM answers in the coordinates it read: its errors are those of a sphere fit.
    assert (error["LM"] < 5.0).all(), error["LM"]
    assert error["cheat"].min() > error.drop(index="cheat").max()


# The end of a test's script: its ``answers`` (trial, center_x, center_y, center_z), claimed
# converged, written as the estimates of the method its output's folder names.
_ANSWERED = """
condition = json.loads(pq.read_schema(blind).metadata[b"jointbench"])["condition"]
method = Path(estimates).parent.name
answers = answers.assign(**condition, method=method, converged=True, iterations=0, seconds=0.0)
answers.assign(status="ok").to_parquet(estimates, index=False)
"""

# A cheat by public numbers: the program draws each trial's placement from the trial's seed
# (the config's base seed, the study, condition and trial, all beside its blind copy) as the
# package's module draws its stream, and answers the protocol's centre placed by it.
SEEDED = (
    """
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

from jointbench.configuration.seeds import trial_seed
from jointbench.running import placement
from jointbench.simulate.cmc import CmcProtocol

blind, estimates = snakemake.input[0], snakemake.output[0]
meta = json.loads(pq.read_schema(blind).metadata[b"jointbench"])
base = snakemake.config["base_seed"]
half = snakemake.config["blind_placement"]["translation_mm"]
centre = np.asarray(CmcProtocol().center_mm, dtype=float)
rows = []
for trial in sorted(pd.read_parquet(blind)["trial"].unique()):
    seed = trial_seed(base, meta["study"], meta["condition"], int(trial))
    rng = np.random.default_rng([seed, placement._STREAM])
    quaternion = rng.standard_normal(4)
    rotation = placement._rotation(quaternion / np.linalg.norm(quaternion))
    rows.append([int(trial), *(rotation @ centre + rng.uniform(-half, half, 3))])
answers = pd.DataFrame(rows, columns=["trial", "center_x", "center_y", "center_z"])
"""
    + _ANSWERED
)


@pytest.mark.pipeline
def test_a_rule_drawing_the_placements_from_the_public_seed_ranks_last(tmp_path):
    """The placements depend on the markers as simulated, not on the public seed alone: the
    cheat's answers are a constant moved by motions it did not guess."""
    error = _collected_with(tmp_path, "seeded", SEEDED, ["seeded", "LM"])
    assert (error["seeded"] > 20.0).all(), error["seeded"]
    assert error["seeded"].min() > error.drop(index="seeded").max()


# The end of a probing script: what each attempt gave (``tried``) written beside its estimates,
# and the centroid of each trial's markers as its answers.
_TOLD_AND_CENTROID = (
    """
(mine / (blind.stem + ".json")).write_text(json.dumps(tried))
answers = pd.read_parquet(blind).groupby("trial")[["x", "y", "z"]].mean().reset_index()
answers.columns = ["trial", "center_x", "center_y", "center_z"]
"""
    + _ANSWERED
)

# A cheat by paths its rule does not declare: the program opens the full dataset beside the
# blind copy it was given, and the copy's placements, and answers the truth as placed.
PEEK = (
    """
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq

blind, estimates = Path(snakemake.input[0]), snakemake.output[0]
full = blind.parent.parent.parent / "datasets" / blind.parent.name / blind.name
truth = np.asarray(json.loads(pq.read_schema(full).metadata[b"jointbench"])["truth"]["center"])
placed = pd.read_parquet(str(full).replace("datasets", "placements")).set_index("trial")
rotations = placed[[f"r{i}{j}" for i in range(3) for j in range(3)]].to_numpy().reshape(-1, 3, 3)
centres = rotations @ truth + placed[["p_x", "p_y", "p_z"]].to_numpy()
answers = pd.DataFrame(centres, columns=["center_x", "center_y", "center_z"])
answers.insert(0, "trial", placed.index.to_numpy())
"""
    + _ANSWERED
)


# Where the kernel has no Landlock, a program's reads are not confined (the run says so).
_CONFINED = pytest.mark.skipif(landlock.abi_version() == 0, reason="this kernel has no Landlock")


@pytest.mark.pipeline
@_CONFINED
def test_a_program_opening_the_truth_by_a_path_its_rule_does_not_declare_is_stopped(tmp_path):
    """Its job is confined to the blind copies and its rule's folders: opening the full
    dataset fails, and so does the job and the run, naming the file."""
    run = _run_with(tmp_path, "peek", PEEK, ["centroid", "peek"])
    message = run.stdout + run.stderr
    assert run.returncode != 0, "the run succeeded with the truth read by an undeclared path"
    denied = r"results/datasets/cmc/\S+\.parquet'?\.? Detail: \[errno 13\] Permission denied"
    assert re.search(denied, message), message[-3000:]
    assert "Error in rule estimate_peek" in message, message[-3000:]


# A program trying every way to the files its job may not open, and to its own: what each
# attempt gave (an error's text, or "read"), written beside its estimates (the centroid's).
PROBE = (
    """
import json
import os
import subprocess
import tempfile
import time
from pathlib import Path

import pandas as pd
import pyarrow.parquet as pq

blind, estimates = Path(snakemake.input[0]), Path(snakemake.output[0])
mine, results = estimates.parent, Path("results")
full = results / "datasets" / "cmc" / blind.name


def attempt(read):
    try:
        read()
    except OSError as error:
        return str(error)
    return "read"


link = mine / (blind.stem + ".link")
link.symlink_to(os.path.relpath(full, mine))
paths = {
    "dataset": full,
    "placements": results / "placements" / "cmc" / blind.name,
    "built-in estimate": results / "estimates" / "cmc" / "LS" / "planted.txt",
    "collected": results / "collected" / "planted.txt",
    "a built-in estimator's log": results / "logs" / "estimate" / "cmc" / "LS.log",
    "a link of its own": link,
    "blind/..": results / "blind" / ".." / "datasets" / "cmc" / blind.name,
    "/proc/self/cwd": Path("/proc/self/cwd") / full,
}
tried = {name: attempt(path.read_bytes) for name, path in paths.items()}
tried["listing datasets"] = attempt(lambda: os.listdir(results / "datasets"))
tried["listing results"] = attempt(lambda: os.listdir(results))
child = subprocess.run(["cat", str(full)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
tried["child process"] = child.stderr.decode() or "read"
# A daemon: in a session of its own, its parent ended, it tells what it read by a file.
told = mine / (blind.stem + ".daemon")
daemon = f"cat {full} > /dev/null 2> {told}.part || true; mv {told}.part {told}"
subprocess.run(["sh", "-c", f"(setsid sh -c '{daemon}' &)"], check=True)
deadline = time.monotonic() + 30
while not told.exists() and time.monotonic() < deadline:
    time.sleep(0.05)
tried["daemon"] = told.read_text() if told.exists() else "no word"
scratch = mine / (blind.stem + ".scratch")
scratch.write_text("its own")
tried["its own folder"] = scratch.read_text()
with tempfile.TemporaryFile("w+") as temporary:
    temporary.write("its own")
    temporary.seek(0)
    tried["its own temporary file"] = temporary.read()
"""
    + _TOLD_AND_CENTROID
)


@pytest.mark.pipeline
@_CONFINED
def test_no_way_of_a_program_leads_to_what_its_job_may_not_open(tmp_path):
    """Every way tried fails with "Permission denied": the full dataset, the placements, a
    built-in estimator's files and the collected results left by an earlier run, by their
    paths, through a link the program makes in its own folder, ``..`` or ``/proc/self/cwd``,
    listing results/, from a child process and from a daemon; a built-in estimator's log.
    The program's own folder and temporary files are its own (here in a temporary folder of
    the job's, as the checkout is under /tmp), and the external estimators shipped (LS-C
    compiled into results/bin/) run beside it."""
    for planted in (
        "estimates/cmc/LS/planted.txt",
        "collected/planted.txt",
        "logs/estimate/cmc/LS.log",
    ):
        (tmp_path / "results" / planted).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / "results" / planted).write_text("made from the truth")
    external = ["centroid", "LM", "LS-C", "probe"]
    error = _collected_with(tmp_path, "probe", PROBE, external)
    (found,) = (tmp_path / "results" / "estimates" / "cmc" / "probe").glob("*.json")
    tried = json.loads(found.read_text())
    assert tried.pop("its own folder") == "its own"
    assert tried.pop("its own temporary file") == "its own"
    assert len(tried) == 12
    refused = {name: "Permission denied" in outcome for name, outcome in tried.items()}
    assert all(refused.values()), tried
    assert set(error.index.get_level_values("method")) == {"LS", *external}


# A program reaching into another external estimator's folders: reading its answers to copy
# them, writing over them to spoil its rank, or planting a file among them. What each attempt
# gave (an error's text, or "read"/"written"), beside its own estimates (the centroid's).
TAMPER = (
    """
import json
import os
from pathlib import Path

import pandas as pd
import pyarrow.parquet as pq

blind, estimates = Path(snakemake.input[0]), Path(snakemake.output[0])
mine, results = estimates.parent, Path("results")
theirs = results / "estimates" / "cmc" / "LM"
their_log = results / "logs" / "estimate" / "cmc" / "LM"


def attempt(act, done):
    try:
        act()
    except OSError as error:
        return str(error)
    return done


tried = {
    "listing its estimates": attempt(lambda: os.listdir(theirs), "read"),
    "planting among its estimates": attempt(
        lambda: (theirs / (blind.stem + ".planted")).write_text("x"), "written"
    ),
    "planting in its log folder": attempt(
        lambda: (their_log / (blind.stem + ".planted")).write_text("x"), "written"
    ),
}
"""
    + _TOLD_AND_CENTROID
)


@pytest.mark.pipeline
@_CONFINED
def test_a_program_cannot_open_another_external_estimators_folders(tmp_path):
    """Each job of a rule of the user's is confined to its own rule's folders, beside the blind
    copies and the inputs it declares: an external estimator's program can neither read another
    one's answers nor write among them or its logs."""
    # LM's folders, as its jobs leave them, whichever job runs first.
    for folder in ("estimates/cmc/LM", "logs/estimate/cmc/LM"):
        (tmp_path / "results" / folder).mkdir(parents=True)
    error = _collected_with(tmp_path, "tamper", TAMPER, ["LM", "tamper"])
    (found, *_) = (tmp_path / "results" / "estimates" / "cmc" / "tamper").glob("*.json")
    tried = json.loads(found.read_text())
    assert all("Permission denied" in outcome for outcome in tried.values()), tried
    assert not list((tmp_path / "results").rglob("*.planted"))
    assert set(error.index.get_level_values("method")) == {"LS", "LM", "tamper"}


# A script that runs a shell command inside its job, as Snakemake's shell() does: by the rule's
# own limited shell, within its job's confinement.
SHELLING = (
    """
import json
from pathlib import Path

import pandas as pd
import pyarrow.parquet as pq
from snakemake.shell import shell

blind, estimates = Path(snakemake.input[0]), Path(snakemake.output[0])
said = estimates.parent / (blind.stem + ".said")
shell(f"head -c 4 {blind} > /dev/null && echo from-the-shell > {said}")
answers = pd.read_parquet(blind).groupby("trial")[["x", "y", "z"]].mean().reset_index()
answers.columns = ["trial", "center_x", "center_y", "center_z"]
"""
    + _ANSWERED
)


@pytest.mark.pipeline
def test_a_script_running_a_shell_command_in_its_job_runs(tmp_path):
    """The command runs by the rule's own shell, whose keeper keeps the confinement the job's
    keeper handed down: it reads the blind copy, writes in its rule's folder, and the run goes
    on."""
    error = _collected_with(tmp_path, "shelling", SHELLING, ["shelling"])
    said = list((tmp_path / "results" / "estimates" / "cmc" / "shelling").glob("*.said"))
    assert said and all(path.read_text() == "from-the-shell\n" for path in said), said
    assert set(error.index.get_level_values("method")) == {"LS", "shelling"}


# A program that rewrites the blind copy it was given in place, its metadata kept (cleaning it,
# or spoiling it for the external estimators that read it after).
SPOIL = (
    """
import json
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq

blind, estimates = snakemake.input[0], snakemake.output[0]
table = pq.read_table(blind)
noise = np.random.default_rng(0).normal(scale=20.0, size=(table.num_rows, 3))
for axis, column in zip("xyz", noise.T):
    moved = pa.array(table.column(axis).to_numpy() + column)
    table = table.set_column(table.schema.get_field_index(axis), axis, moved)
pq.write_table(table, blind)
# Its own answers: the centroid of each trial's markers as it left them.
answers = table.to_pandas().groupby("trial")[["x", "y", "z"]].mean().reset_index()
answers.columns = ["trial", "center_x", "center_y", "center_z"]
"""
    + _ANSWERED
)


@pytest.mark.pipeline
def test_a_program_rewriting_its_blind_input_in_place_stops_the_run_naming_the_file(tmp_path):
    """Run first (one job at a time, its file prioritised), the spoiler changes the markers
    the centroid reads after it: the run stops, naming the blind file (where the kernel has
    Landlock, the spoiler's write is refused, and its job fails naming the file)."""
    condition = "marker_set-M__rom_deg-15__noise_mm-1.0"
    first = f"results/estimates/cmc/spoil/{condition}.parquet"
    external = ["spoil", "centroid"]
    run = _run_with(tmp_path, "spoil", SPOIL, external, "--prioritize", first, jobs=1)
    message = run.stdout + run.stderr
    assert run.returncode != 0, "the run succeeded with the blind copy changed by the spoiler"
    assert f"results/blind/cmc/{condition}.parquet" in message


# Started with every Python process of a run (on PYTHONPATH): a kernel without Landlock.
_NO_LANDLOCK = """
from jointbench.running import landlock
landlock.abi_version = lambda: 0
"""


@pytest.mark.pipeline
def test_where_the_kernel_has_no_landlock_the_run_says_once_that_jobs_are_not_confined(
    tmp_path, monkeypatch
):
    copy_workflow(tmp_path)
    shim = tmp_path / "no_landlock"
    shim.mkdir()
    (shim / "sitecustomize.py").write_text(_NO_LANDLOCK)
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(shim), os.environ.get("PYTHONPATH", "")]))
    overlay = _cmc_only(tmp_path, estimators=["LS"], external_estimators=["centroid"])
    run = run_snakemake(tmp_path, "results/collected/cmc.parquet", "--configfile", overlay, "-n")
    message = run.stdout + run.stderr
    assert run.returncode == 0, message[-3000:]
    said = "this kernel has no Landlock (Linux 5.13 or later, enabled): the programs of external"
    assert message.count(said) == 1, message[-3000:]


def _shell_rule(shell) -> str:
    """The name of the rule whose jobs run with ``shell``, as its comment writes it (JSON): a
    name other than lower-case letters, digits and underscores is not its folder's."""
    (name,) = re.findall(
        r"^# The limited shell of the jobs of rule (.*), with ", shell.read_text(), re.M
    )
    return json.loads(name)


def _handed_down(tmp_path, grid, *, prepared: bool = False) -> dict[str, dict]:
    """What a dry run of cmc on ``grid`` with the external estimators centroid and LM hands
    the jobs of each rule of the user's in :data:`landlock.VARIABLE`, as the shell each rule's
    jobs run with sets it (``.snakemake/jointbench/shells/<rule>/bash``), by rule: the text
    and the confinement it holds. With ``prepared``, the centroid reads what a rule of the
    user's upstream of it (:data:`_PREPARE_RULE`) made of the blind copy, not the copy."""
    tmp_path.mkdir()
    copy_workflow(tmp_path)
    if prepared:
        rule = tmp_path / "workflow" / "rules" / "estimators" / "centroid.smk"
        template = rule.read_text()
        assert _BLIND_INPUT in template
        prepared_input = '"results/prepared/{study}/{condition}.parquet",'
        rule.write_text(template.replace(_BLIND_INPUT, prepared_input) + _PREPARE_RULE)
    overlay = _cmc_only(
        tmp_path, estimators=["LS"], external_estimators=["centroid", "LM"], grid=grid
    )
    run = run_snakemake(tmp_path, "results/collected/cmc.parquet", "--configfile", overlay, "-n")
    assert run.returncode == 0, (run.stdout + run.stderr)[-3000:]
    handed = {}
    for shell in (tmp_path / ".snakemake" / "jointbench" / "shells").glob("*/bash"):
        (text,) = re.findall(rf"{landlock.VARIABLE}=('[^']*')", shell.read_text())
        (text,) = shlex.split(text)
        handed[_shell_rule(shell)] = {"text": text, **json.loads(text)}
    return handed


@pytest.mark.pipeline
def test_what_the_jobs_are_handed_does_not_grow_with_the_conditions(tmp_path):
    """Linux refuses to start a program given an environment variable longer than 128 KiB:
    the variable names folders, not each condition's files, and is as long for one condition
    as for a grid of them. Each rule of the user's is handed its own folders, not another's."""
    one = {"marker_set": ["M"], "rom_deg": [15], "noise_mm": [1.0]}
    many = {"marker_set": ["M", "H"], "rom_deg": [5, 15, 45], "noise_mm": [0.5, 1.0, 2.0]}
    alone = _handed_down(tmp_path / "one", one)  # folders of one length
    grid = _handed_down(tmp_path / "all", many)
    assert set(grid) == set(alone) >= {"estimate_cmc_LM", "estimate_centroid"}, grid
    for rule, handed in grid.items():
        assert len(handed["text"]) == len(alone[rule]["text"]) < 4096, handed
        assert any(p.endswith("/results/blind") for p in handed["readable"]), handed
    lm, centroid = grid["estimate_cmc_LM"]["writable"], grid["estimate_centroid"]["writable"]
    assert any(p.endswith("/results/estimates/cmc/LM") for p in lm), lm
    assert not any(p.endswith("/results/estimates/cmc/LM") for p in centroid), centroid
    assert any(p.endswith("/results/estimates/cmc/centroid") for p in centroid), centroid
    assert not any("centroid" in p for p in lm), lm


@pytest.mark.pipeline
def test_a_checkout_where_the_rules_shells_cannot_be_written_still_lists_its_rules(tmp_path):
    """The shells of the user's rules are written as the workflow loads, also for a command
    that runs no job (``--list-rules``) in a checkout where they cannot be: it answers as
    before. A shell written earlier with another confinement, which cannot be replaced, stops
    the run naming it, as its jobs would run with the grant of another workflow."""
    copy_workflow(tmp_path)
    overlay = _cmc_only(tmp_path, estimators=["LS"], external_estimators=["centroid"])
    (tmp_path / ".snakemake").mkdir()
    (tmp_path / ".snakemake" / "jointbench").write_text("not a folder")
    run = run_snakemake(tmp_path, "--list-rules", "--configfile", overlay)
    assert run.returncode == 0, (run.stdout + run.stderr)[-3000:]
    assert "estimate_centroid" in run.stdout, run.stdout[-3000:]
    (tmp_path / ".snakemake" / "jointbench").unlink()
    stale = tmp_path / ".snakemake" / "jointbench" / "shells" / "estimate_centroid" / "bash"
    stale.mkdir(parents=True)  # in place of the file, which no rename then replaces
    run = run_snakemake(tmp_path, "results/collected/cmc.parquet", "-n", "--configfile", overlay)
    message = run.stdout + run.stderr
    assert run.returncode != 0, message[-3000:]
    assert f"{stale} cannot be replaced" in message, message[-3000:]
    assert "Building DAG of jobs" not in message, message[-3000:]


# Names Snakemake accepts for a rule (its ``name:`` directive takes any string): a line break
# followed by a command, a path up and out, a name longer than a file name may be, letters
# beyond ASCII, names one case apart (a plain one, and two that are not), quotes and a command
# substitution.
_ODD_NAMES = (
    "odd\ntouch INJECTED #",
    "../../../../escaped",
    "r" * 300,
    "Règle_ü",
    "Fold",
    "fold",
    "FOLD",
    "quote'\"$(touch INJECTED)",
)

_ODD_RULE = """

rule:
    name:
        {name!r}
    output:
        "results/odd{number}/made.txt",
    shell:
        "echo made > {{output}}"
"""


@pytest.mark.pipeline
def test_a_rule_of_any_name_snakemake_accepts_runs_in_a_shell_of_its_own(tmp_path):
    """Each rule of the user's gets its own shell, inside the folder of shells, whatever its
    name: the shell's text runs nothing of the name, its file name fits the file system, and
    two names one case apart do not share a folder on a file system blind to case. Each job
    runs with its rule's shell and makes its file."""
    workdir = tmp_path / "checkout"
    workdir.mkdir()
    copy_workflow(workdir)
    rules = workdir / "workflow" / "rules" / "estimators" / "odd.smk"
    rules.write_text(
        "".join(_ODD_RULE.format(name=name, number=i) for i, name in enumerate(_ODD_NAMES))
    )
    overlay = _cmc_only(workdir, estimators=["LS"])
    targets = [f"results/odd{i}/made.txt" for i in range(len(_ODD_NAMES))]
    run = run_snakemake(workdir, *targets, "--configfile", overlay)
    message = run.stdout + run.stderr
    assert run.returncode == 0, message[-3000:]
    for target in targets:
        assert (workdir / target).read_text() == "made\n", target
    assert not list(tmp_path.rglob("INJECTED")), "a rule's name ran as a command"
    assert not (tmp_path / "escaped").exists(), "a shell written outside its folder"
    shells = sorted((workdir / ".snakemake" / "jointbench" / "shells").glob("*/bash"))
    folders = [shell.parent.name for shell in shells]
    assert len({folder.casefold() for folder in folders}) == len(folders), folders
    assert all(len(folder.encode()) <= 255 for folder in folders), folders
    named = set()
    for shell in shells:
        named.add(_shell_rule(shell))
        assert not any(
            row and not row.startswith(("#", "case", "*", "esac", "exec "))
            for row in shell.read_text().splitlines()
        ), shell.read_text()
    assert set(_ODD_NAMES) <= named, named


# A rule of the user's that makes, from each blind copy, the file an external estimator reads.
_PREPARE_RULE = """

rule prepare_blind:
    input:
        "results/blind/{study}/{condition}.parquet",
    output:
        "results/prepared/{study}/{condition}.parquet",
    shell:
        "cp {input} {output}"
"""


@pytest.mark.pipeline
def test_what_a_rule_reads_from_another_of_the_users_is_handed_by_folder(tmp_path):
    """An estimator reading each condition's file of a rule of the user's upstream of it is
    handed that rule's folder to read, not each file, so that what it is handed does not grow
    with the conditions; the upstream rule is handed none of the estimator's folders."""
    one = {"marker_set": ["M"], "rom_deg": [15], "noise_mm": [1.0]}
    many = {"marker_set": ["M", "H"], "rom_deg": [5, 15, 45], "noise_mm": [0.5, 1.0, 2.0]}
    alone = _handed_down(tmp_path / "one", one, prepared=True)
    grid = _handed_down(tmp_path / "all", many, prepared=True)
    centroid, prepare = grid["estimate_centroid"], grid["prepare_blind"]
    assert len(centroid["text"]) == len(alone["estimate_centroid"]["text"]), centroid
    assert any(p.endswith("/results/prepared/cmc") for p in centroid["readable"]), centroid
    assert not any(p.endswith(".parquet") for p in centroid["readable"]), centroid
    assert any(p.endswith("/results/prepared/cmc") for p in prepare["writable"]), prepare
    assert not any("centroid" in p for p in (*prepare["readable"], *prepare["writable"])), prepare


@pytest.mark.pipeline
@pytest.mark.parametrize(
    "log",
    ["results/logs/estimate/{study}/centroid-{condition}.log", "results/{study}-{condition}.log"],
    ids=["beside-the-builtins-logs", "above-everything"],
)
def test_a_rule_writing_in_a_folder_of_the_benchmarks_is_refused_before_any_job(tmp_path, log):
    """Its job may write its file there, and so any file of the benchmark's in or below that
    folder (a built-in estimator's logs or estimates, the datasets): the run stops as it
    loads, naming the rule, the file and the folder."""
    copy_workflow(tmp_path)
    rule = tmp_path / "workflow" / "rules" / "estimators" / "centroid.smk"
    template = rule.read_text()
    declared = '"results/logs/estimate/{study}/centroid/{condition}.log"'
    assert declared in template
    rule.write_text(template.replace(declared, f'"{log}"'))
    overlay = _cmc_only(tmp_path, estimators=["LS"], external_estimators=["centroid"])
    run = run_snakemake(tmp_path, "results/collected/cmc.parquet", "--configfile", overlay, "-n")
    message = run.stdout + run.stderr
    assert run.returncode != 0, message[-3000:]
    assert "rule estimate_centroid writes its log results/" in message, message[-3000:]
    assert "a folder of its own" in message, message[-3000:]
    assert not (tmp_path / "results").exists()


def _cmc_only(tmp_path, **cmc) -> str:
    defaults = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    studies = {name: {"enabled": False} for name in defaults["studies"] if name != "cmc"}
    studies["cmc"] = {
        "trials": 2,
        "grid": {"marker_set": ["M"], "rom_deg": [15], "noise_mm": [1.0]},
        **cmc,
    }
    overlay = tmp_path / "overlay.yaml"
    overlay.write_text(yaml.safe_dump({"studies": studies}))
    return str(overlay)


@pytest.mark.pipeline
@pytest.mark.parametrize(
    "full",
    [
        '"results/datasets/',
        '"./results/datasets/',
        '"results/blind/../datasets/',
        'str(Path(workflow.basedir)) + "/results/datasets/',
    ],
    ids=["as-is", "dot-slash", "dot-dot", "absolute"],
)
def test_an_external_rule_given_the_full_dataset_stops_the_run_before_any_job(tmp_path, full):
    """However the rule spells the dataset file's path: Snakemake finds the file by it."""
    copy_workflow(tmp_path)
    rules = tmp_path / "workflow" / "rules" / "estimators"
    template = (rules / "centroid.smk").read_text()
    assert '"results/blind/{study}/{condition}.parquet"' in template
    (rules / "centroid.smk").write_text(template.replace('"results/blind/', full))
    overlay = _cmc_only(tmp_path, estimators=["LS"], external_estimators=["centroid"])
    run = run_snakemake(tmp_path, "--dry-run", "--configfile", overlay)
    assert run.returncode != 0
    message = "rule estimate_centroid (external estimator 'centroid') reads results/datasets/"
    assert message in run.stdout + run.stderr, run.stdout[-3000:] + run.stderr[-3000:]


# The template's input given as a function of the job's wildcards, as legitimate Snakemake.
_BLIND_INPUT = '"results/blind/{study}/{condition}.parquet",'
_INPUT_FUNCTION = 'lambda w: f"results/{folder}/{{w.study}}/{{w.condition}}.parquet",'


@pytest.mark.pipeline
def test_an_external_rule_reading_the_blind_file_through_an_input_function_runs(tmp_path):
    copy_workflow(tmp_path)
    rules = tmp_path / "workflow" / "rules" / "estimators"
    template = (rules / "centroid.smk").read_text()
    assert _BLIND_INPUT in template
    blind = _INPUT_FUNCTION.format(folder="blind")
    (rules / "centroid.smk").write_text(template.replace(_BLIND_INPUT, blind))
    overlay = _cmc_only(tmp_path, estimators=["LS"], external_estimators=["centroid"])
    run = run_snakemake(tmp_path, "--dry-run", "--configfile", overlay)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "estimate_centroid" in run.stdout


@pytest.mark.pipeline
@pytest.mark.parametrize(
    ("folder", "held"),
    [("datasets", "the truth"), ("placements", "the placement of each trial of a blind copy")],
)
def test_an_external_rule_given_the_benchmarks_file_by_an_input_function_stops_the_run(
    tmp_path, folder, held
):
    """The full dataset holds the truth; the placements map the answers back, and a program
    given them could move a constant answer into each trial's placed frame."""
    copy_workflow(tmp_path)
    rules = tmp_path / "workflow" / "rules" / "estimators"
    template = (rules / "centroid.smk").read_text()
    (rules / "centroid.smk").write_text(
        template.replace(_BLIND_INPUT, _INPUT_FUNCTION.format(folder=folder))
    )
    overlay = _cmc_only(tmp_path, estimators=["LS"], external_estimators=["centroid"])
    run = run_snakemake(tmp_path, "--dry-run", "--configfile", overlay)
    assert run.returncode != 0
    message = (
        "rule estimate_centroid (external estimator 'centroid') reads "
        f"results/{folder}/cmc/marker_set-M__rom_deg-15__noise_mm-1.0.parquet, which holds {held}"
    )
    assert message in run.stdout + run.stderr, run.stdout[-3000:] + run.stderr[-3000:]


# Files under results/ other than the blind copies, each of which gives the truth away: an
# estimates file holds each answer and its error (six answers and their distances trilaterate
# the centre), the collected results the same for every method, the poses the unplaced frame.
_PEEKS = {
    "estimates": 'lambda w: f"results/estimates/{w.study}/LS/{w.condition}.parquet",',
    "collected": '"results/collected/{study}.parquet",',
    "poses": '"results/poses/{study}/{condition}.parquet",',
}


@pytest.mark.pipeline
@pytest.mark.parametrize("peek", sorted(_PEEKS))
def test_an_external_rule_reading_any_other_file_of_the_benchmark_stops_the_run(tmp_path, peek):
    """What an external rule may read under results/ is listed (the blind copies), not what it
    may not: a file of scores names the truth as surely as the dataset."""
    copy_workflow(tmp_path)
    rules = tmp_path / "workflow" / "rules" / "estimators"
    template = (rules / "centroid.smk").read_text()
    assert _BLIND_INPUT in template
    (rules / "centroid.smk").write_text(
        template.replace(_BLIND_INPUT, _BLIND_INPUT + "\n            " + _PEEKS[peek])
    )
    overlay = _cmc_only(tmp_path, estimators=["LS"], external_estimators=["centroid"])
    run = run_snakemake(tmp_path, "--dry-run", "--configfile", overlay)
    assert run.returncode != 0
    message = f"rule estimate_centroid (external estimator 'centroid') reads results/{peek}/cmc"
    assert message in run.stdout + run.stderr, run.stdout[-3000:] + run.stderr[-3000:]
    assert "which holds what the benchmark made from the truth" in run.stdout + run.stderr


@pytest.mark.pipeline
def test_a_rule_parameter_named_like_the_source_digest_is_refused_by_rule(tmp_path):
    copy_workflow(tmp_path)
    rules = tmp_path / "workflow" / "rules" / "estimators"
    template = (rules / "centroid.smk").read_text()
    conda = '    conda:\n        "../../envs/jointbench.yaml"\n'
    assert conda in template
    (rules / "centroid.smk").write_text(
        template.replace(conda, conda + "    params:\n        sources=1,\n")
    )
    overlay = _cmc_only(tmp_path, estimators=["LS"], external_estimators=["centroid"])
    run = run_snakemake(tmp_path, "--dry-run", "--configfile", overlay)
    assert run.returncode != 0
    message = "rule estimate_centroid has a parameter named 'sources', a name the workflow"
    assert message in run.stdout + run.stderr, run.stdout[-3000:] + run.stderr[-3000:]


_LEAK_RULE = """

rule leak_truth:
    input:
        "results/datasets/{study}/{condition}.parquet",
    output:
        "results/leak/{study}/{condition}.parquet",
    shell:
        "cp {input} {output}"


rule pass_it_on:
    input:
        "results/leak/{study}/{condition}.parquet",
    output:
        "results/relay/{study}/{condition}.parquet",
    shell:
        "cp {input} {output}"
"""


@pytest.mark.pipeline
@pytest.mark.parametrize("hops", [1, 2])
def test_a_rule_upstream_of_an_external_estimator_may_not_read_the_truth(tmp_path, hops):
    """Laundering: a rule of the user's reads the full dataset and writes a file of its own,
    which the estimator's rule reads (directly, or through one more rule)."""
    copy_workflow(tmp_path)
    rules = tmp_path / "workflow" / "rules" / "estimators"
    template = (rules / "centroid.smk").read_text()
    folder = "leak" if hops == 1 else "relay"
    laundered = f'"results/{folder}/{{study}}/{{condition}}.parquet",'
    (rules / "centroid.smk").write_text(template.replace(_BLIND_INPUT, laundered) + _LEAK_RULE)
    overlay = _cmc_only(tmp_path, estimators=["LS"], external_estimators=["centroid"])
    run = run_snakemake(tmp_path, "--dry-run", "--configfile", overlay)
    assert run.returncode != 0
    chain = "rule leak_truth, which feeds rule estimate_centroid"
    if hops == 2:
        chain = "rule leak_truth, which feeds rule pass_it_on, which feeds rule estimate_centroid"
    message = f"{chain} (external estimator 'centroid') reads results/datasets/"
    assert message in run.stdout + run.stderr, run.stdout[-3000:] + run.stderr[-3000:]


def _refused(tmp_path, rules: str, estimator_input: str, message: str) -> None:
    """A dry run with ``rules`` added to the centroid's file and its input replaced by
    ``estimator_input`` stops before any job, printing ``message``."""
    folder = tmp_path / "workflow" / "rules" / "estimators"
    template = (folder / "centroid.smk").read_text()
    assert _BLIND_INPUT in template
    (folder / "centroid.smk").write_text(template.replace(_BLIND_INPUT, estimator_input) + rules)
    overlay = _cmc_only(tmp_path, estimators=["LS"], external_estimators=["centroid"])
    run = run_snakemake(tmp_path, "--dry-run", "--configfile", overlay)
    assert run.returncode != 0
    assert message in run.stdout + run.stderr, run.stdout[-3000:] + run.stderr[-3000:]
    # Refused while the workflow loads: no job was planned, let alone run.
    assert "Building DAG of jobs" not in run.stdout + run.stderr


_CONDITION = "marker_set-M__rom_deg-15__noise_mm-1.0"
_DATASET = f"results/datasets/cmc/{_CONDITION}.parquet"

# A rule of the user's that claims to write the datasets, which the package's rule still writes.
_DECOY = """

ruleorder: simulate_cmc > decoy


rule decoy:
    output:
        "results/datasets/{study}/{condition}.parquet",
    shell:
        "touch {output}"
"""


@pytest.mark.pipeline
def test_a_user_rule_writing_a_path_of_the_benchmarks_stops_the_run(tmp_path):
    """A decoy: the file would count as the user's own, and so readable."""
    copy_workflow(tmp_path)
    dataset = '"results/datasets/{study}/{condition}.parquet",'
    message = (
        "rule decoy writes results/datasets/{study}/{condition}.parquet, which rule "
        "simulate_cmc of the benchmark writes"
    )
    _refused(tmp_path, _DECOY, dataset, message)


# A rule of one rule file that writes another estimator's estimates, preferred to that
# estimator's own rule by a rule order: its answers would be ranked under the other's name.
_IMPOSTOR = """

ruleorder: impostor > estimate_centroid


rule impostor:
    input:
        "results/blind/{study}/{condition}.parquet",
    output:
        "results/estimates/{study}/centroid/{condition}.parquet",
    shell:
        "touch {output}"
"""


@pytest.mark.pipeline
def test_a_user_rule_writing_another_external_estimators_estimates_stops_the_run(tmp_path):
    copy_workflow(tmp_path)
    message = (
        "rules estimate_centroid and impostor both write the estimates of 'centroid' in study "
        "cmc (results/estimates/cmc/centroid/marker_set-M__rom_deg-15__noise_mm-1.0.parquet)"
    )
    _refused(tmp_path, _IMPOSTOR, _BLIND_INPUT, message)


@pytest.mark.pipeline
def test_rival_writers_name_the_config_file_that_lists_the_estimator(tmp_path):
    copy_workflow(tmp_path)
    rules = tmp_path / "workflow" / "rules" / "estimators" / "centroid.smk"
    rules.write_text(rules.read_text() + _IMPOSTOR)
    first = _cmc_only(tmp_path, estimators=["LS"], external_estimators=[])
    second = tmp_path / "second.yaml"
    second.write_text("studies: {cmc: {external_estimators: [centroid]}}\n")
    run = run_snakemake(tmp_path, "--dry-run", "--configfile", first, str(second))
    message = run.stdout + run.stderr
    assert run.returncode != 0, message[-3000:]
    for words in ("rules estimate_centroid and impostor both write", f"(set in {second})"):
        assert words in message, message[-3000:]


# A rule file in the package's folder, included by the user's: by its folder it would pass for
# the benchmark's own, and the copy it writes under results/blind/ for a blind one.
_COPY = """
rule copy_truth:
    input:
        "results/datasets/{study}/{condition}.parquet",
    output:
        "results/blind/prep/{study}/{condition}.parquet",
    shell:
        "cp {input} {output}"
"""


@pytest.mark.pipeline
def test_a_user_rule_file_in_the_packages_folder_is_still_the_users(tmp_path):
    copy_workflow(tmp_path)
    (tmp_path / "workflow" / "rules" / "prep.smk").write_text(_COPY)
    prepared = '"results/blind/prep/{study}/{condition}.parquet",'
    message = (
        "rule copy_truth writes results/blind/prep/{study}/{condition}.parquet, under "
        "results/blind/"
    )
    _refused(tmp_path, '\n\ninclude: "../prep.smk"\n', prepared, message)


@pytest.mark.pipeline
def test_an_external_rule_reading_through_a_symbolic_link_stops_the_run(tmp_path):
    copy_workflow(tmp_path)
    (tmp_path / "results" / "blind").mkdir(parents=True)
    (tmp_path / "results" / "blind" / "truth").symlink_to("../datasets")
    linked = '"results/blind/truth/{study}/{condition}.parquet",'
    message = (
        "rule estimate_centroid (external estimator 'centroid') reads "
        "results/blind/truth/cmc/marker_set-M__rom_deg-15__noise_mm-1.0.parquet, which holds "
        "whatever the symbolic link results/blind/truth leads to"
    )
    _refused(tmp_path, "", linked, message)


# A rule file's code runs in the workflow's namespace: these try to pass copy_truth (which
# writes under results/blind/) for a rule of the benchmark's, by adding its name to every set
# of rule names in reach, by rebinding each to one that holds it, and by rebinding the
# function that lists the rules.
_PASS_FOR_THE_BENCHMARKS = {
    "add": """
for _value in list(globals().values()):
    if isinstance(_value, set) and "simulate_cmc" in _value:
        _value.add("copy_truth")
""",
    "rebind": """
for _key, _value in list(globals().items()):
    if isinstance(_value, (set, frozenset)) and "simulate_cmc" in _value:
        globals()[_key] = _value | {"copy_truth"}
rule_names = lambda: set()
""",
}


@pytest.mark.pipeline
@pytest.mark.parametrize("how", sorted(_PASS_FOR_THE_BENCHMARKS))
def test_a_rule_file_cannot_pass_its_rule_for_the_benchmarks(tmp_path, how):
    copy_workflow(tmp_path)
    prepared = '"results/blind/prep/{study}/{condition}.parquet",'
    message = (
        "rule copy_truth writes results/blind/prep/{study}/{condition}.parquet, under "
        "results/blind/"
    )
    _refused(tmp_path, _COPY + _PASS_FOR_THE_BENCHMARKS[how], prepared, message)


# A rule of the user's claiming a file of the benchmark's (the collected results of a study)
# through a wildcard that may match nothing.
_EMPTY_SUFFIX = """

ruleorder: collect > decoy


rule decoy:
    input:
        "results/blind/{study}/marker_set-M__rom_deg-15__noise_mm-1.0.parquet",
    output:
        "results/collected/{study}{suffix,.*}.parquet",
    shell:
        "cp {input} {output}"
"""


@pytest.mark.pipeline
def test_a_user_rule_writing_a_path_of_the_benchmarks_through_an_empty_wildcard_stops_the_run(
    tmp_path,
):
    copy_workflow(tmp_path)
    message = (
        "rule decoy writes results/collected/{study}{suffix}.parquet, which rule collect of "
        "the benchmark writes"
    )
    _refused(tmp_path, _EMPTY_SUFFIX, _BLIND_INPUT, message)


# A rule of the user's writing any log of results/logs/, where every rule of the benchmark's
# writes its own.
_EVERY_LOG = """

rule every_log:
    output:
        "results/logs/{x}.log",
    shell:
        "touch {output}"
"""


@pytest.mark.pipeline
def test_a_user_rule_writing_files_of_many_of_the_benchmarks_rules_names_the_first(tmp_path):
    """The first of the benchmark's rules, in the order they are defined, and the first of its
    files the user's rule writes too."""
    copy_workflow(tmp_path)
    message = (
        "rule every_log writes results/logs/{x}.log, which rule simulate_cmc of the benchmark "
        "writes (results/logs/simulate/cmc.log)"
    )
    _refused(tmp_path, _EVERY_LOG, _BLIND_INPUT, message)


# A rule of the user's whose jobs read the blind file for one wildcard and the full dataset for
# another, the estimator's rule reading what both write.
_TWO_JOBS = f"""

rule either:
    input:
        lambda w: "results/blind/cmc/{_CONDITION}.parquet" if w.k == "a" else "{_DATASET}",
    output:
        "results/either/{{study}}/{{k}}.parquet",
    shell:
        "cp {{input}} {{output}}"
"""


@pytest.mark.pipeline
def test_each_job_of_a_rule_upstream_of_an_external_estimator_is_judged(tmp_path):
    copy_workflow(tmp_path)
    both = '"results/either/{study}/a.parquet", "results/either/{study}/b.parquet",'
    message = (
        "rule either, which feeds rule estimate_centroid (external estimator 'centroid') "
        f"reads {_DATASET}"
    )
    _refused(tmp_path, _TWO_JOBS, both, message)


# A rule of the user's writing one file from the full dataset, which the estimator's rule reads
# by a path with a final newline: a regular expression's $ takes it, so Snakemake finds the
# file's rule by it, and so must the checks.
_LEAK_ONE = f"""

rule leak_one:
    input:
        "{_DATASET}",
    output:
        "results/leak/all.parquet",
    shell:
        "cp {{input}} {{output}}"
"""


@pytest.mark.pipeline
def test_a_rule_upstream_found_by_a_path_with_a_final_newline_is_named(tmp_path):
    copy_workflow(tmp_path)
    newline = 'lambda w: "results/leak/all.parquet\\n",'
    message = (
        "rule leak_one, which feeds rule estimate_centroid (external estimator 'centroid') "
        f"reads {_DATASET}"
    )
    _refused(tmp_path, _LEAK_ONE, newline, message)


# A rule of the user's whose wildcard constraint is no regular expression: an unclosed set, and
# a constraint given again where the wildcard recurs, which Snakemake refuses to match with.
_BAD_CONSTRAINTS = {
    "unclosed": ("results/mine/{x,[a-}.txt", "bad character range"),
    "twice": ("results/mine/{x,a+}/{x,b+}.txt", "Constraint regex must be defined only"),
}
_MISSPELT = """

rule misspelt:
    output:
        "{output}",
    shell:
        "touch {{output}}"
"""


@pytest.mark.pipeline
@pytest.mark.parametrize("case", sorted(_BAD_CONSTRAINTS))
def test_a_user_rule_whose_wildcard_constraint_is_no_regular_expression_is_named(tmp_path, case):
    """Named with its rule and file, not as the bare error of Python's regular expressions."""
    output, why = _BAD_CONSTRAINTS[case]
    copy_workflow(tmp_path)
    message = (
        f"rule misspelt writes {output}, whose wildcard constraint is no regular expression ({why}"
    )
    _refused(tmp_path, _MISSPELT.format(output=output), _BLIND_INPUT, message)


# A rule of the user's writing under results/blind/ by its output, log or benchmark file,
# however the path is spelt: the process's own link to the working directory, a link at the
# top of the repository (``shortcut``, to results/), a folder of its own and back.
_SNEAK = """

rule sneak:
    input:
        "results/blind/{{study}}/{{condition}}.parquet",
    output:
        "{output}",
    log:
        "{log}",
    benchmark:
        "{benchmark}"
    shell:
        "cp {{input}} {{output}}"
"""
_MINE = "results/mine/{study}/{condition}"
_SNEAKS = {
    "output-proc": "/proc/self/cwd/results/blind/x/{study}/{condition}",
    "log-proc": "/proc/self/cwd/results/blind/x/{study}/{condition}",
    "benchmark": "results/blind/x/{study}/{condition}",
    "benchmark-link": "shortcut/blind/x/{study}/{condition}",
    "log-dot-dot": "results/mine/../blind/x/{study}/{condition}",
}
_ENDINGS = {"output": ".parquet", "log": ".log", "benchmark": ".tsv"}


@pytest.mark.pipeline
@pytest.mark.parametrize("sneak", sorted(_SNEAKS))
def test_a_user_rule_writing_under_the_blind_copies_by_any_path_stops_the_run(tmp_path, sneak):
    copy_workflow(tmp_path)
    (tmp_path / "shortcut").symlink_to("results")
    where = sneak.split("-")[0]
    paths = {kind: _MINE + ending for kind, ending in _ENDINGS.items()}
    paths[where] = _SNEAKS[sneak] + _ENDINGS[where]
    message = (
        f"rule sneak writes results/blind/x/{{study}}/{{condition}}{_ENDINGS[where]}, "
        "under results/blind/"
    )
    _refused(tmp_path, _SNEAK.format(**paths), _BLIND_INPUT, message)


# An external rule's input reaching the truth by its real path: the process's own link to the
# working directory, a link at the top of the repository, or a folder holding results/ whole.
_PROC = "/proc/self/cwd/" + _DATASET
_SHORTCUT = _DATASET.replace("results/", "shortcut/", 1)
_REACHES = {
    "proc": ('"/proc/self/cwd/results/datasets/{study}/{condition}.parquet",', _PROC),
    "link": ('"shortcut/datasets/{study}/{condition}.parquet",', _SHORTCUT),
    "dot": ('".",', "."),
    "root": ("str(Path(workflow.basedir)),", "."),
    "results": ('"results",', "results"),
}


@pytest.mark.pipeline
@pytest.mark.parametrize("reach", sorted(_REACHES))
def test_an_external_rule_reaching_the_truth_by_its_real_path_stops_the_run(tmp_path, reach):
    copy_workflow(tmp_path)
    (tmp_path / "shortcut").symlink_to("results")
    estimator_input, spelt = _REACHES[reach]
    real = "" if spelt in (".", "results") else f" (its real path {_DATASET})"
    held = "the truth" if real else "results/, and so the truth"
    message = (
        f"rule estimate_centroid (external estimator 'centroid') reads {spelt}{real}, "
        f"which holds {held}"
    )
    _refused(tmp_path, "", estimator_input, message)


# A rule of the user's whose output folder is the working directory: it holds results/ and so
# every file of the benchmark's, which Snakemake would clear before running it.
_EVERYTHING = """

rule everything:
    output:
        directory("."),
    shell:
        "true"
"""


@pytest.mark.pipeline
def test_a_user_rule_writing_the_folder_that_holds_results_stops_the_run(tmp_path):
    copy_workflow(tmp_path)
    message = "rule everything writes {inside}, under results/blind/"
    _refused(tmp_path, _EVERYTHING, _BLIND_INPUT, message)


# A file of the user's, written by a rule that reads the truth, spelt the way Snakemake matches
# it but not as the checks judge it: an absolute path, a folder reached through "..", or the
# estimator's own rule in another job (an input function choosing by a wildcard).
_LAUNDERED = {
    "absolute path": (
        'os.path.abspath("results/mine") + "/{study}/{condition}.parquet",',
        """

rule stage_truth:
    input:
        "results/datasets/{study}/{condition}.parquet",
    output:
        os.path.abspath("results/mine") + "/{study}/{condition}.parquet",
    shell:
        "cp {input} {output}"
""",
        "rule stage_truth, which feeds rule estimate_centroid",
    ),
    "a wildcard taking ..": (
        '"results/mine/../blind/{study}/{condition}.parquet",',
        """

rule write_over_blind:
    input:
        "results/datasets/{study}/{condition}.parquet",
    output:
        "results/mine/{x}/{study}/{condition}.parquet",
    shell:
        "cp {input} {output}"
""",
        "rule write_over_blind, which feeds rule estimate_centroid",
    ),
}


@pytest.mark.pipeline
@pytest.mark.parametrize("spelling", sorted(_LAUNDERED))
def test_a_truth_reading_rule_upstream_is_found_however_the_path_is_spelt(tmp_path, spelling):
    copy_workflow(tmp_path)
    estimator_input, rules, chain = _LAUNDERED[spelling]
    message = f"{chain} (external estimator 'centroid') reads results/datasets/"
    _refused(tmp_path, rules, estimator_input, message)


_OWN_UPSTREAM = """


def _centroid_or_truth(wildcards):
    if wildcards.folder == "results/estimates":
        return f"results/mine/{wildcards.study}/centroid/{wildcards.condition}.parquet"
    return f"results/datasets/{wildcards.study}/{wildcards.condition}.parquet"


rule estimate_centroid:
    input:
        _centroid_or_truth,
    output:
        "{folder,results/estimates|results/mine}/{study}/centroid/{condition}.parquet",
    shell:
        "cp {input} {output}"
"""


@pytest.mark.pipeline
def test_an_estimators_rule_that_is_its_own_upstream_is_followed(tmp_path):
    """The estimator's rule, in a job writing a file of the user's, reads the truth and feeds
    itself in the job writing the estimates."""
    copy_workflow(tmp_path)
    rules = tmp_path / "workflow" / "rules" / "estimators"
    (rules / "centroid.smk").write_text(_OWN_UPSTREAM)
    overlay = _cmc_only(tmp_path, estimators=["LS"], external_estimators=["centroid"])
    run = run_snakemake(tmp_path, "--dry-run", "--configfile", overlay)
    assert run.returncode != 0
    message = "rule estimate_centroid, which feeds rule estimate_centroid (external estimator"
    assert message in run.stdout + run.stderr, run.stdout[-3000:] + run.stderr[-3000:]


# A rule of the user's writing outside results/, by its output, log or benchmark file: over the
# configuration, the package's code, or anything a later job or run reads. (kind of file, its
# path as written, its real path relative to the working directory, or None for one outside it,
# which the test finds)
_OUTSIDE = {
    "config": ("output", "config/x/{study}/{condition}.yaml", "config/x/{study}/{condition}.yaml"),
    "parent": ("output", "../outside/{study}/{condition}.txt", None),
    "absolute": ("log", "/tmp/jointbench-outside/{study}/{condition}.log", None),
    "dot-dot": ("benchmark", "results/../src/{study}/{condition}.py", "src/{study}/{condition}.py"),
    "link": (
        "output",
        "results/linked/{study}/{condition}.yaml",
        "config/{study}/{condition}.yaml",
    ),
    "a wildcard's names": (
        "output",
        "{where,results/mine|config}/{study}/{condition}.yaml",
        "{where}/{study}/{condition}.yaml",
    ),
}


@pytest.mark.pipeline
@pytest.mark.parametrize("outside", sorted(_OUTSIDE))
def test_a_user_rule_writing_outside_results_stops_the_run_before_any_job(tmp_path, outside):
    """However the path is spelt: each is judged by its real path, a link inside results/ to
    the configuration too."""
    copy_workflow(tmp_path)
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "linked").symlink_to("../config")
    kind, written, real = _OUTSIDE[outside]
    real = real or os.path.realpath(tmp_path / written)
    # As written, the wildcards without their constraints.
    as_written = re.sub(r"\{(\w+),[^}]*\}", r"{\1}", written)
    shown = as_written if real == as_written else f"{as_written} (its real path {real})"
    message = (
        f"rule sneak (workflow/rules/estimators/centroid.smk) writes its {kind} {shown}, "
        "outside results/"
    )
    # The rule's other files, in a folder of its own, with the same wildcards (as Snakemake
    # requires).
    extra = [n for n in re.findall(r"\{(\w+)", written) if n not in ("study", "condition")]
    mine = _MINE + "".join(f"-{{{name}}}" for name in extra)
    paths = {other: mine + ending for other, ending in _ENDINGS.items()}
    _refused(tmp_path, _SNEAK.format(**{**paths, kind: written}), _BLIND_INPUT, message)


# A rule of the user's whose output's wildcard is given a value climbing out of results/ by an
# input of the user's: its pattern lies under results/, the job's file in config/.
_CLIMB = """

rule climb:
    output:
        "results/mine/{x}.yaml",
    shell:
        "touch {output}"


rule ask:
    input:
        "results/mine/../../config/x.yaml",
    output:
        "results/mine/asked.txt",
    shell:
        "touch {output}"
"""


@pytest.mark.pipeline
def test_a_job_of_a_user_rule_whose_wildcard_climbs_out_of_results_stops_before_any_job(
    tmp_path,
):
    copy_workflow(tmp_path)
    rules = tmp_path / "workflow" / "rules" / "estimators"
    (rules / "centroid.smk").write_text((rules / "centroid.smk").read_text() + _CLIMB)
    overlay = _cmc_only(tmp_path, estimators=["LS"], external_estimators=["centroid"])
    run = run_snakemake(tmp_path, "results/mine/asked.txt", "--configfile", overlay)
    assert run.returncode != 0
    message = (
        "rule climb (workflow/rules/estimators/centroid.smk) writes its output "
        "results/mine/../../config/x.yaml (its real path config/x.yaml), outside results/"
    )
    assert message in run.stdout + run.stderr, run.stdout[-3000:] + run.stderr[-3000:]
    assert not (tmp_path / "config" / "x.yaml").exists()
    assert not (tmp_path / "results" / "mine").exists()
