"""Fuzz every registered centre and axis estimator on noise-free and degenerate data.

Usage::

    python benchmarks/fuzz_estimators.py [--hinges 120] [--seed 0]

Families (the generators of ``tests/test_conformance.py``):

* noise-free hinges at random orientations (3-5 markers, 20-120 degrees): an axis answer more
  than its claimed recovery off the true axis with status "ok" is a silent wrong answer;
  the checked call (``jointbench.fit_axis``) is compared with the registered function alone;
* 1 and 2 markers drawn at random, and three collinear markers translating along their line:
  any "ok" is a silent wrong answer (nothing about such data supports a centre or an axis).

Prints per method the silent wrong answers, unchecked and checked.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

import jointbench
from jointbench.estimators import registry
from jointbench.geometry import angle_between_lines_deg

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_conformance import _collinear_translation, _few_markers, random_hinge


def _silent_hinge_errors(method: str, hinges, checked: bool) -> tuple[int, int, float]:
    """(silent wrong "ok" answers, answers off by more than the claim, worst angle [deg])."""
    fit = registry.get("axis", method, checked=checked)
    claim = np.degrees(registry.claims("axis", method).recovery or 1e-4)
    silent = off = 0
    worst = 0.0
    for markers, axis, _ in hinges:
        result = fit(markers)
        angle = angle_between_lines_deg(result.direction, axis)
        worst = max(worst, angle)
        if angle > claim:
            off += 1
            silent += result.status == "ok"
    return silent, off, worst


def _degenerate_ok(kind: str, method: str, cases) -> tuple[int, int]:
    """(calls answered "ok", calls answered at all) on ``cases``."""
    fit = jointbench.fit_center if kind == "center" else jointbench.fit_axis
    ok = answered = 0
    for markers in cases:
        try:
            result = fit(markers, method=method)
        except ValueError:
            continue
        answered += 1
        ok += result.status == "ok"
    return ok, answered


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--hinges", type=int, default=120)
    parser.add_argument("--degenerate", type=int, default=10)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    hinges = [random_hinge(np.random.default_rng(args.seed + i)) for i in range(args.hinges)]
    print(f"noise-free hinges: {args.hinges}")
    print(f"{'method':10s} {'unchecked silent/off/worst':>30s} {'checked silent/off/worst':>30s}")
    for method in jointbench.methods("axis"):
        row = [_silent_hinge_errors(method, hinges, checked) for checked in (False, True)]
        cells = [f"{s:4d} {o:4d} {w:10.3g} deg" for s, o, w in row]
        print(f"{method:10s} {cells[0]:>30s} {cells[1]:>30s}")
    cases = [
        _few_markers(n_markers, args.seed + i)
        for n_markers in (1, 2)
        for i in range(args.degenerate)
    ] + [_collinear_translation(args.seed + i) for i in range(args.degenerate)]
    print(f"\ndegenerate data ({len(cases)} calls: 1 and 2 random markers, collinear translation)")
    total_ok = 0
    for kind in ("center", "axis"):
        for method in jointbench.methods(kind):
            ok, answered = _degenerate_ok(kind, method, cases)
            total_ok += ok
            print(f"{kind:7s} {method:10s} ok {ok:3d} of {answered:3d} answered")
    print(f"silent 'ok' on degenerate data: {total_ok}")


if __name__ == "__main__":
    main()
