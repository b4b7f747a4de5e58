"""The hinge study: paper B's knee and index-MCP protocols, chosen by the condition.

The joint models themselves, with every modelling choice documented, are in
:mod:`jointbench.simulate.hinge`; this module holds the pair the study runs and applies the
config's overrides: ``protocol: {all: {...}, knee: {...}, mcp: {...}}``, where ``all`` applies
to both joints (e.g. the motion model) and a joint's own entry to that joint.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from jointbench.declared import DeclarationError
from jointbench.declared import check_fields as check_declared
from jointbench.simulate import GridValues, Study, Trials, hinge

__all__ = ["STUDY", "HingeStudyProtocol", "simulate"]


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
        shared = dict(overrides.pop("all", {}))
        joints = {}
        for name in sorted(set(hinge.HINGE_PROTOCOLS) | set(overrides)):
            settings = {"name": name, **shared, **overrides.get(name, {})}
            try:
                joints[name] = hinge.protocol_from_config(settings)
            except DeclarationError as error:
                raise error.under(name) from None
        return cls(joints)


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


STUDY = Study(
    name="hinge",
    kind="axis",
    grid_keys=("protocol", "fe_rom_deg", "aa_ratio"),
    seed_keys=("protocol", "fe_rom_deg", "aa_ratio"),
    segments=("moving",),
    protocol_class=HingeStudyProtocol,
    simulate=simulate,
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
