"""The hinge study: paper B's knee and index-MCP protocols, chosen by the condition.

The joint models themselves, with every modelling choice documented, are in
:mod:`jointbench.simulate.hinge`; this module holds the pair the study runs and applies the
config's overrides: ``protocol: {all: {...}, knee: {...}, mcp: {...}}``, where ``all`` applies
to both joints (e.g. the motion model) and a joint's own entry to that joint.

:data:`PRIOR` spans the marker layouts within the anatomical bounds the default layouts were
searched in (:mod:`jointbench.simulate.hinge`); the defaults, fitted to paper B's Table 1, are
one of its members.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from jointbench.declared import DeclarationError
from jointbench.declared import check_fields as check_declared
from jointbench.simulate import GridValues, Study, Trials, hinge
from jointbench.simulate.prior import Choice, Prior

__all__ = ["PRIOR", "STUDY", "HingeStudyProtocol", "placed_fields", "simulate"]


@dataclass(frozen=True)
class HingeStudyProtocol:
    """The joints of the hinge study by name (``"knee"``, ``"mcp"``)."""

    joints: dict[str, hinge.HingeProtocol]

    @classmethod
    def from_config(cls, overrides: Mapping[str, Mapping] | None = None) -> HingeStudyProtocol:
        """Each joint's protocol: its built-in defaults, updated by ``all``, then by its own
        entry (a name not built in adds a joint, which must give every field)."""
        overrides = dict(overrides or {})
        # Checked where they are written, so that a mistake under ``all`` is named there.
        for key, settings in overrides.items():
            if not isinstance(settings, Mapping):
                raise DeclarationError(
                    (key,), f"must be a mapping of HingeProtocol fields, got {settings!r}"
                )
            check_declared(hinge.HingeProtocol, settings, (key,))
        written = dict(overrides)
        shared = dict(overrides.pop("all", {}))
        joints = {}
        for name in sorted(set(hinge.HINGE_PROTOCOLS) | set(overrides)):
            settings = {"name": name, **shared, **overrides.get(name, {})}
            try:
                joints[name] = hinge.protocol_from_config(settings)
            except DeclarationError as error:
                raise _named_where_written(error, written, name) from None
        return cls(joints)


def placed_fields(overrides: Mapping, joint: str, fields: Sequence[str]) -> list[tuple[str, str]]:
    """``(entry, field)`` of each of ``fields`` of ``joint``: where the config's hinge protocol
    ``overrides`` set it. A field is the joint's own entry's where set there, else ``all``'s
    where set there, else the joint's (its default), e.g. ``[("all", "noise_sd_mm"), ("knee",
    "markers_mm")]``: a bound across fields names each where it is written."""

    def entry(field: str) -> str:
        own = field in (overrides.get(joint) or {})
        return "all" if not own and field in (overrides.get("all") or {}) else joint

    return [(entry(field), field) for field in fields]


def _named_where_written(
    error: DeclarationError, overrides: Mapping, joint: str
) -> DeclarationError:
    """``error``, raised by ``joint``'s protocol at its fields (the first key of each of its
    paths), named where the config writes them (:func:`placed_fields`); one met under ``all``
    says which joint it broke."""
    if not error.path:
        return error.under(joint)
    placed = placed_fields(overrides, joint, [str(path[0]) for path in error.paths])
    first, *beside = ((*at, *path[1:]) for at, path in zip(placed, error.paths, strict=True))
    reason = f"{error.reason} (joint {joint!r})" if first[0] == "all" else error.reason
    return DeclarationError(first, reason, beside)


def simulate(
    condition: Mapping[str, object],
    protocol: HingeStudyProtocol,
    rngs: Sequence[np.random.Generator],
) -> Trials:
    """Trials of one condition (keys protocol, fe_rom_deg, aa_ratio) of the chosen joint."""
    name = str(condition["protocol"])
    if name not in protocol.joints:
        raise ValueError(f"unknown hinge protocol {name!r}; known: {', '.join(protocol.joints)}")
    return hinge.simulate(condition, protocol.joints[name], rngs)


def frame_count(condition: Mapping[str, object], protocol: HingeStudyProtocol) -> int:
    """The frames of every trial of ``condition`` under ``protocol``: those of the joint's
    protocol the condition chooses, whatever its excursion or ratio."""
    return protocol.joints[str(condition["protocol"])].n_frames


def frame_keys(condition: Mapping[str, object], overrides: Mapping) -> list[tuple]:
    """Where the config sets the frames :func:`frame_count` gives: the condition's joint's
    ``n_frames``, under its own entry, ``all`` or (its default) its own
    (:func:`placed_fields`)."""
    return [
        ("protocol", *at)
        for at in placed_fields(overrides, str(condition["protocol"]), ("n_frames",))
    ]


STUDY = Study(
    name="hinge",
    kind="axis",
    grid_keys=("protocol", "fe_rom_deg", "aa_ratio"),
    seed_keys=("protocol", "fe_rom_deg", "aa_ratio"),
    segments=("moving",),
    protocol_class=HingeStudyProtocol,
    simulate=simulate,
    frame_count=frame_count,
    frame_keys=frame_keys,
    grid_spec={
        "protocol": GridValues(
            str,
            choices=lambda protocol: tuple(protocol.joints),
            label="protocol",
            text="{}",
            names={"mcp": "index MCP"},
        ),
        "fe_rom_deg": GridValues(
            float, minimum=0, exclusive_minimum=True, maximum=180, label="FE RoM", text="FE {:g}°"
        ),
        "aa_ratio": GridValues(float, minimum=0, label="AA/FE ratio", text="AA/FE {:g}"),
    },
    title="knee and index MCP",
)


_LAYOUT = (
    "The nominal surface marker positions are based on marker protocols for the knee joint and "
    "the index finger metacarpo-phalangeal (MCP) joint."
)


@dataclass(frozen=True)
class _LayoutBounds:
    """Where a joint's markers may sit, in cylindrical coordinates about the moving segment's
    long axis in the neutral pose: ``depth`` [mm] along it from the joint centre, ``radius``
    [mm] from it, ``azimuth`` [deg] from ``+x`` towards ``+y``; markers at least ``spacing``
    [mm] apart, so that a camera tells them apart; ``reason`` in words."""

    depth_mm: tuple[float, float]
    radius_mm: tuple[float, float]
    azimuth_deg: tuple[float, float]
    spacing_mm: float
    reason: str


# The bounds of the layout search (jointbench.simulate.hinge's notes).
_BOUNDS = {
    "knee": _LayoutBounds(
        (40.0, 420.0),
        (35.0, 70.0),
        (-180.0, 180.0),
        30.0,
        "on the shank: 40–420 mm below the joint centre, 35–70 mm from its axis, any side",
    ),
    "mcp": _LayoutBounds(
        (8.0, 42.0),
        (9.5, 14.0),
        (-30.0, 210.0),
        10.0,
        "on the proximal phalanx: 8–42 mm distal to the MCP centre, 9.5–14 mm from its axis, "
        "not on the palmar third",
    ),
}


def _cylindrical(marker: Sequence[float]) -> tuple[float, float, float]:
    x, y, z = marker
    return -z, math.hypot(x, y), math.degrees(math.atan2(y, x))


def _hinge_choices() -> tuple[Choice, ...]:
    choices = []
    for joint, bounds in _BOUNDS.items():
        default = hinge.HINGE_PROTOCOLS[joint]
        for name, marker in zip(default.marker_names, default.markers_mm, strict=True):
            for coordinate, value in zip(
                ("depth_mm", "radius_mm", "azimuth_deg"), _cylindrical(marker), strict=True
            ):
                low, high = getattr(bounds, coordinate)
                choices.append(
                    Choice(f"{joint}.{name}.{coordinate}", low, high, value, _LAYOUT, bounds.reason)
                )
    return tuple(choices)


def _markers(values: Mapping[str, float], joint: str) -> list[list[float]]:
    """The neutral-pose markers ``[[x, y, z], ...]`` [mm] of ``joint`` in one member."""
    markers = []
    for name in hinge.HINGE_PROTOCOLS[joint].marker_names:
        depth, radius, azimuth = (
            values[f"{joint}.{name}.{coordinate}"]
            for coordinate in ("depth_mm", "radius_mm", "azimuth_deg")
        )
        angle = math.radians(azimuth)
        markers.append([radius * math.cos(angle), radius * math.sin(angle), -depth])
    return markers


def _hinge_protocol(values: Mapping[str, float]) -> dict:
    """The ``protocol`` overrides of one member of :data:`PRIOR`: each joint's markers."""
    return {joint: {"markers_mm": _markers(values, joint)} for joint in _BOUNDS}


def _spaced(values: Mapping[str, float]) -> bool:
    """Whether every joint's markers are at least its ``spacing_mm`` apart."""
    return all(
        math.dist(a, b) >= bounds.spacing_mm
        for joint, bounds in _BOUNDS.items()
        for a, b in itertools.combinations(_markers(values, joint), 2)
    )


#: The plausible hinge marker layouts, knee and index MCP.
PRIOR = Prior(study="hinge", choices=_hinge_choices(), build=_hinge_protocol, accept=_spaced)
