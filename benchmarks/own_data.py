"""Own recordings: speed, the real knee trial, and bootstrap calibration on the simulated hip.

    python benchmarks/own_data.py speed
    python benchmarks/own_data.py knee [--resamples 200]
    python benchmarks/own_data.py calibration [--trials 100 --frames 300 --resamples 200]

``speed``: reading the knee file and fitting every axis method (target <= 1 s); a 200-resample
moving-block bootstrap of SCoRE on 1000 frames (target <= 2 s), one-segment (``center``) and
two-segment (``joint_center``). ``knee``: every axis method's axis in the thigh's technical
frame, its angle to the epicondyle line RLFE-RMFE, its bootstrap 95 % cone, and how far it moves
when the frames are reversed; and Gauss–Markov's predicted uncertainty beside the bootstrap's.
``calibration``: coverage of the true hip centre by the bootstrap's 95 % ellipsoid over simulated
trials (white noise), with the binomial 95 % range of the count.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from scipy import stats

import jointbench
from jointbench.configuration.seeds import trial_rng
from jointbench.configuration.studies import get_study
from jointbench.geometry import angle_between_lines_deg
from jointbench.io import Recording, prepare, read
from jointbench.io.segments import technical_frame
from jointbench.running.scoring import CHI2_3DOF_95
from jointbench.simulate.hip import marker_layout

KNEE = Path(__file__).resolve().parents[1] / "data" / "functional-trials" / "right_knee.c3d"
THIGH = "RTHI1,RTHI2,RTHI3,RGT"
SHANK = "RLEG1,RLEG2,RLEG3,RATT,RLM,RSPH"
HIP_LABELS = ("P1", "P2", "P3", "D1", "D2", "D3")


def best_of(repeats: int, work) -> tuple[float, float]:
    """Best wall-clock and CPU seconds over ``repeats`` runs (CPU time stands in for the wall
    clock of an idle machine when other jobs share the cores)."""
    wall, cpu = [], []
    for _ in range(repeats):
        start, start_cpu = time.perf_counter(), time.process_time()
        work()
        wall.append(time.perf_counter() - start)
        cpu.append(time.process_time() - start_cpu)
    return min(wall), min(cpu)


def hip_recording(n_frames: int, trial: int) -> tuple[Recording, np.ndarray]:
    """One simulated hip trial as a recording, and the true centre in the proximal frame."""
    spec = get_study("hip")
    protocol = spec.protocol({"n_frames": max(n_frames, 3)})
    condition = {"n_frames": n_frames}
    trials = spec.simulate(condition, protocol, [trial_rng(0, "own-data", condition, trial)])
    markers = np.concatenate([trials.segments["proximal"][0], trials.segments["distal"][0]], 1)
    proximal, _ = marker_layout(protocol)
    frame = technical_frame(proximal, HIP_LABELS[:3], "layout")
    truth = frame[:3, :3].T @ (np.asarray(protocol.joint_mm) - frame[:3, 3])
    return Recording(HIP_LABELS, markers, protocol.fps, f"hip trial {trial}"), truth


def speed() -> None:
    def knee_all_axes():
        prepared = prepare(read(KNEE), "axis", SHANK, THIGH)
        for method in jointbench.methods("axis"):
            prepared.fit(method)

    wall, cpu = best_of(3, knee_all_axes)
    print(f"read knee + every axis method: {wall:.3f} s wall, {cpu:.3f} s CPU (target 1 s)")
    recording, _ = hip_recording(1000, 0)
    for kind in ("center", "joint_center"):
        prepared = prepare(recording, kind, "D1,D2,D3", "P1,P2,P3")
        wall, cpu = best_of(3, lambda p=prepared: p.fit("SCoRE", n_bootstrap=200))
        print(
            f"SCoRE ({kind}), 1000 frames, 200 resamples: {wall:.2f} s wall, {cpu:.2f} s CPU "
            "(target 2 s)"
        )


def knee(resamples: int) -> None:
    recording = read(KNEE)
    backward = Recording(recording.labels, recording.markers[::-1], recording.rate_hz, "reversed")
    forward_axes = prepare(recording, "axis", SHANK, THIGH)
    backward_axes = prepare(backward, "axis", SHANK, THIGH)
    epicondyles = forward_axes.reference.local(recording.select("RLFE,RMFE")).mean(axis=0)
    line = epicondyles[1] - epicondyles[0]
    print("axis methods, thigh technical frame (RTHI1,RTHI2,RTHI3,RGT):")
    print(
        f"{'method':<10}{'direction':>28}{'to RLFE-RMFE':>14}{'boot cone95':>13}"
        f"{'reversal: angle':>17}{'line shift':>12}"
    )
    directions = []
    for method in jointbench.methods("axis"):
        fitted = forward_axes.fit(method, n_bootstrap=resamples)
        again = backward_axes.fit(method)
        direction = fitted.result.direction * np.sign(fitted.result.direction @ line)
        directions.append(direction)
        shift = again.result.point - fitted.result.point
        across = np.linalg.norm(np.cross(shift, direction))
        print(
            f"{method:<10}{np.array2string(direction, precision=4):>28}"
            f"{angle_between_lines_deg(direction, line):>12.2f} °"
            f"{fitted.bootstrap_cone_deg():>11.2f} °"
            f"{angle_between_lines_deg(direction, again.result.direction):>15.1e} °"
            f"{across:>9.1e} mm"
        )
    spread = max(angle_between_lines_deg(a, b) for a in directions for b in directions)
    print(f"largest angle between two methods: {spread:.2f} °")

    print("joint centre (shank about thigh), thigh technical frame:")
    forward_joint = prepare(recording, "joint_center", SHANK, THIGH)
    backward_joint = prepare(backward, "joint_center", SHANK, THIGH)
    for method in jointbench.methods("joint_center"):
        fitted = forward_joint.fit(method, n_bootstrap=resamples)
        moved = np.linalg.norm(backward_joint.fit(method).result.center - fitted.result.center)
        predicted = fitted.result.covariance
        predicted = "   -  " if predicted is None else f"{np.sqrt(np.trace(predicted)):6.2f}"
        boot = np.sqrt(np.trace(fitted.bootstrap.covariance()))
        print(
            f"{method:<20}{np.array2string(fitted.result.center, precision=1):>26} mm  "
            f"sqrt(tr W_c) {predicted} mm  bootstrap sqrt(tr C) {boot:6.2f} mm  "
            f"reversal {moved:.1e} mm"
        )


def calibration(trials: int, frames: int, resamples: int, methods: list[str]) -> None:
    low, high = stats.binom.interval(0.95, trials, 0.95)
    print(
        f"{trials} simulated hip trials of {frames} frames, {resamples} resamples; "
        f"95 % ellipsoid coverage, binomial 95 % range {int(low)}-{int(high)}"
    )
    for method in methods:
        covered = covered_predicted = 0
        for trial in range(trials):
            recording, truth = hip_recording(frames, trial)
            fitted = prepare(recording, "joint_center", "D1,D2,D3", "P1,P2,P3").fit(
                method, n_bootstrap=resamples, seed=trial
            )
            error = fitted.result.center - truth
            covered += error @ np.linalg.solve(fitted.bootstrap.covariance(), error) <= CHI2_3DOF_95
            if fitted.result.covariance is not None:
                inside = error @ np.linalg.solve(fitted.result.covariance, error) <= CHI2_3DOF_95
                covered_predicted += inside
        line = f"{method:<20} bootstrap covers {covered}/{trials}"
        if method.startswith("gauss-markov"):
            line += f"; predicted W_c covers {covered_predicted}/{trials}"
        print(line, flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("what", choices=("speed", "knee", "calibration"))
    parser.add_argument("--resamples", type=int, default=200)
    parser.add_argument("--trials", type=int, default=100)
    parser.add_argument("--frames", type=int, default=300)
    parser.add_argument("--methods", default="SCoRE,gauss-markov")
    args = parser.parse_args()
    if args.what == "speed":
        speed()
    elif args.what == "knee":
        knee(args.resamples)
    else:
        calibration(args.trials, args.frames, args.resamples, args.methods.split(","))


if __name__ == "__main__":
    main()
