"""One registry type, and every method's one-trial and many-trial forms, checked or not.

A method states its own many-trial form when it registers (``register(..., many=...)`` or
``register_many``); every other method, a newcomer's per-trial function included, is given one
that calls its one-trial function trial by trial. Nothing is attached to the functions.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from rigs import DISTAL, JOINT, apply_pose, two_segments

import jointbench
from jointbench.estimators import registry
from jointbench.estimators.results import CenterResult, JointCenterResult
from jointbench.geometry import rotation_matrix
from jointbench.registries import Registry


def _trials(n_trials: int = 3, n_frames: int = 60) -> np.ndarray:
    rng = np.random.default_rng(4)
    t = np.linspace(0.0, 4.0, n_frames)
    rotvec = np.stack([0.6 * np.sin(1.9 * t), 0.4 * np.sin(1.3 * t), 0.1 * np.sin(t)], -1)
    rotation = rotation_matrix(rotvec)
    clean = apply_pose(rotation, JOINT - rotation @ JOINT, DISTAL)
    return clean + rng.normal(scale=0.3, size=(n_trials, *clean.shape))


@pytest.fixture
def newcomer():
    """A per-trial centre estimator without a many-trial form; fails on trial means above 1e6."""

    def centroid(markers):
        markers = np.asarray(markers)
        if np.abs(markers).max() > 1e6:
            raise FloatingPointError("too far")
        return CenterResult(
            center=markers.reshape(-1, 3).mean(axis=0),
            converged=True,
            iterations=0,
            status="ok",
            method="newcomer",
        )

    registry.register("center", "newcomer")(centroid)
    yield "newcomer"
    registry.unregister("center", "newcomer")


def test_the_estimators_are_held_in_the_one_registry_type():
    assert all(isinstance(registry._REGISTRY[kind], Registry) for kind in registry.KINDS)
    with pytest.raises(ValueError, match=r"unknown center method 'nope'; known: .*LS"):
        registry.get("center", "nope")


@pytest.mark.parametrize("checked", [True, False])
def test_a_newcomer_gets_a_many_trial_form_trial_by_trial(newcomer, checked):
    markers = _trials()
    markers[1, 3, 0] = 2e6
    outcomes = registry.many("center", newcomer, checked=checked)(markers)
    fit = registry.get("center", newcomer, checked=checked)
    assert isinstance(outcomes[1], FloatingPointError)
    for trial in (0, 2):
        alone = fit(markers[trial])
        np.testing.assert_array_equal(outcomes[trial].center, alone.center)
        assert outcomes[trial].status == alone.status and outcomes[trial].diagnostics.keys() == (
            alone.diagnostics.keys()
        )


@pytest.mark.parametrize("checked", [True, False])
def test_a_newcomer_fits_trials_of_other_shapes_trial_by_trial(newcomer, checked):
    """Given as lists, trials of other numbers of frames or markers reach the one-trial
    function as given."""
    trials = [_trials(1, 60)[0], _trials(1, 45)[0][:, :2]]
    outcomes = registry.many("center", newcomer, checked=checked)(trials)
    for outcome, markers in zip(outcomes, trials, strict=True):
        alone = registry.get("center", newcomer, checked=checked)(markers)
        np.testing.assert_array_equal(outcome.center, alone.center)
        assert outcome.status == alone.status


def test_a_checked_many_trial_form_refuses_a_bad_trial_alone(newcomer):
    markers = _trials()
    markers[2, 5, 1] = np.nan
    outcomes = registry.many("center", newcomer)(markers)
    assert isinstance(outcomes[2], ValueError) and "NaN" in str(outcomes[2])
    assert outcomes[0].diagnostics["support_assessed"]


def test_the_stated_many_trial_form_is_the_one_given():
    def one(markers):
        raise AssertionError("the many-trial form is used")

    def many(markers):
        return ["stated"] * len(markers)

    registry.register("center", "stated", many=many)(one)
    try:
        assert registry.many("center", "stated", checked=False) is many
        assert registry.has_own_many("center", "stated")
        with pytest.raises(ValueError, match="already has a many-trial form"):
            registry.register_many("center", "stated", many)
    finally:
        registry.unregister("center", "stated")


@pytest.mark.parametrize("kind", registry.KINDS)
def test_every_method_has_both_forms_and_nothing_attached(kind):
    for name in jointbench.methods(kind):
        for checked in (True, False):
            assert callable(registry.many(kind, name, checked=checked))
            assert not hasattr(registry.get(kind, name, checked=checked), "batched"), name


def _midpoint(proximal, distal, method: str) -> JointCenterResult:
    """The midpoint of the two clusters' centroids over every frame, as ``method``."""
    both = np.concatenate([np.asarray(proximal), np.asarray(distal)], axis=1)
    return JointCenterResult(
        center=both.reshape(-1, 3).mean(axis=0),
        covariance=None,
        converged=True,
        iterations=0,
        status="ok",
        method=method,
    )


