"""A joint centre's stated SD against its errors over many noise draws, as the swing grows.

Usage::

    python benchmarks/joint_centre_stated_sd.py [--method analytic] [--seeds 100]
        [--rom 2,3,5,10,20,30] [--noise 0.5] [--near-hinge] [--exact-frame0]

Each seed draws the noise of one trial of ``joint_centre_degenerate.py``'s two segments (a
proximal segment that sways and drifts, a distal one circumducted about a ball joint, 200
frames, four markers each), with the same motion for every seed, and calls the method through
``jointbench.fit_joint_center``. Per swing (and, with ``--near-hinge``, on 60 degree flexions
with a second rotation of 5 and 10 % of it), printed:

* how many answers read ``ok``; the mean squared Mahalanobis distance of the errors under the
  covariance each answer's SD is read from (``centre_precision.stated_covariance``), 3 where
  that covariance describes them, and the share beyond chi-square(3)'s 99 % quantile; the
  same over the ``ok`` answers alone, with their largest error [mm];
* per component, along the eigenvectors of the mean stated covariance (ascending): the stated
  SD (from that mean) [mm], the errors' SD and mean [mm] and their excess kurtosis;
* the mean of the errors [mm, world frame at frame 0] beside the mean pull the checked call
  reports (``center_pose_noise_pull_mm``, its length) and the mean of the analytic centre's
  second-order bias from the frame-0 poses' errors (:func:`frame0_bias`).

``--exact-frame0`` leaves frame 0's markers noise-free, so that the frame-0 poses are exact.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

import jointbench
from jointbench.estimators.centre_precision import stated_covariance
from jointbench.estimators.pose_noise import lever_factors
from jointbench.estimators.segment_poses import SegmentPoses, trial_poses

sys.path.insert(0, str(Path(__file__).resolve().parent))
from joint_centre_degenerate import circumduction, hinge, two_segments

#: chi-square(3)'s 99 % quantile.
CHI2_3_99 = 11.345


def frame0_bias(proximal: SegmentPoses, distal: SegmentPoses, centre: np.ndarray) -> np.ndarray:
    """The mean ``(3,)`` [mm] of the analytic centre's error that the frame-0 poses' errors
    cause to second order, read at ``centre`` ``(3,)`` [mm] on the fitted poses.

    A frame-0 fit misplaces segment ``a``'s body frame by a rotation ``e_a`` (covariance
    ``Sigma_a = s_a^2 K_a^-1``) and so the joint in it by ``delta_a = [c - m_a]x e_a`` (plus the
    centroid's error). The analytic centre's error is exactly ``N^-1 (D_p delta_p + D_d
    delta_d)`` on the observed relative rotations ``Q_t`` (``D_p = n I - S'``, ``D_d = n I -
    S``, ``S = sum_t Q_t`` over frames ``t >= 1``, ``N = D_p + D_d``), and each ``Q_t`` carries
    the same errors, ``dQ_t = -[e_p]x Q_t + Q_t [e_d]x``: ``D`` and ``delta`` are correlated,
    and the error's mean is ``N^-1 (2 S' G_p (c - m_p) + 2 S G_d (c - m_d))`` with ``G_a =
    (Sigma_a - tr(Sigma_a) I) / 2``, the pose noise's shrinkage."""
    relative = np.einsum("fki,fkj->ij", proximal.rotation[1:], distal.rotation[1:])
    n_frames = len(proximal.rotation) - 1
    terms = []
    for poses in (proximal, distal):
        mean, inertia_inv, _ = lever_factors(np.asarray(poses.body, dtype=float))
        sigma = poses.variance * inertia_inv
        shrinkage = (sigma - np.trace(sigma) * np.eye(3)) / 2.0
        terms.append(2.0 * shrinkage @ (centre - mean))
    normal = 2.0 * n_frames * np.eye(3) - relative - relative.T
    return np.linalg.solve(normal, relative.T @ terms[0] + relative @ terms[1])


def draws(method: str, motion, seeds: int, noise_mm: float, exact_frame0: bool) -> dict:
    """Per seed, the error ``(3,)`` [mm], stated covariance ``(3, 3)`` [mm^2], status, pull
    [mm] and frame-0 bias ``(3,)`` [mm] of ``method``'s checked answer on ``motion``."""
    rows = {"error": [], "covariance": [], "ok": [], "pull": [], "frame0": []}
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
        rows["frame0"].append(frame0_bias(poses["proximal"], poses["distal"], result.center))
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
            f"{np.mean(squared[ok] > CHI2_3_99):.2f}  worst "
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


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--method", default="analytic")
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--rom", default="2,3,5,10,20,30", help="swings [deg], comma-separated")
    parser.add_argument("--noise", type=float, default=0.5, help="marker noise [mm]")
    parser.add_argument("--near-hinge", action="store_true")
    parser.add_argument("--exact-frame0", action="store_true")
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
            arguments.method, motion, arguments.seeds, arguments.noise, arguments.exact_frame0
        )
        report(f"{arguments.method} {name}, {arguments.noise:g} mm", rows)


if __name__ == "__main__":
    main()
