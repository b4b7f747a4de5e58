"""Where the time of a checked one-trial centre or joint-centre call goes, stage by stage, and
for a centre the least any implementation of the same checks could cost: their compiled kernels
alone.

Usage::

    python benchmarks/check_stages.py [--methods LS NM BC] [--calls 400] [--clock {cpu,wall}]
    python benchmarks/check_stages.py --kind joint_center [--methods SCoRE analytic]

On ``estimators.py``'s centre trials (3 markers x 120 frames, 1 mm noise), per method, the
median time per call, by wall clock (the default) or, ``--clock cpu``, by the process's CPU
time, which other processes' load on a shared machine does not lengthen, of:

* ``estimator``: the registered function alone (what ``checked / estimator`` divides by),
  its own checks of its markers included, which inside the checked call it does not repeat
  over the arrays the input checks passed (:func:`jointbench.estimators.validation.passed`);
* ``checked``: ``registry.get("center", method)``, every stage below and the plumbing between;
* ``input checks``: :func:`jointbench.estimators.validation.check_input`;
* ``verdict``: :func:`jointbench.estimators.support.assess_many` on the trial, of which
  ``verdict kernels`` is its compiled work alone (the rigidity and rotation tests, the frames'
  dependence, the lag-1 correlation and its SD);
* ``precision``: :func:`jointbench.estimators.centre_precision.annotate_many` on the method's
  answer and the verdict, of which ``precision kernel`` is
  :func:`jointbench.estimators.centre_precision.centre_statistics` alone.

The last column, ``floor / estimator``, is (estimator + input checks + verdict kernels +
precision kernel) / estimator: the ratio a checked call would have if nothing but the fit, the
input checks and the compiled arithmetic of the checks ran, no Python between them. Where it is
above 1.5 no rearrangement of the checks' Python reaches a checked call within 1.5 times the
fit; only cheaper arithmetic, or fewer checks, would.

With ``--kind joint_center``, on ``estimators.py``'s joint-centre trials (3 + 3 markers x 1200
frames, a ball joint, 0.5 mm noise), per method (by default every registered one), the same
medians of (:data:`JOINT_STAGES`):

* ``estimator``, ``checked`` and ``public``: the registered function alone, ``registry.get``
  and :func:`jointbench.fit_joint_center` (the checked call after the artefact screen);
* ``input checks``: :func:`jointbench.estimators.validation.check_input`;
* ``poses``: both segments' poses as the checked call fits them once for the fit and the
  verdict (``segment_poses._trial_poses``, the samples checked, as the checked call fits them);
* ``fit on poses``: the method's many-trial form on those poses, a batch of one;
* ``verdict``: :func:`jointbench.estimators.support.assess_many` on those poses;
* ``precision``: the method's ``precision_many`` on its answer and those poses (the model
  tests, :mod:`jointbench.estimators.hjc`), in one call's scope
  (:func:`jointbench.numerics.reuse.one_call`) as the checked call runs it;
* ``answers``: :func:`jointbench.estimators.centre_precision.annotate_joint_centres`;
* ``screen``: ``screening._find_artefacts`` of both segments (the artefact screen trusting
  the magnitudes the input checks passed), what the public call adds.

``checked`` less the stages from ``input checks`` to ``answers`` is the plumbing between them.

With ``--kind axis``, on ``estimators.py``'s axis trials (3 markers x ``--frames`` frames, 5000
by default, a near-hinge, 1 mm noise), per one-segment method (by default ``planar``), the same
medians of (:data:`AXIS_STAGES`):

* ``estimator``, ``checked`` and ``public``: the registered function alone, ``registry.get``
  and :func:`jointbench.fit_axis` (the checked call after the artefact screen);
* ``input checks``: :func:`jointbench.estimators.validation.check_input`;
* ``verdict``: :func:`jointbench.estimators.support.assess_many` on the trial, of which
  ``verdict kernels`` is its compiled work alone: the one-segment pass (the rigidity, rotation
  and hinge tests, the frames' dependence, the noise's directions) and the motion's own axis
  (the sampled frames' rotations, the markers' arcs);
* ``self-check``: the method's ``self_check`` on its answer, in one call's scope holding the
  scatter ``S`` that the checked call's fit formed (:func:`jointbench.numerics.reuse.one_call`);
* ``precision``: its ``precision_many`` on the answer and the verdict, likewise, of which
  ``precision kernels`` is its compiled passes over the frames alone (whether two frames are
  equal, the planar residuals' fourth powers);
* ``answers``: :func:`jointbench.estimators.precision.annotate_motion_axis` and
  :func:`jointbench.estimators.support.annotate`;
* ``screen``: ``screening._find_artefacts`` of the markers, what the public call adds.

The last column, ``floor / estimator``, is (estimator + input checks + verdict kernels +
precision kernels + screen) / estimator: the public call's ratio if nothing but the fit and the
compiled passes over the frames ran (the screen of a clean cluster being one compiled call),
no Python between them. The radial cost's derivatives are NumPy arrays, not counted there.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

import numpy as np

import jointbench
from jointbench import screening
from jointbench.estimators import axis, centre_precision, precision, registry, support, validation
from jointbench.estimators.batching import one_trial
from jointbench.estimators.segment_poses import POSE_MIN_FRAMES, _trial_poses, pose_segments
from jointbench.numerics import reuse
from jointbench.numerics.compiled import kernel_array

sys.path.insert(0, str(Path(__file__).resolve().parent))
from estimators import CLOCKS, Clock, axis_data, center_data, two_segment_data

STAGES = (
    "estimator",
    "checked",
    "input checks",
    "verdict",
    "verdict kernels",
    "precision",
    "precision kernel",
)


#: The stages of a checked joint-centre call (module docstring).
JOINT_STAGES = (
    "estimator",
    "checked",
    "public",
    "input checks",
    "poses",
    "fit on poses",
    "verdict",
    "precision",
    "answers",
    "screen",
)


#: The stages of a checked one-segment axis call (module docstring).
AXIS_STAGES = (
    "estimator",
    "checked",
    "public",
    "input checks",
    "verdict",
    "verdict kernels",
    "self-check",
    "precision",
    "precision kernels",
    "answers",
    "screen",
)


def _verdict_kernels(markers: np.ndarray) -> None:
    """The compiled work of the one-segment verdict on ``markers`` ``(1, N, n, 3)`` [mm]: one
    call, which gives the lag-1 statement's numbers too."""
    support._one_segment_numbers(markers, support._FLEX)


