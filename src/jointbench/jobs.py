"""What every workflow job shares: its context (extensions loaded, messages and any error written
to the rule's log) and the provenance its files record.

Each script in ``workflow/scripts`` runs its work inside :func:`job`, calling the module that
does it: :mod:`jointbench.running.run` to simulate, estimate, collect and summarise,
:mod:`jointbench.pipeline` for paper outputs, the extended ranking and the published-value check,
:mod:`jointbench.report` for the report's texts. This module imports none of them, so that a job
loads only what its own work needs.

Every job loads the run's extensions (a study or paper outside the package, listed under
``extensions`` in the config; :mod:`jointbench.configuration.extensions`), as the Snakemake
process does, so the rules and the jobs see the same registries.
"""

from __future__ import annotations

import contextlib
import importlib.metadata
import logging
from collections.abc import Iterator
from pathlib import Path

from jointbench.configuration.extensions import load_extensions

__all__ = ["job", "provenance"]

# The package's logger: every module's messages (``getLogger(__name__)``) reach the job's log
# through it.
log = logging.getLogger("jointbench")


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
