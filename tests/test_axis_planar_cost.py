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


@pytest.mark.parametrize("seed", range(5))
def test_planar_costs_are_the_einsum_sums_to_the_last_bit(seed):
    rng = np.random.default_rng(seed)
    markers = _hinge_markers(rng, 4) * rng.uniform(0.1, 100.0)
    costs = axis.AxisCosts(markers, rng.normal(size=(4, 3)))
    # Unit directions, near-eigenvectors of S (the planar minima) and unnormalised ones.
    eigenvectors = np.linalg.eigh(costs.scatter)[1][:, :, 0]
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
