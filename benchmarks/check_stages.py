"""Where the time of a checked one-trial centre call goes, stage by stage, and the least any
implementation of the same checks could cost: their compiled kernels alone.

Usage::

    python benchmarks/check_stages.py [--methods LS NM BC] [--calls 400] [--clock {cpu,wall}]

On ``estimators.py``'s centre trials (3 markers x 120 frames, 1 mm noise), per method, the
median time per call, by wall clock (the default) or, ``--clock cpu``, by the process's CPU
time, which other processes' load on a shared machine does not lengthen, of:

* ``estimator``: the registered function alone (what ``checked / estimator`` divides by);
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
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from jointbench.estimators import centre_precision, registry, support, validation
from jointbench.numerics.compiled import kernel_array

sys.path.insert(0, str(Path(__file__).resolve().parent))
from estimators import CLOCKS, Clock, center_data

STAGES = (
    "estimator",
    "checked",
    "input checks",
    "verdict",
    "verdict kernels",
    "precision",
    "precision kernel",
)


def _verdict_kernels(markers: np.ndarray) -> None:
    """The compiled work of the one-segment verdict on ``markers`` ``(1, N, n, 3)`` [mm]: one
    call, which gives the lag-1 statement's numbers too."""
    support._one_segment_numbers(markers, support._FLEX)


def stage_calls(method: str, trials: list[np.ndarray]) -> dict[str, Callable[[int], object]]:
    """Per stage of :data:`STAGES`, a call of it on trial ``i`` of ``trials`` ``(N, n, 3)``."""
    bare = registry.get("center", method, checked=False)
    checked = registry.get("center", method)
    stacked = [trial[None] for trial in trials]
    ready = [kernel_array(trial) for trial in stacked]
    results = [bare(trial) for trial in trials]
    verdicts = [support.assess_many("center", (trial,)) for trial in stacked]
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
    parser.add_argument("--methods", nargs="+", default=["LS", "NM", "BC"])
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
    trials = [trial for (trial,) in center_data(np.random.default_rng(0), n_trials).trials]
    header = [*STAGES, "checked / estimator", "floor / estimator"]
    print(
        f"Median {clock_text} µs per call, 3 markers x 120 frames, 1 mm noise "
        "(see the script's doc).\n"
    )
    print("| method | " + " | ".join(header) + " |")
    print("|---|" + "---:|" * len(header))
    for method in args.methods:
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


if __name__ == "__main__":
    raise SystemExit(main())
