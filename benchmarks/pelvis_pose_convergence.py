"""Measure where the skin-marker study's pelvis pose fit stops converging, and hold the config's
check of the pelvis cluster (``jointbench.configuration.bounds.pelvis_poses_problem``) to the
simulate job it stands in for.

Usage::

    python benchmarks/pelvis_pose_convergence.py [--trials 10000] [--protocols 300]
        [--only width,length,artefact,sweep]

The simulate job fits the pelvis poses of every trial (paper C §5) and refuses a trial whose
fit stops before converging (``jointbench.simulate.hip_sta.thigh_in_pelvis_frame``). Prints,
with the current code:

* ``width``: the default pelvis squeezed towards its common line until its width (the RMS
  distance of its markers from that line) is a few times the 1.7 mm white noise, in recordings
  of 4 and 600 frames: of ``--trials`` trials, how many fits stop short;
* ``length``: the same at little noise (0.001 to 0.1 mm), the cluster ever longer than wide;
* ``artefact``: pelvis artefact (``pelvis_sta_ratio``) at the default noise, widths 5 to 80 mm,
  the deformation's RMS departure as the check computes it (``pelvis_departure``);
* ``sweep``: ``--protocols`` random pelvis clusters (3 to 5 markers, 20 to 400 mm long, 1e-3
  to 1 times as wide, noise 0 to 5 mm, pelvis artefact 0 to 3 times the thigh's, 4 to 600
  frames), each run as the simulate job runs it over the default config's grid and trials:
  how many the job refuses that the check passes (to be 0), how many the check refuses that the
  job runs, and the same for the check without the pelvis bound.
"""

from __future__ import annotations

import argparse
import copy
import time
from pathlib import Path

import numpy as np

from jointbench.configuration import bounds
from jointbench.configuration import config as study_config
from jointbench.numerics.poses import fit_rigid_poses
from jointbench.running.run import simulate_condition
from jointbench.simulate import hip_sta

ROOT = Path(__file__).resolve().parents[1]
NOISE_MM = 1.7
BLOCK = 500


def _pelvis_fits(protocol, condition, trials: int):
    """``(stopped, largest iterations)`` of the pelvis pose fits of ``trials`` trials."""
    fits = []
    original = hip_sta.thigh_in_pelvis_frame

    def recorded(pelvis, thigh):
        fits.append(fit_rigid_poses(pelvis))
        return thigh

    hip_sta.thigh_in_pelvis_frame = recorded
    try:
        for start in range(0, trials, BLOCK):
            rngs = [np.random.default_rng(k) for k in range(start, min(start + BLOCK, trials))]
            hip_sta.simulate(condition, protocol, rngs)
    finally:
        hip_sta.thigh_in_pelvis_frame = original
    stopped = sum(int((~fit.converged).sum()) for fit in fits)
    return stopped, max(int(fit.iterations.max()) for fit in fits)


def _print_fits(label: str, protocol, condition, trials: int) -> None:
    """Print ``label``, then how many of ``trials`` pelvis pose fits stopped short."""
    stopped, most = _pelvis_fits(protocol, condition, trials)
    print(f"{label}: {stopped:5d} (iterations <= {most})")


def _squeezed(width_mm: float) -> list[tuple[float, ...]]:
    """The default pelvis squeezed (or stretched) across its common line to ``width_mm``."""
    markers = np.array(hip_sta.HipStaProtocol().pelvis_markers_mm)
    centroid = markers.mean(axis=0)
    _, _, axes = np.linalg.svd(markers - centroid)
    local = (markers - centroid) @ axes.T
    _, width = bounds.line_spreads(markers)
    local[:, 1:] *= width_mm / width
    return [tuple(point) for point in local @ axes + centroid]


def width(trials: int) -> None:
    condition = {"motion": "star_arc", "rom_deg": 45.0, "sta_mm": 0.0}
    print(f"width / noise, white noise {NOISE_MM} mm: fits stopped short of {trials} trials")
    for frames in (4, 600):
        for ratio in (1.25, 1.5, 1.75, 2.0, 3.0, 4.0):
            protocol = hip_sta.HipStaProtocol(
                pelvis_markers_mm=_squeezed(ratio * NOISE_MM), duration_s=frames / 50.0
            )
            _print_fits(
                f"  {frames:4d} frames  width/noise {ratio:5.2f}",
                protocol,
                condition,
                trials,
            )


def length(trials: int) -> None:
    condition = {"motion": "star_arc", "rom_deg": 45.0, "sta_mm": 0.0}
    print(f"length / width at little noise: fits stopped short of {trials} trials")
    along, _ = bounds.line_spreads(hip_sta.HipStaProtocol().pelvis_markers_mm)
    for noise in (0.001, 0.01, 0.1):
        for frames in (4, 600):
            for ratio in (30.0, 45.0, 60.0, 100.0, 300.0):
                protocol = hip_sta.HipStaProtocol(
                    pelvis_markers_mm=_squeezed(along / ratio),
                    noise_mm=noise,
                    duration_s=frames / 50.0,
                )
                _print_fits(
                    f"  noise {noise:5.3f} mm {frames:4d} frames  length/width {ratio:5.0f}",
                    protocol,
                    condition,
                    trials,
                )


