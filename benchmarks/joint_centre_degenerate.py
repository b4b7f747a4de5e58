"""Joint centres from degenerate two-segment trials: which answers the checked calls pass as ``ok``.

Usage::

    python benchmarks/joint_centre_degenerate.py [--seeds 6] [--rows]

Every registered joint-centre method (``jointbench.methods("joint_center")``) is called through
``jointbench.fit_joint_center`` on simulated trials whose centre is known: a proximal segment
that sways and drifts in the world (four markers), a distal one (four markers, 120 to 300 mm
from the joint) moving about a ball joint on top of it, 200 frames, 0.5 mm noise where no other
is named. The cases:

* a 30 degree circumduction (the control);
* the distal segment not moving relative to the proximal one;
* pure hinges of 60 and 20 degrees, and near-hinges (a 60 degree flexion with a second rotation
  of 2, 5 and 10 % of it);
* circumductions of 1, 2 and 3 degrees with 0.5 and 1 mm noise;
* 3, 4, 5 and 8 frames (the methods' fewest is 3);
* distal markers 0.4 and 2 mm off a line;
* distal markers sliding 5 and 10 mm on their segment with the joint angle (skin);
* two distal markers swapped on one frame;
* gaps that leave 4, 6, 10 and 20 frames with every marker (the frames a recording keeps);
* the proximal segment translating only, the distal one rotating;
* the data in metres, and 1e4 mm from the origin;
* the segments given in the wrong order.

Prints, per case and method, how many of the seeded trials read ``ok`` (or raised), the largest
error of an ``ok`` answer [mm] and the largest Mahalanobis distance of one from the truth under
the covariance its SD is read from (``centre_precision.stated_covariance``); ``--rows`` prints
every trial with its status. An ``ok`` answer more than a few millimetres off, or many of its
SDs, is one the checks should not have passed. SARA has no checked two-segment form (the
registered ``axis`` method takes one segment), so it is not among them.
"""

from __future__ import annotations

import argparse
from collections.abc import Iterator

import numpy as np

import jointbench
from jointbench import geometry
from jointbench.estimators.centre_precision import stated_covariance
from jointbench.simulate.noise import isotropic_noise

PROXIMAL = np.array([[0.0, 0.0, 0.0], [80.0, 0.0, 10.0], [20.0, 70.0, -15.0], [60.0, 50.0, 20.0]])
CENTRE_IN_PROXIMAL = np.array([40.0, 30.0, -90.0])
#: The distal markers about the joint, in the proximal frame's directions at rest [mm].
DISTAL = np.array(
    [[30.0, 10.0, -120.0], [-25.0, 20.0, -200.0], [5.0, -30.0, -300.0], [40.0, 30.0, -250.0]]
)
Z = np.array([0.0, 0.0, 1.0])
X = np.array([1.0, 0.0, 0.0])

Trial = tuple[np.ndarray, np.ndarray, np.ndarray]


def circumduction(rom_deg: float, n_frames: int) -> tuple[np.ndarray, np.ndarray]:
    """Rotations ``(N, 3, 3)`` spiralling out to ``rom_deg`` in three turns, and their angles
    ``(N,)`` [rad]."""
    t = np.linspace(0.0, 1.0, n_frames)
    angle, phase = np.radians(rom_deg) * t, 6.0 * np.pi * t
    rotvec = np.stack([angle * np.cos(phase), angle * np.sin(phase), np.zeros_like(t)], axis=-1)
    return geometry.rotation_matrix(rotvec), angle


