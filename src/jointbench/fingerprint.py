"""A fingerprint of the code behind a result: what makes an edited library rerun its jobs.

Snakemake reruns a job when its parameters change, but the library lives in an installed
package it does not track. Each job is therefore given a parameter ``code``: the hash of the
source of its workflow script and of every module of the package that the script can import,
found by reading import statements, never by following objects at run time. The rule is
conservative by construction: a module counts if an import of it is written anywhere that can
run, whether or not the job calls into it. What is hashed is each file's syntax tree without
docstrings, so a change to what code does reruns its jobs, and a docstring, a comment or
formatting does not. The versions of Python and of the package's dependencies count too.

Files a job reads that no job writes (published values, an external estimator's program or
script, a config overlay) are its sources: Snakemake judges an input by its time stamp, which a
copy that keeps times (``cp -p``, ``rsync -a``, ``tar x``) can set back. Each job is therefore
also given a parameter ``sources``, the digest of every such file's content
(:func:`source_digests`): a Python file by its syntax tree as above, any other file byte for byte.

What a module can import:

* every ``import`` and ``from … import`` statement in it, at module level or inside a function
  (those under ``if TYPE_CHECKING:`` never run and do not count), with the parent packages of
  what it names;
* in a module that imports by name at run time (``importlib.import_module``,
  ``importlib.resources.files``), every string constant that names a module of the package,
  and every module of a package whose name, dot included, starts a string constant (the
  constant part of a name built at run time, ``import_module(f"lab.methods.{name}")``); a
  name taken whole from data (a config value) cannot be known. A package's ``__init__`` of
  that kind (PEP 562 lazy names) is followed that far only where the package object itself
  is imported (``import jointbench``, ``from jointbench import fit_center``): importing one
  of its submodules runs the ``__init__`` but cannot reach its lazy names;
* in a module that calls ``submodules("jointbench.<package>")`` (:mod:`jointbench.registries`:
  the study and paper registries import every module of their package), every module of that
  package.

A job's files (its script, the extensions it loads) can also import modules of the user's own,
neither the standard library's nor an installed distribution's: a helper beside an extension, a
lab's package on ``PYTHONPATH``, one installed in editable mode (``pip install -e``: its version
does not change when it is edited). Those are followed by the same rules, transitively, and
hashed by their syntax trees like the package's modules, with every module of the package and
data file they can reach in turn (:func:`own_closure`). A module name is looked up as an import
in that file would (beside the file first, then ``sys.path`` and the import system's finders,
an editable install's hook among them) without running anything; a module found in the folders
of the standard library or of installed distributions is not read (Python's version, and the
package's dependencies' versions, stand for it; the version of a distribution the package does
not depend on is not recorded). A module imported only by a name taken whole from data must be
listed under ``extensions`` itself to count. The start-up modules ``site`` imports in every
process (``sitecustomize``, ``usercustomize``), when they are the user's own, count as a job's
files do (:func:`_site_hooks`); so do the lines of code (``import …``) of the ``.pth`` files in
the site folders, which ``site`` runs at start-up too, by content, with the user's own modules
they import (:func:`_startup_lines`). A ``.pth`` line naming a folder is not counted: it puts the
folder on the path, where the modules a job imports from it are found and read as above.

The package's data files (its schemas, published values: every file in its folders that is not
a Python module, caches and editors' leftovers aside) count like its modules, byte for byte. A
data file counts for a job when a module the job can import names it: a string constant whose
last path component is the file's name (``files("jointbench.schemas").joinpath(
"published.schema.yaml")``, ``Path(__file__).with_name("paper_b.yaml")``). A data file that no
module names (read by a name built at run time, or not read at all) counts wherever the package
whose folder holds it counts: a job that can import that package's modules can read it. Data
files the caller tracks as inputs of exactly the jobs that read them are left out
(:func:`code_fingerprint`'s ``inputs``): the workflow does so with the papers' published values.

What is read of each file's syntax tree is stored by the hash of its text (``$JOINTBENCH_CACHE``,
by default ``~/.cache/jointbench``; ``off`` stores nothing), so that a new process does not
parse the package again: an entry is found only for the same text, parsed by the same Python
under the same version of this module, and one that cannot be read is parsed again.

The store keeps itself tidy, best-effort and never at the cost of a right fingerprint: what it
removes is only parsed again. Once a day (a stamp file, ``.pruned``, in the folder of the
current Python and version of this module, says when it was last done) the first process to use
the store removes, in that folder, the temporary files of writers killed before they finished
(older than ten minutes: a fresh one may still be being written) and the entries no process
read for 30 days; and, beside it, the folders of other Pythons and versions of this module not
used for 30 days (by their time stamp, which that daily pass renews, as writing an entry does).
A process marks an entry it reads as used by renewing its time stamp, at most once a day per
entry, so a warm store costs a process one ``stat`` more than before. A store that cannot be
written is not pruned; one that another process prunes meanwhile, two jobs starting at once,
only misses what that process removed.
"""

from __future__ import annotations

import ast
import hashlib
import importlib.metadata
import importlib.util
import json
import os
import pkgutil
import platform
import py_compile
import re
import shutil
import site
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from functools import cache
from importlib.machinery import PathFinder
from pathlib import Path, PurePosixPath
from typing import Protocol

import yaml

# The folders whose modules are not a user's own: the rule the kernels' cache digest reads too.
from jointbench.owncode import _library_roots

__all__ = [
    "MISSING",
    "OnePass",
    "check_bytecode_by_content",
    "code_fingerprint",
    "compiler_version",
    "data_closure",
    "data_names",
    "dependency_versions",
    "module_closure",
    "numba_jit_disabled",
    "own_closure",
    "source_digests",
]

