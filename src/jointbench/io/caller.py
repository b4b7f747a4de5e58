"""Warnings about a recording, placed at the line that asked for it.

A reader's warning is about the file the caller named, and a fit's about the recording it was
given, so Python names the caller's line with it (``warnings.warn``'s ``stacklevel``), not one
of this package's: the first frame outside it, however deep the public function the caller
called (``jointbench.read`` calls ``read_c3d``, which builds a ``Recording``; ``fit`` calls
``prepare``) reaches into it.
"""

from __future__ import annotations

import sys
import warnings

__all__ = ["warn_caller"]

#: The modules whose frames a warning skips: this package's.
_PACKAGE = __name__.rpartition(".")[0] + "."


def warn_caller(message: str, category: type[Warning] = UserWarning) -> None:
    """Warn ``message`` (``category``) at the first frame up the stack outside this package."""
    frame, level = sys._getframe(0), 1
    while frame is not None and frame.f_globals.get("__name__", "").startswith(_PACKAGE):
        frame, level = frame.f_back, level + 1
    warnings.warn(message, category, stacklevel=level)
