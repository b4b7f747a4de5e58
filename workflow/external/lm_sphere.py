#!/usr/bin/env python3
"""LM: geometric sphere fit by Levenberg–Marquardt — an external jointbench estimator.

This script is the worked example of an estimator that lives outside the ``jointbench``
package: for each dataset file it writes the estimates file of the same name, and it depends on
nothing but NumPy, pandas, pyarrow and SciPy. Copy it, replace :func:`fit_trial`, and add a rule
to ``workflow/rules/estimators/`` (see ``lm_sphere.smk`` there). One run takes every condition of
a study, so the interpreter and SciPy start once per study, not once per condition.

Usage::

    python workflow/external/lm_sphere.py --out-dir ESTIMATES_DIR DATASET.parquet [...]

The method
----------
Minimise paper A's geometric cost over the centre ``c`` and one radius ``r_p`` per marker,

    f1(c, r) = sum_p sum_k (|v_k^p - c| - r_p)^2        [mm^2],

with ``scipy.optimize.least_squares(method="lm")`` (MINPACK's Levenberg–Marquardt) and an
analytic Jacobian, started from the Gamage–Lasenby least-squares (LS) centre with each radius
the marker's mean distance from it. That is IS's cost and IS's start; only the optimiser
differs (IS uses Nelder–Mead over the centre with the radii profiled out), so comparing the
final f1 of the two shows whether IS's local minima (paper A claim A7) belong to the cost or
to the search. After it stops, two restarts (:func:`restart_points`) test the minimum it found;
when one ends lower, the answer is kept (it is what the method finds) but marked
``converged=False`` with a status that names the restart and both costs.

Input: a blind dataset file
---------------------------
Parquet (``results/blind/{study}/{condition}.parquet``), long format, one row per (segment,
trial, frame, marker) with columns ``segment, trial, frame, marker, x, y, z`` [mm]. The schema
metadata key ``jointbench`` holds JSON with ``study``, ``condition`` (grid values, e.g.
``{"marker_set": "M", "rom_deg": 5, "noise_mm": 1.0}``) and ``shapes``; the truth, which the
benchmark scores the estimates with, is not in the file.
Centre studies have one segment, ``moving``: its markers in the reference segment's frame.

Output: an estimates file
-------------------------
Parquet, one row per trial, with the columns of a ``center`` estimator:

* every key of ``condition``, with its value;
* ``trial`` (int), ``method`` (str, ``"LM"`` in every row);
* ``center_x, center_y, center_z`` [mm]: the estimate. No error column: the benchmark computes
  ``error_mm`` from these and the truth when it collects the file (a file that gives one has it
  checked against the benchmark's, and the run stops when they disagree);
* ``converged`` (bool), ``iterations`` (int, Jacobian evaluations), ``seconds`` (float, the
  fit of that trial alone), ``status`` (str, ``"ok"`` or why it did not converge);
* ``f1_mm2``: f1 at the final centre with the radii profiled out (``r_p`` = mean distance),
  directly comparable with IS's f1 [mm^2].

A trial that fails (bad data, a numerical error) becomes a row with NaN estimates,
``converged=False`` and the error in ``status``; only an unreadable dataset stops the script.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
from scipy.optimize import least_squares

METHOD = "LM"
METADATA_KEY = b"jointbench"
SEGMENT = "moving"
# Tolerances far below IS's 1e-4 (fminsearch's TolFun), so that LM's f1 is its minimum's f1 to
# well within the margin used to compare it with IS's; MINPACK's own scaling (diag = column norms
# of the Jacobian) and 100 evaluations per unknown are SciPy's defaults for "lm", fixed here so
# that a SciPy upgrade cannot change the results.
LM_OPTIONS = {"ftol": 1e-10, "xtol": 1e-10, "gtol": 1e-10, "x_scale": "jac"}
EVALUATIONS_PER_UNKNOWN = 100
# Below this distance from a marker the direction (v - c) / |v - c| is undefined.
_TINY_MM = 1e-12
# A restart's f1 counts as lower when it is lower by more than this share of f1: rounding in the
# sums of squares, not a different minimum.
RESTART_MARGIN = 1e-9


# ------------------------------------------------------------------------------------- input


def read_dataset(path: str | Path, segment: str = SEGMENT) -> tuple[dict[int, pd.DataFrame], dict]:
    """One segment's rows per trial, and the ``jointbench`` metadata of a dataset file.

    Returns ``({trial: rows with frame, marker, x, y, z}, metadata)``; the rows are turned into
    arrays per trial by :func:`trial_markers`, so that a malformed trial fails alone.
    """
    metadata = pq.read_schema(path).metadata or {}
    if METADATA_KEY not in metadata:
        raise ValueError(f"{path} is not a jointbench dataset (no 'jointbench' metadata)")
    meta = json.loads(metadata[METADATA_KEY])
    frame = pd.read_parquet(path, columns=["segment", "trial", "frame", "marker", "x", "y", "z"])
    segments = sorted(map(str, frame["segment"].unique()))
    if segment not in segments:
        raise ValueError(f"{path}: no segment {segment!r} (segments: {segments})")
    rows = frame[frame["segment"].astype(str) == segment]
    return {int(trial): part for trial, part in rows.groupby("trial", sort=True)}, meta


def trial_markers(rows: pd.DataFrame) -> np.ndarray:
    """``(n_frames, n_markers, 3)`` [mm] from one trial's long-format rows."""
    rows = rows.sort_values(["frame", "marker"])
    n_frames, n_markers = rows["frame"].nunique(), rows["marker"].nunique()
    if len(rows) != n_frames * n_markers:
        raise ValueError(
            f"{len(rows)} rows are not {n_frames} frames x {n_markers} markers (gaps or repeats)"
        )
    markers = rows[["x", "y", "z"]].to_numpy(dtype=float).reshape(n_frames, n_markers, 3)
    if not np.all(np.isfinite(markers)):
        raise ValueError("marker coordinates contain NaN or inf")
    if n_frames < 4:
        raise ValueError(f"{n_frames} frames; a sphere fit needs at least 4")
    if not np.any(np.ptp(markers, axis=0) > 0):
        raise ValueError("the markers do not move")
    return markers


