"""Command line: ``jointbench snapshot``, ``jointbench readme`` and ``jointbench fit``."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

__all__ = ["main"]


def _snapshot(args: argparse.Namespace) -> int:
    from jointbench.study.snapshot import snapshot_table

    table = snapshot_table(args.results / "collected")
    if table.empty:
        print(f"no collected results under {args.results}; run `snakemake -j2` first")
        return 1
    args.output.parent.mkdir(parents=True, exist_ok=True)
    table.to_csv(args.output, index=False, float_format="%.12g")
    print(f"wrote {len(table)} values to {args.output}")
    return 0


def _readme(args: argparse.Namespace) -> int:
    from jointbench.pipeline import paper_labels
    from jointbench.study.snapshot import reproduction_summary, update_readme

    comparison = pd.read_csv(args.results / "tables" / "published_comparison.csv")
    changed = update_readme(args.readme, reproduction_summary(comparison, paper_labels()))
    print(f"{args.readme}: summary {'updated' if changed else 'already current'}")
    return 0


def _read_markers(path: Path) -> np.ndarray:
    """Long CSV with columns frame, marker, x, y, z [mm] -> (n_frames, n_markers, 3)."""
    frame = pd.read_csv(path)
    missing = {"frame", "marker", "x", "y", "z"} - set(frame.columns)
    if missing:
        raise ValueError(f"{path}: missing columns {sorted(missing)}")
    frame = frame.sort_values(["frame", "marker"])
    n_frames, n_markers = frame["frame"].nunique(), frame["marker"].nunique()
    if len(frame) != n_frames * n_markers:
        raise ValueError(
            f"{path}: every frame needs every marker ({len(frame)} rows for "
            f"{n_frames} frames × {n_markers} markers)"
        )
    return frame[["x", "y", "z"]].to_numpy(float).reshape(n_frames, n_markers, 3)


def _fit(args: argparse.Namespace) -> int:
    import jointbench

    markers = _read_markers(args.markers)
    if args.kind == "center":
        result = jointbench.fit_center(markers, method=args.method)
        print(f"centre (mm): {np.array2string(result.center, precision=3)}")
    else:
        result = jointbench.fit_axis(markers, method=args.method)
        print(f"point (mm): {np.array2string(result.point, precision=3)}")
        print(f"direction: {np.array2string(result.direction, precision=5)}")
    print(f"converged: {result.converged} ({result.iterations} iterations, {result.status})")
    return 0


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="jointbench", description=__doc__)
    sub = parser.add_subparsers(dest="command", required=True)

    snap = sub.add_parser("snapshot", help="write the regression snapshot of tabulated means")
    snap.add_argument("--results", type=Path, default=Path("results"))
    snap.add_argument("--output", type=Path, default=Path("tests/snapshots/summary.csv"))
    snap.set_defaults(run=_snapshot)

    readme = sub.add_parser("readme", help="refresh the README's reproduction summary")
    readme.add_argument("--results", type=Path, default=Path("results"))
    readme.add_argument("--readme", type=Path, default=Path("README.md"))
    readme.set_defaults(run=_readme)

    fit = sub.add_parser("fit", help="fit a centre or axis to a marker CSV (frame,marker,x,y,z)")
    fit.add_argument("kind", choices=["center", "axis"])
    fit.add_argument("markers", type=Path)
    fit.add_argument("--method", default=None)
    fit.set_defaults(run=_fit)

    args = parser.parse_args(argv)
    if args.command == "fit" and args.method is None:
        args.method = "NM" if args.kind == "center" else "combined"
    try:
        return args.run(args)
    except ValueError as error:
        print(f"jointbench: {error}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
