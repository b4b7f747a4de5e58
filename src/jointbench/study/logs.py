"""The log file of a workflow job: where Snakemake points when the job fails.

A Snakemake ``script:`` writes nothing to its ``log:`` file by itself, so a failed job left an
empty log. :func:`logging_to` sends a block's standard error, warnings and log records there,
and the error that ends the block with its traceback, before the error reaches Snakemake.
"""

from __future__ import annotations

import contextlib
import logging
import traceback
from collections.abc import Iterator
from pathlib import Path

__all__ = ["logging_to"]


@contextlib.contextmanager
def logging_to(path: str | Path) -> Iterator[None]:
    """Write the block's stderr, warnings, log records and any error to ``path`` (created with
    its folder, replaced if present); the error still propagates."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    root = logging.getLogger()
    with path.open("w") as stream, contextlib.redirect_stderr(stream):
        handler = logging.StreamHandler(stream)
        handler.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s"))
        root.addHandler(handler)
        # Warnings as log records, so they reach the log whoever shows warnings.
        logging.captureWarnings(True)
        try:
            yield
        except BaseException:
            traceback.print_exc(file=stream)
            raise
        finally:
            logging.captureWarnings(False)
            root.removeHandler(handler)
