"""Trials of other numbers of frames or markers in one many-trial call.

The checked many-trial form fits each shape as a batch of its own and answers every trial as
its one-trial checked call does; the form without checks, whose trials are fitted as one
batch, refuses them with a ``ValueError`` naming the segment and the trials. A trial too short
for the method fails alone in either form, its error its outcome, the others fitted.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest
from rigs import assert_same_outcome, one_segment, two_segments

from jointbench.estimators import registry
from jointbench.estimators.segment_poses import trial_poses

OWN_MANY = [
    (kind, name)
    for kind in registry.KINDS
    for name in registry.methods(kind)
    if registry.has_own_many(kind, name)
]

#: A fourth marker of a cluster, an affine combination of its three: rigid with them.
_WEIGHTS = np.array([0.5, 0.3, 0.2])


def _with_fourth(markers: np.ndarray) -> np.ndarray:
    """``markers`` ``(N, 3, 3)`` [mm] and a fourth marker rigid with them: their weighted mean
    moved 40 mm along the cluster's normal, so the four are not in one plane."""
    fourth = np.einsum("m,fmk->fk", _WEIGHTS, markers)
    normal = np.cross(markers[:, 1] - markers[:, 0], markers[:, 2] - markers[:, 0])
    fourth += 40.0 * normal / np.linalg.norm(normal, axis=-1, keepdims=True)
    return np.concatenate([markers, fourth[:, None]], axis=1)


def _trial(kind: str, n_frames: int, n_markers: int, seed: int) -> tuple[np.ndarray, ...]:
    """One noisy trial of ``kind``: ``n_frames`` frames of ``n_markers`` (3 or 4) markers per
    segment [mm]; a centre's markers turn about JOINT, an axis's about HINGE."""
    rng = np.random.default_rng(seed)
    if kind == "joint_center":
        segments = two_segments(n_frames)
    else:
        segments = (one_segment(n_frames, "hinge" if kind == "axis" else "ball"),)
    if n_markers == 4:
        segments = tuple(_with_fourth(markers) for markers in segments)
    return tuple(markers + rng.normal(scale=0.3, size=markers.shape) for markers in segments)


def _ragged(kind: str) -> list[tuple[np.ndarray, ...]]:
    """Trials of three shapes, the first shape's trials apart, and a trial of wrong shape (two
    coordinates) among them."""
    trials = [
        _trial(kind, 60, 3, 0),
        _trial(kind, 45, 3, 1),
        _trial(kind, 60, 4, 2),
        _trial(kind, 60, 3, 3),
        _trial(kind, 45, 3, 4),
    ]
    trials.insert(3, tuple(markers[..., :2] for markers in _trial(kind, 60, 3, 5)))
    return trials


def _segments(trials: list[tuple[np.ndarray, ...]]) -> tuple[list[np.ndarray], ...]:
    """Per segment, the list of its trials."""
    return tuple(list(segment) for segment in zip(*trials, strict=True))


def _alone(kind: str, name: str, arrays: tuple[np.ndarray, ...]):
    try:
        return registry.get(kind, name)(*arrays)
    except ValueError as error:
        return error


@pytest.mark.parametrize(("kind", "name"), OWN_MANY)
def test_trials_of_other_shapes_answer_as_each_alone(kind, name):
    trials = _ragged(kind)
    outcomes = registry.many(kind, name)(*_segments(trials))
    assert len(outcomes) == len(trials)
    assert isinstance(outcomes[3], ValueError)
    for trial, arrays in enumerate(trials):
        assert_same_outcome(outcomes[trial], _alone(kind, name, arrays))
    assert not any(isinstance(outcome, Exception) for outcome in outcomes[:3] + outcomes[4:])


@pytest.mark.parametrize(("kind", "name"), OWN_MANY)
def test_each_shape_is_fitted_as_one_regular_batch(kind, name, monkeypatch):
    entry = registry._entry(kind, name)
    fitted = entry.many
    given = []

    @functools.wraps(fitted)
    def recording(*segments, **options):
        given.append([np.shape(segment) for segment in segments])
        assert all(isinstance(segment, np.ndarray) for segment in segments)
        return fitted(*segments, **options)

    monkeypatch.setattr(entry, "many", recording)
    registry.many(kind, name)(*_segments(_ragged(kind)))
    shapes = {(60, 3): 2, (45, 3): 2, (60, 4): 1}
    expected = [
        [(count, frames, markers, 3)] * len(_trial(kind, 3, 3, 0))
        for (frames, markers), count in shapes.items()
    ]
    assert given == expected


@pytest.mark.parametrize(("kind", "name"), OWN_MANY)
def test_the_unchecked_form_refuses_trials_of_other_frames_naming_them(kind, name):
    trials = [_trial(kind, 60, 3, 0), _trial(kind, 60, 3, 1), _trial(kind, 45, 3, 2)]
    first = "proximal" if kind == "joint_center" else "markers"
    with pytest.raises(
        ValueError,
        match=rf"^{first} of trial 2 has 45 frames and 3 markers, of trial 0 60 and 3: the "
        r"trials of one call share their numbers of frames and markers",
    ):
        registry.many(kind, name, checked=False)(*_segments(trials))


