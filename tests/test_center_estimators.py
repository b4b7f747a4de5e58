"""Centre-of-rotation estimators NM, LS, BC, IS and MA: recovery, invariances, agreement,
input checks and honest non-convergence.

Tolerances: LS, NM and BC (on noise-free data) are closed forms or converge in one step, so
they recover the centre to rounding (1e-9 mm). IS and MA are Nelder–Mead searches stopped by
fminsearch's rule (every vertex within 1e-4 mm of the best and every cost within 1e-4 of the
best), so their answers are only as good as that simplex: 1e-3 mm on well-conditioned data.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import jointbench
from jointbench import geometry
from jointbench.estimators.amplitude import amplitude, fit_ma
from jointbench.estimators.sphere import (
    fit_bc,
    fit_is,
    fit_ls,
    fit_nm,
    geometric_cost,
    ls_system,
    solve_ls_system,
)
from jointbench.numerics.poses import rigid_poses
from jointbench.simulate.noise import isotropic_noise

CENTER_METHODS = ("NM", "LS", "BC", "IS", "MA")
EXACT = ("NM", "LS")
# Paper A Table 1, M set: marker distances from the CoR 13.8, 29.0 and 15.7 mm; the directions
# are this test's choice (a cluster on one side of the joint, like markers on one bone).
M_SET = geometry.unit(np.array([[0.2, 0.3, 1.0], [0.0, 0.1, 1.0], [-0.3, 0.2, 1.0]])) * np.array(
    [[13.8], [29.0], [15.7]]
)
CENTER = np.array([12.0, -7.0, 31.0])


def moving_markers(rotations: np.ndarray, body: np.ndarray, center: np.ndarray) -> np.ndarray:
    """Body points ``(P, 3)`` relative to the centre, rotated per frame about ``center``."""
    return np.einsum("kij,pj->kpi", rotations, body) + center


def random_rotations(rng: np.random.Generator, n_frames: int, spread_rad: float) -> np.ndarray:
    return geometry.rotation_matrix(rng.normal(scale=spread_rad, size=(n_frames, 3)))


def spiral_rotations(rom_deg: float, n_frames: int = 120, turns: float = 3.0) -> np.ndarray:
    """Circumduction from the mean position spiralling out to ``rom_deg`` (paper A §5.1)."""
    t = np.linspace(0.0, 1.0, n_frames)
    angle, phase = np.radians(rom_deg) * t, 2.0 * np.pi * turns * t
    return geometry.rotation_matrix(
        np.stack([angle * np.cos(phase), angle * np.sin(phase), np.zeros_like(t)], axis=-1)
    )


def well_conditioned(seed: int = 0, noise_mm: float = 0.0, n_markers: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    body = rng.normal(scale=30.0, size=(n_markers, 3))
    markers = moving_markers(random_rotations(rng, 120, 0.6), body, CENTER)
    if noise_mm:
        markers = markers + isotropic_noise(rng, markers.shape[:2], noise_mm)
    return markers


def true_radii(markers: np.ndarray) -> np.ndarray:
    return np.linalg.norm(markers[0] - CENTER, axis=-1)


def test_all_center_methods_registered():
    assert set(CENTER_METHODS) <= set(jointbench.methods("center"))


# --- noise-free recovery -------------------------------------------------------------------


@pytest.mark.parametrize("method", ["NM", "LS", "BC"])
@pytest.mark.parametrize("n_markers", [1, 3, 5])
def test_exact_methods_recover_noise_free_center_and_radii(method, n_markers):
    markers = well_conditioned(seed=n_markers, n_markers=n_markers)
    result = jointbench.fit_center(markers, method=method)
    assert result.converged and result.method == method
    np.testing.assert_allclose(result.center, CENTER, rtol=0, atol=1e-9)
    np.testing.assert_allclose(result.radii, true_radii(markers), rtol=0, atol=1e-9)


def test_bc_on_noise_free_data_stops_after_one_step():
    result = fit_bc(well_conditioned())
    assert result.converged and result.iterations == 1
    assert result.diagnostics["noise_variance"] < 1e-20


@pytest.mark.parametrize("offset", [(0.0, 0.0, 0.0), (4.0, -3.0, 2.0), (-15.0, 10.0, 8.0)])
def test_simplex_methods_recover_noise_free_center_from_a_distant_start(offset):
    """IS and MA to their simplex tolerance, also when started away from the answer."""
    markers = well_conditioned(seed=3)
    start = CENTER + np.array(offset)
    found_is = fit_is(markers, start=start)
    found_ma = fit_ma(markers, start=start)
    for result in (found_is, found_ma):
        assert result.converged, result.status
        np.testing.assert_allclose(result.center, CENTER, rtol=0, atol=1e-3)
    np.testing.assert_allclose(found_is.radii, true_radii(markers), rtol=0, atol=1e-3)
    assert found_ma.radii is None


def test_default_start_of_the_simplex_methods_is_the_ls_centre():
    markers = well_conditioned(seed=4)
    for method in ("IS", "MA"):
        result = jointbench.fit_center(markers, method=method)
        # Noise-free: LS is exact, so the search never finds a better vertex than its start.
        np.testing.assert_allclose(result.center, CENTER, rtol=0, atol=1e-9)


def test_ls_on_a_pure_hinge_returns_a_point_on_the_axis():
    """A pure hinge makes A singular; the pseudo-inverse picks a point on the axis."""
    rng = np.random.default_rng(11)
    axis = geometry.unit(np.array([0.3, -0.5, 0.8]))
    rotations = geometry.rotation_about_axis(axis, rng.uniform(-1.0, 1.0, 90))
    markers = moving_markers(rotations, rng.normal(scale=30.0, size=(3, 3)), CENTER)
    for method in ("LS", "BC"):
        center = jointbench.fit_center(markers, method=method).center
        off_axis = (center - CENTER) - axis * (axis @ (center - CENTER))
        assert np.linalg.norm(off_axis) < 1e-6


# --- invariances -----------------------------------------------------------------------------

rotation_vectors = st.tuples(*[st.floats(-3.0, 3.0) for _ in range(3)]).map(np.array)
translations = st.tuples(*[st.floats(-500.0, 500.0) for _ in range(3)]).map(np.array)


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    rotvec=rotation_vectors,
    shift=translations,
    method=st.sampled_from(EXACT),
)
def test_exact_methods_are_equivariant_under_rigid_motion_of_the_data(seed, rotvec, shift, method):
    markers = well_conditioned(seed=seed, noise_mm=1.0)
    rotation = geometry.rotation_matrix(rotvec)
    moved = markers @ rotation.T + shift
    before = jointbench.fit_center(markers, method=method)
    after = jointbench.fit_center(moved, method=method)
    scale = 1.0 + np.abs(moved).max()
    np.testing.assert_allclose(after.center, rotation @ before.center + shift, atol=1e-9 * scale)
    np.testing.assert_allclose(after.radii, before.radii, rtol=1e-9)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), method=st.sampled_from(EXACT), data=st.data())
def test_exact_methods_ignore_marker_and_frame_order(seed, method, data):
    markers = well_conditioned(seed=seed, noise_mm=1.0, n_markers=4)
    marker_order = np.array(data.draw(st.permutations(range(4))))
    frame_order = np.random.default_rng(seed).permutation(markers.shape[0])
    before = jointbench.fit_center(markers, method=method)
    after = jointbench.fit_center(markers[frame_order][:, marker_order], method=method)
    np.testing.assert_allclose(after.center, before.center, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(after.radii, before.radii[marker_order], rtol=1e-9)


@pytest.mark.parametrize(
    ("method", "atol"),
    # BC's stopping rule is on the max-norm of the step, which a rotation changes, so it may stop
    # one iteration earlier or later; IS builds its simplex from the start's coordinates, so a
    # new frame changes the search path. Both agree to their 1e-4 tolerances, checked at 1e-3.
    [("BC", 1e-3), ("IS", 1e-3)],
)
@pytest.mark.parametrize("seed", [0, 1])
def test_iterative_methods_are_equivariant_within_tolerance(method, atol, seed):
    markers = well_conditioned(seed=seed, noise_mm=0.5)
    rotation = geometry.rotation_matrix([0.3, -1.1, 0.7])
    shift = np.array([250.0, -40.0, 90.0])
    before = jointbench.fit_center(markers, method=method)
    after = jointbench.fit_center(markers @ rotation.T + shift, method=method)
    permuted = jointbench.fit_center(markers[:, ::-1], method=method)
    assert before.converged and after.converged and permuted.converged
    np.testing.assert_allclose(after.center, rotation @ before.center + shift, atol=atol)
    np.testing.assert_allclose(permuted.center, before.center, atol=atol)


def test_ma_is_equivariant_where_its_definition_allows():
    """The bounding-box amplitude is measured along the reference frame's axes, so MA is not
    rotation invariant on noisy data; noise-free, the minimum (zero amplitude at the centre) is.
    On noisy data the non-smooth amplitude makes the simplex stop where its path leads, and the
    path depends on the coordinates (5 % initial edges): a translation moves the answer with the
    data only to within ~0.2 mm. Marker order changes nothing."""
    clean = well_conditioned(seed=5)
    rotation = geometry.rotation_matrix([0.3, -1.1, 0.7])
    shift = np.array([250.0, -40.0, 90.0])
    start = CENTER + np.array([4.0, -3.0, 2.0])
    before = fit_ma(clean, start=start)
    after = fit_ma(clean @ rotation.T + shift, start=rotation @ start + shift)
    np.testing.assert_allclose(after.center, rotation @ before.center + shift, atol=1e-3)

    noisy = well_conditioned(seed=5, noise_mm=0.5)
    before = fit_ma(noisy)
    np.testing.assert_allclose(fit_ma(noisy + shift).center, before.center + shift, atol=0.5)
    np.testing.assert_allclose(fit_ma(noisy[:, ::-1]).center, before.center, atol=1e-9)


# --- agreement -------------------------------------------------------------------------------


def test_ls_system_matches_its_definition():
    """The vectorised normal equations against a literal transcription of the formulas."""
    markers = well_conditioned(seed=7, noise_mm=1.0, n_markers=4) + 1000.0
    a_matrix, b_vector = ls_system(markers)
    means = markers.mean(axis=0)
    sq = np.sum(markers**2, axis=-1)
    expected_a = 2.0 * sum(np.cov(markers[:, p].T, bias=True) for p in range(4))
    expected_b = sum(
        np.mean(sq[:, p, None] * markers[:, p], axis=0) - means[p] * sq[:, p].mean()
        for p in range(4)
    )
    np.testing.assert_allclose(a_matrix, expected_a, rtol=1e-10)
    np.testing.assert_allclose(b_vector, expected_b, rtol=1e-9)
    np.testing.assert_allclose(
        fit_ls(markers).center, solve_ls_system(a_matrix, b_vector), rtol=1e-10
    )


def test_bc_starts_from_the_ls_centre():
    markers = moving_markers(spiral_rotations(15.0), M_SET, CENTER)
    markers = markers + isotropic_noise(np.random.default_rng(5), markers.shape[:2], 1.0)
    start = fit_bc(markers, max_iterations=0)
    assert not start.converged and start.iterations == 0
    assert "maximum iterations (0)" in start.status
    np.testing.assert_array_equal(start.center, fit_ls(markers).center)


def test_bc_noise_variance_is_halvorsens_estimate_at_the_result():
    """BC evaluates its sums from per-marker moments; check them against the formula."""
    markers = moving_markers(spiral_rotations(15.0), M_SET, CENTER) + 500.0
    markers = markers + isotropic_noise(np.random.default_rng(8), markers.shape[:2], 1.0)
    result = fit_bc(markers)
    assert result.converged
    sq = np.sum((markers - result.center) ** 2, axis=-1)  # u_k^2, (N, P)
    mean_sq = sq.mean(axis=0)
    sigma2 = np.mean(np.sum((sq - mean_sq) ** 2, axis=0) / (4.0 * mean_sq * len(markers)))
    assert result.diagnostics["noise_variance"] == pytest.approx(sigma2, rel=1e-9)
    # At a converged point the update reproduces the centre (to the tolerance).
    a_matrix, b_vector = ls_system(markers)
    db = 2.0 * sigma2 * np.sum(markers.mean(axis=0) - result.center, axis=0)
    np.testing.assert_allclose(np.linalg.solve(a_matrix, b_vector - db), result.center, atol=1e-3)
    np.testing.assert_allclose(result.radii, np.sqrt(mean_sq), rtol=1e-9)


@pytest.mark.parametrize("seed", range(3))
def test_nm_ls_is_agree_on_low_noise_large_rom_data(seed):
    markers = well_conditioned(seed=seed, noise_mm=0.1)
    centers = {m: jointbench.fit_center(markers, method=m).center for m in ("NM", "LS", "IS")}
    for center in centers.values():
        np.testing.assert_allclose(center, CENTER, atol=0.1)
    np.testing.assert_allclose(centers["NM"], centers["LS"], atol=0.01)
    np.testing.assert_allclose(centers["IS"], centers["NM"], atol=0.05)


def test_bc_reduces_the_ls_bias_at_small_rom():
    """M set, 15° circumduction, 1 mm noise, 40 trials: LS is biased ~13 mm towards the markers
    (paper A eq. 5); BC must remove most of it. Fails if BC did not compensate."""
    clean = moving_markers(spiral_rotations(15.0), M_SET, CENTER)
    rng = np.random.default_rng(20070514)
    ls, bc = [], []
    for _ in range(40):
        markers = clean + isotropic_noise(rng, clean.shape[:2], 1.0)
        ls.append(fit_ls(markers).center - CENTER)
        result = fit_bc(markers)
        assert result.converged, result.status
        bc.append(result.center - CENTER)
    ls, bc = np.array(ls), np.array(bc)
    assert np.linalg.norm(ls.mean(axis=0)) > 5.0  # the bias exists in this setting
    assert np.linalg.norm(bc.mean(axis=0)) < 0.25 * np.linalg.norm(ls.mean(axis=0))
    assert np.linalg.norm(bc, axis=1).mean() < 0.5 * np.linalg.norm(ls, axis=1).mean()


def test_geometric_cost_is_f1_with_mean_radii():
    markers = well_conditioned(seed=2, noise_mm=1.0)
    point = CENTER + np.array([1.0, 2.0, -0.5])
    distance = np.linalg.norm(markers - point, axis=-1)
    expected = np.sum((distance - distance.mean(axis=0)) ** 2)
    assert geometric_cost(markers, point) == pytest.approx(expected, rel=1e-12)
    assert geometric_cost(well_conditioned(seed=2), CENTER) < 1e-20
    result = fit_is(markers)
    assert result.cost == pytest.approx(geometric_cost(markers, result.center), rel=1e-12)
    assert result.cost <= geometric_cost(markers, fit_ls(markers).center)
    assert result.iterations > 0 and result.diagnostics["function_evaluations"] > 0


def test_ma_reports_the_mean_trajectory_of_the_least_moving_point():
    markers = well_conditioned(seed=6, noise_mm=0.5)
    result = fit_ma(markers)
    rotation, translation, _ = rigid_poses(markers)
    point = np.asarray(result.diagnostics["body_point"])
    trajectory = np.einsum("kij,j->ki", rotation, point) + translation
    np.testing.assert_allclose(result.center, trajectory.mean(axis=0), atol=1e-9)
    assert result.cost == pytest.approx(amplitude(rotation, translation, point), rel=1e-12)
    start = fit_ls(markers).center  # frame 0 is the body frame
    assert result.cost <= amplitude(rotation, translation, start)


# --- non-convergence is reported, not raised -------------------------------------------------


def test_bc_reports_non_convergence_at_tiny_rom_and_large_noise():
    clean = moving_markers(spiral_rotations(5.0), M_SET, CENTER)
    rng = np.random.default_rng(1)
    results = [
        jointbench.fit_center(clean + isotropic_noise(rng, clean.shape[:2], 2.0), method="BC")
        for _ in range(6)
    ]
    failed = [r for r in results if not r.converged]
    assert failed, "expected BC to fail to converge at 5° RoM with 2 mm noise"
    for result in failed:
        assert result.status.startswith(("maximum iterations (600)", "diverged", "non-finite"))
        assert np.all(np.isfinite(result.center))
        if result.status.startswith("maximum"):
            assert result.iterations == 600


def test_bc_iteration_cap_is_an_option():
    markers = well_conditioned(seed=1, noise_mm=1.0)
    capped = fit_bc(markers, max_iterations=1, tol_x=0.0, tol_fun=0.0)
    assert not capped.converged and capped.iterations == 1
    assert capped.status == "maximum iterations (1) reached without convergence"


# --- bad input -------------------------------------------------------------------------------


def _good() -> np.ndarray:
    return well_conditioned(seed=9, noise_mm=0.2)


def _with(value: float) -> np.ndarray:
    markers = _good()
    markers[5, 1, 2] = value
    return markers


@pytest.mark.parametrize("method", CENTER_METHODS)
@pytest.mark.parametrize(
    ("markers", "match"),
    [
        (np.zeros((120, 3)), r"shaped \(n_frames, n_markers, 3\)"),
        (np.zeros((120, 3, 2)), r"shaped \(n_frames, n_markers, 3\)"),
        (_with(np.nan), "NaN or inf"),
        (_with(np.inf), "NaN or inf"),
        (_good()[:3], "3 frames"),
        (np.repeat(_good()[:1], 50, axis=0), "do not move"),
    ],
    ids=["2-d", "xy-only", "nan", "inf", "too-few-frames", "static"],
)
def test_bad_input_raises_value_error_naming_the_problem(method, markers, match):
    with pytest.raises(ValueError, match=match):
        jointbench.fit_center(markers, method=method)


def test_ma_needs_three_non_collinear_markers():
    rotations = random_rotations(np.random.default_rng(0), 60, 0.5)
    line = np.array([[10.0, 0.0, 0.0], [20.0, 0.0, 0.0], [35.0, 0.0, 0.0]])
    with pytest.raises(ValueError, match="collinear"):
        fit_ma(moving_markers(rotations, line, CENTER))
    with pytest.raises(ValueError, match="at least 3"):
        fit_ma(moving_markers(rotations, line[:2] + np.array([0.0, 5.0, 0.0]), CENTER))


@pytest.mark.parametrize("fit", [fit_is, fit_ma])
@pytest.mark.parametrize("start", [np.zeros(2), np.array([0.0, np.nan, 1.0])])
def test_bad_start_point_raises(fit, start):
    with pytest.raises(ValueError, match="start"):
        fit(_good(), start=start)


def test_unknown_method_lists_the_known_ones():
    with pytest.raises(ValueError, match=r"known: .*NM"):
        jointbench.fit_center(_good(), method="nope")


def test_results_are_frozen():
    result = fit_nm(_good())
    with pytest.raises(ValueError):
        result.center[0] = 1.0


def test_support_of_a_noise_free_pure_hinge_reports_zero_off_axis_rotation():
    """Rounding leaves the Gram matrix's zero eigenvalues slightly negative; the off-axis RMS
    must read (nearly) 0, not NaN from the square root of a negative."""
    from jointbench.estimators.support import assess

    rng = np.random.default_rng(11)
    axis = geometry.unit(np.array([0.3, -0.5, 0.8]))
    rotations = geometry.rotation_about_axis(axis, rng.uniform(-1.0, 1.0, 90))
    markers = moving_markers(rotations, rng.normal(scale=30.0, size=(3, 3)), CENTER)
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        support = assess("center", (markers,))
    assert support.diagnostics["off_axis_rotation_rms_deg"] == pytest.approx(0.0, abs=1e-5)
