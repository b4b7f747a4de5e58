"""Count the answers far from the truth that the checks still pass, as the README's list of
what they do not catch quotes them.

Usage::

    python benchmarks/blind_spots.py [--seeds 60] [--only axes]

Prints, with the current code (the public calls ``jointbench.fit_center``, ``fit_axis`` and
``fit_joint_center``), per case and method, how many of ``--seeds`` seeded trials read ``ok``
while more than 10 mm (a centre) or 10 degrees (an axis) from the truth, the largest such
error, and the largest SD those answers stated:

* one segment's centre with its four markers 500 mm from it on a 10 degree two-axis swing
  (the least-squares sphere's bias);
* one segment's centre on a 10 degree swing with noise of 0.1, 0.1 and 2 mm along x, y and z;
* a hinge's axis on a 10 degree arc with noise of 0.3, 0.3 and 1 mm along x, y and z;
* a hinge's axis with four markers 5 mm from it, scattered by 3 mm, 1 mm noise;
* a hinge's axis with two markers 3 mm from it and one, two or three 100 mm from it, on arcs
  of 10, 20 and 30 degrees, noise drawn between 0.5 and 1 mm;
* a hinge's axis on arcs of 5 and 10 degrees (the radial cost);
* a hip joint centre (``tests/test_pose_noise.py``'s hips on a 30 degree two-axis swing) with
  three thigh markers 3 mm off a 50 mm line (20 geometries, five times ``--seeds`` draws in
  all), and with one thigh marker sliding 5 and 10 mm over the 60 frames.

Each trial draws its geometry and noise from its seed; 0.5 mm noise where no other is named.
"""

from __future__ import annotations

import argparse
import functools
import sys
import warnings
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

import jointbench
from jointbench.geometry import angle_between_lines_deg, rotation_matrix, unit

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_pose_noise import CENTRE, _hip, _noisy, _thin_thigh

# An answer this far from the truth is far [mm, deg].
FAR = 10.0


def swing(rng: np.random.Generator, distance_mm: float, rom_deg: float, noise_mm) -> tuple:
    """Four markers ``distance_mm`` from a centre, scattered by up to 20 mm, swung about two
    axes by ``rom_deg`` over 120 frames: markers ``(120, 4, 3)`` [mm] with normal noise of SD
    ``noise_mm`` (a number or one per axis) and the centre ``(3,)`` [mm]."""
    centre = rng.uniform(-50.0, 50.0, 3)
    turn = rotation_matrix(unit(rng.normal(size=3)) * rng.uniform(0.0, np.pi))
    body = distance_mm * unit(rng.normal(size=3)) + rng.normal(
        scale=min(20.0, distance_mm / 2.0), size=(4, 3)
    )
    return swung(rng, turn, body, 120, rom_deg, noise_mm, centre), centre


def swung(
    rng: np.random.Generator,
    turn: np.ndarray,
    body: np.ndarray,
    n_frames: int,
    rom_deg: float,
    noise_mm,
    centre: np.ndarray,
) -> np.ndarray:
    """``body`` ``(n, 3)`` [mm] about ``centre`` ``(3,)`` [mm] swung by ``rom_deg`` about two
    axes turned by ``turn`` ``(3, 3)``: ``(n_frames, n, 3)`` [mm] with normal noise of SD
    ``noise_mm`` (a number or one per axis)."""
    t = np.linspace(0.0, 1.0, n_frames)
    phase = rng.uniform(0.0, 2.0 * np.pi, 3)
    angles = np.column_stack(
        [
            np.sin(2 * np.pi * t + phase[0]),
            np.sin(2 * np.pi * 1.37 * t + phase[1]),
            0.3 * np.sin(2 * np.pi * 0.71 * t + phase[2]),
        ]
    )
    markers = np.einsum("kij,pj->kpi", rotation_matrix(np.radians(rom_deg) * angles @ turn.T), body)
    return markers + centre + rng.normal(size=markers.shape) * np.asarray(noise_mm)


