"""A joint centre's stated SD against its errors over many noise draws, as the swing grows.

Usage::

    python benchmarks/joint_centre_stated_sd.py [--methods analytic,SCoRE] [--seeds 100]
        [--rom 2,3,5,10,20,30] [--noise 0.5,1] [--near-hinge] [--exact-frame0] [--anchors 8]

Each seed draws the noise of one trial of ``joint_centre_degenerate.py``'s two segments (a
proximal segment that sways and drifts, a distal one circumducted about a ball joint, 200
frames, four markers each), with the same motion for every seed, and calls the method through
``jointbench.fit_joint_center``. Per method, noise level and swing (and, with ``--near-hinge``,
on 60 degree flexions with a second rotation of 5 and 10 % of it), printed:

* how many answers read ``ok``; the mean squared Mahalanobis distance of the errors under the
  covariance each answer's SD is read from (``centre_precision.stated_covariance``), 3 where
  that covariance describes them, and the share beyond chi-square(3)'s 99 % quantile; the
  same over the ``ok`` answers alone, with how many lie more than 3 SDs off (Mahalanobis) and
  their largest error [mm]; beside that count, the count the stated covariances imply (the
  ``ok`` answers times chi-square(3)'s share beyond 9, 2.9 %) and the binomial probability of
  the observed count or more under it. Chi-square is the errors' law where they are normal:
  the simulated markers' errors (paper A's, uniform directions with normal lengths) have an
  excess kurtosis of 2.4 per coordinate, and an answer whose error the few markers of frame 0
  lead inherits part of it, so that even a covariance that holds (mean squared distance 3)
  puts more than 2.9 % beyond 3 SDs;
* per component, along the eigenvectors of the mean stated covariance (ascending): the stated
  SD (from that mean) [mm], the errors' SD and mean [mm] and their excess kurtosis;
* the mean of the errors [mm, world frame at frame 0] beside the mean pull the checked call
  reports (``center_pose_noise_pull_mm``, its length) and the mean of the analytic centre's
  second-order bias from the frame-0 poses' errors (``pose_noise.anchor_bias_mm``).

A closing table holds each case's line: answers, ``ok`` answers, those beyond 3 SDs against
the count implied, the binomial p-value and that p-value times the number of cases
(Bonferroni), the significance of a heavier tail than stated where it is below 0.01.

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

#: chi-square(3)'s share beyond 9 (3 SDs, Mahalanobis): what a stated covariance that
#: describes the errors puts there.
BEYOND_3_SDS = float(scipy_special().chdtrc(3, 9.0))


def tail_p_value(beyond: int, answers: int) -> float:
    """The binomial probability of ``beyond`` or more of ``answers`` lying more than 3 SDs off
    where each does so with chi-square(3)'s share :data:`BEYOND_3_SDS`: small where the tail is
    heavier than the stated covariance implies."""
    if beyond == 0:
        return 1.0
    return float(scipy_special().bdtrc(beyond - 1, answers, BEYOND_3_SDS))


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


def report(name: str, rows: dict) -> tuple:
    """Print one case's lines (module docstring) and return its row of the closing table:
    answers, ``ok`` answers, those beyond 3 SDs, the count implied and the p-value."""
    errors, covariances, ok = rows["error"], rows["covariance"], rows["ok"]
    squared = np.einsum("ti,ti->t", errors, np.linalg.solve(covariances, errors[..., None])[..., 0])
    beyond = int(np.sum(squared[ok] > 9.0))
    implied = BEYOND_3_SDS * ok.sum()
    p_value = tail_p_value(beyond, int(ok.sum()))
    line = (
        f"{name}: ok {ok.sum()}/{len(ok)}  M2 {squared.mean():.2f} (3)  beyond 99% "
        f"{np.mean(squared > CHI2_3_99):.2f}"
    )
    if ok.any():
        line += (
            f"  | ok: M2 {np.mean(squared[ok]):.2f}  beyond 99% "
            f"{np.mean(squared[ok] > CHI2_3_99):.2f}  beyond 3 SDs "
            f"{beyond} (implied {implied:.1f}, p {p_value:.2g})  worst "
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
        far = ok & (squared > CHI2_3_99)
        print(
            f"    anchors: spread chi2/dof {np.mean(chi2 / dof):.2f}  rejected "
            f"{rejected.sum()}/{len(chi2)}  ok beyond 99% rejected {np.sum(rejected & far)}/"
            f"{far.sum()}"
        )
    worst = np.linalg.norm(errors[ok], axis=1).max() if ok.any() else np.nan
    return len(ok), int(ok.sum()), beyond, implied, p_value, worst


def table(lines: list) -> None:
    """Print the closing table (module docstring) of ``lines``, (name, row of :func:`report`)."""
    print(
        f"\n{'case':44s} {'n':>5s} {'ok':>5s} {'>3SD':>5s} {'impl':>6s} {'p':>8s} "
        f"{'p x cases':>9s} worst"
    )
    for name, (n, n_ok, beyond, implied, p_value, worst) in lines:
        adjusted = min(1.0, p_value * len(lines))
        flag = "  heavier" if adjusted < 0.01 else ""
        print(
            f"{name:44s} {n:5d} {n_ok:5d} {beyond:5d} {implied:6.1f} {p_value:8.2g} "
            f"{adjusted:9.2g} {worst:5.1f}{flag}"
        )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--methods", default="analytic", help="comma-separated")
    parser.add_argument("--seeds", type=int, default=100)
    parser.add_argument("--rom", default="2,3,5,10,20,30", help="swings [deg], comma-separated")
    parser.add_argument("--noise", default="0.5", help="marker noise [mm], comma-separated")
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
    lines = []
    for method in arguments.methods.split(","):
        for noise in (float(value) for value in arguments.noise.split(",")):
            for name, motion in cases:
                rows = draws(
                    method,
                    motion,
                    arguments.seeds,
                    noise,
                    arguments.exact_frame0,
                    arguments.anchors,
                )
                case = f"{method} {name}, {noise:g} mm"
                lines.append((case, report(case, rows)))
    table(lines)


if __name__ == "__main__":
    main()
