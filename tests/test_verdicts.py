"""Seed ensembles: the member seeds, the verdict rule over seeds, and `snakemake verdicts`."""

from __future__ import annotations

import logging
import os
import re
import shutil
import subprocess
import sys

import pandas as pd
import pytest
import yaml
from scipy import stats
from workflow_copy import ROOT, SNAKEMAKE, copy_workflow, run_snakemake

from jointbench.comparison.snapshot import VERDICTS_BLOCK, readme_summary
from jointbench.comparison.tolerance import wilson_interval
from jointbench.configuration.config import load_config
from jointbench.ensembles.members import MEMBER_COLUMNS, collect_member, member_seed
from jointbench.ensembles.verdicts import (
    PROTOCOL_SHARES,
    SUMMARY_COLUMNS,
    VERDICT_RULE,
    seed_verdict,
    standout_summary,
    summarise_members,
)


def test_member_zero_is_the_default_run_and_the_others_are_independent():
    assert member_seed(20070507, 0) == 20070507
    seeds = [member_seed(20070507, member) for member in range(50)]
    assert len(set(seeds)) == 50
    # Fixed by (base seed, member) alone, whatever K: a larger ensemble extends a smaller one.
    assert seeds[7] == member_seed(20070507, 7)
    assert member_seed(1, 3) != member_seed(2, 3)


@pytest.mark.parametrize(("successes", "n"), [(0, 10), (10, 24), (20, 20), (15, 20), (1, 1)])
def test_wilson_interval_is_scipys(successes, n):
    expected = stats.binomtest(successes, n).proportion_ci(method="wilson")
    assert wilson_interval(successes, n) == pytest.approx((expected.low, expected.high), abs=1e-8)


@pytest.mark.parametrize(
    ("reproduced_in", "seeds", "verdict"),
    [
        (20, 20, "reproduced"),
        (15, 20, "reproduced"),
        (14, 20, "seed-dependent"),
        (10, 20, "seed-dependent"),
        (6, 20, "seed-dependent"),
        (5, 20, "not reproduced"),
        (0, 20, "not reproduced"),
        # One seed decides nothing: even a success is compatible with a coin toss.
        (1, 1, "seed-dependent"),
        (0, 0, "not applicable"),
    ],
)
def test_seed_verdict_by_the_interval_around_one_half(reproduced_in, seeds, verdict):
    assert seed_verdict(reproduced_in, seeds) == verdict


def test_summary_counts_only_seeds_where_a_value_was_evaluated():
    statuses = ["reproduced"] * 8 + ["not reproduced"] * 2 + ["not applicable"] * 5
    members = pd.DataFrame(
        {
            "member": range(len(statuses)),
            "base_seed": range(len(statuses)),
            "paper": "A",
            "study": "cmc",
            "entry": "claim",
            "id": "A1",
            "status": statuses,
            "margin": "",
            "reproduced": [f"value {i}" for i in range(len(statuses))],
        }
    )[MEMBER_COLUMNS]
    (row,) = summarise_members(members, {"A1": "a claim"}).to_dict("records")
    assert list(row) == SUMMARY_COLUMNS
    assert (row["seeds"], row["reproduced_in"], row["share"]) == (10, 8, 0.8)
    assert row["verdict"] == "seed-dependent"
    assert (row["default_seed"], row["default_reproduced"]) == ("reproduced", "value 0")


