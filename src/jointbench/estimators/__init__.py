"""Estimator families. Importing this package registers every built-in estimator."""

from jointbench.estimators import amplitude, axis, hjc, sphere, twosegment  # noqa: F401
from jointbench.estimators.registry import get, methods, register
from jointbench.estimators.results import AxisResult, CenterResult, JointCenterResult

__all__ = ["AxisResult", "CenterResult", "JointCenterResult", "get", "methods", "register"]
