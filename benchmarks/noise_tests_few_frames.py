"""The level and power of the two tests of the noise the fixed-centre model pools, on few frames.

Usage::

    python benchmarks/noise_tests_few_frames.py [--frames 4,5,6,8,10,20,50,200]
        [--trials 2000] [--laws gaussian,paper-a,t5] [--rigs rig,hip] [--power 200]

A checked joint-centre call tests the two segments' rigid-body residuals before the model
(``jointbench.estimators.hjc``): frame 0's residual against the other frames' (``frame0_p``),
and the two segments' residual variances against each other (``not_tested``), each allowing for
the noise's kurtosis read from those residuals. Here both are made, as the checked call makes
them, on trials where they hold: marker noise of RMS length 0.5 mm in every frame of both
segments, drawn from

* ``gaussian``: Gaussian per coordinate (excess kurtosis 0);
* ``paper-a``: paper A's law, uniformly distributed directions with normally distributed
  magnitudes (``jointbench.simulate.noise.isotropic_noise``; excess kurtosis 2.4 per
  coordinate);
* ``t5``: a Student t on 5 dof per coordinate (excess kurtosis 6, the model test's
  ``MAX_NOISE_KURTOSIS``),

on the first ``--frames`` frames of

* ``rig``: the tests' ball-joint rig (``tests/rigs.py``, three markers a segment, 200 frames
  spread over the same motion whatever their number);
* ``hip``: the hip study's recording (``jointbench.simulate.hip``, three markers a segment,
  60 Hz): its first frames, as the study's ``Nt`` conditions take them.

Printed per rig, law and frame count: how many of ``--trials`` trials each test rejects at 5 %
and at ``ROTATION_ALPHA`` (1e-3), and those counts over what the level expects, and the
kurtosis the tests allow for (its median). ``--power N`` then prints, on ``N`` draws each, the
studies' circumduction (``benchmarks/joint_centre_degenerate.py``: 20 degrees, 200 frames, four
markers a segment, 0.5 mm of paper A's noise) with the proximal segment's frame-0 markers each
2 mm off in a direction of their own, then both segments' (the frame-0 warnings at
``ROTATION_ALPHA``), and 2N trials of the rig (200 frames, paper A's law, equal noise: the
tests' false warnings at ``ROTATION_ALPHA`` and at 1 %), after the frame-0 test's warnings
at ``ROTATION_ALPHA`` and 5 % on ``--trials`` trials of the rig on each frame count with the
proximal segment's frame-0 markers 2 mm off (paper A's law, 0.5 mm). Seeds are fixed: the
same command gives the same counts. The wall time of each block is printed (``time.perf_counter``).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from jointbench.estimators import hjc
from jointbench.estimators.segment_poses import trial_poses
from jointbench.estimators.support import ROTATION_ALPHA
from jointbench.simulate.hip import HipProtocol, nominal_recording
from jointbench.simulate.noise import isotropic_noise

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from joint_centre_degenerate import circumduction
from joint_centre_degenerate import two_segments as study_segments
from rigs import two_segments

SD_MM = 0.5
LEVELS = (0.05, ROTATION_ALPHA)


def gaussian(rng: np.random.Generator, shape: tuple, sd_mm: float) -> np.ndarray:
    """Gaussian errors ``(*shape, 3)`` [mm] of RMS length ``sd_mm``."""
    return rng.normal(0.0, sd_mm / math.sqrt(3.0), size=(*shape, 3))


def student_t5(rng: np.random.Generator, shape: tuple, sd_mm: float) -> np.ndarray:
    """Errors ``(*shape, 3)`` [mm] of RMS length ``sd_mm``, each coordinate a t on 5 dof
    (variance 5 / 3 unscaled; excess kurtosis 6)."""
    return rng.standard_t(5, size=(*shape, 3)) * sd_mm / math.sqrt(3.0 * 5.0 / 3.0)


LAWS = {"gaussian": gaussian, "paper-a": isotropic_noise, "t5": student_t5}


def clean(rig: str, frames: int) -> tuple[np.ndarray, np.ndarray]:
    """Noise-free markers ``(frames, 3, 3)`` [mm] of the proximal and distal segments."""
    if rig == "rig":
        return two_segments(frames)
    proximal, distal = nominal_recording(HipProtocol())
    return proximal[:frames], distal[:frames]


def noisy(markers: np.ndarray, law: str, trials: int, rng: np.random.Generator) -> np.ndarray:
    """``trials`` copies ``(trials, N, n, 3)`` [mm] of ``markers`` with noise of ``law``."""
    return markers + np.asarray(LAWS[law](rng, (trials, *markers.shape[:2]), SD_MM))


def noise_test_p_values(proximal: np.ndarray, distal: np.ndarray) -> np.ndarray:
    """Per trial, ``(frame0_p, unequal_p, kurtosis)`` ``(T, 3)`` of the two noise tests
    a checked call makes on the trials' markers ``(T, N, n, 3)`` [mm] (NaN where none)."""
    rows = []
    for poses in trial_poses({"proximal": proximal, "distal": distal}, min_frames=3):
        segments = (poses["proximal"], poses["distal"])
        noise = hjc._segments_noise(*segments, hjc._rounding_variance(segments))
        if noise is None:
            rows.append((math.nan, math.nan, math.nan))
            continue
        frame0_p = hjc._frame0_noise_p(noise)[0]
        rows.append((frame0_p, hjc._unequal_noise_p(noise)[0], noise[1]))
    return np.array(rows)