#: The package whose code is fingerprinted by default: this module's own. Not written as a
#: string: this module imports by name at run time, so a string naming the package would put
#: its lazy names (PEP 562) in the fingerprint of every job, all of which import this module
#: (:mod:`jointbench.jobs` checks the planned fingerprint with it).
PACKAGE = __name__.partition(".")[0]

#: Calls that import a module named by a string at run time.
_DYNAMIC_IMPORTS = frozenset({"import_module", "files", "find_spec", "__import__"})
#: The call that lists every module of a package for its caller to import
#: (:func:`jointbench.registries.submodules`).
_EVERY_MODULE = "submodules"


class _Modules(Protocol):
    """Where the modules a closure follows are: the file of one, the modules of a package."""

    def file(self, module: str) -> Path | None: ...

    def modules(self, package: str) -> list[str]: ...


@dataclass(frozen=True)
class _Package:
    """The package whose modules are tracked: its name and the folder it is imported from."""

    name: str
    root: Path

    def file(self, module: str) -> Path | None:
        """The file of ``module`` (a package's ``__init__.py``), or ``None`` if it is not one
        of the package's modules."""
        return _once(("file", self.root, module), lambda: self._file(module))

    def _file(self, module: str) -> Path | None:
        if module != self.name and not module.startswith(self.name + "."):
            return None
        path = self.root.joinpath(*module.split(".")[1:])
        for candidate in (path / "__init__.py", path.with_suffix(".py")):
            if candidate.is_file():
                return candidate
        return None

    def modules(self, package: str) -> list[str]:
        """The modules of ``package``, one of the package's subpackages (none for another)."""
        path = self.file(package)
        if path is None or path.name != "__init__.py":
            return []
        return [f"{package}.{m.name}" for m in pkgutil.iter_modules([str(path.parent)])]

    def sources(self) -> list[Path]:
        """Every Python file of the package, its subpackages' included."""
        return _once(("sources", self.root), self._sources)

    def data(self) -> dict[str, Path]:
        """Every data file of the package (any file that is not Python code), by its path
        relative to the package's folder."""
        return _once(("data", self.root), self._data)

    def _sources(self) -> list[Path]:
        return sorted(p for p in self.root.rglob("*.py") if _is_kept(p, self.root))

    def _data(self) -> dict[str, Path]:
        found = (p for p in self.root.rglob("*") if p.is_file() and p.suffix not in _CODE)
        return {
            p.relative_to(self.root).as_posix(): p for p in sorted(found) if _is_kept(p, self.root)
        }

    def owner(self, path: Path) -> str:
        """The package whose folder holds ``path``: the nearest folder up with an
        ``__init__.py``, the package itself at the latest."""
        folder = path.parent
        while folder != self.root and not (folder / "__init__.py").is_file():
            folder = folder.parent
        return ".".join([self.name, *folder.relative_to(self.root).parts])


#: Suffixes of the package's code and of its compiled copies: not data.
_CODE = frozenset({".py", ".pyc", ".pyo"})


def _is_kept(path: Path, root: Path) -> bool:
    """Whether ``path`` under ``root`` belongs to the package: Python's and Numba's caches
    (``__pycache__``), hidden files and editors' backups (``name~``) do not."""
    parts = path.relative_to(root).parts
    return not (
        "__pycache__" in parts or any(p.startswith(".") for p in parts) or path.name.endswith("~")
    )


def _package(name: str) -> _Package:
    spec = importlib.util.find_spec(name)
    if spec is None or not spec.submodule_search_locations:
        raise ValueError(f"{name!r} is not an importable package")
    return _Package(name, Path(next(iter(spec.submodule_search_locations))))


@dataclass(frozen=True)
class _OwnModules:
    """A user's own modules, as an import in a file of ``folder`` finds them: Python source
    files beside that file first, then on ``sys.path`` or through the import system's finders
    (an editable install's among them). A module of the standard library or of an installed
    distribution is none (Python's and the distributions' versions stand for it), nor one of
    the package ``tracked`` (its own closure follows those)."""

    folder: Path
    tracked: str

    def file(self, module: str) -> Path | None:
        """The source file of ``module`` (a package's ``__init__.py``), or ``None``."""
        path, _ = self._found(module)
        if path is None or path.suffix != ".py" or not path.is_file():
            return None
        return None if os.path.realpath(path).startswith(_library_roots()) else path

    def modules(self, package: str) -> list[str]:
        """The modules of ``package``, if it is a package: its files decide which count."""
        _, folders = self._found(package)
        return [f"{package}.{m.name}" for m in pkgutil.iter_modules([str(f) for f in folders])]

    def _found(self, module: str) -> tuple[Path | None, tuple[Path, ...]]:
        """The file of ``module`` (``None`` for a namespace package or none found) and, for a
        package, its folders; the top-level name is looked up as an import would, without
        running any of the modules."""
        top, *rest = module.split(".")
        if (
            not _is_module_name(module)
            or top in sys.stdlib_module_names
            or top == self.tracked.split(".")[0]
        ):
            return None, ()
        spec = PathFinder.find_spec(top, [str(self.folder)])
        try:
            spec = spec or importlib.util.find_spec(top)
        except (ImportError, ValueError):  # a module in ``sys.modules`` without a spec
            return None, ()
        if spec is None:
            return None, ()
        path = Path(spec.origin) if spec.has_location and spec.origin else None
        folders = tuple(Path(f) for f in spec.submodule_search_locations or ())
        for name in rest:
            path, folders = _submodule(folders, name)
        return path, folders


