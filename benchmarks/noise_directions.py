"""How often the test of whether the markers' noise is the same in every direction
(:mod:`jointbench.estimators.noise_directions`) rejects isotropic noise, and how many checked
calls' statuses it changes, on the papers' simulated trials and the real knee trial.

Usage::

    python benchmarks/noise_directions.py [--trials 8]

Prints, per study, over ``--trials`` seeded trials of every condition:

* paper A's CMC grid (marker sets M and H, 5, 15 and 45 degrees, 0.5, 1 and 2 mm) and paper
  B's knee and MCP grid (FE 30, 60 and 90 degrees, AA ratio 0.1 to 0.7): the trials the test
  rejects at its level, and per method the checked calls (``fit_center``, ``fit_axis``, their
  artefact screen off: the trials are simulated) whose
  status carries its warning, and of those the ones that read ``ok`` without it;
* paper C's hip rig (three markers per segment, in the world; its joint-centre calls are not
  judged by the test): the clusters it rejects;
* the real knee trial (``/work/shared/data/functional-trials/right_knee.c3d``, skin markers):
  the thigh and shank clusters in the world, and the shank in the thigh's frame as the axis
  calls read it: the test's statistic, whether it rejects (with the noise's SDs along its
  principal directions and its pull where it does) and what each axis method's status says.
"""

from __future__ import annotations

import argparse
import itertools
import warnings
from pathlib import Path

import numpy as np

import jointbench
from jointbench.estimators import noise_directions as by_direction
from jointbench.estimators.support import assess
from jointbench.io import prepare, read
from jointbench.simulate import cmc, hinge, hip

KNEE = Path("/work/shared/data/functional-trials/right_knee.c3d")
THIGH, SHANK = "RTHI1,RTHI2,RTHI3,RGT", "RLEG1,RLEG2,RLEG3,RATT,RLM,RSPH"
NOT_DETERMINED = "precision not determined: the noise differs by direction"


def _found(markers: np.ndarray) -> by_direction.NoiseDirections:
    """The test as the one-segment support verdict makes it on ``markers`` ``(N, n, 3)``."""
    return assess("center", (markers,)).noise_directions


def _statuses(label: str, trials: list[np.ndarray], fit, methods) -> None:
    """One line per method: the calls on ``trials`` whose status carries the warning, and of
    those the ones that read ``ok`` without it; first, the trials the test rejects."""
    rejected = sum(_found(markers).rejected() for markers in trials)
    print(f"{label}: {len(trials)} trials, test rejects {rejected}")
    for method in methods:
        warned = only = 0
        for markers in trials:
            status = fit(markers, method).status
            if NOT_DETERMINED in status:
                warned += 1
                only += status.count("warning:") == 1
        print(f"  {method:10s} warned {warned}, of which ok without it {only}")


def papers(n_trials: int) -> None:
    seeds = [np.random.default_rng(seed) for seed in range(n_trials)]
    grid = itertools.product(("M", "H"), (5, 15, 45), (0.5, 1.0, 2.0))
    trials = []
    for marker_set, rom, noise in grid:
        condition = {"marker_set": marker_set, "rom_deg": rom, "noise_mm": noise}
        trials += list(cmc.simulate(condition, cmc.CmcProtocol(), seeds).segments["moving"])
    _statuses(
        "paper A, CMC grid",
        trials,
        lambda m, method: jointbench.fit_center(m, method=method, artefacts="ignore"),
        ("LS", "NM", "BC", "IS"),
    )
    trials = []
    for joint, rom, ratio in itertools.product(("knee", "mcp"), (30, 60, 90), (0.1, 0.3, 0.5, 0.7)):
        condition = {"fe_rom_deg": rom, "aa_ratio": ratio}
        simulated = hinge.simulate(condition, hinge.HINGE_PROTOCOLS[joint], seeds)
        trials += list(simulated.segments["moving"])
    _statuses(
        "paper B, knee and MCP grid",
        trials,
        lambda m, method: jointbench.fit_axis(m, method=method, artefacts="ignore"),
        ("planar", "radial", "combined", "SARA"),
    )
    segments = hip.simulate({}, hip.HipProtocol(), [np.random.default_rng(s) for s in range(30)])
    clusters = [*segments.segments["proximal"], *segments.segments["distal"]]
    rejected = sum(_found(markers).rejected() for markers in clusters)
    print(f"paper C, hip rig: {len(clusters)} clusters of 30 trials, test rejects {rejected}")


def knee() -> None:
    recording = read(KNEE)
    for name, labels in (("thigh", THIGH), ("shank", SHANK)):
        columns = [list(recording.labels).index(label) for label in labels.split(",")]
        found = _found(recording.markers[:, columns])
        print(f"knee, {name} in the world: {_said(found.numbers())}")
    prepared = prepare(recording, "axis", SHANK, THIGH)
    markers = prepared.arrays[0][prepared.usable]
    for method in ("planar", "radial", "combined", "SARA"):
        result = jointbench.fit_axis(markers, method=method)
        numbers = result.diagnostics
        print(
            f"knee, shank in the thigh's frame, {method}: {_said(numbers)}, pull "
            f"{numbers.get('noise_direction_pull_deg', float('nan')):.3g} deg against SD "
            f"{numbers.get('axis_sd_deg', float('nan')):.3g} deg; warned: "
            f"{NOT_DETERMINED in result.status}"
        )


def _said(numbers: dict) -> str:
    """The test's statistic and, where it rejects, its p-value and the noise's SDs."""
    words = f"W = {numbers['noise_direction_statistic']:.3g}"
    if "noise_direction_p_value" not in numbers:
        return f"{words}, not rejected"
    sds = ", ".join(f"{sd:.3g}" for sd in numbers["noise_direction_sds_mm"])
    return f"{words}, p = {numbers['noise_direction_p_value']:.3g}, SDs {sds} mm"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=8)
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    papers(args.trials)
    knee()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
