"""How one study's cost grows with its number of trials, per Snakemake job.

    python benchmarks/scaling.py [--study cmc] [--factors 1 10 100] [--reduce-from 100]
    python benchmarks/scaling.py --study cmc --grid benchmarks/ehrig_cmc.yaml --trials 100 \
        --factors 1 10          # Ehrig-size: 54 conditions, 100 then 1000 trials each

Runs the study's target (`snakemake -j2 study_<name>`) in a fresh copy of the workflow once per
factor, with the config's trials multiplied by it, and prints every job's wall time, CPU time and
peak resident memory, then each rule's totals across factors. From ``--reduce-from`` on, the
study's grid is the small one of benchmarks/reduced.yaml (say so when quoting the numbers: the
table shows conditions beside trials). With today's code the default run costs about 17
CPU-minutes (1x 96 CPU-s, 10x 293 CPU-s, 100x on the reduced grid about 10 minutes).

The numbers come from the kernel, not from sampling: benchmarks/probe/sitecustomize.py is put on
PYTHONPATH so that every Python process of the run (Snakemake, each job's script, an external
estimator) records its own getrusage at exit. Shell-only jobs that start no Python are not seen;
the workflow has none. Snakemake's own process is shown as "snakemake (scheduler)".
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import pandas as pd
import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from workflow_copy import ROOT, SNAKEMAKE, copy_workflow

PROBE = ROOT / "benchmarks" / "probe"
REDUCED = ROOT / "benchmarks" / "reduced.yaml"
SCHEDULER = "snakemake (scheduler)"


@dataclass(frozen=True)
class Scale:
    """One run: the config's trials times ``factor``, on the full grid or the reduced one."""

    factor: int
    trials: int
    grid: dict[str, list] | None  # None: the grid of config/config.yaml

    def conditions(self, full_grid: dict[str, list]) -> int:
        count = 1
        for values in (self.grid or full_grid).values():
            count *= len(values)
        return count


def study_config(study: str) -> dict:
    """The study's block of config/config.yaml."""
    config = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    if study not in config["studies"]:
        raise ValueError(f"no study {study!r} in config/config.yaml: {sorted(config['studies'])}")
    return config["studies"][study]


def reduced_grid(study: str) -> dict[str, list]:
    """The study's small grid from benchmarks/reduced.yaml."""
    studies = yaml.safe_load(REDUCED.read_text())["studies"]
    if study not in studies:
        raise ValueError(f"benchmarks/reduced.yaml has no grid for study {study!r}")
    return studies[study]["grid"]


def grid_from(path: Path, study: str) -> dict[str, list]:
    """The study's grid from a YAML file shaped like the config (``studies: {name: {grid}}``)."""
    studies = yaml.safe_load(path.read_text())["studies"]
    if study not in studies or "grid" not in studies[study]:
        raise ValueError(f"{path} has no grid for study {study!r}")
    return studies[study]["grid"]


def scales(
    study: str,
    factors: list[int],
    reduce_from: int,
    *,
    trials: int | None = None,
    grid: dict[str, list] | None = None,
) -> list[Scale]:
    """One :class:`Scale` per factor: ``trials`` (default the config's) times the factor, on
    ``grid`` (default the config's; the reduced grid from ``reduce_from`` on)."""
    trials = study_config(study)["trials"] if trials is None else trials
    return [
        Scale(
            factor,
            trials * factor,
            grid or (reduced_grid(study) if factor >= reduce_from else None),
        )
        for factor in factors
    ]


def workflow_clone(folder: Path) -> Path:
    """What a user clones, its profiles/ included, in the new folder ``folder``/workflow, with
    an empty results/: Snakemake applies profiles/default there, as in a clone."""
    destination = folder / "workflow"
    destination.mkdir(parents=True)
    return copy_workflow(destination, profiles=True)


def run_scale(study: str, scale: Scale, folder: Path, jobs: int) -> tuple[float, list[dict]]:
    """Run the study at one scale in ``folder``; its wall time and every process's record."""
    workdir = workflow_clone(folder)
    overrides = {"trials": scale.trials, **({"grid": scale.grid} if scale.grid else {})}
    configfile = folder / "scale.yaml"
    configfile.write_text(yaml.safe_dump({"studies": {study: overrides}}))
    records = folder / "rusage"
    records.mkdir()
    environment = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join(filter(None, [str(PROBE), os.environ.get("PYTHONPATH")])),
        "JOINTBENCH_RUSAGE_DIR": str(records),
    }
    command = [str(SNAKEMAKE), f"study_{study}", f"-j{jobs}", "--configfile", str(configfile)]
    started = time.monotonic()
    with open(folder / "snakemake.log", "w") as log:
        done = subprocess.run(command, cwd=workdir, env=environment, stdout=log, stderr=log)
    wall = time.monotonic() - started
    if done.returncode != 0:
        raise RuntimeError(f"snakemake failed at {scale.factor}x; see {folder / 'snakemake.log'}")
    return wall, [json.loads(path.read_text()) for path in sorted(records.glob("*.json"))]


def job_label(record: dict) -> tuple[str, str]:
    """(rule, job) naming the process: a rule's script, Snakemake, or another interpreter."""
    argv = record["argv"] or [""]
    if record["rule"]:
        return record["rule"], ",".join(record["wildcards"].values())
    program = Path(argv[0]).name
    if program == "snakemake" or argv[0].endswith(os.path.join("snakemake", "__main__.py")):
        return SCHEDULER, ""
    # An external estimator's interpreter: its last argument is the output file.
    return program, Path(argv[-1]).stem if len(argv) > 1 else ""


