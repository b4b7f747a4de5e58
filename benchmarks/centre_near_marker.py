"""Count the checked centres of rotation that read ``ok`` while hiding their step to the
spheres' centre, beside a marker near the joint (a virtual marker placed at it, or a point a
little off), as the README's paragraph on such markers quotes them.

Usage::

    python benchmarks/centre_near_marker.py [--trials 24] [--methods LS,NM,BC,IS,MA,SCoRE]

Each trial is ``tests/test_centre_precision.py``'s 30 degree cap (120 frames, 0.5 mm noise,
four markers 55 to 100 mm from the centre) with a fifth marker 0, 0.5, 1 or 2 mm from the
joint, or none; the trials of each case are drawn from one seed. Per case and method it
prints, over ``--trials`` trials:

* ``ok``: the checked calls with the fifth marker that read ``ok``;
* ``stated alone``: the calls on the four markers alone that read ``ok`` and state their
  step to the spheres' centre as a bias (``center_step_bias_mm``), and ``hidden beside`` how
  many of those, with the fifth marker, read ``ok`` and state none;
* ``hidden, >= 0.45 SDs`` and ``>= 0.89 SDs``: the calls with the fifth marker that read
  ``ok`` and state no bias while their answer lies ``MAX_STEP_SDS`` (twice that) or more of
  the four markers' scatter's SDs (Mahalanobis) from those markers' spheres' centre, found
  here by SciPy's least squares on the radial residuals, not by the check's own iterations
  (a fifth marker clear of the answer counts in the check: a method that ends at the spheres'
  centre of all five, IS, is counted here as far as that is from the four's);
* ``beyond 3 SDs``: the calls with the fifth marker that read ``ok`` and lie more than three
  of the SDs they state (``center_sd_mm``) from the true centre;
* the seconds the checked calls took (``time.perf_counter``).

Run it with the tree of another version of the code on ``PYTHONPATH`` to compare.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from jointbench.estimators import centre_precision, registry, support

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_centre_precision import BODY, CENTRE, _cap, _spheres_centre

# The fifth marker's offset from the joint [mm] per case; None for no fifth marker.
NEAR = {"none": None, "0 mm": 0.0, "0.5 mm": 0.5, "1 mm": 1.0, "2 mm": 2.0}


def step_sds(markers: np.ndarray, answer: np.ndarray) -> float:
    """How many SDs (Mahalanobis, under the scatter's covariance of the check's own
    statistics there, :func:`centre_precision.centre_statistics`) ``answer`` ``(3,)`` [mm]
    lies from the spheres' centre of ``markers`` ``(N, n, 3)`` [mm]
    (``tests/test_centre_precision.py``'s ``_spheres_centre``),
    with the noise the support verdict reads off them."""
    centre = _spheres_centre(markers, answer)
    variance = support.assess("center", (markers,)).diagnostics["rigid_residual_mm"] ** 2 / 3.0
    row = centre_precision.centre_statistics(
        np.ascontiguousarray(markers[None]), centre[None], np.array([variance])
    )[0]
    covariance = row[centre_precision._COVARIANCE].reshape(3, 3)
    step = answer - centre
    return float(np.sqrt(step @ np.linalg.solve(covariance, step)))


def count(method: str, near: float | None, n_trials: int, seed: int) -> dict[str, float]:
    """The counts of :func:`main`'s table for ``method`` with the fifth marker ``near`` [mm]
    from the joint (``None``: none) over ``n_trials`` trials drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    body = BODY if near is None else np.vstack([BODY, [[near, 0.0, 0.0]]])
    fit = registry.get("center", method)
    keys = ("ok", "stated alone", "hidden beside", "hidden 1", "hidden 2", "beyond 3 SDs")
    numbers = dict.fromkeys(keys, 0)
    seconds = 0.0
    bound = centre_precision.MAX_STEP_SDS
    for _ in range(n_trials):
        markers = _cap(rng, 30.0, 0.5, body=body)
        four = np.ascontiguousarray(markers[:, : len(BODY)])
        alone = fit(four)
        started = time.perf_counter()
        beside = fit(markers)
        seconds += time.perf_counter() - started
        if beside.status != "ok":
            continue
        numbers["ok"] += 1
        error = float(np.linalg.norm(beside.center - CENTRE))
        numbers["beyond 3 SDs"] += error > 3.0 * beside.diagnostics["center_sd_mm"]
        stated = "center_step_bias_mm" in beside.diagnostics
        if alone.status == "ok" and "center_step_bias_mm" in alone.diagnostics:
            numbers["stated alone"] += 1
            numbers["hidden beside"] += not stated
        if not stated:
            sds = step_sds(four, beside.center)
            numbers["hidden 1"] += sds >= bound
            numbers["hidden 2"] += sds >= 2.0 * bound
    numbers["seconds"] = seconds
    return numbers


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=24)
    parser.add_argument("--methods", default="LS,NM,BC,IS,MA,SCoRE")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    print(
        "| marker | method | ok | stated alone | hidden beside | hidden, >= 0.45 SDs "
        "| >= 0.89 SDs | beyond 3 SDs | seconds |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for seed, (name, near) in enumerate(NEAR.items()):
        for method in args.methods.split(","):
            n = count(method, near, args.trials, 4100 + seed)
            print(
                f"| {name} | {method} | {n['ok']} | {n['stated alone']} | {n['hidden beside']} "
                f"| {n['hidden 1']} | {n['hidden 2']} | {n['beyond 3 SDs']} | {n['seconds']:.2f} |"
            )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
