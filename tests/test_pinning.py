"""The pins' comparison (:mod:`pinning`): words exactly, numbers (floats, counts, the numbers
written in a statement) to the agreement or to what rounding moved them."""

from __future__ import annotations

import numpy as np
import pytest
from pinning import assert_same, numbers, rounding_moves, words, written_numbers

PINNED = {
    "iterations": 112,
    "converged": True,
    "status": "warning: variance ratio 3.99, p = 1.1e-59, over 32 frames",
}


def test_a_statement_is_its_words_and_its_numbers():
    text = PINNED["status"]
    assert words(text) == "warning: variance ratio #, p = #, over # frames"
    assert written_numbers(text) == [3.99, 1.1e-59, 32.0]
    assert numbers(PINNED, "", {}) == {
        "/iterations": 112,
        "/status#0": 3.99,
        "/status#1": 1.1e-59,
        "/status#2": 32.0,
    }


@pytest.mark.parametrize(
    "changed",
    [
        {"iterations": 111},
        {"iterations": 112.0},
        {"converged": 1},
        {"status": "warning: variance ratio 3.97, p = 1.1e-59, over 32 frames"},
        {"status": "warning: variance ratio 3.99, p = 1.1e-59, over 31 frames"},
        {"status": "warning: variance ratio 3.99, p = 1.1e-59 over 32 frames"},
        {"status": "warning: variance ratio 3.99, p = 1.1e-59, over 32 frames; more"},
    ],
)
def test_a_changed_word_count_or_written_number_fails_where_rounding_did_not_move_it(changed):
    with pytest.raises(AssertionError):
        assert_same({**PINNED, **changed}, PINNED, "", {})


def test_a_count_or_written_number_that_rounding_moved_agrees_to_ten_times_the_move():
    moved = {"/iterations": 1.0, "/status#0": 0.02}
    now = {**PINNED, "iterations": 111, "status": PINNED["status"].replace("3.99", "3.97")}
    assert_same(now, PINNED, "", moved)
    with pytest.raises(AssertionError):
        assert_same({**now, "iterations": 100}, PINNED, "", moved)
    with pytest.raises(AssertionError):
        assert_same({**now, "status": PINNED["status"].replace("3.99", "3.7")}, PINNED, "", moved)
    # Rounding moves the numbers, never the words around them.
    with pytest.raises(AssertionError):
        assert_same({**now, "status": now["status"].replace("ratio", "ratios")}, PINNED, "", moved)


def _statement(method: str, markers: tuple[np.ndarray, ...], options: dict) -> dict:
    """A stand-in for a checked call whose words depend on the last bit of its input."""
    value = float(markers[0][0])
    words_now = "above" if value > 1.0 else "below"
    return {"one": [{"status": f"{words_now} by {value - 1.0:.3g}", "iterations": 3}]}


def test_rounding_that_changes_a_statements_words_stops_the_pin_from_being_written():
    cases = {"edge": ((np.array([1.0]),), {})}
    held = {"edge": {"m": _statement("m", (np.array([1.0]),), {})}}
    with pytest.raises(AssertionError, match="rounding changes its words"):
        rounding_moves(held, cases, ("m",), _statement)


@pytest.mark.parametrize(
    ("pinned", "changed"),
    [
        # A hyphen between a word and a number is a word, not the number's sign.
        ("the frame-0 poses", "the frame0 poses"),
        ("gauss-markov-frame0", "gauss-markov-frame-0"),
        ("the lag-1 autocorrelation", "the lag+1 autocorrelation"),
        ("a range of 0.5-1 mm", "a range of 0.5+1 mm"),
        ("3+3 frames", "3-3 frames"),
        # A point after a number that no digit follows ends the sentence.
        ("stopped at iteration 2.", "stopped at iteration 2"),
    ],
)
def test_a_changed_word_next_to_a_written_number_fails(pinned, changed):
    with pytest.raises(AssertionError):
        assert_same({"status": changed}, {"status": pinned}, "", {})


