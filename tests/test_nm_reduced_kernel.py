"""NM's kernel (:func:`jointbench.estimators.sphere._nm_trials`) against paper A's eigenproblem
reduced to five unknowns and solved by LAPACK, as NumPy calls it: ``Z^-1`` by LU, the Cholesky
factor of ``H = G' S^-1 G``, the symmetric eigen-solve and the triangular solve for ``x``. The
kernel solves the same reduced problem by ``Z``'s own Cholesky factor and Jacobi rotations; on
noisy trials the two agree to rounding, and a scatter the reduction cannot factor is handed to
the SVD path (:func:`sphere._nm_singular`) instead of raising.

On near-exact data (noise of 1e-4 mm, say) the cost ``1 / mu`` is a small eigenvalue of a
matrix of order one and is known only to ``eps / cost`` relative: against a 40-digit solution
both forms' costs were off by up to 1e-4 relative there, so those trials compare failure codes
only.
"""

from __future__ import annotations

import numpy as np
import pytest

from jointbench.estimators import sphere
from jointbench.geometry import rotation_matrix

#: The agreement of the kernel with the LAPACK solution on noisy trials: rounding.
AGREEMENT = 1e-12


def _trial(n_markers: int, n_frames: int, rom_deg: float, noise: float, seed: int) -> np.ndarray:
    """Markers ``(n_frames, n_markers, 3)`` [mm]: a rigid cluster 20 to 220 mm from a centre
    off the origin, turning ``rom_deg`` about three axes, with Gaussian ``noise`` [mm]."""
    rng = np.random.default_rng(seed)
    body = rng.normal(size=(n_markers, 3))
    body *= (20.0 + 200.0 * rng.random((n_markers, 1))) / np.linalg.norm(
        body, axis=1, keepdims=True
    )
    t = np.linspace(0.0, 1.0, n_frames)
    rotvec = np.deg2rad(rom_deg) * np.stack(
        [np.sin(6.0 * np.pi * t), 0.8 * np.cos(6.0 * np.pi * t), 0.3 * np.sin(3.0 * np.pi * t)], -1
    )
    centre = rng.normal(scale=100.0, size=3)
    markers = np.einsum("fij,pj->fpi", rotation_matrix(rotvec), body) + centre
    return markers + rng.normal(scale=noise, size=markers.shape)


def _lapack_fit(markers: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, int]:
    """``(centre [mm], radii [mm], cost, failure code)`` of one trial ``(N, P, 3)`` [mm] by the
    reduced eigenproblem of :func:`sphere._nm_trials` solved with NumPy's LAPACK calls; the
    singular-scatter test on the Cholesky pivots of the full scatter."""
    n_frames, n_markers, _ = markers.shape
    nan = (np.full(3, np.nan), np.full(n_markers, np.nan), np.nan)
    ox, oy, oz, scale = sphere._nm_origin_scale(np.ascontiguousarray(markers))
    origin = np.array([ox, oy, oz])
    scaled = (markers - origin) * (1.0 / scale)
    design = sphere._nm_design(scaled)
    try:
        pivots = np.diag(np.linalg.cholesky(design.T @ design)) ** 2
    except np.linalg.LinAlgError:
        return *nan, 3
    if not pivots.min() > 1e-9 * pivots.max():
        return *nan, 3
    basis = np.concatenate([np.sum(scaled**2, axis=-1, keepdims=True), scaled], axis=-1)
    sums = basis.sum(axis=0)
    centred = basis - sums / n_frames
    within_inv = np.linalg.inv(np.einsum("fpi,fpj->ij", centred, centred))
    total = sums.sum(axis=0)
    reduced = np.empty((5, 5))
    reduced[:4, :4] = within_inv
    reduced[:4, 4] = reduced[4, :4] = -(within_inv @ total) / n_frames
    reduced[4, 4] = n_markers / n_frames + total @ within_inv @ total / n_frames**2
    factor = np.linalg.cholesky(reduced)
    weights = np.zeros((5, 5))
    weights[0, 4] = weights[4, 0] = -2.0
    weights[1:4, 1:4] = n_markers * np.eye(3)
    mu, vectors = np.linalg.eigh(factor.T @ weights @ factor)
    x = np.linalg.solve(factor.T, vectors[:, 4])
    head = within_inv @ (x[:4] - x[4] * total / n_frames)
    u = np.concatenate([head, (x[4] - sums @ head) / n_frames])
    norm = u @ sphere._nm_constraint(n_markers) @ u
    if not (mu[4] > 0 and norm > 0):
        return *nan, 1
    u = u / np.sqrt(norm)
    if not abs(u[0]) >= sphere._EPS * np.abs(u).max():
        return *nan, 2
    centre = u[1:4] / (-2.0 * u[0])
    radii = scale * np.sqrt(np.maximum(centre @ centre - u[4:] / u[0], 0.0))
    return origin + scale * centre, radii, 1.0 / mu[4], 0


