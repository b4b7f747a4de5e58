"""The study registry: every :class:`~jointbench.simulate.Study` the benchmark can run.

The built-in studies are collected by importing their simulator modules; a study outside the
package joins by :func:`register_study` (the workflow does this for the modules listed under
``extensions`` in the config, see :func:`jointbench.jobs.load_extensions`).
"""

from __future__ import annotations

from jointbench.registries import Registry
from jointbench.simulate import Study, cmc, hinge_study, hip, hip_sta

__all__ = ["get_study", "register_study", "study_names"]

_STUDIES: Registry[Study] = Registry("study", lambda study: study.name)
register_study = _STUDIES.register
get_study = _STUDIES.get
study_names = _STUDIES.names

for _study in (cmc.STUDY, hinge_study.STUDY, hip.STUDY, hip_sta.STUDY):
    register_study(_study)