@pytest.mark.pipeline
def test_verdicts_target_runs_the_ensemble_and_is_never_stale(tmp_path):
    workdir = copy_workflow(tmp_path)
    reduced = ROOT / "tests" / "data" / "verdicts.yaml"
    first = run_snakemake(workdir, "verdicts", "--configfile", str(reduced))
    assert first.returncode == 0, first.stderr[-4000:]
    summary = pd.read_csv(workdir / "results" / "tables" / "verdicts.csv")
    assert list(summary.columns) == SUMMARY_COLUMNS
    assert set(summary["paper"]) == {"A", "B", "C", "S"}
    tested = summary[summary["seeds"] > 0]
    assert not tested.empty and (tested["seeds"] <= 2).all()
    assert "Verdict over seeds" in (workdir / "results" / "tables" / "verdicts.md").read_text()
    # One more seed runs its members and the summary, nothing else.
    more = tmp_path / "more.yaml"
    # Keys in the file's order: Snakemake compares parameters as written.
    overlay = {**yaml.safe_load(reduced.read_text()), "verdicts": {"seeds": 3}}
    more.write_text(yaml.safe_dump(overlay, sort_keys=False))
    dry = run_snakemake(workdir, "verdicts", "--dry-run", "--configfile", str(more))
    assert dry.returncode == 0, dry.stderr[-4000:]
    # The dry run's job counts: the new member of each study and the summary, nothing else.
    counts = dict(re.findall(r"^(\w+)\s+(\d+)$", dry.stdout + dry.stderr, flags=re.M))
    counts.pop("total", None)
    studies = ("cmc", "hinge", "hip", "hip_sta")
    members = {f"verdicts_member_{study}": "1" for study in studies}
    assert counts == {**members, "verdicts_summary": "1", "verdicts": "1"}, counts


@pytest.mark.pipeline
def test_the_readme_is_not_rewritten_from_verdicts_an_edit_made_stale(tmp_path):
    """`jointbench readme` rewrites the README's verdicts over seeds from
    results/tables/verdicts.csv while the `verdicts` target is up to date. After an
    estimator's edit it refuses, naming the jobs `snakemake -j2` would redo; once that has
    run, it still refuses the verdicts, which `snakemake -j2` does not carry into that table,
    naming the table, and leaves their block as it was."""
    workdir = copy_workflow(tmp_path)
    shutil.copytree(ROOT / "src", workdir / "src", ignore=shutil.ignore_patterns("*.egg-info"))
    environment = {**os.environ, "PYTHONPATH": str(workdir / "src")}
    reduced = str(ROOT / "tests" / "data" / "verdicts_one_study.yaml")
    made = subprocess.run(
        [
            str(SNAKEMAKE),
            "all",
            "verdicts",
            "-j2",
            "--workflow-profile",
            "none",
            "--directory",
            str(workdir),
            "-s",
            str(workdir / "Snakefile"),
            "--configfile",
            reduced,
        ],
        capture_output=True,
        text=True,
        timeout=900,
        env=environment,
    )
    assert made.returncode == 0, made.stderr[-4000:]
    # The default target too: the command refuses results it would redo. And a README to
    # rewrite.
    blocks = ("reproduction-summary", VERDICTS_BLOCK)
    readme = workdir / "README.md"
    readme.write_text("".join(f"<!-- {b}:start -->\n<!-- {b}:end -->\n" for b in blocks))
    code = "import sys; from jointbench.cli import main; sys.exit(main(sys.argv[1:]))"
    command = [sys.executable, "-c", code, "readme", "--configfile", reduced]
    current = subprocess.run(command, cwd=workdir, capture_output=True, text=True, env=environment)
    assert current.returncode == 0, current.stderr
    assert "Verdicts over" in readme.read_text()
    readme.write_text("".join(f"<!-- {b}:start -->\n<!-- {b}:end -->\n" for b in blocks))
    # An estimator's edit: every member of the ensemble may move.
    sphere = workdir / "src" / "jointbench" / "estimators" / "sphere.py"
    text = sphere.read_text()
    edited = text.replace("change <= tol_fun:", "change <= 2 * tol_fun:", 1)
    assert edited != text
    sphere.write_text(edited)
    rewritten = subprocess.run(
        command, cwd=workdir, capture_output=True, text=True, env=environment
    )
    assert rewritten.returncode != 0, rewritten.stdout
    # First the results the default target makes: `snakemake -j2` redoes the estimates.
    assert "is not up to date" in rewritten.stderr and "estimate_cmc (" in rewritten.stderr
    assert "Verdicts over" not in readme.read_text()
    remade = subprocess.run(
        [str(SNAKEMAKE), "-j2", "--workflow-profile", "none", "--configfile", reduced],
        cwd=workdir,
        capture_output=True,
        text=True,
        timeout=900,
        env=environment,
    )
    assert remade.returncode == 0, remade.stderr[-4000:]
    rewritten = subprocess.run(
        command, cwd=workdir, capture_output=True, text=True, env=environment
    )
    assert rewritten.returncode != 0, rewritten.stdout
    assert "results/tables/verdicts.csv" in rewritten.stderr
    assert "Verdicts over" not in readme.read_text()


