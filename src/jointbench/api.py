"""Public entry points: fit a centre, an axis or a two-segment joint centre by method name."""

from __future__ import annotations

import numpy as np

from jointbench.estimators import registry
from jointbench.estimators.results import AxisResult, CenterResult, JointCenterResult

__all__ = ["fit_axis", "fit_center", "fit_joint_center", "methods"]


def fit_center(markers: np.ndarray, method: str = "NM", **options: object) -> CenterResult:
    """Centre of rotation of a segment moving about a fixed point.

    Parameters
    ----------
    markers : (n_frames, n_markers, 3) array [mm]
        The moving segment's markers in the reference segment's frame.
    method : one of ``methods("center")`` (NM, LS, BC, IS, MA, SCoRE, ...).
    """
    return registry.get("center", method)(markers, **options)


def fit_axis(markers: np.ndarray, method: str = "combined", **options: object) -> AxisResult:
    """Dominant axis of rotation of a segment moving about a (nearly) fixed hinge.

    Parameters
    ----------
    markers : (n_frames, n_markers, 3) array [mm]
        The moving segment's markers in the reference segment's frame.
    method : one of ``methods("axis")`` (planar, radial, combined, SARA, ...).
    """
    return registry.get("axis", method)(markers, **options)


def fit_joint_center(
    proximal: np.ndarray, distal: np.ndarray, method: str = "gauss-markov", **options: object
) -> JointCenterResult:
    """Ball-joint centre of two segments that both move in the world frame.

    Parameters
    ----------
    proximal, distal : (n_frames, n_markers >= 3, 3) arrays [mm], world frame.
    method : one of ``methods("joint_center")`` (gauss-markov, analytic, SCoRE, ...).
    """
    return registry.get("joint_center", method)(proximal, distal, **options)


def methods(kind: str) -> tuple[str, ...]:
    """Registered estimator names of ``kind`` ("center", "axis" or "joint_center")."""
    return registry.methods(kind)
