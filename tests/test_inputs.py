"""Inputs that cannot lie: estimator failures, estimates files checked against their datasets
and scored by the benchmark, not by themselves, corrupt intermediate files named."""

from __future__ import annotations

import dataclasses
import os
import re
import shlex
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from test_extension import CENTROID_SCRIPT, user_clone
from workflow_copy import SNAKEMAKE, run_snakemake

from jointbench import invocation, pipeline
from jointbench.configuration import config as study_config
from jointbench.estimators import registry
from jointbench.estimators.batching import ProgrammingError
from jointbench.estimators.results import CenterResult
from jointbench.figures import extended
from jointbench.papers import get_paper
from jointbench.resultfiles.parquet import (
    iter_dataset,
    read_dataset,
    read_metadata,
    read_table,
    read_trial_numbers,
    write_dataset,
    write_table,
)
from jointbench.resultfiles.schema import check_against_dataset
from jointbench.running.collected import collect
from jointbench.running.placement import dataset_placements, write_placements
from jointbench.running.run import estimate, simulate_condition
from jointbench.running.scoring import score_columns

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def config():
    small = study_config.load_config(ROOT / "config" / "config.yaml")
    small["studies"]["cmc"]["trials"] = 2
    return small


@pytest.fixture(scope="module")
def cmc_trials(config):
    condition = study_config.conditions(config, "cmc")[0]
    return condition, simulate_condition(config, "cmc", condition)


@pytest.fixture
def raising_estimator():
    """Register a centre estimator raising the given exception; yields a setter of it."""
    raised = {}

    def fails(markers):
        raise raised["error"]

    registry.register("center", "raises")(fails)
    yield lambda error: raised.__setitem__("error", error) or "raises"
    registry.unregister("center", "raises")


@pytest.mark.parametrize(
    "error",
    [
        ValueError("markers do not move"),
        np.linalg.LinAlgError("Singular matrix"),
        FloatingPointError("overflow encountered"),
    ],
    ids=lambda e: type(e).__name__,
)
def test_numerical_failure_becomes_a_failed_row(cmc_trials, raising_estimator, error):
    condition, trials = cmc_trials
    frame = estimate("cmc", raising_estimator(error), trials, condition)
    assert len(frame) == 2 and not frame["converged"].any()
    assert frame["status"].str.startswith(f"error: {type(error).__name__}: ").all()
    assert frame["error_mm"].isna().all()


@pytest.mark.parametrize(
    "error",
    [TypeError("fits() got an unexpected keyword argument"), KeyError("x"), AttributeError("y")],
    ids=lambda e: type(e).__name__,
)
def test_programming_error_stops_the_run(cmc_trials, raising_estimator, error):
    condition, trials = cmc_trials
    with pytest.raises(ProgrammingError, match="cmc raises: ") as raised:
        estimate("cmc", raising_estimator(error), trials, condition)
    assert raised.value.__cause__ is error


@pytest.fixture
def batched_estimator():
    """Register a centre estimator whose batched form returns the given per-trial outcomes."""
    outcomes = {}

    def fits(markers):
        raise AssertionError("the batched form is used")

    registry.register("center", "batched-outcomes", many=lambda markers: outcomes["value"])(fits)
    yield lambda value: outcomes.__setitem__("value", value) or "batched-outcomes"
    registry.unregister("center", "batched-outcomes")


def test_a_batched_numerical_failure_becomes_a_failed_row(cmc_trials, batched_estimator):
    condition, trials = cmc_trials
    ok = CenterResult(center=np.zeros(3), converged=True, iterations=1, status="ok", method="b")
    name = batched_estimator([np.linalg.LinAlgError("Singular matrix"), ok])
    frame = estimate("cmc", name, trials, condition)
    assert list(frame["status"]) == ["error: LinAlgError: Singular matrix", "ok"]


def test_a_batched_programming_error_stops_the_run(cmc_trials, batched_estimator):
    condition, trials = cmc_trials
    ok = CenterResult(center=np.zeros(3), converged=True, iterations=1, status="ok", method="b")
    name = batched_estimator([ok, TypeError("unsupported operand")])
    with pytest.raises(ProgrammingError, match="cmc batched-outcomes: TypeError: unsupported"):
        estimate("cmc", name, trials, condition)


