"""Reading recordings (C3D, TRC, CSV) and fitting estimators to them."""

from jointbench.io.fit import Prepared, RecordingFit, fit, prepare
from jointbench.io.readers import read, read_c3d, read_csv, read_trc
from jointbench.io.recording import Recording
from jointbench.io.segments import Artefact, ArtefactRules, Segment

__all__ = [
    "Artefact",
    "ArtefactRules",
    "Prepared",
    "Recording",
    "RecordingFit",
    "Segment",
    "fit",
    "prepare",
    "read",
    "read_c3d",
    "read_csv",
    "read_trc",
]
