"""Time the public calls of another checkout of jointbench on given trials (a worker of
``benchmarks/estimators.py``, run in a subprocess whose ``PYTHONPATH`` is that checkout's
``src``).

Usage::

    PYTHONPATH=<checkout>/src python benchmarks/baseline_worker.py TRIALS.npz CALLS [CLOCK]

``TRIALS.npz`` holds, per data set ``<kind>|<method>|<label>``, the marker arrays
``<key>|<argument index>`` stacked over trials. Each method is timed as the benchmark times
today's: one untimed warm-up call, then ``CALLS`` calls cycling through the trials, the median
time per call by ``CLOCK``, the name of a function of :mod:`time` (``perf_counter``, wall-clock
time, by default). Prints one JSON object ``{key: seconds}`` (NaN where the checkout
does not have the method or the call fails). Uses only the public API, which every version
has.
"""

from __future__ import annotations

import json
import statistics
import sys
import time

import numpy as np

import jointbench

_PUBLIC = {
    "center": jointbench.fit_center,
    "axis": jointbench.fit_axis,
    "joint_center": jointbench.fit_joint_center,
}


def _median_call(fit, trials: list[tuple[np.ndarray, ...]], calls: int, clock) -> float:
    fit(*trials[0])
    timings = []
    for call in range(calls):
        trial = trials[call % len(trials)]
        start = clock()
        fit(*trial)
        timings.append(clock() - start)
    return statistics.median(timings)


def main(path: str, calls: int, clock: str = "perf_counter") -> dict[str, float]:
    stored = np.load(path)
    keys = sorted({name.rsplit("|", 1)[0] for name in stored.files})
    timings: dict[str, float] = {}
    for key in keys:
        kind, method, _ = key.split("|")
        n_arguments = len([name for name in stored.files if name.rsplit("|", 1)[0] == key])
        stacks = [stored[f"{key}|{index}"] for index in range(n_arguments)]
        trials = list(zip(*stacks, strict=True))
        if method not in jointbench.methods(kind):
            timings[key] = float("nan")
            continue

        def fit(*arrays, kind=kind, method=method):
            return _PUBLIC[kind](*arrays, method=method)

        try:
            timings[key] = _median_call(fit, trials, calls, getattr(time, clock))
        except Exception:  # an old version's failure is a missing number, not a crash
            timings[key] = float("nan")
    return timings


if __name__ == "__main__":
    print(
        json.dumps(
            {
                "jointbench": jointbench.__file__,
                **main(sys.argv[1], int(sys.argv[2]), *sys.argv[3:4]),
            }
        )
    )