def test_an_option_the_estimator_does_not_take_stops_the_run(cmc_trials):
    condition, trials = cmc_trials
    with pytest.raises(ProgrammingError, match=r"cmc NM: TypeError: .*'tolerance'"):
        estimate("cmc", "NM", trials, condition, {"tolerance": 1e-3})


# ------------------------------------------------- estimates files held to their datasets


@pytest.fixture
def estimates_and_dataset(tmp_path, config, cmc_trials):
    """A cmc dataset file of two trials and NM's estimates file of the same condition."""
    condition, trials = cmc_trials
    name = f"{study_config.condition_id(condition)}.parquet"
    dataset = tmp_path / "datasets" / "cmc" / name
    write_dataset(dataset, trials, study="cmc", condition=condition)
    estimates = tmp_path / "estimates" / "cmc" / "NM" / name
    write_table(estimate("cmc", "NM", trials, condition), estimates)
    return estimates, dataset


def rewrite(path, change):
    """Apply ``change`` to the table at ``path`` in place."""
    write_table(change(pd.read_parquet(path)), path)


def test_a_matching_estimates_file_is_collected(tmp_path, estimates_and_dataset):
    estimates, dataset = estimates_and_dataset
    collected = collect("cmc", [estimates], str(tmp_path / "c.parquet"), datasets=[dataset])
    assert sorted(collected["trial"]) == [0, 1]


LIES = {
    "missing trial": (lambda f: f[f["trial"] != 1], "missing trials: 1; the dataset has 2 trials"),
    "trial twice": (lambda f: pd.concat([f, f.iloc[[0]]]), "trials listed more than once: 0"),
    "invented trial": (
        lambda f: f.assign(trial=[0, 7]),
        "missing trials: 1; trials not in the dataset: 7; the dataset has 2 trials (0, 1)",
    ),
    "invented condition": (
        lambda f: f.assign(rom_deg=999),
        "column 'rom_deg' must be the dataset's 5 (int) in every row, got 999 (int)",
    ),
    "no rows": (lambda f: f.iloc[:0], "no rows; the dataset has 2 trials (0, 1)"),
}


@pytest.mark.parametrize("lie", LIES)
def test_an_estimates_file_that_lies_is_named(tmp_path, estimates_and_dataset, lie):
    estimates, dataset = estimates_and_dataset
    change, message = LIES[lie]
    rewrite(estimates, change)
    with pytest.raises(ValueError) as error:
        collect("cmc", [estimates], str(tmp_path / "c.parquet"), datasets=[dataset])
    assert str(error.value).startswith(f"{estimates}: ")
    assert message in str(error.value)
    assert not (tmp_path / "c.parquet").exists()


def test_five_and_five_point_zero_are_one_condition_value(tmp_path, estimates_and_dataset):
    estimates, dataset = estimates_and_dataset
    rewrite(estimates, lambda f: f.assign(rom_deg=f["rom_deg"].astype(float)))
    collect("cmc", [estimates], str(tmp_path / "c.parquet"), datasets=[dataset])


def test_a_text_condition_value_is_not_the_number(tmp_path, estimates_and_dataset):
    estimates, dataset = estimates_and_dataset
    rewrite(estimates, lambda f: f.assign(rom_deg="5"))
    # The text '5' and the number 5 print alike: the message shows which is which.
    message = "column 'rom_deg' must be the dataset's 5 (int) in every row, got '5' (str)"
    with pytest.raises(ValueError, match=re.escape(message)):
        collect("cmc", [estimates], str(tmp_path / "c.parquet"), datasets=[dataset])


def test_long_trial_lists_are_shortened(tmp_path, estimates_and_dataset):
    estimates, _ = estimates_and_dataset
    frame = pd.read_parquet(estimates)
    many = pd.concat([frame.iloc[[0]].assign(trial=t) for t in range(2, 40, 3)])
    with pytest.raises(ValueError, match=r"not in the dataset: 2, 5, .*, 29, … \(13 in all\)"):
        check_against_dataset(
            pd.concat([frame, many]), trials=[0, 1], condition={}, source=str(estimates)
        )


