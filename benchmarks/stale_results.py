"""What each kind of edit reruns, as a table: the mutation suite's dry runs side by side.

Run the suite with a report file, once per code version to compare::

    JOINTBENCH_MUTATION_REPORT=after.json pytest tests/test_stale_results.py
    python benchmarks/stale_results.py after.json [before.json]

Each cell counts the jobs the dry run scheduled after the edit (``all`` left out), and names
up to four of their rules; ``nothing`` means Snakemake saw nothing to do.
"""

from __future__ import annotations

import argparse
import json
from collections import Counter
from pathlib import Path


def _cell(jobs: list[str] | None) -> str:
    """``n jobs: rule, rule (+k)`` for one dry run. A rule listed with wildcard values counts
    one job per value (every rule of the default grain has at most one wildcard)."""
    if jobs is None:
        return "not run"
    rules = sorted(job for job in jobs if "[" not in job)
    if not rules:
        return "nothing"
    per_value = Counter(job.split("[", 1)[0] for job in jobs if "[" in job)
    count = sum(per_value.get(rule, 1) for rule in rules)
    shown = ", ".join(rules[:4]) + (f" (+{len(rules) - 4} rules)" if len(rules) > 4 else "")
    return f"{count} jobs: {shown}"


def table(after: dict[str, list[str]], before: dict[str, list[str]] | None) -> str:
    header = "| edit | scheduled |" if before is None else "| edit | before | after |"
    rule = "|---|---|" if before is None else "|---|---|---|"
    rows = [header, rule]
    for kind, jobs in after.items():
        cells = [_cell(jobs)] if before is None else [_cell(before.get(kind)), _cell(jobs)]
        rows.append(f"| {kind} | {' | '.join(cells)} |")
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("after", type=Path)
    parser.add_argument("before", type=Path, nargs="?")
    arguments = parser.parse_args(argv)
    after = json.loads(arguments.after.read_text())
    before = json.loads(arguments.before.read_text()) if arguments.before else None
    print(table(after, before))


if __name__ == "__main__":
    main()
