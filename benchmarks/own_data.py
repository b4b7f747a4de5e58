"""Own recordings: speed, the real knee trial, and bootstrap calibration on the simulated hip.

    python benchmarks/own_data.py speed
    python benchmarks/own_data.py knee [--resamples 200]
    python benchmarks/own_data.py calibration [--trials 100 --frames 300 --resamples 200]
    python benchmarks/own_data.py reading [--frames 100000]

``speed``: reading the knee file and fitting every axis method (target <= 1 s); a 200-resample
moving-block bootstrap of SCoRE on 1000 frames (target <= 2 s), one-segment (``center``) and
two-segment (``joint_center``). ``knee``: every axis method's axis in the thigh's technical
frame, its angle to the epicondyle line RLFE-RMFE, its bootstrap 95 % cone, and how far it moves
when the frames are reversed; and Gauss–Markov's predicted uncertainty beside the bootstrap's.
``calibration``: coverage of the true hip centre by the bootstrap's 95 % ellipsoid over simulated
trials (white noise), with the binomial 95 % range of the count. ``reading``: the peak memory
(RSS over the interpreter's own, each read in a process of its own) and CPU time of reading an
export of 40 markers x ``--frames`` frames as TRC and as CSV, and the CPU time of the rule for
samples at the origin on 10 markers x ``--frames`` frames, a tenth of them in runs at the origin.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy import stats

import jointbench
from jointbench.configuration.seeds import trial_rng
from jointbench.configuration.studies import get_study
from jointbench.geometry import angle_between_lines_deg
from jointbench.io import Recording, prepare, read
from jointbench.io.recording import origin_gaps
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


#: Reads the file its argument names and prints the most memory the reading held [MiB]: its
#: peak RSS over the RSS before it (a high-water mark: a file that takes less than the imports
#: once did reads as less), and as Python and NumPy allocate it (tracemalloc: the parsers' own
#: buffers not counted); and its CPU seconds, timed apart.
_READ_ONE = """
import resource, sys, time, tracemalloc, warnings
from jointbench.io import read
warnings.simplefilter("ignore")
with open("/proc/self/statm") as statm:
    before = int(statm.read().split()[1]) * resource.getpagesize() / 2**20
start = time.process_time()
read(sys.argv[1])
cpu = time.process_time() - start
rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024 - before
tracemalloc.start()
read(sys.argv[1])
print(rss, tracemalloc.get_traced_memory()[1] / 2**20, cpu)
"""


def reading(n_frames: int) -> None:
    rng = np.random.default_rng(0)
    times = np.arange(n_frames)[:, None, None] / 100.0
    markers = 1000.0 + 300.0 * np.sin(times * rng.uniform(0.5, 2.0, (1, 40, 3)))
    labels = [f"M{i:02d}" for i in range(1, 41)]
    with tempfile.TemporaryDirectory() as folder:
        for path in (Path(folder) / "long.trc", Path(folder) / "long.csv"):
            _write_export(path, labels, markers)
            size = path.stat().st_size / 2**20
            run = [sys.executable, "-c", _READ_ONE, str(path)]
            output = subprocess.run(run, capture_output=True, text=True, check=True).stdout
            rss, traced, cpu = map(float, output.split())
            print(
                f"read {path.suffix[1:].upper()}, 40 markers x {n_frames} frames ({size:.0f} MiB): "
                f"peak RSS +{rss:.0f} MiB ({rss / size:.1f}x the file), traced {traced:.0f} MiB "
                f"({traced / size:.1f}x), {cpu:.2f} s CPU"
            )
    gappy = markers[:, :10].copy()
    for marker in range(10):
        starts = rng.integers(0, n_frames - 20, n_frames // 105)
        for start, length in zip(starts, rng.integers(1, 21, starts.size), strict=True):
            gappy[start : start + length, marker] = 0.0
    origin_gaps(gappy)  # compiled before it is timed
    _, cpu = best_of(7, lambda: origin_gaps(gappy))
    print(
        f"origin_gaps, 10 markers x {n_frames} frames, ~10 % at the origin: {cpu * 1e3:.1f} ms CPU"
    )


def _write_export(path: Path, labels: list[str], markers: np.ndarray) -> None:
    """``markers`` ``(n_frames, n, 3)`` [mm] as a TRC or a long CSV (by ``path``'s suffix),
    five decimals."""
    n_frames = len(markers)
    with path.open("w") as file:
        if path.suffix == ".csv":
            file.write("frame,marker,x,y,z\n")
            for frame, sample in enumerate(markers, 1):
                file.writelines(
                    f"{frame},{label},{x:.5f},{y:.5f},{z:.5f}\n"
                    for label, (x, y, z) in zip(labels, sample, strict=True)
                )
            return
        names = "\t".join(f"X{i}\tY{i}\tZ{i}" for i in range(1, len(labels) + 1))
        file.write(
            f"PathFileType\t4\t(X/Y/Z)\t{path.name}\nDataRate\tCameraRate\tNumFrames\t"
            f"NumMarkers\tUnits\n100\t100\t{n_frames}\t{len(labels)}\tmm\nFrame#\tTime\t"
            + "\t\t\t".join(labels)
            + f"\n\t\t{names}\n"
        )
        table = np.column_stack(
            [np.arange(1, n_frames + 1), np.arange(n_frames) / 100.0, markers.reshape(n_frames, -1)]
        )
        np.savetxt(file, table, fmt=["%d", "%.4f"] + ["%.5f"] * (3 * len(labels)), delimiter="\t")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("what", choices=("speed", "knee", "calibration", "reading"))
    parser.add_argument("--resamples", type=int, default=200)
    parser.add_argument("--trials", type=int, default=100)
    parser.add_argument("--frames", type=int, default=None)
    parser.add_argument("--methods", default="SCoRE,gauss-markov")
    args = parser.parse_args()
    if args.what == "speed":
        speed()
    elif args.what == "knee":
        knee(args.resamples)
    elif args.what == "reading":
        reading(args.frames or 100_000)
    else:
        calibration(args.trials, args.frames or 300, args.resamples, args.methods.split(","))


if __name__ == "__main__":
    main()
