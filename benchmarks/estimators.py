"""Time every registered estimator on standard synthetic trials and check the speed targets.

Usage::

    python benchmarks/estimators.py            # full run (a few minutes at most)
    python benchmarks/estimators.py --quick    # seconds; for CI and smoke tests
    python benchmarks/estimators.py --kind center --strict

Every method registered for a kind (``jointbench.methods(kind)``) is timed three ways on trials
this script builds itself from ``jointbench.geometry`` and
``jointbench.simulate.noise.isotropic_noise``: alone (the registered function without checks, as
a study's estimate job runs it; the targets apply to this), checked (``registry.get(kind,
name)``: the input checks, the method's self-check and the support verdict; held to at most
:data:`MAX_CHECK_RATIO` times alone) and through the public API (``fit_center``, ``fit_axis``,
``fit_joint_center``: the checked call after the artefact screen). Beside them, the public call
of the commit ``--baseline`` (Nov 22's, :data:`BASELINE_COMMIT`, by default), checked out in a
``git worktree`` and timed the same way on the same trials in a subprocess
(``benchmarks/baseline_worker.py``). The many-trial forms are timed likewise, bare and checked.
Data sets:

* ``center``: 3 markers (paper A's M set distances) x 120 frames, a ~15 degree circumduction
  spiral, 1 mm noise;
* ``axis``: 3 markers x 121 frames and x 5000 frames, a 60 degree flexion with abduction 0.3
  times the flexion (paper B's kind of near-hinge), 1 mm noise;
* ``joint_center``: 3 + 3 markers x 1200 frames, both segments moving in the world and joined by
  a ball joint, 0.5 mm noise.

A method whose signature takes two segments but is registered under ``axis`` gets two-segment
hinge trials of 3 + 3 markers x 1200 frames. Each method is timed call by call on distinct
trials, its three calls (alone, checked, public) in alternating blocks of the same trials after
an untimed first call each (:func:`time_variants`), its many-trial forms likewise
(:func:`time_batched`); medians are reported with the targets, and kinds with no registered
method are skipped. Timings are wall-clock by default (``--clock wall``); ``--clock cpu`` times
the process's CPU time instead (``time.process_time``), which another process's load on a
shared machine does not lengthen, though it still slows the call through the caches and memory
it shares. On a shared machine run twice before trusting a failure.
"""

from __future__ import annotations

import argparse
import functools
import inspect
import itertools
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

import numpy as np

import jointbench
from jointbench import geometry
from jointbench.estimators import registry
from jointbench.estimators.segment_poses import POSE_MIN_FRAMES, pose_segments, trial_poses
from jointbench.simulate.noise import isotropic_noise

# Targets [s], by (kind, method, data label); ``None`` label applies to every data set.
TARGETS: dict[tuple[str, str, str | None], float] = {
    ("center", "NM", None): 100e-6,
    ("center", "LS", None): 50e-6,
    ("center", "BC", None): 2e-3,
    ("center", "IS", None): 30e-3,
    ("center", "MA", None): 100e-3,
    ("axis", "combined", "3 x 121"): 20e-3,
    ("axis", "combined", "3 x 5000"): 200e-3,
    # The one-segment SARA on 3 markers x 1200 frames in the reference frame is the 3 + 3 x 1200
    # two-segment problem expressed in the proximal frame.
    ("axis", "SARA", "3 x 1200"): 20e-3,
    ("axis", "SARA", "3+3 x 1200"): 20e-3,
    ("joint_center", "gauss-markov", None): 100e-3,
    ("joint_center", "SCoRE", None): 20e-3,
    ("joint_center", "SARA", None): 20e-3,
}

# Per-trial targets [s] of the many-trial (``batched``) forms, by (kind, method, data label).
BATCHED_TARGETS: dict[tuple[str, str, str], float] = {
    ("center", "LS", "3 x 120"): 20e-6,
    ("center", "NM", "3 x 120"): 20e-6,
    ("center", "BC", "3 x 120"): 100e-6,
    ("joint_center", "SCoRE", "3+3 x 1200"): 3e-3,
    ("joint_center", "gauss-markov", "3+3 x 1200"): 5e-3,
    ("axis", "combined", "3 x 121"): 5e-3,
}
# Trials per batched call, by data label: enough to amortise per-call overheads.
_BATCH_SIZE = {"3 x 120": 512, "3 x 121": 64, "3+3 x 1200": 64}

