"""Adding an estimator is adding a rule: a user's rule file and a config entry, end to end;
the extended ranking and the external LM script on their own.

Each pipeline test copies the workflow to a temporary directory, as a user's clone, and runs
Snakemake on a two-condition cmc grid of two trials.
"""

from __future__ import annotations

import importlib.util
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import yaml
from workflow_copy import (
    ROOT,
    SNAKEMAKE,
    copy_workflow,
    readme_builtin_example,
    run_snakemake,
    running_in,
)

from jointbench import pipeline
from jointbench.figures import extended
from jointbench.papers import get_paper
from jointbench.resultfiles.schema import check_estimates
from jointbench.running import landlock, timelimit
from jointbench.running.collected import scored_estimates

# The minimal external estimator of the README's "Adding an estimator", shipped as a template
# (the README quotes these files verbatim: tests/test_any_language.py).
CENTROID_SCRIPT = Path("workflow") / "external" / "centroid.py"


def user_clone(
    destination: Path,
    *,
    estimators: list[str],
    external: list[str],
    centroid_script: str | None = None,
    profiles: bool = False,
) -> Path:
    """The workflow as a user clones it (with the shipped centroid template, its script
    replaced by ``centroid_script`` if given, and with ``profiles`` its profiles/) and a
    cmc-only overlay config; returns the overlay's path."""
    copy_workflow(destination, profiles=profiles)
    if centroid_script is not None:
        (destination / CENTROID_SCRIPT).write_text(centroid_script)
    defaults = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    studies = {name: {"enabled": False} for name in defaults["studies"] if name != "cmc"}
    studies["cmc"] = {
        "trials": 2,
        "grid": {"marker_set": ["M"], "rom_deg": [5, 15], "noise_mm": [1.0]},
        "estimators": estimators,
        "external_estimators": external,
    }
    overlay = destination / "overlay.yaml"
    overlay.write_text(yaml.safe_dump({"studies": studies}))
    return overlay


def snakemake(workdir: Path, overlay: Path, *targets: str, dry_run: bool = False):
    arguments = [*targets, "--configfile", str(overlay), *(["--dry-run"] if dry_run else [])]
    return run_snakemake(workdir, *arguments, timeout=300)


def refusal(workdir: Path, overlay: Path) -> str:
    """What a run of the collected cmc results says as it stops before any job."""
    run = snakemake(workdir, overlay, "results/collected/cmc.parquet")
    assert run.returncode != 0
    assert not (workdir / "results").exists(), "a job ran"
    return run.stdout + run.stderr


@pytest.mark.pipeline
def test_user_rule_joins_collected_results_and_extended_ranking(tmp_path):
    overlay = user_clone(tmp_path, estimators=["NM", "LS"], external=["LM", "centroid"])
    run = snakemake(
        tmp_path,
        overlay,
        "results/tables/extended_cmc.csv",
        "results/figures/extended_cmc.png",
        "results/collected/cmc.parquet",
        "results/tables/paper_a_claims.csv",
        "results/summaries/cmc/centroid.csv",
    )
    assert run.returncode == 0, run.stderr[-4000:]
    results = tmp_path / "results"

    collected = pd.read_parquet(results / "collected" / "cmc.parquet")
    assert set(collected["method"]) == {"NM", "LS", "LM", "centroid"}
    assert len(collected) == 2 * 2 * 4  # conditions x trials x methods
    lm = collected[collected["method"] == "LM"]
    # Every trial answered; one LM's restarts beat is marked as a local minimum, not "ok".
    doubted = ~lm["converged"]
    assert lm["f1_mm2"].notna().all() and lm["center_x"].notna().all()
    assert lm.loc[doubted, "status"].str.startswith("local minimum").all()
    assert collected.loc[collected["method"] == "centroid", "error_mm"].notna().all()

    table = pd.read_csv(results / "tables" / "extended_cmc.csv")
    assert {"centroid", "LM"} <= set(table["method"])
    assert (table.groupby(["rom_deg"])["best"].sum() >= 1).all()
    assert set(table.loc[table["method"].isin(["centroid", "LM"]), "source"]) == {"added"}
    note = (results / "tables" / "extended_cmc.md").read_text()
    assert "external (a rule of their own): LM, centroid" in note

    assert (results / "figures" / "extended_cmc.png").stat().st_size > 10_000
    assert (results / "tables" / "paper_a_claims.csv").exists()
    summary = pd.read_csv(results / "summaries" / "cmc" / "centroid.csv")
    assert list(summary["method"].unique()) == ["centroid"]