def corner(trials: int) -> None:
    """The corner of what the check accepts: width exactly the bound times the noise, length
    the bound times the width (the default pelvis's shape scaled to them)."""
    condition = {"motion": "star_arc", "rom_deg": 45.0, "sta_mm": 0.0}
    print(f"the accepted region's corner: fits stopped short of {trials} trials")
    default = hip_sta.HipStaProtocol().pelvis_markers_mm
    along, _ = bounds.line_spreads(default)
    for noise in (0.1, 0.3, 1.0, 1.7):
        for frames in (4, 600):
            for ratio in (20.0, bounds.PELVIS_LENGTH_PER_WIDTH):
                wide = bounds.PELVIS_WIDTH_PER_DEPARTURE * noise * (1 + 1e-6)
                scale = ratio * wide / along
                markers = np.array(_squeezed(wide / scale))
                centroid = markers.mean(axis=0)
                protocol = hip_sta.HipStaProtocol(
                    pelvis_markers_mm=[tuple(p) for p in (markers - centroid) * scale + centroid],
                    noise_mm=noise,
                    duration_s=frames / 50.0,
                )
                _print_fits(
                    f"  noise {noise:4.2f} mm {frames:4d} frames  width/noise "
                    f"{bounds.PELVIS_WIDTH_PER_DEPARTURE:g}, length/width {ratio:3.0f}",
                    protocol,
                    condition,
                    trials,
                )


def artefact(trials: int) -> None:
    config = study_config.load_config(ROOT / "config" / "config.yaml")
    settings = config["studies"]["hip_sta"]
    print(f"pelvis artefact, noise {NOISE_MM} mm, 600 frames: fits stopped short of {trials}")
    for motion in hip_sta.MOTIONS:
        condition = {"motion": motion, "rom_deg": 45.0, "sta_mm": 30.0}
        for width_mm in (5.0, 20.0, 80.0):
            for ratio in (0.25, 0.5, 1.0, 2.0, 4.0, 8.0):
                protocol = hip_sta.HipStaProtocol(
                    pelvis_markers_mm=_squeezed(width_mm), pelvis_sta_ratio=ratio
                )
                departure, _, _ = bounds.pelvis_departure(
                    {**settings, "grid": {k: [v] for k, v in condition.items()}}, protocol
                )
                _print_fits(
                    f"  {motion:13s} width {width_mm:4.0f} mm  pelvis_sta_ratio {ratio:4.2f}  "
                    f"width/departure {width_mm / departure:6.2f}",
                    protocol,
                    condition,
                    trials,
                )


def _random_protocol(rng: np.random.Generator) -> dict:
    """One random pelvis protocol, as the config writes it."""
    n = int(rng.integers(3, 6))
    length_mm = float(np.exp(rng.uniform(np.log(20.0), np.log(400.0))))
    thinness = float(np.exp(rng.uniform(np.log(1e-3), np.log(1.0))))
    along = rng.uniform(-0.5, 0.5, n) * length_mm
    across = rng.standard_normal((n, 2)) * thinness * length_mm / 2
    if rng.random() < 0.5:
        across[:, 1] = 0.0  # a flat cluster, as the default pelvis is
    turn, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    markers = np.column_stack([along, across]) @ turn.T + [-27.0, 86.0, 78.0]
    noise = 0.0 if rng.random() < 0.2 else float(np.exp(rng.uniform(np.log(0.01), np.log(5.0))))
    frames = int(np.exp(rng.uniform(np.log(4), np.log(600))))
    protocol = {
        "pelvis_markers_mm": markers.round(3).tolist(),
        "noise_mm": round(noise, 4),
        "duration_s": frames / 50.0,
        "pelvis_sta_ratio": 0.0 if rng.random() < 0.4 else round(float(rng.uniform(0, 3)), 3),
    }
    if rng.random() < 0.5:
        protocol["sta_rigid_share"] = round(float(rng.uniform(0.5, 1.0)), 3)
    return protocol


def _job_refuses(config: dict) -> bool:
    """Whether the simulate job refuses some trial of some condition of ``config``'s hip_sta."""
    for condition in study_config.conditions(config, "hip_sta"):
        try:
            simulate_condition(config, "hip_sta", condition)
        except ValueError as error:
            if "does not determine its poses" not in str(error):
                raise
            return True
    return False