# Paper A Table 1, M set (distances from the CoR); directions are this script's choice.
_M_SET = geometry.unit(np.array([[0.2, 0.3, 1.0], [0.0, 0.1, 1.0], [-0.3, 0.2, 1.0]])) * np.array(
    [[13.8], [29.0], [15.7]]
)
_N_TRIALS_POOL = 32  # distinct noisy trials per data set, cycled when timing


@dataclass(frozen=True)
class DataSet:
    kind: str
    label: str
    trials: list[tuple[np.ndarray, ...]]  # positional arguments of the estimator


def _spiral(rom_deg: float, n_frames: int, turns: float = 3.0) -> np.ndarray:
    """Circumduction: rotation vectors spiralling out from the mean pose to ``rom_deg``."""
    t = np.linspace(0.0, 1.0, n_frames)
    angle, phase = np.radians(rom_deg) * t, 2.0 * np.pi * turns * t
    rotvec = np.stack([angle * np.cos(phase), angle * np.sin(phase), np.zeros_like(t)], axis=-1)
    return geometry.rotation_matrix(rotvec)


def _near_hinge(n_frames: int, rom_deg: float = 60.0, ratio: float = 0.3) -> np.ndarray:
    """Flexion about z over ``rom_deg`` with abduction about x of ``ratio`` times the flexion."""
    flexion = np.radians(rom_deg / 2.0) * np.sin(np.linspace(0.0, 2.0 * np.pi, n_frames))
    abduction = geometry.rotation_about_axis(np.array([1.0, 0.0, 0.0]), ratio * flexion)
    return geometry.rotation_about_axis(np.array([0.0, 0.0, 1.0]), flexion) @ abduction


def _rigid(rotations: np.ndarray, body: np.ndarray, origin: np.ndarray) -> np.ndarray:
    return np.einsum("kij,pj->kpi", rotations, body) + origin


def center_data(rng: np.random.Generator, n_trials: int) -> DataSet:
    clean = _rigid(_spiral(15.0, 120), _M_SET, np.array([10.0, -20.0, 30.0]))
    trials = [(clean + isotropic_noise(rng, clean.shape[:2], 1.0),) for _ in range(n_trials)]
    return DataSet("center", "3 x 120", trials)


def axis_data(rng: np.random.Generator, n_trials: int, n_frames: int) -> DataSet:
    body = np.array([[60.0, 20.0, 10.0], [90.0, -15.0, 25.0], [75.0, 5.0, -30.0]])
    clean = _rigid(_near_hinge(n_frames), body, np.array([5.0, 10.0, -20.0]))
    trials = [(clean + isotropic_noise(rng, clean.shape[:2], 1.0),) for _ in range(n_trials)]
    return DataSet("axis", f"3 x {n_frames}", trials)


def two_segment_data(
    rng: np.random.Generator, n_trials: int, kind: str, joint: str, n_frames: int = 1200
) -> DataSet:
    """Proximal and distal markers in the world, joined at a ball joint or a near-hinge."""
    proximal_body = np.array([[0.0, 0.0, 0.0], [80.0, 0.0, 10.0], [20.0, 70.0, -15.0]])
    center_in_proximal = np.array([40.0, 30.0, -90.0])
    distal_body = np.array([[30.0, 10.0, -120.0], [-25.0, 20.0, -200.0], [5.0, -30.0, -300.0]])
    # The proximal segment sways and drifts; the distal one moves about the joint on top of it.
    t = np.linspace(0.0, 1.0, n_frames)
    sway = 0.15 * np.stack([np.sin(3 * t), np.sin(5 * t + 1), np.cos(4 * t)], axis=-1)
    proximal_rot = geometry.rotation_matrix(sway)
    proximal_pos = np.stack([300 * t, 20 * np.sin(7 * t), 900 + 10 * t], axis=-1)
    joint_rot = _spiral(30.0, n_frames) if joint == "ball" else _near_hinge(n_frames)
    center_world = proximal_rot @ center_in_proximal + proximal_pos
    clean_prox = np.einsum("kij,pj->kpi", proximal_rot, proximal_body) + proximal_pos[:, None]
    clean_dist = np.einsum("kij,pj->kpi", proximal_rot @ joint_rot, distal_body)
    clean_dist = clean_dist + center_world[:, None]
    trials = [
        (
            clean_prox + isotropic_noise(rng, clean_prox.shape[:2], 0.5),
            clean_dist + isotropic_noise(rng, clean_dist.shape[:2], 0.5),
        )
        for _ in range(n_trials)
    ]
    return DataSet(kind, f"3+3 x {n_frames}", trials)


