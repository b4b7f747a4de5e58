"""Hinge-joint simulation of paper B §3.1 (Chang & Pollard 2007): knee and index-finger MCP.

What the paper states. "Each synthetic data set simulated joint rotation with FE RoM of 30°,
60°, or 90°, and AA RoM with ratio of 0.1, 0.3, 0.5, or 0.7 relative to the FE RoM. [...] 30
independent error sequences were added to the nominal rotated marker positions. The directions
of the error vectors were uniformly distributed and the error magnitudes were normally
distributed with standard deviation of 1.0 mm. Each data set had 121 frames." The knee AoR "is
fixed with respect to the upper leg reference frame such that surface markers on the lower leg
follow circular paths"; for the index MCP "the AoR is fixed in the hand dorsum frame and the
simulated trajectories model the movement of markers on the proximal phalanx"; "the
flexion-extension (FE) axis is considered the dominant AoR while adduction-abduction (AA)
rotation has a smaller RoM".

What it does not state, and the choices made here (all configurable in :class:`HingeProtocol`):

* The rotations. FE about the fixed FE axis ``x`` of the reference frame, AA about the moving
  segment's AP (knee) / dorsal (MCP) axis, ``R = R_x(FE) R_y(AA)`` (Grood & Suntay's floating
  axis; ``rotation_order="fe_aa"``). This is the order under which the FE axis is "fixed with
  respect to the upper leg"; both axes pass through the joint centre, so every marker stays on
  a sphere about it and the NM sphere fit of paper A gives the point ``m``.
* How FE and AA combine over time. Only the *set* of poses matters: every cost of paper B is a
  sum over frames, so the frame order changes nothing. The candidates differ in which
  (FE, AA) pairs they visit. Chosen: ``motion="grid"``, every combination of 11 equally spaced
  FE angles and 11 equally spaced AA angles, visited as a raster (AA swept back and forth at
  each FE level), which is also what "121 frames" = 11 x 11 suggests. Alternatives:
  ``"lissajous"`` (FE and AA sinusoids with ``fe_cycles`` and ``aa_cycles`` cycles and phase
  ``aa_phase_deg``; 1 and 2 cycles with zero phase trace a figure of eight), ``"sequential"``
  (an FE sweep at neutral AA, then an AA sweep at mid-range FE, each at constant speed) and
  ``"superimposed"`` (a monotone FE sweep with ``aa_cycles`` AA sinusoid cycles on top).
* Half or full range. Chosen: ``rom_convention="full"``, the RoM is the peak-to-peak excursion:
  FE spans ``[0, RoM]`` from full extension and AA spans ``±ratio*RoM/2``. ("half": the RoM is
  the amplitude, the excursion twice as large.) With the FE axis fixed, where the FE range
  starts only rotates the data about the true axis and changes no error.
* The marker coordinates (below).

How the motion model and the marker positions were chosen (the candidates, the search and its
reasoning) is recorded in ``docs/hinge-model-selection.md``; how the defaults fare against
Table 1 is in the generated ``results/tables/paper_b_table1.md``.

Marker positions. The paper gives no coordinates, only the protocol figures: knee "Markers U1,
U2, and U3 define the frame for the upper leg, and markers L1, L2, and L3 are attached to the
lower leg" (Fig. 4a); hand "Three surface markers are attached to each of four body segments:
hand dorsum (H), proximal phalanx (P), middle phalanx (M), and distal phalanx (D)" (Fig. 4b).
Since the errors depend on the geometry as much as on the motion (above), the positions were
chosen by a global search, for each motion candidate alike, within anatomical bounds, maximising
the number of the protocol's 36 cells within tolerance at once (never per cell), then rounded:

* knee (right leg; origin the knee joint centre on the FE axis, ``+x`` lateral, ``+y``
  anterior, ``+z`` proximal along the thigh; the shank hangs along ``-z`` at full extension).
  Bounds: 40–420 mm below the joint centre (a shank of about 400 mm) and 35–70 mm from the
  shank's long axis (skin of the proximal shank plus a 7 mm marker radius), any side.
  L1 (57.5, 36.0, -143.5): anterolateral, 144 mm below the joint, 68 mm from the axis, over
  the belly of tibialis anterior. L2 (-32.5, -23.5, -151.0): posteromedial, 151 mm below,
  40 mm from the axis, just behind the medial border of the tibia (whose subcutaneous face
  sets the 35 mm lower bound). L3 (43.5, -2.0,
  -171.0): lateral, 171 mm below, 44 mm from the axis, over the fibula and peroneal muscles.
  A band of three skin markers round the proximal third of the shank.
* index MCP (right hand; origin the centre of the second metacarpal head on the FE axis,
  ``+x`` radial, ``+y`` dorsal, ``+z`` proximal along the metacarpal; the phalanx points along
  ``-z`` when extended). Bounds: 8–42 mm from the MCP centre (a proximal phalanx of about
  40–45 mm) and 9.5–14 mm from the phalanx's long axis (half its width or depth with soft
  tissue, plus a 2–3 mm marker radius), not on the palmar third. P1 (8.5, 4.5, -40.5):
  dorsoradial, near the phalanx head, 9.6 mm from the axis. P2 (-6.5, 12.0, -28.0):
  dorsoulnar, mid-shaft, 13.6 mm. P3 (11.0, -1.5, -24.5): radial mid-lateral, mid-shaft,
  11.1 mm.
"""

