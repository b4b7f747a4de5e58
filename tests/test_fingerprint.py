"""Code fingerprints: every edit of what code does changes them, text alone does not.

Each case edits one file of a small package made for the test and compares the fingerprint of a
script that imports it before and after. ``tests/test_stale_results.py`` does the same through
Snakemake on the real workflow.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import json
import os
import platform
import site
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from jointbench import fingerprint
from jointbench.fingerprint import (
    MISSING,
    OnePass,
    check_bytecode_by_content,
    code_fingerprint,
    data_closure,
    dependency_versions,
    module_closure,
    source_digests,
)

PACKAGE = "jbfp_pkg"

FILES = {
    "__init__.py": '''
        """A package with a lazy name (PEP 562), as jointbench has."""
        import importlib
        from typing import TYPE_CHECKING

        if TYPE_CHECKING:
            from jbfp_pkg.typing_only import Hint

        _HOMES = {"lazy_value": "jbfp_pkg.lazy"}


        def __getattr__(name):
            return getattr(importlib.import_module(_HOMES[name]), name)
        ''',
    "core.py": '''
        """Shared code."""
        import functools
        from dataclasses import dataclass, field
        from pathlib import Path

        SCALE = 2.0
        LIMITS = Path(__file__).with_name("limits.yaml")
        LAYOUT = ((1.0, 2.0), (3.0, 4.0))


        @dataclass
        class Model:
            """A model."""

            offsets: tuple = field(default_factory=lambda: (0.0, 1.0))
            gain: float = 1.0

            @property
            def doubled(self):
                return 2 * self.gain

            @functools.cached_property
            def cached(self):
                return self.gain + 1

            @staticmethod
            def helper(x):
                return x + 1

            @classmethod
            def make(cls):
                return cls()


        def fit(x, *, tol=1e-4):
            """Fit ``x``."""
            # a comment
            from jbfp_pkg import inner

            return inner.step(x) * SCALE + tol
        ''',
    "inner.py": """
        def step(x):
            return x
        """,
    "unused.py": """
        def never_imported():
            return "unused.yaml"
        """,
    "limits.yaml": "low: 1\n",
    "unused.yaml": "low: 1\n",
    "sub/table.csv": "a,b\n1,2\n",
    "limits.yaml~": "low: 1\n",
    "__pycache__/core.nbi": "cache\n",
    "lazy.py": """
        lazy_value = 1
        """,
    "typing_only.py": """
        class Hint:
            pass
        """,
    "sub/__init__.py": """
        from .deep import deep_value
        """,
    "sub/deep.py": """
        deep_value = 1
        """,
}

SCRIPT = """
from jbfp_pkg import core
from jbfp_pkg.sub import deep_value
"""


@pytest.fixture
def package(tmp_path, monkeypatch) -> Path:
    root = tmp_path / "site"
    for name, text in FILES.items():
        path = root / PACKAGE / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text).lstrip())
    (tmp_path / "script.py").write_text(SCRIPT)
    monkeypatch.syspath_prepend(str(root))
    importlib.invalidate_caches()
    return root / PACKAGE


def _fingerprint(package: Path) -> str:
    return code_fingerprint(package.parent.parent / "script.py", package=PACKAGE)


CHANGES = [
    ("core.py", "SCALE = 2.0", "SCALE = 3.0"),
    ("core.py", "LAYOUT = ((1.0, 2.0)", "LAYOUT = ((1.0, 2.5)"),
    ("core.py", "lambda: (0.0, 1.0)", "lambda: (0.0, 2.0)"),
    ("core.py", "gain: float = 1.0", "gain: float = 1.5"),
    ("core.py", "return 2 * self.gain", "return 3 * self.gain"),
    ("core.py", "return self.gain + 1", "return self.gain + 2"),
    ("core.py", "return x + 1", "return x + 2"),
    ("core.py", "return cls()", "return cls(gain=2.0)"),
    ("core.py", "tol=1e-4", "tol=1e-3"),
    ("core.py", "* SCALE + tol", "* SCALE - tol"),
    ("inner.py", "return x", "return -x"),  # imported inside a function
    ("sub/deep.py", "deep_value = 1", "deep_value = 2"),  # through a relative import
    ("__init__.py", '"jbfp_pkg.lazy"}', '"jbfp_pkg.lazy", "other": "jbfp_pkg.lazy"}'),
]


@pytest.mark.parametrize("path, old, new", CHANGES, ids=[c[1] for c in CHANGES])
def test_an_edit_of_what_code_does_changes_the_fingerprint(package, path, old, new):
    before = _fingerprint(package)
    text = (package / path).read_text()
    assert old in text
    (package / path).write_text(text.replace(old, new))
    assert _fingerprint(package) != before


TEXT_ONLY = [
    ("core.py", '"""Fit ``x``."""', '"""Fit ``x``, better explained."""'),
    ("core.py", '"""A model."""', '"""A model, with more words."""'),
    ("core.py", "# a comment", "# another comment"),
    ("core.py", "SCALE = 2.0", "\n\nSCALE = (\n    2.0\n)"),
    ("unused.py", "return", "return 1 or"),  # no import of it can run
    ("typing_only.py", "pass", "x = 1"),  # imported only for type checkers
]


@pytest.mark.parametrize("path, old, new", TEXT_ONLY, ids=[c[2] for c in TEXT_ONLY])
def test_docstrings_comments_layout_and_unreachable_modules_do_not_count(package, path, old, new):
    before = _fingerprint(package)
    text = (package / path).read_text()
    assert old in text
    (package / path).write_text(text.replace(old, new))
    assert _fingerprint(package) == before


DATA = [
    ("limits.yaml", True),  # named by a module the script imports
    ("sub/table.csv", True),  # named by no module: counts with its package, which is imported
    ("unused.yaml", False),  # named only by a module no import of which can run
    ("limits.yaml~", False),  # an editor's backup
    ("__pycache__/core.nbi", False),  # a cache
]


@pytest.mark.parametrize("path, changes", DATA, ids=[d[0] for d in DATA])
def test_an_edit_of_package_data_changes_the_fingerprint_of_the_jobs_that_read_it(
    package, path, changes
):
    before = _fingerprint(package)
    (package / path).write_text((package / path).read_text() + "high: 2\n")
    # Dated before the first version, as a copy keeping time stamps can leave it.
    os.utime(package / path, ns=(0, 0))
    assert (_fingerprint(package) != before) is changes


def test_one_pass_gives_each_fingerprint_that_reading_anew_gives():
    """The workflow fingerprints every script in one pass, which reads each file once: each
    fingerprint is the one a call reading every file anew gives."""
    scripts = sorted((Path(__file__).resolve().parents[1] / "workflow" / "scripts").glob("*.py"))
    one_pass = OnePass()
    shared = [code_fingerprint(script, one_pass=one_pass) for script in scripts]
    assert shared == [code_fingerprint(script) for script in scripts]


@pytest.mark.parametrize("path, old, new", CHANGES[:1] + CHANGES[-3:], ids=lambda c: str(c)[:20])
def test_a_pass_sees_the_files_as_it_first_read_them_and_a_new_pass_sees_an_edit(
    package, path, old, new
):
    """A pass is one planning pass's view of the files: an edit after it read them is seen by
    a new pass and by a call without one, never by that pass."""
    script = package.parent.parent / "script.py"
    one_pass = OnePass()
    before = code_fingerprint(script, package=PACKAGE, one_pass=one_pass)
    text = (package / path).read_text()
    assert old in text
    (package / path).write_text(text.replace(old, new))
    assert code_fingerprint(script, package=PACKAGE, one_pass=one_pass) == before
    after = code_fingerprint(script, package=PACKAGE, one_pass=OnePass())
    assert after != before
    assert after == _fingerprint(package)


def test_a_pass_sees_a_data_file_edited_before_it_began(package):
    """Kept size and times do not hide an edit from a new pass: it reads the content."""
    data = package / "limits.yaml"
    script = package.parent.parent / "script.py"
    before = code_fingerprint(script, package=PACKAGE, one_pass=OnePass())
    stat = data.stat()
    data.write_text(data.read_text().replace("1", "7"))
    os.utime(data, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    assert data.stat().st_size == stat.st_size
    assert code_fingerprint(script, package=PACKAGE, one_pass=OnePass()) != before


def test_a_data_file_counts_where_a_module_that_names_it_counts(package):
    script = package.parent.parent / "script.py"
    assert set(data_closure(script, package=PACKAGE)) == {"limits.yaml", "sub/table.csv"}
    script.write_text(SCRIPT + f"from {PACKAGE} import unused\n")
    assert "unused.yaml" in data_closure(script, package=PACKAGE)


def test_every_workflow_job_counts_the_schemas_it_reads():
    """The published values' schema counts for the jobs that compare published values, not for
    the data jobs, which read only the config's."""
    scripts = Path(__file__).resolve().parents[1] / "workflow" / "scripts"
    simulate = set(data_closure(scripts / "simulate.py"))
    assert "schemas/config.schema.yaml" in simulate
    assert "schemas/published.schema.yaml" not in simulate
    check = set(data_closure(scripts / "check_published.py"))
    assert {"schemas/published.schema.yaml", "papers/paper_b.yaml"} <= check


