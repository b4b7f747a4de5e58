"""The planar cost ``n' S n`` (paper B eq. 8) of :class:`jointbench.estimators.axis.AxisCosts`
and its scatter ``S``, summed term by term as ``np.einsum`` sums them, and the search's
directions from angles: the fits, their self-checks and the checked calls reach the same
answers to the last bit whichever form computes them."""

from __future__ import annotations

import numpy as np
import pytest
from test_compiled import _hinge_markers

from jointbench.estimators import axis
from jointbench.geometry import unit
from jointbench.numerics.simplex import lockstep


def _einsum_costs(costs: axis.AxisCosts, directions: np.ndarray, trials: np.ndarray):
    return np.einsum("ki,kij,kj->k", directions, costs.scatter[trials], directions)


@pytest.mark.parametrize("seed", range(5))
def test_the_scatter_is_the_einsum_sum_to_the_last_bit(seed):
    rng = np.random.default_rng(seed)
    n_frames, n_markers = int(rng.integers(4, 6000)), int(rng.integers(1, 6))
    markers = rng.normal(scale=100.0, size=(3, n_frames, n_markers, 3)) + rng.normal(
        scale=1000.0, size=3
    )
    costs = axis.AxisCosts(markers, np.zeros((3, 3)))
    for trial, data in enumerate(markers):
        centred = data - data.mean(axis=0)
        expected = np.einsum("kpi,kpj->ij", centred, centred)
        np.testing.assert_array_equal(costs.scatter[trial], expected)


def test_directions_from_angles_are_the_stacked_formula():
    params = np.random.default_rng(8).uniform(-4.0, 4.0, size=(1000, 2))
    azimuth, elevation = params[:, 0], params[:, 1]
    c = np.cos(elevation)
    expected = np.stack((c * np.cos(azimuth), c * np.sin(azimuth), np.sin(elevation)), axis=1)
    np.testing.assert_array_equal(axis.angles_to_directions(params), expected)


def _hinges_costs(rng: np.random.Generator, n_trials: int):
    """The costs of ``n_trials`` hinges at a random scale, and each trial's planar minimum."""
    markers = _hinge_markers(rng, n_trials) * rng.uniform(0.1, 100.0)
    costs = axis.AxisCosts(markers, rng.normal(size=(n_trials, 3)))
    return costs, np.linalg.eigh(costs.scatter)[1][:, :, 0]


@pytest.mark.parametrize("seed", range(5))
def test_planar_costs_are_the_einsum_sums_to_the_last_bit(seed):
    rng = np.random.default_rng(seed)
    costs, eigenvectors = _hinges_costs(rng, 4)
    # Unit directions, near-eigenvectors of S (the planar minima) and unnormalised ones.
    directions = np.concatenate(
        [
            unit(rng.normal(size=(200, 3))),
            unit(eigenvectors + rng.normal(scale=1e-9, size=(4, 3))),
            rng.normal(scale=5.0, size=(50, 3)),
        ]
    )
    trials = rng.integers(-4, 4, len(directions))
    expected = _einsum_costs(costs, directions, trials)
    np.testing.assert_array_equal(costs.planar(directions, trials), expected)
    search = costs.search_cost("planar", "vector")
    norm = np.linalg.norm(directions, axis=1)[:, None]
    np.testing.assert_array_equal(
        search(directions, trials), _einsum_costs(costs, directions / norm, trials)
    )
    combined = costs.search_cost("combined", "vector")(directions, trials)
    np.testing.assert_array_equal(
        combined,
        _einsum_costs(costs, directions / norm, trials) + costs.radial(directions / norm, trials),
    )


def test_planar_costs_refuse_trials_they_do_not_hold():
    rng = np.random.default_rng(7)
    costs = axis.AxisCosts(_hinge_markers(rng, 3)[:, :40], rng.normal(size=(3, 3)))
    directions = unit(rng.normal(size=(3, 3)))
    with pytest.raises(ValueError, match="one per direction"):
        costs.planar(directions, np.array([0, 1]))
    with pytest.raises(ValueError, match=r"trial 3 .*3 trials"):
        costs.planar(directions, np.array([0, 1, 3]))


@pytest.mark.parametrize("cost", ["planar", "radial", "combined"])
def test_the_costs_refuse_trials_that_are_not_indices(cost):
    """A fractional trial would otherwise be truncated to a trial it does not name."""
    rng = np.random.default_rng(8)
    costs = axis.AxisCosts(_hinge_markers(rng, 3)[:, :40], rng.normal(size=(3, 3)))
    directions = unit(rng.normal(size=(3, 3)))
    with pytest.raises(ValueError, match="integer indices"):
        getattr(costs, cost)(directions, np.array([0.9, 1.0, 2.0]))


@pytest.mark.parametrize("seed", range(4))
def test_the_compiled_planar_restarts_take_the_paths_the_search_cost_gives(seed):
    costs, eigenvectors = _hinges_costs(np.random.default_rng(seed), 5)
    # Eigenvectors (the self-check's starts), a direction anywhere, and a pole.
    starts = np.array(
        [axis.direction_to_angles(v) for v in eigenvectors[:3]]
        + [axis.direction_to_angles(unit(np.random.default_rng(seed).normal(size=3)))]
        + [(0.0, np.pi / 2)]
    )
    for limits in (
        {},
        {"xatol": 0.0, "fatol": 0.0},
        {"max_iter": 3},
        {"max_fev": 5, "xatol": 1e-2},
    ):
        expected = lockstep(costs.search_cost("planar", "angles"), starts, **limits)
        assert repr(axis._planar_restarts(costs.scatter, starts, **limits)) == repr(expected)


def test_the_compiled_directions_are_those_from_angles_to_the_last_bit():
    # The restarts' sines and cosines are the C library's: NumPy's must be the same.
    params = np.random.default_rng(9).uniform(-4.0, 4.0, size=(20000, 2))
    params[:5] = [(0.0, 0.0), (np.pi, -np.pi / 2), (1e-300, 1e-300), (-0.0, 4.0), (3.0, -0.0)]
    expected = axis.angles_to_directions(params)
    direction = np.empty(3)
    for (azimuth, elevation), row in zip(params.tolist(), expected, strict=True):
        axis.direction_into(azimuth, elevation, direction)
        np.testing.assert_array_equal(direction, row)