def _submodule(folders: tuple[Path, ...], name: str) -> tuple[Path | None, tuple[Path, ...]]:
    """The file and folders of the submodule ``name`` of a package in ``folders``, as
    :meth:`_OwnModules._found` gives them."""
    for folder in folders:
        package = folder / name
        if (package / "__init__.py").is_file():
            return package / "__init__.py", (package,)
        if package.with_suffix(".py").is_file():
            return package.with_suffix(".py"), ()
    return None, tuple(f / name for f in folders if (f / name).is_dir())


def _is_module_name(text: str) -> bool:
    return all(part.isidentifier() for part in text.split("."))


@dataclass(frozen=True)
class _Imports:
    """What one file can import: ``whole`` (modules, and packages whose object it binds),
    ``named`` (``from package import name`` pairs), ``dynamic`` (string constants that
    name modules, in a file that imports by name) and ``every`` (packages it imports every
    module of)."""

    whole: frozenset[str]
    named: frozenset[tuple[str, str]]
    dynamic: frozenset[str]
    every: frozenset[str] = frozenset()


def _runs(tree: ast.AST) -> Iterator[ast.AST]:
    """Every node of ``tree`` that can run: ``if TYPE_CHECKING:`` bodies are left out."""
    stack = [tree]
    while stack:
        node = stack.pop()
        yield node
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            stack.extend(node.orelse)
            continue
        stack.extend(ast.iter_child_nodes(node))


def _is_type_checking(test: ast.expr) -> bool:
    name = test.attr if isinstance(test, ast.Attribute) else getattr(test, "id", None)
    return name == "TYPE_CHECKING"


def _absolute(level: int, source: str, module: str, is_package: bool) -> str:
    """The module a ``from … import`` of ``source`` at ``level`` names, relative imports
    resolved against ``module``."""
    if not level:
        return source
    parts = module.split(".")
    base = parts if is_package else parts[:-1]
    base = base[: len(base) - level + 1]
    return ".".join([*base, *([source] if source else [])])


class OnePass:
    """What one pass of fingerprints reads of the files, each read once: every file's text,
    every listing of a package's files and where each of its modules is, as first read. A
    caller makes one for the life of one planning pass, over which the files do not change
    (the workflow fingerprints every script with one, in the Snakemake process that plans the
    jobs, before any runs); an edit after a pass first read a file is seen by a new pass, or
    by a call without one, which reads every file anew, never by that pass."""

    def __init__(self) -> None:
        self._texts: dict[Path, str] = {}
        self._found: dict[tuple, object] = {}

    def text(self, path: Path) -> str:
        """The text of ``path``, read at the first call."""
        if path not in self._texts:
            self._texts[path] = path.read_text(encoding="utf-8")
        return self._texts[path]

    def once(self, key: tuple, found: Callable[[], object]) -> object:
        """What ``found`` gives, called at the first call with ``key``."""
        if key not in self._found:
            self._found[key] = found()
        return self._found[key]


#: The pass of the fingerprint being computed (:func:`code_fingerprint`'s ``one_pass``), or
#: ``None``: every read then reads the file.
_PASS: ContextVar[OnePass | None] = ContextVar("_PASS", default=None)


@contextmanager
def _within(one_pass: OnePass | None) -> Iterator[None]:
    """Every read made meanwhile in this context reads through ``one_pass`` (none: anew)."""
    token = _PASS.set(one_pass)
    try:
        yield
    finally:
        _PASS.reset(token)


def _read(path: Path) -> str:
    one_pass = _PASS.get()
    return path.read_text(encoding="utf-8") if one_pass is None else one_pass.text(path)


def _once(key: tuple, found: Callable):
    """What ``found`` gives, through the pass under way (:data:`_PASS`), if any."""
    one_pass = _PASS.get()
    return found() if one_pass is None else one_pass.once(key, found)


@dataclass(frozen=True)
class _Summary:
    """What the fingerprint needs of one Python text, all read from its syntax tree without
    docstrings: ``digest``, the hex SHA-256 of the tree's dump (what the code does);
    ``imports``, its ``import`` statements as ``["import", name, has_alias]`` and its
    ``from … import`` statements as ``["from", level, module, names]``; ``dynamic_calls``,
    whether it imports by a name built at run time; ``every``, the packages it imports every
    module of; ``strings``, its string constants (all in nodes that can run)."""

    digest: str
    imports: tuple[tuple, ...]
    dynamic_calls: bool
    every: frozenset[str]
    strings: frozenset[str]


def _summarised(text: str) -> _Summary:
    """The :class:`_Summary` of ``text``, parsed once."""
    tree = _parsed(text)
    imports: list[tuple] = []
    strings: set[str] = set()
    every: set[str] = set()
    dynamic_calls = False
    for node in _runs(tree):
        if isinstance(node, ast.Import):
            imports.extend(("import", a.name, a.asname is not None) for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            names = tuple(alias.name for alias in node.names)
            imports.append(("from", node.level, node.module or "", names))
        elif isinstance(node, ast.Call):
            function = node.func
            name = function.attr if isinstance(function, ast.Attribute) else function
            dynamic_calls |= getattr(name, "id", name) in _DYNAMIC_IMPORTS
            if getattr(name, "id", name) == _EVERY_MODULE and node.args:
                first = node.args[0]
                if isinstance(first, ast.Constant) and isinstance(first.value, str):
                    every.add(first.value)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str):
            strings.add(node.value)
    digest = hashlib.sha256(ast.dump(tree).encode()).hexdigest()
    return _Summary(digest, tuple(imports), dynamic_calls, frozenset(every), frozenset(strings))


def _parsed(text: str) -> ast.Module:
    """The syntax tree of ``text`` without docstrings: they document, they do not run."""
    tree = ast.parse(text)
    for node in ast.walk(tree):
        if isinstance(node, _DOCUMENTED) and _has_docstring(node.body):
            node.body = node.body[1:] or [ast.Pass()]
    return tree