@pytest.mark.pipeline
def test_wrong_column_fails_naming_it(tmp_path):
    shipped = (ROOT / CENTROID_SCRIPT).read_text()
    assert '"center_z"' in shipped
    wrong = shipped.replace('"center_z"', '"centre_z"')
    overlay = user_clone(tmp_path, estimators=["LS"], external=["centroid"], centroid_script=wrong)
    run = snakemake(tmp_path, overlay, "results/collected/cmc.parquet")
    assert run.returncode != 0
    assert "missing column 'center_z'" in run.stdout + run.stderr
    assert not (tmp_path / "results" / "collected" / "cmc.parquet").exists()


@pytest.mark.pipeline
def test_external_name_of_a_builtin_is_rejected(tmp_path):
    overlay = user_clone(tmp_path, estimators=["LS"], external=["NM"])
    run = snakemake(tmp_path, overlay, "results/collected/cmc.parquet", dry_run=True)
    assert run.returncode != 0
    message = run.stdout + run.stderr
    assert "'NM'" in message and "built-in" in message, message[-2000:]


@pytest.mark.pipeline
def test_an_external_estimator_without_a_rule_is_named_before_any_job(tmp_path):
    """A misspelt name, or a rule file not yet written: the run stops naming the study and
    the estimator, not a CSV of the interchange rules it never meant to write."""
    overlay = user_clone(tmp_path, estimators=["LS"], external=["LS_C"])
    run = snakemake(tmp_path, overlay, "results/collected/cmc.parquet", dry_run=True)
    assert run.returncode != 0
    message = run.stdout + run.stderr
    assert "studies.cmc.external_estimators: no rule writes the estimates of 'LS_C'" in message
    assert "MissingInputException" not in message, message[-2000:]