def _check_refuses(config: dict, *, pelvis_bound: bool = True) -> str | None:
    original = bounds.pelvis_poses_problem
    if not pelvis_bound:
        bounds.pelvis_poses_problem = lambda settings, protocol: None
    try:
        study_config.check_config(config)
    except ValueError as error:
        return str(error)
    finally:
        bounds.pelvis_poses_problem = original
    return None


def _margins(config: dict) -> tuple[float, float]:
    """``(width / departure, length / width)`` of ``config``'s hip_sta pelvis cluster, the two
    ratios the pelvis bound holds to :data:`~bounds.PELVIS_WIDTH_PER_DEPARTURE` and
    :data:`~bounds.PELVIS_LENGTH_PER_WIDTH`."""
    settings = config["studies"]["hip_sta"]
    protocol = study_config.get_study("hip_sta").protocol(settings["protocol"])
    along, width = bounds.line_spreads(protocol.pelvis_markers_mm)
    departure, _, _ = bounds.pelvis_departure(settings, protocol)
    return (width / departure if departure else np.inf), along / width


def sweep(protocols: int) -> None:
    base = study_config.load_config(ROOT / "config" / "config.yaml")
    for study in base["studies"]:
        base["studies"][study]["enabled"] = study == "hip_sta"
    rng = np.random.default_rng(20261206)
    counts = {"new": np.zeros((2, 2), int), "old": np.zeros((2, 2), int)}
    refused_margins, over_refused = [], []
    drawn = 0
    start = time.perf_counter()
    while drawn < protocols:
        config = copy.deepcopy(base)
        config["studies"]["hip_sta"]["protocol"] = _random_protocol(rng)
        try:
            study_config._protocol(
                study_config.get_study("hip_sta"), config["studies"]["hip_sta"]["protocol"], ""
            )
        except ValueError:
            continue  # a protocol another declaration refuses (noise beyond the markers)
        drawn += 1
        refused = _job_refuses(config)
        for name, bound in (("new", True), ("old", False)):
            checked = _check_refuses(config, pelvis_bound=bound)
            counts[name][int(refused), int(checked is not None)] += 1
            if name == "new" and refused and checked is None:
                print("  MISSED:", config["studies"]["hip_sta"]["protocol"])
            if name == "new" and not refused and checked is not None:
                over_refused.append(_margins(config))
        if refused:
            refused_margins.append(_margins(config))
    seconds = time.perf_counter() - start
    print(
        f"{protocols} random pelvis protocols over the default grid "
        f"({config['studies']['hip_sta']['trials']} trials), {seconds:.0f} s:"
    )
    for name, words in (("new", "the check"), ("old", "the check without the pelvis bound")):
        table = counts[name]
        print(
            f"  {words}: job refuses and check passes {table[1, 0]}; check refuses and job "
            f"runs {table[0, 1]}; both refuse {table[1, 1]}; both run {table[0, 0]}"
        )
    widths, lengths = np.array(refused_margins).T
    short = lengths <= bounds.PELVIS_LENGTH_PER_WIDTH
    wide = widths > bounds.PELVIS_WIDTH_PER_DEPARTURE
    print(
        f"  of those the job refuses: the largest width/departure of those no longer than "
        f"{bounds.PELVIS_LENGTH_PER_WIDTH:g} times their width {widths[short].max():.3g} (bound "
        f"{bounds.PELVIS_WIDTH_PER_DEPARTURE:g}); the smallest length/width of those wider than "
        f"{bounds.PELVIS_WIDTH_PER_DEPARTURE:g} times their departure "
        f"{lengths[wide].min() if wide.any() else np.nan:.3g} (bound "
        f"{bounds.PELVIS_LENGTH_PER_WIDTH:g})"
    )
    largest_refused = widths[short].max()
    if over_refused:
        widths, lengths = np.array(over_refused).T
        narrow = widths <= bounds.PELVIS_WIDTH_PER_DEPARTURE
        long = ~narrow & (lengths > bounds.PELVIS_LENGTH_PER_WIDTH)
        print(
            f"  of those the check refuses and the job runs: {int(narrow.sum())} by width/"
            f"departure (median {np.median(widths[narrow]) if narrow.any() else np.nan:.3g}), "
            f"{int(long.sum())} by length/width (median "
            f"{np.median(lengths[long]) if long.any() else np.nan:.3g}), "
            f"{int((~narrow & ~long).sum())} by another check; "
            f"{int((narrow & (widths > largest_refused)).sum())} of them wider than "
            f"{largest_refused:.3g} times their departure, the widest the job refused"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=10_000)
    parser.add_argument("--protocols", type=int, default=300)
    parser.add_argument("--only", default="width,length,corner,artefact,sweep")
    args = parser.parse_args()
    parts = args.only.split(",")
    sections = (("width", width), ("length", length), ("corner", corner), ("artefact", artefact))
    for name, run in sections:
        if name in parts:
            run(args.trials)
    if "sweep" in parts:
        sweep(args.protocols)


if __name__ == "__main__":
    main()
