"""Measure the support verdict's test of the frames' independence, as the README quotes it.

Usage::

    python benchmarks/frame_independence.py [--draws 30]

Prints, with the current code:

* the real knee trial (``data/functional-trials/right_knee.c3d``): per method of every kind,
  whether the status says the frames are not independent, and the independent frames counted;
* 30 noisy frames (0.5 mm) of a circumduction, as drawn and linearly interpolated tenfold: per
  ``--draws`` draws and each of NM, BC, IS and LS, how many fits read ``ok``, how many carry the
  caveat, the median independent frames counted, and the median error over ``center_sd_mm``
  of the fits that read ``ok``;
* NM centres of 3000 frames under 0.3 mm of noise and a slow drift of 0.25 mm: the same;
* a marker sliding 3, 5 and 10 mm with a 30 degree hinge over 60 frames: per axis method, how
  many of 20 draws carry the caveat, and how many read ``ok`` yet lie more than 5 SDs and 5
  degrees off;
* the false alarms of the check's own numbers over 99,200 trials of independent noise.

The generators are those of ``tests/test_frame_independence.py``.
"""

from __future__ import annotations

import argparse
import collections
import sys
import warnings
from pathlib import Path

import numpy as np

import jointbench
from jointbench.geometry import angle_between_lines_deg, rotation_matrix, unit

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_frame_independence import (
    KNEE,
    WARNING,
    _body,
    _interpolated,
    _moved,
    _noisy,
    _swing,
    drifting,
    independent_alarms,
)

CENTRE_METHODS = ("NM", "BC", "IS", "LS")


def knee() -> None:
    """Every method of every kind on the real knee trial, shank in the thigh's frame."""
    recording = jointbench.read(KNEE)
    for kind in ("center", "axis", "joint_center"):
        prepared = jointbench.prepare(
            recording, kind, "RLEG1,RLEG2,RLEG3,RATT", "RTHI1,RTHI2,RTHI3,RGT"
        )
        for method in jointbench.methods(kind):
            result = prepared.fit(method).result
            independent = result.diagnostics.get("support_independent_frames", float("nan"))
            print(
                f"knee {kind:12s} {method:20s} caveat {WARNING in result.status}, "
                f"independent frames {independent:.1f} of {prepared.usable.size}"
            )


def _centre_counts(label: str, trials: list[np.ndarray], methods: tuple[str, ...]) -> None:
    """Over the fits of ``methods`` to ``trials``: those that read ``ok``, those with the
    caveat, the median independent frames counted, and the median error over ``center_sd_mm``
    of all fits and of the ``ok`` ones; the true centre is the origin."""
    counts: collections.Counter = collections.Counter()
    independent, ratios, ok_ratios = [], [], []
    for markers in trials:
        for method in methods:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                result = jointbench.fit_center(markers, method=method)
            counts["fits"] += 1
            counts["ok"] += result.status == "ok"
            counts["caveat"] += WARNING in result.status
            if "support_independent_frames" in result.diagnostics:
                independent.append(result.diagnostics["support_independent_frames"])
            if "center_sd_mm" in result.diagnostics:
                ratio = np.linalg.norm(result.center) / result.diagnostics["center_sd_mm"]
                ratios.append(ratio)
                if result.status == "ok":
                    ok_ratios.append(ratio)
    print(
        f"{label}: {counts['fits']} fits, {counts['ok']} ok, {counts['caveat']} with the caveat; "
        f"median independent frames {_median(independent):.1f}; error / center_sd_mm median "
        f"{_median(ratios):.2f}, of the ok ones {_median(ok_ratios):.2f}"
    )


def _median(values: list[float]) -> float:
    return float(np.median(values)) if values else float("nan")


def interpolated(draws: int) -> None:
    """Noisy frames as drawn and interpolated tenfold (``draws`` seeds)."""
    for factor in (1, 10):
        trials = []
        for seed in range(draws):
            rng = np.random.default_rng(seed)
            markers = _moved(_body(rng), _swing(30))
            trials.append(_interpolated(markers + _noisy(rng, markers.shape, 0.5), factor))
        _centre_counts(f"30 frames interpolated x{factor}", trials, CENTRE_METHODS)


def drift(draws: int) -> None:
    """NM centres under 0.3 mm of noise and a slow 0.25 mm drift (``draws`` draws)."""
    rng = np.random.default_rng(21)
    trials = [drifting(rng, 3000, 0.25) for _ in range(draws)]
    _centre_counts("3000 frames, 0.3 mm noise, 0.25 mm slow drift", trials, ("NM",))


def sliding() -> None:
    """A marker sliding with a hinge's flexion: caveats and silent wrong axes, 20 draws."""
    n_frames, rom = 60, np.radians(30.0)
    flexion = rom * np.sin(np.linspace(0.0, np.pi, n_frames))
    turned = rotation_matrix(np.outer(flexion, [0.0, 0.0, 1.0]))
    for slide_mm in (3.0, 5.0, 10.0):
        counts: collections.Counter = collections.Counter()
        for seed in range(20):
            rng = np.random.default_rng(seed)
            body = np.repeat(_body(rng)[None], n_frames, axis=0)
            body[:, 0] += np.outer(flexion / rom, unit(rng.normal(size=3))) * slide_mm
            markers = np.einsum("kij,kpj->kpi", turned, body) + _noisy(rng, body.shape, 0.5)
            for method in jointbench.methods("axis"):
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore")
                    result = jointbench.fit_axis(markers, method=method)
                error = float(angle_between_lines_deg(result.direction, [0.0, 0.0, 1.0]))
                off = error > max(5.0 * result.diagnostics.get("axis_sd_deg", np.nan), 5.0)
                counts[method, "caveat"] += WARNING in result.status
                counts[method, "ok and off"] += off and result.status == "ok"
        print(f"sliding {slide_mm:g} mm:", dict(sorted(counts.items())))


def false_alarms() -> None:
    """Alarms over 99,200 trials: 3 to 10 markers, 32 to 5,000 frames (fewer frames cannot
    raise one)."""
    rng = np.random.default_rng(5)
    alarms = total = 0
    for n_markers in (3, 4, 6, 10):
        for n_frames in (32, 33, 64, 100, 153, 500, 2000, 5000):
            n_trials = 4000 if n_frames <= 500 else 400
            alarms += independent_alarms(rng, n_markers, n_frames, n_trials, 30.0)
            total += n_trials
    print(f"independent noise: {alarms} alarms in {total} trials")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--draws", type=int, default=30, help="draws per condition")
    args = parser.parse_args(argv)
    knee()
    interpolated(args.draws)
    drift(args.draws)
    sliding()
    false_alarms()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
