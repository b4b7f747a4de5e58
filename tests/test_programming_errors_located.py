"""A programming error is located in the method's own code, wherever that code is installed and
whether or not it went wrong inside a compiled kernel.

A method installed as a package (in site-packages, beside the libraries) is still the method's
own code: the message names its line, and a ``ValueError`` its own ``raise`` statement states
is a failure of the data, not a bug. A kernel compiled by Numba leaves no frame of its own in a
traceback: the message names the kernel, says that it is compiled and how to find the line (its
Python form, ``kernel.__wrapped__``), and locates the error at the kernel's call in the method.
"""

from __future__ import annotations

import importlib
import inspect
import site
import sys
import textwrap

import numpy as np
import pytest
from test_cli import sphere_markers

import jointbench as jb
from jointbench import owncode
from jointbench.estimators import registry, sphere
from jointbench.estimators.batching import ProgrammingError
from jointbench.estimators.results import CenterResult
from jointbench.numerics.compiled import kernel

INSTALLED = "installed_estimator"

#: A method in a module of its own, as a user's installed package holds it.
SOURCE = textwrap.dedent(
    """
    import numpy as np

    from jointbench.estimators import register, sphere


    def _stacked(markers):
        return np.stack([markers[0], markers[0, :2]])  # the bug: rows of other lengths


    @register("center", "installed-bug", min_frames=4)
    def fit_with_bug(markers):
        _stacked(markers)
        return sphere.fit_ls(markers)


    @register("center", "installed-refusal", min_frames=4)
    def fit_refusing(markers):
        raise ValueError("the installed method finds no sphere")
    """
)


def _forget_classes() -> None:
    owncode._library_roots.cache_clear()
    owncode.own_code.cache_clear()


@pytest.fixture
def installed(tmp_path, monkeypatch):
    """The module :data:`SOURCE` imported from a folder the interpreter counts as one of its
    site-packages; its methods unregistered after the test."""
    packages = tmp_path / "lib" / "site-packages"
    packages.mkdir(parents=True)
    (packages / f"{INSTALLED}.py").write_text(SOURCE)
    listed = site.getsitepackages()
    monkeypatch.setattr(site, "getsitepackages", lambda: [*listed, str(packages)])
    monkeypatch.syspath_prepend(str(packages))
    _forget_classes()
    assert not owncode.own_code(str(packages / "other.py"))  # a library's folder, as installed
    module = importlib.import_module(INSTALLED)
    yield module
    for name in ("installed-bug", "installed-refusal"):
        registry.unregister("center", name)
    sys.modules.pop(INSTALLED, None)
    monkeypatch.undo()
    _forget_classes()


def _line(function, text: str) -> int:
    """The line of ``function``'s file that holds ``text``."""
    lines, first = inspect.getsourcelines(function)
    return first + next(i for i, line in enumerate(lines) if text in line)


def _mistake_of(method: str) -> str:
    """The message of the programming error that fitting ``method`` raises."""
    with pytest.raises(ProgrammingError) as raised:
        jb.fit_center(sphere_markers()[0], method)
    return str(raised.value)


def test_an_installed_methods_bug_is_located_in_its_own_code(installed):
    message = _mistake_of("installed-bug")
    where = f"at {installed.__file__}:{_line(installed._stacked, 'np.stack')}, in _stacked"
    assert where in message, message


def test_an_installed_methods_stated_failure_is_the_datas(installed):
    with pytest.raises(ValueError, match=r"^the installed method finds no sphere$") as raised:
        jb.fit_center(sphere_markers()[0], "installed-refusal")
    assert not isinstance(raised.value, ProgrammingError)


@kernel
def _summed(a, b):
    total = np.zeros(3)
    total += a + b  # the bug: a and b of other lengths
    return total


def _calls_the_kernel(markers: np.ndarray) -> CenterResult:
    flat = np.ascontiguousarray(markers.reshape(-1, 3))
    _summed(flat, flat[:2])
    return sphere.fit_ls(markers)


@pytest.fixture
def kernel_caller():
    registry.register("center", "kernel-bug", min_frames=4)(_calls_the_kernel)
    yield
    registry.unregister("center", "kernel-bug")


def test_a_bug_inside_a_compiled_kernel_names_the_kernel_and_its_call(kernel_caller):
    message = _mistake_of("kernel-bug")
    call = f"at {__file__}:{_line(_calls_the_kernel, '_summed(')}, in _calls_the_kernel"
    assert call in message, message
    assert "compiled.py" not in message, message  # not the wrapper that calls the machine code
    assert f"kernel {__name__}._summed" in message, message
    assert "_summed.__wrapped__" in message, message
    # As the message says: the Python form raises at the kernel's line.
    markers = sphere_markers()[0].reshape(-1, 3)
    with pytest.raises(ValueError, match="broadcast") as again:
        _summed.__wrapped__(markers, markers[:2])
    assert again.traceback[-1].lineno + 1 == _line(_summed.__wrapped__, "total += a + b")
