"""jointbench: functional joint centre and axis estimators, and the studies that compare them."""

from jointbench.api import fit_axis, fit_center, fit_joint_center, methods
from jointbench.estimators.results import AxisResult, CenterResult, JointCenterResult
from jointbench.io import Recording, RecordingFit, fit, prepare, read

__all__ = [
    "AxisResult",
    "CenterResult",
    "JointCenterResult",
    "Recording",
    "RecordingFit",
    "fit",
    "fit_axis",
    "fit_center",
    "fit_joint_center",
    "methods",
    "prepare",
    "read",
]
__version__ = "0.1.0"
