"""Synthetic marker data with known ground truth.

Every study's simulator has the signature::

    simulate(condition: Mapping[str, object], protocol: <Study>Protocol,
             rngs: Sequence[numpy.random.Generator]) -> Trials

``condition`` holds one cell of the study's grid (e.g. ``{"marker_set": "M", "rom_deg": 5,
"noise_mm": 1.0}``), ``protocol`` the study's documented, configurable modelling choices, and
``rngs`` one generator per trial (seeded from study, condition and trial). The nominal motion is
a deterministic function of ``condition`` and ``protocol``; the generators draw what varies
between trials.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from jointbench.simulate.noise import isotropic_noise

__all__ = ["Trials", "isotropic_noise"]


@dataclass(frozen=True)
class Trials:
    """Simulated trials of one condition.

    ``segments`` maps a segment name to its markers ``(n_trials, n_frames, n_markers, 3)`` [mm]:
    ``"moving"`` for one-segment studies (markers in the reference segment's frame), or
    ``"proximal"`` and ``"distal"`` (world frame) for two-segment studies. ``truth`` holds the
    JSON-serialisable ground truth shared by all trials (``"center"``; or ``"axis_point"`` and
    ``"axis_direction"``), ``parameters`` the generator settings for provenance.
    """

    segments: dict[str, np.ndarray]
    truth: dict[str, list[float]]
    parameters: dict[str, object] = field(default_factory=dict)

    @property
    def n_trials(self) -> int:
        return next(iter(self.segments.values())).shape[0]
