"""Scoring one estimator result against the simulated truth, by estimator kind."""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from jointbench.geometry import angle_between_lines_deg

__all__ = ["CHI2_3DOF_95", "ERROR_COLUMN", "covariance_from_entries", "score"]

#: The error column each kind's scorer writes; its unit is the suffix.
ERROR_COLUMN = {"center": "error_mm", "axis": "error_deg", "joint_center": "error_mm"}

_NAN3 = (np.nan, np.nan, np.nan)
# 95 % quantile of chi-square with 3 degrees of freedom, scipy.special.chdtri(3, 0.05) to the
# last bit (tests/test_tolerance.py checks it): written out because every estimate job scores
# its trials, and importing scipy.special would cost each job a third of a second.
CHI2_3DOF_95 = 7.814727903251178


def _score_center(result, truth) -> dict[str, float]:
    center = _NAN3 if result is None else result.center
    error = float(np.linalg.norm(np.asarray(center) - np.asarray(truth["center"])))
    return {"center_x": center[0], "center_y": center[1], "center_z": center[2], "error_mm": error}


def _score_axis(result, truth) -> dict[str, float]:
    point = _NAN3 if result is None else result.point
    direction = _NAN3 if result is None else result.direction
    error = float(
        angle_between_lines_deg(np.asarray(direction), np.asarray(truth["axis_direction"]))
    )
    return {
        **{f"point_{a}": float(v) for a, v in zip("xyz", point, strict=True)},
        **{f"direction_{a}": float(v) for a, v in zip("xyz", direction, strict=True)},
        "error_deg": error,
    }


_COVARIANCE_ENTRIES = {
    "cov_xx": (0, 0),
    "cov_xy": (0, 1),
    "cov_xz": (0, 2),
    "cov_yy": (1, 1),
    "cov_yz": (1, 2),
    "cov_zz": (2, 2),
}


def _covariance_entries(covariance) -> dict[str, float]:
    """The six distinct entries of a predicted 3×3 covariance [mm²] (NaN when there is none)."""
    return {
        name: (np.nan if covariance is None else float(covariance[index]))
        for name, index in _COVARIANCE_ENTRIES.items()
    }


def covariance_from_entries(frame) -> np.ndarray:
    """``(n, 3, 3)`` covariances rebuilt from the ``cov_*`` columns of a results table."""
    out = np.empty((len(frame), 3, 3))
    for name, (i, j) in _COVARIANCE_ENTRIES.items():
        out[:, i, j] = out[:, j, i] = frame[name].to_numpy(float)
    return out


def _score_joint_center(result, truth) -> dict[str, float]:
    """Centre error, predicted uncertainty and its honesty against the TRUE centre.

    ``mahalanobis_sq`` is ``e`` of paper C eq. 16, ``validation_index`` is ``v = sqrt(e / 3)``;
    ``cov_*`` are the predicted covariance's entries, so other references can be used later.
    """
    scores = _score_center(result, truth)
    covariance = None if result is None else result.covariance
    entries = _covariance_entries(covariance)
    if covariance is None:
        return {
            **scores,
            "sqrt_trace_cov_mm": np.nan,
            "mahalanobis_sq": np.nan,
            "validation_index": np.nan,
            **entries,
        }
    offset = np.asarray(result.center) - np.asarray(truth["center"])
    try:
        mahalanobis_sq = float(offset @ np.linalg.solve(covariance, offset))
    except np.linalg.LinAlgError:
        mahalanobis_sq = np.nan
    return {
        **scores,
        "sqrt_trace_cov_mm": float(np.sqrt(np.trace(covariance))),
        "mahalanobis_sq": mahalanobis_sq,
        "validation_index": float(np.sqrt(mahalanobis_sq / 3.0)),
        **entries,
    }


_SCORERS: dict[str, Callable] = {
    "center": _score_center,
    "axis": _score_axis,
    "joint_center": _score_joint_center,
}


def score(kind: str, result, truth: Mapping[str, list[float]]) -> dict[str, float]:
    """Estimate and error columns of one result of a ``kind`` estimator (NaN where it failed)."""
    return _SCORERS[kind](result, truth)