# ----------------------------------------------------------- unreadable intermediate files


def truncate(path: Path) -> None:
    """Cut a file to half its length, keeping its modification time (an interrupted copy)."""
    stat = path.stat()
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns))


def read_blocks(path):
    return list(iter_dataset(path))


@pytest.mark.parametrize(
    "read", [read_dataset, read_blocks, read_metadata, read_trial_numbers, read_table]
)
def test_a_truncated_file_is_named_with_the_command_that_regenerates_it(
    estimates_and_dataset, read
):
    _, dataset = estimates_and_dataset
    truncate(dataset)
    with pytest.raises(ValueError) as error:
        read(dataset)
    message = str(error.value)
    assert message.startswith(f"{dataset}: cannot be read as parquet (ArrowInvalid")
    assert f"snakemake -j2 --forcerun {dataset}" in message
    assert dataset.exists()


@pytest.mark.parametrize(
    ("argv", "options"),
    [
        (
            ["results/collected/cmc.parquet", "-j2", "--configfile", "my.yaml"],
            ["--configfile", "my.yaml", "--jobs", "2"],
        ),
        (
            ["--profile", "profiles/slurm", "--configfile", "a.yaml", "b.yaml", "--dry-run"],
            ["--configfile", "a.yaml", "b.yaml", "--profile", "profiles/slurm"],
        ),
        (
            ["--config", "jobs={'estimate': 'per_condition'}", "-d", "run", "--forcerun", "x"],
            ["-j2", "--directory", "run", "--config", "jobs={'estimate': 'per_condition'}"],
        ),
        (["--cores=4", "-s", "other.smk", "-n"], ["--snakefile", "other.smk", "--cores", "4"]),
    ],
    ids=["configfile", "profile", "config and directory", "cores and snakefile"],
)
def test_the_options_a_follow_up_command_repeats(argv, options):
    assert invocation.workflow_options(argv) == options


def test_the_regenerating_command_keeps_the_users_options_and_quotes_paths():
    environ = {}
    invocation.record(["study_cmc", "-j2", "--configfile", "my config.yaml"], environ)
    command = invocation.snakemake_command("--forcerun", "results/a b.parquet", environ=environ)
    assert (
        command
        == "snakemake --configfile 'my config.yaml' --jobs 2 --forcerun 'results/a b.parquet'"
    )
    # A job of a cluster re-reads the rules under its own command line: the user's is kept.
    invocation.record(["--snakefile", "/abs/Snakefile", "--mode", "remote"], environ)
    assert environ[invocation.ENVIRONMENT_VARIABLE] == "--configfile 'my config.yaml' --jobs 2"
    assert invocation.snakemake_command("--forcerun", "x", environ={}) == (
        "snakemake -j2 --forcerun x"
    )


def test_a_truncated_file_is_named_with_the_runs_own_options(estimates_and_dataset, monkeypatch):
    _, dataset = estimates_and_dataset
    truncate(dataset)
    monkeypatch.setenv(invocation.ENVIRONMENT_VARIABLE, "--configfile my.yaml --jobs 2")
    with pytest.raises(ValueError) as error:
        read_dataset(dataset)
    assert f"snakemake --configfile my.yaml --jobs 2 --forcerun {dataset}" in str(error.value)


def test_a_missing_file_is_named(tmp_path):
    with pytest.raises(ValueError, match=r"nowhere\.parquet: cannot be read as parquet"):
        read_dataset(tmp_path / "nowhere.parquet")


def test_collect_names_a_truncated_estimates_file(tmp_path, estimates_and_dataset):
    estimates, dataset = estimates_and_dataset
    truncate(estimates)
    with pytest.raises(ValueError, match=f"^{re.escape(str(estimates))}: cannot be read"):
        collect("cmc", [estimates], str(tmp_path / "c.parquet"), datasets=[dataset])


# ---------------------------------------------------------------------------- end to end

