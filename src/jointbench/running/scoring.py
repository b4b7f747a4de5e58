"""Scoring estimates against the simulated truth, by estimator kind: one implementation for
every estimator.

An estimator reports its estimate (:data:`ESTIMATE_COLUMNS`, and for a joint centre optionally
its predicted covariance, :data:`COVARIANCE_COLUMNS`); the benchmark computes the rest
(:data:`SCORE_COLUMNS`, the error first) from those columns and the truth stored in the
dataset, with :func:`score_columns`. The estimate jobs score their rows with it, and collect
scores every file again with it, built-in and external alike, so a ranking never rests on an
error an estimator reported about itself.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from jointbench.geometry import angle_between_lines_deg
from jointbench.numerics.poses import rigid_fit
from jointbench.simulate import PROXIMAL_TRUTH, RADII_TRUTH

__all__ = [
    "CHI2_3DOF_95",
    "COVARIANCE_COLUMNS",
    "COVARIANCE_MIRRORS",
    "ERROR_COLUMN",
    "ESTIMATE_COLUMNS",
    "PROXIMAL_COLUMNS",
    "PROXIMAL_TRUTH",
    "RADIUS_COLUMN",
    "SCORE_COLUMNS",
    "covariance_from_entries",
    "estimate_values",
    "proximal_at_frame0",
    "score",
    "score_columns",
]

_CENTER = ("center_x", "center_y", "center_z")
#: Per kind, the columns holding an estimator's estimate of one trial [mm; a direction is any
#: non-zero vector along the axis].
ESTIMATE_COLUMNS = {
    "center": _CENTER,
    "axis": ("point_x", "point_y", "point_z", "direction_x", "direction_y", "direction_z"),
    "joint_center": _CENTER,
}
#: Per kind, the columns the benchmark computes from the estimate and the truth; the first is
#: the error a ranking is made of, its unit the suffix.
SCORE_COLUMNS = {
    "center": ("error_mm", "radius_error_mm"),
    "axis": ("error_deg",),
    "joint_center": (
        "error_mm",
        "sqrt_trace_cov_mm",
        "mahalanobis_sq",
        "validation_index",
        "error_proximal_mm",
        "sqrt_trace_cov_proximal_mm",
        "mahalanobis_sq_proximal",
    ),
}
ERROR_COLUMN = {kind: columns[0] for kind, columns in SCORE_COLUMNS.items()}

# 95 % quantile of chi-square with 3 degrees of freedom, scipy.special.chdtri(3, 0.05) to the
# last bit (tests/test_tolerance.py checks it): written out because every estimate job scores
# its trials, and importing scipy.special would cost each job a third of a second.
CHI2_3DOF_95 = 7.814727903251178

_COVARIANCE_ENTRIES = {
    "cov_xx": (0, 0),
    "cov_xy": (0, 1),
    "cov_xz": (0, 2),
    "cov_yy": (1, 1),
    "cov_yz": (1, 2),
    "cov_zz": (2, 2),
}
#: The six distinct entries of a joint-centre method's predicted 3×3 covariance [mm²]: NaN, or
#: absent from a file, when the method predicts none.
COVARIANCE_COLUMNS = tuple(_COVARIANCE_ENTRIES)
#: The entries below the diagonal a file may give besides :data:`COVARIANCE_COLUMNS`, each with
#: the entry it mirrors: a covariance is symmetric, so they must equal it (scoring reads the
#: upper triangle only).
COVARIANCE_MIRRORS = {"cov_yx": "cov_xy", "cov_zx": "cov_xz", "cov_zy": "cov_yz"}

#: A centre's optional estimate column: the mean of its fitted marker radii [mm], for a method
#: that fits one radius per marker (the sphere fits); NaN, or absent from a file, otherwise.
RADIUS_COLUMN = "mean_radius_mm"

#: A joint centre's optional estimate columns: the centre [mm] and its covariance [mm²] in the
#: proximal segment's own frame as its frame-0 fit places it, for a method that estimates it
#: apart from its shared-frame centre (``gauss-markov-frame0``, whose centre is in the world at
#: frame 0). Absent or NaN, the shared body frame, which the proximal frame-0 fit places, is
#: that frame, and the centre and covariance columns are the centre relative to the markers.
PROXIMAL_COLUMNS = (
    "proximal_center_x",
    "proximal_center_y",
    "proximal_center_z",
    *(f"proximal_{name}" for name in COVARIANCE_COLUMNS),
)


def covariance_from_entries(frame, n_rows: int | None = None) -> np.ndarray:
    """``(n, 3, 3)`` covariances rebuilt from the ``cov_*`` columns of a results table, or of a
    mapping of column name to ``n_rows`` values (NaN where a column is absent)."""
    out = np.full((len(frame) if n_rows is None else n_rows, 3, 3), np.nan)
    for name, (i, j) in _COVARIANCE_ENTRIES.items():
        if name in frame:
            out[:, i, j] = out[:, j, i] = np.asarray(frame[name], dtype=float)
    return out


def estimate_values(kind: str, result) -> dict[str, float]:
    """The estimate columns of one result of a ``kind`` estimator (NaN where it failed: no
    result), for a joint centre the covariance entries (NaN when none is predicted) and for a
    centre its mean fitted radius, :data:`RADIUS_COLUMN` (NaN when it fits no radii)."""
    if kind == "axis":
        vectors = (None, None) if result is None else (result.point, result.direction)
    else:
        vectors = (None if result is None else result.center,)
    values = np.concatenate([np.full(3, np.nan) if v is None else np.asarray(v) for v in vectors])
    out = dict(zip(ESTIMATE_COLUMNS[kind], map(float, values), strict=True))
    if kind == "joint_center":
        covariance = None if result is None else result.covariance
        for name, index in _COVARIANCE_ENTRIES.items():
            out[name] = np.nan if covariance is None else float(covariance[index])
        out.update(_proximal_values(result))
    if kind == "center":
        radii = None if result is None else result.radii
        out[RADIUS_COLUMN] = np.nan if radii is None else float(np.mean(radii))
    return out


def _proximal_values(result) -> dict[str, float]:
    """:data:`PROXIMAL_COLUMNS` of one joint-centre result: its diagnostics' ``center_proximal``
    and ``covariance_proximal``, or nothing when it gives no centre apart from its own."""
    diagnostics = {} if result is None else result.diagnostics or {}
    if "center_proximal" not in diagnostics:
        return {}
    center = np.asarray(diagnostics["center_proximal"], dtype=float)
    covariance = np.asarray(diagnostics.get("covariance_proximal", np.full((3, 3), np.nan)))
    entries = [covariance[index] for index in _COVARIANCE_ENTRIES.values()]
    return dict(zip(PROXIMAL_COLUMNS, map(float, [*center, *entries]), strict=True))


def _distance(points: np.ndarray, target) -> np.ndarray:
    """Euclidean distances ``(n,)`` of ``(n, 3)`` points from one point ``(3,)``, by
    ``hypot`` so that a finite point far out has a finite distance (a sum of squares
    overflows from 1e154 on)."""
    offset = points - np.asarray(target, dtype=float)
    return np.hypot(np.hypot(offset[:, 0], offset[:, 1]), offset[:, 2])


def _stack(estimates: Mapping[str, object], columns) -> np.ndarray:
    """The ``columns`` of ``estimates`` as an ``(n, len(columns))`` float array."""
    return np.column_stack([np.asarray(estimates[c], dtype=float) for c in columns])


def _score_center(estimates, truth) -> dict[str, np.ndarray]:
    """The centre's error and ``radius_error_mm``, the signed error of the mean fitted marker
    radius: :data:`RADIUS_COLUMN` less the mean true radius (:data:`RADII_TRUTH`), negative
    for an underestimate; NaN without either."""
    center = _stack(estimates, _CENTER)
    radius_error = np.full(len(center), np.nan)
    if RADIUS_COLUMN in estimates and RADII_TRUTH in truth:
        fitted = np.asarray(estimates[RADIUS_COLUMN], dtype=float)
        radius_error = fitted - float(np.mean(truth[RADII_TRUTH]))
    return {"error_mm": _distance(center, truth["center"]), "radius_error_mm": radius_error}


def _score_axis(estimates, truth) -> dict[str, np.ndarray]:
    direction = _stack(estimates, ESTIMATE_COLUMNS["axis"][3:])
    true_direction = np.asarray(truth["axis_direction"], dtype=float)
    return {"error_deg": angle_between_lines_deg(direction, true_direction)}


def _mahalanobis_sq(offsets: np.ndarray, covariances: np.ndarray) -> np.ndarray:
    """``e = d' C^-1 d`` ``(n,)`` of offsets ``(n, 3)`` [mm] under covariances ``(n, 3, 3)``
    [mm²]; NaN where either has a NaN or the covariance is singular."""
    out = np.full(len(offsets), np.nan)
    usable = np.isfinite(offsets).all(axis=1) & np.isfinite(covariances).all(axis=(1, 2))
    # One at a time: a batched solve fails as a whole on one singular matrix.
    for row in np.flatnonzero(usable):
        try:
            out[row] = offsets[row] @ np.linalg.solve(covariances[row], offsets[row])
        except np.linalg.LinAlgError:
            pass
    return out


def _proximal_estimate(estimates, center: np.ndarray, covariance: np.ndarray):
    """The centre ``(n, 3)`` and covariance ``(n, 3, 3)`` relative to the proximal markers:
    the :data:`PROXIMAL_COLUMNS` where a row gives them, else ``center`` and ``covariance``."""
    names = PROXIMAL_COLUMNS[:3]
    if not all(name in estimates for name in names):
        return center, covariance
    own = _stack(estimates, names)
    entries = {name: estimates[f"proximal_{name}"] for name in COVARIANCE_COLUMNS}
    own_covariance = covariance_from_entries(entries, len(center))
    given = np.isfinite(own).all(axis=1)
    return (
        np.where(given[:, None], own, center),
        np.where(given[:, None, None], own_covariance, covariance),
    )


def _true_center_placed(truth, proximal_frame0, n_rows: int) -> np.ndarray:
    """The true centre ``(n, 3)`` [mm] in each trial's frame placed by its recorded frame-0
    proximal markers ``(n, k, 3)``: moved by the least-squares rigid fit of the true frame-0
    markers onto the recorded ones. NaN rows without recorded markers or truth."""
    if PROXIMAL_TRUTH not in truth or proximal_frame0 is None or not n_rows:
        return np.full((n_rows, 3), np.nan)
    true_markers = np.asarray(truth[PROXIMAL_TRUTH], dtype=float)
    rotation, translation = rigid_fit(true_markers, np.asarray(proximal_frame0, dtype=float))
    return np.einsum("nij,j->ni", rotation, np.asarray(truth["center"], dtype=float)) + translation


def _score_joint_center(estimates, truth, proximal_frame0=None) -> dict[str, np.ndarray]:
    """Centre error, predicted uncertainty and its honesty against the TRUE centre, and the
    same relative to the proximal markers.

    ``mahalanobis_sq`` is ``e`` of paper C eq. 16, ``validation_index`` is ``v = sqrt(e / 3)``;
    both NaN for a method that predicts no covariance. ``error_proximal_mm``,
    ``sqrt_trace_cov_proximal_mm`` and ``mahalanobis_sq_proximal`` compare the centre relative
    to the proximal markers (:data:`PROXIMAL_COLUMNS`) with the true centre relative to them:
    the estimate's frame is placed by the proximal markers as recorded at frame 0
    ``(n, k, 3)``, the truth's by the true ones (:data:`PROXIMAL_TRUTH`), so the error of that
    placement, shared by the whole trial, drops out. NaN without either.
    """
    center = _stack(estimates, _CENTER)
    covariance = covariance_from_entries(estimates, len(center))
    mahalanobis_sq = _mahalanobis_sq(center - np.asarray(truth["center"], dtype=float), covariance)
    proximal_center, proximal_covariance = _proximal_estimate(estimates, center, covariance)
    placed = _true_center_placed(truth, proximal_frame0, len(center))
    proximal_offset = proximal_center - placed
    return {
        "error_mm": _distance(center, truth["center"]),
        "sqrt_trace_cov_mm": np.sqrt(np.trace(covariance, axis1=1, axis2=2)),
        "mahalanobis_sq": mahalanobis_sq,
        "validation_index": np.sqrt(mahalanobis_sq / 3.0),
        "error_proximal_mm": _distance(proximal_offset, np.zeros(3)),
        "sqrt_trace_cov_proximal_mm": np.sqrt(np.trace(proximal_covariance, axis1=1, axis2=2)),
        "mahalanobis_sq_proximal": _mahalanobis_sq(proximal_offset, proximal_covariance),
    }


_SCORERS = {"center": _score_center, "axis": _score_axis}


def score_columns(
    kind: str,
    estimates: Mapping[str, object],
    truth: Mapping[str, list[float]],
    proximal_frame0: np.ndarray | None = None,
) -> dict[str, np.ndarray]:
    """The :data:`SCORE_COLUMNS` of ``kind`` ``(n,)`` from the estimate columns of ``n`` rows
    (a table or a mapping of column name to values; covariance columns may be absent) and the
    dataset's ``truth``. NaN where an estimate is missing; a finite estimate has a finite
    error, however far out. A joint centre's scores relative to the proximal markers need
    ``proximal_frame0`` ``(n, k, 3)`` [mm], each row's proximal markers as recorded at frame 0
    (:func:`proximal_at_frame0`), and the truth's (:data:`PROXIMAL_TRUTH`): NaN without them.
    ``ValueError`` when ``truth`` is ``None`` (trials of a blind dataset file)."""
    if truth is None:
        raise ValueError(
            "no truth to score against: trials read from a blind dataset file are not scored"
        )
    # A negative variance or a NaN estimate is a NaN score, not a warning in a job's log.
    with np.errstate(invalid="ignore", over="ignore"):
        if kind == "joint_center":
            return _score_joint_center(estimates, truth, proximal_frame0)
        return _SCORERS[kind](estimates, truth)


def proximal_at_frame0(segments: Mapping[str, np.ndarray], names) -> np.ndarray | None:
    """The first of a two-segment study's ``names`` segments as recorded at frame 0,
    ``(n_trials, k, 3)`` [mm], from its ``segments`` ``(n_trials, n_frames, k, 3)``; ``None``
    for a study of another kind."""
    if len(names) != 2:
        return None
    return np.asarray(segments[names[0]][:, 0], dtype=float)


def score(
    kind: str, result, truth: Mapping[str, list[float]], proximal_frame0: np.ndarray | None = None
) -> dict[str, float]:
    """Estimate and score columns of one result of a ``kind`` estimator (NaN where it failed):
    the estimate columns, the scores, then any covariance entries. ``proximal_frame0``
    ``(k, 3)``: the trial's proximal markers at frame 0 (see :func:`score_columns`)."""
    values = estimate_values(kind, result)
    markers = None if proximal_frame0 is None else np.asarray(proximal_frame0)[None]
    scores = score_columns(kind, {name: [value] for name, value in values.items()}, truth, markers)
    estimate = {name: values.pop(name) for name in ESTIMATE_COLUMNS[kind]}
    return {**estimate, **{name: float(column[0]) for name, column in scores.items()}, **values}
