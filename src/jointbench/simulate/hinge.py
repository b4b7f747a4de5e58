"""Hinge-joint simulation of paper B §3.1 (Chang & Pollard 2007): knee and index-finger MCP.

MODEL_NOTES_PLACEHOLDER
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from jointbench.geometry import rotation_about_axis
from jointbench.simulate import Trials
from jointbench.simulate.noise import isotropic_noise

__all__ = [
    "FE_AXIS",
    "HINGE_PROTOCOLS",
    "MOTIONS",
    "ROM_CONVENTIONS",
    "ROTATION_ORDERS",
    "HingeProtocol",
    "joint_angles",
    "nominal_markers",
    "protocol_from_config",
    "simulate",
]

MOTIONS = ("lissajous", "sequential", "superimposed", "grid")
ROM_CONVENTIONS = ("full", "half")
ROTATION_ORDERS = ("fe_aa", "aa_fe")

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
    motion : how FE and AA are combined over time, one of :data:`MOTIONS` (see the module notes).
    rom_convention : "full" (the RoM is the peak-to-peak excursion) or "half" (the RoM is the
        amplitude, so the excursion is twice the RoM).
    fe_cycles, aa_cycles : cycles of FE and AA over the recording ("lissajous"; "superimposed"
        uses ``aa_cycles``).
    aa_phase_deg : phase of the AA sinusoid relative to FE ("lissajous", "superimposed").
    rotation_order : "fe_aa": ``R = R_FE(fe) R_AA(aa)``, AA about the axis carried by the moving
        segment (Grood & Suntay's floating axis), so the FE axis stays fixed in the reference
        frame, as paper B's model requires; "aa_fe": ``R = R_AA(aa) R_FE(fe)``, AA about the
        reference segment's axis, which carries the FE axis with it.
    noise_sd_mm : SD of the isotropic marker-noise magnitude [mm] (paper B: 1.0).
    n_frames : frames per trial (paper B: 121).
    """

    name: str
    marker_names: tuple[str, ...]
    markers_mm: tuple[tuple[float, float, float], ...]
    motion: str = "lissajous"
    rom_convention: str = "full"
    fe_cycles: float = 1.0
    aa_cycles: float = 2.0
    aa_phase_deg: float = 0.0
    rotation_order: str = "fe_aa"
    noise_sd_mm: float = 1.0
    n_frames: int = 121

    def __post_init__(self) -> None:
        markers = tuple(tuple(float(c) for c in marker) for marker in self.markers_mm)
        object.__setattr__(self, "markers_mm", markers)
        object.__setattr__(self, "marker_names", tuple(str(n) for n in self.marker_names))
        if not markers or any(len(m) != 3 for m in markers):
            raise ValueError("markers_mm must be a non-empty sequence of (x, y, z) positions")
        if not all(math.isfinite(c) for m in markers for c in m):
            raise ValueError("markers_mm must be finite")
        if len(self.marker_names) != len(markers):
            raise ValueError(
                f"marker_names has {len(self.marker_names)} names for {len(markers)} markers"
            )
        for field, allowed in (
            ("motion", MOTIONS),
            ("rom_convention", ROM_CONVENTIONS),
            ("rotation_order", ROTATION_ORDERS),
        ):
            if getattr(self, field) not in allowed:
                raise ValueError(
                    f"{field} must be one of {', '.join(allowed)}, got {getattr(self, field)!r}"
                )
        if not self.noise_sd_mm >= 0:
            raise ValueError(f"noise_sd_mm must be >= 0, got {self.noise_sd_mm}")
        if int(self.n_frames) != self.n_frames or self.n_frames < 4:
            raise ValueError(f"n_frames must be an integer >= 4, got {self.n_frames}")
        if self.motion == "grid" and math.isqrt(int(self.n_frames)) ** 2 != self.n_frames:
            raise ValueError(f"motion 'grid' needs a square n_frames, got {self.n_frames}")
        if not (self.fe_cycles > 0 and self.aa_cycles > 0):
            raise ValueError("fe_cycles and aa_cycles must be > 0")

    @property
    def markers(self) -> np.ndarray:
        """Neutral-pose marker positions ``(n_markers, 3)`` [mm]."""
        return np.array(self.markers_mm)


HINGE_PROTOCOLS: dict[str, HingeProtocol] = {
    "knee": HingeProtocol(
        name="knee",
        marker_names=("L1", "L2", "L3"),
        markers_mm=((65.8, 24.4, -174.4), (-23.5, -30.9, -188.8), (42.3, -18.8, -153.2)),
    ),
    "mcp": HingeProtocol(
        name="mcp",
        marker_names=("P1", "P2", "P3"),
        markers_mm=((3.0, 11.0, -12.0), (6.0, 10.0, -24.0), (2.0, 10.0, -36.0)),
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
    fields = {f.name for f in dataclasses.fields(HingeProtocol)}
    unknown = sorted(set(settings) - fields)
    if unknown:
        raise ValueError(
            f"unknown hinge protocol settings: {', '.join(unknown)}; "
            f"known: {', '.join(sorted(fields))}"
        )
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
        # An FE cycle about mid-range with AA at neutral, then an AA cycle at mid-range FE.
        split = n // 2
        first, second = np.linspace(0.0, 1.0, split), np.linspace(0.0, 1.0, n - split)
        fe_wave = np.concatenate([np.sin(2.0 * np.pi * first), np.zeros(n - split)])
        aa_wave = np.concatenate([np.zeros(split), np.sin(2.0 * np.pi * second)])
    elif protocol.motion == "superimposed":
        fe_wave = np.linspace(-1.0, 1.0, n)
        aa_wave = np.sin(2.0 * np.pi * protocol.aa_cycles * t + phase)
    else:  # grid: every combination of sqrt(n) FE and sqrt(n) AA values, boustrophedon order
        side = math.isqrt(n)
        levels = np.linspace(-1.0, 1.0, side)
        fe_wave = np.repeat(levels, side)
        aa_wave = np.concatenate([levels if i % 2 == 0 else levels[::-1] for i in range(side)])
    return fe_half * (1.0 + fe_wave), aa_half * aa_wave


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
