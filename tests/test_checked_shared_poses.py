"""A checked call of a pose-based two-segment method fits the segments' poses once, for the fit
and for the support verdict (:func:`jointbench.estimators.registry.get`, ``many``), and answers
exactly as the method and the verdict each fitting their own: every field of every result,
every error, one trial or many, with poses passed by the caller or not.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from rigs import assert_same_outcome, two_segments

from jointbench.estimators import registry, support, validation
from jointbench.estimators.segment_poses import _trial_poses, pose_segments, trial_poses

KIND = "joint_center"
POSE_BASED = [
    name
    for name in registry.methods(KIND)
    if registry.has_own_many(KIND, name)
    and pose_segments(registry.many(KIND, name, checked=False)) is not None
]


def _noisy(arrays, noise_mm: float, seed: int):
    rng = np.random.default_rng(seed)
    return tuple(a + rng.normal(scale=noise_mm, size=a.shape) for a in arrays)


def _cases() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Two-segment trials a user meets: good, noise-free, hinged, still, too short, collinear,
    non-rigid, with a third segment-length of frames."""
    ball = two_segments(60)
    proximal, distal = ball
    collinear = distal.copy()
    collinear[:, 2] = 2.0 * distal[:, 1] - distal[:, 0]
    return {
        "ball-noisy": _noisy(ball, 0.5, 0),
        "ball-noise-free": ball,
        "hinge-noisy": _noisy(two_segments(60, relative="hinge"), 0.3, 1),
        "still": _noisy(two_segments(60, relative="none"), 0.3, 2),
        "two-frames": (proximal[:2], distal[:2]),
        "collinear-distal": (proximal, collinear),
        "non-rigid-distal": _noisy(
            (proximal, distal + np.random.default_rng(3).normal(scale=40.0, size=distal.shape)),
            0.3,
            4,
        ),
    }


CASES = _cases()


def _with_sample(markers: np.ndarray, value: float) -> np.ndarray:
    changed = markers.copy()
    changed[7, 1] = value
    return changed


def _user_input() -> dict[str, tuple]:
    """The noisy ball trial as users hand it over: nested lists, float32, integers, masked
    arrays, gaps as NaN or zeros, a segment a frame short, three or two frames, coordinates
    near 1e8 mm or offset by 1e6 mm, near 1e200 (the pose fit overflows), nearly collinear
    distal markers."""
    proximal, distal = CASES["ball-noisy"]
    nearly = distal.copy()
    nearly[:, 2] = 2.0 * distal[:, 1] - distal[:, 0] + 1e-3
    masked = np.ma.masked_array(distal, mask=np.zeros(distal.shape, dtype=bool))
    gap = np.ma.masked_array(distal, mask=np.isnan(_with_sample(distal, np.nan)))
    return {
        "lists": (proximal.tolist(), distal.tolist()),
        "float32": (proximal.astype(np.float32), distal.astype(np.float32)),
        "integers": (np.rint(proximal).astype(int), np.rint(distal).astype(np.int32)),
        "masked-nothing": (proximal, masked),
        "masked-gap": (proximal, gap),
        "nan-gap": (proximal, _with_sample(distal, np.nan)),
        "zero-gap": (_with_sample(proximal, 0.0), distal),
        "distal-a-frame-short": (proximal, distal[:-1]),
        "three-frames": (proximal[:3], distal[:3]),
        "two-frames-as-lists": (proximal[:2].tolist(), distal[:2].tolist()),
        "near-1e8": (proximal + 1e8, distal + 1e8),
        "offset-1e6": (proximal + 1e6, distal - 1e6),
        "near-1e200": (proximal * 1e197, distal * 1e197),
        "nearly-collinear-distal": (proximal, nearly),
    }


USER_INPUT = _user_input()

ONE_TRIAL = {**CASES, **USER_INPUT}


def _separately(name: str, arrays, **options):
    """The method, its own check (the Gauss–Markov model test), the verdict and the check of
    the answer against it each fitting their own poses: the composition before the poses were
    shared."""
    fn = registry.get(KIND, name, checked=False)
    clean = validation.check_input(KIND, arrays)
    return _checked_alone(fn, fn(*clean, **options), clean, options)


