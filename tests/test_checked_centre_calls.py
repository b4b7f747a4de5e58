"""The centre methods' checked forms, one trial and many, give one answer: the batched checked
call's outcome per trial is the one-trial checked call's, its status and support verdict to
the last bit, on data that pass and data that draw each of the verdict's warnings."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jointbench.estimators import registry, support
from jointbench.geometry import rotation_matrix

CENTRE = np.array([10.0, -20.0, 30.0])
BODY = np.array([[60.0, 20.0, 10.0], [90.0, -15.0, 25.0], [75.0, 5.0, -30.0], [50.0, -10.0, -20.0]])


def _trial(rng, rom_deg, noise_mm, *, hinge=False, n_frames=90, body=BODY) -> np.ndarray:
    """Markers ``body`` ``(n, 3)`` [mm], ``(n_frames, n, 3)``, turning about a centre through a
    spiral of rotations ``rom_deg`` wide (about one axis for a ``hinge``), with isotropic noise
    ``noise_mm``."""
    t = np.linspace(0.0, 1.0, n_frames)
    angle = math.radians(rom_deg)
    if hinge:
        vectors = angle * np.stack([np.sin(2 * np.pi * t), 0 * t, 0 * t], axis=-1)
    else:
        spiral = 6 * np.pi * t
        vectors = angle * np.stack([t * np.cos(spiral), t * np.sin(spiral), 0.3 * t], axis=-1)
    markers = np.einsum("kij,mj->kmi", rotation_matrix(vectors), body) + CENTRE
    return markers + rng.normal(scale=noise_mm, size=markers.shape)


def _trials():
    rng = np.random.default_rng(11)
    return np.stack(
        [
            _trial(rng, 30.0, 0.5),  # supported
            _trial(rng, 15.0, 1.0),
            _trial(rng, 0.05, 1.0),  # range of motion too small
            _trial(rng, 40.0, 0.5, hinge=True),  # rotation about a single axis
            _trial(rng, 20.0, 25.0),  # not one rigid body
        ]
    )


def _same(a, b) -> bool:
    """Equal, NaN equal to NaN, arrays element by element."""
    if isinstance(b, np.ndarray) or isinstance(a, np.ndarray):
        return np.array_equal(a, b, equal_nan=True)
    if isinstance(b, float) and math.isnan(b):
        return isinstance(a, float) and math.isnan(a)
    return type(a) is type(b) and a == b


@pytest.mark.parametrize("method", ["LS", "NM", "BC"])
def test_the_batched_checked_call_is_the_one_trial_checked_call(method):
    trials = _trials()
    outcomes = registry.many("center", method)(trials)
    fit = registry.get("center", method)
    statuses = set()
    for trial, outcome in zip(trials, outcomes, strict=True):
        single = fit(trial)
        assert outcome.status == single.status
        assert outcome.diagnostics.keys() == single.diagnostics.keys()
        for key, value in single.diagnostics.items():
            assert _same(outcome.diagnostics[key], value), key
        verdict = support.assess("center", (trial,))
        statuses.add(verdict.warnings[0][:25] if verdict.warnings else "ok")
        for key, value in verdict.diagnostics.items():
            assert _same(single.diagnostics[f"support_{key}"], value), key
            assert _same(outcome.diagnostics[f"support_{key}"], value), key
        np.testing.assert_allclose(outcome.center, single.center, rtol=1e-9)
    # The data draw every one-segment verdict: none, range, single axis, not rigid.
    assert len(statuses) == 4, statuses
