"""A joint-centre estimator's predicted covariance, held to being one: given in full or not at
all by a trial that claims success, symmetric where the file also gives the entries below the
diagonal, and positive semi-definite; the centre's own and the one relative to the proximal
markers alike."""

from __future__ import annotations

import re

import numpy as np
import pandas as pd
import pytest

from jointbench.resultfiles.schema import (
    COVARIANCE_PSD_TOL,
    COVARIANCE_RTOL,
    check_covariances,
    check_estimates,
)
from jointbench.running.scoring import COVARIANCE_COLUMNS, COVARIANCE_MIRRORS

SOURCE = "results/estimates/hip/GM-C/n_frames-300.csv"


def _entries(matrix: np.ndarray, prefix: str = "") -> dict[str, float]:
    """The six distinct entries of a 3×3 matrix as ``cov_*`` columns, the upper triangle."""
    index = {"x": 0, "y": 1, "z": 2}
    return {
        f"{prefix}{name}": float(matrix[index[name[-2]], index[name[-1]]])
        for name in COVARIANCE_COLUMNS
    }


def _mirrors(matrix: np.ndarray, prefix: str = "") -> dict[str, float]:
    """The three entries below the diagonal as their mirror columns (``cov_yx``, …)."""
    index = {"x": 0, "y": 1, "z": 2}
    return {
        f"{prefix}{name}": float(matrix[index[name[-2]], index[name[-1]]])
        for name in COVARIANCE_MIRRORS
    }


def _table(*rows: dict, converged=True, status="ok") -> pd.DataFrame:
    """Estimates rows of trials 0, 1, … of method GM-C, each with the given columns."""
    return pd.DataFrame(
        [
            {
                "n_frames": 300,
                "trial": trial,
                "method": "GM-C",
                "center_x": 1.0,
                "center_y": 2.0,
                "center_z": 3.0,
                "converged": converged,
                "iterations": 3,
                "seconds": 1e-4,
                "status": status,
                **row,
            }
            for trial, row in enumerate(rows)
        ]
    )


def _spd(seed: int, scale: float = 1.0) -> np.ndarray:
    """A symmetric positive definite 3×3 matrix [mm²]."""
    a = np.random.default_rng(seed).normal(size=(3, 3))
    return scale * (a @ a.T + 0.1 * np.eye(3))


def _refused(table: pd.DataFrame, message: str) -> str:
    with pytest.raises(ValueError, match=re.escape(message)) as error:
        check_covariances(table, "joint_center", source=SOURCE)
    assert str(error.value).startswith(f"{SOURCE}: "), str(error.value)
    return str(error.value)


@pytest.mark.parametrize("prefix", ["", "proximal_"])
def test_a_positive_semi_definite_covariance_is_accepted(prefix):
    """Definite, singular (a zero variance along one direction), tiny and huge, with and
    without the mirror entries."""
    singular = np.diag([4.0, 1.0, 0.0])
    rotation = np.linalg.qr(np.random.default_rng(3).normal(size=(3, 3)))[0]
    turned = rotation @ singular @ rotation.T
    turned = 0.5 * (turned + turned.T)
    matrices = [_spd(0), _spd(1, 1e-12), _spd(2, 1e12), singular, turned, np.zeros((3, 3))]
    table = _table(*({**_entries(m, prefix), **_mirrors(m, prefix)} for m in matrices))
    check_covariances(table, "joint_center", source=SOURCE)
    check_covariances(table.drop(columns=list(_mirrors(singular, prefix))), "joint_center")


def test_a_trial_that_predicts_no_covariance_carries_nan_in_every_entry():
    """A method predicts none (NaN throughout, as the built-ins without one write it), or a
    failed trial carries NaN in some entries only: nothing to check."""
    nothing = dict.fromkeys(_entries(np.eye(3)), np.nan)
    check_covariances(_table(nothing, nothing), "joint_center", source=SOURCE)
    partial = {**_entries(np.eye(3)), "cov_xy": np.nan}
    failed = _table(partial, converged=False, status="error: singular")
    check_covariances(failed, "joint_center", source=SOURCE)


def test_rounding_is_not_a_fault():
    """A mirror off by rounding, and a smallest eigenvalue below 0 by rounding, are accepted."""
    matrix = _spd(4, 100.0)
    largest = np.abs(matrix).max()
    mirrors = _mirrors(matrix)
    mirrors["cov_zy"] += 0.5 * COVARIANCE_RTOL * largest
    check_covariances(_table({**_entries(matrix), **mirrors}), "joint_center", source=SOURCE)
    nearly = np.diag([5.0, 1.0, -0.5 * COVARIANCE_PSD_TOL * 5.0])
    check_covariances(_table(_entries(nearly)), "joint_center", source=SOURCE)


