"""The input checks of a batch of trials decide, trial by trial, what the one-trial checks do.

:func:`jointbench.estimators.validation.check_input_many` checks a regular batch in one pass
and words only the refused trials' errors with the one-trial
:func:`~jointbench.estimators.validation.check_input`; every other batch goes trial by trial.
Hostile batches mix every kind of bad trial with valid ones, and each trial must get exactly
the one-trial outcome: the same error, word for word, or the same float64 arrays.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rigs import DISTAL, JOINT, apply_pose, two_segments

from jointbench.estimators import registry, support, validation
from jointbench.geometry import rotation_matrix
from jointbench.numerics.magnitudes import largest_coordinate

N_FRAMES = 40


def _moving(seed: int) -> np.ndarray:
    """A valid trial: three markers rotating about JOINT, with noise, ``(N_FRAMES, 3, 3)``."""
    t = np.linspace(0.0, 3.0, N_FRAMES)
    rotvec = np.stack([0.5 * np.sin(1.7 * t), 0.3 * np.sin(1.1 * t), 0.1 * np.sin(t)], -1)
    rotation = rotation_matrix(rotvec)
    clean = apply_pose(rotation, JOINT - rotation @ JOINT, DISTAL)
    return clean + np.random.default_rng(seed).normal(scale=0.2, size=clean.shape)


def _bad_samples(kind: str, seed: int) -> np.ndarray:
    trial = _moving(seed)
    if kind == "nan":
        trial[7, 1, 2] = np.nan
    elif kind == "inf":
        trial[3, 0, 0] = np.inf
        trial[9, 2, 1] = -np.inf
    elif kind == "origin":
        trial[11, 2] = 0.0
    elif kind == "negative zero":
        trial[5, 0] = (-0.0, 0.0, -0.0)
    elif kind == "nan and origin":
        trial[2, 1] = 0.0
        trial[20, 0, 1] = np.nan
    elif kind == "static":
        trial[:] = trial[0]
    elif kind == "nearly static":
        trial[:] = trial[0]
        trial[4, 1, 0] += 1e-13
    elif kind == "sliding":
        steps = np.linspace(0.0, 30.0, N_FRAMES)[:, None, None]
        trial = trial[0] + steps * np.array([0.3, -0.5, 0.8])
    elif kind == "one static marker":  # valid: the others rotate
        trial[:, 1] = trial[0, 1]
    return trial


_BAD = ("nan", "inf", "origin", "negative zero", "nan and origin", "static", "nearly static")
_KINDS = (*_BAD, "sliding", "one static marker", "valid")


def _regular_batch() -> np.ndarray:
    """Every kind of trial twice, valid ones between, ``(n_trials, N_FRAMES, 3, 3)``."""
    trials = []
    for seed, kind in enumerate(_KINDS * 2):
        trials += [_bad_samples(kind, seed), _moving(100 + seed)]
    return np.stack(trials)


def _one_by_one(kind: str, segments: tuple, n_trials: int) -> list:
    """Per trial, the one-trial checks' error or their arrays."""
    outcomes = []
    for trial in range(n_trials):
        try:
            outcomes.append(validation.check_input(kind, tuple(s[trial] for s in segments)))
        except ValueError as error:
            outcomes.append(error)
    return outcomes


def _assert_as_one_by_one(kind: str, segments: tuple, n_trials: int) -> None:
    checked = validation.check_input_many(kind, segments, n_trials)
    expected = _one_by_one(kind, segments, n_trials)
    assert len(checked.errors) == n_trials
    for trial, alone in enumerate(expected):
        error = checked.errors[trial]
        if isinstance(alone, ValueError):
            assert type(error) is type(alone) and str(error) == str(alone), trial
            continue
        assert error is None, (trial, error)
        got = checked.arrays(trial)
        assert len(got) == len(alone)
        for array, one in zip(got, alone, strict=True):
            assert array.dtype == np.float64 and array.shape == one.shape
            np.testing.assert_array_equal(array, one)
    passed = [trial for trial, error in enumerate(checked.errors) if error is None]
    if len({tuple(a.shape for a in expected[t]) for t in passed}) == 1:  # trials that stack
        for array, arrays in zip(
            checked.stacked(passed), zip(*(expected[t] for t in passed), strict=True), strict=True
        ):
            np.testing.assert_array_equal(array, np.stack(arrays))


def test_a_regular_batch_mixing_every_bad_trial_is_checked_as_trial_by_trial():
    markers = _regular_batch()
    errors = validation.check_input_many("center", (markers,), len(markers)).errors
    assert sum(error is not None for error in errors) == 2 * (len(_BAD) + 1)  # and sliding
    for kind in ("center", "axis"):
        _assert_as_one_by_one(kind, (markers,), len(markers))


