"""A centre of a near hinge (a knee's flexion with a few degrees of another rotation) whose
answer lies several of its stated SDs from the truth while its status reads ``ok``.

The precision check reports a step to the spheres' common centre only beyond
:data:`jointbench.estimators.centre_precision.MIN_REJECTED_STEP_MM` (5 mm), as a method's
own bias; an SD far below that step then states a scatter the answer does not keep to.
"""

from __future__ import annotations

import numpy as np
import pytest
from rigs import DISTAL, HINGE, JOINT, apply_pose

import jointbench
from jointbench.geometry import rotation_matrix, unit

# A second axis normal to the hinge: the few degrees of rotation that make a knee no hinge.
_OTHER = unit(np.cross(HINGE, [0.0, 0.0, 1.0]))


def _near_hinge(seed: int, *, flexion_deg=40.0, other_deg=4.0, noise_mm=0.5) -> np.ndarray:
    """DISTAL ``(200, 3, 3)`` [mm] swung ``flexion_deg`` about HINGE and ``other_deg`` about
    a normal axis through JOINT, with isotropic noise of ``noise_mm`` per coordinate."""
    t = np.linspace(0.0, 4.0, 200)
    rotvec = np.deg2rad(flexion_deg) * np.sin(1.9 * t)[:, None] * HINGE
    rotvec += np.deg2rad(other_deg) * np.sin(1.3 * t + 0.5)[:, None] * _OTHER
    rotation = rotation_matrix(rotvec)
    markers = apply_pose(rotation, JOINT - rotation @ JOINT, DISTAL)
    return markers + np.random.default_rng(seed).normal(0.0, noise_mm, markers.shape)


@pytest.mark.xfail(
    strict=True,
    reason="a step to the spheres' centre under MIN_REJECTED_STEP_MM is not reported, "
    "however many SDs it is: SCoRE reads ok 3.1 mm off with an SD of 0.51 mm (4 deg), "
    "7.4 mm off with an SD of 1.05 mm and a score test at p < 1e-3 (2 deg)",
)
@pytest.mark.parametrize("other_deg, seed", [(4.0, 1), (4.0, 3), (2.0, 26)])
def test_an_ok_score_centre_of_a_near_hinge_lies_within_three_of_its_sds(other_deg, seed):
    result = jointbench.fit_center(_near_hinge(seed, other_deg=other_deg), "SCoRE")
    sd = float(result.diagnostics["center_sd_mm"])
    error = float(np.linalg.norm(result.center - JOINT))
    assert result.status != "ok" or error <= 3.0 * sd, (result.status, error, sd)
