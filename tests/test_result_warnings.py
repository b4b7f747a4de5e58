"""How a result's status gathers warnings (jointbench.estimators.results.with_warnings): each
once, in the order given, after the method's own status, and its diagnostics merged."""

import numpy as np

from jointbench.estimators.results import CenterResult, with_warnings


def _result(status: str = "ok", **diagnostics) -> CenterResult:
    return CenterResult(
        converged=True,
        iterations=1,
        status=status,
        method="LS",
        diagnostics=diagnostics,
        center=np.zeros(3),
    )


def test_warnings_replace_ok_once_each_in_order():
    noted = with_warnings(_result(a=1), ("too little motion", "bent", "too little motion"), {})
    assert noted.status == "warning: too little motion; warning: bent"
    assert noted.diagnostics == {"a": 1}


def test_warnings_follow_the_methods_status_and_a_warning_said_is_not_said_again():
    first = with_warnings(_result("max iterations reached"), ("bent",), {"b": 2})
    again = with_warnings(first, ("bent", "bent further", "ben"), {"b": 3, "c": 4})
    assert again.status == (
        "max iterations reached; warning: bent; warning: bent further; warning: ben"
    )
    assert again.diagnostics == {"b": 3, "c": 4}
    assert list(again.diagnostics) == ["b", "c"]
    assert first.diagnostics == {"b": 2}  # the result it was made from is unchanged


def test_numbers_alone_leave_the_status_as_it_is():
    result = _result("warning: bent", a=1)
    noted = with_warnings(result, (), {"z": 0.5})
    assert noted.status == "warning: bent" and noted.diagnostics == {"a": 1, "z": 0.5}
    assert noted.center is result.center and noted.converged is True
