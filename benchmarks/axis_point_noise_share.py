"""Measure the combined axis point's noise-share check, as the README quotes it.

Usage::

    python benchmarks/axis_point_noise_share.py [--seeds 400] [--trials 30]

Prints, with the current code (the checked one-segment axis methods,
``registry.many("axis", method)``), per method and case: the ``ok`` answers before the check
(``ok``, or the check's warning alone: :func:`jointbench.estimators.precision.annotate_point`
with the stated noise's share not below 1) and now, how many of each have their point beyond 3
of its stated SDs from the true axis (a squared Mahalanobis distance above 9), and the mean
squared Mahalanobis distance (2 expected). On:

* swings about z of 5, 10 and 20 degrees, 0.5, 1 and 2 mm, four markers about 100 mm from the
  axis (``tests/test_axis_sd_validity.py``'s generator), ``--seeds`` each;
* paper B's grid as the hinge study simulates it (knee and MCP, FE 30, 60 and 90 degrees, AA
  0.1 to 0.7 times FE, 1 mm, the study's base seed), ``--trials`` each: the combined answers
  ``ok`` before and now, how far off the axis those the check refuses lie, and the largest
  share read.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from jointbench.estimators import registry

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_axis_motion_check import paper_b_trials
from test_axis_point_sd import (
    PAPER_B_GRID,
    PAPER_B_SEED,
    POINT_NOT_DETERMINED,
    squared_mahalanobis,
)
from test_axis_sd_validity import swing

ARCS_DEG = (5.0, 10.0, 20.0)
NOISES_MM = (0.5, 1.0, 2.0)
METHODS = ("planar", "radial", "combined")
SHARE_WARNING = f"{POINT_NOT_DETERMINED}under the stated noise the noise's own term"


def ok_before(result) -> bool:
    """Whether ``result`` read ``ok`` before the check: ``ok``, or the check's warning alone."""
    return result.status == "ok" or (
        result.status.startswith(SHARE_WARNING) and "; warning: " not in result.status
    )


def summary(distances: list[float]) -> str:
    """``ok`` count, beyond 3 SDs, mean squared Mahalanobis distance."""
    if not distances:
        return "0"
    beyond = sum(d > 9.0 for d in distances)
    return f"{len(distances)}, {beyond}, {np.mean(distances):.2f}"


def swings(seeds: int) -> None:
    print("| method | arc | noise | before: ok, beyond 3 SD, mean | now |")
    print("|---|---:|---:|---|---|")
    for arc_deg in ARCS_DEG:
        for noise in NOISES_MM:
            trials = np.stack([swing(seed, arc_deg, noise=noise) for seed in range(seeds)])
            for method in METHODS:
                checked = registry.many("axis", method)(trials)
                before = [squared_mahalanobis(r) for r in checked if ok_before(r)]
                now = [squared_mahalanobis(r) for r in checked if r.status == "ok"]
                print(
                    f"| {method} | {arc_deg:g}° | {noise:g} mm | {summary(before)} | "
                    f"{summary(now)} |"
                )


def paper_b(trials: int) -> None:
    n_before = n_now = 0
    refused, shares = [], []
    for condition in PAPER_B_GRID:
        moving = paper_b_trials(*condition, trials, base_seed=PAPER_B_SEED)
        for result in registry.many("axis", "combined")(moving):
            share = result.diagnostics.get("axis_point_noise_share", math.nan)
            if not math.isnan(share):
                shares.append((share, condition))
            n_before += ok_before(result)
            n_now += result.status == "ok"
            if ok_before(result) and result.status != "ok":
                # The true axis is x: the point's offset across it.
                refused.append((condition, float(np.hypot(*result.point[1:]))))
    print(f"\npaper B's grid, {trials} trials a condition: combined ok {n_before} -> {n_now}")
    for condition, off_mm in refused:
        print(f"  refused: {condition}, point {off_mm:.2f} mm off the axis")
    largest, where = max(shares)
    print(f"  largest share read: {largest:.3f} ({where}), of {len(shares)} read")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=400)
    parser.add_argument("--trials", type=int, default=30)
    args = parser.parse_args()
    swings(args.seeds)
    paper_b(args.trials)


if __name__ == "__main__":
    main()