def test_the_readme_states_the_rule_the_code_applies():
    readme = " ".join((ROOT / "README.md").read_text().split())
    assert VERDICT_RULE in readme


def test_a_member_warms_each_method_up_once(caplog):
    """An ensemble member pays each estimator's one-time work once, not once per condition:
    a warm-up fit costs up to a third of a batch."""
    config = load_config(ROOT / "config" / "config.yaml")
    hinge = {**config["studies"]["hinge"], "trials": 2, "estimators": ["planar", "radial"]}
    hinge["grid"] = {"protocol": ["knee"], "fe_rom_deg": [30, 60], "aa_ratio": [0.1]}
    config = {**config, "studies": {**config["studies"], "hinge": hinge}}
    with caplog.at_level(logging.INFO, logger="jointbench"):
        collected = collect_member(config, "hinge")
    assert len(collected) == 2 * 2 * 2
    warm_ups = [r.getMessage() for r in caplog.records if "warm-up fit" in r.getMessage()]
    assert len(warm_ups) == 2, warm_ups


def _summary_of(shares: dict[str, tuple[int, int]]) -> pd.DataFrame:
    """A verdicts summary with each id reproduced in ``k`` of ``n`` seeds."""
    rows = []
    for entry_id, (k, n) in shares.items():
        statuses = ["reproduced"] * k + ["not reproduced"] * (n - k)
        rows.append(
            pd.DataFrame(
                {
                    "member": range(n),
                    "base_seed": range(n),
                    "paper": entry_id[0],
                    "study": "cmc",
                    "entry": "claim",
                    "id": entry_id,
                    "status": statuses,
                    "margin": "",
                    "reproduced": "",
                }
            )
        )
    members = pd.concat(rows, ignore_index=True)[MEMBER_COLUMNS]
    return summarise_members(members, {i: f"claim {i}" for i in shares})


def test_the_readme_verdicts_are_generated_from_the_seed_shares():
    """Counts per paper and the closest calls, nearest a share of 1/2 first, with the
    intervals of the summary; a protocol share beside each when the sensitivity file gives
    one."""
    summary = _summary_of({"A1": (20, 20), "A2": (1, 20), "A4": (12, 20), "B2": (9, 20)})
    text = standout_summary(summary, closest=2)
    assert "**Verdicts over 20 base seeds**" in text
    assert "| A | 1 | 1 | 1 |" in text and "| B | 0 | 0 | 1 |" in text
    lines = [line for line in text.splitlines() if line.startswith(("| A", "| B"))]
    calls = [line for line in lines if "seeds" not in line and "of 20" in line]
    # 9/20 is nearer 1/2 than 12/20; the others are not among the two closest.
    assert [line.split(" | ")[0] for line in calls] == ["| B2", "| A4"]
    (b2,) = summary.loc[summary["id"] == "B2", "interval_95"]
    assert f"| 9 of 20 | {b2} | seed-dependent |" in calls[0]
    assert "protocols" not in text
    protocols = pd.DataFrame({"id": ["A4"], "reproduced_in": [7], "draws": [20]})
    with_protocols = standout_summary(summary, protocols, closest=2)
    assert "| protocols reproducing |" in with_protocols
    assert "| seed-dependent | 7 of 20 |" in with_protocols


@pytest.mark.skipif(
    not (ROOT / "results" / "tables" / "verdicts.csv").is_file(),
    reason="run `snakemake -j2 verdicts` first: no results/tables/verdicts.csv",
)
def test_the_readme_verdicts_are_current():
    summary = pd.read_csv(ROOT / "results" / "tables" / "verdicts.csv")
    protocols = ROOT / "results" / PROTOCOL_SHARES
    expected = standout_summary(
        summary, pd.read_csv(protocols) if protocols.is_file() else None
    ).strip()
    assert readme_summary(ROOT / "README.md", VERDICTS_BLOCK) == expected, (
        "README verdicts over seeds are stale: run `jointbench readme`"
    )
