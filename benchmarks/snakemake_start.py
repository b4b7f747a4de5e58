"""How long Snakemake takes to decide what to run, with and without the fingerprint's store.

Every Snakemake process fingerprints the code of each rule's script (:mod:`jointbench.fingerprint`).
Without a store (``JOINTBENCH_CACHE=off``) it parses every module of the package each time; with
one, it reads what an earlier process stored. Run from a clone (a finished ``results/`` or not:
the dry run's work is the same up to the listing of the jobs)::

    python benchmarks/snakemake_start.py [--repeats 5] [-- extra snakemake arguments]

The two variants alternate; the store is warmed by one run first and not counted. Prints the
minimum and the median wall time of ``snakemake -j2 --dry-run --quiet`` for each.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path


def _dry_run(store: str, extra: list[str]) -> float:
    """Seconds of one ``snakemake --dry-run`` with ``JOINTBENCH_CACHE=store``."""
    snakemake = Path(sys.executable).with_name("snakemake")
    command = [str(snakemake), "-j2", "--dry-run", "--quiet", *extra]
    start = time.perf_counter()
    subprocess.run(
        command, env={**os.environ, "JOINTBENCH_CACHE": store}, check=True, capture_output=True
    )
    return time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("extra", nargs="*", help="further snakemake arguments")
    arguments = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        _dry_run(folder, arguments.extra)  # warms the store
        times: dict[str, list[float]] = {"no store": [], "a warm store": []}
        for _ in range(arguments.repeats):
            times["no store"].append(_dry_run("off", arguments.extra))
            times["a warm store"].append(_dry_run(folder, arguments.extra))
    print("| snakemake -j2 --dry-run | minimum [s] | median [s] |")
    print("|---|---:|---:|")
    for variant, seconds in times.items():
        print(f"| {variant} | {min(seconds):.2f} | {statistics.median(seconds):.2f} |")


if __name__ == "__main__":
    main()
