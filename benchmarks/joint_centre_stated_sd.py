"""A joint centre's stated SD against its errors over many noise draws, as the swing grows.

Usage::

    python benchmarks/joint_centre_stated_sd.py [--method analytic] [--seeds 100]
        [--rom 2,3,5,10,20,30] [--noise 0.5] [--near-hinge] [--exact-frame0] [--anchors 8]

Each seed draws the noise of one trial of ``joint_centre_degenerate.py``'s two segments (a
proximal segment that sways and drifts, a distal one circumducted about a ball joint, 200
frames, four markers each), with the same motion for every seed, and calls the method through
``jointbench.fit_joint_center``. Per swing (and, with ``--near-hinge``, on 60 degree flexions
with a second rotation of 5 and 10 % of it), printed:

* how many answers read ``ok``; the mean squared Mahalanobis distance of the errors under the
  covariance each answer's SD is read from (``centre_precision.stated_covariance``), 3 where
  that covariance describes them, and the share beyond chi-square(3)'s 99 % quantile; the
  same over the ``ok`` answers alone, with how many lie more than 3 SDs off (Mahalanobis) and
  their largest error [mm];
* per component, along the eigenvectors of the mean stated covariance (ascending): the stated
  SD (from that mean) [mm], the errors' SD and mean [mm] and their excess kurtosis;
* the mean of the errors [mm, world frame at frame 0] beside the mean pull the checked call
  reports (``center_pose_noise_pull_mm``, its length) and the mean of the analytic centre's
  second-order bias from the frame-0 poses' errors (``pose_noise.anchor_bias_mm``).

``--exact-frame0`` leaves frame 0's markers noise-free, so that the frame-0 poses are exact.

``--anchors K`` (``analytic`` only) asks whether an answer's dependence on the frame that
anchors its body frames tells the answers its SD understates: the same markers are fitted again
with each of ``K`` evenly spread frames first (frame 0 among them), each answer taken to the
proximal body frame of the first fit by that frame's proximal pose, its stated covariance
turned with it; the spread of the ``K`` answers about their mean against their mean covariance
is chi-square on ``3 (K - 1)`` degrees of freedom where the anchors' errors are independent
and the covariances hold (the frames' shared noise moves every answer alike and leaves the
spread, so the statistic is conservative). Printed: its mean over dof, how many answers it
rejects at ``support.ROTATION_ALPHA``, and how many of the ``ok`` answers beyond chi-square's
99 % quantile it rejects. Slow: ``K`` fits per draw.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import jointbench
from jointbench.estimators.centre_precision import stated_covariance
from jointbench.estimators.pose_noise import anchor_bias_mm
from jointbench.estimators.segment_poses import trial_poses
from jointbench.estimators.support import ROTATION_ALPHA
from jointbench.numerics.special import scipy_special

sys.path.insert(0, str(Path(__file__).resolve().parent))
from joint_centre_degenerate import circumduction, hinge, two_segments

#: chi-square(3)'s 99 % quantile.
CHI2_3_99 = 11.345


def anchor_spread(proximal: np.ndarray, distal: np.ndarray, anchors: int) -> tuple:
    """The spread chi-square of the analytic answers to the markers ``proximal``, ``distal``
    ``(N, n, 3)`` [mm] anchored at ``anchors`` evenly spread frames (module docstring) and its
    degrees of freedom."""
    poses = trial_poses({"proximal": [proximal]}, min_frames=3)[0]["proximal"]
    n_frames = len(proximal)
    answers, covariances = [], []
    for frame in np.unique(np.linspace(0, n_frames - 1, anchors).astype(int)):
        order = np.r_[frame, np.delete(np.arange(n_frames), frame)]
        result = jointbench.fit_joint_center(proximal[order], distal[order], "analytic")
        back = poses.rotation[frame].T
        answers.append(back @ (result.center - poses.translation[frame]))
        covariances.append(back @ stated_covariance(result)[0] @ back.T)
    spread = np.array(answers) - np.mean(answers, axis=0)
    pooled = np.mean(covariances, axis=0)
    chi2 = float(np.einsum("ki,ik->", spread, np.linalg.solve(pooled, spread.T)))
    return chi2, 3 * (len(answers) - 1)


def draws(
    method: str, motion, seeds: int, noise_mm: float, exact_frame0: bool, anchors: int = 0
) -> dict:
    """Per seed, the error ``(3,)`` [mm], stated covariance ``(3, 3)`` [mm^2], status, pull
    [mm] and frame-0 bias ``(3,)`` [mm] of ``method``'s checked answer on ``motion``."""
    rows = {"error": [], "covariance": [], "ok": [], "pull": [], "frame0": [], "anchors": []}
    for seed in range(seeds):
        proximal, distal, centre = two_segments(
            np.random.default_rng(seed), motion(), noise_mm=noise_mm
        )
        if exact_frame0:
            clean = two_segments(np.random.default_rng(seed), motion(), noise_mm=0.0)
            proximal, distal = proximal.copy(), distal.copy()
            proximal[0], distal[0] = clean[0][0], clean[1][0]
        result = jointbench.fit_joint_center(proximal, distal, method)
        poses = trial_poses({"proximal": [proximal], "distal": [distal]}, min_frames=3)[0]
        rows["error"].append(result.center - centre[0])
        rows["covariance"].append(stated_covariance(result)[0])
        rows["ok"].append(result.status == "ok")
        rows["pull"].append(result.diagnostics.get("center_pose_noise_pull_mm", np.nan))
        rows["frame0"].append(anchor_bias_mm(poses["proximal"], poses["distal"], result.center))
        if anchors:
            rows["anchors"].append(anchor_spread(proximal, distal, anchors))
    return {key: np.array(value) for key, value in rows.items()}