@pytest.mark.parametrize("prefix", ["", "proximal_"])
@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_a_trial_claiming_success_with_part_of_a_covariance_is_refused(prefix, value):
    good = _entries(_spd(5), prefix)
    bad = {**good, f"{prefix}cov_yz": value}
    message = _refused(
        _table(good, bad),
        f"method 'GM-C', trial 1: converged=True, status 'ok', but column "
        f"'{prefix}cov_yz' is {value!r} while {prefix}cov_xx",
    )
    assert "NaN in every entry when the method predicts none" in message


def test_infinity_in_every_entry_is_not_no_prediction():
    _refused(_table(dict.fromkeys(_entries(np.eye(3)), np.inf)), "'cov_xx' is inf")


def test_a_trial_that_claims_ok_by_status_alone_is_held_to_it():
    bad = {**_entries(np.eye(3)), "cov_zz": np.nan}
    _refused(_table(bad, converged=False, status="ok"), "converged=False, status 'ok', but")


@pytest.mark.parametrize("prefix", ["", "proximal_"])
@pytest.mark.parametrize("mirror", list(COVARIANCE_MIRRORS))
def test_an_asymmetric_covariance_is_refused(prefix, mirror):
    matrix = _spd(6)
    mirrors = _mirrors(matrix, prefix)
    mirrors[f"{prefix}{mirror}"] += 0.01
    entry = COVARIANCE_MIRRORS[mirror]
    _refused(
        _table(
            {**_entries(matrix, prefix), **_mirrors(matrix, prefix)},
            {**_entries(matrix, prefix), **mirrors},
        ),
        f"method 'GM-C', trial 1: column '{prefix}{mirror}' is "
        f"{mirrors[f'{prefix}{mirror}']!r}, but '{prefix}{entry}', which it mirrors, is "
        f"{_entries(matrix, prefix)[f'{prefix}{entry}']!r} (1 such rows)",
    )


def test_a_mirror_alone_is_refused():
    """cov_yx without the six: which matrix it belongs to is for nobody to guess."""
    _refused(_table({"cov_yx": 1.0}), "column 'cov_xx' is missing, but 'cov_yx' is given")


@pytest.mark.parametrize("prefix", ["", "proximal_"])
@pytest.mark.parametrize(
    "matrix",
    [
        np.diag([1.0, 2.0, -1e-3]),
        -np.eye(3),
        np.array([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
        np.diag([0.0, 0.0, -1e-300]),
    ],
    ids=["negative variance", "negative definite", "indefinite", "negative next to zero"],
)
def test_a_covariance_not_positive_semi_definite_is_refused(prefix, matrix):
    names = ", ".join(f"{prefix}{name}" for name in COVARIANCE_COLUMNS)
    _refused(
        _table(_entries(_spd(7), prefix), _entries(matrix, prefix)),
        f"method 'GM-C', trial 1: the predicted covariance in columns {names} is not positive "
        "semi-definite: its eigenvalues are ",
    )


def test_a_failed_trial_giving_a_full_matrix_has_it_checked():
    """A failed trial's finite centre and covariance are scored all the same: a matrix it
    gives in full must be a covariance."""
    _refused(
        _table(_entries(-np.eye(3)), converged=False, status="error: max iterations"),
        "trial 0: the predicted covariance",
    )


def test_other_kinds_are_not_checked_and_mirrors_must_be_numbers():
    """A centre file's columns named like a covariance are not scored, so not checked; a
    joint centre's mirror column of text is refused by name with the others."""
    table = _table(_entries(-np.eye(3)))
    check_covariances(table, "center", source=SOURCE)
    with pytest.raises(ValueError, match="column 'cov_zy' must be numeric"):
        check_estimates(
            table.assign(cov_zy="0"),
            kind="joint_center",
            condition_keys=["n_frames"],
            source=SOURCE,
        )


def test_a_mirror_left_blank_in_a_trial_claiming_success_is_refused():
    """The file gives the mirrors: a row that claims success gives them as well."""
    matrix = _spd(8)
    full = {**_entries(matrix), **_mirrors(matrix)}
    blank = {**full, "cov_zx": np.nan}
    _refused(
        _table(full, blank), "trial 1: converged=True, status 'ok', but column 'cov_zx' is nan"
    )
