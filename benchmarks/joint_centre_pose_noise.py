"""Measure the joint-centre checks of the poses' noise and of the centre's SD, as the README
quotes them.

Usage::

    python benchmarks/joint_centre_pose_noise.py [--geometries 20] [--draws 100]

Prints, with the current code (``jointbench.fit_joint_center``, every joint-centre method):

* hips (``tests/test_pose_noise.py``'s generator, 60 frames, 0.5 mm noise) swung in five
  ways, one noise draw for each of ``--geometries`` marker geometries: per method, how many
  answers the pull warns about and how many the SD says are undetermined, how many read
  ``ok`` without those two warnings (as before the checks) and with them, and how many of
  each lie more than 10 mm off;
* thigh clusters of three markers 1, 3 and 5 mm off a 50 mm line on a 30 degree two-axis swing:
  the same counts for SCoRE and the analytic centre;
* a noisy pelvis with a nearly noise-free thigh, the other way round, and noise larger along
  one direction of the world than across it: the same counts for SCoRE and the analytic centre;
* the support verdict on pure hinges whose segments carry unequal noise: how often it resolves
  a second axis of rotation (at its level, a thousandth);
* the pull against the mean error of SCoRE over ``--draws`` noise draws, three geometries of
  three near-hinges;
* paper C's hip rig (``jointbench.simulate.hip``, at 150 and 1200 frames) and the skin-marker
  hip study (``jointbench.simulate.hip_sta``) at each of their motions, ranges and artefacts:
  the same counts over 10 trials each (the studies' own calls run without checks);
* the real knee trial (``data/functional-trials/right_knee.c3d``): each method's status,
  share, pull and SD.
"""

from __future__ import annotations

import argparse
import collections
import itertools
import math
import sys
import warnings
from pathlib import Path

import numpy as np

import jointbench
from jointbench.simulate import hip, hip_sta

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_pose_noise import (
    _PULLED,
    CENTRE,
    _hip,
    _noisy,
    _thin_thigh,
    errors_and_pulls,
    second_axes_resolved,
)

# The SD's warning (jointbench.estimators.centre_precision.annotate_joint_centres).
_UNDETERMINED = "centre not determined by the data"

KNEE = Path(__file__).resolve().parents[1] / "data" / "functional-trials" / "right_knee.c3d"
MOTIONS = {
    "nearly a hinge (6 %)": {"ratio": 0.06},
    "3 deg two-axis swing": {"ratio": 1.0, "rom_deg": 3.0},
    "second rotation 15 %": {"ratio": 0.15},
    "second rotation 30 %": {"ratio": 0.3},
    "30 deg two-axis swing": {"ratio": 1.0},
}


def _only_checked(status: str) -> bool:
    """Whether ``status`` would read ``ok`` but for the warnings of the pull and the SD."""
    parts = [
        part for part in status.split("; ") if _PULLED not in part and _UNDETERMINED not in part
    ]
    return len(parts) < len(status.split("; ")) and not parts


def _count(label: str, trials: list[tuple], methods: tuple[str, ...], centre=CENTRE) -> None:
    """Per method, how many of ``trials`` read ``ok`` now and would without the warnings of
    the pull and the SD, how many of each lie more than 10 mm from ``centre``, and the
    largest SD stated."""
    counts: dict[str, collections.Counter] = collections.defaultdict(collections.Counter)
    largest_sd: dict[str, float] = collections.defaultdict(float)
    for segments in trials:
        for method in methods:
            result = jointbench.fit_joint_center(*segments, method=method)
            off = bool(np.linalg.norm(result.center - centre) > 10.0)
            before = result.status == "ok" or _only_checked(result.status)
            tally = counts[method]
            tally["pulled"] += _PULLED in result.status
            tally["undetermined"] += _UNDETERMINED in result.status
            sd = result.diagnostics.get("center_sd_mm", math.nan)
            largest_sd[method] = max(largest_sd[method], sd)
            tally["ok before"] += before
            tally["ok before, >10 mm off"] += before and off
            tally["ok"] += result.status == "ok"
            tally["ok, >10 mm off"] += result.status == "ok" and off
    for method, tally in counts.items():
        words = ", ".join(f"{key} {value}" for key, value in tally.items())
        words += f", largest SD {largest_sd[method]:.3g} mm"
        print(f"{label:44s} {method:20s} of {len(trials)}: {words}")


def hips(n_geometries: int) -> None:
    """The counts on hips swung in each of :data:`MOTIONS`, 0.5 mm noise."""
    for label, motion in MOTIONS.items():
        trials = [
            _noisy(_hip(geometry, **motion), 1000 + geometry) for geometry in range(n_geometries)
        ]
        _count(label, trials, jointbench.methods("joint_center"))


def unequal_and_anisotropic(n_geometries: int) -> None:
    """A noisy wide pelvis with a nearly noise-free compact thigh on a 30 degree two-axis swing
    (answers the poses' noise pooled over both segments would pull), a noise-free pelvis with a
    noisy compact thigh and a second rotation of 30 %, and noise larger along z than across."""
    cases = {
        "pelvis 3 mm, thigh 0.1 mm": ({"ratio": 1.0, "spreads_mm": (60.0, 8.0)}, (3.0, 0.1)),
        "pelvis 0 mm, thigh 1 mm": ({"ratio": 0.3, "spreads_mm": (60.0, 10.0)}, (0.0, 1.0)),
        "noise (0.25, 0.25, 2) mm": ({"ratio": 1.0}, ((0.25, 0.25, 2.0),) * 2),
    }
    for label, (motion, noise_mm) in cases.items():
        trials = [
            _noisy(_hip(geometry, **motion), 3000 + geometry, noise_mm)
            for geometry in range(n_geometries)
        ]
        _count(label, trials, ("SCoRE", "analytic"))