def test_a_trial_overflowing_the_checks_arithmetic_fails_alone():
    markers = _regular_batch()
    markers[5] *= 1e200 / np.abs(markers[5]).max()
    with np.errstate(all="ignore"):
        _assert_as_one_by_one("center", (markers,), len(markers))


@pytest.mark.parametrize(
    "convert",
    [
        lambda m: m.astype(np.float32),
        lambda m: np.round(np.nan_to_num(m, nan=1.0, posinf=2.0, neginf=3.0)).astype(np.int64),
        lambda m: np.asfortranarray(m),
        lambda m: m[:, ::2],
        lambda m: m[::-1],
    ],
    ids=["float32", "int64", "fortran", "strided", "reversed"],
)
def test_a_regular_batch_of_another_layout_or_real_dtype_is_checked_as_trial_by_trial(convert):
    markers = convert(_regular_batch())
    _assert_as_one_by_one("center", (markers,), len(markers))


def _irregular_batches() -> dict[str, object]:
    valid = _moving(1)
    masked = np.ma.masked_array(valid, mask=np.zeros(valid.shape, dtype=bool))
    masked.mask[3, 1, 0] = True
    mixed = [
        valid,
        valid.astype(complex),
        valid > 0,
        valid.astype(object),
        valid[:, 0],
        valid[..., :2],
        valid[:0],
        valid[:2],
        masked,
        np.ma.masked_array(_moving(2)),
        valid.tolist(),
        "markers",
        _bad_samples("nan", 3),
        _bad_samples("sliding", 4),
        _moving(5),
    ]
    regular = _regular_batch()
    return {
        "mixed list": mixed,
        "list of regular trials": list(regular),
        "complex": regular.astype(complex),
        "bool": regular > 0,
        "object": regular.astype(object),
        "two coordinates": regular[..., :2],
        "one trial's shape": regular[0],
        "five axes": regular[:, None],
        "no frames": regular[:, :0],
        "no markers": regular[:, :, :0],
        "masked": np.ma.masked_array(regular, mask=np.isnan(regular)),
    }


@pytest.mark.parametrize("name", list(_irregular_batches()))
def test_an_irregular_batch_is_checked_as_trial_by_trial(name):
    segment = _irregular_batches()[name]
    _assert_as_one_by_one("center", (segment,), len(segment))


def _two_segment_batches() -> dict[str, tuple]:
    proximal, distal = (np.stack([segment] * 6) for segment in two_segments(N_FRAMES))
    proximal, distal = proximal.copy(), distal.copy()
    proximal[1, 4, 2, 1] = np.nan
    distal[1, 6, 0] = 0.0  # the proximal NaN is named first
    distal[3, 8, 1] = 0.0
    distal[4, :, :] = distal[4, 0]  # a distal segment that does not move is the verdict's
    return {
        "regular": (proximal, distal),
        "different frames": (proximal, distal[:, :-1]),
        "different trials": (proximal, distal[:-1]),
        "lists": (list(proximal), [*distal[:3], distal[3, :, :2], distal[4].astype(complex), 1]),
        "one segment": (proximal,),
    }


@pytest.mark.parametrize("name", list(_two_segment_batches()))
def test_two_segment_batches_are_checked_as_trial_by_trial(name):
    segments = _two_segment_batches()[name]
    n_trials = len(segments[0]) if name != "different trials" else len(segments[1])
    _assert_as_one_by_one("joint_center", segments, n_trials)


@pytest.mark.parametrize("as_list", [False, True])
def test_the_checked_many_trial_form_gives_each_trial_its_one_trial_outcome(as_list):
    markers = _regular_batch()
    segment = list(markers) if as_list else markers
    outcomes = registry.many("center", "LS")(segment)
    fit = registry.get("center", "LS")
    for trial, outcome in enumerate(outcomes):
        try:
            alone = fit(markers[trial])
        except ValueError as error:
            assert type(outcome) is ValueError and str(outcome) == str(error), trial
            continue
        np.testing.assert_allclose(outcome.center, alone.center, rtol=0, atol=1e-9)
        assert outcome.status == alone.status, trial


@pytest.fixture
def assessed(monkeypatch):
    """The arrays each call of the many-trial support verdict was given."""
    given = []
    assess_many = support.assess_many

    def recording(kind, arrays, **keywords):
        given.append(arrays)
        return assess_many(kind, arrays, **keywords)

    monkeypatch.setattr(support, "assess_many", recording)
    return given


def test_a_batch_of_clean_trials_reaches_the_verdict_without_a_copy(assessed):
    markers = np.stack([_moving(seed) for seed in range(4)])
    given = markers.copy()
    registry.many("center", "LS")(markers)
    (arrays,) = assessed
    assert arrays[0] is markers
    np.testing.assert_array_equal(markers, given)  # and left as it was given


