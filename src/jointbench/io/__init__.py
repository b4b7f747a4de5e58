"""Reading recordings (C3D, TRC, CSV) and fitting estimators to them.

The names below are imported on first use (PEP 562), so that :mod:`jointbench.api` can screen
arrays with :mod:`jointbench.io.segments` without loading the readers, and without a circular
import (:mod:`jointbench.io.fit` fits through :mod:`jointbench.api`).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

__all__ = [
    "ARTEFACT_POLICIES",
    "DEFAULT_METHODS",
    "Artefact",
    "ArtefactRules",
    "Prepared",
    "Recording",
    "RecordingFit",
    "Segment",
    "Swap",
    "fit",
    "prepare",
    "read",
    "read_c3d",
    "read_csv",
    "read_trc",
]

if TYPE_CHECKING:  # for type checkers; at run time __getattr__ imports each name from _HOMES
    from jointbench.io.fit import (
        ARTEFACT_POLICIES,
        DEFAULT_METHODS,
        Prepared,
        RecordingFit,
        fit,
        prepare,
    )
    from jointbench.io.readers import read, read_c3d, read_csv, read_trc
    from jointbench.io.recording import Recording
    from jointbench.io.segments import Artefact, ArtefactRules, Segment, Swap

_HOMES = {
    **dict.fromkeys(
        ("ARTEFACT_POLICIES", "DEFAULT_METHODS", "Prepared", "RecordingFit", "fit", "prepare"),
        "jointbench.io.fit",
    ),
    **dict.fromkeys(("read", "read_c3d", "read_csv", "read_trc"), "jointbench.io.readers"),
    "Recording": "jointbench.io.recording",
    **dict.fromkeys(("Artefact", "ArtefactRules", "Segment", "Swap"), "jointbench.io.segments"),
}


def __getattr__(name: str) -> object:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(home), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *__all__})
