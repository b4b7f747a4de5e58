"""Public entry points: fit a centre, an axis or a two-segment joint centre by method name.

Every method is reached through the registry, which holds it to the same rules:

* bad input raises ``ValueError`` naming the problem and where it is: complex, boolean or
  non-numeric arrays, masked arrays with masked values, a wrong shape, NaN/inf or a sample at
  exactly ``(0, 0, 0)`` (marker and frame named), markers that do not move or that only slide
  along straight lines (see :mod:`jointbench.estimators.validation`);
* data that cannot support an answer — markers that are not one rigid body, a rotation not
  resolved above the rigid-body residual, or (for a centre) rotation about a single axis — give
  a result whose ``status`` starts with or carries ``"warning: ..."``, with the numbers in
  ``diagnostics["support_..."]`` (see :mod:`jointbench.estimators.support`). ``converged`` keeps
  the meaning the method's paper gives it, so check ``status == "ok"`` for a clean answer.
"""

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