@pytest.mark.pipeline
def test_a_crashing_estimator_fails_alone_and_the_run_finishes_the_rest(tmp_path):
    """A user's program that crashes on one condition fails that job, named, and the run with
    it; every job that does not need its file still runs and keeps what it made. Run as a
    clone runs, with the repository's default profile, one job at a time, the crash first."""
    shipped = (ROOT / CENTROID_SCRIPT).read_text()
    crashed = "marker_set-M__rom_deg-15__noise_mm-1.0"
    crashing = f'if "{crashed}" in estimates:\n    raise RuntimeError("centroid crashed")\n'
    script = shipped.replace("rows = []\n", f"{crashing}rows = []\n", 1)
    assert script != shipped
    overlay = user_clone(
        tmp_path, estimators=["LS"], external=["centroid"], centroid_script=script, profiles=True
    )
    run = subprocess.run(
        [
            str(SNAKEMAKE),
            "results/collected/cmc.parquet",
            "results/summaries/cmc/LS.csv",
            "--prioritize",
            f"results/estimates/cmc/centroid/{crashed}.parquet",
            "-j1",
            "--directory",
            str(tmp_path),
            "-s",
            str(tmp_path / "Snakefile"),
            "--configfile",
            str(overlay),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    message = run.stdout + run.stderr
    assert run.returncode != 0
    assert "Error in rule estimate_centroid" in message and "centroid crashed" in message
    # Its last lines name the failed job, its log and the command that redoes it once mended.
    failure = f"estimate_centroid: results/logs/estimate/cmc/centroid/{crashed}.log"
    assert failure in message.split("jointbench: 1 job failed:")[-1], message[-3000:]
    assert "--forcerun estimate_centroid`" in message
    # The crash is the estimator's own: the other condition's answers and every built-in
    # estimator's results are made and kept, and nothing is collected without it.
    estimates = tmp_path / "results" / "estimates" / "cmc"
    assert (estimates / "centroid" / "marker_set-M__rom_deg-5__noise_mm-1.0.parquet").is_file()
    assert (tmp_path / "results" / "summaries" / "cmc" / "LS.csv").is_file(), message[-3000:]
    assert not (tmp_path / "results" / "collected" / "cmc.parquet").exists()


@pytest.mark.pipeline
def test_an_estimator_that_never_ends_is_stopped_and_named(tmp_path):
    """A user's program that hangs on every condition, under a limit of seconds: each of its
    jobs fails at the limit, named with its condition, the limit and the key to raise, its
    program stopped; every built-in estimator's results are made and kept, and the closing
    summary names the failed jobs and their logs, which say the limit stopped them. Run as a
    clone runs, with the default profile."""
    shipped = (ROOT / CENTROID_SCRIPT).read_text()
    # Bounded, so that a program the run left behind ends by itself. Whether the program got
    # this far within the limit depends on the machine's load (its interpreter and imports take
    # about the 3 s on a loaded one): what is left of it is looked for wherever it was stopped.
    script = shipped.replace("rows = []\n", "time.sleep(240)\nrows = []\n", 1)
    assert script != shipped
    overlay = user_clone(
        tmp_path, estimators=["LS"], external=["centroid"], centroid_script=script, profiles=True
    )
    config = yaml.safe_load(overlay.read_text())
    config["jobs"] = {"external_time_limit_s": 3}
    overlay.write_text(yaml.safe_dump(config))
    run = run_snakemake(
        tmp_path,
        "results/collected/cmc.parquet",
        "results/summaries/cmc/LS.csv",
        "--configfile",
        str(overlay),
        timeout=200,
    )
    message = run.stdout + run.stderr
    assert run.returncode != 0
    conditions = ["marker_set-M__rom_deg-5__noise_mm-1.0", "marker_set-M__rom_deg-15__noise_mm-1.0"]
    for condition in conditions:
        expected = (
            f"rule estimate_centroid (study=cmc, condition={condition}): its program ran past "
            "the time limit of 3 s for a job of an external estimator and was stopped"
        )
        assert expected in message, message[-4000:]
    assert "raise jobs.external_time_limit_s in the config" in message
    summary = message.split("jointbench: 2 jobs failed:")[-1]
    for condition in conditions:
        log = f"results/logs/estimate/cmc/centroid/{condition}.log"
        assert f"estimate_centroid: {log}" in summary
        # The log the summary names says why: in a long run the error is printed far above.
        assert f"condition={condition}): its program ran past the time limit of 3 s" in (
            (tmp_path / log).read_text()
        )
    assert running_in(tmp_path) == [], "a program of the run still runs"
    assert (tmp_path / "results" / "summaries" / "cmc" / "LS.csv").is_file(), message[-3000:]
    assert not (tmp_path / "results" / "collected" / "cmc.parquet").exists()


@pytest.mark.pipeline
@pytest.mark.parametrize("limit", [-1, float("nan")])
def test_a_time_limit_that_is_no_limit_stops_the_run_before_any_job(limit, tmp_path):
    """Refused by the schema (-1) or by the limit's own check (NaN, which the schema's bound
    lets through): either way the run stops as it loads, naming the key."""
    overlay = user_clone(tmp_path, estimators=["LS"], external=["centroid"])
    config = yaml.safe_load(overlay.read_text())
    config["jobs"] = {"external_time_limit_s": limit}
    overlay.write_text(yaml.safe_dump(config))
    message = refusal(tmp_path, overlay)
    assert re.search(r"jobs[./]external_time_limit_s", message), message[-2000:]


@pytest.mark.pipeline
def test_an_external_job_runs_by_the_limited_shell_with_a_cluster_runtime_above_the_limit(
    tmp_path,
):
    """Whatever runtime the profile and the command line give it, a job of the user's gets one
    just above the limit, so that on a cluster the limit stops it first; the built-in jobs
    keep theirs and Snakemake's own shell."""
    overlay = user_clone(tmp_path, estimators=["LS"], external=["centroid"])
    run = snakemake(
        tmp_path,
        overlay,
        "results/collected/cmc.parquet",
        "--default-resources",
        "runtime=15",
        "--set-resources",
        "estimate_centroid:runtime=1",
        dry_run=True,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    resources = dict(
        re.findall(r"^rule (\S+):\n(?: {4}.*\n)*? {4}resources: (.*)$", run.stdout, re.M)
    )
    minutes = timelimit.runtime_minutes(3600)
    assert f"runtime={minutes}," in resources["estimate_centroid"], resources
    # The rule's own shell, which runs the limited shell with the rule's own grant.
    shell = tmp_path / ".snakemake" / "jointbench" / "shells" / "estimate_centroid" / "bash"
    assert f"shell_exec='{shell}'" in resources["estimate_centroid"], resources
    assert f'exec {timelimit.LIMITED_SHELL} "$@"' in shell.read_text()
    assert (
        "runtime=15" in resources["estimate_cmc"] and "shell_exec" not in resources["estimate_cmc"]
    )


@pytest.mark.pipeline
def test_a_rule_of_the_users_with_a_run_block_is_refused_before_any_job(tmp_path):
    """Code in a run: block runs inside Snakemake, where no time limit can stop it."""
    overlay = user_clone(tmp_path, estimators=["LS"], external=["centroid"])
    rule_file = tmp_path / "workflow" / "rules" / "estimators" / "centroid.smk"
    shipped = rule_file.read_text()
    script = '    script:\n        "../../external/centroid.py"\n'
    assert script in shipped
    rule_file.write_text(shipped.replace(script, "    run:\n        pass\n"))
    message = refusal(tmp_path, overlay)
    assert (
        "rule estimate_centroid runs its code in a run: block, inside Snakemake, where the "
        "time limit of an external estimator's job (jobs.external_time_limit_s) cannot stop it"
    ) in message, message[-2000:]


@pytest.mark.pipeline
def test_the_summary_of_an_estimator_the_study_does_not_list_names_the_list(tmp_path):
    overlay = user_clone(tmp_path, estimators=["LS"], external=["centroid"])
    run = snakemake(tmp_path, overlay, "results/summaries/cmc/LS-C.csv", dry_run=True)
    assert run.returncode != 0
    message = run.stdout + run.stderr
    assert "'LS-C' is not listed under studies.cmc (LS, centroid)" in message, message[-2000:]
    assert "MissingInputException" not in message


# ------------------------------------------------------------------------ without Snakemake


@pytest.mark.pipeline
def test_the_readme_builtin_example_plans_beside_the_shipped_template(tmp_path):
    """Followed as written, the README's built-in estimator is listed and planned: its name is
    not one a shipped external rule (the centroid template) writes under, which would stop
    the run before any job."""
    code, listing = readme_builtin_example()
    (tmp_path / "readme_estimator.py").write_text(code)
    cmc = listing["studies"]["cmc"]
    overlay = user_clone(tmp_path, estimators=cmc["estimators"], external=[])
    config = yaml.safe_load(overlay.read_text())
    config["extensions"] = ["readme_estimator.py"]
    config["studies"]["cmc"]["options"] = cmc["options"]
    overlay.write_text(yaml.safe_dump(config))
    run = snakemake(tmp_path, overlay, "results/collected/cmc.parquet", dry_run=True)
    assert run.returncode == 0, (run.stdout + run.stderr)[-3000:]
    added = next(name for name in cmc["estimators"] if name not in {"NM", "LS", "BC", "MA", "IS"})
    assert f"results/estimates/cmc/{added}/" in run.stdout


@pytest.mark.pipeline
def test_a_builtin_named_as_a_rule_files_estimator_is_named_as_such(tmp_path):
    """A built-in estimator listed under the name a shipped rule file writes under (the
    centroid template's), though nothing lists that rule's estimator: the run stops naming the
    name, the study's list and both rules, not as a rule of the user's writing the
    benchmark's files."""
    code, _ = readme_builtin_example()
    registered = re.search(r'@register\("center", "([^"]+)"', code).group(1)
    (tmp_path / "clashing.py").write_text(code.replace(f'"{registered}"', '"centroid"'))
    overlay = user_clone(tmp_path, estimators=["LS", "centroid"], external=[])
    config = yaml.safe_load(overlay.read_text())
    config["extensions"] = ["clashing.py"]
    overlay.write_text(yaml.safe_dump(config))
    run = snakemake(tmp_path, overlay, "results/collected/cmc.parquet", dry_run=True)
    assert run.returncode != 0
    message = run.stdout + run.stderr
    expected = (
        "rule estimate_centroid writes the estimates of 'centroid' in study cmc "
        "(results/estimates/{study}/centroid/{condition}.parquet), an estimator "
        "studies.cmc.estimators lists as built in, run by rule estimate_cmc: "
        "a built-in estimator and a rule file's take different names"
    )
    assert expected in message, message[-3000:]


@pytest.mark.pipeline
def test_a_builtin_named_as_a_rule_files_estimator_names_the_config_file_listing_it(tmp_path):
    code, _ = readme_builtin_example()
    registered = re.search(r'@register\("center", "([^"]+)"', code).group(1)
    (tmp_path / "clashing.py").write_text(code.replace(f'"{registered}"', '"centroid"'))
    first = user_clone(tmp_path, estimators=["LS"], external=[])
    config = yaml.safe_load(first.read_text())
    config["extensions"] = ["clashing.py"]
    first.write_text(yaml.safe_dump(config))
    second = tmp_path / "second.yaml"
    second.write_text("studies: {cmc: {estimators: [LS, centroid]}}\n")
    run = run_snakemake(tmp_path, "--dry-run", "--configfile", str(first), str(second))
    message = run.stdout + run.stderr
    assert run.returncode != 0, message[-3000:]
    for words in ("studies.cmc.estimators lists as built in", f"(set in {second})"):
        assert words in message, message[-3000:]


def test_the_readme_builtin_example_passes_the_style_checks(tmp_path):
    """Copied into src/jointbench/estimators/, the README's example passes tests/test_lint.py's
    ruff checks as it stands."""
    code, _ = readme_builtin_example()
    module = tmp_path / "readme_estimator.py"
    module.write_text(code)
    ruff = Path(sys.executable).with_name("ruff")
    for command in (["check"], ["format", "--check"]):
        result = subprocess.run(
            [str(ruff), *command, "--config", str(ROOT / "pyproject.toml"), str(module)],
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]


def _results(methods: dict[str, list[float]], study: str = "cmc") -> pd.DataFrame:
    """A collected-results table: one condition, one row per (method, trial) error."""
    error = "error_deg" if study == "hinge" else "error_mm"
    condition = (
        {"protocol": "knee", "fe_rom_deg": 60, "aa_ratio": 0.1}
        if study == "hinge"
        else {"marker_set": "M", "rom_deg": 5, "noise_mm": 1.0}
    )
    rows = [
        {
            **condition,
            "trial": t,
            "method": m,
            error: e,
            "converged": np.isfinite(e),
            "seconds": 0.1,
        }
        for m, errors in methods.items()
        for t, e in enumerate(errors)
    ]
    return pd.DataFrame(rows)


def test_extended_table_ranks_any_method_and_survives_failures():
    collected = _results(
        {
            "NM": [1.0, 2.0],
            "IS": [1.0002, 2.0],  # equal to 3 significant digits: ties with NM
            "my method": [0.5, np.nan],  # one failed trial: its mean is over the other
            "broken": [np.nan, np.nan],
        }
    )
    paper_a = ("A", get_paper("paper_a").methods)
    table = extended.extended_table(collected, "cmc", paper_a).set_index("method")
    assert table.loc["NM", "rank"] == table.loc["IS", "rank"] == 1
    assert table.loc["NM", "best"] and table.loc["IS", "best"]
    # Best on the trial it answered, but it gave up on the other: ranked after every method
    # that answered both, not first.
    assert table.loc["my method", "rank"] == 3 and not table.loc["my method", "best"]
    assert table.loc["my method", "failed"] == 1
    assert table.loc["broken", "rank"] == 4 and not table.loc["broken", "best"]
    assert table.loc["NM", "source"] == "paper A" and table.loc["my method", "source"] == "added"


def test_giving_up_on_hard_trials_does_not_win():
    # A contestant that answers only the trial it gets right and reports the others as failed.
    collected = _results(
        {
            "LS": [9.0, 9.5, 8.5],
            "quitter": [1.0, np.nan, np.nan],
            "careful": [9.0, 9.5, np.nan],
            "never": [np.nan, np.nan, np.nan],
            "overflowing": [np.inf, np.inf, np.inf],
        }
    )
    table = extended.extended_table(collected, "cmc").set_index("method")
    assert table["rank"].to_dict() == {
        "LS": 1,
        "overflowing": 2,
        "careful": 3,
        "quitter": 4,
        "never": 5,
    }
    assert table.loc[table["best"]].index.tolist() == ["LS"]
    ranks = extended.mean_ranks(extended.extended_table(collected, "cmc")).set_index("method")
    assert ranks.loc["LS", "best_alone"] == 1 and ranks.loc["quitter", "best_in"] == 0


def test_at_equal_failures_the_methods_are_compared_on_the_trials_they_all_answered():
    # Trial 9 is hard. "honest" failed one easy trial by accident; "quitter", worse on every
    # trial it answers, reports the hard one as failed. Over the trials each answered, the
    # quitter's mean (3.0) would beat the honest one's (6.2).
    collected = _results(
        {
            "honest": [2.0] * 8 + [np.nan, 40.0],
            "quitter": [3.0] * 9 + [np.nan],
            "steady": [2.5] * 9 + [41.0],
        }
    )
    table = extended.extended_table(collected, "cmc").set_index("method")
    assert table["rank"].to_dict() == {"steady": 1, "honest": 2, "quitter": 3}
    assert table["common_trials"].to_dict() == {"steady": 10, "honest": 8, "quitter": 8}
    assert table.loc["honest", "common_mean_error_mm"] == 2.0
    assert table.loc["quitter", "common_mean_error_mm"] == 3.0
    assert table.loc["quitter", "mean_error_mm"] == 3.0  # its own mean is still shown


def test_a_method_failing_more_trials_does_not_change_how_the_others_rank():
    before = {"A": [1.0, 1.0, 10.0], "B": [2.0, 2.0, 2.0]}
    # Answers only the trial A does best on: the others' common trials stay all three.
    after = {**before, "C": [0.5, np.nan, np.nan]}
    for methods in (before, after):
        table = extended.extended_table(_results(methods), "cmc").set_index("method")
        assert table.loc["B", "rank"] == 1 and table.loc["A", "rank"] == 2
    assert table.loc["C", "rank"] == 3


def test_methods_with_no_trial_in_common_are_ranked_by_their_own_means_and_say_so():
    collected = _results({"early": [1.0, np.nan], "late": [np.nan, 5.0]})
    table = extended.extended_table(collected, "cmc").set_index("method")
    assert table["rank"].to_dict() == {"early": 1, "late": 2}
    assert table["common_trials"].to_dict() == {"early": 0, "late": 0}
    assert table.loc["late", "common_mean_error_mm"] == table.loc["late", "mean_error_mm"] == 5.0


def test_extended_outputs_for_an_axis_study(tmp_path):
    collected = _results({"combined": [2.0, 3.0], "SARA": [1.0, 1.5], "user": [4.0, 5.0]}, "hinge")
    table = extended.extended_table(collected, "hinge")
    assert "mean_error_deg" in table.columns
    assert table.loc[table["best"], "method"].tolist() == ["SARA"]
    path = tmp_path / "hinge.parquet"
    collected.to_parquet(path)
    config = {"studies": {"hinge": {"external_estimators": ["user"]}}}
    outputs = {name: str(tmp_path / f"extended_hinge.{name}") for name in ("csv", "md", "png")}
    pipeline.render_extended("hinge", str(path), outputs, config, what="table")
    pipeline.render_extended("hinge", str(path), outputs, config, what="figure")
    note = Path(outputs["md"]).read_text()
    assert "Paper B's methods: combined" in note and "external (a rule of their own): user" in note
    assert Path(outputs["png"]).stat().st_size > 10_000


@pytest.mark.parametrize("abi", [0, 7], ids=["no-landlock", "landlock"])
def test_the_ranking_says_what_the_benchmark_does_not_check_of_an_external_estimator(
    abi, monkeypatch
):
    """An external estimator's seconds are its program's own report; where the kernel has no
    Landlock its program may open files its rule does not declare (the full dataset, by its
    path) and rank first on the truth. The ranking that lists one says which holds."""
    monkeypatch.setattr(landlock, "abi_version", lambda: abi)
    paper = ("A", ("LS",))
    config = {"studies": {"cmc": {"external_estimators": ["mine"]}}}
    note = extended.origin_note("cmc", ["LS", "mine"], paper, config)
    assert "external estimator's seconds are as its program reports them" in note, note
    unchecked = "checks the files its rule declares, not those its program opens"
    confined = "its program may open only the blind copies and its rule's own files"
    assert (unchecked in note, confined in note) == (not abi, bool(abi)), note
    alone = extended.origin_note("cmc", ["LS"], paper, {"studies": {"cmc": {}}})
    assert "its program" not in alone, alone


def _lm_script():
    path = ROOT / "workflow" / "external" / "lm_sphere.py"
    spec = importlib.util.spec_from_file_location("lm_sphere", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _sphere_dataset(path: Path, n_trials: int = 3) -> np.ndarray:
    """A cmc-like dataset of markers on concentric spheres about a known centre; returns it."""
    rng = np.random.default_rng(7)
    center = np.array([20.0, -25.0, -30.0])
    rows = []
    for trial in range(n_trials):
        for frame in range(40):
            angle = np.deg2rad(30.0) * np.array([np.sin(frame / 6), np.cos(frame / 9), 0.3])
            for marker, radius in enumerate((15.0, 30.0, 20.0)):
                direction = np.array([np.sin(angle[0] + marker), np.cos(angle[1]), angle[2]])
                point = center + radius * direction / np.linalg.norm(direction)
                point += rng.normal(scale=0.01, size=3)
                rows.append(("moving", trial, frame, marker, *point))
    frame = pd.DataFrame(rows, columns=["segment", "trial", "frame", "marker", "x", "y", "z"])
    frame.loc[(frame["trial"] == 1) & (frame["frame"] == 3), "x"] = np.nan  # one bad trial
    metadata = {
        "study": "cmc",
        "condition": {"marker_set": "M", "rom_deg": 30, "noise_mm": 0.0},
        "truth": {"center": center.tolist()},
        "parameters": {},
    }
    table = pa.Table.from_pandas(frame, preserve_index=False)
    table = table.replace_schema_metadata({b"jointbench": json.dumps(metadata).encode()})
    pq.write_table(table, path)
    return center


def test_lm_script_fits_and_turns_a_bad_trial_into_a_row(tmp_path):
    lm = _lm_script()
    dataset, output = tmp_path / "dataset.parquet", tmp_path / "out" / "dataset.parquet"
    center = _sphere_dataset(dataset)
    assert lm.main(["--out-dir", str(output.parent), str(dataset)]) == 0
    estimates = pd.read_parquet(output)
    check_estimates(
        estimates, kind="center", condition_keys=["marker_set", "rom_deg", "noise_mm"], method="LM"
    )
    assert "error_mm" not in estimates  # the benchmark's to compute
    truth = {"center": center.tolist()}
    estimates = scored_estimates(estimates, kind="center", truth=truth, source=str(output))
    good = estimates[estimates["trial"] != 1]
    assert good["converged"].all() and (good["error_mm"] < 0.1).all()
    bad = estimates[estimates["trial"] == 1].iloc[0]
    assert not bad["converged"] and np.isnan(bad["error_mm"]) and "NaN" in bad["status"]
    assert estimates["rom_deg"].tolist() == [30, 30, 30]


def test_lm_says_when_a_restart_finds_a_lower_minimum():
    """LM's self-check: an answer that is not f1's lowest minimum is named, a true one is not."""
    lm = _lm_script()
    rng = np.random.default_rng(3)
    directions = rng.normal(size=(60, 3, 3))
    directions /= np.linalg.norm(directions, axis=-1, keepdims=True)
    centre = np.array([10.0, -20.0, 30.0])
    markers = centre + directions * np.array([40.0, 55.0, 70.0])[None, :, None]
    truth_f1 = lm.profiled_f1(markers, centre)
    assert lm.self_check(markers, centre, truth_f1) is None
    # A centre 30 mm off, claimed with its own f1 as if it were a minimum: a restart goes lower.
    off = centre + np.array([30.0, 0.0, 0.0])
    doubt = lm.self_check(markers, off, lm.profiled_f1(markers, off))
    assert doubt is not None and doubt.startswith("local minimum: a restart from")


def test_a_run_of_no_study_with_a_paper_writes_an_empty_comparison(tmp_path):
    """A run of studies of the user's own, none with a paper, has no published value to
    check: the comparison's tables are written empty, with their columns, not a crash."""
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    outputs = {suffix: str(tmp_path / f"published_comparison.{suffix}") for suffix in ("csv", "md")}
    table = pipeline.check_published({}, outputs, config)
    assert table.empty
    assert list(pd.read_csv(outputs["csv"]).columns) == list(table.columns)
    assert "status" in table.columns