def _checked_alone(fn, result, arrays: tuple, options: dict):
    """``result`` of ``fn`` on one trial's checked ``arrays`` after the method's own check, the
    verdict and the check of the answer against it, each fitting its own poses."""
    result = registry._self_checked(fn, result, arrays, options)
    stacked = tuple(array[None] for array in arrays)
    verdict = support.assess(KIND, arrays)
    (result,) = registry._precision_checked(fn, [result], stacked, None, [verdict])
    (result,) = registry._answers_checked(KIND, [result], stacked, [verdict])
    return support.annotate(result, verdict)


def _outcome(call):
    try:
        return call()
    except (ValueError, TypeError) as error:
        return error


def test_the_pose_based_methods_are_found():
    assert {"SCoRE", "analytic", "gauss-markov", "gauss-markov-frame0"} <= set(POSE_BASED)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@pytest.mark.parametrize("case", list(ONE_TRIAL))
@pytest.mark.parametrize("name", POSE_BASED)
def test_one_checked_trial_answers_as_fitting_twice(name, case):
    arrays = ONE_TRIAL[case]
    found = _outcome(lambda: registry.get(KIND, name)(*arrays))
    assert_same_outcome(found, _outcome(lambda: _separately(name, arrays)))


@pytest.mark.parametrize("name", ["gauss-markov", "gauss-markov-frame0"])
def test_options_reach_the_fit_as_before(name):
    arrays = CASES["ball-noisy"]
    options = {"noise_mm": 0.5, "max_iterations": 3, "tol_mm": 1e-9}
    found = registry.get(KIND, name)(*arrays, **options)
    assert_same_outcome(found, _separately(name, arrays, **options))


@pytest.mark.parametrize("name", POSE_BASED)
def test_an_option_the_method_does_not_take_is_a_type_error(name):
    with pytest.raises(TypeError, match="bogus"):
        registry.get(KIND, name)(*CASES["ball-noisy"], bogus=1)


@pytest.mark.parametrize("name", POSE_BASED)
def test_the_verdict_reads_the_fits_poses(name, monkeypatch):
    """The verdict of a checked call does not fit poses of its own."""

    def refuse(*args, **kwargs):
        raise AssertionError("the verdict fitted its own poses")

    monkeypatch.setattr(support, "_fitted_poses", refuse)
    result = registry.get(KIND, name)(*CASES["ball-noisy"])
    assert result.diagnostics["support_assessed"] is True
    results = registry.many(KIND, name)(*(np.stack([a, a]) for a in CASES["hinge-noisy"]))
    assert all(r.diagnostics["support_assessed"] is True for r in results)


def _batch(names: list[str]) -> tuple[np.ndarray, ...]:
    return tuple(np.stack(arrays) for arrays in zip(*(CASES[n] for n in names), strict=True))


BATCH = ["ball-noisy", "ball-noise-free", "hinge-noisy", "still", "collinear-distal"]


@pytest.mark.parametrize("name", POSE_BASED)
def test_many_checked_trials_answer_as_each_fitting_twice(name):
    outcomes = registry.many(KIND, name)(*_batch(BATCH))
    for case, found in zip(BATCH, outcomes, strict=True):
        assert_same_outcome(found, _outcome(lambda case=case: _separately(name, CASES[case])))


@pytest.mark.parametrize("name", POSE_BASED)
def test_poses_of_the_very_markers_give_the_answer_of_none(name):
    """Poses a caller fitted to the call's own markers give the answer the call gives without
    them, every field of every trial."""
    segments = _batch(BATCH)
    names = pose_segments(registry.many(KIND, name, checked=False))
    own = trial_poses(dict(zip(names, segments, strict=True)), min_frames=3)
    without = registry.many(KIND, name)(*segments)
    with_own = registry.many(KIND, name)(*segments, poses=own)
    for found, expected in zip(with_own, without, strict=True):
        assert_same_outcome(found, expected)


FITTED = ["ball-noisy", "ball-noise-free", "hinge-noisy", "still"]


def _misfitted(segments: tuple, names: tuple) -> dict[str, tuple[list, str]]:
    """Poses a caller may pass that were not fitted to the call's ``segments``, with the trial
    and segment the refusal must name: the trials' poses in reverse order, one trial's poses
    fitted to its markers moved by a millimetre, and one trial's last segment's poses taken
    from another trial."""
    own = trial_poses(dict(zip(names, segments, strict=True)), min_frames=3)
    moved = segments[-1].copy()
    moved[2] += 1.0
    edited = trial_poses(dict(zip(names, (*segments[:-1], moved), strict=True)), min_frames=3)
    swapped = list(own)
    swapped[2] = {**own[2], names[-1]: own[0][names[-1]]}
    return {
        "reversed": (own[::-1], f"trial 0's {names[0]}"),
        "moved-markers": ([*own[:2], edited[2], *own[3:]], f"trial 2's {names[-1]}"),
        "one-segment-swapped": (swapped, f"trial 2's {names[-1]}"),
    }


