"""The study registry: every :class:`~jointbench.simulate.Study` the benchmark can run.

The built-in studies are collected by importing every simulator module (each module of
:mod:`jointbench.simulate` that exports a ``STUDY``, in module name order); a study outside the
package joins by :func:`register_study` (the workflow does this for the modules listed under
``extensions`` in the config, see :func:`jointbench.configuration.extensions.load_extensions`).
"""

from __future__ import annotations

import importlib

from jointbench.registries import Registry, exported, submodules
from jointbench.simulate import Study

__all__ = ["get_study", "register_study", "study_names"]

_STUDIES: Registry[Study] = Registry("study", lambda study: study.name)
register_study = _STUDIES.register
get_study = _STUDIES.get
study_names = _STUDIES.names

_SIMULATORS = [importlib.import_module(name) for name in submodules("jointbench.simulate")]
for _study in exported(_SIMULATORS, "STUDY"):
    register_study(_study)
