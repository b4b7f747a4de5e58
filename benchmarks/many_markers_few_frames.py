"""What a checked call costs on many markers over few frames: a large cluster, or a recording
passed as ``(markers, frames, 3)``.

::

    python benchmarks/many_markers_few_frames.py [--markers 2000 5000 10000] [--frames 5]
        [--calls LS NM BC MA IS planar radial combined SARA SCoRE analytic gauss-markov
        gauss-markov-frame0 screen]
        [--trees SRC ...] [--timeout 300]

Per marker count and call, the CPU time [s] (the process's own, which other processes' load on
a shared machine does not lengthen) and the peak resident memory [MB] of the process during one
call (Linux's ``VmHWM``, reset before the call, so that the kernels' compilation does not count;
elsewhere the process's peak), each in a process of its own after a small call (30 markers)
that loads the compiled kernels:

* ``LS``, ``NM``, ``BC``, ``MA``, ``IS``: :func:`jointbench.fit_center` with
  ``artefacts="warn"``;
* ``planar``, ``radial``, ``combined``, ``SARA``: :func:`jointbench.fit_axis` with
  ``artefacts="warn"``;
* ``SCoRE``, ``analytic``, ``gauss-markov``, ``gauss-markov-frame0``:
  :func:`jointbench.fit_joint_center` with ``artefacts="warn"`` on two clusters of that many
  markers each;
* ``screen``: :func:`jointbench.screen` of the one cluster.

The clusters are :func:`screen_large_clusters.cluster`'s (a rigid cluster turning about three
axes, 0.3 mm noise). ``--trees`` names source trees (each put first on ``PYTHONPATH``): every
case runs once per tree, one after the other, so a before/after comparison shares the load of
the moment. A call past ``--timeout`` seconds of wall time is reported as ``>`` that.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

from screen_large_clusters import cluster

import jointbench

JOINT_CENTRES = ("SCoRE", "analytic", "gauss-markov", "gauss-markov-frame0")
CENTRES = ("LS", "NM", "BC", "MA", "IS")
AXES = ("planar", "radial", "combined", "SARA")
CALLS = (*CENTRES, *AXES, *JOINT_CENTRES, "screen")


def _call(name: str, n_markers: int, n_frames: int):
    """The call ``name`` on clusters of ``n_markers`` over ``n_frames``, as a function of no
    arguments."""
    markers = cluster(n_markers, n_frames)
    if name == "screen":
        return lambda: jointbench.screen(markers)
    if name in AXES:
        return lambda: jointbench.fit_axis(markers, name, artefacts="warn")
    if name in JOINT_CENTRES:
        distal = cluster(n_markers, n_frames, seed=1)
        return lambda: jointbench.fit_joint_center(markers, distal, name, artefacts="warn")
    return lambda: jointbench.fit_center(markers, name, artefacts="warn")


def _one(name: str, n_markers: int, n_frames: int) -> None:
    """Print the CPU time [s] and the peak resident memory [MB] of one call, after a small one
    that takes the same paths (more markers than frames, and than the verdict's rigidity test
    compares)."""
    _call(name, 30, n_frames)()
    run = _call(name, n_markers, n_frames)
    resettable = os.access("/proc/self/clear_refs", os.W_OK)
    if resettable:
        # The call's own peak, not the kernels' compilation before it.
        with open("/proc/self/clear_refs", "w") as peak:
            peak.write("5")
    start = time.process_time()
    run()
    cpu = time.process_time() - start
    if resettable:
        peak_mb = _status_kb("VmHWM:") / 1024.0
    else:
        peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(f"{cpu:.3f} {peak_mb:.0f}")


def _status_kb(key: str) -> int:
    """The line ``key`` of Linux's ``/proc/self/status`` [kB]."""
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) for line in status if line.startswith(key))


def _measured(tree: str | None, name: str, n_markers: int, n_frames: int, timeout: float) -> str:
    """The cell of one call in a process of its own, its source tree ``tree`` first on the
    path: ``CPU s / MB``."""
    env = dict(os.environ)
    if tree is not None:
        env["PYTHONPATH"] = os.pathsep.join([tree, str(Path(__file__).parent)])
    command = [sys.executable, __file__, "--one", name, str(n_markers), str(n_frames)]
    try:
        done = subprocess.run(
            command, env=env, capture_output=True, text=True, timeout=timeout, check=True
        )
    except subprocess.TimeoutExpired:
        return f"> {timeout:.0f} s wall"
    except subprocess.CalledProcessError as error:
        return f"failed: {error.stderr.strip().splitlines()[-1]}"
    cpu, peak = done.stdout.split()
    return f"{cpu} s / {peak} MB"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--markers", type=int, nargs="+", default=[2000, 5000, 10000])
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--calls", nargs="+", choices=CALLS, default=list(CALLS))
    parser.add_argument("--trees", nargs="+", default=[None])
    parser.add_argument("--timeout", type=float, default=300.0)
    parser.add_argument("--one", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        name, n_markers, n_frames = args.one
        _one(name, int(n_markers), int(n_frames))
        return
    trees = [tree or "installed" for tree in args.trees]
    print(f"{args.frames} frames; CPU time and peak memory of one call per cell")
    print(f"| markers | call | {' | '.join(trees)} |")
    print(f"|---|---|{'---|' * len(trees)}")
    for n_markers in args.markers:
        for name in args.calls:
            cells = [
                _measured(tree, name, n_markers, args.frames, args.timeout) for tree in args.trees
            ]
            print(f"| {n_markers} | {name} | {' | '.join(cells)} |", flush=True)


if __name__ == "__main__":
    main()
