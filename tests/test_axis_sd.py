"""The axis methods' statement of how precisely their own cost determines the direction
(:mod:`jointbench.estimators.precision`): its calibration on pure hinges, the cases whose cost
leaves the axis undetermined, and its invariances."""

from __future__ import annotations

import math

import numpy as np
import pytest

import jointbench
from jointbench.estimators import axis, precision, registry
from jointbench.geometry import angle_between_lines_deg, rotation_about_axis

CENTRE = np.array([20.0, -25.0, -30.0])
LOCAL = np.array([[40.0, 10, 5], [10, 50, -10], [-5, 15, 60], [30, -20, 40]])
Z = np.array([0.0, 0.0, 1.0])
LEAST_SQUARES = ("planar", "radial", "combined")


def hinge(seed: int, arc_deg: float, *, noise=0.3, n_frames=120, n_markers=4) -> np.ndarray:
    """Markers ``(n_frames, n_markers, 3)`` [mm] of a pure hinge about z through CENTRE, the
    angle running linearly over ``arc_deg``, with isotropic noise ``noise`` [mm]."""
    angles = np.radians(np.linspace(0.0, arc_deg, n_frames))
    rotations = rotation_about_axis(Z, angles)
    markers = CENTRE + np.einsum("fij,mj->fmi", rotations, LOCAL[:n_markers])
    return markers + np.random.default_rng(seed).normal(scale=noise, size=markers.shape)


def ok_but_for_the_point(status: str) -> bool:
    """Whether ``status`` passes the answer's direction: ``"ok"``, or warnings only that its
    point is not determined across the axis (``tests/test_axis_point_sd.py``), which a short
    arc's well determined direction can carry."""
    said = status.removeprefix("warning: ").split("; warning: ")
    return status == "ok" or (
        status.startswith("warning: ") and all(w.startswith("point not determined: ") for w in said)
    )


def checked(method: str, markers: np.ndarray):
    return registry.get("axis", method)(markers)


def error_deg(result) -> float:
    return float(angle_between_lines_deg(np.asarray(result.direction), Z))


@pytest.mark.parametrize(
    ("arc_deg", "seed"), [(2.0, 0), (2.0, 1), (5.0, 0)], ids=["2deg-s0", "2deg-s1", "5deg-s0"]
)
def test_a_small_arc_whose_radial_answer_is_tens_of_degrees_off_is_warned_about(arc_deg, seed):
    result = jointbench.fit_axis(hinge(seed, arc_deg), method="radial")
    assert error_deg(result) > 10.0  # the case: the radial answer is far off
    assert result.diagnostics["axis_sd_deg"] > precision.MAX_AXIS_SD_DEG
    assert "warning: axis not determined by the radial cost" in result.status
    assert result.converged  # left as the method set it


def test_five_frames_repeated_do_not_count_as_120_and_the_radial_answer_is_warned_about():
    markers = np.concatenate([hinge(1, 60.0)[:5]] * 24)
    result = jointbench.fit_axis(markers, method="radial")
    assert error_deg(result) > 80.0
    assert result.diagnostics["axis_sd_deg"] > precision.MAX_AXIS_SD_DEG
    assert "axis not determined by the radial cost: " in result.status
    # The distinct frames alone give the same statement.
    alone = axis._direction_sd_deg(markers[:5], result.point, result.direction, "radial")
    assert result.diagnostics["axis_sd_deg"] == pytest.approx(alone, rel=1e-9)


@pytest.mark.parametrize("method", jointbench.methods("axis"))
def test_a_thirty_degree_hinge_with_1mm_noise_is_not_warned_about(method):
    result = jointbench.fit_axis(hinge(0, 30.0, noise=1.0), method=method)
    assert result.status == "ok"
    assert 0.0 < result.diagnostics["axis_sd_deg"] < 5.0


@pytest.mark.parametrize("method", jointbench.methods("axis"))
def test_noise_free_data_give_an_sd_of_about_zero(method):
    with np.errstate(all="raise"):
        result = checked(method, hinge(0, 60.0, noise=0.0))
    assert result.status == "ok"
    # Rounding, and for SARA the pose fit's own: the SD of 0.3 mm noise is 0.1-1 degree.
    assert 0.0 <= result.diagnostics["axis_sd_deg"] < 1e-4


