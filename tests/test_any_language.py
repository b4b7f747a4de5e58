"""Estimators in any language: the CSV interchange, the C worked example run as a rule with no
Python of its own, external rules that serve every study they are listed for and ignore the
others, and the README's template as the file the workflow ships."""

from __future__ import annotations

import os
import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow.parquet as pq
import pytest
import yaml
from workflow_copy import ROOT, copy_workflow, run_snakemake, running_in

from jointbench.resultfiles.interchange import (
    DATASET_COLUMNS,
    check_dataset_csv,
    read_estimates_csv,
    write_dataset_csv,
)
from jointbench.resultfiles.parquet import read_source, write_dataset, write_table
from jointbench.resultfiles.schema import check_estimates
from jointbench.running.collected import collect, summarise_estimates
from jointbench.running.placement import dataset_placements, write_placements
from jointbench.simulate import Trials


def _dataset(tmp_path, segments=("moving",)):
    rng = np.random.default_rng(7)
    trials = Trials(
        segments={name: rng.normal(size=(2, 5, 3, 3)) * 10 for name in segments},
        truth={"center": [1.0, 2.0, 3.0]},
    )
    path = tmp_path / "marker_set-M__rom_deg-5__noise_mm-1.0.parquet"
    condition = {"marker_set": "M", "rom_deg": 5, "noise_mm": 1.0}
    write_dataset(path, trials, study="cmc", condition=condition)
    return path, trials


def test_the_dataset_csv_holds_every_sample_to_the_last_bit(tmp_path):
    path, trials = _dataset(tmp_path, segments=("proximal", "distal"))
    write_dataset_csv(path, tmp_path / "markers.csv")
    lines = (tmp_path / "markers.csv").read_text().splitlines()
    assert lines[0] == ",".join(DATASET_COLUMNS)
    frame = pd.read_csv(tmp_path / "markers.csv")
    assert len(frame) == 2 * 2 * 5 * 3
    # Trial by trial, each segment's frames in the dataset's segment order.
    first = frame[frame["trial"] == 0]
    assert list(dict.fromkeys(first["segment"])) == ["proximal", "distal"]
    for name, markers in trials.segments.items():
        rows = frame[frame["segment"] == name].sort_values(["trial", "frame", "marker"])
        assert np.array_equal(rows[["x", "y", "z"]].to_numpy(), markers.reshape(-1, 3))
    assert "center" not in (tmp_path / "markers.csv").read_text()  # the truth stays out


