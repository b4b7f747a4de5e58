"""Extensions: a study or paper outside the package, a module listed under ``extensions`` in the
config, imported and its ``Study`` and ``Paper`` values registered. The Snakemake process and the
command line load them when they open a run's config
(:func:`jointbench.configuration.config.open_config`), every job when it starts
(:func:`jointbench.jobs.job`).
"""

from __future__ import annotations

import importlib.util
import sys
from collections.abc import Mapping
from pathlib import Path

from jointbench.configuration.studies import register_study
from jointbench.simulate import Study

__all__ = ["load_extensions"]


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
    it defines. Importing the same file again is a no-op."""
    for entry in config.get("extensions", []):
        path = (Path(base) / entry).resolve()
        if not path.is_file():
            raise ValueError(f"config error at extensions: {entry!r} is not a file ({path})")
        name = f"jointbench_extension_{path.stem}"
        module = sys.modules.get(name)
        if module is None or Path(module.__file__).resolve() != path:
            spec = importlib.util.spec_from_file_location(name, path)
            module = importlib.util.module_from_spec(spec)
            sys.modules[name] = module
            spec.loader.exec_module(module)
        for value in vars(module).values():
            _register(value)