class _OneSegment(NamedTuple):
    """What the stages of a checked one-segment call read, per trial of ``trials``
    ``(N, n, 3)`` [mm] (:func:`_one_segment`)."""

    bare: Callable  # the registered function
    checked: Callable  # registry.get's checked form
    stacked: list[np.ndarray]  # each trial as a batch of one, (1, N, n, 3)
    ready: list[np.ndarray]  # those as a kernel takes them
    results: list  # the registered function's answers
    verdicts: list[list]  # the support verdict of each, a list of one


def _one_segment(kind: str, method: str, trials: list[np.ndarray]) -> _OneSegment:
    """:class:`_OneSegment` of the ``kind`` method ``method`` on ``trials``."""
    bare = registry.get(kind, method, checked=False)
    stacked = [trial[None] for trial in trials]
    return _OneSegment(
        bare,
        registry.get(kind, method),
        stacked,
        [kernel_array(trial) for trial in stacked],
        [bare(trial) for trial in trials],
        [support.assess_many(kind, (trial,)) for trial in stacked],
    )


def stage_calls(method: str, trials: list[np.ndarray]) -> dict[str, Callable[[int], object]]:
    """Per stage of :data:`STAGES`, a call of it on trial ``i`` of ``trials`` ``(N, n, 3)``."""
    bare, checked, stacked, ready, results, verdicts = _one_segment("center", method, trials)
    centres = [result.center[None] for result in results]
    variances = [
        np.array([verdict[0].diagnostics["rigid_residual_mm"] ** 2 / 3.0]) for verdict in verdicts
    ]
    return {
        "estimator": lambda i: bare(trials[i]),
        "checked": lambda i: checked(trials[i]),
        "input checks": lambda i: validation.check_input("center", (trials[i],)),
        "verdict": lambda i: support.assess_many("center", (stacked[i],)),
        "verdict kernels": lambda i: _verdict_kernels(ready[i]),
        "precision": lambda i: centre_precision.annotate_many(
            [results[i]], stacked[i], verdicts[i]
        ),
        "precision kernel": lambda i: centre_precision.centre_statistics(
            ready[i], centres[i], variances[i]
        ),
    }


