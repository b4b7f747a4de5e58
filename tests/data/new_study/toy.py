"""A toy study in the package: three markers swinging about a known centre (the recipe's test)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from jointbench.geometry import rotation_matrix
from jointbench.simulate import GridValues, Study, Trials, isotropic_noise

__all__ = ["STUDY", "ToyProtocol", "simulate"]

CENTRE = (10.0, -5.0, 20.0)


@dataclass(frozen=True)
class ToyProtocol:
    """Markers 40–60 mm from the centre, swinging ±30° about two axes over ``n_frames``."""

    n_frames: int = 60

    @classmethod
    def from_config(cls, overrides=None) -> ToyProtocol:
        return cls(**(overrides or {}))


def simulate(condition, protocol: ToyProtocol, rngs) -> Trials:
    """Trials of one noise level: markers ``(n_trials, n_frames, 3, 3)`` [mm]."""
    phase = np.linspace(0.0, 2 * np.pi, protocol.n_frames)
    angles = np.radians(30.0) * np.stack([np.sin(phase), np.cos(phase), 0 * phase], axis=1)
    body = np.diag([40.0, 50.0, 60.0])
    clean = np.einsum("fij,mj->fmi", rotation_matrix(angles), body) + CENTRE
    noise = float(condition["noise_mm"])
    markers = np.stack([clean + isotropic_noise(rng, clean.shape[:-1], noise) for rng in rngs])
    return Trials(segments={"moving": markers}, truth={"center": list(CENTRE)})


STUDY = Study(
    name="toy",
    kind="center",
    grid_keys=("noise_mm",),
    seed_keys=("noise_mm",),
    segments=("moving",),
    protocol_class=ToyProtocol,
    simulate=simulate,
    frame_count=lambda condition, protocol: protocol.n_frames,
    grid_spec={"noise_mm": GridValues(float, minimum=0, label="noise", text="σ {:g} mm")},
    title="toy centre",
)
