"""What the axis methods' checked calls rely on to cost less than their fit: the shortcuts in
their self-check and statement of precision give the numbers the longer computations gave."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_axis_sd import hinge

from jointbench.estimators import axis, precision, registry
from jointbench.geometry import angle_between_lines_deg, rotation_about_axis
from jointbench.numerics.compiled import kernel_array


@pytest.mark.parametrize("shape", [(1, 500, 3, 3), (3, 121, 4, 3), (2, 5, 1, 3)])
@pytest.mark.parametrize("offset_mm", [0.0, 1e4])
def test_the_scatter_kernel_is_numpys_mean_and_einsum_to_the_last_bit(shape, offset_mm):
    markers = np.random.default_rng(len(shape) + shape[1]).normal(scale=30.0, size=shape)
    markers += offset_mm
    expected = [
        np.einsum("kpi,kpj->ij", trial - trial.mean(axis=0), trial - trial.mean(axis=0))
        for trial in markers
    ]
    np.testing.assert_array_equal(axis._scatters(kernel_array(markers)), np.stack(expected))


@pytest.mark.parametrize("seed", range(3))
def test_the_planar_sd_does_not_depend_on_the_point_of_the_axis(seed):
    # So the planar statement needs no foot on the axis (the radial one does).
    markers = hinge(seed, 30.0, noise=1.0)
    result = registry.get("axis", "planar", checked=False)(markers)
    direction = np.asarray(result.direction)
    sds = [
        axis._direction_sd_deg(markers, np.asarray(point), direction, "planar")
        for point in (result.point, np.zeros(3), np.array([1e3, -2e3, 5e2]))
    ]
    assert sds[0] == sds[1] == sds[2]


def _numpy_basis(direction: np.ndarray) -> np.ndarray:
    """The tangent basis as :func:`np.cross` gives it, normalised by the root of its squares
    summed in order: ``np.linalg.norm`` sums them in the order of the processor's BLAS kernel,
    which differs between processors in the last bit."""
    helper = np.zeros(3)
    helper[np.argmin(np.abs(direction))] = 1.0
    first = np.cross(direction, helper)
    first /= math.sqrt(first[0] * first[0] + first[1] * first[1] + first[2] * first[2])
    return np.stack([first, np.cross(direction, first)], axis=1)


def test_the_tangent_basis_is_the_one_numpys_cross_product_gives_to_the_last_bit():
    directions = np.random.default_rng(5).normal(size=(500, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    for direction in [*directions, np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0])]:
        np.testing.assert_array_equal(precision.tangent_basis(direction), _numpy_basis(direction))


def test_lines_told_within_the_ambiguity_angle_without_measuring_it_are_within_it():
    rng = np.random.default_rng(11)
    base = rng.normal(size=(2000, 3))
    side = np.cross(base, rng.normal(size=(2000, 3)))
    angles = np.radians(rng.uniform(28.0, 32.0, 2000))
    told = 0
    for a, s, angle, length in zip(base, side, angles, rng.uniform(-8, 8, 2000), strict=True):
        a, s = a / np.linalg.norm(a), s / np.linalg.norm(s)
        b = (math.cos(angle) * a + math.sin(angle) * s) * 10.0**length
        if axis._surely_within(a, b, axis._APART_COSINE):
            told += 1
            assert not angle_between_lines_deg(a, b) > precision.AMBIGUOUS_APART_DEG
    assert told > 500  # the angles below 29.5 degrees
    for unknown in (np.zeros(3), np.full(3, np.nan), np.full(3, 1e300)):
        assert not axis._surely_within(unknown, np.array([0.0, 0.0, 1.0]), axis._APART_COSINE)


def test_a_checked_fit_whose_two_minima_agree_does_not_measure_their_angle(monkeypatch):
    measured = []

    def counting(a, b):
        measured.append(1)
        return angle_between_lines_deg(a, b)

    monkeypatch.setattr(axis, "angle_between_lines_deg", counting)
    result = registry.get("axis", "planar")(hinge(0, 30.0, noise=1.0))
    assert "other_minimum" not in result.diagnostics
    assert result.diagnostics["self_check"].startswith("a restart from the planar-cost")
    assert measured == []


def test_the_planar_cost_states_its_other_minimum_where_its_ten_starts_are_cut_short():
    # Its cost has one minimum, but its search need not reach it: the ambiguity check is kept.
    # 37 degrees from the nearest of the ten starts, where a search cut short ends.
    axis_direction = np.array([-0.8, 0.5, 0.0])
    axis_direction /= np.linalg.norm(axis_direction)
    turn = np.cross([0.0, 0.0, 1.0], axis_direction)
    rotation = rotation_about_axis(
        turn / np.linalg.norm(turn), math.asin(float(np.linalg.norm(turn)))
    )
    markers = hinge(0, 30.0) @ rotation.T
    # One iteration, the fewest the option takes, cuts every start's search short.
    result = registry.get("axis", "planar")(markers, max_iter=1)
    other = result.diagnostics["other_minimum"]
    assert result.status.startswith("restarted: ")
    assert other["angle_deg"] > precision.AMBIGUOUS_APART_DEG
    assert float(angle_between_lines_deg(np.asarray(result.direction), axis_direction)) < 1.0


def _distinct_as_np_unique(markers: np.ndarray) -> np.ndarray:
    """distinct_frames by np.unique of the whole frames: ``markers`` itself when they are all
    distinct."""
    flat = markers.reshape(len(markers), -1)
    distinct = np.unique(flat, axis=0)
    if len(distinct) == len(markers):
        return markers
    return distinct.reshape(len(distinct), *markers.shape[1:])


def _overflowing(n_frames: int) -> np.ndarray:
    """Frames whose sums of coordinates overflow (inf - inf), all distinct."""
    frames = np.zeros((n_frames, 3, 3))
    frames[:, 0, 0] = 1.7e308
    frames[:, 0, 1] = -1.7e308
    frames[:, 2, 2] = np.arange(n_frames)
    return frames


def _colliding() -> np.ndarray:
    """Two distinct frames whose weighted sums with the square roots of 2, 3, ... are equal
    (the keys by which frames were once told apart), and a third."""
    for scale in np.linspace(1.0, 2.0, 1000):
        a, b = math.sqrt(3.0) * scale, math.sqrt(2.0) * scale
        if a * math.sqrt(2.0) == b * math.sqrt(3.0) and a != b:
            frames = np.zeros((3, 1, 3))
            frames[0, 0, 0], frames[1, 0, 1], frames[2, 0, 2] = a, b, 1.0
            return frames
    raise AssertionError("no colliding frames found")


@pytest.mark.parametrize(
    "markers",
    [
        hinge(0, 30.0),
        np.concatenate([hinge(1, 30.0)[:7]] * 3),
        np.concatenate([hinge(2, 30.0), hinge(2, 30.0)[[5]]]),
        hinge(3, 30.0)[:1],
        _overflowing(1),
        _overflowing(2),
        _overflowing(5),
        _colliding(),
        np.stack([np.zeros((2, 3)), np.full((2, 3), -0.0), np.ones((2, 3))]),
    ],
    ids=[
        "distinct",
        "repeated",
        "one-repeat",
        "one-frame",
        "one-overflow",
        "two-overflows",
        "five-overflows",
        "colliding-sums",
        "signed-zeros",
    ],
)
def test_the_distinct_frames_are_those_np_unique_tells(markers):
    distinct = precision.distinct_frames(markers)
    expected = _distinct_as_np_unique(markers)
    np.testing.assert_array_equal(distinct, expected)
    assert (distinct is markers) == (expected is markers)


@pytest.mark.parametrize("method", ["planar", "radial", "combined"])
def test_a_checked_fit_passes_over_its_samples_for_each_sum_once(monkeypatch, method):
    # The point's covariance reads neither cost's fourth powers, and its height and the
    # combined cost's foot are read from one centroid.
    passes = {"_height_fourths": 0, "_sample_centroid": 0}

    def counting(name):
        compiled = getattr(axis, name)

        def counted(*args):
            passes[name] += 1
            return compiled(*args)

        return counted

    for name in passes:
        monkeypatch.setattr(axis, name, counting(name))
    registry.get("axis", method)(hinge(0, 30.0, noise=1.0))
    # Once each: the planar residuals' for the answer's own statement (the radial answer's
    # being checked against the planar eigenvector's), the centroid for the radial costs.
    assert passes == {"_height_fourths": 1, "_sample_centroid": 1}
