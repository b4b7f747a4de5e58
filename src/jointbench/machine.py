"""The machine a process runs on, described for tables and reports beside measured times."""

from __future__ import annotations

import os
import platform
from pathlib import Path

import numpy as np

__all__ = ["describe", "processor"]


def processor() -> str:
    """The CPU model (from ``/proc/cpuinfo`` where there is one)."""
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.exists():
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or platform.machine()


def describe() -> str:
    """One line: CPU model, logical CPUs, operating system, Python and NumPy versions."""
    return (
        f"{processor()}, {os.cpu_count()} logical CPUs, {platform.system()}; "
        f"Python {platform.python_version()}, NumPy {np.__version__}"
    )
