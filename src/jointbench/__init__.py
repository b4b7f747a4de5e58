"""jointbench: functional joint centre and axis estimators, and the studies that compare them.

The names below (``jointbench.fit_center``, ``jointbench.read``, ...) are imported on first use
(PEP 562): importing a submodule, as every workflow job does, does not load the recording readers
or the estimators it does not use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

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
    "screen",
]
__version__ = "0.1.0"

if TYPE_CHECKING:  # for type checkers; at run time __getattr__ imports each name from _HOMES
    from jointbench.api import fit_axis, fit_center, fit_joint_center, methods, screen
    from jointbench.estimators.results import AxisResult, CenterResult, JointCenterResult
    from jointbench.io import Recording, RecordingFit, fit, prepare, read

# The module defining each name of __all__ (tests/test_imports.py holds this, __all__ and the
# imports above to the same names).
_HOMES = {
    "AxisResult": "jointbench.estimators.results",
    "CenterResult": "jointbench.estimators.results",
    "JointCenterResult": "jointbench.estimators.results",
    "Recording": "jointbench.io",
    "RecordingFit": "jointbench.io",
    "fit": "jointbench.io",
    "fit_axis": "jointbench.api",
    "fit_center": "jointbench.api",
    "fit_joint_center": "jointbench.api",
    "methods": "jointbench.api",
    "prepare": "jointbench.io",
    "read": "jointbench.io",
    "screen": "jointbench.api",
}


def __getattr__(name: str) -> object:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(home), name)
    globals()[name] = value  # later look-ups find it without coming here
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
