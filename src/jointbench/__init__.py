"""jointbench: functional joint centre and axis estimators, and the studies that compare them."""

from jointbench.api import fit_axis, fit_center, fit_joint_center, methods
from jointbench.estimators.results import AxisResult, CenterResult, JointCenterResult

__all__ = [
    "AxisResult",
    "CenterResult",
    "JointCenterResult",
    "fit_axis",
    "fit_center",
    "fit_joint_center",
    "methods",
]
__version__ = "0.1.0"