def test_lazy_names_count_only_where_the_package_object_is_imported(package):
    script = package.parent.parent / "script.py"
    assert f"{PACKAGE}.lazy" not in module_closure(script, package=PACKAGE)
    script.write_text(SCRIPT + f"import {PACKAGE}\n")
    assert f"{PACKAGE}.lazy" in module_closure(script, package=PACKAGE)


def test_the_script_itself_counts(package):
    before = _fingerprint(package)
    script = package.parent.parent / "script.py"
    script.write_text(SCRIPT + "x = core.fit(1.0)\n")
    assert _fingerprint(package) != before


def test_every_workflow_script_reaches_the_modules_it_runs():
    scripts = Path(__file__).resolve().parents[1] / "workflow" / "scripts"
    estimate = module_closure(scripts / "estimate.py")
    assert {"jointbench.estimators.sphere", "jointbench.numerics.compiled"} <= set(estimate)
    assert "jointbench.figures.common" not in estimate
    render = module_closure(scripts / "render.py")
    assert {"jointbench.figures.paper_a", "jointbench.papers.paper_b"} <= set(render)


def test_modules_found_by_a_registry_are_in_the_fingerprint():
    """The study and paper registries import every module of their packages by name; an edit
    of any of them reruns the jobs that load the registry."""
    scripts = Path(__file__).resolve().parents[1] / "workflow" / "scripts"
    simulate = set(module_closure(scripts / "simulate.py"))
    assert {"jointbench.simulate.hip_sta", "jointbench.simulate.cmc"} <= simulate
    render = set(module_closure(scripts / "render.py"))
    assert {"jointbench.papers.paper_sta", "jointbench.papers.paper_c"} <= render


