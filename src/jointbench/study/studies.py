"""The study registry: every :class:`~jointbench.simulate.Study` the benchmark can run.

The built-in studies are collected by importing their simulator modules; a study outside the
package joins by :func:`register_study` (the workflow does this for the modules listed under
``extensions`` in the config, see :mod:`jointbench.extensions`).
"""

from __future__ import annotations

from jointbench.simulate import Study, cmc, hinge_study, hip

__all__ = ["get_study", "register_study", "study_names"]

_STUDIES: dict[str, Study] = {}


def register_study(study: Study) -> Study:
    """Add ``study`` to the registry; registering the same value twice is harmless."""
    known = _STUDIES.get(study.name)
    if known is not None and known is not study:
        raise ValueError(f"a different study named {study.name!r} is already registered")
    _STUDIES[study.name] = study
    return study


def get_study(name: str) -> Study:
    """The study called ``name``; ``ValueError`` listing the known studies otherwise."""
    try:
        return _STUDIES[name]
    except KeyError:
        raise ValueError(f"unknown study {name!r}; known: {', '.join(_STUDIES)}") from None


def study_names() -> tuple[str, ...]:
    """Names of the registered studies, built-ins first."""
    return tuple(_STUDIES)


for _study in (cmc.STUDY, hinge_study.STUDY, hip.STUDY):
    register_study(_study)
