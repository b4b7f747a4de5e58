"""A toy fourth study and its paper, outside the package: how a user adds both.

The study spins three markers about a known centre; the paper draws one figure and publishes two
values (one that holds, one that does not, with its recorded reason).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from jointbench.estimators import CenterResult, register
from jointbench.papers import Inputs, Measured, Output, Paper
from jointbench.simulate import GridValues, Study, Trials, isotropic_noise

CENTRE = np.array([10.0, -5.0, 20.0])


@dataclass(frozen=True)
class ToyProtocol:
    """Markers at 40–60 mm from the centre, swinging ±30° about two axes, 60 frames."""

    n_frames: int = 60

    @classmethod
    def from_config(cls, overrides=None) -> ToyProtocol:
        return cls(**(overrides or {}))


def simulate(condition, protocol: ToyProtocol, rngs) -> Trials:
    angles = np.radians(30.0) * np.sin(np.linspace(0.0, 2 * np.pi, protocol.n_frames))
    body = np.array([[40.0, 0.0, 0.0], [0.0, 50.0, 0.0], [0.0, 0.0, 60.0]])
    frames = []
    for a, b in zip(angles, np.roll(angles, protocol.n_frames // 4), strict=True):
        rx = np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])
        ry = np.array([[np.cos(b), 0, np.sin(b)], [0, 1, 0], [-np.sin(b), 0, np.cos(b)]])
        frames.append(body @ (ry @ rx).T + CENTRE)
    clean = np.asarray(frames)
    noisy = np.stack(
        [
            clean + isotropic_noise(rng, clean.shape[:-1], float(condition["noise_mm"]))
            for rng in rngs
        ]
    )
    return Trials(segments={"moving": noisy}, truth={"center": CENTRE.tolist()})


def frame_count(condition, protocol: ToyProtocol) -> int:
    """The frames of every trial: read from the protocol, so that the config's check counts
    them without simulating one."""
    return protocol.n_frames


@register("center", "toy-centroid")
def fit_centroid(markers: np.ndarray) -> CenterResult:
    """The mean marker position, (n_frames, n_markers, 3) [mm] -> (3,) [mm]: a user's estimator."""
    return CenterResult(
        center=markers.reshape(-1, 3).mean(axis=0),
        converged=True,
        iterations=0,
        status="ok",
        method="toy-centroid",
    )


STUDY = Study(
    name="toy",
    kind="center",
    grid_keys=("noise_mm",),
    seed_keys=("noise_mm",),
    segments=("moving",),
    protocol_class=ToyProtocol,
    simulate=simulate,
    frame_count=frame_count,
    # What each grid key allows: checked before any job runs, naming the key.
    grid_spec={"noise_mm": GridValues(float, minimum=0)},
)


def measure(inputs: Inputs) -> dict[str, Measured]:
    means = inputs.collected.groupby(["method", "noise_mm"])["error_mm"].mean()
    nm = float(means[("NM", 0.5)])
    ls = float(means[("LS", 1.0)])
    return {"T1": Measured(nm, f"{nm:.2f} mm"), "T2": Measured(ls, f"{ls:.2f} mm")}


def errors_figure(inputs: Inputs):
    fig, ax = plt.subplots(figsize=(4, 3))
    means = inputs.collected.groupby(["method", "noise_mm"])["error_mm"].mean().unstack(0)
    means.plot(ax=ax, marker="o")
    ax.set_xlabel("noise SD (mm)")
    ax.set_ylabel("mean centre error (mm)")
    return fig


PAPER = Paper(
    key="paper_t",
    letter="T",
    title="Paper T: a toy study",
    citation="Toy (2026), a fourth study for the extension test",
    study="toy",
    methods=("NM", "LS"),
    published=Path(__file__).with_name("paper_t.yaml"),
    measure=measure,
    outputs=(
        Output(
            "paper_t_errors",
            "figure",
            errors_figure,
            caption="Mean centre error of NM and LS against the noise level, toy study.",
        ),
    ),
)