def test_numbas_code_generator_is_recorded_as_a_dependency():
    # One Numba release allows several of llvmlite's, each with its own LLVM.
    assert dependency_versions()["llvmlite"] == importlib.metadata.version("llvmlite")


def test_the_c_library_is_recorded_as_a_dependency():
    # Numba's kernels and NumPy call the C library's libm (acos, atan2, exp, ...), whose
    # releases differ in the last bits of some results.
    library, version = platform.libc_ver()
    if not library:
        pytest.skip("libc_ver cannot tell this C library (the tests below cover macOS's)")
    assert dependency_versions()["libc"] == f"{library} {version}"


def test_another_c_library_changes_the_fingerprint(monkeypatch):
    script = Path(__file__).resolve().parents[1] / "workflow" / "scripts" / "estimate.py"
    before = code_fingerprint(script)
    monkeypatch.setattr(platform, "libc_ver", lambda *args, **kwargs: ("glibc", "1.0"))
    fingerprint._c_library.cache_clear()
    try:
        assert code_fingerprint(script) != before
    finally:
        fingerprint._c_library.cache_clear()


@pytest.mark.parametrize("release", ["14.1", "14.2"])
def test_on_macos_the_systems_release_stands_for_its_c_library(monkeypatch, release):
    # libc_ver cannot tell macOS's C library (libSystem, which holds its libm): it comes with
    # the system, and a system update that changes it changes the fingerprint.
    monkeypatch.setattr(platform, "libc_ver", lambda *args, **kwargs: ("", ""))
    monkeypatch.setattr(platform, "mac_ver", lambda *args: (release, ("", "", ""), "arm64"))
    fingerprint._c_library.cache_clear()
    try:
        assert dependency_versions()["libc"] == f"macOS {release}"
    finally:
        fingerprint._c_library.cache_clear()


def test_a_c_library_python_cannot_tell_is_named_unknown(monkeypatch):
    monkeypatch.setattr(platform, "libc_ver", lambda *args, **kwargs: ("", ""))
    monkeypatch.setattr(platform, "mac_ver", lambda *args: ("", ("", "", ""), ""))
    fingerprint._c_library.cache_clear()
    try:
        assert dependency_versions()["libc"] == "unknown"
    finally:
        fingerprint._c_library.cache_clear()


def test_a_compilers_version_is_its_first_line_and_none_is_named(tmp_path, monkeypatch):
    compiler = tmp_path / "mycc"
    compiler.write_text("#!/bin/sh\necho 'mycc (Lab) 12.2.0'\necho 'Copyright'\n")
    compiler.chmod(0o755)
    monkeypatch.setenv("PATH", f"{tmp_path}{os.pathsep}{os.environ['PATH']}")
    assert fingerprint.compiler_version("mycc") == "mycc (Lab) 12.2.0"
    assert fingerprint.compiler_version("no-such-compiler-here") == "not found"


def test_an_upgraded_dependency_changes_the_fingerprint(monkeypatch):
    script = Path(__file__).resolve().parents[1] / "workflow" / "scripts" / "estimate.py"
    versions = dependency_versions()
    assert {"python", "numpy", "scipy", "numba"} <= set(versions)
    before = code_fingerprint(script)
    monkeypatch.setattr(
        fingerprint, "dependency_versions", lambda package: {**versions, "numpy": "0.0.1"}
    )
    assert code_fingerprint(script) != before


