"""Centre estimators against literal transcriptions of their definitions on noisy data, and
their stopping rules and self-checks at the limits those set.

Noise-free data give every exact method the true centre, whatever the weighting of its cost
(and send NM down its singular-scatter path), so they cannot tell a method from a neighbour
of it: these tests use noisy data, where each definition has an answer of its own.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.linalg
from test_center_estimators import CENTER, M_SET, moving_markers, spiral_rotations

from jointbench.estimators import amplitude, sphere
from jointbench.estimators.amplitude import fit_ma
from jointbench.estimators.sphere import fit_bc, fit_is, fit_ls, fit_nm
from jointbench.estimators.twosegment import fit_score_center
from jointbench.numerics.poses import rigid_poses
from jointbench.simulate.noise import isotropic_noise


def _noisy_cap(seed: int, rom_deg: float = 25.0, noise_mm: float = 0.5) -> np.ndarray:
    """Paper A's M set on a circumduction, far from the origin, with isotropic noise."""
    markers = moving_markers(spiral_rotations(rom_deg), M_SET, CENTER) + 300.0
    return markers + isotropic_noise(np.random.default_rng(seed), markers.shape[:2], noise_mm)


def _nm_by_the_generalised_eigenproblem(markers: np.ndarray):
    """Paper A eqs. 13-25 as printed (radii with the sign the fit's docstring corrects),
    solved by ``scipy.linalg.eig(S, C)`` on the data centred and scaled to unit RMS: the centre
    [mm], the radii [mm] and the least admissible ``lambda = u' S u`` with ``u' C u = 1``."""
    n_frames, n_markers, _ = markers.shape
    rows = markers.reshape(-1, 3)
    origin = rows.mean(axis=0)
    scale = np.sqrt(np.mean(np.sum((rows - origin) ** 2, axis=1)))
    scaled = (markers - origin) / scale
    design = np.zeros((n_markers * n_frames, 4 + n_markers))
    for p in range(n_markers):
        block = slice(p * n_frames, (p + 1) * n_frames)
        design[block, 0] = np.sum(scaled[:, p] ** 2, axis=1)
        design[block, 1:4] = scaled[:, p]
        design[block, 4 + p] = 1.0
    scatter = design.T @ design
    constraint = np.zeros((4 + n_markers, 4 + n_markers))
    constraint[1:4, 1:4] = n_markers * np.eye(3)
    constraint[0, 4:] = constraint[4:, 0] = -2.0
    values, vectors = scipy.linalg.eig(scatter, constraint)
    best = None
    for value, vector in zip(values, vectors.T, strict=True):
        vector = np.real(vector)
        norm = vector @ constraint @ vector
        if not (np.isfinite(value) and norm > 0.0):
            continue
        u = vector / np.sqrt(norm)
        cost = u @ scatter @ u
        if best is None or cost < best[0]:
            best = (cost, u)
    cost, u = best
    a, bcd, e = u[0], u[1:4], u[4:]
    centre = bcd / (-2.0 * a)
    radii = np.sqrt(centre @ centre - e / a)
    return origin + scale * centre, scale * radii, cost


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_nm_is_the_least_admissible_generalised_eigenvector(seed):
    """NM's centre, radii and cost are paper A's eigenproblem ``S u = lambda C u`` solved
    directly (the fit whitens it instead). Three markers, so that the constraint's ``P I``
    block weighs the centre's terms against the markers' constants."""
    markers = _noisy_cap(seed)
    centre, radii, cost = _nm_by_the_generalised_eigenproblem(markers)
    result = fit_nm(markers)
    np.testing.assert_allclose(result.center, centre, atol=1e-6)
    np.testing.assert_allclose(result.radii, radii, rtol=1e-8)
    assert result.cost == pytest.approx(cost, rel=1e-6)