def report(name: str, rows: dict) -> None:
    """Print one case's lines (module docstring)."""
    errors, covariances, ok = rows["error"], rows["covariance"], rows["ok"]
    squared = np.einsum("ti,ti->t", errors, np.linalg.solve(covariances, errors[..., None])[..., 0])
    line = (
        f"{name}: ok {ok.sum()}/{len(ok)}  M2 {squared.mean():.2f} (3)  beyond 99% "
        f"{np.mean(squared > CHI2_3_99):.2f}"
    )
    if ok.any():
        line += (
            f"  | ok: M2 {np.mean(squared[ok]):.2f}  beyond 99% "
            f"{np.mean(squared[ok] > CHI2_3_99):.2f}  beyond 3 SDs "
            f"{np.sum(squared[ok] > 9.0)}  worst "
            f"{np.linalg.norm(errors[ok], axis=1).max():.1f} mm"
        )
    print(line)
    values, vectors = np.linalg.eigh(covariances.mean(axis=0))
    along = errors @ vectors
    for i in range(3):
        centred = along[:, i] - along[:, i].mean()
        kurtosis = np.mean(centred**4) / np.mean(centred**2) ** 2 - 3.0
        print(
            f"    component {i}: stated SD {np.sqrt(values[i]):6.2f}  errors' SD "
            f"{along[:, i].std(ddof=1):6.2f}  mean {along[:, i].mean():6.2f}  "
            f"kurtosis {kurtosis:5.2f}"
        )
    print(
        f"    mean error {np.round(errors.mean(axis=0), 2)}  mean |pull| "
        f"{np.nanmean(rows['pull']):.2f}  mean frame-0 bias {np.round(rows['frame0'].mean(0), 2)}"
    )
    if len(rows["anchors"]):
        chi2, dof = rows["anchors"].T
        rejected = scipy_special().chdtrc(dof, chi2) < ROTATION_ALPHA
        beyond = ok & (squared > CHI2_3_99)
        print(
            f"    anchors: spread chi2/dof {np.mean(chi2 / dof):.2f}  rejected "
            f"{rejected.sum()}/{len(chi2)}  ok beyond 99% rejected {np.sum(rejected & beyond)}/"
            f"{beyond.sum()}"
        )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--method", default="analytic")
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--rom", default="2,3,5,10,20,30", help="swings [deg], comma-separated")
    parser.add_argument("--noise", type=float, default=0.5, help="marker noise [mm]")
    parser.add_argument("--near-hinge", action="store_true")
    parser.add_argument("--exact-frame0", action="store_true")
    parser.add_argument("--anchors", type=int, default=0, help="frames anchoring refits")
    arguments = parser.parse_args(argv)
    cases = [
        (f"swing {rom:g} deg", lambda rom=rom: circumduction(rom, 200))
        for rom in (float(value) for value in arguments.rom.split(","))
    ]
    if arguments.near_hinge:
        cases += [
            (f"near-hinge {second:g}", lambda second=second: hinge(60.0, 200, second))
            for second in (0.05, 0.1)
        ]
    for name, motion in cases:
        rows = draws(
            arguments.method,
            motion,
            arguments.seeds,
            arguments.noise,
            arguments.exact_frame0,
            arguments.anchors,
        )
        report(f"{arguments.method} {name}, {arguments.noise:g} mm", rows)


if __name__ == "__main__":
    main()
