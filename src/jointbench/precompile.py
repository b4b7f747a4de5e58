"""Every estimator's compiled kernels, compiled once, before anything needs them.

The kernels (:mod:`jointbench.numerics.compiled`) compile on their first call and are cached
beside their source, so the first checked fit of a fresh install compiles the support verdict's,
the screen's and the precision checks' kernels: minutes of one core, paid by whatever calls
first — one user's fit, or every job of a cluster run started at once, each compiling the same
kernels for itself. :func:`precompile` pays it up front (``jointbench precompile``): it fits one
small synthetic trial per built-in method of every kind, checked (the public call, screening
included) and unchecked, one trial and a batch of two, so the kernels of each path are in the
cache; a later process loads them. The trials are made to be fitted without a warning (a
swing about a fixed point, a hinge, two segments meeting at a ball joint), so the fits take the
paths an answer that holds takes.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.spatial.transform import Rotation

from jointbench import api
from jointbench.estimators import registry

#: Frames of each synthetic trial: enough for every check the support verdict runs.
N_FRAMES = 120
#: Noise SD [mm] of the synthetic markers: a laboratory's order, so no check reads the trial as
#: noise-free or as too noisy to decide.
NOISE_MM = 0.5


def _cluster(rng: np.random.Generator, centre: tuple[float, float, float]) -> np.ndarray:
    """Four markers [mm], shape (4, 3), spread about 40 mm around ``centre``."""
    return rng.normal(scale=40.0, size=(4, 3)) + np.asarray(centre)


def _moved(cluster: np.ndarray, rotation_vectors: np.ndarray, rng) -> np.ndarray:
    """``cluster`` (M, 3) turned by each of ``rotation_vectors`` (F, 3) [rad] about the origin,
    with noise: shape (F, M, 3) [mm]."""
    turned = np.einsum("fij,mj->fmi", Rotation.from_rotvec(rotation_vectors).as_matrix(), cluster)
    return turned + rng.normal(scale=NOISE_MM, size=turned.shape)


def synthetic_trials(seed: int = 0) -> dict[str, tuple[np.ndarray, ...]]:
    """One trial per kind, as its estimators take it: ``"center"`` and ``"axis"`` a moving
    segment's markers (F, 4, 3) [mm] swinging about the origin (two axes) and about the z axis;
    ``"joint_center"`` a still proximal and a swinging distal segment (F, 4, 3) each."""
    rng = np.random.default_rng(seed)
    phase = np.linspace(0.0, 1.0, N_FRAMES)
    swing = 0.4 * np.column_stack([np.sin(6.0 * phase), np.cos(4.0 * phase), 0.6 * phase - 0.3])
    hinge = np.outer(1.2 * phase, [0.0, 0.0, 1.0])
    distal = _moved(_cluster(rng, (100.0, 0.0, 0.0)), swing, rng)
    proximal = _moved(_cluster(rng, (0.0, 0.0, -100.0)), np.zeros_like(swing), rng)
    return {
        "center": (distal,),
        "axis": (_moved(_cluster(rng, (100.0, 0.0, 0.0)), hinge, rng),),
        "joint_center": (proximal, distal),
    }


#: The public one-trial call of each kind, checks and screen included.
_PUBLIC_FIT = {
    "center": api.fit_center,
    "axis": api.fit_axis,
    "joint_center": api.fit_joint_center,
}


def precompile(kinds: tuple[str, ...] = registry.KINDS) -> list[tuple[str, str, float]]:
    """Fit every registered method of ``kinds`` (the built-in ones, in a process that loaded no
    extension) on :func:`synthetic_trials` by each path (module
    doc); returns ``(kind, method, seconds)`` per method, its paths' wall time [s]."""
    trials = synthetic_trials()
    timings = []
    for kind in kinds:
        arrays = trials[kind]
        batch = tuple(np.stack([a, a]) for a in arrays)
        for method in registry.methods(kind):
            start = time.perf_counter()
            _PUBLIC_FIT[kind](*arrays, method=method)
            registry.get(kind, method, checked=False)(*arrays)
            for checked in (True, False):
                registry.many(kind, method, checked=checked)(*batch)
            timings.append((kind, method, time.perf_counter() - start))
    return timings