def _startup_site(monkeypatch, tmp_path, own_name: str = "own") -> tuple[Path, Path]:
    """A site folder that alone holds the ``.pth`` files read at start-up, and a folder of the
    user's own modules on the path, both new in ``tmp_path``."""
    folder, own = tmp_path / "site-packages", tmp_path / own_name
    folder.mkdir()
    own.mkdir()
    monkeypatch.setattr(site, "getsitepackages", lambda *_: [str(folder)])
    monkeypatch.setattr(site, "ENABLE_USER_SITE", False)
    monkeypatch.syspath_prepend(str(own))
    return folder, own


# Python's site runs, at start-up of every process, each line of the .pth files of the site
# folders that starts with ``import``: such a line changes what every job imports, as a
# sitecustomize does. A line naming a folder only puts it on the path, where the modules a job
# imports are found and read by content wherever they are.
def test_the_code_a_pth_file_runs_at_start_up_counts_by_content(monkeypatch, tmp_path):
    folder, own = _startup_site(monkeypatch, tmp_path)
    script = Path(__file__).resolve().parents[1] / "workflow" / "scripts" / "estimate.py"
    before = code_fingerprint(script)
    pth = folder / "lab.pth"
    pth.write_text(f"# a comment\n{own}\n\n")
    assert code_fingerprint(script) == before, "a comment or a path line counted"
    pth.write_text("import os; os.environ.setdefault('OMP_NUM_THREADS', '1')\n")
    hooked = code_fingerprint(script)
    assert hooked != before, "the code a .pth file runs left out"
    os.utime(pth, ns=(946_684_800 * 10**9,) * 2)
    assert code_fingerprint(script) == hooked, "a time stamp counted"
    (folder / "a-first.pth").write_text("import os\n")
    first = code_fingerprint(script)
    assert first not in (before, hooked)
    assert code_fingerprint(script) == first, "not the same from one call to the next"
    pth.write_text("import os; os.environ.setdefault('OMP_NUM_THREADS', '2')\n")
    assert code_fingerprint(script) != first
    # A module of the user's that such a line imports counts by its code, as a job's file does.
    (own / "labstart.py").write_text("SCALE = 1.0\n")
    pth.write_text("import labstart\n")
    started = code_fingerprint(script)
    (own / "labstart.py").write_text("SCALE = 2.0\n")
    assert code_fingerprint(script) != started, "a module a .pth line imports left out"


@pytest.mark.parametrize(
    ("name", "text", "edited", "changes"),
    [
        ("paper.yaml", "published: 8.0\n", "published: 80.0\n", True),
        ("fit.c", "int main(void) { return 0; }\n", "int main(void) { return 1; }\n", True),
        ("fit.py", "x = 1\n", "x = 2\n", True),
        ("fit.py", '"""Fit."""\nx = 1\n', '"""Fit a sphere."""\n\nx = 1  # one\n', False),
    ],
    ids=["data", "C source", "Python code", "Python docstring and layout"],
)
def test_a_source_digest_follows_the_content_not_the_time_stamp(
    tmp_path, name, text, edited, changes
):
    path = tmp_path / name
    path.write_text(text)
    before = source_digests([path])
    path.write_text(edited)
    # Dated before the first version, as a copy keeping time stamps can leave it.
    os.utime(path, ns=(0, 0))
    assert (source_digests([path]) != before) is changes


def test_a_missing_source_and_a_folder_have_digests(tmp_path):
    folder = tmp_path / "overlays"
    folder.mkdir()
    (folder / "a.yaml").write_text("a: 1\n")
    before = source_digests([folder, tmp_path / "absent.yaml"])
    assert before[str(tmp_path / "absent.yaml")] == MISSING
    (folder / "a.yaml").write_text("a: 2\n")
    assert source_digests([folder])[str(folder)] != before[str(folder)]


def _imported_value(folder: Path) -> str:
    """``lab.VALUE`` as a new process imports it from ``folder``, writing bytecode as Python
    does by default."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPATH"] = str(folder)
    code = "import lab; print(lab.VALUE)"
    ran = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert ran.returncode == 0, ran.stderr
    return ran.stdout.strip()


def test_an_edit_that_keeps_size_and_time_is_imported_once_the_bytecode_is_checked(tmp_path):
    module = tmp_path / "lab.py"
    module.write_text("VALUE = 1.0\n")
    assert _imported_value(tmp_path) == "1.0"  # its bytecode cached, by size and time
    stat = module.stat()
    module.write_text("VALUE = 2.0\n")
    os.utime(module, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    assert _imported_value(tmp_path) == "1.0"  # what Python does alone: the old bytecode
    check_bytecode_by_content(module)
    assert _imported_value(tmp_path) == "2.0"
    module.write_text("VALUE = 3.0\n")
    os.utime(module, ns=(stat.st_atime_ns, stat.st_mtime_ns))
    assert _imported_value(tmp_path) == "3.0"  # and it stays checked by content


# The store of parsed summaries (``JOINTBENCH_CACHE``): each Snakemake process reads it instead
# of parsing the package again. Each case runs fresh processes, as Snakemake does, so that
# nothing comes from one process's memory.
_PRINT_FINGERPRINT = (
    "import sys; from jointbench.fingerprint import code_fingerprint; "
    "print(code_fingerprint(sys.argv[1], package=sys.argv[2]))"
)


def _fingerprint_in_a_new_process(package: Path, store: Path | str) -> str:
    return _in_a_new_process(package, store, _PRINT_FINGERPRINT)


def _new_process(package: Path, store: Path | str, code: str, *args: str):
    """The environment and command of a new process running ``code`` on the test's script."""
    environment = {
        **os.environ,
        "JOINTBENCH_CACHE": str(store),
        "PYTHONPATH": os.pathsep.join(
            [str(package.parent), str(Path(fingerprint.__file__).parents[1])]
        ),
    }
    script = package.parent.parent / "script.py"
    return environment, [sys.executable, "-c", code, str(script), PACKAGE, *args]


