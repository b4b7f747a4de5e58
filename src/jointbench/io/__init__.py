"""Reading recordings (C3D, TRC, CSV) and fitting estimators to them."""

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