DATASET = "results/datasets/cmc/marker_set-M__rom_deg-5__noise_mm-1.0.parquet"


def cmc_clone(destination: Path, *, estimators, external=(), centroid_script=None) -> list[str]:
    """The workflow copied to ``destination`` with a two-condition, two-trial cmc grid (the
    shipped centroid template's script replaced by ``centroid_script`` if given); returns the
    Snakemake arguments selecting that config."""
    overlay = user_clone(
        destination,
        estimators=list(estimators),
        external=list(external),
        centroid_script=centroid_script,
    )
    return ["--configfile", str(overlay)]


@pytest.mark.pipeline
def test_a_truncated_dataset_is_named_logged_and_regenerated(tmp_path):
    config = cmc_clone(tmp_path, estimators=["LS"])
    assert run_snakemake(tmp_path, DATASET, *config).returncode == 0
    truncate(tmp_path / DATASET)

    failed = run_snakemake(tmp_path, "results/collected/cmc.parquet", *config)
    assert failed.returncode != 0
    message = f"{DATASET}: cannot be read as parquet"
    assert message in failed.stdout + failed.stderr
    log = (tmp_path / "results/logs/estimate/cmc/LS.log").read_text()
    assert message in log
    assert (tmp_path / DATASET).exists()  # nothing removed: the user decides

    # The command the message prints, as printed: it must run this config, not the default one
    # (whose grid has nine times the conditions).
    printed = re.search(r"Regenerate it and what depends on it with: (snakemake .*)", log)[1]
    assert f"--configfile {config[1]}" in printed
    program, *options = shlex.split(printed)
    assert program == "snakemake"
    # The target first: --forcerun takes every word after it.
    again = subprocess.run(
        [str(SNAKEMAKE), "results/collected/cmc.parquet", *options],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert again.returncode == 0, again.stderr[-3000:]
    read_dataset(tmp_path / DATASET)
    assert len(pd.read_parquet(tmp_path / "results/collected/cmc.parquet")) == 2 * 2


@pytest.mark.pipeline
@pytest.mark.parametrize(
    ("lie", "message"),
    [
        ("rows[1:]", "missing trials: 0; the dataset has 2 trials (0, 1)"),
        ("[{**r, 'rom_deg': 999} for r in rows]", "column 'rom_deg' must be the dataset's 5"),
    ],
    ids=["trial missing", "condition invented"],
)
def test_an_external_estimator_that_lies_stops_collect(tmp_path, lie, message):
    shipped = (ROOT / CENTROID_SCRIPT).read_text()
    script = shipped.replace("pd.DataFrame(rows)", f"pd.DataFrame({lie})")
    assert script != shipped
    config = cmc_clone(tmp_path, estimators=["LS"], external=["centroid"], centroid_script=script)
    run = run_snakemake(tmp_path, "results/collected/cmc.parquet", *config)
    assert run.returncode != 0
    named = (
        f"results/estimates/cmc/centroid/marker_set-M__rom_deg-5__noise_mm-1.0.parquet: {message}"
    )
    assert named in run.stdout + run.stderr, (run.stdout + run.stderr)[-3000:]
    assert named in (tmp_path / "results/logs/collect/cmc.log").read_text()
    assert not (tmp_path / "results/collected/cmc.parquet").exists()


# ------------------------------------- every estimate scored by the benchmark, not by itself


def estimates_of(path: Path, method: str) -> Path:
    """The estimates file of ``method`` for the condition of estimates file ``path``."""
    return path.parent.parent / method / path.name


def test_a_file_reporting_half_its_error_is_named_with_the_trial(tmp_path, estimates_and_dataset):
    estimates, dataset = estimates_and_dataset
    rewrite(estimates, lambda f: f.assign(error_mm=f["error_mm"] * [1.0, 0.5]))
    with pytest.raises(ValueError) as error:
        collect("cmc", [estimates], str(tmp_path / "c.parquet"), datasets=[dataset])
    assert str(error.value).startswith(f"{estimates}: trial 1: column 'error_mm' is ")
    assert "1 of 2 rows disagree" in str(error.value)
    assert not (tmp_path / "c.parquet").exists()


def test_a_file_without_errors_is_ranked_by_its_true_error(tmp_path, estimates_and_dataset):
    estimates, dataset = estimates_and_dataset
    nm = pd.read_parquet(estimates)
    # 50 mm farther from the truth than NM, and silent about it.
    far = estimates_of(estimates, "far")
    write_table(
        nm.assign(method="far", center_x=nm["center_x"] + 50.0).drop(columns="error_mm"), far
    )
    # An estimator outside the package: its answers are mapped back from its blind copy's frame.
    placements = tmp_path / "placements" / dataset.name
    write_placements(placements, dataset_placements(dataset, base_seed=1))
    collected = collect(
        "cmc", [estimates, far], str(tmp_path / "c.parquet"), [dataset], placements=[placements]
    )
    truth = np.asarray(read_metadata(dataset)["truth"]["center"])
    rows = collected[collected["method"] == "far"]
    expected = np.linalg.norm(rows[["center_x", "center_y", "center_z"]].to_numpy() - truth, axis=1)
    np.testing.assert_allclose(rows["error_mm"], expected, rtol=1e-12)
    table = extended.extended_table(collected, "cmc").set_index("method")
    assert table.loc["NM", "rank"] == 1 and table.loc["far", "rank"] == 2


@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf], ids=["nan", "inf", "-inf"])
@pytest.mark.parametrize("claim", [(True, "ok"), (True, "done"), (False, "ok")], ids=str)
def test_a_non_finite_estimate_claiming_success_is_refused_by_name(
    tmp_path, estimates_and_dataset, value, claim
):
    estimates, dataset = estimates_and_dataset

    def claims(frame):
        frame.loc[1, ["center_y", "error_mm"]] = value
        frame.loc[1, ["converged", "status"]] = claim
        return frame

    rewrite(estimates, claims)
    with pytest.raises(ValueError) as error:
        collect("cmc", [estimates], str(tmp_path / "c.parquet"), datasets=[dataset])
    message = str(error.value)
    assert message.startswith(f"{estimates}: method 'NM', trial 1: converged={claim[0]}")
    assert f"center_y={value!r}" in message and "not finite" in message