from __future__ import annotations

import dataclasses
import math
import typing
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Annotated, Literal

import numpy as np

from jointbench.declared import DeclarationError, Length, NonNegative, Positive, Range
from jointbench.declared import check_fields as check_declared
from jointbench.geometry import rotation_about_axis
from jointbench.simulate import Trials
from jointbench.simulate.noise import check_noise_level, isotropic_noise
from jointbench.simulate.ranges import Angle, MarkerOffset, check_marker_offsets

__all__ = [
    "AMPLITUDE_FIELDS",
    "FE_AXIS",
    "HINGE_PROTOCOLS",
    "MOTIONS",
    "MOTION_FIELDS",
    "ROM_CONVENTIONS",
    "ROTATION_ORDERS",
    "HingeProtocol",
    "joint_angles",
    "nominal_markers",
    "protocol_from_config",
    "simulate",
    "sine_waves",
]

Motion = Literal["lissajous", "sequential", "superimposed", "grid"]
RomConvention = Literal["full", "half"]
RotationOrder = Literal["fe_aa", "aa_fe"]
MOTIONS = typing.get_args(Motion)
ROM_CONVENTIONS = typing.get_args(RomConvention)
ROTATION_ORDERS = typing.get_args(RotationOrder)

#: The fields of :class:`HingeProtocol` that only some motions read, by motion: those setting
#: the sine waves of the lissajous motion (FE and AA) and of the superimposed one (AA); the
#: sequential and grid motions run no waves. Every other field every motion reads. The config
#: refuses one of these written where no joint the grid runs reads it: under a joint whose
#: motion does not, or under ``all`` where no joint taking it from there has a motion that
#: does (it would change no data): :func:`jointbench.configuration.bounds.study_problem`.
MOTION_FIELDS: dict[str, tuple[str, ...]] = {
    "lissajous": ("fe_cycles", "aa_cycles", "aa_phase_deg"),
    "sequential": (),
    "superimposed": ("aa_cycles", "aa_phase_deg"),
    "grid": (),
}

#: The fields of :class:`HingeProtocol` that shape the trials only through abduction–adduction,
#: by the grid key that sets its amplitude: the AA wave's cycles and phase, and the order of the
#: FE and AA rotations (``R_AA`` is the identity without AA, so both orders give ``R_FE``). Where
#: every ``aa_ratio`` of the grid is 0 no trial reads them, whatever the motion; the config
#: refuses one written for a joint the grid runs, as it does a field the motion does not read:
#: :func:`jointbench.configuration.bounds.study_problem`.
AMPLITUDE_FIELDS: dict[str, tuple[str, ...]] = {
    "aa_ratio": ("aa_cycles", "aa_phase_deg", "rotation_order"),
}

#: The flexion–extension axis, the true axis of rotation, in the reference segment's frame.
FE_AXIS = np.array([1.0, 0.0, 0.0])
#: The adduction–abduction axis in the neutral pose (anterior / dorsal).
AA_AXIS = np.array([0.0, 1.0, 0.0])