def test_the_warning_states_the_sd_and_the_limit():
    result = precision.annotate(checked("planar", hinge(0, 60.0)), 31.4, "the radial cost")
    assert result.status == (
        "warning: axis not determined by the radial cost: its direction's SD is 31.4 deg "
        "(above 10 deg)"
    )
    # One decimal: three significant digits would print 10.04 as "10", above 10.
    just_above = precision.annotate(checked("planar", hinge(0, 60.0)), 10.4, "the planar cost")
    assert "its direction's SD is 10.4 deg (above 10 deg)" in just_above.status
    unbounded = precision.annotate(checked("planar", hinge(0, 60.0)), math.inf, "the radial cost")
    assert "SD is unbounded (above 10 deg)" in unbounded.status


def test_an_sd_beyond_what_a_direction_can_be_off_is_stated_as_no_number():
    """An SD above 90 deg (the furthest one line's direction can be from another's) is no
    precision: the warning says the axis is not determined without printing it as a number,
    and :func:`precision.stated_axis_sd` gives none, as above the 10 deg bound."""
    fitted = checked("planar", hinge(0, 60.0))
    result = precision.annotate(fitted, 299.7, "the radial cost")
    assert result.status == (
        "warning: axis not determined by the radial cost: its direction's SD is over 90 deg, "
        "more than a direction can be off (above 10 deg)"
    )
    assert result.diagnostics["axis_sd_deg"] == 299.7
    assert precision.stated_axis_sd(299.7) is None
    assert precision.stated_axis_sd(31.4) is None
    assert precision.stated_axis_sd(math.inf) is None
    assert precision.stated_axis_sd(math.nan) is None
    assert precision.stated_axis_sd(4.2) == 4.2
    assert precision.stated_axis_sd(precision.MAX_AXIS_SD_DEG) == precision.MAX_AXIS_SD_DEG


def _numerical_hessian(markers, foot, direction, basis, step=1e-4):
    """The radial cost's Hessian in (tangent angles, shift) by central differences of
    :class:`axis.AxisCosts` (on a long arc, where such a step exists)."""

    def cost(params):
        n = direction + basis @ params[:2]
        return float(
            axis.AxisCosts(markers, foot + basis @ params[2:]).radial(n / np.linalg.norm(n))
        )

    unit = np.eye(4) * step
    return np.array(
        [
            [
                (
                    cost(unit[i] + unit[j])
                    - cost(unit[i] - unit[j])
                    - cost(unit[j] - unit[i])
                    + cost(-unit[i] - unit[j])
                )
                / (4 * step**2)
                for j in range(4)
            ]
            for i in range(4)
        ]
    )


def _numerical_residual_jacobian(markers, foot, direction, basis, step=1e-6):
    """The Jacobian ``(N P, 4)`` of the radial residuals (each sample's distance from the axis
    less its marker's mean) in (tangent angles, shift), by central differences."""

    def residuals(params):
        n = direction + basis @ params[:2]
        n = n / np.linalg.norm(n)
        offsets = markers - (foot + basis @ params[2:])
        distances = np.linalg.norm(offsets - (offsets @ n)[..., None] * n, axis=-1)
        return (distances - distances.mean(axis=0)).ravel()

    unit = np.eye(4) * step
    return np.stack([(residuals(e) - residuals(-e)) / (2 * step) for e in unit], axis=1)


def test_the_analytic_hessians_match_the_costs_central_differences():
    markers = hinge(0, 60.0)
    direction = np.array([0.05, -0.03, 1.0]) / np.linalg.norm([0.05, -0.03, 1.0])
    foot = CENTRE + np.array([0.4, -0.2, 20.0])
    basis = precision.tangent_basis(direction)
    derivatives = axis._radial_derivatives(markers, foot, direction, basis)
    gradient, hessian, cost, _, gauss_newton, _ = derivatives
    assert cost == pytest.approx(float(axis.AxisCosts(markers, foot).radial(direction)), rel=1e-12)
    expected = _numerical_hessian(markers, foot, direction, basis)
    assert np.abs(hessian - expected).max() < 1e-5 * np.abs(hessian).max()
    jacobian = _numerical_residual_jacobian(markers, foot, direction, basis)
    assert np.abs(gauss_newton - 2.0 * jacobian.T @ jacobian).max() < 1e-6 * np.abs(hessian).max()
    scatter = axis.AxisCosts(markers, foot).scatter[0]
    planar = axis._planar_hessian(scatter, direction, basis)
    step = 1e-4

    def planar_cost(a):
        n = direction + basis @ a
        return float(n @ scatter @ n / (n @ n))

    e1, e2 = np.eye(2) * step
    second = (planar_cost(e1) - 2 * planar_cost(0 * e1) + planar_cost(-e1)) / step**2
    mixed = (planar_cost(e1 + e2) - planar_cost(e1 - e2) - planar_cost(e2 - e1)) / (4 * step**2)
    mixed += planar_cost(-e1 - e2) / (4 * step**2)
    assert planar[0, 0] == pytest.approx(second, rel=1e-5)
    assert planar[0, 1] == pytest.approx(mixed, rel=1e-4, abs=1e-6 * abs(planar).max())
    assert np.linalg.norm(gradient) > 0  # off the minimum: the step is not zero


