"""The peak memory a call takes in a process of its own, for tests that hold a call on many
markers to memory that grows at most linearly in them.

The peak is Linux's (``VmHWM``), reset (``/proc/self/clear_refs``) after the call has run once
on a small input, which loads its compiled kernels: their compilation can take more memory
than the call.
"""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import pytest


def peak_growth_mb(setup: str, call: str, small: int, large: int) -> float:
    """How far [MB] the peak resident memory of a fresh process rises above its resident memory
    while ``call`` (a statement) runs, after ``setup`` (statements making its input from the
    size ``n``) with ``n = large``; ``setup`` and ``call`` run first with ``n = small``."""
    if not os.access("/proc/self/clear_refs", os.W_OK):
        pytest.skip("the peak memory cannot be reset here (Linux's /proc/self/clear_refs)")
    lines = [
        "def memory_kb(key):",
        "    with open('/proc/self/status') as status:",
        "        return next(int(line.split()[1]) for line in status if line.startswith(key))",
        f"n = {small}",
        textwrap.dedent(setup),
        textwrap.dedent(call),
        f"n = {large}",
        textwrap.dedent(setup),
        "with open('/proc/self/clear_refs', 'w') as peak:",
        "    peak.write('5')",
        "before = memory_kb('VmRSS:')",
        textwrap.dedent(call),
        "print((memory_kb('VmHWM:') - before) / 1024.0)",
    ]
    done = subprocess.run(
        [sys.executable, "-c", "\n".join(lines)],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)},
    )
    assert done.returncode == 0, done.stderr
    return float(done.stdout)
