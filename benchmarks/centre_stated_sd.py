"""Whether a checked centre of rotation that reads ``ok`` lies within its stated SD of the
truth, per method, on near hinges and on small caps, as
:mod:`jointbench.estimators.centre_precision`'s docstring quotes it.

Usage::

    python benchmarks/centre_stated_sd.py [--seeds 100]

Prints, with the current code (``jointbench.fit_center``), per case and method, over
``--seeds`` seeded trials: how many read ``ok``, how many of those lie more than three of
their SDs (``center_sd_mm``, along the least determined direction) from the truth, the share
beyond one SD, the mean of the squared ratio of the error's length to the SD, and the
largest ratio. Cases:

* ``tests/test_near_hinge_centre.py``'s near hinge: 40 degrees of flexion and 2, 4 or 8
  about a normal axis, 200 frames, 0.5 mm noise;
* ``blind_spots.py``'s swings of four markers 200 mm from the centre about two axes by 5, 10
  and 20 degrees, 120 frames, 0.5 and 1 mm noise.

Run it with the tree of another version of the code on ``PYTHONPATH`` to compare.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

import jointbench

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from blind_spots import swing
from rigs import JOINT
from test_near_hinge_centre import _near_hinge

METHODS = ("LS", "NM", "BC", "IS", "MA", "SCoRE")


def _cases() -> dict[str, Callable[[int], tuple[np.ndarray, np.ndarray]]]:
    """Case name -> seed -> (markers ``(N, n, 3)`` [mm], true centre ``(3,)`` [mm])."""
    cases = {}
    for other_deg in (2.0, 4.0, 8.0):
        cases[f"near hinge, {other_deg:g} deg off-axis"] = lambda seed, o=other_deg: (
            _near_hinge(seed, other_deg=o),
            JOINT,
        )
    for rom_deg in (5.0, 10.0, 20.0):
        for noise_mm in (0.5, 1.0):
            cases[f"cap {rom_deg:g} deg, {noise_mm:g} mm"] = lambda seed, r=rom_deg, z=noise_mm: (
                swing(np.random.default_rng(1000 + seed), 200.0, r, z)
            )
    return cases


def _row(ratios: list[float], n_ok: int) -> str:
    """One table row's numbers of the error-to-SD ``ratios`` of the ``n_ok`` answers read ok."""
    if not n_ok:
        return "| 0 | | | | |"
    z = np.array(ratios)
    return (
        f"| {n_ok} | {int(np.sum(z > 3.0))} | {np.mean(z > 1.0):.2f} | {np.mean(z**2):.2f} "
        f"| {z.max():.1f} |"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=100)
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    print("| case | method | ok | beyond 3 SDs | beyond 1 SD | mean (error/SD)^2 | largest |")
    print("|---|---|---|---|---|---|---|")
    for name, make in _cases().items():
        trials = [make(seed) for seed in range(args.seeds)]
        for method in METHODS:
            ratios = []
            for markers, truth in trials:
                result = jointbench.fit_center(markers, method)
                if result.status == "ok":
                    error = float(np.linalg.norm(result.center - truth))
                    ratios.append(error / result.diagnostics["center_sd_mm"])
            print(f"| {name} | {method} {_row(ratios, len(ratios))}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
