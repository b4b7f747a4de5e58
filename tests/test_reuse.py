"""A value of a trial's frames that several stages of one checked call read is computed once in
the call (:mod:`jointbench.numerics.reuse`), and each stage's numbers are those it computes
alone."""

from __future__ import annotations

import functools
import threading

import numpy as np
import pytest
from test_axis_sd import hinge
from test_frame_independence import _counting_kernel_calls, _interpolated, _kind_trial, _noisy

from jointbench import owncode
from jointbench.estimators import axis, registry, support
from jointbench.numerics import reuse


def _counting(counts: list):
    def compute(array: np.ndarray) -> float:
        counts.append(1)
        return float(array.sum())

    return compute


def test_outside_a_call_every_value_is_computed_where_it_is_asked_for():
    counts: list = []
    array = np.arange(12.0).reshape(2, 2, 3)
    assert reuse.remembered("sum", array, _counting(counts)) == 66.0
    assert reuse.remembered("sum", array, _counting(counts)) == 66.0
    assert len(counts) == 2


def test_a_value_kept_for_an_array_object_is_held_by_that_object_inside_one_call_alone():
    array = np.arange(12.0).reshape(2, 2, 3)
    reuse.keep("passed", array, 7)
    assert reuse.kept_for("passed", array) is None  # outside a call nothing is held
    with reuse.one_call():
        reuse.keep("passed", array, 7)
        assert reuse.kept_for("passed", array) == 7
        assert reuse.kept_for("other", array) is None
        assert reuse.kept_for("passed", array[:]) is None  # another object, same memory
        with reuse.one_call():
            assert reuse.kept_for("passed", array) is None  # an inner scope starts empty
        assert reuse.kept_for("passed", array) == 7
    assert reuse.kept_for("passed", array) is None


def test_inside_a_call_a_view_of_the_same_memory_reads_the_value_back():
    counts: list = []
    batch = np.arange(24.0).reshape(2, 2, 2, 3)
    with reuse.one_call():
        first = reuse.remembered("sum", batch[1], _counting(counts))
        again = reuse.remembered("sum", list(batch)[1], _counting(counts))
        other_name = reuse.remembered("total", batch[1], _counting(counts))
    assert first == again == other_name == float(batch[1].sum())
    assert len(counts) == 2  # once per name


@pytest.mark.parametrize(
    "other",
    [
        lambda batch: batch[1].copy(),  # the same values elsewhere
        lambda batch: batch[0],  # another trial
        lambda batch: batch[1, :1],  # part of the trial
        lambda batch: batch[1, ::-1],  # the trial's frames reversed
    ],
    ids=["copy", "other-trial", "part", "reversed"],
)
def test_inside_a_call_other_memory_is_computed_anew(other):
    counts: list = []
    batch = np.random.default_rng(0).normal(size=(2, 4, 2, 3))
    with reuse.one_call():
        reuse.remembered("sum", batch[1], _counting(counts))
        view = other(batch)
        assert reuse.remembered("sum", view, _counting(counts)) == float(view.sum())
    assert len(counts) == 2


def test_a_call_forgets_its_values_at_its_end_and_a_call_inside_it_starts_empty():
    counts: list = []
    array = np.ones((3, 1, 3))
    with reuse.one_call():
        reuse.remembered("sum", array, _counting(counts))
        with reuse.one_call():
            reuse.remembered("sum", array, _counting(counts))
        reuse.remembered("sum", array, _counting(counts))
    array[0, 0, 0] = 5.0  # changed between calls: the next call sees it
    with reuse.one_call():
        assert reuse.remembered("sum", array, _counting(counts)) == 13.0
    assert len(counts) == 3


def _counting_scatters(monkeypatch) -> list:
    """The trials whose scatter S the planar methods sum, one entry per trial."""
    summed: list = []
    kernel = axis._scatters

    def counting(markers):
        summed.extend([1] * len(markers))
        return kernel(markers)

    monkeypatch.setattr(axis, "_scatters", counting)
    return summed


def test_a_checked_planar_call_sums_its_trials_scatter_once(monkeypatch):
    markers = hinge(0, 30.0, noise=1.0)
    expected = registry.get("axis", "planar")(markers)
    summed = _counting_scatters(monkeypatch)
    result = registry.get("axis", "planar")(markers)
    # The fit's, the package's own, which the self-check and the precision read again.
    assert len(summed) == 1
    assert result.status == expected.status
    assert result.diagnostics == expected.diagnostics


def test_a_checked_many_trial_planar_call_sums_each_trials_scatter_once(monkeypatch):
    markers = np.stack([hinge(seed, 30.0, noise=1.0) for seed in range(3)])
    expected = registry.many("axis", "planar")(markers)
    summed = _counting_scatters(monkeypatch)
    results = registry.many("axis", "planar")(markers)
    assert len(summed) == 3
    for result, alone in zip(results, expected, strict=True):
        assert result.status == alone.status
        assert result.diagnostics == alone.diagnostics