@pytest.mark.parametrize("case", ["reversed", "moved-markers", "one-segment-swapped"])
@pytest.mark.parametrize("checked", [True, False])
@pytest.mark.parametrize("name", POSE_BASED)
def test_poses_fitted_to_other_markers_are_refused_naming_trial_and_segment(name, checked, case):
    """A trial fitted with poses of other markers (another trial's, or its own before an edit)
    would give a confident answer about the wrong data: the call is refused, checked or not,
    naming the first such trial and segment."""
    segments = _batch(FITTED)
    names = pose_segments(registry.many(KIND, name, checked=False))
    poses, named = _misfitted(segments, names)[case]
    with pytest.raises(ValueError, match=rf"^poses: {named} poses were not fitted to"):
        registry.many(KIND, name, checked=checked)(*segments, poses=poses)


@pytest.mark.parametrize("name", POSE_BASED)
@pytest.mark.parametrize("checked", [True, False])
def test_poses_for_another_number_of_trials_are_refused(name, checked):
    segments = _batch(BATCH)
    names = pose_segments(registry.many(KIND, name, checked=False))
    poses = trial_poses(dict(zip(names, segments, strict=True)), min_frames=3)
    with pytest.raises(ValueError, match="poses: 4 entries for 5 trials"):
        registry.many(KIND, name, checked=checked)(*segments, poses=poses[:4])


def _unshared_many(name: str, segments: tuple, **options) -> list:
    """The many-trial composition before the poses were shared: the method's many-trial form
    fitting its own poses, then per trial the input checks (whose error wins), the method's
    own check, the verdict and the answer's check, each fitting its own."""
    fn = registry.get(KIND, name, checked=False)
    outcomes = list(registry.many(KIND, name, checked=False)(*segments, **options))
    checked = validation.check_input_many(KIND, segments, len(outcomes))
    for trial, (outcome, error) in enumerate(zip(outcomes, checked.errors, strict=True)):
        if error is not None:
            outcomes[trial] = error
        elif not isinstance(outcome, Exception):
            outcomes[trial] = _checked_alone(fn, outcome, checked.arrays(trial), options)
    return outcomes


def _assert_same_outcomes(found, expected) -> None:
    if isinstance(expected, Exception) or isinstance(found, Exception):
        assert_same_outcome(found, expected)
        return
    assert len(found) == len(expected)
    for one, other in zip(found, expected, strict=True):
        assert_same_outcome(one, other)


def _not_one_batch() -> dict[str, tuple]:
    """Segments whose poses cannot be fitted as one batch: a third marker array. (Trials of
    other lengths are fitted length by length: ``test_ragged_trials.py``.)"""
    proximal, distal = CASES["ball-noisy"]
    return {
        "three-arrays": (np.stack([proximal] * 2), np.stack([distal] * 2), np.stack([distal] * 2)),
    }


NOT_ONE_BATCH = _not_one_batch()


@pytest.mark.parametrize("options", [{}, {"noise_mm": -1.0}], ids=["", "bad-option"])
@pytest.mark.parametrize("case", list(NOT_ONE_BATCH))
@pytest.mark.parametrize("name", POSE_BASED)
def test_segments_that_are_not_one_batch_answer_as_fitting_twice(name, case, options):
    """Where the poses cannot be fitted as one batch, the checked call answers (per trial or
    for the whole call) as the method fitting its own poses does, after the options' check."""
    segments = NOT_ONE_BATCH[case]
    found = _outcome(lambda: registry.many(KIND, name)(*segments, **options))
    _assert_same_outcomes(found, _outcome(lambda: _options_then_unshared(name, segments, options)))


def _options_then_unshared(name: str, segments: tuple, options: dict) -> list:
    """:func:`_unshared_many` after the options' check of every checked form."""
    registry.check_options(KIND, name, options, f"{KIND} method {name}")
    return _unshared_many(name, segments, **options)


def _other_entries(own: list) -> dict[str, object]:
    """What a caller may pass for one trial's poses that is none: the poses of a one-segment
    fit, nothing, one segment's poses alone, another error than the fit's."""
    proximal = own[2]["proximal"]
    (one_segment,) = trial_poses({"markers": [proximal.markers]}, min_frames=3)
    return {
        "one-segment": (one_segment, "the segments markers"),
        "nothing": (None, "NoneType"),
        "one-segment-alone": (proximal, "SegmentPoses"),
        "another-error": (FloatingPointError("overflow"), "FloatingPointError"),
    }


