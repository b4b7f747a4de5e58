"""What every workflow job shares: its context (extensions loaded, messages and any error written
to the rule's log) and the provenance its files record.

Each script in ``workflow/scripts`` runs its work inside :func:`job`, calling the module that
does it: :mod:`jointbench.study.run` to simulate, estimate, collect and summarise,
:mod:`jointbench.pipeline` for paper outputs, the extended ranking and the published-value check,
:mod:`jointbench.report` for the report's texts. This module imports none of them, so that a job
loads only what its own work needs.

Extensions (a study or paper outside the package, listed under ``extensions`` in the config) are
imported here, in the Snakemake process and in every job, so the rules and the jobs see the same
registries.
"""

from __future__ import annotations

import contextlib
import importlib.metadata
import importlib.util
import logging
import sys
from collections.abc import Iterator, Mapping
from pathlib import Path

from jointbench.simulate import Study
from jointbench.study.studies import register_study

__all__ = ["job", "load_extensions", "provenance"]

# The package's logger: every module's messages (``getLogger(__name__)``) reach the job's log
# through it.
log = logging.getLogger("jointbench")


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


@contextlib.contextmanager
def job(snakemake) -> Iterator[None]:
    """Run one Snakemake job's work: extensions loaded, messages and any error written to the
    job's log (the file Snakemake points to when the job fails)."""
    handlers = []
    for path in list(snakemake.log):
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        handler = logging.FileHandler(path, mode="w")
        handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(message)s"))
        handlers.append(handler)
        log.addHandler(handler)
    log.setLevel(logging.INFO)
    try:
        load_extensions(snakemake.config)
        log.info(
            "rule %s: %d input(s) -> %d output(s)",
            snakemake.rule,
            len(snakemake.input),
            len(snakemake.output),
        )
        yield
        log.info("done")
    except Exception:
        log.exception("rule %s failed", snakemake.rule)
        raise
    finally:
        for handler in handlers:
            log.removeHandler(handler)
            handler.close()


def provenance(snakemake) -> dict[str, object]:
    """What a job's files record of how they were made: the package version, the rule, the
    fingerprint of the code it ran, and the config values its study depends on."""
    study = getattr(snakemake.params, "study", None) or snakemake.wildcards.get("study")
    settings = snakemake.config.get("studies", {}).get(study, {}) if study else {}
    return {
        "jointbench": importlib.metadata.version("jointbench"),
        "rule": snakemake.rule,
        "code": getattr(snakemake.params, "code", ""),
        "config": {"base_seed": snakemake.config.get("base_seed"), "study": settings},
    }