def _refilled_trials() -> tuple[tuple[np.ndarray, np.ndarray], ...]:
    """Two joint-centre trials of the same shape, ``(proximal, distal)`` ``(N, 4, 3)`` each
    [mm]: the first with noise independent in each frame, the second with its frames
    interpolated tenfold, which the support verdict says are not independent."""
    rng = np.random.default_rng(11)
    interpolated = tuple(
        _interpolated(array, 10)
        for array in _kind_trial("joint_center", rng, 30, lambda shape: _noisy(rng, shape, 0.5))
    )
    n_frames = interpolated[0].shape[0]
    independent = _kind_trial("joint_center", rng, n_frames, lambda shape: _noisy(rng, shape, 0.5))
    return independent, interpolated


def test_a_verdict_on_a_refilled_buffer_inside_a_checked_call_reads_the_new_content():
    """An estimator registered from outside may, inside its own fit, judge trial after trial
    refilled into one buffer (a lab's loop): each verdict is the one the trial gets alone,
    never the numbers an earlier content of the same memory left in the checked call."""
    trials = _refilled_trials()
    alone = [support.assess("joint_center", trial) for trial in trials]
    assert alone[0].caveats != alone[1].caveats  # the two differ
    buffers = tuple(array.copy() for array in trials[0])
    seen: list = []
    fit = registry.get("joint_center", "SCoRE", checked=False)

    def judges_a_refilled_buffer(proximal, distal):
        for trial in trials:
            for buffer, array in zip(buffers, trial, strict=True):
                np.copyto(buffer, array)
            seen.append(support.assess("joint_center", buffers))
        return fit(proximal, distal)

    registry.register("joint_center", "judges-a-refilled-buffer")(judges_a_refilled_buffer)
    try:
        registry.get("joint_center", "judges-a-refilled-buffer")(*trials[0])
    finally:
        registry.unregister("joint_center", "judges-a-refilled-buffer")
    for verdict, expected in zip(seen, alone, strict=True):
        assert verdict.caveats == expected.caveats
        assert verdict.diagnostics == expected.diagnostics
        assert verdict.untested == expected.untested


def test_a_scope_is_its_own_threads():
    """A value kept in one thread's checked call is not read by another thread's, which
    computes its own."""
    counts: list = []
    array = np.ones((3, 1, 3))
    found: list = []
    with reuse.one_call():
        reuse.remembered("sum", array, _counting(counts))
        other = threading.Thread(
            target=lambda: found.append(reuse.remembered("sum", array, _counting(counts)))
        )
        other.start()
        other.join()
    assert found == [9.0]
    assert len(counts) == 2


def test_a_batch_whose_flagged_trials_are_left_unread_reads_each_trial_as_alone():
    """A batch's verdict reads the lag-1 statement of its unflagged trials only (a copy of
    them): each trial's verdict is the one it gets alone, the numbers of the whole batch not
    read for the part."""
    independent, interpolated = _refilled_trials()
    trials = (independent, interpolated, independent[::-1])
    stacked = tuple(np.stack(arrays) for arrays in zip(*trials, strict=True))
    with reuse.one_call():
        batch = support.assess_many("joint_center", stacked)
    for verdict, trial in zip(batch, trials, strict=True):
        alone = support.assess("joint_center", trial)
        assert verdict.caveats == alone.caveats
        assert verdict.untested == alone.untested
        assert verdict.diagnostics == alone.diagnostics
    assert batch[1].caveats and not batch[0].caveats  # the middle trial is left unread


def test_a_batch_verdict_with_a_flagged_trial_passes_over_each_segment_once(monkeypatch):
    """Two segments' frame numbers, which the block test computes for every trial, are read
    again for the lag-1 statement of the unflagged trials, not computed again for them."""
    independent, interpolated = _refilled_trials()
    trials = (independent, interpolated, independent[::-1])
    stacked = tuple(np.stack(arrays) for arrays in zip(*trials, strict=True))
    support.assess_many("joint_center", stacked)
    calls = _counting_kernel_calls(monkeypatch)
    batch = support.assess_many("joint_center", stacked)
    assert batch[1].caveats and not batch[0].caveats
    assert calls.count("_frame_numbers") == 2