def hinge_calibration() -> None:
    """How often the support verdict resolves a second axis on a pure hinge whose two segments
    carry unequal noise (and equal, for comparison; and noise beyond the first order of the
    poses' noise, 3 mm on markers 8 mm about their centre): 10 geometries x 20 noise draws
    each."""
    cases = {
        "0.2 and 1 mm": ((40.0, 20.0), (0.2, 1.0)),
        "1 mm compact, 0.1 mm wide": ((15.0, 60.0), (1.0, 0.1)),
        "0.1 mm wide, 1 mm compact": ((60.0, 15.0), (0.1, 1.0)),
        "0.5 and 0.5 mm": ((40.0, 20.0), (0.5, 0.5)),
        "3 mm compact (8 mm), 0.1 mm wide": ((8.0, 60.0), (3.0, 0.1)),
    }
    for label, (spreads_mm, noise_mm) in cases.items():
        resolved = second_axes_resolved(spreads_mm, noise_mm, 20)
        print(f"pure hinge, noise {label:34s} second axis resolved in {resolved} of 200")


def thin(n_geometries: int) -> None:
    """The counts with three thigh markers 1, 3 and 5 mm off a 50 mm line."""
    for off_line_mm in (1.0, 3.0, 5.0):
        trials = []
        for geometry in range(n_geometries):
            rng = np.random.default_rng(geometry)
            proximal, distal = _hip(geometry, ratio=1.0)
            line = rng.normal(size=3)
            line /= np.linalg.norm(line)
            body = np.outer([-25.0, 0.0, 25.0], line) + rng.normal(scale=off_line_mm, size=(3, 3))
            trials.append(_noisy((proximal, _thin_thigh(distal, body)), 2000 + geometry))
        _count(f"thin thigh, {off_line_mm:g} mm off line", trials, ("SCoRE", "analytic"))


def pull_against_error(n_draws: int) -> None:
    """SCoRE's mean error and the mean pull at its answers over ``n_draws`` noise draws."""
    for ratio, geometry in itertools.product((0.06, 0.15, 0.3), range(3)):
        errors, pulls = errors_and_pulls(_hip(geometry, ratio=ratio), n_draws)
        bounded = np.isfinite(pulls).all(axis=1)
        error, pull = errors.mean(axis=0), pulls[bounded].mean(axis=0)
        print(
            f"ratio {ratio:4.2f} geometry {geometry}: SCoRE's mean error {np.round(error, 1)} "
            f"(|.| {np.linalg.norm(error):.1f} mm), mean pull {np.round(pull, 1)} "
            f"(|.| {np.linalg.norm(pull):.1f} mm; unbounded in {n_draws - bounded.sum()} of "
            f"{n_draws} draws)"
        )


def _pulled_in(label: str, trials) -> None:
    """:func:`_count` on a study's simulated ``trials``."""
    pairs = zip(trials.segments["proximal"], trials.segments["distal"], strict=True)
    centre = np.array(trials.truth["center"])
    _count(label, list(pairs), jointbench.methods("joint_center"), centre)


def _rngs() -> list[np.random.Generator]:
    """The generators of 10 trials of a study's condition."""
    return [np.random.default_rng(seed) for seed in range(10)]


def studies() -> None:
    """The counts on paper C's rig and the skin-marker hip study's conditions."""
    for n_frames in (150, 1200):
        trials = hip.simulate({"n_frames": n_frames}, hip.HipProtocol(), _rngs())
        _pulled_in(f"paper C's rig, {n_frames} frames", trials)
    for motion, rom_deg, sta_mm in itertools.product(
        ("star_arc", "circumduction"), (20.0, 45.0), (0.0, 30.0)
    ):
        condition = {"motion": motion, "rom_deg": rom_deg, "sta_mm": sta_mm}
        trials = hip_sta.simulate(condition, hip_sta.HipStaProtocol(), _rngs())
        _pulled_in(f"skin markers, {motion} {rom_deg:g} deg, artefact {sta_mm:g} mm", trials)


def knee() -> None:
    """Each joint-centre method's share, pull, SD and status on the real knee trial."""
    recording = jointbench.read(KNEE)
    prepared = jointbench.prepare(
        recording, "joint_center", "RLEG1,RLEG2,RLEG3,RATT", "RTHI1,RTHI2,RTHI3,RGT"
    )
    for method in jointbench.methods("joint_center"):
        result = prepared.fit(method).result
        print(
            f"knee {method:20s} share {result.diagnostics.get('center_pose_noise_share'):.3f} "
            f"pull {result.diagnostics.get('center_pose_noise_pull_mm'):.1f} mm, "
            f"SD {result.diagnostics.get('center_sd_mm'):.3g} mm, "
            f"undetermined {_UNDETERMINED in result.status}, status {result.status[:90]!r}"
        )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--geometries", type=int, default=20)
    parser.add_argument("--draws", type=int, default=100)
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    hips(args.geometries)
    thin(args.geometries)
    unequal_and_anisotropic(args.geometries)
    hinge_calibration()
    pull_against_error(args.draws)
    studies()
    knee()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