@pytest.mark.parametrize("entry", ["one-segment", "nothing", "one-segment-alone", "another-error"])
@pytest.mark.parametrize("checked", [True, False])
@pytest.mark.parametrize("name", POSE_BASED)
def test_poses_that_are_not_a_trials_poses_are_refused_naming_the_trial(name, checked, entry):
    segments = _batch(BATCH)
    names = pose_segments(registry.many(KIND, name, checked=False))
    poses = trial_poses(dict(zip(names, segments, strict=True)), min_frames=3)
    poses[2], held = _other_entries(poses)[entry]
    with pytest.raises(ValueError, match=rf"^poses: trial 2 holds {held}; give per trial"):
        registry.many(KIND, name, checked=checked)(*segments, poses=poses)


@pytest.mark.filterwarnings("ignore::RuntimeWarning")
@pytest.mark.parametrize("name", POSE_BASED)
def test_a_batch_of_user_input_answers_as_fitting_twice(name):
    """Trials of one shape as a list per segment, some refused by the input checks, one that
    overflows the pose fit: per trial, the answer of fitting twice, alone or in the batch."""
    same_shape = [
        case for case, (proximal, _) in USER_INPUT.items() if np.shape(proximal) == (60, 3, 3)
    ]
    segments = tuple([USER_INPUT[case][index] for case in same_shape] for index in range(2))
    outcomes = registry.many(KIND, name)(*segments)
    _assert_same_outcomes(outcomes, _unshared_many(name, segments))
    for case, found in zip(same_shape, outcomes, strict=True):
        assert_same_outcome(found, _outcome(lambda case=case: _separately(name, USER_INPUT[case])))


@pytest.mark.parametrize("name", POSE_BASED)
def test_trials_of_other_lengths_are_refused_naming_them_without_checks(name):
    """The form without checks fits the trials of one call as one batch: a trial of other
    length that passes the pose fit's checks is named, with the length of the first; one the
    checks refuse is that trial's error alone. (The checked form fits them length by length:
    ``test_ragged_trials.py``.)"""
    checked = False
    proximal, distal = CASES["ball-noisy"]
    segments = ([proximal, proximal[:2], proximal[:-5]], [distal, distal[:2], distal[:-5]])
    with pytest.raises(
        ValueError,
        match=r"^proximal of trial 2 has 55 frames and 3 markers, of trial 0 60 and 3: the "
        r"trials of one call share their numbers of frames and markers",
    ):
        registry.many(KIND, name, checked=checked)(*segments)
    outcomes = registry.many(KIND, name, checked=checked)(*(s[:2] for s in segments))
    assert "has 2 frames; this method needs at least 3" in str(outcomes[1])


@pytest.mark.parametrize("case", list(CASES))
def test_poses_of_checked_samples_are_those_of_unchecked_ones(case):
    """A checked call's inputs passed the sample checks just before their poses are fitted:
    its private form with ``samples_checked`` skips that scan, and fits and refuses (too few
    frames, collinear markers) exactly as the scan does."""
    arrays = tuple(validation.check_input(KIND, CASES[case]))
    segments = {"proximal": [arrays[0]], "distal": [arrays[1]]}
    scanned = trial_poses(segments, min_frames=3)
    skipped = _trial_poses(segments, min_frames=3, samples_checked=True)
    for found, expected in zip(skipped, scanned, strict=True):
        if isinstance(expected, ValueError):
            assert type(found) is type(expected) and str(found) == str(expected)
        else:
            for name in segments:
                for field in dataclasses.fields(expected[name]):
                    mine = getattr(found[name], field.name)
                    theirs = getattr(expected[name], field.name)
                    assert np.array_equal(mine, theirs), (name, field.name)


def test_samples_checked_still_counts_frames_and_markers():
    proximal, distal = CASES["ball-noisy"]
    short = {"proximal": [proximal[:2]], "distal": [distal[:2]]}
    few = {"proximal": [proximal[:, :2]], "distal": [distal]}
    for segments in (short, few):
        (scanned,) = trial_poses(segments, min_frames=3)
        (skipped,) = _trial_poses(segments, min_frames=3, samples_checked=True)
        assert isinstance(skipped, ValueError) and str(skipped) == str(scanned)