@dataclass(frozen=True)
class HingeProtocol:
    """Documented, configurable modelling choices of one simulated hinge joint.

    Frame (the reference segment's: upper leg, or hand dorsum), millimetres: origin at the joint
    centre, where the FE and AA axes meet; ``+x`` along the FE axis (lateral for the right knee,
    radial for the right index MCP), ``+y`` anterior (knee) / dorsal (hand), ``+z`` proximal,
    along the reference segment. In the neutral pose (FE = AA = 0) the moving segment points
    along ``-z``.

    Attributes
    ----------
    name : "knee" or "mcp" (any name for a custom protocol).
    marker_names : names of the moving segment's markers.
    markers_mm : ((x, y, z), ...) their positions in the neutral pose [mm].
    motion : which (FE, AA) poses are visited, one of :data:`MOTIONS` (see the module notes).
    rom_convention : "full" (the RoM is the peak-to-peak excursion) or "half" (the RoM is the
        amplitude, so the excursion is twice the RoM).
    fe_cycles, aa_cycles : cycles of FE and AA over the recording ("lissajous"; "superimposed"
        uses ``aa_cycles``; "grid" and "sequential" read neither, :data:`MOTION_FIELDS`).
    aa_phase_deg : phase of the AA sinusoid relative to FE ("lissajous", "superimposed").
        Neither it nor ``aa_cycles`` nor ``rotation_order`` shapes a trial without AA
        (``aa_ratio`` 0, :data:`AMPLITUDE_FIELDS`).
    rotation_order : "fe_aa": ``R = R_FE(fe) R_AA(aa)``, AA about the axis carried by the moving
        segment (Grood & Suntay's floating axis), so the FE axis stays fixed in the reference
        frame, as paper B's model requires; "aa_fe": ``R = R_AA(aa) R_FE(fe)``, AA about the
        reference segment's axis, which carries the FE axis with it.
    noise_sd_mm : SD of the isotropic marker-noise magnitude [mm] (paper B: 1.0).
    n_frames : frames per trial (paper B: 121).
    """

    name: str
    marker_names: Annotated[tuple[str, ...], Length(1)]
    markers_mm: Annotated[tuple[MarkerOffset, ...], Length(1)]
    motion: Motion = "grid"
    rom_convention: RomConvention = "full"
    fe_cycles: Positive = 1.0
    aa_cycles: Positive = 2.0
    aa_phase_deg: Angle = 0.0
    rotation_order: RotationOrder = "fe_aa"
    noise_sd_mm: NonNegative = 1.0
    # Four frames: the fewest of a "grid" motion (2 x 2) and of the axis searches.
    n_frames: Annotated[int, Range(4)] = 121

    def __post_init__(self) -> None:
        # Lists from the config become tuples: a protocol is immutable and hashable.
        markers = tuple(tuple(float(c) for c in marker) for marker in self.markers_mm)
        object.__setattr__(self, "markers_mm", markers)
        object.__setattr__(self, "marker_names", tuple(self.marker_names))
        if len(self.marker_names) != len(markers):
            raise DeclarationError(
                ("marker_names",),
                f"has {len(self.marker_names)} names for {len(markers)} markers",
            )
        if self.motion == "grid" and math.isqrt(self.n_frames) ** 2 != self.n_frames:
            raise DeclarationError(
                ("n_frames",), f"motion 'grid' needs a square n_frames, got {self.n_frames}"
            )
        # The joint centre is the origin of the frame the markers are given in.
        check_marker_offsets("markers_mm", markers)
        check_noise_level("noise_sd_mm", self.noise_sd_mm, np.array(markers), ("markers_mm",))

    @property
    def markers(self) -> np.ndarray:
        """Neutral-pose marker positions ``(n_markers, 3)`` [mm]."""
        return np.array(self.markers_mm)