_DOCUMENTED = (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)


def _has_docstring(body: list[ast.stmt]) -> bool:
    first = body[0] if body else None
    return (
        isinstance(first, ast.Expr)
        and isinstance(first.value, ast.Constant)
        and isinstance(first.value.value, str)
    )


# Every Snakemake process fingerprints its jobs anew, and parsing the package's modules is most
# of a dry run's time. A summary is a pure function of the text, of this module's code and of
# the Python that parsed it (syntax trees differ between versions), so it is stored under the
# hash of all three: an edited file, an edited rule of this module or another Python can only
# miss the store, never read a summary of something else.
def _store() -> Path | None:
    """The folder of stored summaries: ``$JOINTBENCH_CACHE`` or the user's cache folder, one
    subfolder per Python and per version of this module; ``None`` when it is switched off
    (``JOINTBENCH_CACHE=off``)."""
    setting = os.environ.get("JOINTBENCH_CACHE")
    if setting == "off":
        return None
    base = Path(setting) if setting else _user_cache() / PACKAGE
    return base / "fingerprint" / _namespace()


def _user_cache() -> Path:
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")


@cache
def _namespace() -> str:
    own = Path(__file__).read_bytes()
    return hashlib.sha256(sys.version.encode() + b"\0" + own).hexdigest()[:16]


@cache
def _summary(text: str) -> _Summary:
    """The :class:`_Summary` of ``text``: from the store when it holds one, else parsed (and
    stored; a store that cannot be written or read is only slower)."""
    store = _store()
    if store is None:
        return _summarised(text)
    _kept_tidy(store)
    entry = store / f"{hashlib.sha256(text.encode()).hexdigest()}.json"
    try:
        return _from_json(json.loads(_read_entry(entry)))
    except (OSError, ValueError, KeyError, TypeError):
        pass
    summary = _summarised(text)
    _write_atomically(entry, json.dumps(_to_json(summary)))
    return summary


# The store's housekeeping (module docstring). Every removal is of something that is only
# parsed again when missed, and every failure to remove is ignored, so no race between
# processes and no folder that cannot be written changes a fingerprint.

#: Seconds: a temporary file older than this was left by a writer that was killed; the
#: renewal of a read entry's time stamp and the pruning of the store are each due once a
#: day; an entry or another version's folder unused for 30 days is removed.
_STALE_TEMPORARY = 10 * 60
_DAY = 24 * 3600
_UNUSED = 30 * _DAY

#: The stamp file in the namespace folder whose time stamp is that of the last pruning.
_STAMP = ".pruned"

#: Names of what the store itself writes, the only files and folders it removes: a namespace
#: (:func:`_namespace`), an entry (:func:`_summary`) and a temporary file of
#: :func:`_write_atomically` (``tempfile``'s ``tmp`` prefix and random letters).
_NAMESPACE_NAME = re.compile(r"[0-9a-f]{16}")
_ENTRY_NAME = re.compile(r"[0-9a-f]{64}\.json")
_TEMPORARY_NAME = re.compile(r"tmp\w+\.tmp")


def _read_entry(entry: Path) -> str:
    """The text of the stored ``entry``, which is marked as used (its time stamp renewed)
    when it was last marked more than a day ago: the daily pruning keeps what was read within
    :data:`_UNUSED`."""
    with entry.open(encoding="utf-8") as handle:
        text = handle.read()
        marked = os.fstat(handle.fileno()).st_mtime
    if time.time() - marked > _DAY:
        _touch(entry)
    return text


@cache
def _kept_tidy(store: Path) -> None:
    """Prune ``store``, the namespace folder in use, and its siblings (module docstring), when
    its stamp says the last pruning was a day ago or more; once per process at most."""
    stamp = store / _STAMP
    now = time.time()
    try:
        if now - stamp.stat().st_mtime < _DAY:
            return
    except OSError:
        pass  # never pruned, or the stamp cannot be read: try
    try:
        store.mkdir(parents=True, exist_ok=True)
        # Stamped first, so that a process starting meanwhile mostly leaves it to this one (if
        # both prune, each only finds some files already gone); the folder's own time stamp
        # says when this version was last used.
        stamp.touch()
        os.utime(store)
    except OSError:
        return  # a store that cannot be written: nothing could be removed either
    _prune(store, now)


def _prune(store: Path, now: float) -> None:
    """Remove, as of ``now`` [s since the epoch], the stale temporary files and the unused
    entries of ``store`` and the unused namespace folders beside it."""
    for found in _listed(store):
        if _TEMPORARY_NAME.fullmatch(found.name):
            age = _STALE_TEMPORARY
        elif _ENTRY_NAME.fullmatch(found.name):
            age = _UNUSED
        else:
            continue
        if _older(found, now - age, folder=False):
            _remove(found)
    for found in _listed(store.parent):
        if (
            found.name != store.name
            and _NAMESPACE_NAME.fullmatch(found.name)
            and _older(found, now - _UNUSED, folder=True)
        ):
            shutil.rmtree(found.path, ignore_errors=True)


def _listed(folder: Path) -> list[os.DirEntry]:
    """The entries of ``folder``; none when it cannot be listed (gone meanwhile)."""
    try:
        with os.scandir(folder) as entries:
            return list(entries)
    except OSError:
        return []


def _older(found: os.DirEntry, then: float, *, folder: bool) -> bool:
    """Whether ``found`` is a file (``folder``: a folder; never a link) last modified before
    ``then``; ``False`` when it is gone or cannot be read."""
    try:
        kind = (
            found.is_dir(follow_symlinks=False) if folder else found.is_file(follow_symlinks=False)
        )
        return kind and found.stat(follow_symlinks=False).st_mtime < then
    except OSError:
        return False