def hinge(rom_deg: float, n_frames: int, second: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A flexion over ``rom_deg`` about z, with a rotation about x of ``second`` times its
    amplitude at twice its frequency: rotations ``(N, 3, 3)`` and flexion angles ``(N,)``
    [rad]."""
    phase = np.linspace(0.0, 2.0 * np.pi, n_frames)
    flexion = np.radians(rom_deg / 2.0) * np.sin(phase)
    across = second * np.radians(rom_deg / 2.0) * np.cos(2.0 * phase)
    rotations = geometry.rotation_about_axis(Z, flexion) @ geometry.rotation_about_axis(X, across)
    return rotations, flexion


def still(n_frames: int) -> tuple[np.ndarray, np.ndarray]:
    """No relative rotation: identities ``(N, 3, 3)`` and zero angles ``(N,)``."""
    return np.broadcast_to(np.eye(3), (n_frames, 3, 3)), np.zeros(n_frames)


def proximal_motion(n_frames: int, rotates: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The proximal segment's rotations ``(N, 3, 3)`` (a sway, or one fixed tilt) and
    positions ``(N, 3)`` [mm] (a drift 900 mm from the origin)."""
    t = np.linspace(0.0, 1.0, n_frames)
    sway = 0.15 * np.stack([np.sin(3 * t), np.sin(5 * t + 1), np.cos(4 * t)], axis=-1)
    if not rotates:
        sway = np.broadcast_to([0.1, -0.2, 0.3], sway.shape)
    position = np.stack([300 * t, 20 * np.sin(7 * t), 900 + 10 * t], axis=-1)
    return geometry.rotation_matrix(sway), position


def two_segments(
    rng: np.random.Generator,
    joint: tuple[np.ndarray, np.ndarray],
    *,
    noise_mm: float = 0.5,
    proximal_rotates: bool = True,
    distal: np.ndarray = DISTAL,
    sliding_mm: float = 0.0,
) -> Trial:
    """Noisy proximal and distal markers ``(N, 4, 3)`` [mm] in the world and the joint's world
    position in every frame ``(N, 3)`` [mm], the distal segment turned by ``joint`` (relative
    rotations and angles) about the joint; its markers slide ``sliding_mm`` at the largest
    angle, each along a direction of its own, in proportion to the angle."""
    rotations, angles = joint
    proximal_rotation, proximal_position = proximal_motion(len(angles), proximal_rotates)
    centre = proximal_rotation @ CENTRE_IN_PROXIMAL + proximal_position
    body = np.broadcast_to(distal, (len(angles), *distal.shape))
    if sliding_mm:
        directions = rng.normal(size=distal.shape)
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        share = angles / np.abs(angles).max()
        body = body + sliding_mm * share[:, None, None] * directions
    proximal = np.einsum("kij,pj->kpi", proximal_rotation, PROXIMAL) + proximal_position[:, None]
    moved = np.einsum("kij,kpj->kpi", proximal_rotation @ rotations, body) + centre[:, None]
    return (
        proximal + isotropic_noise(rng, proximal.shape[:2], noise_mm),
        moved + isotropic_noise(rng, moved.shape[:2], noise_mm),
        centre,
    )


def nearly_collinear(off_mm: float) -> np.ndarray:
    """Four distal markers ``(4, 3)`` [mm] 60 mm apart along a line, up to ``off_mm`` off it."""
    line = np.array([1.0, 0.3, -0.5]) / np.linalg.norm([1.0, 0.3, -0.5])
    off = off_mm * np.array([[0.0, 0.0, 0.0], [0.75, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.75]])
    return np.array([30.0, 10.0, -150.0]) + np.outer([0.0, 60.0, 120.0, 180.0], line) + off


def frames_kept(rng: np.random.Generator, trial: Trial, n_kept: int) -> Trial:
    """``trial`` with only ``n_kept`` frames, drawn at random in order: those a recording
    with gaps keeps with every marker."""
    kept = np.sort(rng.choice(len(trial[0]), n_kept, replace=False))
    return tuple(array[kept] for array in trial)


def swapped(trial: Trial, frame: int) -> Trial:
    """``trial`` with the first two distal markers exchanged on ``frame``."""
    distal = trial[1].copy()
    distal[frame, [0, 1]] = distal[frame, [1, 0]]
    return trial[0], distal, trial[2]


def cases(rng: np.random.Generator) -> Iterator[tuple[str, Trial, float]]:
    """Each case's name, trial and the factor [mm per unit] of its coordinates."""
    yield "control", two_segments(rng, circumduction(30.0, 200)), 1.0
    yield "no relative motion", two_segments(rng, still(200)), 1.0
    for rom in (60.0, 20.0):
        yield f"hinge {rom:g} deg", two_segments(rng, hinge(rom, 200)), 1.0
    for second in (0.02, 0.05, 0.1):
        yield f"near-hinge {second:g}", two_segments(rng, hinge(60.0, 200, second)), 1.0
    for rom in (1.0, 2.0, 3.0):
        for noise in (0.5, 1.0):
            trial = two_segments(rng, circumduction(rom, 200), noise_mm=noise)
            yield f"rom {rom:g} deg, {noise:g} mm", trial, 1.0
    for n_frames in (3, 4, 5, 8):
        yield f"{n_frames} frames", two_segments(rng, circumduction(30.0, n_frames)), 1.0
    for off in (0.4, 2.0):
        trial = two_segments(rng, circumduction(30.0, 200), distal=nearly_collinear(off))
        yield f"collinear {off:g} mm", trial, 1.0
    for sliding in (5.0, 10.0):
        trial = two_segments(rng, circumduction(30.0, 200), sliding_mm=sliding)
        yield f"sliding {sliding:g} mm", trial, 1.0
    yield "swap on one frame", swapped(two_segments(rng, circumduction(30.0, 200)), 100), 1.0
    for kept in (4, 6, 10, 20):
        trial = frames_kept(rng, two_segments(rng, circumduction(30.0, 200)), kept)
        yield f"gaps keep {kept} frames", trial, 1.0
    trial = two_segments(rng, circumduction(30.0, 200), proximal_rotates=False)
    yield "proximal translates", trial, 1.0
    proximal, distal, centre = two_segments(rng, circumduction(30.0, 200))
    yield "metres", (proximal / 1000.0, distal / 1000.0, centre / 1000.0), 1000.0
    yield "1e4 mm away", (proximal + 1e4, distal + 1e4, centre + 1e4), 1.0
    yield "order swapped", (distal, proximal, centre), 1.0


def outcome(method: str, trial: Trial, unit_mm: float) -> tuple[str, float, float]:
    """The checked call's status (``"raised: ..."`` for a refusal), its error [mm] and its
    Mahalanobis distance from the truth (the centre at frame 0) under the covariance its SD
    is read from (NaN where it states none)."""
    proximal, distal, centre = trial
    try:
        result = jointbench.fit_joint_center(proximal, distal, method)
    except ValueError as error:
        return f"raised: {error}", np.nan, np.nan
    error_mm = (result.center - centre[0]) * unit_mm
    stated = stated_covariance(result)
    distance = np.nan
    if stated is not None and np.isfinite(stated[0]).all():
        distance = float(np.sqrt(error_mm @ np.linalg.lstsq(stated[0], error_mm, rcond=None)[0]))
    return result.status, float(np.linalg.norm(error_mm)), distance


def sweep(seeds: int) -> dict[tuple[str, str], list[tuple[str, float, float]]]:
    """Every case's outcome per method over ``seeds`` seeds, by (case, method)."""
    outcomes: dict[tuple[str, str], list] = {}
    for seed in range(seeds):
        for name, trial, unit_mm in cases(np.random.default_rng(seed)):
            for method in jointbench.methods("joint_center"):
                outcomes.setdefault((name, method), []).append(outcome(method, trial, unit_mm))
    return outcomes


def summary_line(name: str, method: str, rows: list[tuple[str, float, float]]) -> str:
    """One case's and method's line: ``ok`` and raised counts, the largest error and
    Mahalanobis distance of an ``ok`` answer."""
    passed = [(error, distance) for status, error, distance in rows if status == "ok"]
    raised = sum(status.startswith("raised") for status, _, _ in rows)
    worst = max((error for error, _ in passed), default=np.nan)
    farthest = max((distance for _, distance in passed), default=np.nan)
    return (
        f"{name:22s} {method:20s} ok {len(passed):2d}/{len(rows)}  raised {raised:2d}  "
        f"worst ok {worst:7.2f} mm  {farthest:6.2f} SDs"
    )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=6)
    parser.add_argument("--rows", action="store_true", help="print every trial's status")
    arguments = parser.parse_args(argv)
    outcomes = sweep(arguments.seeds)
    for (name, method), rows in outcomes.items():
        print(summary_line(name, method, rows))
        if arguments.rows:
            for status, error, distance in rows:
                print(f"    {error:8.2f} mm {distance:7.2f} SDs  {status[:160]}")


if __name__ == "__main__":
    main()
