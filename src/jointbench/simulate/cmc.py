"""Thumb carpometacarpal (CMC) circumduction: the simulation study of paper A (§5.1).

Paper A: "We tested two sets of marker positions, motivated by a spherical joint model of the
thumb carpometacarpal (CMC) joint (Fig. 2). The M marker set models markers on the thumb
metacarpal segment (M1, M2, and M3) and the H marker set represents markers on the hand dorsum
(H1, H2, and H3) (Table 1)." Table 1 gives only each marker's distance from the CoR; the figure
with the layout is not in the text. The directions below are therefore our choice, made
anatomically and kept as configurable protocol parameters.

Frame (ours): ``x`` dorsal, ``y`` radial, ``z`` distal along the thumb metacarpal in its mean
position. The nominal CoR sits at ``center_mm`` = (20, -25, -30) mm, 44 mm from the origin, as a
joint does from the origin of a technical frame defined by a marker cluster. It must not sit at
the origin: the simplex searches (IS, MA) scale their initial simplex with the coordinates of the
start point (fminsearch's rule), so they are not translation invariant, and a start at the origin
would give a degenerate 0.00025 mm simplex.

* M set, on the dorsoradial skin of the thumb metacarpal (about 45 mm long, skin 6–8 mm above
  the bone axis): M1 over the base, dorsal (13.8 mm, 30° from the shaft axis); M2 over the distal
  shaft, dorsal (29.0 mm, 15° from the axis); M3 over the base, radial (15.7 mm, 35° from the
  axis, 90° round from M1). Their triangle has sides of 11–18 mm.
* H set, on the hand dorsum ulnar and distal to the CMC joint: H1 over the base of the index
  metacarpal (48.7 mm), H2 over the base of the middle metacarpal (56.7 mm), H3 over the index
  metacarpal shaft towards its head (69.1 mm), all 12 mm dorsal to the CMC. Sides of 16–40 mm:
  the wider spread and larger distance from the CoR that paper A §6 contrasts with the M set.

Motion: "The generated marker trajectories simulated thumb circumduction by beginning from a
nominal mean position and circling out to increasing angles relative to the mean position. The
maximum angular RoMs tested were 5°, 15°, and 45° from the mean position." We model this as a
swing with no axial twist whose tilt angle grows linearly from 0 in the first frame to the
maximum RoM in the last, while the tilt direction turns ``spiral_turns`` times round the mean
axis (an Archimedean spiral of the segment's long axis on the sphere). The number of turns is
not given; two turns over 120 frames is our choice. ``tilt_power`` bends the spiral: the tilt
grows as the frame's fraction of the trial to that power (1, linear, is our choice).

:data:`PRIOR` spans the plausible values of every choice above (the directions within the
skin regions named, the turns, the spiral's shape and the CoR's distance from the origin), each
with the sentence it fills in; the defaults are one of its members.

Noise: "The directions of the error vectors were uniformly distributed, and the magnitudes of
the random errors were normally distributed" (see
:func:`jointbench.simulate.noise.isotropic_noise`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Annotated

import numpy as np

from jointbench.declared import Count, DeclarationError, Length, NonNegative, Positive, Vector3
from jointbench.declared import check_fields as check_declared
from jointbench.estimators.registry import many
from jointbench.estimators.sphere import FMINSEARCH_OPTIONS, geometric_cost
from jointbench.geometry import rotation_matrix, unit
from jointbench.simulate import RADII_TRUTH, Diagnostic, GridValues, Study, Trials
from jointbench.simulate.noise import isotropic_noise, largest_noise_mm
from jointbench.simulate.prior import Choice, Prior
from jointbench.simulate.ranges import LabPoint, MarkerDistance

__all__ = [
    "LOCAL_MINIMUM",
    "PRIOR",
    "STUDY",
    "CmcProtocol",
    "is_local_minimum",
    "marker_positions",
    "nominal_trajectory",
    "simulate",
    "spiral_rotations",
]

_DEFAULT_DIRECTIONS = {
    # (dorsal, radial, distal) components; only the direction matters, length comes from Table 1.
    "M": (
        (np.sin(np.radians(30)), 0.0, np.cos(np.radians(30))),
        (np.sin(np.radians(15)), 0.0, np.cos(np.radians(15))),
        (0.0, np.sin(np.radians(35)), np.cos(np.radians(35))),
    ),
    "H": ((12.0, -35.0, 30.0), (12.0, -50.0, 25.0), (12.0, -30.0, 60.0)),
}
_TABLE_1_DISTANCES_MM = {"M": (13.8, 29.0, 15.7), "H": (48.7, 56.7, 69.1)}


def _as_tuples(mapping: Mapping[str, Sequence]) -> dict[str, tuple]:
    return {
        name: tuple(tuple(float(x) for x in row) if np.ndim(row) else float(row) for row in rows)
        for name, rows in mapping.items()
    }


@dataclass(frozen=True)
class CmcProtocol:
    """Modelling choices of the thumb-CMC study; every field can be overridden from the config.

    ``directions``: per marker set, one direction per marker from the CoR (any length) in the
    frame described in the module docstring. ``distances_mm``: paper A Table 1.
    ``spiral_turns``: turns of the circumduction spiral. ``tilt_power``: the tilt grows as the
    frame's fraction of the trial to this power (the config refuses one whose thumb has not
    begun to circle out by the middle of the trial, or has already reached nearly its RoM,
    :data:`jointbench.configuration.bounds.CMC_TILT_SHARE_BY_MIDDLE`). ``n_frames``: 120
    (paper A §5.1).
    ``center_mm``: the nominal CoR in the reference frame. A marker set has as many
    directions as distances.
    """

    directions: dict[str, Annotated[tuple[Vector3, ...], Length(1)]] = field(
        default_factory=lambda: _as_tuples(_DEFAULT_DIRECTIONS)
    )
    distances_mm: dict[str, Annotated[tuple[MarkerDistance, ...], Length(1)]] = field(
        default_factory=lambda: _as_tuples(_TABLE_1_DISTANCES_MM)
    )
    # No turns is a swing in one plane: a hinge, whose centre the fits cannot place (flagged).
    spiral_turns: NonNegative = 2.0
    tilt_power: Positive = 1.0
    n_frames: Count = 120
    center_mm: LabPoint = (20.0, -25.0, -30.0)

    def __post_init__(self) -> None:
        for name in {**self.directions, **self.distances_mm}:
            directions = self.directions.get(name)
            distances = self.distances_mm.get(name)
            if directions is None or distances is None:
                missing = "directions" if directions is None else "distances_mm"
                raise DeclarationError(
                    (missing,),
                    f"has no marker set {name!r}: a marker set needs both directions and "
                    "distances_mm",
                )
            if len(directions) != len(distances):
                raise DeclarationError(
                    ("distances_mm", name),
                    f"gives {len(distances)} distances for the {len(directions)} directions of "
                    f"marker set {name!r}",
                )
            for index, direction in enumerate(directions):
                if not _normalisable(direction):
                    raise DeclarationError(
                        ("directions", name, index),
                        f"{list(direction)!r} is not a direction whose length can be divided "
                        "out: its squared length must be a positive, finite, normal number "
                        "(components of about 1e-150 to 1e150; zero is no direction)",
                    )

    @property
    def largest_noise_mm(self) -> float:
        """The largest grid ``noise_mm`` [mm]: the farthest marker of any set from the CoR
        (:func:`jointbench.simulate.noise.largest_noise_mm`)."""
        return max(largest_noise_mm(marker_positions(self, name)) for name in self.directions)

    @classmethod
    def from_config(cls, overrides: Mapping[str, object] | None = None) -> CmcProtocol:
        """Defaults updated by the config's ``protocol`` mapping (a marker set's directions and
        distances replace the default set of that name, other sets are kept)."""
        overrides = dict(overrides or {})
        check_declared(cls, overrides)
        for key in ("directions", "distances_mm"):
            if key in overrides:
                overrides[key] = {**getattr(cls(), key), **_as_tuples(overrides[key])}
        return cls(**overrides)


def _normalisable(direction: Sequence[float]) -> bool:
    """Whether ``direction`` ``(3,)`` (any length) has a unit vector :func:`unit` computes: its
    squared length neither overflows nor falls to zero or below the normal numbers, where the
    division would give inf, NaN or a vector of another length than 1."""
    squared = sum(float(c) * float(c) for c in direction)
    return np.finfo(float).tiny <= squared < np.inf


def marker_positions(protocol: CmcProtocol, marker_set: str) -> np.ndarray:
    """Nominal marker positions ``(n_markers, 3)`` [mm] relative to the CoR."""
    if marker_set not in protocol.directions:
        raise ValueError(
            f"unknown marker set {marker_set!r}; known: {', '.join(protocol.directions)}"
        )
    directions = unit(np.array(protocol.directions[marker_set], dtype=float))
    distances = np.array(protocol.distances_mm[marker_set], dtype=float)
    if directions.shape[0] != distances.shape[0]:
        raise ValueError(f"marker set {marker_set!r}: directions and distances differ in count")
    return directions * distances[:, None]


def spiral_rotations(
    max_angle_deg: float, n_frames: int, turns: float, tilt_power: float = 1.0
) -> np.ndarray:
    """Circumduction spiral ``(n_frames, 3, 3)``: tilt from 0 to ``max_angle_deg``, no twist.

    The tilt axis ``(cos phi, sin phi, 0)`` lies in the plane normal to the mean long axis ``z``
    and turns ``turns`` times at a constant rate; the tilt angle grows as the frame's fraction
    of the trial to the power ``tilt_power`` (1: linearly with the frame index).
    """
    progress = np.linspace(0.0, 1.0, n_frames)
    tilt = np.radians(max_angle_deg) * progress**tilt_power
    phase = 2.0 * np.pi * turns * progress
    axes = np.stack([np.cos(phase), np.sin(phase), np.zeros_like(phase)], axis=-1)
    return rotation_matrix(axes * tilt[:, None])


def nominal_trajectory(protocol: CmcProtocol, marker_set: str, rom_deg: float) -> np.ndarray:
    """Noise-free marker trajectories ``(n_frames, n_markers, 3)`` [mm] about ``center_mm``."""
    rotations = spiral_rotations(
        rom_deg, protocol.n_frames, protocol.spiral_turns, protocol.tilt_power
    )
    offsets = np.einsum("fij,pj->fpi", rotations, marker_positions(protocol, marker_set))
    return offsets + np.asarray(protocol.center_mm, dtype=float)


def simulate(
    condition: Mapping[str, object], protocol: CmcProtocol, rngs: Sequence[np.random.Generator]
) -> Trials:
    """Trials of one condition (keys marker_set, rom_deg, noise_mm); one generator per trial."""
    nominal = nominal_trajectory(
        protocol, str(condition["marker_set"]), float(condition["rom_deg"])
    )
    noise_mm = float(condition["noise_mm"])
    moving = np.stack([nominal + isotropic_noise(rng, nominal.shape[:2], noise_mm) for rng in rngs])
    markers = marker_positions(protocol, str(condition["marker_set"]))
    return Trials(
        segments={"moving": moving},
        truth={
            "center": [float(x) for x in protocol.center_mm],
            RADII_TRUTH: np.linalg.norm(markers, axis=1).tolist(),
        },
        parameters={
            "spiral_turns": protocol.spiral_turns,
            "n_frames": protocol.n_frames,
            "markers_mm": markers.tolist(),
        },
    )


#: The column of :func:`is_local_minimum` that paper A's claim A7 counts.
LOCAL_MINIMUM = "local_minimum"


def is_local_minimum(arguments, results: Sequence, truth: Mapping) -> list[dict[str, object]]:
    """Claim A7 (paper A §5.1.1), made operational: IS "returned a local minimum" when IS
    restarted from the true centre reaches a lower geometric cost f1 than IS from the LS centre.

    The check of :attr:`Study.diagnostics` for IS: ``arguments`` is ``(markers,)``, the markers
    of all trials ``(n_trials, n_frames, n_markers, 3)`` [mm]. Columns: :data:`LOCAL_MINIMUM` (bool)
    and ``f1_gap`` = f1(IS from LS) − f1(IS from truth) [mm²]. The restarts of all trials run
    as one batch (the same searches as one at a time).
    """
    # Two searches found the same minimum when their f1 differ by less than this margin:
    # fminsearch stops once the simplex's f1 values agree to TolFun (absolute, mm^2), so final
    # values of one minimum can differ by a few TolFun; ten times TolFun, or 1e-6 relative for
    # large f1.
    same_atol, same_rtol = 10.0 * FMINSEARCH_OPTIONS["fatol"], 1e-6
    (markers,) = arguments
    restarts = many("center", "IS", checked=False)(
        markers, start=np.asarray(truth["center"], dtype=float)
    )
    rows: list[dict[str, object]] = []
    for data, result, from_truth in zip(markers, results, restarts, strict=True):
        if result is None:
            rows.append({})
            continue
        if isinstance(from_truth, Exception):
            raise from_truth
        own = geometric_cost(data, result.center)
        best = geometric_cost(data, from_truth.center)
        rows.append(
            {
                LOCAL_MINIMUM: bool(own - best > max(same_atol, same_rtol * best)),
                "f1_gap": float(own - best),
            }
        )
    return rows


def frame_count(condition: Mapping[str, object], protocol: CmcProtocol) -> int:
    """The frames of every trial of ``condition`` under ``protocol``: the protocol's, whatever
    the marker set, excursion or noise."""
    return protocol.n_frames


def frame_keys(condition: Mapping[str, object], overrides: Mapping) -> list[tuple[str, str]]:
    """Where the config sets the frames :func:`frame_count` gives."""
    return [("protocol", "n_frames")]


STUDY = Study(
    name="cmc",
    kind="center",
    grid_keys=("marker_set", "rom_deg", "noise_mm"),
    seed_keys=("marker_set", "rom_deg", "noise_mm"),
    segments=("moving",),
    protocol_class=CmcProtocol,
    simulate=simulate,
    frame_count=frame_count,
    frame_keys=frame_keys,
    grid_spec={
        "marker_set": GridValues(
            str,
            choices=lambda protocol: tuple(protocol.directions),
            label="marker set",
            text="{} set",
        ),
        # A circumduction tilt: 0° does not move, beyond 180° it repeats.
        "rom_deg": GridValues(
            float, minimum=0, exclusive_minimum=True, maximum=180, label="RoM", text="±{:g}°"
        ),
        "noise_mm": GridValues(
            float,
            minimum=0,
            maximum=lambda protocol: protocol.largest_noise_mm,
            label="noise SD",
            text="{:g} mm noise",
        ),
    },
    title="thumb CMC",
    diagnostics={"IS": Diagnostic((LOCAL_MINIMUM, "f1_gap"), is_local_minimum)},
)


_CIRCUMDUCTION = (
    "The generated marker trajectories simulated thumb circumduction by beginning from a "
    "nominal mean position and circling out to increasing angles relative to the mean position."
)
_MARKER_SETS = (
    "The M marker set models markers on the thumb metacarpal segment (M1, M2, and M3) and the "
    "H marker set represents markers on the hand dorsum (H1, H2, and H3) (Table 1)."
)
_SIMPLEX = (
    "The procedures for MA and IS employ the MATLAB function fminsearch, which uses simplex "
    "direct search."
)
_DEFAULT_CENTER_MM = np.array(CmcProtocol().center_mm)
# The M set's (polar angle from the shaft axis, azimuth from dorsal towards radial) [deg]: M1
# fixes the dorsal direction; each is drawn within ±10° of the skin spot the module names.
_M_ANGLES_DEG = {"M1": (30.0, 0.0), "M2": (15.0, 0.0), "M3": (35.0, 90.0)}
_M_POLAR_BOUNDS_DEG = {"M1": (20.0, 40.0), "M2": (5.0, 25.0), "M3": (25.0, 45.0)}
_M_AZIMUTH_BOUNDS_DEG = {"M2": (-30.0, 30.0), "M3": (60.0, 120.0)}
_H_NAMES = ("H1", "H2", "H3")
# Each H marker's radial and distal offset may move 10 mm over its metacarpal base or shaft.
_H_SHIFT_MM = 10.0


def _m_direction(polar_deg: float, azimuth_deg: float) -> list[float]:
    polar, azimuth = np.radians(polar_deg), np.radians(azimuth_deg)
    return [
        float(np.sin(polar) * np.cos(azimuth)),
        float(np.sin(polar) * np.sin(azimuth)),
        float(np.cos(polar)),
    ]


def _cmc_choices() -> tuple[Choice, ...]:
    choices = [
        Choice(
            "center_distance_mm",
            20.0,
            1500.0,
            float(np.linalg.norm(_DEFAULT_CENTER_MM)),
            _SIMPLEX,
            "fminsearch scales its first simplex with the start point's coordinates, so the "
            "CoR's distance from the origin matters: from a marker cluster's own frame (tens "
            "of mm) to a laboratory origin (1.5 m); log-uniform, the direction kept",
            log=True,
        ),
        Choice(
            "spiral_turns",
            1.0,
            4.0,
            CmcProtocol().spiral_turns,
            _CIRCUMDUCTION,
            "at least one full circle, at most four in 120 frames (30 frames a circle)",
        ),
        Choice(
            "tilt_power",
            0.5,
            2.0,
            CmcProtocol().tilt_power,
            _CIRCUMDUCTION,
            "circling out faster early (0.5) or late (2); log-uniform around linear",
            log=True,
        ),
    ]
    for name, (low, high) in _M_POLAR_BOUNDS_DEG.items():
        choices.append(
            Choice(
                f"{name}_polar_deg",
                low,
                high,
                _M_ANGLES_DEG[name][0],
                _MARKER_SETS,
                "within 10° of its skin spot on the thumb metacarpal",
            )
        )
    for name, (low, high) in _M_AZIMUTH_BOUNDS_DEG.items():
        choices.append(
            Choice(
                f"{name}_azimuth_deg",
                low,
                high,
                _M_ANGLES_DEG[name][1],
                _MARKER_SETS,
                "within 30° round the shaft from its skin spot",
            )
        )
    choices.append(
        Choice(
            "H_dorsal_mm",
            8.0,
            16.0,
            _DEFAULT_DIRECTIONS["H"][0][0],
            _MARKER_SETS,
            "the hand dorsum 8–16 mm dorsal to the CMC joint",
        )
    )
    for name, (_, radial, distal) in zip(_H_NAMES, _DEFAULT_DIRECTIONS["H"], strict=True):
        for axis, value in (("radial", radial), ("distal", distal)):
            choices.append(
                Choice(
                    f"{name}_{axis}_mm",
                    value - _H_SHIFT_MM,
                    value + _H_SHIFT_MM,
                    value,
                    _MARKER_SETS,
                    "within 10 mm of its spot over the metacarpal",
                )
            )
    return tuple(choices)


def _cmc_protocol(values: Mapping[str, float]) -> dict:
    """The ``protocol`` overrides of one member of :data:`PRIOR` (directions as unit vectors
    for M, as offsets from the CoR [mm] for H; the CoR scaled along its default direction)."""
    scale = values["center_distance_mm"] / float(np.linalg.norm(_DEFAULT_CENTER_MM))
    m_directions = [
        _m_direction(
            values[f"{name}_polar_deg"],
            values.get(f"{name}_azimuth_deg", _M_ANGLES_DEG[name][1]),
        )
        for name in _M_ANGLES_DEG
    ]
    h_directions = [
        [values["H_dorsal_mm"], values[f"{name}_radial_mm"], values[f"{name}_distal_mm"]]
        for name in _H_NAMES
    ]
    return {
        "center_mm": [float(x) for x in _DEFAULT_CENTER_MM * scale],
        "spiral_turns": values["spiral_turns"],
        "tilt_power": values["tilt_power"],
        "directions": {"M": m_directions, "H": h_directions},
    }


#: The plausible thumb-CMC protocols: every unpublished choice of this module, with its bounds.
PRIOR = Prior(study="cmc", choices=_cmc_choices(), build=_cmc_protocol)
