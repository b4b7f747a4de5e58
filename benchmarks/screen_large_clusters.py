"""How long the artefact screen takes as a cluster grows, and what it leaves untested.

::

    python benchmarks/screen_large_clusters.py [--markers 8 20 40 120] [--frames 120 1000]

For each cluster (a rigid cluster of markers about 60 mm apart, turning about three axes, with
0.3 mm noise), the wall time of :func:`jointbench.screening.find_artefacts` (what the public fits
run) and of the whole :func:`jointbench.screening.screen`, the best of ``--repeat`` runs after
one that compiles the kernels, and whether the label-exchange test ran (at most
:data:`jointbench.screening.MAX_EXCHANGE_MARKERS` markers) or was skipped.
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np

from jointbench.geometry import rotation_matrix
from jointbench.screening import MAX_EXCHANGE_MARKERS, exchanges_untested, find_artefacts, screen


def cluster(n_markers: int, n_frames: int, seed: int = 0) -> np.ndarray:
    """Markers ``(n_frames, n_markers, 3)`` [mm] of a noisy rigid cluster turning about three
    axes."""
    rng = np.random.default_rng(seed)
    body = rng.normal(scale=60.0, size=(n_markers, 3))
    t = np.linspace(0.0, 2.0 * np.pi, n_frames)
    rotvec = np.stack([0.5 * np.cos(t), 0.5 * np.sin(2.0 * t), 0.25 * np.sin(t)], -1)
    markers = np.einsum("fij,mj->fmi", rotation_matrix(rotvec), body)
    return markers + rng.normal(scale=0.3, size=markers.shape)


def best_time(run: Callable[..., object], arguments: tuple, repeat: int) -> float:
    """The least wall time [s] of ``repeat`` calls of ``run(*arguments)``."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        run(*arguments)
        times.append(time.perf_counter() - start)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--markers", type=int, nargs="+", default=[8, 20, 40, 120])
    parser.add_argument("--frames", type=int, nargs="+", default=[120, 1000])
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    warm = cluster(4, 30)
    find_artefacts(warm, ("a", "b", "c", "d"), "warm-up")
    screen(warm, ("a", "b", "c", "d"), "warm-up")
    print(f"exchange test up to {MAX_EXCHANGE_MARKERS} markers")
    print("| markers | frames | find_artefacts [s] | screen [s] | exchange test |")
    print("|---|---|---|---|---|")
    for n_markers in args.markers:
        labels = tuple(f"m{column}" for column in range(n_markers))
        for n_frames in args.frames:
            markers = cluster(n_markers, n_frames)
            fast = best_time(find_artefacts, (markers, labels, "bench"), args.repeat)
            whole = best_time(screen, (markers, labels, "bench"), args.repeat)
            ran = "skipped" if exchanges_untested(n_markers) else "run"
            print(f"| {n_markers} | {n_frames} | {fast:.4f} | {whole:.4f} | {ran} |", flush=True)


if __name__ == "__main__":
    main()