def _kernel(data: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(centres, radii, costs, failures)`` of NM's kernel on trials ``(T, N, P, 3)`` [mm]."""
    n_trials, _, n_markers, _ = data.shape
    out = (
        np.full((n_trials, 3), np.nan),
        np.full((n_trials, n_markers), np.nan),
        np.full(n_trials, np.nan),
        np.full(n_trials, -1, dtype=np.int64),
    )
    sphere._nm_trials(np.ascontiguousarray(data), sphere._EPS, *out)
    return out


@pytest.mark.parametrize("n_markers", [1, 2, 3, 4, 8, 25])
@pytest.mark.parametrize("n_frames", [5, 12, 120])
def test_noisy_trials_agree_with_the_lapack_solution(n_markers, n_frames):
    """Twelve noisy trials per size (0.3 and 1 mm, 5 to 90 degrees): the same failure codes,
    centres and radii to rounding, and costs to rounding too: a cost is a sum of ``N P``
    squared residuals of unit-RMS rows, its rounding some ``eps N P`` whatever its size
    (the two forms' costs of 1e-5 differ by 5e-17)."""
    trials = [
        _trial(n_markers, n_frames, rom, noise, seed)
        for seed, (rom, noise) in enumerate(
            [(rom, noise) for rom in (5.0, 30.0, 90.0) for noise in (0.3, 1.0)] * 2
        )
    ]
    centres, radii, costs, failures = _kernel(np.stack(trials))
    for trial, markers in enumerate(trials):
        centre, radius, cost, code = _lapack_fit(markers)
        assert failures[trial] == code, trial
        if code:
            continue
        scale = np.linalg.norm(centre)
        assert np.linalg.norm(centres[trial] - centre) <= AGREEMENT * scale, trial
        np.testing.assert_allclose(radii[trial], radius, rtol=AGREEMENT)
        rounding = 8.0 * sphere._EPS * n_frames * n_markers
        assert abs(costs[trial] - cost) <= AGREEMENT * cost + rounding, trial


@pytest.mark.parametrize("n_markers", [1, 3, 4, 8])
@pytest.mark.parametrize("rom", [0.5, 2.0, 15.0])
def test_near_exact_trials_take_the_same_path(n_markers, rom):
    """Noise-free and nearly noise-free trials (1e-6 and 1e-4 mm): the same failure codes,
    a singular scatter (code 3) among them."""
    trials = [
        _trial(n_markers, n_frames, rom, noise, seed)
        for seed, (n_frames, noise) in enumerate(
            [(n_frames, noise) for n_frames in (6, 10, 30) for noise in (0.0, 1e-6, 1e-4)]
        )
    ]
    failures = [_kernel(markers[None])[3][0] for markers in trials]
    assert failures == [_lapack_fit(markers)[3] for markers in trials]
    assert 3 in failures


@pytest.mark.parametrize(
    ("n_frames", "rom", "seed", "code"), [(10, 0.5, 0, 3), (30, 2.0, 93, 0), (30, 0.5, 127, 0)]
)
def test_exact_data_near_the_singular_test_get_their_centre(n_frames, rom, seed, code):
    """Exact data of 4 markers whose scatter passes the pivots' test though rounding leaves
    ``Z`` all but singular, where ``H``'s Cholesky factor from ``Z^-1`` by LU failed: the
    kernel answers from ``Z``'s own factor, or hands the trial to the SVD path (code 3) where a
    pivot of ``Z`` is not positive; the fit finds the centre, it does not raise."""
    markers = _trial(4, n_frames, rom, 0.0, seed)
    assert _kernel(markers[None])[3][0] == code
    result = sphere.fit_nm(markers)
    assert result.status == "ok"
    np.testing.assert_allclose(result.center, _true_centre(seed), atol=1e-9)


def _true_centre(seed: int) -> np.ndarray:
    """The centre [mm] :func:`_trial` draws for ``seed``, after the body (4 markers)."""
    rng = np.random.default_rng(seed)
    rng.normal(size=(4, 3))
    rng.random((4, 1))
    return rng.normal(scale=100.0, size=3)
