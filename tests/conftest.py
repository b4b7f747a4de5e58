"""Finished runs that the end-to-end suites share.

A reduced run of the built-in studies costs a minute of both cores, and the fourth study's run
a good part of one. Each is made once per session, in a work tree with its own copy of the
package, which its jobs import (``PYTHONPATH``), and handed out read only to the suites that
read a finished run (``test_pipeline.py``, ``test_fourth_study.py``) or ask it what an edit
makes stale (``test_stale_results.py``, whose every edit puts the file back as it was, times
included). A test that writes a file into a run (a report) writes into
:meth:`~workflow_copy.FinishedRun.copy`. At the end of the session each shared tree must be as
it was made: a test that left a change in one fails there.

Under ``pytest -n 2 --dist loadgroup`` every test of one run is in that run's group, so one
worker makes the run, once, and runs them one after another: the mutation suite edits its run
in place, which no other test may read meanwhile. A test that asks for the run by name
(``test_stale_results.py``) puts itself in the group; any other is put there at collection.
Without the groups each worker makes its own runs, in its own temporary directory: slower, and
as safe.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
import yaml
from workflow_copy import ROOT, FinishedRun, finish_run

from jointbench import papers
from jointbench.configuration import studies
from jointbench.estimators import registry

FOURTH_STUDY = ROOT / "tests" / "data" / "fourth_study"
#: A second extension, and its study's settings: one condition, one trial, one method.
SECOND_STUDY = ROOT / "tests" / "data" / "second_study.py"
#: A module of the user's own that the second extension imports: on the jobs' PYTHONPATH.
SECOND_HELPER = ROOT / "tests" / "data" / "second_helper.py"
SECOND_SETTINGS = {
    "trials": 1,
    "grid": {"marker_set": ["M"], "rom_deg": [45], "noise_mm": [0.5]},
    "estimators": ["NM"],
}
# The fixtures below: each names its run's pytest-xdist group.
SHARED_RUNS = frozenset({"reduced_run", "fourth_study_run"})
# The names under which jointbench.configuration.extensions imports an extension's file.
EXTENSION_MODULES = "jointbench_extension_"


def _state(workdir: Path) -> dict[str, tuple[int, int]]:
    """Size and modification time of every file of a work tree outside Snakemake's own
    records (which a dry run may touch)."""
    return {
        str(path.relative_to(workdir)): (path.stat().st_size, path.stat().st_mtime_ns)
        for path in workdir.rglob("*")
        if path.is_file() and ".snakemake" not in path.parts and "__pycache__" not in path.parts
    }


def _shared(run: FinishedRun):
    """Hand ``run`` out, then check that no test wrote into it."""
    before = _state(run.workdir)
    yield run
    after = _state(run.workdir)
    changed = sorted(
        name for name in before.keys() | after.keys() if before.get(name) != after.get(name)
    )
    assert not changed, f"a test wrote into the shared run (use FinishedRun.copy): {changed[:20]}"


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Put each test that uses a shared run in the group named after the run's fixture
    (before pytest-xdist reads the groups)."""
    for item in items:
        runs = SHARED_RUNS & set(item.fixturenames)
        # A test of two runs would be in a group of its own, beside the tests that edit them.
        assert len(runs) <= 1, f"{item.nodeid} uses two shared runs: {sorted(runs)}"
        for name in runs:
            item.add_marker(pytest.mark.xdist_group(name))


def _load(name: str) -> dict:
    return yaml.safe_load((ROOT / "tests" / "data" / name).read_text())


@pytest.fixture(scope="session")
def reduced_run(tmp_path_factory) -> FinishedRun:
    """The reduced grid of the built-in studies (``tests/data/reduced.yaml``), with the
    external LM rule of the default config, finished. Read only: write into a copy."""
    yield from _shared(finish_run(tmp_path_factory.mktemp("reduced_run"), _load("reduced.yaml")))


@pytest.fixture(scope="session")
def fourth_study_run(tmp_path_factory) -> FinishedRun:
    """The fourth study of ``tests/data/fourth_study`` without the built-in studies, its
    module loaded as an extension beside a second (``tests/data/second_study.py``), finished.
    Read only: write into a copy."""
    files = (*(FOURTH_STUDY / name for name in ("toy_study.py", "paper_t.yaml")), SECOND_STUDY)
    overlay = _load("fourth_study/toy.yaml")
    # Two extensions, each with a study: the order the config lists them in must rerun nothing
    # (test_stale_results.py). The second's study is one job of each kind.
    overlay["extensions"].append(SECOND_STUDY.name)
    overlay["studies"]["second"] = SECOND_SETTINGS
    workdir = tmp_path_factory.mktemp("fourth_study_run")
    yield from _shared(finish_run(workdir, overlay, files, (SECOND_HELPER,)))


@pytest.fixture
def forget_registrations(monkeypatch):
    """Registries of estimators, studies and papers that forget, at the test's end, what it
    registered, and the extensions it loaded in the test's process (whose estimators register
    as their module runs, so a later load must run it again): a method left registered would
    run in every later test of the process that runs all methods."""
    for entries in registry._REGISTRY.values():
        monkeypatch.setattr(entries, "_values", dict(entries._values))
    monkeypatch.setattr(studies._STUDIES, "_values", dict(studies._STUDIES._values))
    monkeypatch.setattr(papers._PAPERS, "_values", dict(papers._PAPERS._values))
    loaded = set(sys.modules)
    yield
    for name in set(sys.modules) - loaded:
        if name.startswith(EXTENSION_MODULES):
            del sys.modules[name]