@pytest.mark.parametrize("wraps", [False, True])
def test_a_fit_on_a_refilled_buffer_inside_a_checked_call_reads_the_new_content(wraps):
    """An estimator registered from outside may, inside its own fit, fit a built-in method on
    trial after trial refilled into one buffer: each answer is the one the trial gets alone,
    never the sums an earlier content of the same memory left in the checked call. So too
    where it states the built-in fit as the one it wraps (``functools.wraps`` sets
    ``__wrapped__``): it is still the user's code, run before the checks' scope."""
    trials = [hinge(seed, 30.0, noise=1.0) for seed in range(2)]
    planar = registry.get("axis", "planar", checked=False)
    alone = [planar(trial).direction for trial in trials]
    assert not np.allclose(alone[0], alone[1])  # the two differ
    buffer = trials[0].copy()
    seen: list = []

    def fits_a_refilled_buffer(markers):
        for trial in trials:
            np.copyto(buffer, trial)
            seen.append(planar(buffer).direction)
        return planar(markers)

    if wraps:
        fits_a_refilled_buffer = functools.wraps(planar)(fits_a_refilled_buffer)
        assert not owncode.package_code(fits_a_refilled_buffer)
    registry.register("axis", "fits-a-refilled-buffer")(fits_a_refilled_buffer)
    try:
        registry.get("axis", "fits-a-refilled-buffer")(trials[0])
        registry.many("axis", "fits-a-refilled-buffer")(np.stack(trials))
    finally:
        registry.unregister("axis", "fits-a-refilled-buffer")
    assert len(seen) == 2 + 2 * 2
    for direction, expected in zip(seen, alone * 3, strict=True):
        np.testing.assert_array_equal(direction, expected)


def test_a_wrapping_users_fit_refilling_its_input_is_checked_on_the_data_given():
    """A user's fit wrapping a built-in one may write to the array it was handed after the
    built-in fit read it: it was handed a copy of its own, and the checks after the fit read
    the data as the caller gave them, as they do for any user's fit (``tests/test_fit_writes.py``),
    never the sums the built-in fit left on its copy."""
    trials = [hinge(seed, 30.0, noise=1.0) for seed in range(2)]
    planar = registry.get("axis", "planar", checked=False)

    def refills(markers):
        result = planar(markers)
        np.copyto(markers, trials[1])
        return result

    wrapped = functools.wraps(planar)(lambda markers: refills(markers))
    # The same wrapper (the built-in fit's attributes too) without ``__wrapped__``.
    plain = functools.wraps(planar)(lambda markers: refills(markers))
    del plain.__wrapped__
    results = []
    for name, fn in (("refills-plain", plain), ("refills-wrapped", wrapped)):
        registry.register("axis", name)(fn)
        try:
            results.append(registry.get("axis", name)(trials[0].copy()))
        finally:
            registry.unregister("axis", name)
    plain, wrapped_result = results
    assert wrapped_result.status == plain.status
    assert wrapped_result.diagnostics == plain.diagnostics
    np.testing.assert_array_equal(wrapped_result.direction, plain.direction)


def test_a_value_of_several_arrays_is_known_by_the_memory_of_each():
    counts: list = []

    def compute(arrays: tuple) -> float:
        counts.append(1)
        return float(sum(array.sum() for array in arrays))

    batch = np.arange(24.0).reshape(2, 2, 2, 3)
    with reuse.one_call():
        first = reuse.remembered("sum", (batch[0], batch[1]), compute)
        views = list(batch)  # other array objects over the same memory
        again = reuse.remembered("sum", (views[0], views[1]), compute)
        swapped = reuse.remembered("sum", (batch[1], batch[0]), compute)
        alone = reuse.remembered("sum", (batch[0],), compute)
    assert first == again == swapped == float(batch.sum())
    assert alone == float(batch[0].sum())
    assert len(counts) == 3  # the pair, the pair in the other order, the one array


def test_a_checked_analytic_centre_passes_over_its_relative_rotations_once(monkeypatch):
    """Its covariance, its anchor bias and its noise share read the same relative rotations of
    the poses: one compiled pass in the checked call, and the same numbers as the checks'
    own passes outside it."""
    rng = np.random.default_rng(5)
    trial = _kind_trial("joint_center", rng, 200, lambda shape: _noisy(rng, shape, 0.5))
    checked = registry.get("joint_center", "analytic")
    expected = checked(*trial)
    calls = _counting_kernel_calls(monkeypatch)
    result = checked(*trial)
    assert calls.count("_relative_rows_of") == 1
    assert result.diagnostics == expected.diagnostics
    assert result.status == expected.status


def test_an_array_asked_for_is_held_so_another_never_takes_its_identity():
    """Arrays made and dropped in turn inside one call (each perhaps where the one before
    was) are each read for their own values."""
    counts: list = []
    with reuse.one_call():
        for value in range(20):
            assert reuse.remembered("sum", np.full((2, 3), float(value)), _counting(counts)) == (
                6.0 * value
            )
    assert len(counts) == 20


def test_a_second_view_found_by_its_memory_is_held_too():
    """A view found by the memory another view of it was first asked for under is held as
    well: views of one row after another, each made, asked for and dropped in turn (each
    perhaps taking the identity of the one before), are each read for their own row's value,
    never the row an earlier view of that identity was."""
    counts: list = []
    batch = np.arange(60.0).reshape(10, 2, 3)
    with reuse.one_call():
        for row in range(len(batch)):
            reuse.remembered("sum", batch[row], _counting(counts))
            again = batch[row]  # another view of the same memory, found by it
            assert reuse.remembered("sum", again, _counting(counts)) == batch[row].sum()
            del again
    assert len(counts) == len(batch)