@pytest.mark.parametrize(("kind", "name"), OWN_MANY)
def test_the_unchecked_form_refuses_trials_of_other_markers_naming_them(kind, name):
    trials = [_trial(kind, 60, 3, 0), _trial(kind, 60, 4, 1)]
    if kind == "joint_center":  # the proximal markers alike: the distal ones are named
        trials[1] = (trials[0][0], trials[1][1])
    last = "distal" if kind == "joint_center" else "markers"
    with pytest.raises(
        ValueError, match=rf"^{last} of trial 1 has 60 frames and 4 markers, of trial 0 60 and 3:"
    ):
        registry.many(kind, name, checked=False)(*_segments(trials))


@pytest.mark.parametrize("checked", [True, False])
@pytest.mark.parametrize(("kind", "name"), OWN_MANY)
def test_an_empty_list_of_trials_has_no_outcome(kind, name, checked):
    n_segments = len(_trial(kind, 3, 3, 0))
    assert registry.many(kind, name, checked=checked)(*([[]] * n_segments)) == []


@pytest.mark.parametrize("name", ["SCoRE", "gauss-markov"])
def test_an_option_not_declared_refuses_the_call_before_any_shape(name):
    with pytest.raises(ValueError, match=rf"^joint_center method {name}: option noise_mm"):
        registry.many("joint_center", name)(*_segments(_ragged("joint_center")), noise_mm=-1.0)


@pytest.mark.parametrize("name", ["SCoRE", "analytic", "gauss-markov"])
def test_poses_given_for_trials_of_other_lengths_are_split_with_them(name):
    trials = _ragged("joint_center")
    segments = _segments(trials)
    poses = [
        trial_poses(dict(zip(("proximal", "distal"), arrays, strict=True)), min_frames=3)[0]
        if arrays[0].shape[-1] == 3
        else ValueError("no poses")
        for arrays in ((proximal[None], distal[None]) for proximal, distal in trials)
    ]
    shared = registry.many("joint_center", name)(*segments, poses=poses)
    for found, expected in zip(shared, registry.many("joint_center", name)(*segments), strict=True):
        assert_same_outcome(found, expected)
    with pytest.raises(ValueError, match=r"^poses: 5 entries for 6 trials"):
        registry.many("joint_center", name)(*segments, poses=poses[1:])


@pytest.mark.parametrize(("kind", "name"), OWN_MANY)
def test_a_trial_too_short_fails_alone_in_either_form(kind, name):
    # As the checked form and a pose-based method's pose fit treat it: a trial too short for
    # the method (a frame fewer than it claims to need) among normal ones carries its own
    # error, and the others are fitted as without it.
    too_few = registry.claims(kind, name).min_frames - 1
    normal = [_trial(kind, 60, 3, 0), _trial(kind, 60, 3, 1)]
    mixed = _segments([normal[0], _trial(kind, too_few, 3, 2), normal[1]])
    checked = registry.many(kind, name)(*mixed)
    assert isinstance(checked[1], ValueError) and f"has {too_few} frames" in str(checked[1])
    unchecked = registry.many(kind, name, checked=False)(*mixed)
    assert_same_outcome(unchecked[1], checked[1])
    alone = registry.many(kind, name, checked=False)(*_segments(normal))
    for found, expected in zip(unchecked[::2], alone, strict=True):
        assert_same_outcome(found, expected)


@pytest.mark.parametrize(("kind", "name"), OWN_MANY)
def test_beside_a_trial_too_short_trials_of_other_frames_are_named_as_given(kind, name):
    too_few = registry.claims(kind, name).min_frames - 1
    trials = [_trial(kind, 60, 3, 0), _trial(kind, too_few, 3, 1), _trial(kind, 45, 3, 2)]
    first = "proximal" if kind == "joint_center" else "markers"
    with pytest.raises(
        ValueError, match=rf"^{first} of trial 2 has 45 frames and 3 markers, of trial 0 60 and 3"
    ):
        registry.many(kind, name, checked=False)(*_segments(trials))


@pytest.mark.parametrize(("kind", "name"), OWN_MANY)
def test_trials_all_too_short_fail_each_alone(kind, name):
    too_few = registry.claims(kind, name).min_frames - 1
    trials = [_trial(kind, too_few, 3, 0), _trial(kind, too_few - 1, 3, 1)]
    outcomes = registry.many(kind, name, checked=False)(*_segments(trials))
    for outcome, frames in zip(outcomes, (too_few, too_few - 1), strict=True):
        assert isinstance(outcome, ValueError) and f"has {frames} frames" in str(outcome)


@pytest.mark.parametrize(("kind", "name"), OWN_MANY)
def test_trials_given_as_tuples_are_read_as_lists(kind, name):
    # A sequence of trials is a list or a tuple (batching.trial_shapes): a tuple of trials of
    # other frames is named as a list of them is, and a trial too short among them fails alone.
    first = "proximal" if kind == "joint_center" else "markers"
    trials = [_trial(kind, 60, 3, 0), _trial(kind, 60, 3, 1), _trial(kind, 45, 3, 2)]
    as_tuples = tuple(tuple(segment) for segment in _segments(trials))
    with pytest.raises(ValueError, match=rf"^{first} of trial 2 has 45 frames and 3 markers"):
        registry.many(kind, name, checked=False)(*as_tuples)
    too_few = registry.claims(kind, name).min_frames - 1
    mixed = _segments([trials[0], _trial(kind, too_few, 3, 3), trials[1]])
    unchecked = registry.many(kind, name, checked=False)
    for found, expected in zip(
        unchecked(*(tuple(segment) for segment in mixed)), unchecked(*mixed), strict=True
    ):
        assert_same_outcome(found, expected)