@pytest.mark.parametrize("method", ["planar", "radial", "combined"])
def test_the_noise_term_stated_is_the_mean_of_the_residuals_term_over_noise_draws(method):
    """The residuals' own term ``N = G - H`` of each cost at the true axis, averaged over noise
    draws, is the expected value the cost states under unit noise times the noise's variance
    (:func:`jointbench.estimators.axis._radial_derivatives` derives the radial one), within 4
    standard errors in every element (10 of them: a chance of 6e-4 of one beyond)."""
    clean = hinge(3, 20.0, noise=0.0, n_frames=50)
    axis_direction = np.array([0.0, 0.0, 1.0])
    rng = np.random.default_rng(11)
    noise = 1.0
    terms = []
    for _ in range(400):
        markers = clean + rng.normal(scale=noise, size=clean.shape)
        at = axis._cost_at(markers, CENTRE, axis_direction, method, fourths=False)
        terms.append(at.gauss_newton - at.hessian)
    terms = np.array(terms)
    mean, se = terms.mean(axis=0), terms.std(axis=0) / math.sqrt(len(terms))
    stated = noise**2 * axis._cost_at(clean, CENTRE, axis_direction, method).unit_noise_term
    assert np.all(np.abs(mean - stated) <= 4.0 * se + 1e-9 * np.abs(stated).max())
    assert np.abs(stated).max() > 10.0 * se.max()  # a term the draws resolve, not zero


def test_the_planar_costs_noise_share_is_its_eigen_problems_with_the_noise_stated():
    """:func:`jointbench.estimators.precision.noise_share` of the planar cost at its eigenvector
    is ``s^2 P (N - 1) / (lambda_1 - s^2 P (N - 1))``: the planar eigen-problem's share with the
    answer's eigenvalue read as the stated noise's, against the smaller gap it leaves."""
    markers = hinge(4, 10.0, noise=1.0)
    values, vectors = np.linalg.eigh(axis.trial_scatter(markers))
    at = axis._cost_at(markers, np.zeros(3), vectors[:, 0], "planar", fourths=False)
    n_frames, n_markers = markers.shape[:2]
    for noise_variance in (0.5, 1.0):
        noise_eigenvalue = noise_variance * n_markers * (n_frames - 1)
        expected = noise_eigenvalue / (values[1] - noise_eigenvalue)
        assert precision.noise_share(at, noise_variance) == pytest.approx(expected, rel=1e-9)
    assert precision.noise_share(at, 0.0) == 0.0
    assert math.isnan(precision.noise_share(at, math.nan))  # no noise stated: not read
    beyond = 1.01 * values[1] / (n_markers * (n_frames - 1))  # the noise takes all of the gap
    assert precision.noise_share(at, beyond) == math.inf


@pytest.mark.parametrize("method", LEAST_SQUARES)
def test_the_sd_moves_with_a_rigid_transform_and_ignores_marker_and_frame_order(method):
    markers = hinge(2, 30.0, noise=0.5)
    result = checked(method, markers)
    sd = result.diagnostics["axis_sd_deg"]
    rotation = rotation_about_axis(np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1, 2, -0.5]), 1.1)
    moved = markers @ rotation.T + np.array([300.0, -150.0, 80.0])
    order = np.random.default_rng(4).permutation(len(markers) - 1) + 1
    for changed in (moved, markers[:, ::-1], markers[np.r_[0, order]]):
        other = checked(method, changed)
        # The answers agree to the search's tolerance (1e-4 rad), and so do their SDs.
        assert other.diagnostics["axis_sd_deg"] == pytest.approx(sd, rel=2e-2)
    # At the same answer the statement is the same to rounding.
    point, direction = np.asarray(result.point), np.asarray(result.direction)
    same = axis._direction_sd_deg(
        moved, rotation @ point + [300.0, -150.0, 80.0], rotation @ direction, method
    )
    assert same == pytest.approx(sd, rel=1e-6)
    shuffled = axis._direction_sd_deg(markers[np.r_[0, order]][:, ::-1], point, direction, method)
    assert shuffled == pytest.approx(sd, rel=1e-9)