def _axis_verdict_kernels(markers: np.ndarray) -> None:
    """The compiled work of the one-segment verdict on an axis's ``markers`` ``(1, N, n, 3)``
    [mm]: its pass over the frames, then the motion's own axis from the sampled frames'
    rotations and the markers' arcs (``support._one_segment_axes``'s kernels)."""
    numbers = support._one_segment_numbers(markers, support._FLEX)
    variance = kernel_array(numbers[:, 0])
    central = kernel_array(numbers[:, support._CENTRAL_FRAME])
    step = support._frame_step(markers.shape[1])
    found = support._sampled_axis_numbers(markers, step, variance, central)
    support._arc_rotation_sd_deg(markers, variance, found[-2], found[-1])


def _axis_precision_kernels(markers: np.ndarray, direction: np.ndarray) -> None:
    """The compiled passes over the frames of an axis's statement of precision on ``markers``
    ``(N, n, 3)`` [mm] at ``direction`` (3,): whether two frames are equal, and the planar
    residuals' fourth powers."""
    precision._rows_all_differ(markers.reshape(len(markers), -1))
    axis._height_fourths(markers, direction)


#: The name under which :func:`jointbench.estimators.axis.trial_scatter` keeps paper B's ``S``
#: in one call's scope.
_SCATTER = "planar scatter"


def _formed_by_the_fit(markers: np.ndarray, scatter: np.ndarray) -> None:
    """Hold ``scatter``, the ``S`` ``(3, 3)`` [mm^2] of ``markers`` ``(N, n, 3)``, in the open
    scope of one call, as a checked call's fit leaves it for the checks after it, so that a
    stage's time is its own and not that of forming ``S`` again."""
    reuse.remembered(_SCATTER, markers, lambda _: scatter)


def axis_stage_calls(method: str, trials: list[np.ndarray]) -> dict[str, Callable[[int], object]]:
    """Per stage of :data:`AXIS_STAGES`, a call of it on trial ``i`` of ``trials``
    ``(N, n, 3)`` [mm] by the one-segment axis method ``method``."""
    bare, checked, stacked, ready, results, verdicts = _one_segment("axis", method, trials)
    directions = [kernel_array(np.asarray(result.direction)) for result in results]
    scatters = [axis.trial_scatter(trial) for trial in trials]
    labels = tuple(f"markers[:, {column}]" for column in range(trials[0].shape[1]))

    def self_check(i: int) -> object:
        with reuse.one_call():
            _formed_by_the_fit(trials[i], scatters[i])
            return bare.self_check(results[i], trials[i])

    def precision_stage(i: int) -> object:
        with reuse.one_call():
            _formed_by_the_fit(trials[i], scatters[i])
            return bare.precision_many([results[i]], stacked[i], verdicts=verdicts[i])

    def answers(i: int) -> object:
        (verdict,) = verdicts[i]
        reason = verdict.diagnostics.get("reason", "")
        checked_answer = precision.annotate_motion_axis(
            results[i],
            verdict.motion_axis,
            reason,
            verdict.diagnostics.get("off_axis_p_value", math.nan),
        )
        return support.annotate(checked_answer, verdict)

    return {
        "estimator": lambda i: bare(trials[i]),
        "checked": lambda i: checked(trials[i]),
        "public": lambda i: jointbench.fit_axis(trials[i], method=method),
        "input checks": lambda i: validation.check_input("axis", (trials[i],)),
        "verdict": lambda i: support.assess_many("axis", (stacked[i],)),
        "verdict kernels": lambda i: _axis_verdict_kernels(ready[i]),
        "self-check": self_check,
        "precision": precision_stage,
        "precision kernels": lambda i: _axis_precision_kernels(ready[i][0], directions[i]),
        "answers": answers,
        "screen": lambda i: screening._find_artefacts(trials[i], labels, "markers"),
    }


