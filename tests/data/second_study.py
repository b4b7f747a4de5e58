"""A second extension beside the toy study of ``fourth_study/``: a study of its own, the thumb
CMC simulation under another name, so that a run lists two extensions, each with a study, whose
order in the config must reach no job, and whose title comes from a module of the user's own
that it imports, ``second_helper.py`` (``tests/test_stale_results.py``)."""

from __future__ import annotations

import dataclasses

from second_helper import TITLE

import jointbench.simulate.cmc as cmc

STUDY = dataclasses.replace(cmc.STUDY, name="second", title=TITLE)