def test_saras_sd_moves_with_a_rigid_transform_and_ignores_marker_and_frame_order():
    markers = hinge(2, 30.0, noise=0.5)
    sd = checked("SARA", markers).diagnostics["axis_sd_deg"]
    rotation = rotation_about_axis(np.array([0.3, -1.0, 2.0]) / np.linalg.norm([0.3, -1, 2]), 2.0)
    order = np.random.default_rng(5).permutation(len(markers) - 1) + 1
    moved = markers @ rotation.T + np.array([-40.0, 900.0, 12.0])
    for changed in (moved, markers[:, ::-1], markers[np.r_[0, order]]):
        assert checked("SARA", changed).diagnostics["axis_sd_deg"] == pytest.approx(sd, rel=1e-6)


# Noise-limited pure hinges: (arc [deg], noise [mm], markers, frames).
CALIBRATION = [
    (5.0, 0.3, 4, 120),
    (20.0, 1.0, 4, 120),
    (30.0, 0.3, 4, 120),
    (60.0, 1.0, 3, 20),
    (45.0, 1.0, 4, 60),
    (60.0, 0.3, 4, 200),
]
# Over 40 seeds the RMS reported SD over the RMS error measured 0.96-1.23 for planar and
# combined and 0.89-1.27 for SARA on these; the test allows a factor 1.5 either way. Below
# them the errors outgrow the linearisation: on a 2 degree arc (0.3 mm, 4 x 120) the ratio is
# 0.73 (planar), 0.85 (combined), 0.57 (SARA); on 10 degrees with 1 mm and 3 x 200, 0.88,
# 0.69, 0.42.
FACTOR = 1.5


def _ratio(method: str, case: tuple, **options) -> float:
    """RMS reported SD over RMS angular error of ``method`` on 40 seeds of ``case``."""
    arc_deg, noise, n_markers, n_frames = case
    fit = registry.many("axis", method)
    trials = np.stack(
        [
            hinge(seed, arc_deg, noise=noise, n_frames=n_frames, n_markers=n_markers)
            for seed in range(40)
        ]
    )
    results = fit(trials, **options)
    errors = [error_deg(result) for result in results]
    sds = [result.diagnostics["axis_sd_deg"] for result in results]
    return math.sqrt(np.mean(np.square(sds)) / np.mean(np.square(errors)))


@pytest.mark.parametrize("method", ["planar", "combined", "SARA"])
@pytest.mark.parametrize(
    "case", CALIBRATION, ids=[f"{c[0]:g}deg-{c[1]:g}mm-{c[2]}x{c[3]}" for c in CALIBRATION]
)
def test_the_sd_agrees_with_the_rms_error_over_seeds(method, case):
    assert 1 / FACTOR < _ratio(method, case) < FACTOR


# Radial with 3 markers x 20 frames leaves the axis and its position unbounded in a few seeds.
RADIAL_CALIBRATION = [case for case in CALIBRATION[1:] if case[3] > 20]


@pytest.mark.parametrize(
    "case",
    RADIAL_CALIBRATION,
    ids=[f"{c[0]:g}deg-{c[1]:g}mm-{c[2]}x{c[3]}" for c in RADIAL_CALIBRATION],
)
def test_the_radial_sd_is_conservative_by_at_most_a_stated_factor(case):
    """The radial SD leaves the axis's position free; with the point held at the true centre
    the answer can be better than that on long arcs: the ratio measured 0.89 (20 degrees,
    1 mm) to 1.92 (30 degrees, 0.3 mm), and a factor 1/1.5-2.5 is allowed. With the default
    point (the NM centre) a third of such trials can end at another minimum 80-90 degrees off,
    as sharp as the true one: no statement of the cost's curvature sees that (module notes of
    :mod:`jointbench.estimators.precision`)."""
    assert 1 / FACTOR < _ratio("radial", case, point=CENTRE) < 2.5


def test_the_many_trial_form_gives_each_trial_its_outcome_alone():
    repeated = np.concatenate([hinge(1, 60.0)[:5]] * 24)
    trials = np.stack([hinge(0, 2.0), hinge(1, 30.0, noise=1.0), hinge(3, 5.0), repeated])
    for method in jointbench.methods("axis"):
        together = registry.many("axis", method)(trials)
        for trial, outcome in zip(trials, together, strict=True):
            alone = checked(method, trial)
            assert outcome.status == alone.status
            assert outcome.diagnostics["axis_sd_deg"] == pytest.approx(
                alone.diagnostics["axis_sd_deg"], rel=1e-9
            )


def test_the_simulated_studies_bare_functions_carry_no_sd():
    result = registry.get("axis", "radial", checked=False)(hinge(0, 2.0))
    assert "axis_sd_deg" not in result.diagnostics
    assert "axis_point_sd_mm" not in result.diagnostics
    assert result.status == "ok"