HINGE_PROTOCOLS: dict[str, HingeProtocol] = {
    # Positions and their anatomical reading: see the module notes.
    "knee": HingeProtocol(
        name="knee",
        marker_names=("L1", "L2", "L3"),
        markers_mm=((57.5, 36.0, -143.5), (-32.5, -23.5, -151.0), (43.5, -2.0, -171.0)),
    ),
    "mcp": HingeProtocol(
        name="mcp",
        marker_names=("P1", "P2", "P3"),
        markers_mm=((8.5, 4.5, -40.5), (-6.5, 12.0, -28.0), (11.0, -1.5, -24.5)),
    ),
}


def protocol_from_config(config: Mapping[str, object] | str) -> HingeProtocol:
    """A :class:`HingeProtocol` from a name or a mapping of overrides.

    ``config`` is a protocol name ("knee", "mcp") or a mapping with ``name`` and any field
    overrides, e.g. ``{"name": "knee", "rom_convention": "half", "noise_sd_mm": 0.5}``. A name
    not in :data:`HINGE_PROTOCOLS` must come with every field without a default. Unknown keys
    raise ``ValueError``.
    """
    if isinstance(config, str):
        config = {"name": config}
    settings = dict(config)
    if "name" not in settings:
        raise ValueError("a hinge protocol config needs a 'name' (e.g. 'knee' or 'mcp')")
    check_declared(HingeProtocol, settings)
    base = HINGE_PROTOCOLS.get(str(settings["name"]))
    if base is None:
        try:
            return HingeProtocol(**settings)
        except TypeError as error:
            raise ValueError(
                f"protocol {settings['name']!r} is not built in ({', '.join(HINGE_PROTOCOLS)}); "
                f"give every field: {error}"
            ) from None
    return dataclasses.replace(base, **settings)


def _check_condition(
    condition: Mapping[str, object], protocol: HingeProtocol
) -> tuple[float, float]:
    missing = [key for key in ("fe_rom_deg", "aa_ratio") if key not in condition]
    if missing:
        raise ValueError(f"hinge condition needs {', '.join(missing)}; got {dict(condition)}")
    name = condition.get("protocol", protocol.name)
    if name != protocol.name:
        raise ValueError(
            f"condition is for protocol {name!r} but the {protocol.name!r} protocol was given"
        )
    fe_rom = float(condition["fe_rom_deg"])
    ratio = float(condition["aa_ratio"])
    if not (math.isfinite(fe_rom) and fe_rom > 0):
        raise ValueError(f"fe_rom_deg must be > 0, got {condition['fe_rom_deg']!r}")
    if not (math.isfinite(ratio) and ratio >= 0):
        raise ValueError(f"aa_ratio must be >= 0, got {condition['aa_ratio']!r}")
    return fe_rom, ratio


def joint_angles(
    condition: Mapping[str, object], protocol: HingeProtocol
) -> tuple[np.ndarray, np.ndarray]:
    """FE and AA angles ``(n_frames,)`` [rad] of the nominal motion.

    The FE excursion is ``fe_rom_deg`` ("full") or twice it ("half"), starting from the neutral
    pose (FE in ``[0, excursion]``, flexion positive); the AA excursion is ``aa_ratio`` times the
    FE excursion, centred on neutral. Time runs over ``t = k / (n_frames - 1)``, ``k = 0..n-1``.
    """
    fe_rom, ratio = _check_condition(condition, protocol)
    scale = 1.0 if protocol.rom_convention == "full" else 2.0
    fe_half = math.radians(fe_rom) * scale / 2.0  # half the FE excursion
    aa_half = fe_half * ratio
    n = int(protocol.n_frames)
    t = np.linspace(0.0, 1.0, n)
    phase = math.radians(protocol.aa_phase_deg)
    if protocol.motion == "lissajous":
        fe_wave = -np.cos(2.0 * np.pi * protocol.fe_cycles * t)
        aa_wave = np.sin(2.0 * np.pi * protocol.aa_cycles * t + phase)
    elif protocol.motion == "sequential":
        # An FE sweep over its whole range at neutral AA, then an AA sweep over its whole range
        # at mid-range FE, each at constant speed (the jump between them does not matter: only
        # the set of poses enters the costs).
        split = (n + 1) // 2
        fe_wave = np.concatenate([np.linspace(-1.0, 1.0, split), np.zeros(n - split)])
        aa_wave = np.concatenate([np.zeros(split), np.linspace(-1.0, 1.0, n - split)])
    elif protocol.motion == "superimposed":
        fe_wave = np.linspace(-1.0, 1.0, n)
        aa_wave = np.sin(2.0 * np.pi * protocol.aa_cycles * t + phase)
    else:  # grid: every combination of sqrt(n) FE and sqrt(n) AA values, boustrophedon order
        side = math.isqrt(n)
        levels = np.linspace(-1.0, 1.0, side)
        fe_wave = np.repeat(levels, side)
        aa_wave = np.concatenate([levels if i % 2 == 0 else levels[::-1] for i in range(side)])
    return fe_half * (1.0 + fe_wave), aa_half * aa_wave