@pytest.mark.parametrize("fit", [fit_ls, fit_bc])
def test_ls_and_bc_cost_is_f2_at_their_centre(fit):
    """``cost`` is paper A's eq. 4, ``sum_p sum_k (|v - c|^2 - r_p^2)^2`` with the radii
    profiled out (``r_p^2`` the mean squared distance), evaluated literally."""
    markers = _noisy_cap(seed=3)
    result = fit(markers)
    squared = np.sum((markers - result.center) ** 2, axis=-1)
    expected = np.sum((squared - squared.mean(axis=0)) ** 2)
    assert result.cost == pytest.approx(expected, rel=1e-9)
    np.testing.assert_allclose(result.radii, np.sqrt(squared.mean(axis=0)), rtol=1e-12)


@pytest.mark.parametrize(
    ("module", "fit"), [(sphere, fit_is), (amplitude, fit_ma)], ids=["IS", "MA"]
)
def test_a_search_stopped_by_its_iteration_limit_is_not_converged(monkeypatch, module, fit):
    """With fminsearch's iteration limit lowered to 5 the simplex cannot meet its tolerances:
    the answer must say it stopped at the limit, not claim convergence."""
    limits = {**module.FMINSEARCH_OPTIONS, "max_iter": 5}
    monkeypatch.setattr(module, "FMINSEARCH_OPTIONS", limits)
    markers = _noisy_cap(seed=4)
    result = fit(markers, start=CENTER + 300.0 + np.array([20.0, -10.0, 15.0]))
    assert result.iterations == 5
    assert not result.converged
    assert result.status == "Maximum number of iterations has been exceeded."


def test_bc_self_check_fails_an_answer_a_few_tolerances_from_its_fixed_point():
    """BC's self-check takes one more of Halvorsen's updates from the returned centre; an
    answer moved 5 tol_x off the fixed point comes back by about that much, more than tol_x
    (and less than ten times it), so it must fail while the answer itself holds."""
    markers = _noisy_cap(seed=5)
    result = fit_bc(markers)
    assert result.converged, result.status
    held = fit_bc.self_check(result, markers)
    assert held.converged and held.status == "ok"
    moved = dataclasses.replace(result, center=result.center + np.array([5e-4, 0.0, 0.0]))
    checked = fit_bc.self_check(moved, markers)
    assert not checked.converged
    assert checked.status.startswith("self-check failed: not BC's fixed point")
    step = float(checked.diagnostics["self_check"].split("by ")[1].split(" mm")[0])
    assert 1e-4 < step < 1e-3


def test_amplitude_is_the_summed_sides_of_the_trajectorys_bounding_box():
    """Identity rotations and translations ``k (1, 2, 3)`` mm over 5 frames move every point
    along a box of sides 4, 8 and 12 mm: amplitude 24 mm wherever the point is."""
    rotation = np.repeat(np.eye(3)[None], 5, axis=0)
    translation = np.arange(5.0)[:, None] * np.array([1.0, 2.0, 3.0])
    for point in ([0.0, 0.0, 0.0], [10.0, -3.0, 7.0]):
        assert amplitude.amplitude(rotation, translation, np.array(point)) == pytest.approx(24.0)


def _halvorsen(markers: np.ndarray, tol_x: float, tol_fun: float, max_iterations: int = 600):
    """Halvorsen's iteration as :func:`fit_bc` documents it, written out with the sums over
    frames: the centre, the updates made and whether both tests were met."""
    means = markers.mean(axis=0)
    centred = markers - means
    a_matrix = 2.0 * np.einsum("kpi,kpj->ij", centred, centred) / len(markers)
    squares = np.sum(markers**2, axis=-1)
    b_vector = np.einsum("kpi,kp->i", centred, squares - squares.mean(axis=0)) / len(markers)

    def variance(centre):
        u2 = np.sum((markers - centre) ** 2, axis=-1)
        mean_u2 = u2.mean(axis=0)
        return np.mean(np.sum((u2 - mean_u2) ** 2, axis=0) / (4.0 * mean_u2 * len(markers)))

    centre = np.linalg.solve(a_matrix, b_vector)
    sigma2 = variance(centre)
    for iteration in range(1, max_iterations + 1):
        compensation = 2.0 * sigma2 * np.sum(means - centre, axis=0)
        updated = np.linalg.solve(a_matrix, b_vector - compensation)
        updated_sigma2 = variance(updated)
        step, change = np.max(np.abs(updated - centre)), abs(updated_sigma2 - sigma2)
        centre, sigma2 = updated, updated_sigma2
        if step <= tol_x and change <= tol_fun:
            return centre, iteration, True
    return centre, max_iterations, False