def job_table(records: list[dict]) -> pd.DataFrame:
    """One row per process, in start order: rule, job, wall, CPU and peak RSS."""
    rows = []
    for record in sorted(records, key=lambda r: r["start"]):
        rule, job = job_label(record)
        # A job's own children (none today) are part of its cost; Snakemake's children are the
        # jobs themselves, listed on their own rows.
        children = record["children_cpu_s"] if rule != SCHEDULER else 0.0
        rows.append(
            {
                "rule": rule,
                "job": job,
                "wall_s": record["wall_s"],
                "cpu_s": record["cpu_s"] + children,
                "peak_rss_mb": max(
                    record["peak_rss_mb"],
                    record["children_peak_rss_mb"] if rule != SCHEDULER else 0.0,
                ),
            }
        )
    return pd.DataFrame(rows, columns=["rule", "job", "wall_s", "cpu_s", "peak_rss_mb"])


def total_cpu(records: list[dict]) -> float:
    """The whole run's CPU time: Snakemake's own and that of every process it waited for."""
    schedulers = [r for r in records if job_label(r)[0] == SCHEDULER]
    if len(schedulers) != 1:
        raise RuntimeError(f"expected one Snakemake process record, found {len(schedulers)}")
    return schedulers[0]["cpu_s"] + schedulers[0]["children_cpu_s"]


def rule_growth(tables: dict[int, pd.DataFrame]) -> pd.DataFrame:
    """Per rule and factor: jobs, summed CPU, largest peak RSS, CPU relative to the first factor."""
    per_factor = []
    for factor, table in tables.items():
        grouped = table.groupby("rule").agg(
            jobs=("job", "size"), cpu_s=("cpu_s", "sum"), peak_rss_mb=("peak_rss_mb", "max")
        )
        per_factor.append(grouped.assign(factor=factor).reset_index())
    growth = pd.concat(per_factor, ignore_index=True)
    first = growth[growth["factor"] == min(tables)].set_index("rule")["cpu_s"]
    growth["cpu_ratio"] = growth["cpu_s"] / growth["rule"].map(first)
    values = ["cpu_s", "cpu_ratio", "peak_rss_mb"]
    return growth.pivot(index="rule", columns="factor", values=values)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--study", default="cmc")
    parser.add_argument("--factors", type=int, nargs="+", default=[1, 10, 100])
    parser.add_argument(
        "--reduce-from",
        type=int,
        default=100,
        help="factors from this one on use benchmarks/reduced.yaml's grid (default 100)",
    )
    parser.add_argument(
        "--trials", type=int, help="trials per condition at 1x (default: the config's)"
    )
    parser.add_argument(
        "--grid",
        type=Path,
        help="YAML with studies.<study>.grid: run every factor on this grid "
        "(e.g. benchmarks/ehrig_cmc.yaml, 54 conditions)",
    )
    parser.add_argument("--jobs", type=int, default=2, help="snakemake -j (default 2)")
    parser.add_argument("--keep", type=Path, help="run in this folder and keep it")
    parser.add_argument("--json", type=Path, help="also write every process record here")
    arguments = parser.parse_args(argv)
    if not SNAKEMAKE.exists():
        parser.error(f"no snakemake beside this Python ({SNAKEMAKE})")

    full_grid = study_config(arguments.study)["grid"]
    folder = arguments.keep or Path(tempfile.mkdtemp(prefix="jointbench-scaling-"))
    tables, summary, everything = {}, [], {}
    pd.set_option("display.width", 120)
    grid = grid_from(arguments.grid, arguments.study) if arguments.grid else None
    for scale in scales(
        arguments.study,
        arguments.factors,
        arguments.reduce_from,
        trials=arguments.trials,
        grid=grid,
    ):
        conditions = scale.conditions(full_grid)
        grid_name = (
            f"grid of {arguments.grid}"
            if grid
            else ("reduced grid" if scale.grid else "config grid")
        )
        print(
            f"\n== {arguments.study} {scale.factor}x: {scale.trials} trials x {conditions} "
            f"conditions ({grid_name}), snakemake -j{arguments.jobs}",
            flush=True,
        )
        run_folder = folder / f"x{scale.factor}"
        wall, records = run_scale(arguments.study, scale, run_folder, arguments.jobs)
        table = job_table(records)
        print(table.to_string(index=False, float_format=lambda x: f"{x:.2f}"))
        tables[scale.factor] = table
        everything[scale.factor] = records
        summary.append(
            {
                "factor": scale.factor,
                "trials": scale.trials,
                "conditions": conditions,
                "wall_s": wall,
                "cpu_s": total_cpu(records),
                "max_job_rss_mb": table.loc[table["rule"] != SCHEDULER, "peak_rss_mb"].max(),
            }
        )
    summary = pd.DataFrame(summary)
    summary["cpu_per_trial_condition_ms"] = (
        1e3 * summary["cpu_s"] / (summary["trials"] * summary["conditions"])
    )
    print("\n== per rule: summed CPU (s), ratio to the first factor, largest peak RSS (MB)")
    print(rule_growth(tables).to_string(float_format=lambda x: f"{x:.2f}"))
    print("\n== whole runs")
    print(summary.to_string(index=False, float_format=lambda x: f"{x:.2f}"))
    if arguments.json:
        arguments.json.write_text(json.dumps({str(k): v for k, v in everything.items()}, indent=1))
    if not arguments.keep:
        shutil.rmtree(folder)
    return 0


if __name__ == "__main__":
    sys.exit(main())