def sine_waves(protocol: HingeProtocol) -> dict[str, tuple[float, float]]:
    """The sinusoids of ``protocol``'s motion, by the field that sets their cycles: ``(cycles,
    phase [rad])`` of ``sin(2 pi cycles t + phase)`` over ``t`` in ``[0, 1]``, each the wave
    :func:`joint_angles` lays out (the Lissajous FE wave ``-cos`` is the sine from ``-pi/2``,
    full extension); those the motion reads (:data:`MOTION_FIELDS`), none for the grid and
    sequential motions, which run no cycles."""
    waves = {
        "fe_cycles": (protocol.fe_cycles, -math.pi / 2.0),
        "aa_cycles": (protocol.aa_cycles, math.radians(protocol.aa_phase_deg)),
    }
    return {name: wave for name, wave in waves.items() if name in MOTION_FIELDS[protocol.motion]}


def nominal_markers(condition: Mapping[str, object], protocol: HingeProtocol) -> np.ndarray:
    """Noise-free marker positions ``(n_frames, n_markers, 3)`` [mm] in the reference frame."""
    fe, aa = joint_angles(condition, protocol)
    r_fe = rotation_about_axis(FE_AXIS, fe)
    r_aa = rotation_about_axis(AA_AXIS, aa)
    rotation = r_fe @ r_aa if protocol.rotation_order == "fe_aa" else r_aa @ r_fe
    return np.einsum("fij,mj->fmi", rotation, protocol.markers)


def simulate(
    condition: Mapping[str, object],
    protocol: HingeProtocol,
    rngs: Sequence[np.random.Generator],
) -> Trials:
    """Simulated trials of one hinge condition: the nominal motion plus isotropic noise.

    Parameters
    ----------
    condition : ``{"protocol": "knee" | "mcp", "fe_rom_deg": 30 | 60 | 90, "aa_ratio": 0.1 ...}``
        (``protocol``, when present, must match ``protocol.name``).
    protocol : the joint's :class:`HingeProtocol`, e.g. ``HINGE_PROTOCOLS["knee"]``.
    rngs : one generator per trial; each draws that trial's noise only.

    Returns
    -------
    Trials
        ``segments["moving"]`` ``(n_trials, n_frames, n_markers, 3)`` [mm] in the reference
        frame; ``truth`` the FE axis (``axis_point`` the joint centre, ``axis_direction`` a unit
        vector); ``parameters`` the protocol and the derived angle ranges.
    """
    nominal = nominal_markers(condition, protocol)
    fe, aa = joint_angles(condition, protocol)
    moving = (
        np.stack(
            [
                nominal + isotropic_noise(rng, nominal.shape[:2], protocol.noise_sd_mm)
                for rng in rngs
            ]
        )
        if len(rngs)
        else np.empty((0, *nominal.shape))
    )
    parameters = {
        **{key: value for key, value in dataclasses.asdict(protocol).items()},
        "condition": dict(condition),
        "fe_range_deg": [float(np.degrees(fe.min())), float(np.degrees(fe.max()))],
        "aa_range_deg": [float(np.degrees(aa.min())), float(np.degrees(aa.max()))],
    }
    parameters["markers_mm"] = [list(m) for m in protocol.markers_mm]
    parameters["marker_names"] = list(protocol.marker_names)
    return Trials(
        segments={"moving": moving},
        truth={"axis_point": [0.0, 0.0, 0.0], "axis_direction": FE_AXIS.tolist()},
        parameters=parameters,
    )