@pytest.fixture
def two_segment_newcomer():
    """A per-trial joint centre estimator without a many-trial form: the midpoint of the
    clusters' centroids."""

    def midpoint(proximal, distal):
        return _midpoint(proximal, distal, "midpoint")

    registry.register("joint_center", "midpoint")(midpoint)
    yield "midpoint"
    registry.unregister("joint_center", "midpoint")


@pytest.mark.parametrize("distal_trials", [2, 4])
@pytest.mark.parametrize("checked", [True, False])
@pytest.mark.parametrize("name", [*registry.methods("joint_center"), "midpoint"])
def test_segments_holding_other_numbers_of_trials_are_refused(
    name, checked, distal_trials, two_segment_newcomer
):
    """A distal trial too many would be left out unsaid, one too few fail with an IndexError."""
    proximal, distal = two_segments(30)
    segments = (np.stack([proximal] * 3), np.stack([distal] * distal_trials))
    with pytest.raises(
        ValueError,
        match=rf"^proximal holds 3 trials, distal {distal_trials}: give every segment the same",
    ):
        registry.many("joint_center", name, checked=checked)(*segments)


@pytest.mark.parametrize("checked", [True, False])
def test_arrays_of_other_numbers_of_trials_are_named_by_position_past_the_segments(checked):
    proximal, distal = two_segments(30)
    segments = (np.stack([proximal] * 3), np.stack([distal] * 3), np.stack([distal] * 2))
    with pytest.raises(
        ValueError, match=r"^marker array 1 holds 3 trials, marker array 2 3, marker array 3 2:"
    ):
        registry.many("joint_center", "SCoRE", checked=checked)(*segments)


@dataclasses.dataclass
class _MidpointOf:
    """A joint-centre estimator that is a callable instance with fields, as a user may write
    one: a dataclass compares by its fields, so it has no hash."""

    method: str

    def __call__(self, proximal, distal):
        return _midpoint(proximal, distal, self.method)


def test_an_estimator_without_a_hash_is_checked_as_any_other():
    """Its checked call shares the poses it fits with the verdict, whether its signature takes
    the trial asked (remembered per method) included."""
    estimator = _MidpointOf("midpoint-of")
    with pytest.raises(TypeError):
        hash(estimator)

    def midpoints(proximal, distal, *, poses=None):
        return [estimator(p, d) for p, d in zip(proximal, distal, strict=True)]

    midpoints.pose_segments = ("proximal", "distal")
    registry.register("joint_center", "midpoint-of", many=midpoints)(estimator)
    try:
        proximal, distal = two_segments(30)
        result = registry.get("joint_center", "midpoint-of")(proximal, distal)
    finally:
        registry.unregister("joint_center", "midpoint-of")
    np.testing.assert_array_equal(result.center, estimator(proximal, distal).center)