def _remove(found: os.DirEntry) -> None:
    try:
        os.unlink(found.path)
    except OSError:
        pass  # removed by another process meanwhile, or not ours to remove


def _touch(path: Path) -> None:
    try:
        os.utime(path)
    except OSError:
        pass  # a store that cannot be written keeps its time stamps


def _to_json(summary: _Summary) -> dict:
    return {
        "digest": summary.digest,
        "imports": [list(entry) for entry in summary.imports],
        "dynamic_calls": summary.dynamic_calls,
        "every": sorted(summary.every),
        "strings": sorted(summary.strings),
    }


def _from_json(stored: dict) -> _Summary:
    """The summary :func:`_to_json` stored; ``ValueError`` for an entry that is not one (cut
    short, or written by hand)."""
    digest = stored["digest"]
    if not isinstance(digest, str) or len(bytes.fromhex(digest)) != hashlib.sha256().digest_size:
        raise ValueError("not a SHA-256 digest")
    return _Summary(
        digest,
        tuple(_import_from_json(entry) for entry in stored["imports"]),
        _typed(stored["dynamic_calls"], bool),
        frozenset(_typed(s, str) for s in stored["every"]),
        frozenset(_typed(s, str) for s in stored["strings"]),
    )


def _import_from_json(entry: list) -> tuple:
    match entry:
        case ["import", str(name), bool(has_alias)]:
            return ("import", name, has_alias)
        case ["from", int(level), str(module), list(names)]:
            return ("from", level, module, tuple(_typed(n, str) for n in names))
    raise ValueError(f"not an import: {entry!r}")


def _typed(value, kind: type):
    if not isinstance(value, kind):
        raise ValueError(f"{value!r} is no {kind.__name__}")
    return value


