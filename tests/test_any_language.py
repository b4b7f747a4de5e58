"""Estimators in any language: the CSV interchange, the C worked example run as a rule with no
Python of its own, external rules that serve every study they are listed for and ignore the
others, and the README's template as the file the workflow ships."""

from __future__ import annotations

import re
import shutil

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
import yaml
from workflow_copy import ROOT, copy_workflow, run_snakemake

from jointbench.resultfiles.interchange import (
    DATASET_COLUMNS,
    read_estimates_csv,
    write_dataset_csv,
)
from jointbench.resultfiles.parquet import write_dataset
from jointbench.resultfiles.schema import check_estimates
from jointbench.simulate import Trials


def _dataset(tmp_path, segments=("moving",)):
    rng = np.random.default_rng(7)
    trials = Trials(
        segments={name: rng.normal(size=(2, 5, 3, 3)) * 10 for name in segments},
        truth={"center": [1.0, 2.0, 3.0]},
    )
    path = tmp_path / "marker_set-M__rom_deg-5__noise_mm-1.0.parquet"
    condition = {"marker_set": "M", "rom_deg": 5, "noise_mm": 1.0}
    write_dataset(path, trials, study="cmc", condition=condition)
    return path, trials


def test_the_dataset_csv_holds_every_sample_to_the_last_bit(tmp_path):
    path, trials = _dataset(tmp_path, segments=("proximal", "distal"))
    write_dataset_csv(path, tmp_path / "markers.csv")
    lines = (tmp_path / "markers.csv").read_text().splitlines()
    assert lines[0] == ",".join(DATASET_COLUMNS)
    frame = pd.read_csv(tmp_path / "markers.csv")
    assert len(frame) == 2 * 2 * 5 * 3
    # Trial by trial, each segment's frames in the dataset's segment order.
    first = frame[frame["trial"] == 0]
    assert list(dict.fromkeys(first["segment"])) == ["proximal", "distal"]
    for name, markers in trials.segments.items():
        rows = frame[frame["segment"] == name].sort_values(["trial", "frame", "marker"])
        assert np.array_equal(rows[["x", "y", "z"]].to_numpy(), markers.reshape(-1, 3))
    assert "center" not in (tmp_path / "markers.csv").read_text()  # the truth stays out


def _estimates_csv(tmp_path, body: str):
    folder = tmp_path / "estimates" / "LS-C"
    folder.mkdir(parents=True)
    path = folder / "marker_set-M__rom_deg-5__noise_mm-1.0.csv"
    header = "trial,center_x,center_y,center_z,converged,iterations,seconds,status\n"
    path.write_text(header + body)
    return path


def test_estimates_csv_gain_their_condition_and_method(tmp_path):
    dataset, _ = _dataset(tmp_path)
    source = _estimates_csv(
        tmp_path, "0,1.5,2,3,true,0,1e-5,ok\n1,nan,nan,nan,false,0,1e-5,error: singular\n"
    )
    read_estimates_csv(source, dataset, tmp_path / "out.parquet")
    table = pq.read_table(tmp_path / "out.parquet").to_pandas()
    assert list(table["method"]) == ["LS-C", "LS-C"]
    assert list(table["rom_deg"]) == [5, 5] and list(table["marker_set"]) == ["M", "M"]
    assert table["converged"].tolist() == [True, False]
    assert np.isnan(table.loc[1, "center_x"]) and table.loc[0, "center_x"] == 1.5


@pytest.mark.parametrize(
    "body, message",
    [
        ("0,1,2,3,maybe,0,1e-5,ok\n", "'converged' must hold true/false or 1/0"),
        ("0,1,2,3,2,0,1e-5,ok\n", "'converged' must hold true/false or 1/0"),
    ],
)
def test_a_bad_estimates_csv_is_refused_by_name(tmp_path, body, message):
    dataset, _ = _dataset(tmp_path)
    source = _estimates_csv(tmp_path, body)
    with pytest.raises(ValueError, match=re.escape(message)) as error:
        read_estimates_csv(source, dataset, tmp_path / "out.parquet")
    assert str(source) in str(error.value)


def test_an_estimates_csv_without_status_is_refused(tmp_path):
    dataset, _ = _dataset(tmp_path)
    path = tmp_path / "LS-C" / "c.csv"
    path.parent.mkdir()
    path.write_text(
        "trial,center_x,center_y,center_z,converged,iterations,seconds\n0,1,2,3,1,0,0\n"
    )
    with pytest.raises(ValueError, match="missing column 'status'"):
        read_estimates_csv(path, dataset, tmp_path / "out.parquet")


