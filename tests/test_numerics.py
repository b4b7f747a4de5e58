"""Shared numerics: the fminsearch simplex, its lockstep driver, the rank threshold and angles."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import minimize

from jointbench.geometry import angle_between_lines_deg
from jointbench.numerics import rank, simplex, small, special


def rosenbrock3(a: float, b: float, c: float) -> float:
    return (1 - a) ** 2 + 100 * (b - a * a) ** 2 + (c - 0.5) ** 2


@pytest.mark.parametrize("x0", [(-1.2, 1.0, 0.0), (0.5, 0.5, 0.5), (2.0, 0.0, 1.0)])
def test_nelder_mead_matches_scipy_fminsearch_port(x0):
    """Same coefficients, initial simplex and stopping rules as fminsearch (and SciPy's port)."""
    x, f, converged, iterations, evaluations = simplex.nelder_mead(rosenbrock3, x0)
    reference = minimize(
        lambda v: rosenbrock3(*v),
        x0,
        method="Nelder-Mead",
        options={"xatol": 1e-4, "fatol": 1e-4, "maxiter": 600, "maxfev": 600},
    )
    np.testing.assert_array_equal(x, reference.x)
    assert f == reference.fun
    assert (iterations, evaluations, converged) == (reference.nit, reference.nfev, True)


def test_initial_simplex_is_fminsearchs():
    """Each coordinate of the start in turn scaled by 1.05, or 0.00025 where it is zero."""
    asked = []

    def record(points, _owners):
        asked.append(points.tolist())
        return np.zeros(len(points))

    simplex.lockstep(record, [(12.0, 0.0, -4.0)])
    expected = [(12.0, 0.0, -4.0), (12.6, 0.0, -4.0), (12.0, 0.00025, -4.0), (12.0, 0.0, -4.2)]
    np.testing.assert_allclose(asked[0], expected, rtol=1e-15)
    assert dict(simplex.FMINSEARCH_OPTIONS) == {
        "xatol": 1e-4,
        "fatol": 1e-4,
        "max_iter": 600,
        "max_fev": 600,
    }


def test_nelder_mead_reports_the_iteration_limit():
    result = simplex.nelder_mead(rosenbrock3, (-1.2, 1.0, 0.0), max_iter=20)
    assert not result.converged
    assert result.iterations == 20
    assert simplex.stop_status(result, 600) == "Maximum number of iterations has been exceeded."


def test_nelder_mead_reports_the_evaluation_limit():
    result = simplex.nelder_mead(rosenbrock3, (-1.2, 1.0, 0.0), max_fev=30)
    assert not result.converged
    assert result.evaluations >= 30
    assert simplex.stop_status(result, 30).startswith("Maximum number of function evaluations")


@pytest.mark.parametrize("few", [True, False])
def test_lockstep_runs_equal_independent_runs(few):
    """Searches advanced together follow the paths they follow alone; owners say whose point."""
    centres = np.array([[1.0, -2.0], [0.3, 0.4], [-5.0, 2.5]])

    def batch(points, owners):
        return np.sum((points - centres[owners]) ** 2, axis=1) + owners

    starts = [(0.0, 1.0), (2.0, 2.0), (-1.0, 0.5)]
    starts = starts if few else starts * 20
    centres = np.tile(centres, (len(starts) // len(centres), 1))
    together = simplex.lockstep(batch, starts)
    for i, (x0, joint) in enumerate(zip(starts, together, strict=True)):
        alone = simplex.nelder_mead(
            lambda a, b, i=i: float(batch(np.array([[a, b]]), np.array([i]))[0]), x0
        )
        assert alone == joint


def test_negligible_is_relative_to_the_largest():
    values = np.array([1e-13, 1e-11, 1.0])
    np.testing.assert_array_equal(rank.negligible(values, 1.0), [True, False, False])
    assert rank.negligible(-1e-13, 1.0)
    assert rank.RCOND == 1e-12


@pytest.mark.parametrize("angle_rad", [1e-12, 1e-9, 1e-6, 0.3, np.pi / 2])
def test_angle_between_lines_resolves_small_angles(angle_rad):
    """The cosine of an angle below ~1e-8 rad rounds to 1: the angle must not come from it."""
    a = np.array([0.0, 0.0, 2.0])
    b = 3.0 * np.array([np.sin(angle_rad), 0.0, np.cos(angle_rad)])
    for sign in (1.0, -1.0):
        measured = np.radians(angle_between_lines_deg(a, sign * b))
        assert measured == pytest.approx(angle_rad, rel=1e-6, abs=0.0)


def test_small_matrix_helpers_match_numpy():
    rng = np.random.default_rng(3)
    matrices = rng.normal(size=(200, 3, 3))
    spd = matrices @ np.swapaxes(matrices, 1, 2) + np.eye(3)
    np.testing.assert_allclose(small.inverse3(spd), np.linalg.inv(spd), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(small.inverse3(matrices[0]), np.linalg.inv(matrices[0]), rtol=1e-10)
    q, _ = np.linalg.qr(matrices)
    expected = q @ spd[0] @ np.swapaxes(q, 1, 2)
    rotated = np.empty_like(expected)
    for frame, rotation in enumerate(q):
        small.rotated3_into(rotation, spd[0], rotated[frame])
    np.testing.assert_allclose(rotated, expected, rtol=1e-13, atol=1e-13)
    # A covariance stays a covariance: exactly symmetric, not to rounding.
    assert np.array_equal(rotated, np.swapaxes(rotated, 1, 2))
    assert not np.isfinite(small.inverse3(np.zeros((3, 3)))).any()


def test_the_small_solve_answers_as_lapack_and_says_when_singular():
    """``solve_into`` (partial pivoting) answers as ``np.linalg.solve`` and stops, as LAPACK
    reports it, at an exactly zero pivot."""
    rng = np.random.default_rng(4)
    for k in (3, 9):
        matrix = rng.normal(size=(k, k))
        vector = rng.normal(size=k)
        for solve in (small.solve_into, small.solve_into.__wrapped__):
            solution = np.empty(k)
            assert solve(matrix.copy(), vector, solution)
            np.testing.assert_allclose(solution, np.linalg.solve(matrix, vector), rtol=1e-10)
            singular = matrix.copy()
            singular[:, 1] = 0.0
            assert not solve(singular, vector, solution)


def test_f_survival_is_scipys_fdtrc_on_every_kind_of_number():
    """The scalar F survival the checks read is the ufunc's number, bit for bit, on integers
    (degrees of freedom are counts), NumPy scalars, zero, infinite and NaN ratios."""
    fdtrc = special.scipy_special().fdtrc
    numbers = [0, 1, 3, 2.5, np.int64(7), np.float64(0.75), 1e6, np.inf, np.nan]
    for dfn in numbers[1:]:
        for dfd in numbers[1:]:
            for ratio in numbers:
                found = special.f_survival(dfn, dfd, ratio)
                assert type(found) is float
                np.testing.assert_array_equal(found, float(fdtrc(dfn, dfd, ratio)))
