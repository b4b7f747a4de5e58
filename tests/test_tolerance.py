"""Typed tolerances: each type's verdict and margin, and that a tolerance names one type."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy import special, stats

from jointbench.comparison.tolerance import binomial_interval, describe, evaluate, is_compared
from jointbench.configuration.config import MAX_TRIALS
from jointbench.running.scoring import CHI2_3DOF_95


@pytest.mark.parametrize(
    ("tolerance", "published", "measured", "holds", "margin"),
    [
        ({"abs": 2.0}, 10.0, 11.5, True, 0.5),
        ({"abs": 2.0}, 10.0, 12.5, False, -0.5),
        ({"rel": 0.25}, 8.0, 9.0, True, 1.0),
        ({"max_abs_rel": [2.0, 0.25]}, 4.0, 5.9, True, 0.1),
        ({"max_abs_rel": [2.0, 0.25]}, 40.0, 51.0, False, -1.0),
        ({"at_least": 0.8}, None, 0.9, True, 0.1),
        ({"at_least": 0.8}, None, 0.7, False, -0.1),
        ({"at_most": 0}, None, 0, True, 0.0),
        ({"at_most": 0}, None, 2, False, -2.0),
        ({"greater_than": [25, 60]}, None, [30, 61], True, 1.0),
        ({"greater_than": 0.55}, None, 0.55, False, 0.0),
        ({"less_than": 1.5}, None, 1.2, True, 0.3),
        ({"range": [0.8, 1.25]}, None, [0.9, 1.2], True, 0.05),
        ({"range": [0.8, 1.25]}, None, [0.9, 1.3], False, -0.05),
        ({"factor": 2}, 0.2, 0.3, True, 2 / 1.5 - 1),
        ({"factor": 2}, 0.2, 0.5, False, 2 / 2.5 - 1),
    ],
)
def test_verdict_and_margin(tolerance, published, measured, holds, margin):
    verdict = evaluate(tolerance, published, measured)
    assert verdict.holds is holds
    assert verdict.margin == pytest.approx(margin)


def test_nan_never_holds():
    assert not evaluate({"abs": 1.0}, 1.0, float("nan")).holds
    assert not evaluate({"at_least": 0.5}, None, [0.9, float("nan")]).holds


def test_binomial_counts_inside_and_outside():
    low, high = binomial_interval(30, 16 / 30)
    inside = evaluate({"binomial95": {"of_n": 30}}, [16], {"count": [low], "trials": [30]})
    outside = evaluate({"binomial95": {"of_n": 30}}, [16], {"count": [high + 1], "trials": [30]})
    assert inside.holds and inside.margin == 0
    assert not outside.holds and outside.margin == -1


# binomial_interval once called scipy.stats, which costs a second to import in every job that
# checks a tolerance or draws paper C's calibration; it now uses scipy.special. These tests hold
# it to the calls it replaced, count for count.
_TRIALS = [*range(61), 75, 100, 150, 200, 300, 600, 1000, 1200, 2000, 5000, MAX_TRIALS]
_SHARES = sorted({*np.linspace(0, 1, 201), *(k / 30 for k in range(31)), 1e-9, 1 - 1e-9})


@pytest.mark.parametrize("trials", _TRIALS)
def test_binomial_interval_is_scipy_stats_binom_ppf(trials):
    """``stats.binom(trials, p).ppf(0.025)`` and ``ppf(0.975)``, as tolerance.py called them."""
    ours = np.array([binomial_interval(trials, p) for p in _SHARES])
    theirs = stats.binom(trials, np.array(_SHARES)[:, None]).ppf([0.025, 0.975]).astype(int)
    np.testing.assert_array_equal(ours, theirs)


@given(st.integers(0, MAX_TRIALS), st.floats(0, 1))
def test_binomial_interval_is_scipy_stats_binom_ppf_anywhere(trials, share):
    ours = binomial_interval(trials, share)
    assert ours == tuple(int(k) for k in stats.binom(trials, share).ppf([0.025, 0.975]))


def test_the_calibration_band_is_the_one_scipy_stats_gave():
    """figures/paper_c.py's bounds on the share of trials inside the 95 % ellipsoid, for every
    number of trials a study may have."""
    trials = np.arange(1, MAX_TRIALS + 1)
    ours = np.array([binomial_interval(n, 0.95) for n in trials]) / trials[:, None]
    theirs = stats.binom(trials[:, None], 0.95).ppf([0.025, 0.975]) / trials[:, None]
    np.testing.assert_array_equal(ours, theirs)


def test_a_binomial_interval_needs_a_distribution():
    for trials, share in ((30, 1.5), (30, -0.1), (30, float("nan")), (-1, 0.5)):
        with pytest.raises(ValueError):
            binomial_interval(trials, share)


def test_all_needs_every_part_and_reads_named_parts():
    tolerance = {"all": [{"of": "share", "at_least": 0.68}, {"of": "gap", "at_most": 3.7}]}
    assert evaluate(tolerance, None, {"share": 0.9, "gap": 0.3}).holds
    verdict = evaluate(tolerance, None, {"share": 0.9, "gap": 26.6})
    assert not verdict.holds and verdict.margin == pytest.approx(3.7 - 26.6)
    assert "gap" in verdict.margin_text


@pytest.mark.parametrize("tolerance", [{}, {"abs": 1, "rel": 0.1}, {"roughly": 1}])
def test_a_tolerance_has_exactly_one_type(tolerance):
    with pytest.raises(ValueError, match="exactly one type"):
        evaluate(tolerance, 1.0, 1.0)


def test_shown_only_is_not_compared():
    assert not is_compared({"shown_only": True})
    with pytest.raises(ValueError, match="not compared"):
        evaluate({"shown_only": True}, 1.0, 1.0)
    assert describe({"shown_only": True}) == "none (shown beside ours)"


@given(st.floats(-1e3, 1e3), st.floats(0, 1e3), st.floats(-1e3, 1e3, allow_nan=False))
def test_abs_margin_is_the_distance_to_the_edge(published, width, measured):
    verdict = evaluate({"abs": width}, published, measured)
    assert verdict.margin == pytest.approx(width - abs(measured - published), abs=1e-9)
    assert verdict.holds == (abs(measured - published) <= width)


def test_a_measurement_of_the_wrong_length_is_refused():
    with pytest.raises(ValueError, match="lacks part"):
        evaluate({"binomial95": {"of_n": 30}}, [30, 16, 9], {"count": [], "trials": []})
    with pytest.raises(ValueError, match="lacks part"):
        evaluate({"greater_than": [25, 60]}, None, [30.0])


def test_the_written_out_chi_square_quantile_is_scipys_to_the_last_bit():
    assert CHI2_3DOF_95 == float(special.chdtri(3, 0.05))
    assert CHI2_3DOF_95 == pytest.approx(stats.chi2(3).ppf(0.95), rel=1e-15)
