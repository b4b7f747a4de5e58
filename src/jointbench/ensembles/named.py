"""The members of a run's protocol ensembles, by name, and the named protocols they read: what
the workflow plans and ``jointbench fit --configfile`` checks alike, apart from
:mod:`jointbench.ensembles.sensitivity`, which runs and judges them (and whose figures and
tables a command that only opens a config does not load)."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

from jointbench import declared
from jointbench.configuration.config import (
    ConfigError,
    named_overlays,
    sources_named,
    study_names,
)
from jointbench.papers import papers_of_study
from jointbench.simulate import cmc, hinge_study, hip
from jointbench.simulate.prior import Prior

__all__ = ["DEFAULT", "DRAW_PREFIX", "PRIORS", "ensembles", "member_names"]

#: The prior of every study a protocol ensemble draws.
PRIORS: dict[str, Prior] = {
    prior.study: prior for prior in (cmc.PRIOR, hinge_study.PRIOR, hip.PRIOR)
}
DEFAULT = "default"
DRAW_PREFIX = "draw-"


def ensembles(
    config: Mapping, sources: Sequence[tuple[str, Mapping]], base: str | Path = "."
) -> tuple[dict[str, Mapping], dict[str, list[str]]]:
    """``(overlays, members)`` of a run of the opened ``config``: each named protocol's config
    overlay by name (:func:`~jointbench.configuration.config.named_overlays`, relative to
    ``base``) and the members of each switched-on study's ensemble in the config's order
    (:func:`member_names`), of the studies with a prior and a paper whose values it judges;
    where none has, no overlay is read. A mistake names the ``sources`` (``(name, document)``)
    that set its keys (:func:`~jointbench.configuration.config.sources_named`). The workflow
    and ``jointbench fit --configfile`` read a config's named protocols so alike."""
    studies = [s for s in study_names(config) if s in PRIORS and papers_of_study(s)]
    draws = int(config.get("sensitivity", {}).get("draws", 1))
    with sources_named(sources):
        overlays = named_overlays(config, base) if studies else {}
        members = {study: member_names(study, draws, overlays) for study in studies}
    return overlays, members


def member_names(study: str, draws: int, overlays: Mapping[str, Mapping]) -> list[str]:
    """Every member of ``study``'s ensemble: the default, ``draw-1`` to ``draw-<draws>`` and
    each named member whose overlay (a config document, by name) sets ``study``'s protocol;
    :class:`~jointbench.configuration.config.ConfigError` at ``sensitivity.named.<name>`` for
    one named as the default or a draw."""
    named = [
        name
        for name, overlay in overlays.items()
        if "protocol" in ((overlay or {}).get("studies", {}).get(study) or {})
    ]
    for name in named:
        if name == DEFAULT or name.startswith(DRAW_PREFIX):
            at = ("sensitivity", "named", name)
            raise ConfigError(
                f"config: {declared.key(at)}: named protocol {name!r} takes the name of a "
                "default or drawn one",
                [at],
            )
    return [DEFAULT, *(f"{DRAW_PREFIX}{k}" for k in range(1, draws + 1)), *named]