def build_data(kind: str, label: str, rng: np.random.Generator, n_pool: int) -> DataSet:
    """The standard data set ``label`` ("3 x 120", "3 x <frames>", "3+3 x 1200") of ``kind``."""
    if label == "3 x 120":
        return center_data(rng, n_pool)
    if label == "3+3 x 1200":
        return two_segment_data(rng, n_pool, kind, "ball" if kind == "joint_center" else "hinge")
    n_frames = int(label.split(" x ")[1])
    return axis_data(rng, n_pool if n_frames <= 1200 else max(2, n_pool // 4), n_frames)


_PUBLIC: dict[str, Callable] = {
    "center": jointbench.fit_center,
    "axis": jointbench.fit_axis,
    "joint_center": jointbench.fit_joint_center,
}


def _n_segments(kind: str, name: str) -> int:
    """Positional marker arrays the estimator takes (1, or 2 for two-segment methods)."""
    if kind == "joint_center":
        return 2
    parameters = inspect.signature(registry.get(kind, name)).parameters.values()
    required = [
        p
        for p in parameters
        if p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) and p.default is p.empty
    ]
    return max(1, len(required))


#: The clocks a timing may read, by ``--clock`` name: the name of a function of :mod:`time`
#: (the baseline worker reads the same function by that name).
CLOCKS = {"wall": "perf_counter", "cpu": "process_time"}

#: A clock: seconds since an arbitrary origin.
Clock = Callable[[], float]


class Timed(NamedTuple):
    """One variant's timing: median seconds per call by the clock it was timed with (NaN if it
    failed), the calls timed and a note (an error, or trials that did not converge)."""

    seconds: float
    calls: int
    note: str


def time_variants(
    fits: dict[str, Callable],
    data: DataSet,
    seconds: float,
    min_calls: int,
    max_calls: int,
    clock: Clock = time.perf_counter,
) -> dict[str, Timed]:
    """:class:`Timed` of each of ``fits`` (the variants of one method: alone, checked, public)
    called on the trials of ``data``, by the same name, each call timed by ``clock``.

    Each variant is first called once untimed, before the clock starts: the imports, the
    compilation of kernels and the caches of a first call are not what is measured, and must not
    use up a variant's time. The variants are then timed in rounds, each fitting the same block
    of distinct trials in turn, the order rotating from round to round, so that every variant
    meets the same windows of the machine's load and their ratios compare like with like. The
    rounds stop when every variant has ``max_calls`` calls, or, once each has ``min_calls``,
    when they have used ``seconds`` each (of wall-clock time, whatever ``clock``). A variant
    that raises is reported (its note) and dropped; the others go on.
    """
    timings: dict[str, list[float]] = {name: [] for name in fits}
    notes = dict.fromkeys(fits, "")
    live = []
    for name, fit in fits.items():
        try:
            fit(*data.trials[0])
            live.append(name)
        except Exception as error:  # report and go on: one broken variant must not hide others
            notes[name] = f"error: {type(error).__name__}: {error}"
    block = data.trials[: min(len(data.trials), max_calls)]
    budget = seconds * len(fits)
    start = time.perf_counter()
    for round_index in itertools.count():
        if not live or all(len(timings[name]) >= max_calls for name in live):
            break
        if time.perf_counter() - start > budget and all(
            len(timings[name]) >= min_calls for name in live
        ):
            break
        shift = round_index % len(live)
        for name in live[shift:] + live[:shift]:
            try:
                converged = _time_block(
                    fits[name], block[: max_calls - len(timings[name])], timings[name], clock
                )
            except Exception as error:
                notes[name] = f"error: {type(error).__name__}: {error}"
                continue
            if not converged and not notes[name]:
                notes[name] = "some trials did not converge"
        live = [name for name in live if not notes[name].startswith("error")]
    return {
        name: Timed(
            statistics.median(timings[name]) if name in live else float("nan"),
            len(timings[name]),
            notes[name],
        )
        for name in fits
    }


def _time_block(fit: Callable, trials: list, timings: list[float], clock: Clock) -> bool:
    """Append the seconds by ``clock`` of ``fit(*trial)`` for each of ``trials`` to
    ``timings``; whether every result converged."""
    converged = True
    for trial in trials:
        start = clock()
        result = fit(*trial)
        timings.append(clock() - start)
        converged = converged and bool(result.converged)
    return converged


def _batch(data: DataSet, n_trials: int) -> list[np.ndarray]:
    """The data set's distinct trials, cycled up to ``n_trials``, stacked per argument."""
    picks = [data.trials[i % len(data.trials)] for i in range(n_trials)]
    return [np.stack(arrays) for arrays in zip(*picks, strict=True)]


def time_batched(
    kind: str,
    name: str,
    data: DataSet,
    n_trials: int,
    repeats: int,
    clock: Clock = time.perf_counter,
) -> dict[str, tuple[float, str]]:
    """Median over ``repeats`` of a batched call's seconds by ``clock`` divided by its trials, and a
    note, for each variant of the many-trial form of method ``name``: ``"estimator"``, the bare
    form the study's estimate jobs run; ``"checked"``, the registry's checked form (input checks
    and support verdict per trial, as a user's call); and, for a pose-based method, ``"from
    fitted poses"``, the bare form given the trials' poses fitted beforehand, as the hip study's
    estimate jobs are (that fit is timed by :func:`time_pose_fit`).

    The batch cycles through the data set's distinct trials up to ``n_trials``. Each variant is
    called once untimed on two trials first; then every repeat calls the variants in turn, the
    order rotating, so that they share the machine's load as the one-trial variants do
    (:func:`time_variants`). A variant that raises is reported and dropped.
    """
    segments = _batch(data, n_trials)
    bare = registry.many(kind, name, checked=False)
    variants: dict[str, tuple[Callable, dict]] = {
        "estimator": (bare, {}),
        "checked": (registry.many(kind, name, checked=True), {}),
    }
    names = pose_segments(bare)
    if names is not None:
        poses = trial_poses(dict(zip(names, segments, strict=True)), min_frames=POSE_MIN_FRAMES)
        variants["from fitted poses"] = (bare, {"poses": poses})
    timings: dict[str, list[float]] = {variant: [] for variant in variants}
    notes = dict.fromkeys(variants, "")
    for variant, (batched, _) in variants.items():
        try:
            batched(*(segment[:2] for segment in segments))
        except Exception as error:  # report and go on: one broken variant must not hide others
            notes[variant] = f"error: {type(error).__name__}: {error}"
    for repeat in range(repeats):
        live = [variant for variant in variants if not notes[variant].startswith("error")]
        shift = repeat % max(len(live), 1)
        for variant in live[shift:] + live[:shift]:
            batched, options = variants[variant]
            try:
                start = clock()
                outcomes = batched(*segments, **options)
                timings[variant].append((clock() - start) / n_trials)
            except Exception as error:
                notes[variant] = f"error: {type(error).__name__}: {error}"
                continue
            failures = sum(isinstance(outcome, Exception) for outcome in outcomes)
            notes[variant] = f"{failures} trials failed" if failures else ""
    return {
        variant: (
            float("nan")
            if notes[variant].startswith("error")
            else statistics.median(timings[variant]),
            notes[variant],
        )
        for variant in variants
    }


def time_pose_fit(
    data: DataSet, n_trials: int, repeats: int, clock: Clock = time.perf_counter
) -> float:
    """Median seconds by ``clock`` per trial of fitting every segment's poses of a batch (with
    the checks the pose-based methods make), which pose-based methods can share."""
    segments = _batch(data, n_trials)
    names = [f"segment {index}" for index in range(len(segments))]
    timings = []
    for _ in range(repeats):
        start = clock()
        trial_poses(dict(zip(names, segments, strict=True)), min_frames=POSE_MIN_FRAMES)
        timings.append((clock() - start) / n_trials)
    return statistics.median(timings)


#: The landed code of Nov 22, before the input checks and the support verdict joined the
#: public call: its public call is the reference the checked call is held to.
BASELINE_COMMIT = "235295a"


def baseline_timings(
    commit: str, jobs: dict[tuple[str, str, str], DataSet], calls: int, clock: str = "wall"
) -> dict[tuple[str, str, str], float]:
    """Median seconds per public call of ``commit``'s jointbench on the same trials, by
    ``(kind, method, data label)``: the commit is checked out into a temporary ``git
    worktree`` and timed in a subprocess (``benchmarks/baseline_worker.py``) whose
    ``PYTHONPATH`` is that checkout's ``src``, by the clock named ``clock`` (a key of
    :data:`CLOCKS`). NaN where it lacks the method."""
    repo = Path(__file__).resolve().parent.parent
    worker = Path(__file__).resolve().parent / "baseline_worker.py"
    with tempfile.TemporaryDirectory(prefix="jointbench-baseline-") as scratch:
        checkout = Path(scratch) / "checkout"
        git = ["git", "-C", str(repo)]
        subprocess.run(
            [*git, "worktree", "add", "--detach", "--quiet", str(checkout), commit], check=True
        )
        try:
            trials = Path(scratch) / "trials.npz"
            stacks = {
                f"{kind}|{name}|{label}|{index}": np.stack([trial[index] for trial in data.trials])
                for (kind, name, label), data in jobs.items()
                for index in range(len(data.trials[0]))
            }
            np.savez(trials, **stacks)
            env = {**os.environ, "PYTHONPATH": str(checkout / "src")}
            found = subprocess.run(
                [sys.executable, str(worker), str(trials), str(calls), CLOCKS[clock]],
                check=True,
                capture_output=True,
                text=True,
                env=env,
            )
        finally:
            subprocess.run([*git, "worktree", "remove", "--force", str(checkout)], check=True)
    timings = json.loads(found.stdout.strip().splitlines()[-1])
    if not str(timings.pop("jointbench")).startswith(str(checkout)):
        raise RuntimeError(f"the baseline worker did not import {commit}'s jointbench")
    return {tuple(key.split("|")): float(value) for key, value in timings.items()}


def _format_seconds(value: float) -> str:
    if not np.isfinite(value):
        return "—"
    if value < 1e-3:
        return f"{value * 1e6:.1f} µs"
    if value < 1.0:
        return f"{value * 1e3:.2f} ms"
    return f"{value:.2f} s"


def _labels(kind: str, name: str) -> list[str]:
    """The standard data sets a method of ``kind`` is timed on."""
    if _n_segments(kind, name) == 2:
        return ["3+3 x 1200"]
    if kind == "center":
        return ["3 x 120"]
    labels = ["3 x 121", "3 x 5000"]
    # Extra sizes only where a target asks for them (one-segment SARA: 3 x 1200).
    extra = [label for (k, n, label) in TARGETS if (k, n) == (kind, name) and label]
    return labels + [label for label in extra if label not in labels and "+" not in label]


def _target(kind: str, name: str, label: str) -> float | None:
    return TARGETS.get((kind, name, label), TARGETS.get((kind, name, None)))


#: The most the public (checked) call may cost, as a multiple of the bare estimator.
MAX_CHECK_RATIO = 1.5


def _verdict(value: float, limit: float | None, note: str = "") -> str:
    if note.startswith("error") or not np.isfinite(value):
        return "error" if note.startswith("error") else "—"
    if limit is None:
        return "—"
    return "pass" if value <= limit else "FAIL"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="few calls per method (seconds)")
    parser.add_argument(
        "--kind",
        action="append",
        choices=registry.KINDS,
        help="only this kind (repeatable); default all",
    )
    parser.add_argument(
        "--seconds", type=float, default=None, help="time budget per method and data set"
    )
    parser.add_argument("--max-calls", type=int, default=None, help="calls per method at most")
    parser.add_argument("--seed", type=int, default=20070514, help="seed of the synthetic trials")
    parser.add_argument(
        "--baseline",
        default=BASELINE_COMMIT,
        help="commit whose public call is timed beside today's (default: Nov 22's, %(default)s)",
    )
    parser.add_argument("--no-baseline", action="store_true", help="do not time the baseline")
    parser.add_argument(
        "--clock",
        choices=sorted(CLOCKS),
        default="wall",
        help="time each call by wall-clock time or by the process's CPU time (%(default)s)",
    )
    parser.add_argument(
        "--strict",
        action="store_true",
        help="exit with status 1 when a target or the checks' cost limit is missed",
    )
    args = parser.parse_args(argv)
    clock = getattr(time, CLOCKS[args.clock])
    clock_text = "wall-clock" if args.clock == "wall" else "process CPU"

    seconds = args.seconds if args.seconds is not None else (0.3 if args.quick else 3.0)
    max_calls = args.max_calls if args.max_calls is not None else (30 if args.quick else 400)
    # Fast methods reach max_calls (>= 200 in a full run) well within the budget; slow ones stop
    # at the budget but never below min_calls.
    min_calls = min(3 if args.quick else 10, max_calls)
    n_pool = 4 if args.quick else _N_TRIALS_POOL
    kinds = args.kind or list(registry.KINDS)
    rng = np.random.default_rng(args.seed)

    rows: list[tuple[str, str, str, int, float, float, float, float | None, str]] = []
    data_by_kind: dict[str, dict[str, DataSet]] = {}
    for kind in kinds:
        names = jointbench.methods(kind)
        if not names:
            print(f"<!-- kind {kind!r}: no registered methods, skipped -->")
            continue
        data_sets: dict[str, DataSet] = {}  # built once per kind and label, shared by methods
        data_by_kind[kind] = data_sets
        for name in names:
            bare = registry.get(kind, name, checked=False)
            checked = registry.get(kind, name)
            public = functools.partial(_PUBLIC[kind], method=name)
            for label in _labels(kind, name):
                if label not in data_sets:
                    data_sets[label] = build_data(kind, label, rng, n_pool)
                data = data_sets[label]
                timed = time_variants(
                    {"estimator": bare, "checked": checked, "public": public},
                    data,
                    seconds,
                    min_calls,
                    max_calls,
                    clock,
                )
                alone, held, api = timed["estimator"], timed["checked"], timed["public"]
                note = alone.note or held.note or api.note
                target = _target(kind, name, data.label)
                rows.append(
                    (
                        kind,
                        name,
                        data.label,
                        alone.calls,
                        alone.seconds,
                        held.seconds,
                        api.seconds,
                        target,
                        note,
                    )
                )

    baseline: dict[tuple[str, str, str], float] = {}
    if not args.no_baseline:
        jobs = {(kind, name, label): data_by_kind[kind][label] for kind, name, label, *_ in rows}
        calls = max(min_calls, min(max_calls, 100))
        baseline = baseline_timings(args.baseline, jobs, calls, args.clock)
    old = f"public call at {args.baseline}" if baseline else "baseline"

    print(
        f"Estimator timings: median {clock_text} seconds per call "
        f"({'quick' if args.quick else 'full'} run; Python {platform.python_version()}, "
        f"NumPy {np.__version__}, {platform.machine()}). 'estimator': the registered function "
        "alone, as a study's estimate job calls it (the target applies to it); 'checked': "
        "registry.get(kind, name), which adds the input checks, the method's self-check and the "
        "support verdict (jointbench.estimators.support), held to at most "
        f"{MAX_CHECK_RATIO}x the estimator; 'public call': fit_center / fit_axis / "
        "fit_joint_center, the checked call after the artefact screen (jointbench.screen, "
        f"artefacts='refuse'); '{old}': the public call of that commit (Nov 22's by default, "
        "before the checks and the screen), checked out in a git worktree and timed the same "
        "way in a subprocess on the same trials. The three calls of a method are timed after "
        "an untimed first call each (imports, compiling kernels), in alternating blocks of the "
        "same distinct trials ('calls' per variant), so that their ratios share the machine's "
        "load. On a shared machine only ratios within one run are comparable.\n"
    )
    print(
        "| kind | method | data (markers x frames) | calls | estimator | target | pass "
        f"| checked | checked / estimator | ≤ {MAX_CHECK_RATIO}× | public call "
        f"| public / estimator | ≤ {MAX_CHECK_RATIO}× | {old} |"
    )
    print("|---|---|---|---:|---:|---:|:---:|---:|---:|:---:|---:|---:|:---:|---:|")
    failed = False
    for kind, name, label, n_calls, median, held, api, target, note in rows:
        verdict = _verdict(median, target, note)
        ratio, public_ratio = held / median, api / median
        cheap = _verdict(ratio, MAX_CHECK_RATIO, note)
        public_cheap = _verdict(public_ratio, MAX_CHECK_RATIO, note)
        failed = failed or verdict in ("error", "FAIL") or "FAIL" in (cheap, public_cheap)
        target_text = "—" if target is None else f"≤ {_format_seconds(target)}"
        line = (
            f"| {kind} | {name} | {label} | {n_calls} | {_format_seconds(median)} | "
            f"{target_text} | {verdict} | {_format_seconds(held)} | {ratio:.2f}× | {cheap} | "
            f"{_format_seconds(api)} | {public_ratio:.2f}× | {public_cheap} | "
            f"{_format_seconds(baseline.get((kind, name, label), float('nan')))} |"
        )
        print(line + (f" {note}" if note else ""))

    one_trial = {(kind, name, label): median for kind, name, label, _, median, *_ in rows}
    print(
        f"\nMany trials at once: median over repeats of the call's {clock_text} time divided by "
        "its trials; 'estimator' is the bare many-trial form the estimate jobs run and time (the "
        "target applies to it; a method without its own is fitted trial by trial), 'checked' the "
        "registry's checked form with every trial's input checks and support verdict, the "
        "variants called in turn in every repeat; "
        "'speed-up' = one-trial estimator median above / batched estimator. The baseline had no "
        "many-trial form: its column repeats its one-trial public call.\n"
    )
    print(
        "| kind | method | data | trials per call | estimator | speed-up | target | pass "
        f"| checked | checked / estimator | ≤ {MAX_CHECK_RATIO}× | from fitted poses | {old} |"
    )
    print("|---|---|---|---:|---:|---:|---:|:---:|---:|---:|:---:|---:|---:|")
    # Per data set, the largest batch a pose-based method was timed with, and its repeats.
    pose_labels: dict[tuple[str, str], tuple[int, int]] = {}
    for kind, name, label in one_trial:
        target = BATCHED_TARGETS.get((kind, name, label))
        n_trials = _BATCH_SIZE.get(label, 8) if target else 8
        n_trials = max(4, n_trials // (8 if args.quick else 1))
        repeats = 3 if args.quick or target is None else 7
        data = data_by_kind[kind][label]
        timed = time_batched(kind, name, data, n_trials, repeats, clock)
        per_trial, note = timed["estimator"]
        checked, checked_note = timed["checked"]
        posed, _ = timed.get("from fitted poses", (float("nan"), ""))
        if np.isfinite(posed):
            pose_labels[(kind, label)] = max(
                pose_labels.get((kind, label), (0, 0)), (n_trials, repeats)
            )
        verdict = _verdict(per_trial, target, note)
        ratio = checked / per_trial
        cheap = _verdict(ratio, MAX_CHECK_RATIO, note or checked_note)
        failed = failed or verdict in ("error", "FAIL") or cheap == "FAIL"
        target_text = "—" if target is None else f"≤ {_format_seconds(target)}"
        print(
            f"| {kind} | {name} | {label} | {n_trials} | {_format_seconds(per_trial)} | "
            f"{one_trial[(kind, name, label)] / per_trial:.1f}× | {target_text} | {verdict} | "
            f"{_format_seconds(checked)} | {ratio:.2f}× | {cheap} | {_format_seconds(posed)} | "
            f"{_format_seconds(baseline.get((kind, name, label), float('nan')))} |"
            + (f" {note}" if note else "")
        )
    if pose_labels:
        print(
            "\n'from fitted poses': the bare batched form given every trial's poses fitted "
            "beforehand, as the hip study's estimate jobs read them from its poses job. That fit, "
            "shared by every pose-based method, costs per trial:\n"
        )
        for (kind, label), (n_trials, repeats) in sorted(pose_labels.items()):
            seconds_per_trial = time_pose_fit(data_by_kind[kind][label], n_trials, repeats, clock)
            print(f"- {kind}, {label}: {_format_seconds(seconds_per_trial)} (both segments' poses)")
    return 1 if failed and args.strict else 0


if __name__ == "__main__":
    sys.exit(main())
