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