def level_rows(rigs: list, laws: list, frame_counts: list, trials: int) -> None:
    """The level table: per rig, law and frame count, each test's rejections."""
    print(
        f"{'rig':>4} {'law':>8} {'N':>4} | frame 0 at 5 %  at 1e-3 | segments at 5 %  at 1e-3 "
        f"| kurtosis allowed (median) | s"
    )
    for rig in rigs:
        for law in laws:
            for frames in frame_counts:
                start = time.perf_counter()
                rng = np.random.default_rng([frames, len(law), sum(map(ord, law + rig))])
                proximal, distal = clean(rig, frames)
                p = noise_test_p_values(
                    noisy(proximal, law, trials, rng), noisy(distal, law, trials, rng)
                )
                cells = []
                for column in (0, 1):
                    for level in LEVELS:
                        count = int(np.sum(p[:, column] < level))
                        cells.append(f"{count:5d} ({count / (level * trials):4.2f}x)")
                print(
                    f"{rig:>4} {law:>8} {frames:4d} | {cells[0]} {cells[1]} | {cells[2]} "
                    f"{cells[3]} | {np.nanmedian(p[:, 2]):5.2f} | "
                    f"{time.perf_counter() - start:.1f}"
                )


def few_frame_power(frame_counts: list, trials: int) -> None:
    """The frame-0 test's power on few frames: the rig with paper A's law, the proximal
    segment's frame-0 markers each 2 mm off in a direction of their own."""
    for frames in frame_counts:
        start = time.perf_counter()
        rng = np.random.default_rng([frames, 43])
        proximal, distal = (noisy(m, "paper-a", trials, rng) for m in clean("rig", frames))
        proximal[:, 0] += 2.0 * _directions(rng, 3 * trials).reshape(trials, 3, 3)
        p = noise_test_p_values(proximal, distal)[:, 0]
        print(
            f"frame 0 2 mm off, one segment's ({trials} trials, {frames} frames, three markers): "
            f"warned {int(np.sum(p < ROTATION_ALPHA))} at 1e-3, {int(np.sum(p < 0.05))} at 5 % "
            f"({time.perf_counter() - start:.1f} s)"
        )


def frame0_off(draws: int, both: bool, seed: int = 31) -> tuple[np.ndarray, np.ndarray]:
    """The studies' circumduction with frame-0 markers 2 mm off (one segment's or both's),
    ``draws`` trials ``(draws, 200, 4, 3)`` [mm] each (``tests/test_gauss_markov_fit.py``'s
    ``_frame0_off`` with more draws)."""
    proximal, distal = [], []
    for k in range(draws):
        rng = np.random.default_rng(seed + k)
        p, d, _ = study_segments(rng, circumduction(20.0, 200), noise_mm=SD_MM)
        p, d = p.copy(), d.copy()
        p[0] += 2.0 * _directions(rng, p.shape[1])
        if both:
            d[0] += 2.0 * _directions(rng, d.shape[1])
        proximal.append(p)
        distal.append(d)
    return np.array(proximal), np.array(distal)


def _directions(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` unit vectors ``(n, 3)`` in uniformly distributed directions."""
    v = rng.normal(size=(n, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def power_rows(draws: int) -> None:
    """The frame-0 test's power at 200 frames, and both tests' false warnings there."""
    for both in (False, True):
        start = time.perf_counter()
        p = noise_test_p_values(*frame0_off(draws, both))
        warned = int(np.sum(p[:, 0] < ROTATION_ALPHA))
        which = "both segments'" if both else "one segment's"
        print(
            f"frame 0 2 mm off, {which} ({draws} draws, 200 frames): warned {warned}, "
            f"kurtosis allowed {np.median(p[:, 2]):.2f} ({time.perf_counter() - start:.1f} s)"
        )
    start = time.perf_counter()
    rng = np.random.default_rng(29)
    proximal, distal = clean("rig", 200)
    trials = 2 * draws
    p = noise_test_p_values(
        noisy(proximal, "paper-a", trials, rng), noisy(distal, "paper-a", trials, rng)
    )
    counts = [int(np.sum(p[:, c] < a)) for a in (ROTATION_ALPHA, 0.01) for c in (0, 1)]
    print(
        f"equal noise, paper A's law ({trials} trials, 200 frames): frame 0 / segments warned "
        f"{counts[0]} / {counts[1]} at 1e-3, {counts[2]} / {counts[3]} at 1 % "
        f"({time.perf_counter() - start:.1f} s)"
    )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", default="4,5,6,8,10,20,50,200")
    parser.add_argument("--trials", type=int, default=2000)
    parser.add_argument("--laws", default="gaussian,paper-a,t5")
    parser.add_argument("--rigs", default="rig,hip")
    parser.add_argument("--power", type=int, default=0)
    arguments = parser.parse_args(argv)
    frames = [int(x) for x in arguments.frames.split(",") if x]
    laws = [x for x in arguments.laws.split(",") if x]
    rigs = [x for x in arguments.rigs.split(",") if x]
    if frames:
        level_rows(rigs, laws, frames, arguments.trials)
    if arguments.power:
        few_frame_power(frames, arguments.trials)
        power_rows(arguments.power)


if __name__ == "__main__":
    main()