def _hinge(
    rng: np.random.Generator, arc_deg: float, noise_mm, distance_mm=100.0, spread_mm=25.0
) -> tuple:
    """Four markers about ``distance_mm`` from a hinge's axis, scattered by ``spread_mm``,
    flexed over ``arc_deg`` and back in 120 frames: markers ``(120, 4, 3)`` [mm] with normal
    noise of SD ``noise_mm`` (a number or one per axis) and the axis ``(3,)``."""
    centre = rng.uniform(-50.0, 50.0, 3)
    turn = rotation_matrix(unit(rng.normal(size=3)) * rng.uniform(0.0, np.pi))
    axis = turn[:, 2]
    body = (np.array([distance_mm, 0.0, 0.0]) + rng.normal(scale=spread_mm, size=(4, 3))) @ turn.T
    flexion = np.radians(arc_deg) * np.sin(np.pi * np.linspace(0.0, 1.0, 120))
    markers = np.einsum("kij,pj->kpi", rotation_matrix(flexion[:, None] * axis), body)
    noisy = markers + centre + rng.normal(size=markers.shape) * np.asarray(noise_mm)
    return noisy, axis


def _lever_hinge(rng: np.random.Generator, arc_deg: float, n_far: int) -> tuple:
    """Two markers 3 mm from a hinge's axis and ``n_far`` 100 mm from it, each at a random
    angle about it and up to 40 mm along it, flexed over ``arc_deg`` and back in 120 frames
    with normal noise of an SD drawn between 0.5 and 1 mm: markers ``(120, 2 + n_far, 3)``
    [mm] and the axis ``(3,)``."""
    centre = rng.uniform(-50.0, 50.0, 3)
    turn = rotation_matrix(unit(rng.normal(size=3)) * rng.uniform(0.0, np.pi))
    axis = turn[:, 2]
    radii = np.array([3.0, 3.0] + [100.0] * n_far)
    angles = rng.uniform(0.0, 2.0 * np.pi, len(radii))
    body = np.column_stack(
        [radii * np.cos(angles), radii * np.sin(angles), rng.uniform(-40.0, 40.0, len(radii))]
    )
    flexion = np.radians(arc_deg) * np.sin(np.pi * np.linspace(0.0, 1.0, 120))
    markers = np.einsum("kij,pj->kpi", rotation_matrix(flexion[:, None] * axis), body @ turn.T)
    noise_mm = rng.uniform(0.5, 1.0)
    return markers + centre + rng.normal(scale=noise_mm, size=markers.shape), axis


def _sliding_hip(seed: int, slide_mm: float) -> tuple:
    """``tests/test_pose_noise.py``'s hip on a 30 degree two-axis swing, 0.5 mm noise, its
    first thigh marker sliding ``slide_mm`` along a random direction over the 60 frames."""
    proximal, distal = _noisy(_hip(seed, ratio=1.0), 5000 + seed)
    direction = unit(np.random.default_rng(seed).normal(size=3))
    distal = distal.copy()
    distal[:, 0] += np.linspace(0.0, 1.0, len(distal))[:, None] * slide_mm * direction
    return proximal, distal


def _thin_hip(geometry: int, draw: int, off_line_mm: float) -> tuple:
    """``tests/test_pose_noise.py``'s hip on a 30 degree two-axis swing with three thigh
    markers ``off_line_mm`` off a 50 mm line, 0.5 mm noise of draw ``draw``."""
    rng = np.random.default_rng(geometry)
    proximal, distal = _hip(geometry, ratio=1.0)
    line = unit(rng.normal(size=3))
    body = np.outer([-25.0, 0.0, 25.0], line) + rng.normal(scale=off_line_mm, size=(3, 3))
    return _noisy((proximal, _thin_thigh(distal, body)), 100_000 * geometry + draw)


def _report(label: str, method: str, outcomes: Iterable[tuple[object, float]], sd_key: str):
    """One line: how many ``outcomes`` (a result and its error) read ``ok`` while far off."""
    outcomes = list(outcomes)
    far = [(result, error) for result, error in outcomes if result.status == "ok" and error > FAR]
    line = f"{label:42s} {method:20s} ok, more than {FAR:g} off: {len(far):2d} of {len(outcomes)}"
    if far:
        worst = max(error for _, error in far)
        sd = max(result.diagnostics.get(sd_key, float("nan")) for result, _ in far)
        line += f"; worst {worst:.1f}, largest stated SD {sd:.2f}"
    print(line)


