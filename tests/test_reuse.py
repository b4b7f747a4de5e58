"""A value of a trial's frames that several stages of one checked call read is computed once in
the call (:mod:`jointbench.numerics.reuse`), and each stage's numbers are those it computes
alone."""

from __future__ import annotations

import numpy as np
import pytest
from test_axis_sd import hinge

from jointbench.estimators import axis, registry
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
    assert len(summed) == 1  # the fit's, read again by the self-check and the precision
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