def test_a_non_finite_estimate_of_a_failed_trial_is_collected(tmp_path, estimates_and_dataset):
    estimates, dataset = estimates_and_dataset
    rewrite(
        estimates,
        lambda f: f.assign(
            center_y=f["center_y"].where(f["trial"] != 1), converged=False, status="no fit"
        ).drop(columns="error_mm"),
    )
    collected = collect("cmc", [estimates], str(tmp_path / "c.parquet"), datasets=[dataset])
    assert collected["error_mm"].isna().tolist() == [False, True]


def test_estimates_far_off_have_their_true_error():
    center = {"center_x": [1e300], "center_y": [0.0], "center_z": [0.0]}
    assert score_columns("center", center, {"center": [1.0, 2.0, 3.0]})["error_mm"] == [1e300]
    # A direction is a direction whatever its length: 1e300 along x and y is 45° from x.
    directions = {f"direction_{a}": [1e300, 1e-300, 0.0] for a in "xy"}
    axis = {**dict.fromkeys(["point_x", "point_y", "point_z"], [0.0] * 3), **directions}
    axis["direction_z"] = [0.0, 0.0, 0.0]
    errors = score_columns("axis", axis, {"axis_direction": [1.0, 0.0, 0.0]})["error_deg"]
    np.testing.assert_allclose(errors[:2], 45.0)
    assert np.isnan(errors[2])  # a zero vector has no direction


def all_failed(frame: pd.DataFrame, methods) -> pd.DataFrame:
    """``frame`` with every trial of ``methods`` failed: no estimate, the reason in status."""
    rows = frame["method"].isin(methods)
    frame = frame.copy()
    frame.loc[rows, ["center_x", "center_y", "center_z", "error_mm"]] = np.nan
    frame.loc[rows, ["converged", "status"]] = (False, "error: ValueError: too few frames")
    return frame