def _cases(seeds: range, make: Callable, fit: Callable, error: Callable, methods, label, sd_key):
    trials = [make(np.random.default_rng(seed)) for seed in seeds]
    for method in methods:
        outcomes = []
        for data, truth in trials:
            try:
                result = fit(data, method)
            except ValueError:
                continue
            outcomes.append((result, error(result, truth)))
        _report(label, method, outcomes, sd_key)


def centres(seeds: range) -> None:
    def fit(markers, method):
        return jointbench.fit_center(markers, method=method)

    def error(result, centre):
        return float(np.linalg.norm(result.center - centre))

    _cases(
        seeds,
        lambda rng: swing(rng, 500.0, 10.0, 0.5),
        fit,
        error,
        ("LS", "NM", "BC", "IS"),
        "centre, markers 500 mm out, 10 deg",
        "center_sd_mm",
    )
    _cases(
        seeds,
        lambda rng: swing(rng, 60.0, 10.0, (0.1, 0.1, 2.0)),
        fit,
        error,
        ("LS", "NM", "BC", "IS"),
        "centre, noise (0.1, 0.1, 2) mm, 10 deg",
        "center_sd_mm",
    )


def axes(seeds: range) -> None:
    def fit(markers, method):
        return jointbench.fit_axis(markers, method=method)

    def error(result, axis):
        return float(angle_between_lines_deg(result.direction, axis))

    methods = ("planar", "radial", "combined", "SARA")
    cases = {
        "axis, noise (0.3, 0.3, 1) mm, 10 deg": lambda rng: _hinge(rng, 10.0, (0.3, 0.3, 1.0)),
        "axis, markers 5 mm from it, 1 mm noise": lambda rng: _hinge(
            rng, 30.0, 1.0, distance_mm=5.0, spread_mm=3.0
        ),
        "axis, 5 deg arc": lambda rng: _hinge(rng, 5.0, 0.5),
        "axis, 10 deg arc": lambda rng: _hinge(rng, 10.0, 0.5),
    }
    for n_far in (1, 2, 3):
        for arc_deg in (10.0, 20.0, 30.0):
            label = f"axis, 2 markers 3 mm, {n_far} 100 mm, {arc_deg:g} deg"
            cases[label] = functools.partial(_lever_hinge, arc_deg=arc_deg, n_far=n_far)
    for label, make in cases.items():
        _cases(seeds, make, fit, error, methods, label, "axis_sd_deg")


def joint_centres(seeds: range) -> None:
    thin = [_thin_hip(seed % 20, seed // 20, 3.0) for seed in range(5 * len(seeds))]
    for method in ("SCoRE", "analytic"):
        outcomes = []
        for proximal, distal in thin:
            result = jointbench.fit_joint_center(proximal, distal, method=method)
            outcomes.append((result, float(np.linalg.norm(result.center - CENTRE))))
        _report("hip, three thigh markers 3 mm off a line", method, outcomes, "center_sd_mm")
    for slide_mm in (5.0, 10.0):
        trials = [_sliding_hip(seed, slide_mm) for seed in seeds]
        for method in jointbench.methods("joint_center"):
            outcomes = []
            for proximal, distal in trials:
                result = jointbench.fit_joint_center(proximal, distal, method=method)
                outcomes.append((result, float(np.linalg.norm(result.center - CENTRE))))
            label = f"hip, a thigh marker sliding {slide_mm:g} mm"
            _report(label, method, outcomes, "center_sd_mm")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=60)
    parts = {"centres": centres, "axes": axes, "joint_centres": joint_centres}
    parser.add_argument("--only", choices=sorted(parts), help="one part of the cases")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    seeds = range(args.seeds)
    for name, part in parts.items():
        if args.only in (None, name):
            part(seeds)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