@pytest.mark.parametrize(
    ("tol_x", "tol_fun"), [(1e-4, 1e-4), (1e3, 1e-4), (1e-4, 1e3)], ids=["both", "fun", "x"]
)
def test_bc_follows_halvorsens_iteration_update_by_update(tol_x, tol_fun):
    """On a 15 degree cap with 1 mm noise BC takes tens of updates: it must stop at the update
    the written-out iteration stops at, under either test alone and under both."""
    markers = moving_markers(spiral_rotations(15.0), M_SET, CENTER) + 300.0
    markers = markers + isotropic_noise(np.random.default_rng(8), markers.shape[:2], 1.0)
    centre, iterations, converged = _halvorsen(markers, tol_x, tol_fun)
    result = fit_bc(markers, tol_x=tol_x, tol_fun=tol_fun)
    assert iterations > 3
    assert (result.iterations, result.converged) == (iterations, converged)
    np.testing.assert_allclose(result.center, centre, atol=1e-6)


def test_is_radii_are_the_mean_distances_from_its_centre():
    markers = _noisy_cap(seed=6)
    result = fit_is(markers)
    distances = np.linalg.norm(markers - result.center, axis=-1)
    np.testing.assert_allclose(result.radii, distances.mean(axis=0), rtol=1e-12)


def test_is_self_check_restarts_from_a_neighbour_a_few_tol_fun_below_the_answer():
    """An IS answer whose f1 lies 5 TolFun above the lower of its neighbours' (the LS and NM
    centres; more than fminsearch's TolFun, less than ten times it) is restarted."""
    markers = _noisy_cap(seed=7)
    neighbours = [fit_ls(markers).center, fit_nm(markers).center]
    costs = [sphere.geometric_cost(markers, point) for point in neighbours]
    nearest, least = neighbours[int(np.argmin(costs))], min(costs)
    target = least + 5e-4
    outward = np.array([1.0, 0.0, 0.0])
    low, high = 0.0, 1.0
    while sphere.geometric_cost(markers, nearest + high * outward) < target:
        high *= 2.0
    for _ in range(200):
        middle = 0.5 * (low + high)
        if sphere.geometric_cost(markers, nearest + middle * outward) < target:
            low = middle
        else:
            high = middle
    centre = nearest + high * outward
    answer = dataclasses.replace(
        fit_is(markers), center=centre, cost=sphere.geometric_cost(markers, centre)
    )
    assert 1e-4 < answer.cost - least < 1e-3
    checked = fit_is.self_check(answer, markers)
    assert checked.status.startswith("restarted: ")
    assert checked.cost < answer.cost


def test_mean_sq_radii_are_the_mean_squared_distances_from_the_centre():
    markers = _noisy_cap(seed=8)
    centre = CENTER + 300.0 + np.array([1.0, -2.0, 0.5])
    expected = np.mean(np.sum((markers - centre) ** 2, axis=-1), axis=0)
    np.testing.assert_allclose(sphere.mean_sq_radii(markers, centre), expected, rtol=1e-12)


def test_ma_self_check_restarts_from_a_neighbour_a_few_tol_fun_below_the_answer():
    """An MA answer whose amplitude lies 5 TolFun above the least of its neighbours' (the LS,
    NM and SCoRE centres, each the body point whose trajectory has that mean) is restarted."""
    markers = _noisy_cap(seed=9)
    rotation, translation = amplitude._mean_anchored(*rigid_poses(markers)[:2])
    neighbours = [fit_ls(markers).center, fit_nm(markers).center]
    neighbours.append(fit_score_center(markers).center)
    least = min(amplitude.amplitude(rotation, translation, point) for point in neighbours)
    answer = dataclasses.replace(fit_ma(markers), cost=least + 5e-4)
    checked = fit_ma.self_check(answer, markers)
    assert checked.status.startswith("restarted: ")
    assert checked.cost < answer.cost