def test_a_study_whose_every_trial_failed_is_not_collected(tmp_path, estimates_and_dataset):
    estimates, dataset = estimates_and_dataset
    rewrite(estimates, lambda f: all_failed(f, ["NM"]))
    output = tmp_path / "c.parquet"
    with pytest.raises(ValueError) as error:
        collect("cmc", [estimates], str(output), datasets=[dataset])
    assert str(error.value).startswith(
        f"{output}: study 'cmc': none of its 2 trials (NM) has a finite error_mm"
    )
    assert "2 × 'error: ValueError: too few frames'" in str(error.value)
    assert not output.exists()


@pytest.mark.parametrize(
    ("failed", "message"),
    [
        (["NM", "BC"], "study 'cmc': none of its 4 trials (BC, NM) has a finite error_mm"),
        (["BC"], "study 'cmc': every trial of BC failed (no finite error_mm)"),
    ],
    ids=["every method", "a paper's method"],
)
def test_nothing_is_rendered_or_judged_from_trials_that_all_failed(
    tmp_path, config, estimates_and_dataset, failed, message
):
    estimates, _ = estimates_and_dataset
    nm = pd.read_parquet(estimates)
    path = tmp_path / "collected.parquet"
    write_table(all_failed(pd.concat([nm, nm.assign(method="BC")]), failed), path)
    with pytest.raises(ValueError, match=re.escape(f"{path}: {message}")):
        pipeline.render_study("cmc", {}, str(path), [], {}, config)
    with pytest.raises(ValueError, match=re.escape(f"{path}: {message}")):
        pipeline.comparison({"cmc": str(path)}, config)


@pytest.mark.parametrize(
    ("after_a5", "message"),
    [
        (0, "no entry for A5, A6, A7, A8, A9, A10, A11, A12, A13, which the paper measures"),
        # Inside A5's criterion, a quoted text that the cut leaves open.
        (7, "not valid YAML"),
    ],
    ids=["cut at an entry", "cut inside an entry"],
)
def test_a_published_values_file_cut_short_is_refused_by_name(
    tmp_path, monkeypatch, config, estimates_and_dataset, after_a5, message
):
    estimates, _ = estimates_and_dataset
    nm = pd.read_parquet(estimates)
    collected = tmp_path / "collected.parquet"
    write_table(pd.concat([nm, nm.assign(method="BC")]), collected)
    paper = get_paper("paper_a")
    cut = tmp_path / "paper_a.yaml"
    lines = paper.published.read_text().splitlines(keepends=True)
    cut.write_text("".join(lines[: lines.index("- id: A5\n") + after_a5]))
    monkeypatch.setattr(
        pipeline, "papers_of_study", lambda study: [dataclasses.replace(paper, published=cut)]
    )
    with pytest.raises(ValueError, match=re.escape(f"published values {cut}: {message}")):
        pipeline.comparison({"cmc": str(collected)}, config)


def test_a_joint_centre_is_scored_with_its_covariance_in_a_table_or_a_mapping():
    truth = {"center": [0.0, 0.0, 0.0]}
    rows = {"center_x": [3.0, 3.0], "center_y": [4.0, 4.0], "center_z": [0.0, 0.0]}
    covariance = {"cov_xx": [4.0, np.nan], "cov_yy": [4.0, np.nan], "cov_zz": [4.0, np.nan]}
    covariance |= {key: [0.0, np.nan] for key in ("cov_xy", "cov_xz", "cov_yz")}
    for estimates in ({**rows, **covariance}, pd.DataFrame({**rows, **covariance})):
        scores = score_columns("joint_center", estimates, truth)
        np.testing.assert_allclose(scores["error_mm"], [5.0, 5.0])
        np.testing.assert_allclose(scores["sqrt_trace_cov_mm"], [np.sqrt(12.0), np.nan])
        np.testing.assert_allclose(scores["mahalanobis_sq"], [25.0 / 4.0, np.nan])
        np.testing.assert_allclose(scores["validation_index"], [np.sqrt(25.0 / 12.0), np.nan])
    # Without covariance columns the method predicts none.
    assert np.isnan(score_columns("joint_center", rows, truth)["mahalanobis_sq"]).all()