def test_only_the_trials_that_passed_reach_the_verdict(assessed):
    markers = np.stack([_moving(0), _bad_samples("nan", 1), _moving(2)])
    registry.many("center", "LS")(markers)
    (arrays,) = assessed
    np.testing.assert_array_equal(arrays[0], markers[[0, 2]])


@settings(max_examples=200, deadline=None)
@given(
    frame=st.integers(0, N_FRAMES - 1),
    marker=st.integers(0, 2),
    axis=st.integers(0, 2),
    value=st.sampled_from([np.nan, np.inf, -np.inf]),
    magnitude=st.sampled_from([1e-300, 1.0, 1e200, 1e305]),
)
def test_one_non_finite_coordinate_anywhere_is_refused_at_any_magnitude(
    frame, marker, axis, value, magnitude
):
    """Every coordinate is read, whatever the others' size: finite values up to the largest
    double do not hide a NaN or an infinity, nor pass for one (beyond float64's sums they are
    refused as too large, and the NaN or infinity is still what is named)."""
    trial = _moving(7) * magnitude / 100.0
    if magnitude > largest_coordinate(trial.shape[0] * trial.shape[1]):
        with pytest.raises(ValueError, match=r"^markers has a coordinate of .* beyond the "):
            validation.check_markers(trial)
    else:
        validation.check_markers(trial)  # the finite trial passes the sample checks
    trial[frame, marker, axis] = value
    with pytest.raises(ValueError, match=f"NaN or inf at marker {marker}, frame {frame} "):
        validation.check_markers(trial)


def _sized_batches() -> dict[str, tuple[str, tuple]]:
    """Batches of valid trials but for the size of one trial's segment, the one fault in the
    batch: a cluster in metres, or ten times a body segment's size (millimetres read as
    centimetres or the markers of several segments). By kind, its segments."""
    markers = np.stack([_moving(seed) for seed in range(5)])
    proximal, distal = (np.stack([segment] * 5) for segment in two_segments(N_FRAMES))
    distal = distal.copy()
    distal[1] *= 1e-3
    return {
        "metres": ("center", (np.concatenate([markers[:3], 1e-3 * markers[3:4], markers[4:]]),)),
        "too large": ("axis", (np.concatenate([markers[:3], 1e3 * markers[3:4], markers[4:]]),)),
        "distal metres": ("joint_center", (proximal, distal)),
    }


@pytest.mark.parametrize("name", list(_sized_batches()))
def test_a_batch_whose_one_fault_is_a_trials_size_refuses_that_trial(name):
    """The size check's error stands where no trial fails the checks of the samples, the
    motion or the lines: the batch's one pass measures every trial's size beside them."""
    kind, segments = _sized_batches()[name]
    checked = validation.check_input_many(kind, segments, 5)
    refused = [trial for trial, error in enumerate(checked.errors) if error is not None]
    assert refused == [1 if kind == "joint_center" else 3]
    assert "Marker positions are millimetres" in str(checked.errors[refused[0]])
    _assert_as_one_by_one(kind, segments, 5)


@pytest.mark.parametrize("scale", [1e-3, 1e3], ids=["metres", "too large"])
@pytest.mark.parametrize("fault", ["nan", "inf", "origin", "nan and origin", "static", "sliding"])
def test_a_trials_own_fault_is_named_before_its_size(fault, scale):
    """A trial out of size that also fails the checks of the samples, the motion or the lines
    is refused for that fault, in its words, one trial and in a batch, as the checks' order
    says: the size is measured in the same pass, its error raised after theirs."""
    trial = _bad_samples(fault, 3)
    with pytest.raises(ValueError) as alone:
        validation.check_input("center", (trial,))
    with np.errstate(invalid="ignore"), pytest.raises(ValueError) as scaled:
        validation.check_input("center", (scale * trial,))
    assert "Marker positions are millimetres" not in str(scaled.value)
    assert str(scaled.value) == str(alone.value)
    markers = np.stack([_moving(seed) for seed in range(5)])
    markers[3] = scale * trial
    with np.errstate(invalid="ignore"):
        errors = validation.check_input_many("axis", (markers,), 5).errors
    assert [str(error) if error else None for error in errors] == [None] * 3 + [
        str(alone.value),
        None,
    ]


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_markers_that_move_along_one_axis_alone_move(axis):
    """The motion from frame 0 is read along every axis: markers that travel along one axis
    only, by far more than the tolerance, move (and are refused as not rotating), while the
    same markers held at frame 0 do not."""
    still = np.repeat(_moving(3)[:1], N_FRAMES, axis=0)
    with pytest.raises(ValueError, match="do not move"):
        validation.check_moves(still)
    travel = still.copy()
    travel[..., axis] += np.linspace(0.0, 50.0, N_FRAMES)[:, None]
    validation.check_moves(travel)
    with pytest.raises(ValueError, match="do not rotate"):
        validation.check_input("center", (travel,))
