"""How long Snakemake takes to plan a run with one tree's package and workflow against another's.

Each invocation of ``snakemake`` reads the workflow and plans its jobs before it runs any: the
config's checks, the checks of the rules of external estimators, the code fingerprint of every
script. This times ``snakemake -j2 --dry-run --quiet`` with the workflow and the package of two
checkouts (``old`` and ``new``), alternating between them so that the machine's load falls on
both alike, in two states:

* ``default, empty``: the default config, nothing run yet (results/ empty);
* ``reduced, finished``: ``tests/data/reduced.yaml`` over it, run to the end first, as
  ``tests/workflow_copy.py``'s ``finish_run`` does (the workflow copied, the package copied
  beside it on ``PYTHONPATH``), so that the dry run has nothing to do;
* ``large grid, empty``: the cmc study alone on a grid of ``--conditions`` conditions (both
  marker sets, as many RoMs and noise levels as it takes), nothing run yet: how the plan grows
  with a user's grid (its LM rule writes every condition's estimates in one job).

Run from anywhere::

    python benchmarks/snakemake_plan.py OLD_CHECKOUT NEW_CHECKOUT [--repeats 7] [--state ...]
        [--conditions 400] [--clock {wall,cpu}]

Prints the median and the minimum time of each checkout in each state, by wall clock (the
default) or, ``--clock cpu``, by the CPU time of the Snakemake process, which other processes'
load on a shared machine does not lengthen.
(:mod:`benchmarks.snakemake_start` times one checkout with and without the fingerprint's store.)
"""

from __future__ import annotations

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SNAKEMAKE = Path(sys.executable).with_name("snakemake")
STATES = ("default, empty", "reduced, finished", "large grid, empty")
OVERLAY = Path("tests", "data", "reduced.yaml")


def _workflow_copy(checkout: Path, workdir: Path, *, with_package: bool) -> Path:
    """The files a user clones from ``checkout`` (Snakefile, workflow/, config/) in
    ``workdir``, with a copy of its package under ``src/`` when ``with_package``."""
    workdir.mkdir(parents=True)
    shutil.copy(checkout / "Snakefile", workdir / "Snakefile")
    for folder in ("workflow", "config"):
        shutil.copytree(checkout / folder, workdir / folder)
    if with_package:
        ignored = shutil.ignore_patterns("*.egg-info")
        shutil.copytree(checkout / "src", workdir / "src", ignore=ignored)
    return workdir


def _command(workdir: Path, overlay: Path | None, *extra: str) -> list[str]:
    command = [str(SNAKEMAKE), "-j2", "--workflow-profile", "none"]
    command += ["--directory", str(workdir), "-s", str(workdir / "Snakefile"), *extra]
    return command + (["--configfile", str(overlay)] if overlay else [])


def _large_grid(conditions: int) -> str:
    """An overlay running the cmc study alone on ``conditions`` conditions (rounded up to a
    multiple of 40): both marker sets, twenty noise levels, the RoMs (5 to 90 degrees, up to
    18 of them) the rest takes."""
    roms = -(-conditions // 40)
    return (
        "studies:\n  cmc:\n    grid:\n      marker_set: [M, H]\n"
        f"      rom_deg: {[5 + 5 * i for i in range(roms)]}\n"
        f"      noise_mm: {[0.25 * (i + 1) for i in range(20)]}\n"
        "  hinge: {enabled: false}\n  hip: {enabled: false}\n  hip_sta: {enabled: false}\n"
    )


def _prepared(
    checkout: Path, folder: Path, state: str, conditions: int
) -> tuple[list[str], dict[str, str]]:
    """The dry-run command and its environment for ``checkout`` in ``state``, in ``folder``."""
    if state in ("default, empty", "large grid, empty"):
        workdir = _workflow_copy(checkout, folder, with_package=False)
        environment = {**os.environ, "PYTHONPATH": str(checkout / "src")}
        overlay = None
        if state == "large grid, empty":
            overlay = workdir / "large_grid.yaml"
            overlay.write_text(_large_grid(conditions))
        return _command(workdir, overlay, "--dry-run", "--quiet"), environment
    workdir = _workflow_copy(checkout, folder, with_package=True)
    overlay = checkout / OVERLAY
    environment = {**os.environ, "PYTHONPATH": str(workdir / "src")}
    subprocess.run(_command(workdir, overlay), env=environment, check=True, capture_output=True)
    return _command(workdir, overlay, "--dry-run", "--quiet"), environment


def _seconds(command: list[str], environment: dict[str, str], clock: str = "wall") -> float:
    """The time ``command`` takes: wall clock, or the CPU time of the processes it ran."""
    start, used = time.perf_counter(), _children_cpu()
    done = subprocess.run(command, env=environment, capture_output=True, text=True)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(command)} failed:\n{done.stderr[-2000:]}")
    return time.perf_counter() - start if clock == "wall" else _children_cpu() - used


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old", type=Path)
    parser.add_argument("new", type=Path)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--state", choices=STATES, action="append")
    parser.add_argument("--conditions", type=int, default=400)
    parser.add_argument("--clock", choices=("wall", "cpu"), default="wall")
    arguments = parser.parse_args()
    checkouts = {"old": arguments.old.resolve(), "new": arguments.new.resolve()}
    print(f"{arguments.clock} clock; large grid: {arguments.conditions} conditions")
    print("| state | checkout | median [s] | minimum [s] |")
    print("|---|---|---:|---:|")
    with tempfile.TemporaryDirectory() as scratch:
        for state in arguments.state or STATES:
            runs = {
                name: _prepared(
                    path, Path(scratch, state.split(",")[0], name), state, arguments.conditions
                )
                for name, path in checkouts.items()
            }
            for command, environment in runs.values():
                _seconds(command, environment)  # warms the store and the compiled kernels
            times: dict[str, list[float]] = {name: [] for name in runs}
            for _ in range(arguments.repeats):
                for name, (command, environment) in runs.items():
                    times[name].append(_seconds(command, environment, arguments.clock))
            for name, seconds in times.items():
                median, least = statistics.median(seconds), min(seconds)
                print(f"| {state} | {name} | {median:.2f} | {least:.2f} |", flush=True)


if __name__ == "__main__":
    main()