def _in_a_new_process(package: Path, store: Path | str, code: str, *args: str) -> str:
    """What a new process running ``code`` prints (:func:`_new_process`)."""
    environment, command = _new_process(package, store, code, *args)
    done = subprocess.run(command, capture_output=True, text=True, env=environment, check=True)
    return done.stdout.strip()


def _entries(store: Path) -> list[Path]:
    return sorted(store.rglob("*.json"))


def test_a_stored_summary_gives_the_fingerprint_parsing_gives(package, tmp_path):
    store = tmp_path / "store"
    parsed = _fingerprint_in_a_new_process(package, "off")
    assert _fingerprint_in_a_new_process(package, store) == parsed  # writes the store
    written = _entries(store)
    assert written and not list(store.rglob("*.tmp"))
    assert _fingerprint_in_a_new_process(package, store) == parsed  # reads it
    assert _entries(store) == written
    # What the second process used was the store: a summary altered there counts instead.
    for entry in written:
        stored = json.loads(entry.read_text())
        stored["digest"] = "0" * 64 if stored["digest"] != "0" * 64 else "1" * 64
        entry.write_text(json.dumps(stored))
    assert _fingerprint_in_a_new_process(package, store) != parsed


@pytest.mark.parametrize("path, old, new", CHANGES[:3] + CHANGES[-3:], ids=lambda c: str(c)[:20])
def test_an_edit_is_seen_through_a_warm_store(package, tmp_path, path, old, new):
    store = tmp_path / "store"
    before = _fingerprint_in_a_new_process(package, store)
    (package / path).write_text((package / path).read_text().replace(old, new))
    after = _fingerprint_in_a_new_process(package, store)
    assert after != before
    assert after == _fingerprint_in_a_new_process(package, "off")


@pytest.mark.parametrize(
    "damage",
    [
        b"",
        b"{",
        b'{"digest": "00"}',
        b"\x00\xff",
        b'{"digest": 1, "imports": 2, "dynamic_calls": 3, "every": 4, "strings": 5}',
        b'{"digest": "xyz", "imports": [], "dynamic_calls": false, "every": [], "strings": []}',
        b'{"digest": "' + b"0" * 64 + b'", "imports": [["from", 1]], "dynamic_calls": false, '
        b'"every": [], "strings": []}',
    ],
    ids=["empty", "cut", "missing keys", "not text", "wrong types", "not hex", "short import"],
)
def test_a_damaged_store_entry_is_parsed_again(package, tmp_path, damage):
    store = tmp_path / "store"
    parsed = _fingerprint_in_a_new_process(package, store)
    for entry in _entries(store):
        entry.write_bytes(damage)
    assert _fingerprint_in_a_new_process(package, store) == parsed


def test_a_store_that_cannot_be_written_only_costs_time(package, tmp_path):
    blocked = tmp_path / "a file, not a folder"
    blocked.write_text("")
    assert _fingerprint_in_a_new_process(package, blocked) == _fingerprint_in_a_new_process(
        package, "off"
    )


def test_the_store_is_kept_apart_per_python_and_per_version_of_the_rules(monkeypatch, tmp_path):
    monkeypatch.setenv("JOINTBENCH_CACHE", str(tmp_path))
    here = fingerprint._store()
    assert here.parent == tmp_path / "fingerprint"
    monkeypatch.setattr(fingerprint.sys, "version", sys.version + " (another build)")
    fingerprint._namespace.cache_clear()
    try:
        assert fingerprint._store() != here
    finally:
        fingerprint._namespace.cache_clear()


# The store's housekeeping: once a day the first process prunes it. What it removes is found
# again by parsing, so every case checks that the fingerprint stays the one parsing gives.
_DAY = 24 * 3600


def _aged(path: Path, seconds: float) -> Path:
    """``path`` with its time stamps set ``seconds`` into the past."""
    then = time.time() - seconds
    os.utime(path, (then, then))
    return path


