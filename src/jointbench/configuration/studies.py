"""The study registry: every :class:`~jointbench.simulate.Study` the benchmark can run.

The built-in studies are collected by importing every simulator module (each module of
:mod:`jointbench.simulate` that exports a ``STUDY``, in module name order); a study outside the
package joins by :func:`register_study` (the workflow does this for the modules listed under
``extensions`` in the config, see :func:`jointbench.configuration.extensions.load_extensions`).
"""

from __future__ import annotations

import importlib

from jointbench.estimators import registry
from jointbench.registries import Registry, exported, submodules
from jointbench.simulate import Study

__all__ = ["get_study", "method_kind", "register_study", "study_names"]

_STUDIES: Registry[Study] = Registry("study", lambda study: study.name)
register_study = _STUDIES.register
get_study = _STUDIES.get
study_names = _STUDIES.names

_SIMULATORS = [importlib.import_module(name) for name in submodules("jointbench.simulate")]
for _study in exported(_SIMULATORS, "STUDY"):
    register_study(_study)


def method_kind(study: Study, method: str) -> str:
    """The kind under which ``study`` runs ``method``: the first of its kinds whose registry
    holds the name. A name no kind registers (an estimator with a rule of its own) runs as the
    study's own :attr:`~jointbench.simulate.Study.kind`, the kind its rule's file is scored as.
    """
    return next((kind for kind in study.kinds if method in registry.methods(kind)), study.kind)