@pytest.mark.parametrize(
    ("text", "written", "held"),
    [
        ("the lag-1 autocorrelation", "the lag-# autocorrelation", [1.0]),
        ("below -0.36, +2 and (-5)", "below #, # and (#)", [-0.36, 2.0, -5.0]),
        ("0.5-1 mm", "#-# mm", [0.5, 1.0]),
        ("1e6 mm, 12mm, 2.5E-3", "# mm, #mm, #", [1e6, 12.0, 2.5e-3]),
        ("7,245 frames", "#,# frames", [7.0, 245.0]),
        ("at iteration 2.", "at iteration #.", [2.0]),
        ("p = nan, ratio inf", "p = nan, ratio inf", []),
    ],
)
def test_written_numbers_and_the_words_around_them(text, written, held):
    assert words(text) == written
    assert written_numbers(text) == held


def _warned(method: str, markers: tuple[np.ndarray, ...], options: dict) -> dict:
    """A stand-in for a checked call that warns, and says it did not converge, where the last
    bit of its input puts it above 1."""
    above = float(markers[0][0]) > 1.0
    warnings = ["the fit is above"] if above else []
    return {"one": [{"warnings": warnings, "converged": not above, "iterations": 3}]}


def test_rounding_that_adds_a_warning_or_flips_a_flag_stops_the_pin_from_being_written():
    cases = {"edge": ((np.array([1.0]),), {})}
    held = {"edge": {"m": _warned("m", (np.array([1.0]),), {})}}
    with pytest.raises(AssertionError, match="rounding changes its words"):
        rounding_moves(held, cases, ("m",), _warned)


@pytest.mark.parametrize(
    ("pinned", "now"),
    [
        ("p = 5e-10", "p = 1e-257"),
        ("variance 7e-10 mm^2", "variance 3e-12 mm^2"),
        ("p = 1.9e-94", "p = 0"),
        ("p = 0", "p = 1e-300"),
        ("p = 0.5", "p = 0.5001"),
    ],
)
def test_a_small_written_number_agrees_relative_to_its_size(pinned, now):
    """A number written in a statement carries its own significant digits: 1e-257 is not
    5e-10, however small both are beside 1."""
    with pytest.raises(AssertionError):
        assert_same({"status": now}, {"status": pinned}, "", {})


@pytest.mark.parametrize("text", ["p = 5e-10", "p = 1.9e-94, sd 3e-12 mm", "p = 0", "p = -0.0"])
def test_a_written_number_identical_to_its_pin_agrees(text):
    assert_same({"status": text}, {"status": text}, "", {})


def test_a_small_written_number_that_rounding_moved_agrees_to_ten_times_the_move():
    moved = {"/status#0": 1e-12}
    assert_same({"status": "p = 5.05e-10"}, {"status": "p = 5e-10"}, "", moved)
    with pytest.raises(AssertionError):
        assert_same({"status": "p = 5.2e-10"}, {"status": "p = 5e-10"}, "", moved)


def _small_statement(method: str, markers: tuple[np.ndarray, ...], options: dict) -> dict:
    """A stand-in for a checked call that writes a small number rounding moves relatively by
    about 1e-8, and a float beside it that it moves alike."""
    value = float(markers[0][0]) * (1.0 + 1e-8 * (float(markers[0][0]) != 1.0))
    return {"one": [{"status": f"p = {5e-10 * value!r}", "cost": 5e-10 * value}]}


def test_rounding_moves_of_a_small_written_number_are_measured_relative_to_its_size():
    """Rounding's move of a small written number is measured against the number's own size;
    a pinned float's, as the agreement allows it, against at least one."""
    cases = {"edge": ((np.array([1.0]),), {})}
    held = {"edge": {"m": _small_statement("m", (np.array([1.0]),), {})}}
    moved = rounding_moves(held, cases, ("m",), _small_statement)
    assert list(moved) == ["/edge/m/one[0]/status#0"]
    assert moved["/edge/m/one[0]/status#0"] == pytest.approx(5e-18, rel=1e-3)