def joint_stage_calls(
    method: str, trials: list[tuple[np.ndarray, np.ndarray]]
) -> dict[str, Callable[[int], object]]:
    """Per stage of :data:`JOINT_STAGES`, a call of it on trial ``i`` of ``trials`` (proximal
    and distal markers ``(N, n, 3)`` each)."""
    bare = registry.get("joint_center", method, checked=False)
    checked = registry.get("joint_center", method)
    many = registry.many("joint_center", method, checked=False)
    names = pose_segments(many) or ("proximal", "distal")
    stacked = [tuple(array[None] for array in trial) for trial in trials]
    poses = [
        _trial_poses(
            {name: [array] for name, array in zip(names, trial, strict=True)},
            min_frames=POSE_MIN_FRAMES,
            samples_checked=True,
        )
        for trial in trials
    ]
    results = [
        [one_trial(many, *trial, poses=fitted)] for trial, fitted in zip(trials, poses, strict=True)
    ]
    verdicts = [
        support.assess_many("joint_center", arrays, poses=fitted)
        for arrays, fitted in zip(stacked, poses, strict=True)
    ]
    labels = {
        name: tuple(f"{name}[:, {column}]" for column in range(trials[0][index].shape[1]))
        for index, name in enumerate(("proximal", "distal"))
    }

    def precision(i: int) -> object:
        with reuse.one_call():
            return bare.precision_many(
                results[i], *stacked[i], verdicts=verdicts[i], poses=poses[i]
            )

    def screen(i: int) -> None:
        for (name, names_), markers in zip(labels.items(), trials[i], strict=True):
            screening._find_artefacts(markers, names_, name)

    return {
        "estimator": lambda i: bare(*trials[i]),
        "checked": lambda i: checked(*trials[i]),
        "public": lambda i: jointbench.fit_joint_center(*trials[i], method=method),
        "input checks": lambda i: validation.check_input("joint_center", trials[i]),
        "poses": lambda i: _trial_poses(
            {name: [array] for name, array in zip(names, trials[i], strict=True)},
            min_frames=POSE_MIN_FRAMES,
            samples_checked=True,
        ),
        "fit on poses": lambda i: one_trial(many, *trials[i], poses=poses[i]),
        "verdict": lambda i: support.assess_many("joint_center", stacked[i], poses=poses[i]),
        "precision": precision,
        "answers": lambda i: centre_precision.annotate_joint_centres(results[i], verdicts[i]),
        "screen": screen,
    }