def _warm(package: Path, store: Path) -> tuple[str, Path]:
    """The fingerprint parsing gives, and the namespace folder of a store warmed by a process
    whose daily prune is due again in the next."""
    parsed = _fingerprint_in_a_new_process(package, "off")
    assert _fingerprint_in_a_new_process(package, store) == parsed
    (namespace,) = (store / "fingerprint").iterdir()
    _aged(namespace / fingerprint._STAMP, 2 * _DAY)
    return parsed, namespace


def test_a_killed_writers_temporary_file_is_removed_once_stale(package, tmp_path):
    store = tmp_path / "store"
    parsed, namespace = _warm(package, store)
    stale = namespace / "tmpk1ll3d_0.tmp"
    stale.write_text('{"dig')
    _aged(stale, 3600)
    fresh = namespace / "tmpwr1t1ng.tmp"
    fresh.write_text('{"dig')
    assert _fingerprint_in_a_new_process(package, store) == parsed
    assert not stale.exists()
    assert fresh.exists()  # another process may be writing it


def test_the_store_is_pruned_at_most_once_a_day(package, tmp_path):
    store = tmp_path / "store"
    parsed, namespace = _warm(package, store)
    assert _fingerprint_in_a_new_process(package, store) == parsed  # prunes
    stale = namespace / "tmpk1ll3d_0.tmp"
    stale.write_text("")
    _aged(stale, 3600)
    assert _fingerprint_in_a_new_process(package, store) == parsed
    assert stale.exists()  # left to the next day's prune


def test_the_namespaces_of_other_versions_unused_for_a_month_are_removed(package, tmp_path):
    store = tmp_path / "store"
    parsed, namespace = _warm(package, store)
    folders = {}
    for name, age in (("0123456789abcdef", 40), ("fedcba9876543210", 20), ("notes", 40)):
        folder = store / "fingerprint" / name
        folder.mkdir()
        (folder / f"{'a' * 64}.json").write_text("{}")
        folders[name] = _aged(folder, age * _DAY)
    _aged(namespace, 40 * _DAY)  # the current one is used now
    assert _fingerprint_in_a_new_process(package, store) == parsed
    assert not folders["0123456789abcdef"].exists()
    assert folders["fedcba9876543210"].exists()  # used within the month
    assert folders["notes"].exists()  # not the store's own
    assert namespace.exists() and time.time() - namespace.stat().st_mtime < _DAY


def test_entries_unused_for_a_month_are_removed_and_used_ones_kept(package, tmp_path):
    store = tmp_path / "store"
    parsed, namespace = _warm(package, store)
    used = _entries(store)
    for entry in used:
        _aged(entry, 2 * _DAY)
    unused = namespace / f"{'b' * 64}.json"
    unused.write_text(used[0].read_text())
    _aged(unused, 40 * _DAY)
    other = namespace / "notes.json"
    other.write_text("{}")
    _aged(other, 40 * _DAY)
    assert _fingerprint_in_a_new_process(package, store) == parsed
    assert not unused.exists()
    assert other.exists()  # not an entry
    # An entry read is marked as used: its time stamp is renewed, at most once a day.
    assert _entries(store) == sorted([*used, other])
    assert all(time.time() - entry.stat().st_mtime < _DAY for entry in used)
    # Unused for a month, they are removed before they are read: what they say does not count.
    for entry in used:
        stored = json.loads(entry.read_text())
        entry.write_text(json.dumps({**stored, "digest": "0" * 64}))
        _aged(entry, 40 * _DAY)
    _aged(namespace / fingerprint._STAMP, 2 * _DAY)
    assert _fingerprint_in_a_new_process(package, store) == parsed
    assert _entries(store) == sorted([*used, other])


_FINGERPRINT_AS_ANOTHER_PROCESS_PRUNES = """
import shutil, sys
from jointbench import fingerprint
read = fingerprint._read_entry

def pruned_meanwhile(entry):
    # Another process removes the folder, or the entry, right before this one reads it.
    if sys.argv[3] == "folder":
        shutil.rmtree(entry.parent, ignore_errors=True)
    else:
        entry.unlink(missing_ok=True)
    return read(entry)

fingerprint._read_entry = pruned_meanwhile
print(fingerprint.code_fingerprint(sys.argv[1], package=sys.argv[2]))
"""


@pytest.mark.parametrize("what", ["folder", "entry"])
def test_a_prune_by_another_process_meanwhile_only_costs_time(package, tmp_path, what):
    store = tmp_path / "store"
    parsed, _ = _warm(package, store)
    done = _in_a_new_process(package, store, _FINGERPRINT_AS_ANOTHER_PROCESS_PRUNES, what)
    assert done == parsed
    assert _fingerprint_in_a_new_process(package, store) == parsed


