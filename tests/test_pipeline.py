"""The real Snakemake workflow, end to end, on a reduced config in a temporary directory."""

from __future__ import annotations

import pandas as pd
import pytest
import yaml
from workflow_copy import ROOT, copy_workflow, run_snakemake

pytestmark = pytest.mark.pipeline


@pytest.fixture(scope="session")
def reduced_run(tmp_path_factory):
    workdir = copy_workflow(tmp_path_factory.mktemp("workflow"))
    reduced = ROOT / "tests" / "data" / "reduced.yaml"
    first = run_snakemake(workdir, "--configfile", str(reduced))
    assert first.returncode == 0, first.stderr[-4000:]
    second = run_snakemake(workdir, "--dry-run", "--configfile", str(reduced))
    return workdir, yaml.safe_load(reduced.read_text()), second


OUTPUTS = {
    "cmc": [
        "collected/cmc.parquet",
        "figures/paper_a_fig3.png",
        "figures/paper_a_fig3.pdf",
        "figures/paper_a_fig4.png",
        "figures/paper_a_fig4.pdf",
        "tables/paper_a_table2.csv",
        "tables/paper_a_table2.md",
        "tables/paper_a_claims.csv",
        "tables/paper_a_claims.md",
    ],
}


def test_every_output_is_produced(reduced_run):
    workdir, reduced, _ = reduced_run
    for study in reduced["studies"]:
        for name in OUTPUTS[study]:
            path = workdir / "results" / name
            assert path.exists(), f"missing output results/{name}"
            assert path.stat().st_size > 200, f"results/{name} is nearly empty"


def test_second_run_has_nothing_to_do(reduced_run):
    _, _, second = reduced_run
    assert second.returncode == 0
    assert "Nothing to be done" in second.stdout + second.stderr


def test_collected_cmc_has_one_row_per_trial_and_method(reduced_run):
    workdir, reduced, _ = reduced_run
    collected = pd.read_parquet(workdir / "results" / "collected" / "cmc.parquet")
    study = reduced["studies"]["cmc"]
    n_conditions = 1
    for values in study["grid"].values():
        n_conditions *= len(values)
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    methods = config["studies"]["cmc"]["estimators"] + config["studies"]["cmc"].get(
        "external_estimators", []
    )
    assert len(collected) == n_conditions * study["trials"] * len(methods)
    required = [
        "marker_set",
        "rom_deg",
        "noise_mm",
        "trial",
        "method",
        "center_x",
        "center_y",
        "center_z",
        "error_mm",
        "converged",
        "iterations",
        "seconds",
        "status",
    ]
    assert set(required) <= set(collected.columns)
    assert set(collected["method"]) == set(methods)


def test_claims_tables_are_computed(reduced_run):
    workdir, _, _ = reduced_run
    claims = pd.read_csv(workdir / "results" / "tables" / "paper_a_claims.csv")
    assert list(claims["id"]) == [f"A{i}" for i in range(1, 12)]
    assert set(claims["status"]) <= {"reproduced", "not reproduced", "not applicable"}