def _write_atomically(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` by renaming a finished temporary file, so that a process
    reading it meanwhile sees the whole entry or none; give up quietly if the folder cannot
    be written."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(
            "w", encoding="utf-8", dir=path.parent, suffix=".tmp", delete=False
        ) as handle:
            handle.write(text)
        os.replace(handle.name, path)
    except OSError:
        return


def _imports(path: Path, module: str) -> _Imports:
    return _imports_of(_read(path), module, path.name == "__init__.py")


@cache
def _imports_of(text: str, module: str, is_package: bool) -> _Imports:
    summary = _summary(text)
    whole: set[str] = set()
    named: set[tuple[str, str]] = set()
    for entry in summary.imports:
        if entry[0] == "import":
            _, name, has_alias = entry
            # ``import a.b`` binds ``a``; ``import a.b as c`` binds only ``a.b``.
            whole.add(name if has_alias else name.split(".")[0])
            whole.add(name)
        else:
            _, level, source_module, names = entry
            source = _absolute(level, source_module, module, is_package)
            named.update((source, name) for name in names)
    return _Imports(
        frozenset(whole),
        frozenset(named),
        summary.strings if summary.dynamic_calls else frozenset(),
        summary.every,
    )


def _parents(module: str) -> list[str]:
    parts = module.split(".")
    return [".".join(parts[:i]) for i in range(1, len(parts))]


def _closure(package: _Modules, roots: Iterable[Path]) -> dict[str, Path]:
    """Modules of ``package`` the files ``roots`` can import (see the module's docstring)."""
    found: dict[str, Path] = {}
    # (module, whole): ``whole`` when the module object itself is imported, not only run as
    # the parent package of a submodule.
    stack: list[tuple[str, bool]] = []
    # Asked about the same names thousands of times; the folder does not change meanwhile.
    file_of = cache(package.file)

    def follow(imports: _Imports, followed_dynamic: bool) -> None:
        stack.extend((m, True) for m in imports.whole)
        for source, name in imports.named:
            submodule = f"{source}.{name}"
            if file_of(submodule) is not None:
                stack.append((submodule, True))
                stack.append((source, False))
            else:
                stack.append((source, True))
        if followed_dynamic:
            for name in imports.dynamic:
                if file_of(name) is not None:
                    stack.append((name, True))
                elif name.endswith(".") and _is_module_name(name[:-1]):
                    # The constant part of a name built at run time (f"lab.methods.{name}"):
                    # any module of that package.
                    stack.extend((m, True) for m in package.modules(name[:-1]))
        # Run whenever the file runs, however it was imported.
        stack.extend((m, True) for p in imports.every for m in package.modules(p))

    for root in roots:
        follow(_imports(Path(root), "__main__"), followed_dynamic=True)
    visited: set[tuple[str, bool]] = set()
    while stack:
        module, whole = stack.pop()
        path = file_of(module)
        if path is None or (module, whole) in visited or (module, True) in visited:
            continue
        visited.add((module, whole))
        found[module] = path
        stack.extend((parent, False) for parent in _parents(module))
        is_package = path.name == "__init__.py"
        try:
            imports = _imports(path, module)
        except (SyntaxError, UnicodeDecodeError, ValueError):
            continue  # cannot run, so imports nothing; its digest is its bytes
        follow(imports, followed_dynamic=whole or not is_package)
    return dict(sorted(found.items()))


def module_closure(*roots: str | Path, package: str = PACKAGE) -> dict[str, Path]:
    """The modules of ``package`` that the Python files ``roots`` can import, by name."""
    return _closure(_package(package), [Path(r) for r in roots])


def own_closure(*roots: str | Path, package: str = PACKAGE) -> list[tuple[str, Path]]:
    """The user's own modules (neither the standard library's, nor an installed distribution's,
    nor of ``package``) that the Python files ``roots`` can import, each found as an import in
    its root would find it (beside the root first), by name and file: two roots may reach two
    modules of one name."""
    found: set[tuple[str, Path]] = set()
    for root in map(Path, roots):
        found.update(_closure(_OwnModules(root.resolve().parent, package), [root]).items())
    return sorted(found)


@cache
def _named(text: str, names: frozenset[str]) -> frozenset[str]:
    """Those of the file ``names`` that the code ``text`` names: the last path component of
    one of its string constants (docstrings and comments left out)."""
    # Most modules name no data file: a text search spares parsing them.
    candidates = {name for name in names if name in text}
    if not candidates:
        return frozenset()
    return frozenset(candidates & {PurePosixPath(value).name for value in _summary(text).strings})


def _names(paths: Iterable[Path], names: frozenset[str]) -> frozenset[str]:
    """Those of the file ``names`` that the Python files ``paths`` name."""
    return frozenset().union(*(_named(_read(path), names) for path in paths))


def _data_closure(
    package: _Package, roots: list[Path], modules: dict[str, Path]
) -> dict[str, Path]:
    """The data files of ``package`` that a job running ``roots``, which can import
    ``modules``, can read (see the module's docstring), by path relative to the package."""
    data = package.data()
    names = frozenset(path.name for path in data.values())
    named_here = _names([*roots, *modules.values()], names)
    named_anywhere = named_here | _names(package.sources(), names)
    return {
        name: path
        for name, path in data.items()
        if path.name in named_here
        or (path.name not in named_anywhere and package.owner(path) in modules)
    }


def data_closure(*roots: str | Path, package: str = PACKAGE) -> dict[str, Path]:
    """The data files of ``package`` that the Python files ``roots`` can read through the
    modules they can import, by path relative to the package's folder."""
    found = _package(package)
    paths = [Path(r) for r in roots]
    return _data_closure(found, paths, _closure(found, paths))


def _source_digest(path: Path) -> bytes:
    """What the code of ``path`` does: its syntax tree without docstrings, line numbers or
    comments."""
    return _digest_of(_read(path))


def _digest_of(text: str) -> bytes:
    return bytes.fromhex(_summary(text).digest)


def dependency_versions(package: str = PACKAGE) -> dict[str, str]:
    """The installed version of Python and of every distribution ``package`` requires (its
    run-time dependencies, extras left out): upgrading NumPy or SciPy can move a result too;
    and of llvmlite, Numba's code generator (:data:`_CODE_GENERATORS`); and ``libc``, the C
    library's name and version (:func:`_c_library`).
    With Numba's compiler switched off (:func:`numba_jit_disabled`), also ``numba_jit``:
    ``"disabled"``."""
    versions = {
        "python": platform.python_version(),
        "libc": _c_library(),
        **dict(_installed_versions(package)),
    }
    if numba_jit_disabled():
        versions["numba_jit"] = "disabled"
    return versions


#: Numba's switch of its compiler: an environment variable, or the key of its config file in the
#: working directory without the prefix (the variable wins).
_NUMBA_DISABLE_JIT = "NUMBA_DISABLE_JIT"
_NUMBA_CONFIG_FILE = Path(".numba_config.yaml")


def numba_jit_disabled() -> bool:
    """Whether Numba runs the kernels as Python: ``NUMBA_DISABLE_JIT``, or ``disable_jit`` in
    ``.numba_config.yaml`` (a key in any case), a non-zero integer, as Numba reads them (a
    value that is no integer leaves the compiler on). The kernels' results differ from the
    compiled code's in the last bits, so a run without the compiler is another run. Read at
    every call: the setting is the environment's now, not when the process started."""
    value = os.environ.get(_NUMBA_DISABLE_JIT)
    if value is None and _NUMBA_CONFIG_FILE.is_file():
        settings = yaml.safe_load(_NUMBA_CONFIG_FILE.read_text(encoding="utf-8"))
        if isinstance(settings, dict):
            # Numba reads each key in upper case, so the last of one name wins.
            upper = {str(key).upper(): setting for key, setting in settings.items()}
            value = upper.get("DISABLE_JIT")
    try:
        return value is not None and int(value) != 0
    except (TypeError, ValueError):
        return False


# The compiled kernels' and NumPy's elementary functions (acos, atan2, exp) are the C library's
# libm, whose releases round some results differently. Asked once per process: where the C
# library does not state its version (glibc does), ``libc_ver`` reads the interpreter's binary.
@cache
def _c_library() -> str:
    """The C library the interpreter runs on, as ``"glibc 2.36"``; on macOS, whose C library
    (libSystem, its libm included) comes with the system, the system's release, as ``"macOS
    14.2"``; ``"unknown"`` where Python cannot tell (musl)."""
    library, version = platform.libc_ver()
    if library:
        return f"{library} {version}"
    release = platform.mac_ver()[0]
    return f"macOS {release}" if release else "unknown"


# Reading the installed distributions' metadata costs more than a job's whole fingerprint, and a
# Snakemake process fingerprints every rule: it is read once per process, which no upgrade can
# happen inside.
@cache
def _installed_versions(package: str) -> tuple[tuple[str, str], ...]:
    try:
        requirements = importlib.metadata.requires(package) or []
    except importlib.metadata.PackageNotFoundError:  # modules on the path, not installed
        requirements = []
    versions = {}
    for requirement in requirements:
        if "extra ==" in requirement:
            continue
        name = re.split(r"[\s<>=!~;\[(]", requirement, maxsplit=1)[0]
        try:
            versions[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            versions[name] = "not installed"
    for name in _CODE_GENERATORS:
        try:
            versions[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            continue  # a dependency without its compiler compiles nothing
    return tuple(versions.items())


#: Distributions that make the machine code the package's dependencies run, not required by the
#: package itself: llvmlite holds the LLVM that Numba compiles the kernels with, one Numba
#: version allowing several of its releases, and another LLVM may optimise a kernel otherwise.
_CODE_GENERATORS = ("llvmlite",)


def compiler_version(command: str) -> str:
    """The first line ``command --version`` prints (a C compiler's name and version, ``cc
    (Debian 12.2.0-14) 12.2.0``), or ``"not found"``: what a rule compiling a program records
    as a parameter, so that another compiler, which may optimise the program otherwise, makes
    it again. Asked once per process."""
    return _compiler_version(shutil.which(command) or "")


@cache
def _compiler_version(path: str) -> str:
    if not path:
        return "not found"
    try:
        done = subprocess.run(
            [path, "--version"], capture_output=True, text=True, timeout=30, check=False
        )
    except (OSError, subprocess.SubprocessError):
        return "not found"
    lines = done.stdout.splitlines()
    return lines[0].strip() if lines else "not found"


def code_fingerprint(
    *roots: str | Path,
    package: str = PACKAGE,
    inputs: Iterable[str] = (),
    one_pass: OnePass | None = None,
) -> str:
    """A short hash of the Python files ``roots`` (a job's script, the extension modules it
    loads), of every module of ``package`` they can import, of every data file of ``package``
    those can read (:func:`data_closure`) and of the versions of its dependencies
    (:func:`dependency_versions`), and of the user's own modules they can import, outside the
    standard library, installed distributions and ``package`` (:func:`own_closure`), with every
    module of ``package`` and data file those can reach in turn. Equal fingerprints mean the
    same code ran on the same package data.

    ``inputs``: data files of the package that the caller tracks as inputs of the very jobs that
    read them (the papers' published values), left out here, by their paths relative to the
    package's folder (:func:`data_names`): a job's code can reach every paper's, and one
    paper's values must not rerun the jobs of another's study. ``ValueError`` naming any that
    is no data file of the package by that path.

    ``one_pass``: the pass of fingerprints this one belongs to, which reads each file once for
    them all (:class:`OnePass`); without one, every file is read anew."""
    with _within(one_pass):
        return _code_fingerprint([Path(r) for r in roots], package, frozenset(inputs))


def _code_fingerprint(paths: list[Path], package: str, tracked: frozenset[str]) -> str:
    found = _package(package)
    # A file named otherwise (by its own path, as these once were) would leave nothing out.
    unknown = sorted(
        name
        for name in tracked
        if PurePosixPath(name).is_absolute() or not (found.root / name).is_file()
    )
    if unknown:
        raise ValueError(
            f"inputs {', '.join(map(repr, unknown))}: no data file of the package {package} "
            "by its path relative to the package's folder (data_names)"
        )
    started = _startup_lines()
    paths = [*paths, *_site_hooks(), *_startup_imports(started)]
    own = own_closure(*paths, package=package)
    reached = [*paths, *(path for _, path in own)]
    modules = _closure(found, reached)
    digest = hashlib.sha256()
    digest.update(repr(sorted(dependency_versions(package).items())).encode())
    for line in started:
        digest.update(line)
    # By name and content, not by path: where the checkout lies, which decides how its files
    # sort among the user's start-up modules outside it, is no change.
    roots = [path.resolve() for path in paths]
    for named in sorted(root.name.encode() + _source_digest(root) for root in roots):
        digest.update(named)
    for name, path in own:
        digest.update(name.encode() + _file_digest(path).encode())
    for name, path in modules.items():
        digest.update(name.encode() + _source_digest(path))
    for name, path in _data_closure(found, reached, modules).items():
        if name not in tracked:
            digest.update(name.encode() + _file_digest(path).encode())
    return digest.hexdigest()[:16]


#: The modules Python's ``site`` imports by name at start-up, wherever the path finds them: they run
#: in every job's process before its script does.
_SITE_HOOKS = ("sitecustomize", "usercustomize")


def _site_hooks() -> list[Path]:
    """The files of the start-up modules (:data:`_SITE_HOOKS`) that are the user's own, found
    on the path as ``site`` finds them: one outside the standard library and installed
    distributions (a ``sitecustomize.py`` on ``PYTHONPATH``) changes what a job computes as
    surely as its script, and counts as one of its roots."""
    return [path for name in _SITE_HOOKS if (path := _own_module_file(name)) is not None]


def _own_module_file(name: str) -> Path | None:
    """The source file of the top-level module ``name`` as the path finds it, if it is the
    user's own (outside the standard library and installed distributions), else ``None``."""
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):  # in ``sys.modules`` without a spec
        return None
    origin = spec.origin if spec is not None and spec.has_location else None
    if origin and origin.endswith(".py"):
        if not os.path.realpath(origin).startswith(_library_roots()):
            return Path(origin)
    return None


def _site_folders() -> list[Path]:
    """The folders whose ``.pth`` files Python's ``site`` reads at start-up, in its order: the
    user's site folder (when ``site`` reads it) before the environment's."""
    user = [site.getusersitepackages()] if site.ENABLE_USER_SITE else []
    return [Path(folder) for folder in (*user, *site.getsitepackages())]


def _startup_lines() -> list[bytes]:
    """The lines of code ``site`` runs at start-up in every process, before any job's script:
    those starting with ``import`` (then a space or a tab) of each ``.pth`` file of the site
    folders (:func:`_site_folders`), in the order ``site`` runs them (folder, then file name),
    each with its file's name. By content: a time stamp is no change. A line naming a folder
    only puts it on the path, where a module a job imports is found and read by content
    wherever it is (:func:`own_closure`), so it is not counted itself."""
    lines = []
    for folder in _site_folders():
        try:
            names = sorted(n for n in os.listdir(folder) if n.endswith(".pth"))
        except OSError:  # no such folder
            continue
        for name in names:
            if name.startswith("."):  # skipped by site
                continue
            try:
                text = (folder / name).read_bytes()
            except OSError:
                continue
            lines += [
                name.encode() + b"\0" + line
                for line in text.splitlines()
                if line.startswith((b"import ", b"import\t"))
            ]
    return lines


def _startup_imports(lines: list[bytes]) -> list[Path]:
    """The files of the user's own modules the start-up lines ``lines`` (:func:`_startup_lines`)
    import, found as :func:`_site_hooks` finds its modules: their code runs in every job. A
    module is imported by a statement, or by a call with its name written out (setuptools' own
    ``.pth`` line calls ``__import__('_distutils_hack')``), as :func:`_summarised` reads both."""
    names = set()
    for line in lines:
        try:
            summary = _summarised(line.partition(b"\0")[2].decode())
        except (SyntaxError, ValueError):  # ValueError: not UTF-8, or a null byte
            continue  # site stops at it with an error: it imports nothing
        for kind, *rest in summary.imports:
            if kind == "import" or rest[0] == 0:  # not a relative ``from . import``
                names.add(rest[0 if kind == "import" else 1])
        if summary.dynamic_calls:
            names.update(s for s in summary.strings if _MODULE_NAME.fullmatch(s))
    tops = sorted({name.partition(".")[0] for name in names if name})
    return [path for name in tops if (path := _own_module_file(name)) is not None]


#: A module's absolute name, as a string a start-up line imports by a call may hold.
_MODULE_NAME = re.compile(r"[A-Za-z_]\w*(\.[A-Za-z_]\w*)*")


def data_names(paths: Iterable[str | Path], package: str = PACKAGE) -> list[str]:
    """Those of the files ``paths`` that are data files of ``package``, each by its path
    relative to the package's folder (as :func:`data_closure` names it), in order: how
    :func:`code_fingerprint` is told which to leave out, the same wherever the package is
    imported from. A file outside the package is none: no fingerprint reads it."""
    root = _package(package).root.resolve()
    resolved = (Path(path).resolve() for path in paths)
    return sorted(
        path.relative_to(root).as_posix() for path in resolved if path.is_relative_to(root)
    )


#: The digest of a source that does not exist: Snakemake names the missing input itself.
MISSING = "missing"


def _file_digest(path: Path) -> str:
    """What ``path`` holds: a Python file's code (:func:`_source_digest`; its bytes when it does
    not parse), any other file's bytes, a folder's files and their names."""
    if path.is_dir():
        digest = hashlib.sha256()
        for member in sorted(p for p in path.rglob("*") if p.is_file()):
            digest.update(member.relative_to(path).as_posix().encode())
            digest.update(_file_digest(member).encode())
        return digest.hexdigest()[:16]
    data = path.read_bytes()
    if path.suffix == ".py":
        try:
            return _digest_of(data.decode("utf-8")).hex()[:16]
        except (SyntaxError, UnicodeDecodeError, ValueError):
            pass
    return hashlib.sha256(data).hexdigest()[:16]


def source_digests(paths: Iterable[str | Path]) -> dict[str, str]:
    """The digest of each file of ``paths`` (16 hex digits, :data:`MISSING` for a file that does
    not exist), by path as given, and of each of the user's own modules a Python file among
    them can import (:func:`own_closure`, by path as found): equal digests mean the same
    content, whatever the files' time stamps."""
    given = sorted(set(map(str, paths)))
    return {
        str(path): _file_digest(Path(path)) if Path(path).exists() else MISSING
        for path in sorted({*given, *_own_imports(given)})
    }


def _own_imports(paths: Iterable[str]) -> list[str]:
    """The user's own modules the existing Python files of ``paths`` can import: an external
    estimator's script runs them as surely as its own lines."""
    scripts = [path for path in paths if path.endswith(".py") and Path(path).is_file()]
    # Relative to the working directory when inside it, as the workflow names its sources: a
    # project moved elsewhere keeps its digests' keys.
    here = Path.cwd()
    return [
        os.path.relpath(module) if module.is_relative_to(here) else str(module)
        for _, module in own_closure(*scripts)
    ]


# Python takes a module's cached bytecode (``__pycache__``) as current while the source keeps its
# size and its modification time to the second: an edit that keeps both (a same-second rewrite,
# a copy that keeps time stamps) changes the fingerprint, which reads the source, and reruns the
# job, which would run the old bytecode. A cache checked by the source's hash instead
# (PEP 552) is compiled anew whenever the content differs, and stays checked by hash when Python
# rewrites it.

#: The flags of a bytecode cache that Python checks against the source's hash.
_CHECKED_HASH = 0b11


def check_bytecode_by_content(*roots: str | Path, package: str = PACKAGE) -> None:
    """Make every cached bytecode of ``package``'s modules, of the Python files ``roots`` (the
    extensions) and of the user's own modules they import (:func:`own_closure`) one that Python
    checks against its source's content: compiled now from the source as it is. A module
    without a cache, or a cache that cannot be written, is left as it is."""
    paths = [*_package(package).sources(), *map(Path, roots)]
    paths += [path for _, path in own_closure(*roots, package=package)]
    for path in paths:
        cached = Path(importlib.util.cache_from_source(str(path)))
        try:
            with cached.open("rb") as handle:
                flags = int.from_bytes(handle.read(8)[4:], "little")
        except OSError:
            continue  # none yet: the next run, before any job, checks the one Python writes
        if flags == _CHECKED_HASH:
            continue
        try:
            py_compile.compile(
                str(path),
                cfile=str(cached),
                doraise=True,
                invalidation_mode=py_compile.PycInvalidationMode.CHECKED_HASH,
            )
        except (OSError, py_compile.PyCompileError):
            continue  # a folder that cannot be written, or code that does not compile
