"""``jointbench precompile``: every built-in method fitted by each path on trials that hold."""

from __future__ import annotations

import pytest

from jointbench.cli import main
from jointbench.estimators import registry
from jointbench.precompile import _PUBLIC_FIT, precompile, synthetic_trials


@pytest.mark.parametrize("kind", registry.KINDS)
def test_each_synthetic_trial_is_fitted_without_a_warning_by_every_method(kind):
    """The trials take the paths of an answer that holds: a warning would leave the kernels of
    the later checks uncompiled."""
    arrays = synthetic_trials()[kind]
    statuses = {m: _PUBLIC_FIT[kind](*arrays, method=m).status for m in registry.methods(kind)}
    assert statuses == dict.fromkeys(registry.methods(kind), "ok")


def test_precompile_fits_every_method_of_every_kind_once():
    fitted = [(kind, method) for kind, method, _ in precompile()]
    assert fitted == [(kind, m) for kind in registry.KINDS for m in registry.methods(kind)]


def test_the_command_names_every_method_it_compiled(capsys):
    assert main(["precompile"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[:2] for line in lines[:-1]] == [
        [kind, m] for kind in registry.KINDS for m in registry.methods(kind)
    ]
    assert lines[-1].startswith("compiled (or loaded from the cache) every method's kernels")
