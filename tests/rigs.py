"""A noise-free two-segment rig joined by a ball joint, shared by the two-segment tests; one
segment moving about the joint in the reference frame; two outcomes compared field by field."""

from __future__ import annotations

import dataclasses

import numpy as np

from jointbench.geometry import rotation_matrix, unit

JOINT = np.array([30.0, -20.0, 900.0])
PROXIMAL = JOINT + np.array([[90.0, 0.0, 500.0], [-60.0, 90.0, 520.0], [-50.0, -100.0, 480.0]])
DISTAL = JOINT + np.array([[80.0, 20.0, -500.0], [-70.0, 80.0, -470.0], [-30.0, -90.0, -530.0]])
HINGE = unit(np.array([1.0, 0.3, -0.2]))


def apply_pose(rotation, translation, body):
    return body @ np.swapaxes(rotation, -1, -2) + translation[:, None, :]


def two_segments(n_frames=200, *, relative="ball", proximal_moves=True):
    """Noise-free world markers of two segments joined at JOINT (poses = identity at frame 0).

    ``relative``: "ball" (rotation about three axes), "hinge" (about HINGE only) or "none".
    """
    t = np.linspace(0.0, 4.0, n_frames)
    s = np.sin
    scale = 1.0 if proximal_moves else 0.0
    r0 = rotation_matrix(scale * np.stack([0.1 * s(t), 0.07 * s(0.7 * t), 0.05 * s(1.3 * t)], -1))
    d0 = scale * np.stack([40 * s(0.5 * t), 30 * s(0.8 * t), 20 * s(1.1 * t)], -1)
    if relative == "ball":
        rel = np.stack([0.6 * s(1.9 * t), 0.4 * s(1.3 * t), 0.15 * s(2.3 * t)], -1)
    elif relative == "hinge":
        rel = 0.7 * s(1.9 * t)[:, None] * HINGE
    else:
        rel = np.zeros((n_frames, 3))
    r1 = r0 @ rotation_matrix(rel)
    d1 = r0 @ JOINT + d0 - r1 @ JOINT
    return apply_pose(r0, d0, PROXIMAL), apply_pose(r1, d1, DISTAL)


def one_segment(n_frames: int, motion: str = "ball") -> np.ndarray:
    """Noise-free markers ``(N, 3, 3)`` [mm] of DISTAL moving about JOINT in the reference frame:
    ``"ball"`` about three axes, ``"hinge"`` about HINGE only."""
    t = np.linspace(0.0, 4.0, n_frames)
    if motion == "hinge":
        rotvec = 0.7 * np.sin(1.9 * t)[:, None] * HINGE
    else:
        rotvec = np.stack([0.6 * np.sin(1.9 * t), 0.4 * np.sin(1.3 * t), 0.1 * np.sin(t)], -1)
    rotation = rotation_matrix(rotvec)
    return apply_pose(rotation, JOINT - rotation @ JOINT, DISTAL)


def assert_same_outcome(found, expected) -> None:
    """``found`` is ``expected``: the same error type and words, or every field of the result
    equal to the bit."""
    if isinstance(expected, Exception):
        assert type(found) is type(expected) and str(found) == str(expected), (found, expected)
        return
    assert not isinstance(found, Exception), found
    for field in dataclasses.fields(expected):
        np.testing.assert_equal(getattr(found, field.name), getattr(expected, field.name))
