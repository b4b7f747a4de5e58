"""NM on clusters of many markers: its kernel (:func:`jointbench.estimators.sphere._nm_trials`),
which reduces paper A's ``(4 + P)``-square eigenproblem to five unknowns, gives the answers of
that problem solved at its full size (:func:`sphere._nm_singular`, whitened by the SVD of the
data matrix), in memory linear in the markers.

The full problem's own rounding bounds the agreement: against a 40-digit solution of the same
problem (21 and 60 markers over 5 frames) a full-size solution's centres were off by up to
9e-12 and its costs by up to 5e-11 relative, the reduced fit's by 1e-13 and 2e-13.
"""

from __future__ import annotations

import numpy as np
import pytest
from peak_memory import peak_growth_mb

from jointbench.estimators import sphere
from jointbench.geometry import rotation_matrix

#: The agreement of the two forms: above the full problem's own error (see above).
AGREEMENT = 1e-9

#: Markers whose full problem keeps five ``(4 + P)``-square matrices of 18 MB each.
MANY_MARKERS = 1500


def _cluster(n_markers: int, n_frames: int, seed: int, noise: float = 0.3) -> np.ndarray:
    """Markers ``(n_frames, n_markers, 3)`` [mm] of a rigid cluster turning about three axes
    about a centre away from the origin, with Gaussian ``noise`` [mm]."""
    rng = np.random.default_rng(seed)
    body = rng.normal(scale=60.0, size=(n_markers, 3)) + np.array([0.0, 0.0, 250.0])
    t = np.linspace(0.0, 2.0 * np.pi, n_frames)
    rotvec = np.stack([0.5 * np.cos(t), 0.5 * np.sin(2.0 * t), 0.25 * np.sin(t)], -1)
    markers = np.einsum("fij,mj->fmi", rotation_matrix(rotvec), body) + np.array(
        [40.0, -30.0, 20.0]
    )
    return markers + rng.normal(scale=noise, size=markers.shape)


def _kernel(data: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(centres, radii, costs, failures)`` of NM's kernel on trials ``data``
    ``(T, N, P, 3)`` [mm]."""
    data = np.ascontiguousarray(data)
    n_trials, _, n_markers, _ = data.shape
    out = (
        np.full((n_trials, 3), np.nan),
        np.full((n_trials, n_markers), np.nan),
        np.full(n_trials, np.nan),
        np.zeros(n_trials, dtype=np.int64),
    )
    sphere._nm_trials(data, sphere._EPS, *out)
    return out


@pytest.mark.parametrize(("n_markers", "n_frames"), [(3, 120), (21, 5), (60, 5), (200, 20)])
def test_the_reduced_fit_is_the_full_problems(n_markers, n_frames):
    """Centres, radii and costs of the kernel agree, trial by trial, with the problem solved at
    its full size, and a noise-free trial (a singular scatter) is handed on (code 3)."""
    trials = [_cluster(n_markers, n_frames, seed) for seed in range(3)]
    trials.append(_cluster(n_markers, n_frames, 9, noise=0.0))
    centres, radii, costs, failures = _kernel(np.stack(trials))
    assert list(failures) == [0, 0, 0, 3]
    for trial, markers in enumerate(trials[:3]):
        full = sphere._nm_singular(markers)
        centre_error = np.linalg.norm(centres[trial] - full.center)
        assert centre_error <= AGREEMENT * np.linalg.norm(full.center)
        np.testing.assert_allclose(radii[trial], full.radii, rtol=AGREEMENT)
        np.testing.assert_allclose(costs[trial], full.cost, rtol=AGREEMENT)


@pytest.mark.parametrize("method", ["NM", "MA"])
def test_nm_on_many_markers_takes_memory_linear_in_them(method):
    """A checked NM call (and MA's, whose self-check fits NM) on 1,500 markers over 5 frames
    takes less memory than one ``(4 + P)``-square matrix of the full problem (18 MB)."""
    setup = """
        import numpy as np
        import jointbench
        from jointbench.geometry import rotation_matrix
        rng = np.random.default_rng(0)
        body = rng.normal(scale=60.0, size=(n, 3))
        t = np.linspace(0.0, 2.0 * np.pi, 5)
        rotvec = np.stack([0.5 * np.cos(t), 0.5 * np.sin(2.0 * t), 0.25 * np.sin(t)], -1)
        markers = np.einsum("fij,mj->fmi", rotation_matrix(rotvec), body)
        markers = markers + rng.normal(scale=0.3, size=markers.shape)
        """
    call = f"jointbench.fit_center(markers, {method!r}, artefacts='warn')"
    most_mb = (4 + MANY_MARKERS) ** 2 * 8 / 2**20
    assert peak_growth_mb(setup, call, 30, MANY_MARKERS) < most_mb


def test_nearly_noise_free_small_arcs_are_solved_as_the_full_problem():
    """Four markers on a 2 degree arc with 1e-11 mm of noise (a simulation's rounding): the
    scatter passes the test of a singular one, but the reduced problem's ``G' S^-1 G`` can
    round to indefinite. Every draw gets the full problem's answer (handed on where the
    reduced one cannot be solved), none an error from inside the linear algebra."""
    rng = np.random.default_rng(0)
    t = np.linspace(0.0, 1.0, 120)
    spiral = 6.0 * np.pi * t
    rotvec = np.radians(2.0) * np.stack([t * np.cos(spiral), t * np.sin(spiral), 0.3 * t], -1)
    turns = rotation_matrix(rotvec)
    for _ in range(60):
        body = rng.normal(scale=50.0, size=(4, 3))
        markers = np.einsum("fij,mj->fmi", turns, body) + np.array([10.0, -20.0, 30.0])
        markers = markers + rng.normal(scale=1e-11, size=markers.shape)
        full = sphere._nm_singular(markers)
        found = sphere.fit_nm(markers)
        assert np.linalg.norm(found.center - full.center) <= AGREEMENT * np.linalg.norm(full.center)