def test_an_estimates_csv_giving_a_column_twice_is_refused_by_name(tmp_path):
    """Two centre_x columns: which one would be scored is for nobody to guess."""
    dataset, _ = _dataset(tmp_path)
    path = tmp_path / "LS-C" / "c.csv"
    path.parent.mkdir()
    header = "trial,center_x,center_y,center_z,converged,iterations,seconds,status,center_x\n"
    path.write_text(header + "0,1,2,3,1,0,0,ok,9\n1,1,2,3,1,0,0,ok,9\n")
    with pytest.raises(ValueError, match="column 'center_x' appears more than once") as error:
        read_estimates_csv(path, dataset, tmp_path / "out.parquet")
    assert str(path) in str(error.value)


def test_a_condition_whose_every_trial_failed_is_read_as_failed_trials(tmp_path):
    """NaN, NA or nothing in every row: CSV gives such a column no type of its own, yet the
    estimate is a number column, so the file is collected as the failures it reports."""
    dataset, _ = _dataset(tmp_path)
    source = _estimates_csv(
        tmp_path, "0,nan,nan,nan,false,0,1e-5,error: singular\n1,NA,,-nan,0,0,1e-5,\n"
    )
    read_estimates_csv(source, dataset, tmp_path / "out.parquet")
    table = pq.read_table(tmp_path / "out.parquet")
    keys = ["marker_set", "rom_deg", "noise_mm"]
    check_estimates(table, kind="center", condition_keys=keys, method="LS-C")
    frame = table.to_pandas()
    assert frame[["center_x", "center_y", "center_z"]].isna().all(axis=None)
    assert not frame["converged"].any() and frame["status"].tolist() == ["error: singular", ""]


def test_an_estimates_csv_without_rows_is_refused(tmp_path):
    dataset, _ = _dataset(tmp_path)
    source = _estimates_csv(tmp_path, "")
    with pytest.raises(ValueError, match="no rows; the dataset has 2 trials") as error:
        read_estimates_csv(source, dataset, tmp_path / "out.parquet")
    assert str(source) in str(error.value)


def _overlay(tmp_path, **cmc) -> str:
    defaults = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    studies = {name: {"enabled": False} for name in defaults["studies"] if name != "cmc"}
    studies["cmc"] = {
        "trials": 2,
        "grid": {"marker_set": ["M"], "rom_deg": [15], "noise_mm": [0.0, 1.0]},
        **cmc,
    }
    path = tmp_path / "overlay.yaml"
    path.write_text(yaml.safe_dump({"studies": studies}))
    return str(path)


@pytest.mark.pipeline
@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc) on this machine")
def test_the_c_estimator_runs_as_a_rule_and_equals_the_built_in_ls(tmp_path):
    copy_workflow(tmp_path)
    overlay = _overlay(tmp_path, estimators=["LS"], external_estimators=["LS-C"])
    run = run_snakemake(tmp_path, "results/collected/cmc.parquet", "--configfile", overlay)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    collected = pd.read_parquet(tmp_path / "results" / "collected" / "cmc.parquet")
    keys = ["marker_set", "rom_deg", "noise_mm", "trial"]
    ours = collected[collected["method"] == "LS"].set_index(keys).sort_index()
    theirs = collected[collected["method"] == "LS-C"].set_index(keys).sort_index()
    assert len(theirs) == 2 * 2 and theirs["converged"].all()
    columns = ["center_x", "center_y", "center_z"]
    gap = np.linalg.norm(ours[columns].to_numpy() - theirs[columns].to_numpy(), axis=1)
    assert gap.max() < 1e-9, gap
    # Scored by the benchmark, from the estimate: the same error as the built-in LS.
    assert np.allclose(theirs["error_mm"], ours["error_mm"], rtol=0, atol=1e-9)


@pytest.mark.pipeline
def test_external_rules_of_a_study_not_in_the_run_are_ignored(tmp_path):
    """The shipped external rules (LM, LS-C, centroid) with the cmc study switched off: the
    default targets plan without them."""
    copy_workflow(tmp_path)
    overlay = tmp_path / "hinge_only.yaml"
    overlay.write_text(
        yaml.safe_dump(
            {
                "studies": {
                    "cmc": {"enabled": False},
                    "hip": {"enabled": False},
                    "hinge": {"trials": 2, "grid": {"fe_rom_deg": [30]}},
                }
            }
        )
    )
    run = run_snakemake(tmp_path, "--dry-run", "--configfile", str(overlay))
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "estimate_cmc_LM" not in run.stdout
    assert "estimate_LS_C" not in run.stdout


def test_the_readme_template_is_the_file_the_workflow_ships():
    """The template and the worked example's rule, as the README quotes them in full."""
    readme = (ROOT / "README.md").read_text()
    quoted = ("centroid.smk", "lm_sphere.smk")
    shipped = ["workflow/external/centroid.py", *(f"workflow/rules/estimators/{n}" for n in quoted)]
    for path in shipped:
        assert (ROOT / path).read_text().strip() in readme, f"{path} differs from the README"
