"""Extensions: a study, paper or estimator outside the package, a module listed under
``extensions`` in the config, imported and its ``Study`` and ``Paper`` values registered (an
estimator registers itself on import, ``@register``). The Snakemake process and the command line
load them when they open a run's config
(:func:`jointbench.configuration.config.open_config`), every job when it starts
(:func:`jointbench.jobs.job`).
"""

from __future__ import annotations

import importlib.util
import sys
import traceback
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import ModuleType

from jointbench.configuration.studies import register_study
from jointbench.simulate import Study

__all__ = ["in_load_order", "load_extensions"]


def _register(value: object) -> None:
    """Register ``value`` if it is a ``Study`` or a ``Paper``."""
    if isinstance(value, Study):
        register_study(value)
        return
    # A Paper exists only once jointbench.papers, the home of its class and of the paper
    # registry, has been imported (by the extension defining it); it is looked up there rather
    # than imported here, so that jobs rendering no paper output do not load every paper.
    papers = sys.modules.get("jointbench.papers")
    if papers is not None and isinstance(value, papers.Paper):
        papers.register_paper(value)


def load_extensions(config: Mapping, base: str | Path = ".") -> None:
    """Import every file under ``extensions`` and register the ``Study`` and ``Paper`` values
    it defines, the files in the order of their names (:func:`in_load_order`). Importing the
    same file again is a no-op. A file that is missing, fails to import or defines a value that
    cannot be registered raises ``ValueError`` naming the file and the key that lists it; a file
    that failed is not kept as loaded."""
    for entry, path in in_load_order(config.get("extensions", []), base):
        where = f"config error at extensions: {entry!r} ({path})"
        if not path.is_file():
            raise ValueError(f"config error at extensions: {entry!r} is not a file ({path})")
        name = f"jointbench_extension_{path.stem}"
        module = sys.modules.get(name)
        if module is None or Path(module.__file__).resolve() != path:
            module = _imported(name, path, where)
        try:
            for value in vars(module).values():
                _register(value)
        except ValueError as error:
            raise ValueError(f"{where}: cannot be registered: {_reason(error, path)}") from error


def in_load_order(entries: Sequence[str], base: str | Path = ".") -> list[tuple[str, Path]]:
    """Each of the config's ``entries`` under ``extensions`` with its file (relative to
    ``base``), in the order of the files' names, then of their paths.

    What a file registers joins the registries in the order the files load, and the studies'
    order reaches the jobs' parameters (every study's settings): loaded in the order the config
    lists them, a reorder of the list would rerun jobs though no result changes. Built-in
    studies are in the order of their modules' names too."""
    files = [(entry, (Path(base) / entry).resolve()) for entry in entries]
    return sorted(files, key=lambda file: (file[1].name, str(file[1])))


def _imported(name: str, path: Path, where: str) -> ModuleType:
    """The module ``name`` executed from ``path``, in ``sys.modules`` only if it ran to its end;
    whatever it raises, as ``ValueError`` starting with ``where``."""
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    # Registered first: dataclasses look their module up while a class is being made.
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    except Exception as error:
        # Any exception: an extension is a user's code, and what it raises is named as theirs.
        del sys.modules[name]
        raise ValueError(f"{where}: cannot be imported: {_reason(error, path)}") from error
    return module


def _reason(error: BaseException, path: Path) -> str:
    """``error``'s type and message, after the last line of ``path`` it passed through (a
    syntax error names its own line)."""
    lines = [
        line
        for frame, line in traceback.walk_tb(error.__traceback__)
        if Path(frame.f_code.co_filename) == path
    ]
    where = f"line {lines[-1]}: " if lines and not isinstance(error, SyntaxError) else ""
    return f"{where}{type(error).__name__}: {error}"
