"""A kernel's cached machine code is rebuilt whenever anything compiled into it changes.

Numba caches a kernel's machine code beside its source and rebuilds it when that file changes.
What it compiles in from elsewhere, a kernel or a function of ``numba.njit`` or
``register_jitable`` it calls or a constant it reads from another module (by name or as
``module.NAME``), is not part of that check: edited there, a process would run the old code
while every job that depends on it reruns. Each test builds two modules, runs a kernel in a
fresh process (compiling and caching it), edits the other module, keeping the kernel's own file
as it was, and runs it again in a fresh process.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"

CALLER = """
from jointbench.numerics.compiled import kernel
from callee import SCALE, helper


@kernel
def outer(x):
    return helper(x) + SCALE
"""

CALLEE = """
from jointbench.numerics.compiled import kernel

SCALE = {scale}


@kernel
def helper(x):
    return {factor} * x
"""

DEEP = """
from jointbench.numerics.compiled import kernel
from callee import helper


@kernel
def middle(x):
    return helper(x)
"""

DEEPER = """
from jointbench.numerics.compiled import kernel
from deep import middle


@kernel
def outer(x):
    return middle(x) + 0.0
"""


ATTRIBUTE_CALLER = """
import callee
from jointbench.numerics.compiled import kernel


@kernel
def outer(x):
    return callee.helper(x) + callee.SCALE
"""

NUMBA_CALLEE = """
import numba
from numba.extending import register_jitable

SCALE = {scale}


@{decorator}
def helper(x):
    return {factor} * x
"""


def _python(folder: Path, code: str) -> float:
    """What ``code`` prints, run in a fresh process with Numba's cache beside the sources in
    ``folder``: what a new job meets."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(folder), str(SRC)])}
    env["PYTHONDONTWRITEBYTECODE"] = "1"  # a same-second edit of the same size
    env.pop("NUMBA_CACHE_DIR", None)
    env.pop("NUMBA_DISABLE_JIT", None)
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    return float(out.stdout)


def _run(folder: Path, module: str) -> float:
    return _python(folder, f"from {module} import outer; print(outer(3.0))")


def _write(path: Path, text: str) -> None:
    path.write_text(text)


@pytest.mark.parametrize(
    ("before", "after", "expected"),
    [
        ({"scale": 0.0, "factor": 2.0}, {"scale": 0.0, "factor": 5.0}, (6.0, 15.0)),
        ({"scale": 0.0, "factor": 2.0}, {"scale": 1.0, "factor": 2.0}, (6.0, 7.0)),
    ],
    ids=["a called kernel", "a constant of another module"],
)
def test_an_edit_of_what_a_kernel_compiles_in_rebuilds_it(tmp_path, before, after, expected):
    _write(tmp_path / "caller.py", CALLER)
    _write(tmp_path / "callee.py", CALLEE.format(**before))
    assert _run(tmp_path, "caller") == expected[0]
    assert _run(tmp_path, "caller") == expected[0]  # from the cache
    _write(tmp_path / "callee.py", CALLEE.format(**after))
    assert _run(tmp_path, "caller") == expected[1]


@pytest.mark.parametrize(
    ("caller", "decorator", "after", "expected"),
    [
        (CALLER, "numba.njit(cache=True)", {"scale": 0.0, "factor": 5.0}, 15.0),
        (CALLER, "register_jitable", {"scale": 0.0, "factor": 5.0}, 15.0),
        (ATTRIBUTE_CALLER, "numba.njit", {"scale": 1.0, "factor": 2.0}, 7.0),
        (ATTRIBUTE_CALLER, "numba.njit", {"scale": 0.0, "factor": 5.0}, 15.0),
    ],
    ids=[
        "a helper of numba.njit",
        "a helper of register_jitable",
        "a constant read as module.NAME",
        "a helper called as module.name",
    ],
)
def test_an_edit_of_a_numba_function_or_a_module_attribute_rebuilds_it(
    tmp_path, caller, decorator, after, expected
):
    _write(tmp_path / "caller.py", caller)
    _write(tmp_path / "callee.py", NUMBA_CALLEE.format(decorator=decorator, scale=0.0, factor=2.0))
    assert _run(tmp_path, "caller") == 6.0
    assert _run(tmp_path, "caller") == 6.0  # from the cache
    _write(tmp_path / "callee.py", NUMBA_CALLEE.format(decorator=decorator, **after))
    assert _run(tmp_path, "caller") == expected


def test_an_edit_two_calls_away_rebuilds_the_kernel(tmp_path):
    _write(tmp_path / "callee.py", CALLEE.format(scale=0.0, factor=2.0))
    _write(tmp_path / "deep.py", DEEP)
    _write(tmp_path / "deeper.py", DEEPER)
    assert _run(tmp_path, "deeper") == 6.0
    _write(tmp_path / "callee.py", CALLEE.format(scale=0.0, factor=7.0))
    assert _run(tmp_path, "deeper") == 21.0


def test_an_unchanged_kernel_is_loaded_from_the_cache(tmp_path):
    _write(tmp_path / "caller.py", CALLER)
    _write(tmp_path / "callee.py", CALLEE.format(scale=0.0, factor=2.0))
    _run(tmp_path, "caller")
    cached = sorted(p.name for p in (tmp_path / "__pycache__").glob("*.nbi"))
    _run(tmp_path, "caller")
    assert sorted(p.name for p in (tmp_path / "__pycache__").glob("*.nbi")) == cached
    assert any(name.startswith("caller.outer") for name in cached), cached


EDITED_AFTER_IMPORT = """
import callee

with open(callee.__file__) as handle:
    text = handle.read()
with open(callee.__file__, "w") as handle:
    handle.write(text.replace("return 2.0 * x", "return 5.0 * x"))
print(callee.helper(3.0))
"""


def test_a_kernel_edited_after_its_module_was_imported_caches_the_code_that_ran(tmp_path):
    # A job imports the package, then compiles each kernel on its first call, seconds later: an
    # edit saved meanwhile must not file the machine code of the code as imported under the
    # edited source, where every later process would load it.
    _write(tmp_path / "callee.py", CALLEE.format(scale=0.0, factor=2.0))
    assert _python(tmp_path, EDITED_AFTER_IMPORT) == 6.0  # the code the process imported
    _write(tmp_path / "caller.py", "from callee import helper as outer\n")
    assert _run(tmp_path, "caller") == 15.0  # the code the file now holds