def time_stages(
    calls: dict[str, Callable[[int], object]],
    n_trials: int,
    rounds: int,
    clock: Clock = time.perf_counter,
) -> dict:
    """Median seconds by ``clock`` per call of each of ``calls`` over ``rounds`` rounds of
    ``n_trials`` calls, the stages taking turns round by round so that they share the
    machine's load."""
    for call in calls.values():
        call(0)  # compiles the kernels and fills the caches before the clock starts
    times: dict[str, list[float]] = {name: [] for name in calls}
    for _ in range(rounds):
        for name, call in calls.items():
            start = clock()
            for i in range(n_trials):
                call(i)
            times[name].append((clock() - start) / n_trials)
    return {name: statistics.median(values) for name, values in times.items()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--kind", choices=["center", "axis", "joint_center"], default="center")
    parser.add_argument(
        "--methods",
        nargs="+",
        help="(default: LS NM BC; planar for axis; every method for joint_center)",
    )
    parser.add_argument(
        "--frames", type=int, default=5000, help="frames of the axis trials (%(default)s)"
    )
    parser.add_argument("--calls", type=int, default=400, help="calls per stage in all")
    parser.add_argument(
        "--clock",
        choices=sorted(CLOCKS),
        default="wall",
        help="time the calls by wall-clock time or by the process's CPU time (%(default)s)",
    )
    args = parser.parse_args(argv)
    clock = getattr(time, CLOCKS[args.clock])
    clock_text = "wall-clock" if args.clock == "wall" else "process CPU"
    n_trials = min(40, args.calls)
    rounds = max(1, args.calls // n_trials)
    if args.kind == "joint_center":
        methods = args.methods or registry.methods("joint_center")
        print(
            f"Median {clock_text} µs per call, 3 + 3 markers x 1200 frames, a ball joint, "
            "0.5 mm noise (see the script's doc).\n"
        )
        return _joint_table(methods, n_trials, rounds, clock)
    if args.kind == "axis":
        print(
            f"Median {clock_text} µs per call, 3 markers x {args.frames} frames, a near-hinge, "
            "1 mm noise (see the script's doc).\n"
        )
        return _axis_table(args.methods or ["planar"], args.frames, n_trials, rounds, clock)
    trials = [trial for (trial,) in center_data(np.random.default_rng(0), n_trials).trials]
    header = [*STAGES, "checked / estimator", "floor / estimator"]
    print(
        f"Median {clock_text} µs per call, 3 markers x 120 frames, 1 mm noise "
        "(see the script's doc).\n"
    )
    print("| method | " + " | ".join(header) + " |")
    print("|---|" + "---:|" * len(header))
    for method in args.methods or ["LS", "NM", "BC"]:
        median = time_stages(stage_calls(method, trials), n_trials, rounds, clock)
        floor = sum(
            median[name]
            for name in ("estimator", "input checks", "verdict kernels", "precision kernel")
        )
        cells = [f"{1e6 * median[name]:.1f}" for name in STAGES]
        cells += [
            f"{median['checked'] / median['estimator']:.2f}×",
            f"{floor / median['estimator']:.2f}×",
        ]
        print(f"| {method} | " + " | ".join(cells) + " |")
    return 0


def _axis_table(methods: list[str], n_frames: int, n_trials: int, rounds: int, clock: Clock) -> int:
    """Print the axis stages' table (module docstring) of ``methods`` on ``n_frames`` frames."""
    trials = [trial for (trial,) in axis_data(np.random.default_rng(0), n_trials, n_frames).trials]
    header = [*AXIS_STAGES, "checked / estimator", "public / estimator", "floor / estimator"]
    print(f"| method | {' | '.join(header)} |")
    print("|---|" + "---:|" * len(header))
    floor_stages = ("estimator", "input checks", "verdict kernels", "precision kernels", "screen")
    for method in methods:
        median = time_stages(axis_stage_calls(method, trials), n_trials, rounds, clock)
        cells = [f"{1e6 * median[name]:.1f}" for name in AXIS_STAGES]
        cells += [f"{median[name] / median['estimator']:.2f}×" for name in ("checked", "public")]
        floor = sum(median[name] for name in floor_stages)
        cells.append(f"{floor / median['estimator']:.2f}×")
        print(f"| {method} | " + " | ".join(cells) + " |")
    return 0


def _joint_table(methods: list[str], n_trials: int, rounds: int, clock: Clock) -> int:
    """Print the joint-centre stages' table (module docstring) of ``methods``."""
    rng = np.random.default_rng(0)
    trials = two_segment_data(rng, n_trials, "joint_center", "ball").trials
    header = [*JOINT_STAGES, "checked / estimator", "public / estimator"]
    print(f"| method | {' | '.join(header)} |")
    print("|---|" + "---:|" * len(header))
    for method in methods:
        median = time_stages(joint_stage_calls(method, trials), n_trials, rounds, clock)
        cells = [f"{1e6 * median[name]:.1f}" for name in JOINT_STAGES]
        cells += [f"{median[name] / median['estimator']:.2f}×" for name in ("checked", "public")]
        print(f"| {method} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