def test_processes_starting_at_once_get_the_fingerprint(package, tmp_path):
    """Two Snakemake jobs starting together: each may prune what the other reads or writes."""
    store = tmp_path / "store"
    parsed, namespace = _warm(package, store)
    for entry in [*_entries(store), namespace]:
        _aged(entry, 40 * _DAY)  # everything due for removal
    _aged(namespace / fingerprint._STAMP, 2 * _DAY)
    environment, command = _new_process(package, store, _PRINT_FINGERPRINT)
    running = [
        subprocess.Popen(command, stdout=subprocess.PIPE, text=True, env=environment)
        for _ in range(4)
    ]
    assert [process.communicate()[0].strip() for process in running] == [parsed] * 4
    assert all(process.returncode == 0 for process in running)
    assert _fingerprint_in_a_new_process(package, store) == parsed


# A lab's own modules that an extension imports: beside it, in a package on PYTHONPATH, installed
# in editable mode. Each case runs fresh processes, with the paths and import hooks a job has.
_LAB = {
    # Run at start-up by every process with lab/ on its path, before any script.
    "lab/sitecustomize.py": """
        _HOOKED = 1
        """,
    "ext/mine.py": """
        import json

        import numpy as np
        from helper import centre
        from labpkg.core import scale
        from labpkg.loader import load
        import labedit
        import labhook.tools

        from jointbench.estimators.results import CenterResult
        """,
    "ext/helper.py": """
        from helper2 import offset

        def centre(m):
            return m.mean(axis=0) + offset()
        """,
    "ext/helper2.py": """
        import jointbench.uncertainty

        def offset():
            return 0.0
        """,
    "ext/unrelated.py": """
        x = 1
        """,
    "lab/labpkg/__init__.py": "",
    "lab/labpkg/core.py": """
        from . import units

        def scale(x):
            return x * units.MM
        """,
    "lab/labpkg/units.py": """
        MM = 1.0
        """,
    "lab/labpkg/unused.py": """
        x = 1
        """,
    # Imports by name at run time: a constant name, and a name built on a package's.
    "lab/labpkg/loader.py": """
        import importlib

        PLUGIN = importlib.import_module("labplug")


        def load(name):
            return importlib.import_module(f"labpkg.methods.{{name}}")
        """,
    "lab/labplug.py": """
        PLUGGED = 1
        """,
    "lab/labpkg/methods/__init__.py": "",
    "lab/labpkg/methods/sphere.py": """
        def fit(m):
            return m
        """,
    # ``pip install -e`` of a lab library: a path added by a .pth file (the legacy form) ...
    "editable/labedit/__init__.py": """
        GAIN = 1.0
        """,
    "site/__editable__.labedit-0.1.pth": "{root}/editable\n",
    # ... and setuptools' import hook, which maps the name to the source folder.
    "hooked/labhook/__init__.py": "",
    "hooked/labhook/tools.py": """
        TOOL = 1.0
        """,
    "site/__editable__.labhook-0.1.pth": "import __editable___labhook_finder; "
    "__editable___labhook_finder.install()\n",
    "site/__editable___labhook_finder.py": """
        import importlib.util
        import sys

        MAPPING = {{"labhook": "{root}/hooked/labhook"}}


        class Finder:
            @classmethod
            def find_spec(cls, fullname, path=None, target=None):
                if fullname in MAPPING:
                    init = MAPPING[fullname] + "/__init__.py"
                    return importlib.util.spec_from_file_location(
                        fullname, init, submodule_search_locations=[MAPPING[fullname]]
                    )
                return None


        def install():
            sys.meta_path.append(Finder)
        """,
}

# Prints the fingerprint of a script and the extension, and the files read for it (JSON).
_LAB_FINGERPRINT = """
import json, site, sys
site.addsitedir(sys.argv[3])
from jointbench import fingerprint
read, files = fingerprint._read, []

def recorded(path):
    files.append(str(path))
    return read(path)

fingerprint._read = recorded
code = fingerprint.code_fingerprint(sys.argv[1], sys.argv[2])
print(json.dumps({"code": code, "read": files}))
"""


@pytest.fixture
def lab(tmp_path) -> Path:
    for name, text in _LAB.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(textwrap.dedent(text.format(root=tmp_path)).lstrip())
    (tmp_path / "script.py").write_text("from jointbench.estimators import register\n")
    return tmp_path


def _lab_fingerprint(lab: Path) -> dict:
    environment = {
        **os.environ,
        "JOINTBENCH_CACHE": str(lab / "store"),
        "PYTHONPATH": os.pathsep.join(
            [str(lab / "lab"), str(Path(fingerprint.__file__).parents[1])]
        ),
    }
    command = [
        sys.executable,
        "-c",
        _LAB_FINGERPRINT,
        str(lab / "script.py"),
        str(lab / "ext/mine.py"),
        str(lab / "site"),
    ]
    done = subprocess.run(command, capture_output=True, text=True, env=environment, check=True)
    return json.loads(done.stdout)


