"""The ranges a motion-capture study's protocol quantities can have, each with its reason.

The studies' protocol fields are declared with these types (:mod:`jointbench.declared`), so
the config's check refuses a value out of its range before any job, naming
``studies.<study>.protocol.<field>`` and the value: a typo (``1e300``, ``-1e30``, ``1e-300``)
stops the run there instead of failing inside a simulation ("SVD did not converge") or writing
inf or NaN markers. Every bound holds the papers' values and the priors' draws with room to
spare; ranges that depend on other fields (a frequency below half the frame rate, the turns of
a motion against its frames) are in :mod:`jointbench.configuration.bounds`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Annotated

from jointbench.declared import DeclarationError, Range

__all__ = [
    "LAB_MM",
    "MAX_DURATION_S",
    "MAX_FPS",
    "RESOLUTION_MM",
    "ROTATION_DEG",
    "SEGMENT_MM",
    "TURN_DEG",
    "Angle",
    "Duration",
    "FrameRate",
    "LabPoint",
    "MarkerDistance",
    "MarkerOffset",
    "Rotation",
    "Rotations",
    "TimeConstant",
    "check_marker_offsets",
]

#: [mm] A position in the world (lab) frame, or a displacement of a whole segment in it, lies
#: within this of the origin on each axis: a motion-capture volume is a few metres to tens of
#: metres across, and 100 m holds any of them; the rounding of a coordinate there (about 1e-11
#: mm) stays far below any marker noise, while at 1e30 mm nothing of a marker's millimetres is
#: left and the pose fits fail ("SVD did not converge").
LAB_MM = 1e5
#: [mm] A marker lies at most this far from the joint centre it is simulated about, on each axis
#: and in distance: markers sit on the segments either side of the joint, and the longest of
#: them (a leg, about 1 m; paper C's rig carries its markers about 0.5 m from the joint) holds
#: none 2 m away.
SEGMENT_MM = 2000.0
#: [mm] A marker lies at least this far from the joint centre: a tenth of what optical motion
#: capture resolves, so a marker nearer is on the centre, turned by no rotation about it, and
#: the marker noise a study may simulate, bounded by the farthest marker's distance
#: (:func:`jointbench.simulate.noise.largest_noise_mm`), would vanish with it.
RESOLUTION_MM = 0.01
#: [deg] A rotation's amplitude (a swing, a twist, a segment's sway) lies within a half turn
#: either way: a rotation further reaches the poses of a smaller one the other way, and at
#: 1e300 deg its cosines are rounding alone (non-finite markers).
ROTATION_DEG = 180.0
#: [deg] A phase or a direction's azimuth lies within one turn either way, which names every
#: one with either sign.
TURN_DEG = 360.0

#: [Hz] A recording's frame rate is at most this: optical motion-capture cameras record at up
#: to a few kHz (about 10 kHz in a reduced window), and none at 100 kHz.
MAX_FPS = 1e5
#: [s] A recording lasts at most a day: a functional trial takes seconds to minutes, and its
#: frames (``duration_s`` times ``fps``) must still be a count the frame check can bound.
MAX_DURATION_S = 86400.0

#: A frame rate [Hz].
FrameRate = Annotated[float, Range(0, MAX_FPS, exclusive_minimum=True)]
#: A recording's duration [s].
Duration = Annotated[float, Range(0, MAX_DURATION_S, exclusive_minimum=True)]
#: A time constant [s]: at least one frame at the fastest frame rate, :data:`MAX_FPS`; a
#: shorter one is an instant step in any recording, the same as that one, and its ratio to a
#: recording's times overflows.
TimeConstant = Annotated[float, Range(1 / MAX_FPS)]
#: A coordinate [mm] of a position or a segment's displacement in the world frame.
LabCoordinate = Annotated[float, Range(-LAB_MM, LAB_MM)]
#: ``(x, y, z)`` [mm] of a position or a displacement in the world frame.
LabPoint = tuple[LabCoordinate, LabCoordinate, LabCoordinate]
#: A coordinate [mm] of a marker relative to its joint centre.
MarkerCoordinate = Annotated[float, Range(-SEGMENT_MM, SEGMENT_MM)]
#: ``(x, y, z)`` [mm] of a marker relative to its joint centre (its distance is checked by
#: :func:`check_marker_offsets`).
MarkerOffset = tuple[MarkerCoordinate, MarkerCoordinate, MarkerCoordinate]
#: A marker's distance [mm] from its joint centre.
MarkerDistance = Annotated[float, Range(RESOLUTION_MM, SEGMENT_MM)]
#: A rotation's amplitude [deg], of either sign.
Rotation = Annotated[float, Range(-ROTATION_DEG, ROTATION_DEG)]
#: Rotation amplitudes [deg] about the three axes.
Rotations = tuple[Rotation, Rotation, Rotation]
#: A phase or an azimuth [deg].
Angle = Annotated[float, Range(-TURN_DEG, TURN_DEG)]


def check_marker_offsets(name: str, markers_mm: Sequence[Sequence[float]]) -> None:
    """Raise :class:`~jointbench.declared.DeclarationError` at ``name[index]`` for the first of
    ``markers_mm`` ``(n, 3)`` [mm, relative to the joint centre] whose distance from the centre
    is not within ``[RESOLUTION_MM, SEGMENT_MM]``."""
    for index, marker in enumerate(markers_mm):
        distance = math.hypot(*marker)  # without overflow, unlike the sum of squares
        if not RESOLUTION_MM <= distance <= SEGMENT_MM:
            raise DeclarationError(
                (name, index),
                f"{list(marker)!r} lies {distance:.3g} mm from the joint centre, not "
                f"within [{RESOLUTION_MM:g}, {SEGMENT_MM:g}] mm: a marker nearer than "
                f"{RESOLUTION_MM:g} mm is on the centre, turned by no rotation about it; one "
                f"further than {SEGMENT_MM:g} mm is on no body segment",
            )