# ------------------------------------------------------------------------------------ method


def ls_center(markers: np.ndarray) -> np.ndarray:
    """Gamage & Lasenby's least-squares centre ``(3,)`` [mm] of ``(N, P, 3)`` markers.

    Solves ``A c = b`` with ``A = 2 sum_p Cov(v^p)`` and
    ``b = sum_p [mean(|v|^2 v) - mean(v) mean(|v|^2)]`` (1/N moments). The data are centred on
    their centroid first: the fit moves with the data, and the moments of coordinates near zero
    lose fewer digits. Singular values below 1e-12 of the largest are dropped (a pure hinge).
    """
    origin = markers.reshape(-1, 3).mean(axis=0)
    v = markers - origin
    sq = np.einsum("kpi,kpi->kp", v, v)
    mean_v, mean_sq = v.mean(axis=0), sq.mean(axis=0)
    centred = v - mean_v
    a_matrix = 2.0 * np.einsum("kpi,kpj->ij", centred, centred) / markers.shape[0]
    b_vector = np.einsum("kp,kpi->i", sq - mean_sq, centred) / markers.shape[0]
    center, *_ = np.linalg.lstsq(a_matrix, b_vector, rcond=1e-12)
    return origin + center


def _distances(center: np.ndarray, flat: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Offsets ``(N P, 3)`` and distances ``(N P,)`` of the marker rows from ``center``."""
    offsets = flat - center
    return offsets, np.sqrt(np.einsum("ri,ri->r", offsets, offsets))


def residuals(params: np.ndarray, flat: np.ndarray, marker: np.ndarray) -> np.ndarray:
    """``|v - c| - r_p`` ``(N P,)`` [mm] for ``params = (c (3,), r (P,))``; ``marker`` ``(N P,)``
    is the marker index of each row of ``flat``."""
    _, distance = _distances(params[:3], flat)
    return distance - params[3:][marker]


def jacobian(params: np.ndarray, flat: np.ndarray, marker: np.ndarray) -> np.ndarray:
    """``(N P, 3 + P)`` derivative of :func:`residuals`: ``-(v - c) / |v - c|`` for the centre,
    ``-1`` for the marker's own radius."""
    offsets, distance = _distances(params[:3], flat)
    jac = np.zeros((flat.shape[0], params.size))
    jac[:, :3] = -offsets / np.maximum(distance, _TINY_MM)[:, None]
    jac[np.arange(flat.shape[0]), 3 + marker] = -1.0
    return jac


def profiled_f1(markers: np.ndarray, center: np.ndarray) -> float:
    """f1 [mm^2] at ``center`` with each radius at its optimum, the marker's mean distance."""
    _, distance = _distances(center, markers.reshape(-1, 3))
    distance = distance.reshape(markers.shape[:2])
    spread = distance - distance.mean(axis=0)
    return float(np.sum(spread * spread))


def _solve(markers: np.ndarray, start: np.ndarray):
    """Levenberg–Marquardt on f1 from the centre ``start`` ``(3,)`` [mm], each radius the
    marker's mean distance from it: SciPy's result, ``x = (c, r)``."""
    n_frames, n_markers, _ = markers.shape
    flat = markers.reshape(-1, 3)
    marker = np.tile(np.arange(n_markers), n_frames)
    radii = _distances(start, flat)[1].reshape(n_frames, n_markers).mean(axis=0)
    params = np.concatenate([start, radii])
    return least_squares(
        residuals,
        params,
        jac=jacobian,
        method="lm",
        args=(flat, marker),
        max_nfev=EVALUATIONS_PER_UNKNOWN * params.size,
        **LM_OPTIONS,
    )


def restart_points(markers: np.ndarray, start: np.ndarray) -> dict[str, np.ndarray]:
    """Starts ``(3,)`` [mm] that a search from the LS centre ``start`` can miss, by name: the LS
    centre reflected through the markers' mean position (a sphere on the other side of the
    marker cap) and twice as far from it (a flatter cap)."""
    centroid = markers.reshape(-1, 3).mean(axis=0)
    return {
        "the LS centre reflected through the markers' mean": 2.0 * centroid - start,
        "twice as far from the markers' mean as the LS centre": centroid + 2.0 * (start - centroid),
    }


def self_check(markers: np.ndarray, start: np.ndarray, f1: float) -> str | None:
    """Why the minimum of f1 [mm^2] found from ``start`` may not be the lowest: a restart from
    :func:`restart_points` that ends lower by more than rounding (``None`` when none does)."""
    for name, point in restart_points(markers, start).items():
        result = _solve(markers, point)
        if not np.all(np.isfinite(result.x)):
            continue
        lower = profiled_f1(markers, result.x[:3])
        if lower < f1 - RESTART_MARGIN * max(f1, 1.0):
            return (
                f"local minimum: a restart from {name} reached f1 = {lower:.6g} mm^2, "
                f"below this answer's {f1:.6g} mm^2"
            )
    return None


def fit_trial(markers: np.ndarray) -> dict[str, object]:
    """Fit one trial's ``(N, P, 3)`` markers [mm], then check the minimum (:func:`self_check`).

    Returns ``center`` ``(3,)`` [mm], ``converged``, ``iterations``, ``status`` and ``f1_mm2``.
    The answer is the search from the LS centre, as IS's; a restart that ends lower makes it
    ``converged=False`` with a status that says so.
    """
    start = ls_center(markers)
    result = _solve(markers, start)
    center = np.asarray(result.x[:3], dtype=float)
    finite = bool(np.all(np.isfinite(result.x)))
    converged = bool(result.success) and finite
    f1 = profiled_f1(markers, center) if finite else np.nan
    status = "ok" if converged else f"not converged: {result.message}"
    if converged:
        doubt = self_check(markers, start, f1)
        if doubt is not None:
            converged, status = False, doubt
    return {
        "center": center,
        "converged": converged,
        # MINPACK evaluates the Jacobian once per outer iteration: njev counts iterations.
        "iterations": int(result.njev if result.njev is not None else result.nfev),
        "status": status,
        "f1_mm2": f1,
    }


# ------------------------------------------------------------------------------------ output


def trial_row(trial: int, rows: pd.DataFrame, condition: Mapping[str, object]) -> dict[str, object]:
    """The estimates row of one trial; any error becomes a failed row instead of a crash.

    ``seconds`` times the fit alone, as the benchmark times its built-in estimators.
    """
    start = time.perf_counter()
    try:
        markers = trial_markers(rows)
        start = time.perf_counter()
        fit = fit_trial(markers)
    except Exception as error:  # one bad trial must not lose the others
        fit = {
            "center": np.full(3, np.nan),
            "converged": False,
            "iterations": 0,
            "status": f"error: {type(error).__name__}: {error}",
            "f1_mm2": np.nan,
        }
    seconds = time.perf_counter() - start
    center = fit["center"]
    return {
        **condition,
        "trial": trial,
        "method": METHOD,
        "center_x": center[0],
        "center_y": center[1],
        "center_z": center[2],
        "converged": fit["converged"],
        "iterations": fit["iterations"],
        "seconds": seconds,
        "status": fit["status"],
        "f1_mm2": fit["f1_mm2"],
    }


# The dtypes the benchmark checks (jointbench.resultfiles.schema), set explicitly so that an
# empty or all-failed table still has them.
DTYPES = {
    "trial": "int64",
    "method": "object",
    "center_x": "float64",
    "center_y": "float64",
    "center_z": "float64",
    "converged": "bool",
    "iterations": "int64",
    "seconds": "float64",
    "status": "object",
    "f1_mm2": "float64",
}


def estimate(trials: Mapping[int, pd.DataFrame], metadata: Mapping) -> pd.DataFrame:
    """One row per trial of a dataset read by :func:`read_dataset`."""
    condition = dict(metadata["condition"])
    rows = [trial_row(trial, part, condition) for trial, part in trials.items()]
    columns = [*condition, *DTYPES]
    return pd.DataFrame(rows, columns=columns).astype(DTYPES)


def parse_arguments(argv: Sequence[str] | None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(
        description="Geometric sphere fit by Levenberg–Marquardt (method LM) on every trial of a "
        "jointbench dataset file.",
    )
    parser.add_argument("datasets", type=Path, nargs="+", help="dataset parquet files (input)")
    parser.add_argument(
        "--out-dir",
        type=Path,
        required=True,
        help="folder of the estimates files, each named as its dataset (output)",
    )
    parser.add_argument(
        "--segment", default=SEGMENT, help=f"segment whose markers are fitted (default {SEGMENT})"
    )
    return parser.parse_args(argv)


def main(argv: Sequence[str] | None = None) -> int:
    arguments = parse_arguments(argv)
    arguments.out_dir.mkdir(parents=True, exist_ok=True)
    for dataset in arguments.datasets:
        try:
            trials, metadata = read_dataset(dataset, arguments.segment)
        except (OSError, ValueError) as error:
            print(f"lm_sphere: {dataset}: {error}", file=sys.stderr)
            return 1
        estimates = estimate(trials, metadata)
        estimates.to_parquet(arguments.out_dir / dataset.name, index=False)
        print(
            f"lm_sphere: {dataset.name}: {len(estimates)} trials, "
            f"{int(estimates['converged'].sum())} converged",
            file=sys.stderr,
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
