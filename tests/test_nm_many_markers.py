"""NM on clusters of many markers: the fit reduced to five unknowns
(:func:`jointbench.estimators.sphere._nm_reduced_trials`) gives the answers, failure codes and
checked results of the full ``(4 + P)``-square problem (:func:`sphere._nm_trials`), in memory
linear in the markers.

The full problem's own rounding bounds the agreement: against a 40-digit solution of the same
problem (21 and 60 markers over 5 frames) its centres were off by up to 9e-12 and its costs by
up to 5e-11 relative, the reduced fit's by 1e-13 and 2e-13.
"""

from __future__ import annotations

import numpy as np
import pytest
from peak_memory import peak_growth_mb

import jointbench
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


def _both(data: np.ndarray) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    """``(centres, radii, costs, failures)`` of the full and the reduced kernel on trials
    ``data`` ``(T, N, P, 3)`` [mm]."""
    data = np.ascontiguousarray(data)
    n_trials, _, n_markers, _ = data.shape
    answers = []
    for full in (True, False):
        out = (
            np.full((n_trials, 3), np.nan),
            np.full((n_trials, n_markers), np.nan),
            np.full(n_trials, np.nan),
            np.zeros(n_trials, dtype=np.int64),
        )
        if full:
            sphere._nm_trials(data, sphere._nm_constraint(n_markers), sphere._EPS, *out)
        else:
            sphere._nm_reduced_trials(data, sphere._EPS, *out)
        answers.append(out)
    return answers[0], answers[1]


@pytest.mark.parametrize(("n_markers", "n_frames"), [(3, 120), (21, 5), (60, 5), (200, 20)])
def test_the_reduced_fit_is_the_full_problems(n_markers, n_frames):
    """Centres, radii, costs and failure codes of the two forms agree, trial by trial, for a
    noise-free trial (a singular scatter, code 3) among noisy ones."""
    trials = [_cluster(n_markers, n_frames, seed) for seed in range(3)]
    trials.append(_cluster(n_markers, n_frames, 9, noise=0.0))
    full, reduced = _both(np.stack(trials))
    np.testing.assert_array_equal(reduced[3], full[3])
    assert list(full[3]) == [0, 0, 0, 3]
    centre_error = np.linalg.norm(reduced[0][:3] - full[0][:3], axis=1)
    assert np.all(centre_error <= AGREEMENT * np.linalg.norm(full[0][:3], axis=1))
    np.testing.assert_allclose(reduced[1][:3], full[1][:3], rtol=AGREEMENT)
    np.testing.assert_allclose(reduced[2][:3], full[2][:3], rtol=AGREEMENT)


def test_the_checked_call_is_the_same(monkeypatch):
    """:func:`jointbench.fit_center` on more markers than :data:`sphere.NM_DENSE_MARKERS`:
    the status, convergence and diagnostics of the full problem's call, its numbers within
    the agreement."""
    markers = _cluster(sphere.NM_DENSE_MARKERS + 5, 6, 4)
    reduced = jointbench.fit_center(markers.copy(), "NM", artefacts="warn")
    monkeypatch.setattr(sphere, "NM_DENSE_MARKERS", 10**9)
    full = jointbench.fit_center(markers.copy(), "NM", artefacts="warn")
    assert (reduced.status, reduced.converged) == (full.status, full.converged)
    assert reduced.diagnostics.keys() == full.diagnostics.keys()
    for key, value in full.diagnostics.items():
        if isinstance(value, float):
            assert reduced.diagnostics[key] == pytest.approx(value, rel=AGREEMENT, abs=1e-12)
        else:
            assert str(reduced.diagnostics[key]) == str(value), key
    np.testing.assert_allclose(reduced.center, full.center, rtol=AGREEMENT)


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
