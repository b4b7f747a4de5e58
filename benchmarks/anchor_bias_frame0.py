"""The analytic joint centre's anchor bias against the mean error of frame-0 pose errors alone.

Usage::

    python benchmarks/anchor_bias_frame0.py [--rom 3,5,10,30,90] [--noise 0.5,0.02]
        [--pairs 400] [--offset 0]

``pose_noise.anchor_bias_mm`` is the analytic centre's mean error, to second order, from the
errors of the frame-0 poses that anchor both body frames. Here that is the only noise: one
noise-free circumduction of ``joint_centre_degenerate.py``'s two segments (200 frames) per
swing, ``--offset`` [mm] added to every coordinate, gets isotropic noise of ``--noise`` [mm] on
frame 0's markers alone. The draws come in antithetic pairs (the noise and its negative), whose
mean cancels the first-order error and leaves the even orders the bias is the first of. Printed
per swing and noise: the mean error [mm] over the pairs with its standard error, and the
formula read at the true centre on the noise-free poses with the variance of the noise drawn
(not the one the residual would estimate, which frame 0 alone shares among all frames).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from types import SimpleNamespace

import numpy as np

import jointbench
from jointbench.estimators.pose_noise import anchor_bias_mm
from jointbench.estimators.segment_poses import trial_poses

sys.path.insert(0, str(Path(__file__).resolve().parent))
from joint_centre_degenerate import circumduction, two_segments


def formula(proximal: np.ndarray, distal: np.ndarray, centre: np.ndarray, noise_mm: float):
    """``anchor_bias_mm`` ``(3,)`` [mm] at ``centre`` ``(3,)`` [mm] on the noise-free poses of
    markers ``proximal``, ``distal`` ``(N, n, 3)`` [mm] with the marker variance of ``noise_mm``:
    the function reads only their rotations, body-fixed markers and variance."""
    poses = trial_poses({"proximal": [proximal], "distal": [distal]}, min_frames=3)[0]
    read = [
        SimpleNamespace(rotation=pose.rotation, body=pose.body, variance=noise_mm**2)
        for pose in (poses["proximal"], poses["distal"])
    ]
    return anchor_bias_mm(*read, centre)


def pair_means(
    proximal: np.ndarray, distal: np.ndarray, centre: np.ndarray, noise_mm: float, pairs: int
) -> np.ndarray:
    """The analytic centre's errors ``(pairs, 3)`` [mm], each the mean of an antithetic pair
    of frame-0 noises on the noise-free markers ``proximal``, ``distal`` ``(N, n, 3)`` [mm]."""
    rng = np.random.default_rng(1)
    means = np.empty((pairs, 3))
    for k in range(pairs):
        noise = rng.normal(scale=noise_mm, size=(2, *proximal.shape[1:]))
        errors = []
        for sign in (1.0, -1.0):
            noisy = [proximal.copy(), distal.copy()]
            for markers, drawn in zip(noisy, noise, strict=True):
                markers[0] += sign * drawn
            errors.append(jointbench.fit_joint_center(*noisy, "analytic").center - centre)
        means[k] = np.mean(errors, axis=0)
    return means


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rom", default="3,5,10,30,90", help="swings [deg], comma-separated")
    parser.add_argument("--noise", default="0.5,0.02", help="frame-0 noise [mm], comma-separated")
    parser.add_argument("--pairs", type=int, default=400)
    parser.add_argument("--offset", type=float, default=0.0, help="added to coordinates [mm]")
    arguments = parser.parse_args(argv)
    for rom in (float(value) for value in arguments.rom.split(",")):
        proximal, distal, centre = two_segments(
            np.random.default_rng(0), circumduction(rom, 200), noise_mm=0.0
        )
        proximal, distal = proximal + arguments.offset, distal + arguments.offset
        truth = centre[0] + arguments.offset
        for noise_mm in (float(value) for value in arguments.noise.split(",")):
            means = pair_means(proximal, distal, truth, noise_mm, arguments.pairs)
            error = np.sqrt(means.var(axis=0, ddof=1) / len(means))
            print(
                f"swing {rom:g} deg, {noise_mm:g} mm: mean error {np.round(means.mean(0), 4)} "
                f"+- {np.round(error, 4)}  anchor_bias_mm "
                f"{np.round(formula(proximal, distal, truth, noise_mm), 4)}",
                flush=True,
            )


if __name__ == "__main__":
    main()