LAB_EDITS = [
    ("ext/helper.py", True),  # beside the extension
    ("ext/helper2.py", True),  # imported by that helper
    ("lab/labpkg/core.py", True),  # a package on PYTHONPATH
    ("lab/labpkg/units.py", True),  # by a relative import in it
    ("lab/labplug.py", True),  # imported by a constant name at run time
    ("lab/labpkg/methods/sphere.py", True),  # by a name built on its package's
    ("editable/labedit/__init__.py", True),  # installed in editable mode, by a .pth path
    ("hooked/labhook/tools.py", True),  # installed in editable mode, by an import hook
    ("lab/sitecustomize.py", True),  # imported by name by Python's site at start-up
    ("ext/unrelated.py", False),
    ("lab/labpkg/unused.py", False),
]


@pytest.mark.parametrize("path, changes", LAB_EDITS, ids=[e[0] for e in LAB_EDITS])
def test_an_edit_of_a_lab_module_an_extension_imports_changes_the_fingerprint(lab, path, changes):
    before = _lab_fingerprint(lab)["code"]
    (lab / path).write_text((lab / path).read_text() + "\n_EDITED = 2\n")
    assert (_lab_fingerprint(lab)["code"] != before) is changes


def test_the_standard_library_and_installed_distributions_are_not_read(lab):
    import sysconfig

    read = [Path(p).resolve() for p in _lab_fingerprint(lab)["read"]]
    assert (lab / "ext/helper2.py").resolve() in read
    # What a lab's module imports of the package counts, as what the extension imports does.
    assert Path(fingerprint.__file__).with_name("uncertainty.py").resolve() in read
    installed = [
        Path(sysconfig.get_paths()[key]).resolve() for key in ("stdlib", "purelib", "platlib")
    ]
    assert not [p for p in read if any(p.is_relative_to(folder) for folder in installed)]


def test_a_python_sources_digests_follow_its_own_imports(tmp_path):
    """An external estimator's script is a source: a module of the user's it imports, beside
    it, changes what it does as surely as its own lines."""
    script = tmp_path / "estimate.py"
    script.write_text("from helper import SHIFT\n\nprint(SHIFT)\n")
    helper = tmp_path / "helper.py"
    helper.write_text("SHIFT = 1\n")
    before = source_digests([script])
    helper.write_text("SHIFT = 2\n")
    assert source_digests([script]) != before


def test_inputs_left_out_of_the_code_must_be_named_as_the_packages_data_files():
    """The files left out of the code are named by their paths in the package (data_names):
    a path given as a file's own (absolute) would leave nothing out, and is refused naming it."""
    script = Path(__file__).resolve().parents[1] / "workflow" / "scripts" / "render.py"
    published = Path(fingerprint.__file__).parent / "papers" / "paper_a.yaml"
    assert code_fingerprint(script, inputs=["papers/paper_a.yaml"]) != code_fingerprint(script)
    with pytest.raises(ValueError, match=r"paper_a\.yaml.* no data file of the package"):
        code_fingerprint(script, inputs=[str(published)])
    with pytest.raises(ValueError, match=r"'papers/paper_z\.yaml'.* no data file of the package"):
        code_fingerprint(script, inputs=["papers/paper_z.yaml"])


# A checkout moved or cloned again elsewhere reruns nothing: where a job's script lies beside
# the user's own start-up module (one a .pth line imports, or a sitecustomize) is no change.
def test_the_fingerprint_does_not_depend_on_where_the_checkout_lies(monkeypatch, tmp_path):
    folder, own = _startup_site(monkeypatch, tmp_path, "m-own")
    (own / "labstart.py").write_text("SCALE = 1.0\n")
    (folder / "lab.pth").write_text("import labstart\n")
    script = Path(__file__).resolve().parents[1] / "workflow" / "scripts" / "estimate.py"
    prints = set()
    for checkout in ("a-clone", "z-clone"):
        (tmp_path / checkout).mkdir()
        moved = tmp_path / checkout / script.name
        moved.write_bytes(script.read_bytes())
        prints.add(code_fingerprint(moved))
    assert len(prints) == 1, "a checkout's folder counted"


# A .pth line may import by a call, as setuptools' own does (``__import__('_distutils_hack')``):
# the user's module it names runs in every job as surely as one an import statement names.
@pytest.mark.parametrize(
    "line",
    [
        "import os; __import__('labstart').setup()",
        "import importlib; importlib.import_module('labstart.hooks')",
    ],
)
def test_a_module_a_pth_line_imports_by_a_call_counts_by_content(monkeypatch, tmp_path, line):
    folder, own = _startup_site(monkeypatch, tmp_path)
    (own / "labstart").mkdir()
    (folder / "lab.pth").write_text(line + "\n")
    script = Path(__file__).resolve().parents[1] / "workflow" / "scripts" / "estimate.py"
    module = own / "labstart" / "__init__.py"
    module.write_text("SCALE = 1.0\n")
    before = code_fingerprint(script)
    module.write_text("SCALE = 2.0\n")
    assert code_fingerprint(script) != before, "a module a .pth line imports by a call left out"