def _cut_at_a_lines_end(text: str) -> str:
    """The first three quarters of ``text``'s lines, the last one whole: of two trials, the
    second keeps about half its frames, still enough for a fit."""
    lines = text.splitlines(keepends=True)
    return "".join(lines[: 3 * len(lines) // 4])


@pytest.mark.parametrize(
    ("cut", "ending"),
    [
        (_cut_at_a_lines_end, "ending with a newline;"),
        (lambda text: text[: len(text) // 2], "ends without one"),
        (lambda text: text[:-1], "ends without one"),
        (lambda text: "", "0 lines ending with a newline;"),
    ],
    ids=["at a line's end", "inside a line", "its last newline", "to nothing"],
)
def test_a_markers_csv_cut_short_is_refused_by_name(tmp_path, cut, ending):
    """A program given a cut file fits the frames that are left and reports success: the
    file is checked before its estimates are used, wherever the cut falls."""
    path, _ = _dataset(tmp_path, segments=("proximal", "distal"))
    markers = tmp_path / "markers.csv"
    write_dataset_csv(path, markers)
    check_dataset_csv(markers, path)
    left = cut(markers.read_text())
    markers.write_text(left)
    with pytest.raises(ValueError) as error:
        check_dataset_csv(markers, path)
    message = str(error.value)
    assert message.startswith(f"{markers}: {left.count(chr(10))} lines ending with a newline")
    assert f"the markers CSV of {path} has 61 (a header and one per marker sample)" in message
    assert ending in message and "cut short" in message and "--forcerun" in message


def test_a_markers_csv_grown_by_a_line_is_refused(tmp_path):
    path, _ = _dataset(tmp_path)
    markers = tmp_path / "markers.csv"
    write_dataset_csv(path, markers)
    with open(markers, "a") as stream:
        stream.write("1,moving,4,2,0,0,0\n")
    with pytest.raises(ValueError, match=re.escape(f"{markers}: 32 lines ending with a newline;")):
        check_dataset_csv(markers, path)


def test_a_markers_csv_changed_in_place_is_refused_naming_the_line(tmp_path):
    """A program that rewrites the markers CSV it read (normalising it, or spoiling it for the
    estimators that read it after): as many lines, other markers. The estimates of every
    program that read it are refused, naming the file and the first line that differs."""
    path, _ = _dataset(tmp_path)
    markers = tmp_path / "markers.csv"
    write_dataset_csv(path, markers)
    lines = markers.read_text().splitlines(keepends=True)
    fields = lines[5].split(",")
    fields[4] = "0"  # one sample's x, every line still in place
    lines[5] = ",".join(fields)
    markers.write_text("".join(lines))
    with pytest.raises(ValueError, match=re.escape(f"{markers}: line 6 is not the line")) as error:
        check_dataset_csv(markers, path)
    # Either file may have changed (the blind copy, rewritten by a program that read it after
    # the CSV was made): the command writes both anew, the blind copy first.
    assert "the CSV or the blind copy it was made from was changed" in str(error.value)
    assert f"--forcerun {path}" in str(error.value)


def _estimates_csv(tmp_path, body: str):
    folder = tmp_path / "estimates" / "LS-C"
    folder.mkdir(parents=True)
    path = folder / "marker_set-M__rom_deg-5__noise_mm-1.0.csv"
    header = "trial,center_x,center_y,center_z,converged,iterations,seconds,status\n"
    path.write_text(header + body)
    return path


def test_estimates_csv_gain_their_condition_and_method(tmp_path):
    dataset, _ = _dataset(tmp_path)
    source = _estimates_csv(
        tmp_path, "0,1.5,2,3,true,0,1e-5,ok\n1,nan,nan,nan,false,0,1e-5,error: singular\n"
    )
    read_estimates_csv(source, dataset, tmp_path / "out.parquet")
    table = pq.read_table(tmp_path / "out.parquet").to_pandas()
    assert list(table["method"]) == ["LS-C", "LS-C"]
    assert list(table["rom_deg"]) == [5, 5] and list(table["marker_set"]) == ["M", "M"]
    assert table["converged"].tolist() == [True, False]
    assert np.isnan(table.loc[1, "center_x"]) and table.loc[0, "center_x"] == 1.5


@pytest.mark.parametrize(
    "body, message",
    [
        ("0,1,2,3,maybe,0,1e-5,ok\n", "'converged' must hold true/false or 1/0"),
        ("0,1,2,3,2,0,1e-5,ok\n", "'converged' must hold true/false or 1/0"),
    ],
)
def test_a_bad_estimates_csv_is_refused_by_name(tmp_path, body, message):
    dataset, _ = _dataset(tmp_path)
    source = _estimates_csv(tmp_path, body)
    with pytest.raises(ValueError, match=re.escape(message)) as error:
        read_estimates_csv(source, dataset, tmp_path / "out.parquet")
    assert str(source) in str(error.value)


def test_an_estimates_csv_without_status_is_refused(tmp_path):
    dataset, _ = _dataset(tmp_path)
    path = tmp_path / "LS-C" / "c.csv"
    path.parent.mkdir()
    path.write_text(
        "trial,center_x,center_y,center_z,converged,iterations,seconds\n0,1,2,3,1,0,0\n"
    )
    with pytest.raises(ValueError, match="missing column 'status'"):
        read_estimates_csv(path, dataset, tmp_path / "out.parquet")


def test_an_estimates_csv_giving_a_column_twice_is_refused_by_name(tmp_path):
    """Two centre_x columns: which one would be scored is for nobody to guess."""
    dataset, _ = _dataset(tmp_path)
    path = tmp_path / "LS-C" / "c.csv"
    path.parent.mkdir()
    header = "trial,center_x,center_y,center_z,converged,iterations,seconds,status,center_x\n"
    path.write_text(header + "0,1,2,3,1,0,0,ok,9\n1,1,2,3,1,0,0,ok,9\n")
    with pytest.raises(ValueError, match="column 'center_x' appears more than once") as error:
        read_estimates_csv(path, dataset, tmp_path / "out.parquet")
    assert str(path) in str(error.value)


def test_a_condition_whose_every_trial_failed_is_read_as_failed_trials(tmp_path):
    """NaN, NA or nothing in every row: CSV gives such a column no type of its own, yet the
    estimate is a number column, so the file is collected as the failures it reports."""
    dataset, _ = _dataset(tmp_path)
    source = _estimates_csv(
        tmp_path, "0,nan,nan,nan,false,0,1e-5,error: singular\n1,NA,,-nan,0,0,1e-5,\n"
    )
    read_estimates_csv(source, dataset, tmp_path / "out.parquet")
    table = pq.read_table(tmp_path / "out.parquet")
    keys = ["marker_set", "rom_deg", "noise_mm"]
    check_estimates(table, kind="center", condition_keys=keys, method="LS-C")
    frame = table.to_pandas()
    assert frame[["center_x", "center_y", "center_z"]].isna().all(axis=None)
    assert not frame["converged"].any() and frame["status"].tolist() == ["error: singular", ""]


def test_an_estimates_csv_without_rows_is_refused(tmp_path):
    dataset, _ = _dataset(tmp_path)
    source = _estimates_csv(tmp_path, "")
    with pytest.raises(ValueError, match="no rows; the dataset has 2 trials") as error:
        read_estimates_csv(source, dataset, tmp_path / "out.parquet")
    assert str(source) in str(error.value)


def test_an_estimates_csv_not_in_utf8_is_refused_by_name(tmp_path):
    """A status written in a legacy encoding (Latin-1 'échec'): text in a results file is
    UTF-8, and the refusal names the CSV and the trial rather than a byte offset alone."""
    dataset, _ = _dataset(tmp_path)
    source = _estimates_csv(tmp_path, "0,1.5,2,3,true,0,1e-5,ok\n")
    with open(source, "ab") as stream:
        stream.write("1,nan,nan,nan,false,0,1e-5,échec\n".encode("latin-1"))
    message = "column 'status' is not UTF-8 text in the row of trial 1"
    with pytest.raises(ValueError, match=re.escape(message)) as error:
        read_estimates_csv(source, dataset, tmp_path / "out.parquet")
    assert str(error.value).startswith(f"{source}: "), str(error.value)


# ------------------------------- a contestant's mistakes, named in the CSV the contestant wrote

_ROW_HEADER = "trial,center_x,center_y,center_z,converged,iterations,seconds,status"
_GOOD_ROWS = ("0,1.5,2,3,true,3,1e-5,ok", "1,1,2.5,3,true,4,1e-5,ok")


def _lines(rows) -> str:
    """The text of a CSV whose ``rows`` (header first) each end with a newline, as a program
    printing one line per row writes it."""
    return "".join(f"{row}\n" for row in rows)


# Each deliberate mistake: the CSV's text (header and rows) and what the refusal must name.
_CENTER_MISTAKES = {
    "cut in a row": (
        "\n".join([_ROW_HEADER, _GOOD_ROWS[0], "1,1,2"]),
        "cannot be read as CSV",
    ),
    "cut after a row": (_lines([_ROW_HEADER, _GOOD_ROWS[0]]), "missing trials: 1"),
    # The writer stopped inside its last row's last value: 3.25 would be read as 3.2.
    "cut inside the last value": (
        "trial,converged,iterations,seconds,status,center_x,center_y,center_z\n"
        "0,true,3,1e-5,ok,1.5,2,3.25\n1,true,4,1e-5,ok,1,2.5,3.2",
        "line 3, the last, ends without a newline",
    ),
    "missing column": (
        "trial,center_x,center_y,converged,iterations,seconds,status\n"
        "0,1,2,true,0,0,ok\n1,1,2,true,0,0,ok\n",
        "missing column 'center_z'",
    ),
    # Semicolons, as a spreadsheet set to a decimal comma writes: one column, named by the
    # whole header, and the message says so rather than that "trial" is missing alone.
    "semicolons": (
        _lines(row.replace(",", ";") for row in [_ROW_HEADER, *_GOOD_ROWS]),
        "missing column 'trial': the header is one column, 'trial;center_x;center_y;",
    ),
    "missing status": (
        "trial,center_x,center_y,center_z,converged,iterations,seconds\n0,1,2,3,1,0,0\n",
        "missing column 'status'",
    ),
    "extra trial": (
        _lines([_ROW_HEADER, *_GOOD_ROWS, "2,1,2,3,true,0,0,ok"]),
        "trials not in the dataset: 2",
    ),
    "missing trial": (_lines([_ROW_HEADER, _GOOD_ROWS[1]]), "missing trials: 0"),
    "duplicate trial": (
        _lines([_ROW_HEADER, *_GOOD_ROWS, _GOOD_ROWS[1]]),
        "trials listed more than once: 1",
    ),
    "trial not a whole number": (
        _lines([_ROW_HEADER, _GOOD_ROWS[0], "1.5,1,2,3,true,0,0,ok"]),
        "column 'trial' must be integer",
    ),
    "wrong condition value": (
        _lines([f"{_ROW_HEADER},rom_deg", *(f"{row},999" for row in _GOOD_ROWS)]),
        "column 'rom_deg' must be the dataset's 5 (int) in every row, got 999 (int)",
    ),
    "wrong method": (
        _lines([f"{_ROW_HEADER},method", *(f"{row},LS" for row in _GOOD_ROWS)]),
        "column 'method' must be 'LS-C' in every row, got ['LS']",
    ),
    "non-numeric value": (
        _lines([_ROW_HEADER, _GOOD_ROWS[0], "1,1,two,3,true,0,0,ok"]),
        "column 'center_y' must be numeric, got large_string; the row of trial 1 holds 'two'",
    ),
    "iterations left empty": (
        _lines([_ROW_HEADER, _GOOD_ROWS[0], "1,1,2,3,true,,0,ok"]),
        "column 'iterations' must be integer, got double; the row of trial 1 holds nothing",
    ),
    "trial a word": (
        _lines([_ROW_HEADER, _GOOD_ROWS[0], "one,1,2,3,true,0,0,ok"]),
        "column 'trial' must be integer, got large_string; the row holds 'one'",
    ),
    "bad converged": (
        _lines([_ROW_HEADER, _GOOD_ROWS[0], "1,1,2,3,maybe,0,0,ok"]),
        "'converged' must hold true/false or 1/0",
    ),
    "claims ok with a NaN estimate": (
        _lines([_ROW_HEADER, _GOOD_ROWS[0], "1,nan,2,3,true,0,0,ok"]),
        "method 'LS-C', trial 1: converged=True, status 'ok', but the estimate is not finite",
    ),
    "negative error": (
        _lines([f"{_ROW_HEADER},error_mm", f"{_GOOD_ROWS[0]},-1", f"{_GOOD_ROWS[1]},0.5"]),
        "trial 0: column 'error_mm' is -1.0",
    ),
    "negative seconds": (
        _lines([_ROW_HEADER, _GOOD_ROWS[0], "1,1,2,3,true,0,-0.5,ok"]),
        "trial 1: column 'seconds' is -0.5, below 0",
    ),
    # A comma ending every line, as a loop printing "value," writes: a column without a name.
    "trailing comma": (
        _lines([f"{_ROW_HEADER},", *(f"{row}," for row in _GOOD_ROWS)]),
        "column 9 has no name (a comma ending the header line?)",
    ),
    # An empty cell says neither success nor failure: the row would be scored as neither.
    "converged left empty": (
        _lines([_ROW_HEADER, _GOOD_ROWS[0], "1,1,2.5,3,,4,1e-5,ok"]),
        "column 'converged' is empty in the row of trial 1 (1 such rows)",
    ),
    "converged left empty in a failed row": (
        _lines([_ROW_HEADER, _GOOD_ROWS[0], "1,nan,nan,nan,,4,1e-5,"]),
        "column 'converged' is empty in the row of trial 1 (1 such rows)",
    ),
    "converged empty in every row": (
        _lines([_ROW_HEADER, "0,1,2,3,,0,0,ok", "1,1,2,3,,0,0,ok"]),
        "column 'converged' is empty in the row of trial 0 (2 such rows)",
    ),
    "converged 1/0 with a gap": (
        _lines([_ROW_HEADER, "0,1,2,3,1,0,0,ok", "1,1,2,3,,0,0,ok"]),
        "column 'converged' is empty in the row of trial 1 (1 such rows)",
    ),
    # An axis study's score in a centre's file: not computed for it, so never checked.
    "another kind's score": (
        _lines([f"{_ROW_HEADER},error_deg", f"{_GOOD_ROWS[0]},0", f"{_GOOD_ROWS[1]},0"]),
        "column 'error_deg' is a score the benchmark computes for axis estimates",
    ),
}


def _hip_dataset(tmp_path):
    """A two-segment condition of the ``hip`` study, two trials, the true centre (1, 2, 3)."""
    rng = np.random.default_rng(11)
    trials = Trials(
        segments={name: rng.normal(size=(2, 5, 3, 3)) * 10 for name in ("proximal", "distal")},
        truth={"center": [1.0, 2.0, 3.0]},
    )
    path = tmp_path / "n_frames-5.parquet"
    write_dataset(path, trials, study="hip", condition={"n_frames": 5})
    return path


_COV_HEADER = f"{_ROW_HEADER},cov_xx,cov_xy,cov_xz,cov_yy,cov_yz,cov_zz"
_GOOD_COV = ("4,1,0,3,0.5,2", "2,0,0,2,0,2")
_HIP_MISTAKES = {
    "asymmetric covariance": (
        _lines(
            [
                f"{_COV_HEADER},cov_yx",
                f"{_GOOD_ROWS[0]},{_GOOD_COV[0]},1",
                f"{_GOOD_ROWS[1]},{_GOOD_COV[1]},0.25",
            ]
        ),
        "method 'GM-C', trial 1: column 'cov_yx' is 0.25, but 'cov_xy', which it mirrors, is 0.0",
    ),
    "covariance not positive semi-definite": (
        _lines([_COV_HEADER, f"{_GOOD_ROWS[0]},{_GOOD_COV[0]}", f"{_GOOD_ROWS[1]},1,2,0,1,0,1"]),
        "method 'GM-C', trial 1: the predicted covariance in columns cov_xx, cov_xy, cov_xz, "
        "cov_yy, cov_yz, cov_zz is not positive semi-definite: its eigenvalues are -1, 1, 3",
    ),
    "NaN covariance entry in an ok row": (
        _lines([_COV_HEADER, f"{_GOOD_ROWS[0]},4,1,0,3,nan,2", f"{_GOOD_ROWS[1]},{_GOOD_COV[1]}"]),
        "method 'GM-C', trial 0: converged=True, status 'ok', but column 'cov_yz' is nan",
    ),
    "infinite covariance in an ok row": (
        _lines([_COV_HEADER, f"{_GOOD_ROWS[0]},{_GOOD_COV[0]}", f"{_GOOD_ROWS[1]},inf,0,0,2,0,2"]),
        "method 'GM-C', trial 1: converged=True, status 'ok', but column 'cov_xx' is inf",
    ),
    "covariance column missing": (
        _lines(
            [
                _COV_HEADER.removesuffix(",cov_zz"),
                f"{_GOOD_ROWS[0]},4,1,0,3,0.5",
                f"{_GOOD_ROWS[1]},2,0,0,2,0",
            ]
        ),
        "column 'cov_zz' is missing, but 'cov_xx' is given",
    ),
    "proximal covariance not positive semi-definite": (
        _lines(
            [
                f"{_ROW_HEADER},proximal_center_x,proximal_center_y,proximal_center_z,"
                + ",".join(f"proximal_cov_{e}" for e in ("xx", "xy", "xz", "yy", "yz", "zz")),
                f"{_GOOD_ROWS[0]},1,2,3,{_GOOD_COV[0]}",
                f"{_GOOD_ROWS[1]},1,2,3,-1,0,0,2,0,2",
            ]
        ),
        "method 'GM-C', trial 1: the predicted covariance in columns proximal_cov_xx",
    ),
    # A centre's score in a joint centre's file: a study running both kinds (hip_sta) would
    # collect it beside the benchmark's own.
    "a centre's score": (
        _lines([f"{_ROW_HEADER},radius_error_mm", f"{_GOOD_ROWS[0]},0", f"{_GOOD_ROWS[1]},0"]),
        "column 'radius_error_mm' is a score the benchmark computes for center estimates",
    ),
}


def _contestant(tmp_path, study: str, method: str, text: str):
    """The estimates CSV ``text`` of ``method`` for the one condition of a ``study`` (``cmc``
    or ``hip``) written where the workflow asks for it, converted as the workflow converts it,
    then collected; the CSV's path, the dataset's and the converted file's."""
    dataset = _dataset(tmp_path)[0] if study == "cmc" else _hip_dataset(tmp_path)
    csv = tmp_path / "estimates" / study / method / f"{dataset.stem}.csv"
    csv.parent.mkdir(parents=True)
    csv.write_text(text)
    converted = csv.with_suffix(".parquet")
    read_estimates_csv(csv, dataset, converted)
    # Its blind copy's placements: the answers are mapped back with them before scoring.
    placements = tmp_path / "placements" / dataset.name
    write_placements(placements, dataset_placements(dataset, base_seed=1))
    collect(study, [converted], str(tmp_path / "collected.parquet"), [dataset], None, [placements])
    return csv, dataset, converted


@pytest.mark.parametrize(
    ("study", "method", "mistake"),
    [
        *(("cmc", "LS-C", name) for name in _CENTER_MISTAKES),
        *(("hip", "GM-C", name) for name in _HIP_MISTAKES),
    ],
    ids=[*_CENTER_MISTAKES, *_HIP_MISTAKES],
)
def test_a_contestants_mistake_is_named_in_the_csv_it_wrote(tmp_path, study, method, mistake):
    """Converted and collected as the workflow does it: whichever step refuses the file, the
    message names the CSV the program wrote, which its author can correct, not the
    intermediate estimates file made from it, and what is wrong there."""
    text, message = {**_CENTER_MISTAKES, **_HIP_MISTAKES}[mistake]
    csv = tmp_path / "estimates" / study / method
    with pytest.raises(ValueError, match=re.escape(message)) as error:
        _contestant(tmp_path, study, method, text)
    assert str(error.value).startswith(f"{csv}{os.sep}"), str(error.value)
    assert ".csv" in str(error.value).split(":")[0] and ".parquet:" not in str(error.value)
    assert not (tmp_path / "collected.parquet").exists()


def test_a_good_contestant_is_collected_with_its_predicted_covariance(tmp_path):
    """Mirror entries equal to theirs, a failed trial carrying NaN: collected and scored."""
    text = _lines(
        [
            f"{_COV_HEADER},cov_yx,cov_zx,cov_zy",
            f"{_GOOD_ROWS[0]},{_GOOD_COV[0]},1,0,0.5",
            "1,nan,nan,nan,false,9,1e-5,error: singular,nan,nan,nan,nan,nan,nan,nan,nan,nan",
        ]
    )
    csv, _, converted = _contestant(tmp_path, "hip", "GM-C", text)
    assert read_source(converted) == str(csv)
    collected = pd.read_parquet(tmp_path / "collected.parquet")
    assert collected["converged"].tolist() == [True, False]
    assert collected.loc[0, "sqrt_trace_cov_mm"] == pytest.approx(3.0)
    assert np.isnan(collected.loc[1, "sqrt_trace_cov_mm"])


def test_a_column_two_files_give_as_other_kinds_of_value_is_refused_naming_both(tmp_path):
    """A column of the contestant's own beside one of the same name another estimator gives
    (LM's ``f1_mm2``), text in one file and numbers in the other: the collected table cannot
    hold both, and the refusal names the column and both files, not Arrow's conversion."""
    dataset, _ = _dataset(tmp_path)
    placements = tmp_path / "placements" / dataset.name
    write_placements(placements, dataset_placements(dataset, base_seed=1))
    converted = []
    for method, value in (("LM-C", "1.5"), ("MY-C", "small")):
        csv = tmp_path / "estimates" / "cmc" / method / f"{dataset.stem}.csv"
        csv.parent.mkdir(parents=True)
        csv.write_text(_lines([f"{_ROW_HEADER},f1_mm2", *(f"{row},{value}" for row in _GOOD_ROWS)]))
        read_estimates_csv(csv, dataset, csv.with_suffix(".parquet"))
        converted.append(csv.with_suffix(".parquet"))
    first, second = (path.with_suffix(".csv") for path in converted)
    message = f"{second}: column 'f1_mm2' holds text, but {first} gives it numbers"
    with pytest.raises(ValueError, match=re.escape(message)):
        collect("cmc", converted, str(tmp_path / "c.parquet"), [dataset], None, [placements])
    assert not (tmp_path / "c.parquet").exists()


def test_the_summary_names_the_csv_too(tmp_path):
    """An estimator's summary, made apart from collect, checks the same and names the CSV."""
    text, message = _CENTER_MISTAKES["missing trial"]
    with pytest.raises(ValueError):
        _contestant(tmp_path, "cmc", "LS-C", text)
    csv = next((tmp_path / "estimates").rglob("*.csv"))
    dataset = tmp_path / f"{csv.stem}.parquet"
    with pytest.raises(ValueError, match=re.escape(f"{csv}: {message}")):
        summarise_estimates("cmc", [str(csv.with_suffix(".parquet"))], "s.csv", [dataset])


def test_a_file_written_as_parquet_is_named_itself(tmp_path):
    """An estimator that writes its estimates file itself converts nothing: the file is the
    source, and it is what a refusal names."""
    dataset, _ = _dataset(tmp_path)
    path = tmp_path / "estimates" / "cmc" / "LS-P" / f"{dataset.stem}.parquet"
    frame = pd.DataFrame(
        {
            "marker_set": "M",
            "rom_deg": 5,
            "noise_mm": 1.0,
            "trial": [1],
            "method": "LS-P",
            **{c: [1.0] for c in ("center_x", "center_y", "center_z")},
            "converged": True,
            "iterations": 0,
            "seconds": 0.0,
            "status": "ok",
        }
    )
    write_table(frame, path)
    assert read_source(path) == str(path)
    with pytest.raises(ValueError, match=re.escape(f"{path}: missing trials: 0")):
        collect("cmc", [path], str(tmp_path / "collected.parquet"), [dataset])


def _overlay(tmp_path, **cmc) -> str:
    defaults = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
    studies = {name: {"enabled": False} for name in defaults["studies"] if name != "cmc"}
    studies["cmc"] = {
        "trials": 2,
        "grid": {"marker_set": ["M"], "rom_deg": [15], "noise_mm": [0.0, 1.0]},
        **cmc,
    }
    path = tmp_path / "overlay.yaml"
    path.write_text(yaml.safe_dump({"studies": studies}))
    return str(path)


@pytest.mark.pipeline
@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc) on this machine")
def test_the_c_estimator_runs_as_a_rule_and_equals_the_built_in_ls(tmp_path, monkeypatch):
    copy_workflow(tmp_path)
    overlay = _overlay(tmp_path, estimators=["LS"], external_estimators=["LS-C"])
    run = run_snakemake(tmp_path, "results/collected/cmc.parquet", "--configfile", overlay)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    collected = pd.read_parquet(tmp_path / "results" / "collected" / "cmc.parquet")
    keys = ["marker_set", "rom_deg", "noise_mm", "trial"]
    ours = collected[collected["method"] == "LS"].set_index(keys).sort_index()
    theirs = collected[collected["method"] == "LS-C"].set_index(keys).sort_index()
    assert len(theirs) == 2 * 2 and theirs["converged"].all()
    columns = ["center_x", "center_y", "center_z"]
    gap = np.linalg.norm(ours[columns].to_numpy() - theirs[columns].to_numpy(), axis=1)
    assert gap.max() < 1e-9, gap
    # Scored by the benchmark, from the estimate: the same error as the built-in LS.
    assert np.allclose(theirs["error_mm"], ours["error_mm"], rtol=0, atol=1e-9)
    # Another C compiler, which may optimise the program otherwise, compiles it again.
    other = tmp_path / "other-cc"
    other.mkdir()
    (other / "cc").write_text(
        '#!/bin/sh\n[ "$1" = --version ] && echo "cc (Other) 99.0" && exit 0\n'
        f'exec {shutil.which("cc")} "$@"\n'
    )
    (other / "cc").chmod(0o755)
    monkeypatch.setenv("PATH", f"{other}{os.pathsep}{os.environ['PATH']}")
    planned = run_snakemake(
        tmp_path, "results/collected/cmc.parquet", "--configfile", overlay, "-n"
    )
    assert planned.returncode == 0, planned.stdout[-3000:] + planned.stderr[-3000:]
    assert "rule compile_ls_sphere:" in planned.stdout, planned.stdout[-3000:]


@pytest.mark.pipeline
@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc) on this machine")
def test_a_c_program_that_never_ends_is_stopped_with_the_child_it_forked(tmp_path):
    """The C example edited to ignore SIGTERM, fork a child that ignores it too and wait for
    ever: with no Python of its own, each of its jobs is stopped at the limit, the child with
    it, and fails naming the rule and the condition; the built-in LS's results are kept."""
    copy_workflow(tmp_path, profiles=True)
    program = tmp_path / "workflow" / "external" / "ls_sphere.c"
    shipped = program.read_text()
    start = "int main(int argc, char **argv) {\n"
    hang = f"{start}    signal(SIGTERM, SIG_IGN);\n    fork();\n    for (;;) pause();\n"
    posix = "#define _POSIX_C_SOURCE 200809L\n#include <signal.h>\n#include <unistd.h>\n"
    program.write_text(posix + shipped.replace(start, hang, 1))
    overlay = _overlay(tmp_path, estimators=["LS"], external_estimators=["LS-C"])
    # Compiled first, under the default limit: a job of the user's too, the compiler would be
    # stopped by a limit of seconds on a loaded machine (2 s of a 3 s limit at a load of 14),
    # and the program that never ends would never run.
    built = run_snakemake(tmp_path, "results/bin/ls_sphere", "--configfile", overlay)
    assert built.returncode == 0, built.stdout[-3000:] + built.stderr[-3000:]
    config = yaml.safe_load(Path(overlay).read_text())
    config["jobs"] = {"external_time_limit_s": 3}
    Path(overlay).write_text(yaml.safe_dump(config))
    targets = ["results/collected/cmc.parquet", "results/summaries/cmc/LS.csv"]
    run = run_snakemake(tmp_path, *targets, "--configfile", overlay, timeout=300)
    message = run.stdout + run.stderr
    assert run.returncode != 0
    assert "compile_ls_sphere" not in message, message[-3000:]  # built, not run again
    for noise in ("0.0", "1.0"):
        assert (
            f"rule estimate_LS_C (study=cmc, condition=marker_set-M__rom_deg-15__noise_mm-{noise})"
            ": its program ran past the time limit of 3 s"
        ) in message, message[-3000:]
    assert running_in(tmp_path) == []
    assert (tmp_path / "results" / "summaries" / "cmc" / "LS.csv").is_file(), message[-3000:]


@pytest.mark.pipeline
@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc) on this machine")
def test_the_workflow_names_the_csv_a_c_program_got_wrong(tmp_path):
    """The C example edited to report -1 iterations: collect stops, naming the CSV the program
    wrote, which is what its author can open, and the trial and column."""
    copy_workflow(tmp_path)
    program = tmp_path / "workflow" / "external" / "ls_sphere.c"
    shipped = program.read_text()
    program.write_text(shipped.replace(",true,0,%.9g,ok", ",true,-1,%.9g,ok"))
    assert program.read_text() != shipped
    overlay = _overlay(tmp_path, estimators=["LS"], external_estimators=["LS-C"])
    run = run_snakemake(tmp_path, "results/collected/cmc.parquet", "--configfile", overlay)
    assert run.returncode != 0
    named = re.compile(
        r"results/estimates/cmc/LS-C/marker_set-M__rom_deg-15__noise_mm-[0-9.]+\.csv: "
        r"trial 0: column 'iterations' is -1, below 0"
    )
    assert named.search(run.stdout + run.stderr), (run.stdout + run.stderr)[-3000:]
    assert not (tmp_path / "results" / "collected" / "cmc.parquet").exists()


@pytest.mark.pipeline
@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc) on this machine")
def test_the_workflow_refuses_estimates_made_from_a_cut_markers_csv(tmp_path):
    """The markers CSV cut after it was written, at a line's end: the C program fits the
    frames left and reports success; its estimates are refused, naming the cut file."""
    copy_workflow(tmp_path)
    overlay = _overlay(tmp_path, estimators=["LS"], external_estimators=["LS-C"])
    target = "results/collected/cmc.parquet"
    run = run_snakemake(tmp_path, target, "--configfile", overlay)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    name = "results/interchange/cmc/marker_set-M__rom_deg-15__noise_mm-1.0.csv"
    markers = tmp_path / name
    markers.write_text(_cut_at_a_lines_end(markers.read_text()))
    run = run_snakemake(tmp_path, target, "--configfile", overlay)
    assert run.returncode != 0
    named = re.compile(rf"{re.escape(name)}: [0-9]+ lines ending with a newline; the markers CSV")
    assert named.search(run.stdout + run.stderr), (run.stdout + run.stderr)[-3000:]


@pytest.mark.pipeline
def test_external_rules_of_a_study_not_in_the_run_are_ignored(tmp_path):
    """The shipped external rules (LM, LS-C, centroid) with the cmc study switched off: the
    default targets plan without them."""
    copy_workflow(tmp_path)
    overlay = tmp_path / "hinge_only.yaml"
    overlay.write_text(
        yaml.safe_dump(
            {
                "studies": {
                    "cmc": {"enabled": False},
                    "hip": {"enabled": False},
                    "hinge": {"trials": 2, "grid": {"fe_rom_deg": [30]}},
                }
            }
        )
    )
    run = run_snakemake(tmp_path, "--dry-run", "--configfile", str(overlay))
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "estimate_cmc_LM" not in run.stdout
    assert "estimate_LS_C" not in run.stdout


def test_the_readme_template_is_the_file_the_workflow_ships():
    """The template and the worked example's rule, as the README quotes them in full."""
    readme = (ROOT / "README.md").read_text()
    quoted = ("centroid.smk", "lm_sphere.smk")
    shipped = ["workflow/external/centroid.py", *(f"workflow/rules/estimators/{n}" for n in quoted)]
    for path in shipped:
        assert (ROOT / path).read_text().strip() in readme, f"{path} differs from the README"
