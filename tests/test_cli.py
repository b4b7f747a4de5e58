"""The command line: fitting files, clear errors for bad input, help, version."""

from __future__ import annotations

import argparse
import io
import json
import re
import shutil
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from rigs import JOINT, PROXIMAL
from test_axis_sd_validity import swing
from test_io_recordings import DIST, KNEE, PROX, in_frame, rig_recording, swapped, write_c3d
from test_pose_noise import _hip, _noisy
from workflow_copy import ROOT

import jointbench
from jointbench import cli
from jointbench.cli import main
from jointbench.estimators.centre_precision import MAX_CENTER_SD_MM
from jointbench.estimators.results import PRECISION_NOT_DETERMINED
from jointbench.geometry import rotation_matrix
from jointbench.io.fit import NOT_DETERMINED

SHANK = "RLEG1,RLEG2,RLEG3,RATT,RLM,RSPH"
THIGH = "RTHI1,RTHI2,RTHI3,RGT"


def long_table(markers: np.ndarray) -> pd.DataFrame:
    n_frames, n_markers, _ = markers.shape
    frame, marker = np.meshgrid(np.arange(n_frames), np.arange(n_markers), indexing="ij")
    table = pd.DataFrame({"frame": frame.ravel(), "marker": marker.ravel()})
    table[["x", "y", "z"]] = markers.reshape(-1, 3)
    return table.sample(frac=1.0, random_state=0)  # row order must not matter


def sphere_markers() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(3)
    center = np.array([12.0, -40.0, 7.0])
    body = rng.normal(size=(3, 3)) * 30.0
    rotations = rotation_matrix(rng.normal(size=(60, 3)) * 0.5)
    return np.einsum("fij,pj->fpi", rotations, body) + center, center


def run(capsys, *argv) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return code, out, err


def csv_rows(text: str) -> pd.DataFrame:
    return pd.read_csv(io.StringIO(text))


def test_fit_center_from_csv(tmp_path, capsys):
    markers, center = sphere_markers()
    path = tmp_path / "markers.csv"
    long_table(markers).to_csv(path, index=False)
    code, out, _ = run(capsys, "fit", "center", str(path), "--method", "NM", "--format", "csv")
    assert code == 0
    row = csv_rows(out).iloc[0]
    np.testing.assert_allclose(row[["x_mm", "y_mm", "z_mm"]].to_numpy(float), center, atol=1e-3)
    assert bool(row["converged"])


def test_csv_with_a_missing_row_leaves_the_frame_out(tmp_path, capsys):
    markers, center = sphere_markers()
    path = tmp_path / "markers.csv"
    table = long_table(markers)
    table[~((table["frame"] == 7) & (table["marker"] == 1))].to_csv(path, index=False)
    code, out, _ = run(capsys, "fit", str(path), "--method", "NM", "--format", "csv")
    assert code == 0
    row = csv_rows(out).iloc[0]
    assert row["frames"] == 59 and row["gap_frames"] == 1
    np.testing.assert_allclose(row[["x_mm", "y_mm", "z_mm"]].to_numpy(float), center, atol=1e-3)


def test_csv_with_a_duplicated_row_is_refused(tmp_path, capsys):
    markers, _ = sphere_markers()
    path = tmp_path / "markers.csv"
    table = long_table(markers)
    duplicate = table[(table["frame"] == 3) & (table["marker"] == 2)]
    pd.concat([table[~((table["frame"] == 7) & (table["marker"] == 1))], duplicate]).to_csv(
        path, index=False
    )
    code, _, err = run(capsys, "fit", "center", str(path))
    assert code == 2
    assert f"jointbench: {path}: frame 3, marker 2 has 2 rows" in err


def test_malformed_csv_names_the_missing_columns(tmp_path, capsys):
    path = tmp_path / "bad.csv"
    pd.DataFrame({"frame": [0], "x": [0.0]}).to_csv(path, index=False)
    code, _, err = run(capsys, "fit", "axis", str(path))
    assert code == 2
    assert "missing columns ['marker', 'y', 'z']" in err


@pytest.mark.parametrize("command", ["fit", "inspect"])
def test_missing_file_or_directory_is_one_line(tmp_path, capsys, command):
    code, _, err = run(capsys, command, str(tmp_path / "absent.c3d"))
    assert code == 2 and err.strip() == f"jointbench: {tmp_path / 'absent.c3d'}: no such file"
    code, _, err = run(capsys, command, str(tmp_path))
    assert code == 2 and "is a directory" in err


def test_help_lists_every_method_and_the_defaults(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["fit", "--help"])
    assert exit_.value.code == 0
    out = capsys.readouterr().out
    for kind in ("center", "axis", "joint_center"):
        for name in jointbench.methods(kind):
            assert f"    {name} " in out
    assert "(default: refuse)" in out and "center (default NM)" in out


def test_version(capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0
    assert capsys.readouterr().out.strip() == f"jointbench {jointbench.__version__}"


def test_readme_without_results_says_what_to_run(tmp_path, capsys):
    code, _, err = run(capsys, "readme", "--results", str(tmp_path))
    assert code == 1
    assert "run `snakemake -j2` first" in err


def test_inspect_lists_labels_rate_and_gaps(tmp_path, capsys):
    markers = rig_recording(20).markers.copy()
    markers[4:7, 2] = 0.0
    path = write_c3d(tmp_path / "rig.c3d", PROX + DIST, markers)
    code, out, _ = run(capsys, "inspect", str(path), "--format", "json")
    assert code == 0
    summary = json.loads(out)
    assert summary["n_frames"] == 20 and summary["rate_hz"] == 100.0
    assert summary["missing_samples"] == {"P1": 0, "P2": 0, "P3": 3, "D1": 0, "D2": 0, "D3": 0}


def test_fit_joint_centre_of_a_c3d_in_the_reference_frame(tmp_path, capsys):
    path = write_c3d(tmp_path / "rig.c3d", PROX + DIST, rig_recording().markers)
    arguments = ["--reference", ",".join(PROX), "--moving", ",".join(DIST)]
    code, out, _ = run(
        capsys, "fit", str(path), "--kind", "joint_center", *arguments, "--method", "all",
        "--format", "json",
    )  # fmt: skip
    assert code == 0
    fits = json.loads(out)
    assert [f["method"] for f in fits] == list(jointbench.methods("joint_center"))
    for fitted in fits:
        # A C3D file holds float32: ~1e-4 mm on these coordinates.
        np.testing.assert_allclose(fitted["center_mm"], in_frame(JOINT, PROXIMAL), atol=2e-3)
        assert fitted["frame"]["x"] == "from P1 towards P2"


def test_artefact_is_refused_or_excluded_on_request(tmp_path, capsys):
    path = write_c3d(
        tmp_path / "swap.c3d", PROX + DIST, swapped(rig_recording(), 150, "D1", "D2").markers
    )
    arguments = ["fit", str(path), "--reference", ",".join(PROX), "--moving", ",".join(DIST)]
    code, _, err = run(capsys, *arguments)
    assert code == 2
    # A C3D file numbers its frames from 1: row 150 is frame 151.
    assert "swap.c3d: markers D1 and D2 exchange labels at frame 151 (1.51 s)" in err
    code, out, err = run(capsys, *arguments, "--artefacts", "exclude", "--format", "csv")
    assert code == 0
    assert "jointbench: warning:" in err and "left out 50 frames" in err
    assert csv_rows(out).iloc[0]["frames"] == 150


def test_fit_knee_axis_with_bootstrap(capsys):
    code, out, _ = run(
        capsys, "fit", str(KNEE), "--kind", "axis", "--reference", THIGH, "--moving", SHANK,
        "--method", "SARA", "--bootstrap", "20", "--format", "csv",
    )  # fmt: skip
    assert code == 0
    row = csv_rows(out).iloc[0]
    assert row["frames"] == 922 and 0.0 < row["boot_cone95_deg"] < 30.0


def test_every_row_states_the_answer_s_sd(tmp_path, capsys):
    """A table or CSV row states each answer's SD, as the Python call does
    (:meth:`jointbench.RecordingFit.stated_sd`): ``sd_mm`` for a centre or joint centre (the
    analytic centre's included, which has no covariance of its own), ``sd_deg`` for an axis.
    On the knee's skin markers every status says its precision is not determined (922 frames
    holding about 22 independent ones; for a centre also markers that keep no distance from
    any centre, for a joint centre the noise in the poses pulling it tens of millimetres):
    their rows state none, whatever the SD's size. A swing under independent noise states
    its axis's."""
    path = tmp_path / "swing.csv"
    long_table(swing(0, 60.0)).to_csv(path, index=False)
    code, out, _ = run(capsys, "fit", "axis", str(path), "--method", "planar", "--format", "csv")
    assert code == 0
    row = csv_rows(out).iloc[0]
    recording = jointbench.read(path)
    fitted = jointbench.fit(recording, "axis", list(recording.labels), method="planar")
    assert row["sd_stated"] and row["status"] == "ok"
    assert row["sd_deg"] == pytest.approx(fitted.result.diagnostics["axis_sd_deg"], rel=1e-6)
    assert fitted.stated_sd() == pytest.approx(row["sd_deg"], rel=1e-6)
    for kind, moving, key, column in (
        ("joint_center", SHANK, "center_sd_mm", "sd_mm"),
        ("center", SHANK, "center_sd_mm", "sd_mm"),
        ("axis", SHANK, "axis_sd_deg", "sd_deg"),
    ):
        method = {"joint_center": "analytic", "center": "NM", "axis": "planar"}[kind]
        code, out, _ = run(
            capsys, "fit", str(KNEE), "--kind", kind, "--reference", THIGH, "--moving", moving,
            "--method", method, "--format", "csv",
        )  # fmt: skip
        assert code == 0
        recording = jointbench.read(KNEE)
        fitted = jointbench.prepare(recording, kind, moving, THIGH).fit(method)
        result = fitted.result
        row = csv_rows(out).iloc[0]
        assert result.diagnostics[key] < MAX_CENTER_SD_MM  # the case: under the bounds
        assert PRECISION_NOT_DETERMINED in result.status
        assert np.isnan(row[column]) and not row["sd_stated"]


def test_an_sd_that_states_no_precision_is_printed_not_determined(capsys):
    """The radial axis of the knee's frames 700 to 999: its cost leaves the direction's SD
    far above what an axis direction can be off (90 deg). The row says "not determined", in
    the table and the CSV, as its status does, and prints no number for it; so does the planar
    axis of the same frames, whose SD is under the bound but counts 300 frames where they hold
    far fewer independent ones."""
    arguments = ["fit", str(KNEE), "--kind", "axis", "--reference", THIGH, "--moving", SHANK]
    arguments += ["--frames", "700:1000", "--method"]
    recording = jointbench.read(KNEE).frames("700:1000")
    prepared = jointbench.prepare(recording, "axis", SHANK.split(","), THIGH.split(","))
    stated = prepared.fit("radial").result.diagnostics["axis_sd_deg"]
    assert stated > 90.0  # the case
    code, out, _ = run(capsys, *arguments, "radial", "--format", "csv")
    assert code == 0
    row = csv_rows(out).iloc[0]
    assert np.isnan(row["sd_deg"]) and not row["sd_stated"]
    assert row["status"].startswith(
        "warning: axis not determined by the radial cost: its direction's SD is over 90 deg"
    )
    assert f"{stated:.1f}" not in out
    code, out, _ = run(capsys, *arguments, "radial")
    assert code == 0
    assert table_cell(out, "radial", "sd_deg") == NOT_DETERMINED, out
    assert f"{stated:.1f}" not in out and f"{stated:.4f}" not in out
    code, out, _ = run(capsys, *arguments, "planar", "--format", "csv")
    planar = prepared.fit("planar").result
    assert planar.diagnostics["axis_sd_deg"] < 10.0
    assert "the frames are not independent" in planar.status
    assert np.isnan(csv_rows(out).iloc[0]["sd_deg"]) and not csv_rows(out).iloc[0]["sd_stated"]


def sd_outputs(capsys, arguments: list[str]) -> tuple[pd.DataFrame, list[dict], str]:
    """The CSV (read by pandas), the JSON and the table of one ``jointbench fit``."""
    outputs = []
    for output in ("csv", "json", "table"):
        code, out, _ = run(capsys, *arguments, "--format", output)
        assert code == 0
        outputs.append(out)
    return csv_rows(outputs[0]), json.loads(outputs[1]), outputs[2]


def table_cell(text: str, method: str, column: str) -> str:
    """The printed ``column`` of ``method``'s row of a ``jointbench fit`` table ``text``: the
    columns are right-aligned, each cell ending where its header does."""
    header = re.search(rf"^\s*method .*\b{column}\b.*$", text, re.MULTILINE).group(0)
    end = re.search(rf"\b{column}\b", header).end()
    before = re.search(rf"^\s*{method} .*$", text, re.MULTILINE).group(0)[:end]
    # "not determined" is the one cell of two words.
    return NOT_DETERMINED if before.endswith(NOT_DETERMINED) else before.split()[-1]


def check_sd_outputs(capsys, arguments: list[str], column: str, undetermined: set[str]):
    """Each method's SD in ``column``: a number in the CSV (the column float, NaN where it
    states no precision) and the JSON (null there), flagged by ``sd_stated``; the table reads
    "not determined" for ``undetermined``, the methods whose SD states no precision."""
    table, fits, text = sd_outputs(capsys, arguments)
    assert table[column].dtype == np.float64 and table["sd_stated"].dtype == bool
    assert set(table.loc[~table["sd_stated"], "method"]) == undetermined
    assert table.loc[~table["sd_stated"], column].isna().all()
    assert table.loc[table["sd_stated"], column].notna().all()
    for fitted, row in zip(fits, table.itertuples(), strict=True):
        assert fitted["method"] == row.method and fitted["sd_stated"] == row.sd_stated
        if row.sd_stated:
            assert fitted[column] == pytest.approx(getattr(row, column), rel=1e-6)
        else:
            assert fitted[column] is None
    for method in table["method"]:
        cell = table_cell(text, method, column)
        assert (cell == NOT_DETERMINED) == (method in undetermined), cell
    assert "sd_stated" not in text
    return table


def test_machine_readable_outputs_keep_the_sd_a_number(capsys):
    """Every axis method on the knee's frames 700 to 999, where no SD states a precision (the
    radial cost's is over 90 deg, and every one counts 300 frames holding far fewer
    independent ones): the CSV's ``sd_deg`` is read as a float column, each row NaN and
    flagged; JSON gives null and the same flag. (A fit of which some rows state an SD:
    :func:`test_a_status_saying_the_precision_is_not_determined_prints_no_sd`.)"""
    arguments = ["fit", str(KNEE), "--kind", "axis", "--reference", THIGH, "--moving", SHANK]
    arguments += ["--frames", "700:1000", "--method", "all"]
    every = {"planar", "radial", "combined", "SARA"}
    table = check_sd_outputs(capsys, arguments, "sd_deg", every)
    recording = jointbench.read(KNEE).frames("700:1000")
    prepared = jointbench.prepare(recording, "axis", SHANK.split(","), THIGH.split(","))
    for row in table[table["sd_stated"]].itertuples():
        stated = prepared.fit(row.method).result.diagnostics["axis_sd_deg"]
        assert row.sd_deg == pytest.approx(stated, rel=1e-6)


def test_a_status_saying_the_precision_is_not_determined_prints_no_sd(tmp_path, capsys):
    """A hinge swung 2 deg: the planar cost's and SARA's eigen-gaps lie within the noise, and
    their statuses say the precision is not determined, though their SDs (some 5 deg) are
    under the 10 deg bound; the combined cost's SD stands. No output gives the former as a
    number."""
    path = tmp_path / "swing.csv"
    long_table(swing(39, 2.0)).to_csv(path, index=False)
    arguments = ["fit", "axis", str(path), "--method", "all"]
    table, _, _ = sd_outputs(capsys, arguments)
    warned = table["status"].str.contains("precision not determined")
    assert set(table.loc[warned, "method"]) == {"planar", "SARA"}  # the case
    check_sd_outputs(capsys, arguments, "sd_deg", {"planar", "SARA", "radial"})


def test_a_joint_centre_row_states_the_covariance_of_its_scatter(capsys):
    """``sqrt_trace_center_cov_mm`` is the root of the trace of the covariance a joint centre
    states of its scatter, ``center_sd_mm``'s: for ``gauss-markov`` paper C's ``W_c`` with the
    frame-0 poses' errors added, several times the ``W_c`` alone that is conditional on them;
    for the analytic centre, which has no covariance of its own, the one from both segments'
    poses. ``sqrt_trace_cov_mm`` is the method's own, as the pipeline's scores name it (paper C's
    ``W_c``; none for the analytic centre), so that one name means one thing. The table names
    where the stated one comes from, and JSON the source. On the knee the noise in the poses
    pulls both answers, so neither covariance states a precision: the CSV leaves their roots
    empty, as it does the SD, the table reads "not determined", and JSON's covariances are
    null beside the SD's null."""
    recording = jointbench.read(KNEE)
    prepared = jointbench.prepare(recording, "joint_center", SHANK.split(","), THIGH.split(","))
    arguments = ["fit", str(KNEE), "--kind", "joint_center", "--reference", THIGH]
    arguments += ["--moving", SHANK, "--method"]
    for method, source in (
        ("gauss-markov", "its method's covariance with the frame-0 poses' errors added"),
        ("analytic", "the noise of both segments' poses"),
    ):
        result = prepared.fit(method).result
        stated = np.asarray(result.diagnostics["center_covariance_mm2"])
        assert PRECISION_NOT_DETERMINED in result.status  # the case
        code, out, _ = run(capsys, *arguments, method, "--format", "csv")
        assert code == 0
        row = csv_rows(out).iloc[0]
        assert np.isnan(row["sqrt_trace_center_cov_mm"]) and not row["sd_stated"]
        # Nor does the method's own covariance, where it has one, state a precision.
        assert "sqrt_trace_cov_mm" not in row or np.isnan(row["sqrt_trace_cov_mm"])
        if result.covariance is not None:
            assert np.sqrt(np.trace(stated)) > 2.0 * np.sqrt(np.trace(result.covariance))
        code, out, _ = run(capsys, *arguments, method)
        assert code == 0
        assert f"sqrt_trace_center_cov_mm: {method}: from {source}" in out
        line = re.search(rf"^\s*{method} .*$", out, re.MULTILINE).group(0)
        line = line.replace(result.status, "")  # its words may say "not determined" too
        not_determined = 2 if result.covariance is None else 3
        assert line.count(" not determined ") == not_determined, line
        code, out, _ = run(capsys, *arguments, method, "--format", "json")
        assert code == 0
        (fitted,) = json.loads(out)
        assert fitted["center_covariance_mm2"] is None and not fitted["sd_stated"]
        assert fitted.get("covariance_mm2") is None
        assert fitted["center_covariance_is"] == source


def test_no_root_of_a_covariance_states_a_precision_the_sd_does_not(tmp_path, capsys):
    """A noisy pure hinge, fitted by ``gauss-markov-frame0``: the support verdict refuses the
    data (the centre is not determined along the axis), so ``sd_mm`` states no precision, and
    neither may any root of a covariance of the answer beside it. For this method the
    method's own covariance is the one ``sd_mm`` is read from: ``sqrt_trace_cov_mm`` printed
    as a number would state, under another name, the precision ``sd_mm`` and
    ``sqrt_trace_center_cov_mm`` say is not determined."""
    proximal, distal = _noisy(_hip(1, ratio=0.0), 3)
    labels = [f"P{i}" for i in range(4)], [f"D{i}" for i in range(4)]
    markers = np.concatenate([proximal, distal], axis=1)
    path = write_c3d(tmp_path / "hinge.c3d", labels[0] + labels[1], markers)
    arguments = ["fit", str(path), "--kind", "joint_center", "--reference", ",".join(labels[0])]
    arguments += ["--moving", ",".join(labels[1]), "--method", "gauss-markov-frame0"]
    code, out, _ = run(capsys, *arguments, "--format", "csv")
    assert code == 0
    row = csv_rows(out).iloc[0]
    assert "the centre is not determined along it" in row["status"]  # the case
    assert not row["sd_stated"]
    assert np.isnan(row["sqrt_trace_center_cov_mm"])
    assert np.isnan(row["sqrt_trace_cov_mm"])
    code, out, _ = run(capsys, *arguments)
    assert code == 0
    line = re.search(r"^\s*gauss-markov-frame0 .*$", out, re.MULTILINE).group(0)
    columns = line.partition("warning:")[0]  # the status says "not determined along it" too
    assert columns.count(" not determined ") == 3, line


def test_a_joint_centre_row_whose_sd_holds_states_the_root_of_its_covariance(tmp_path, capsys):
    """A hip swung 30 deg about two axes, 0.5 mm noise, whose joint centre's SD states its
    precision: ``sqrt_trace_center_cov_mm`` is the root of the trace of the covariance that SD
    is read from."""
    proximal, distal = _noisy(_hip(0, ratio=1.0), 7)
    labels = [f"P{i}" for i in range(4)], [f"D{i}" for i in range(4)]
    markers = np.concatenate([proximal, distal], axis=1)
    path = write_c3d(tmp_path / "hip.c3d", labels[0] + labels[1], markers)
    arguments = ["--reference", ",".join(labels[0]), "--moving", ",".join(labels[1])]
    code, out, _ = run(
        capsys, "fit", str(path), "--kind", "joint_center", *arguments, "--method", "SCoRE",
        "--format", "csv",
    )  # fmt: skip
    assert code == 0
    row = csv_rows(out).iloc[0]
    assert row["sd_stated"]  # the case
    fitted = jointbench.fit(
        jointbench.read(path), "joint_center", *reversed(labels), method="SCoRE"
    )
    stated = fitted.stated_covariance()[0]
    assert row["sqrt_trace_center_cov_mm"] == pytest.approx(np.sqrt(np.trace(stated)), rel=1e-6)


def test_world_trajectory_on_request(tmp_path, capsys):
    path = write_c3d(tmp_path / "rig.c3d", PROX + DIST, rig_recording().markers)
    world = tmp_path / "world.csv"
    arguments = ["--reference", ",".join(PROX), "--moving", ",".join(DIST)]
    code, _, err = run(
        capsys, "fit", str(path), "--kind", "joint_center", *arguments, "--method", "SCoRE",
        "--frames", "11:61", "--world", str(world),
    )  # fmt: skip
    assert code == 0 and "world trajectory" in err
    table = pd.read_csv(world)
    assert table["frame"].tolist() == list(range(11, 61))  # rows 10 to 59: frames from 1
    # The joint of the rig stays at the same distance from every distal marker.
    distal = rig_recording().markers[10:60, 3:]
    distance = np.linalg.norm(table[["x_mm", "y_mm", "z_mm"]].to_numpy()[:, None] - distal, axis=-1)
    np.testing.assert_allclose(distance, np.broadcast_to(distance[0], distance.shape), atol=2e-3)


def test_readme_writes_the_verdicts_over_seeds_from_the_results(tmp_path, capsys, monkeypatch):
    """`jointbench readme` fills the README's verdicts block from results/tables/verdicts.csv
    (and the protocol shares beside them when results/tables/sensitivity.csv exists) while the
    run's `verdicts` target has nothing to redo; where it has, it leaves the block as it was,
    names the jobs and exits 1 (tests/test_verdicts.py makes an edit for it)."""
    monkeypatch.setattr(cli, "_verdicts_pending", lambda args: {"verdicts_member_cmc": 1})
    tables = tmp_path / "results" / "tables"
    tables.mkdir(parents=True)
    pd.DataFrame({"paper": ["A"], "entry": ["claim"], "status": ["reproduced"]}).to_csv(
        tables / "published_comparison.csv", index=False
    )
    pd.DataFrame(
        {
            "paper": ["A", "A"],
            "entry": ["claim", "claim"],
            "id": ["A1", "A2"],
            "quantity": ["first", "second"],
            "seeds": [20, 20],
            "reproduced_in": [20, 9],
            "share": [1.0, 0.45],
            "interval_95": ["0.84–1.00", "0.26–0.66"],
            "verdict": ["reproduced", "seed-dependent"],
            "default_seed": ["reproduced", "not reproduced"],
            "default_reproduced": ["", ""],
        }
    ).to_csv(tables / "verdicts.csv", index=False)
    readme = tmp_path / "README.md"
    readme.write_text(
        "<!-- reproduction-summary:start -->\n<!-- reproduction-summary:end -->\n"
        "<!-- verdicts-summary:start -->\ntyped\n<!-- verdicts-summary:end -->\n"
    )
    arguments = ("readme", "--results", str(tmp_path / "results"), "--readme", str(readme))
    code, _, err = run(capsys, *arguments)
    assert code == 1 and "typed" in readme.read_text()
    assert "`snakemake -j2 verdicts` would redo verdicts_member_cmc (1): run it first" in err

    # Nothing to redo, but a failed job's outputs missing, which no run remakes while the
    # verdicts made from them are present: refused too, naming them and the command.
    monkeypatch.setattr(cli, "_verdicts_pending", lambda args: {})
    missing = {"results/verdicts/cmc/3.parquet": "verdicts_member_cmc"}
    monkeypatch.setattr(cli, "_verdicts_missing", lambda args: missing)
    code, _, err = run(capsys, *arguments)
    assert code == 1 and "typed" in readme.read_text()
    assert "1 file of the run is missing (results/verdicts/cmc/3.parquet)" in err
    assert "`snakemake -j2 verdicts --forcerun verdicts_member_cmc` first" in err

    monkeypatch.setattr(cli, "_verdicts_missing", lambda args: {})
    code, out, _ = run(capsys, *arguments)
    assert code == 0 and "verdicts over seeds updated" in out
    text = readme.read_text()
    assert "typed" not in text
    assert "| A2 | second | 9 of 20 | 0.26–0.66 | seed-dependent |" in text
    assert "protocols reproducing" not in text
    pd.DataFrame({"id": ["A2"], "reproduced_in": [16], "draws": [20]}).to_csv(
        tables / "sensitivity.csv", index=False
    )
    code, _, _ = run(capsys, *arguments)
    assert "| seed-dependent | 16 of 20 |" in readme.read_text()


def test_readme_asks_about_the_verdicts_with_every_config_file(monkeypatch):
    """Snakemake keeps the last of several ``--configfile`` options: the dry run that asks
    whether the verdicts are current, and the command the refusal names, give all of a run's
    config files to one."""
    asked = []
    monkeypatch.setattr(cli, "dry_run_pending", lambda command, what: asked.append(command))
    args = cli._parser().parse_args(["readme", "--configfile", "a.yaml", "--configfile", "b.yaml"])
    cli._verdicts_pending(args)
    assert asked[0][1:] == ["verdicts", "--dry-run", "--configfile", "a.yaml", "b.yaml"]
    command = "snakemake -j2 verdicts --configfile a.yaml b.yaml"
    assert cli._verdicts_command(args) == command
    monkeypatch.setattr(cli, "run_missing_outputs", lambda command, what: asked.append(command))
    cli._verdicts_missing(args)
    assert asked[1][1:] == ["verdicts", "--summary", "--configfile", "a.yaml", "b.yaml"]


def _toy_run(tmp_path):
    """A run directory of the fourth study (an extension): its files, the repository's config,
    and the results the snapshot and the README read."""
    from workflow_copy import ROOT

    for name in ("toy_study.py", "paper_t.yaml", "toy.yaml"):
        (tmp_path / name).write_text((ROOT / "tests" / "data" / "fourth_study" / name).read_text())
    # The whole of config/: its config names the named protocols' overlays beside it.
    shutil.copytree(ROOT / "config", tmp_path / "config")
    (tmp_path / "results" / "collected").mkdir(parents=True)
    (tmp_path / "results" / "tables").mkdir()
    pd.DataFrame(
        {
            "noise_mm": [0.5, 0.5, 1.0, 1.0],
            "trial": [0, 1, 0, 1],
            "method": ["toy-centroid"] * 4,
            "error_mm": [1.0, 2.0, 3.0, 4.0],
            "converged": [True] * 4,
            "seconds": [0.1] * 4,
        }
    ).to_parquet(tmp_path / "results" / "collected" / "toy.parquet")
    pd.DataFrame(
        {"paper": ["T", "T"], "entry": ["value", "value"], "status": ["reproduced", "x"]}
    ).to_csv(tmp_path / "results" / "tables" / "published_comparison.csv", index=False)
    (tmp_path / "README.md").write_text(
        "# toy\n<!-- reproduction-summary:start -->\n<!-- reproduction-summary:end -->\n"
    )
    return tmp_path


def _cli(workdir, *argv):
    """The command line in a fresh interpreter (an extension registers its study, paper and
    estimator for the rest of the process)."""
    import subprocess
    import sys

    code = "import sys; from jointbench.cli import main; sys.exit(main(sys.argv[1:]))"
    return subprocess.run(
        [sys.executable, "-c", code, *argv], cwd=workdir, capture_output=True, text=True
    )


def test_snapshot_loads_the_configs_extensions(tmp_path):
    workdir = _toy_run(tmp_path)
    done = _cli(workdir, "snapshot", "--configfile", "toy.yaml", "--output", "summary.csv")
    assert done.returncode == 0, done.stderr
    snapshot = pd.read_csv(workdir / "summary.csv")
    assert set(snapshot["study"]) == {"toy"} and set(snapshot["method"]) == {"toy-centroid"}
    # A folder with no workflow has no run to ask whether its results are current: said.
    assert "not checked whether results is up to date: it is not the results/ of a workflow" in (
        done.stderr
    )
    # Without the extension's config the run is the default one, whose studies this folder
    # has not collected: the error names their files, and the toy study's is not read.
    bare = _cli(workdir, "snapshot", "--output", "summary.csv")
    assert bare.returncode == 2 and "results/collected/cmc.parquet" in bare.stderr
    assert "toy" not in bare.stderr


def test_snapshot_pins_the_runs_studies_and_no_other(tmp_path):
    workdir = _toy_run(tmp_path)
    collected = workdir / "results" / "collected"
    # Left by an earlier run: toy.yaml switches cmc off, so these are no result of this run's.
    pd.DataFrame(
        {
            "marker_set": ["M", "M"],
            "rom_deg": [5, 5],
            "noise_mm": [1.0, 1.0],
            "trial": [0, 1],
            "method": ["LS", "LS"],
            "error_mm": [1.0, 2.0],
            "converged": [True, True],
            "seconds": [0.1, 0.1],
        }
    ).to_parquet(collected / "cmc.parquet")
    done = _cli(workdir, "snapshot", "--configfile", "toy.yaml", "--output", "summary.csv")
    assert done.returncode == 0, done.stderr
    assert set(pd.read_csv(workdir / "summary.csv")["study"]) == {"toy"}
    # A study of the run that has not been collected is named, not left out of the snapshot.
    (collected / "toy.parquet").unlink()
    missing = _cli(workdir, "snapshot", "--configfile", "toy.yaml", "--output", "summary.csv")
    assert missing.returncode == 2, missing.stderr
    assert "results/collected/toy.parquet: no such file" in missing.stderr


def test_readme_names_an_extensions_paper(tmp_path):
    workdir = _toy_run(tmp_path)
    done = _cli(workdir, "readme", "--configfile", "toy.yaml")
    assert done.returncode == 0, done.stderr
    assert "| T (a toy study) | 1 / 2 |" in (workdir / "README.md").read_text()


def test_a_configs_missing_extension_is_named(tmp_path):
    workdir = _toy_run(tmp_path)
    (workdir / "toy_study.py").unlink()
    done = _cli(workdir, "snapshot", "--configfile", "toy.yaml")
    assert done.returncode == 2 and "extensions: 'toy_study.py' is not a file" in done.stderr


def _help(capsys, command: str) -> str:
    with pytest.raises(SystemExit) as exit_:
        main([command, "--help"])
    assert exit_.value.code == 0
    return " ".join(capsys.readouterr().out.split())


def test_fit_snapshot_and_readme_take_the_same_configfile_option(capsys):
    texts = {command: _help(capsys, command) for command in ("fit", "snapshot", "readme")}
    option = "--configfile CONFIGFILE a config over config/config.yaml"
    for command, text in texts.items():
        assert option in text, command
    described = {text[text.index(option) :].split(" --", 1)[0] for text in texts.values()}
    assert len(described) == 1


def test_fit_runs_an_extension_estimator_of_the_config(tmp_path):
    workdir = _toy_run(tmp_path)
    markers, _ = sphere_markers()
    long_table(markers).to_csv(workdir / "markers.csv", index=False)
    arguments = ("fit", "markers.csv", "--configfile", "toy.yaml", "--format", "csv")
    done = _cli(workdir, *arguments, "--method", "toy-centroid")
    assert done.returncode == 0, done.stderr
    row = csv_rows(done.stdout).iloc[0]
    assert row["method"] == "toy-centroid" and row["frames"] == 60
    mean = markers.reshape(-1, 3).mean(axis=0)
    np.testing.assert_allclose(row[["x_mm", "y_mm", "z_mm"]].to_numpy(float), mean, atol=1e-9)
    # `all` is every method of the kind the run knows: the built-ins and the extension's.
    every = _cli(workdir, *arguments, "--method", "all")
    assert every.returncode == 0, every.stderr
    known = [*jointbench.methods("center"), "toy-centroid"]
    assert csv_rows(every.stdout)["method"].tolist() == known
    # Without the config the name is unknown.
    bare = _cli(workdir, "fit", "markers.csv", "--method", "toy-centroid")
    assert bare.returncode == 2 and "unknown center method 'toy-centroid'" in bare.stderr


def test_an_unknown_method_is_named_before_the_file_is_read(tmp_path, capsys):
    absent = tmp_path / "absent.csv"
    code, _, err = run(capsys, "fit", str(absent), "--method", "NMM")
    assert code == 2 and "no such file" not in err
    known = ", ".join(jointbench.methods("center"))
    assert f"--method: unknown center method 'NMM'; known: {known}" in err
    code, _, err = run(capsys, "fit", str(absent), "--kind", "axis", "--method", "NM")
    assert code == 2 and f"known: {', '.join(jointbench.methods('axis'))}" in err


def test_an_unknown_method_lists_the_configs_extension_estimators(tmp_path):
    workdir = _toy_run(tmp_path)
    done = _cli(workdir, "fit", "absent.csv", "--configfile", "toy.yaml", "--method", "toy")
    assert done.returncode == 2 and "no such file" not in done.stderr
    known = ", ".join([*jointbench.methods("center"), "toy-centroid"])
    assert f"unknown center method 'toy'; known: {known}" in done.stderr


def _overlay(workdir, extension_source: str, **config) -> str:
    """An overlay config listing one extension, ``extension.py`` holding
    ``extension_source``, beside the keys of ``config``; returns the overlay's name."""
    (workdir / "extension.py").write_text(extension_source)
    (workdir / "overlay.yaml").write_text(json.dumps({"extensions": ["extension.py"], **config}))
    return "overlay.yaml"


@pytest.mark.parametrize("command", ["fit", "snapshot"])
def test_a_config_typo_is_named_before_any_extension_is_imported(
    tmp_path, monkeypatch, capsys, command
):
    workdir = _toy_run(tmp_path)
    monkeypatch.chdir(workdir)
    overlay = _overlay(
        workdir,
        'raise RuntimeError("imported")\n',
        studies={"cmc": {"trails": 3}},
    )
    arguments = ["markers.csv"] if command == "fit" else []
    code, _, err = run(capsys, command, *arguments, "--configfile", overlay)
    assert code == 2
    assert "config error at studies/cmc: Additional properties" in err
    assert "'trails' was unexpected" in err


def _fit_over(workdir, first: str, second: str) -> list[str]:
    """The options of a fit with the overlays ``first`` then ``second``, written in
    ``workdir`` as ``a.yaml`` and ``b.yaml``."""
    (workdir / "a.yaml").write_text(first)
    (workdir / "b.yaml").write_text(second)
    return ["fit", "markers.csv", "--configfile", "a.yaml", "--configfile", "b.yaml"]


def test_fit_names_the_config_file_of_a_schema_error(tmp_path, monkeypatch, capsys):
    workdir = _toy_run(tmp_path)
    monkeypatch.chdir(workdir)
    arguments = _fit_over(workdir, "studies: {cmc: {trials: 0}}\n", "base_seed: 3\n")
    code, _, err = run(capsys, *arguments)
    assert code == 2
    assert "config error at studies/cmc/trials" in err and "(set in a.yaml)" in err, err
    (workdir / "b.yaml").write_text("base_seed: 010\n")
    code, _, err = run(capsys, *arguments)
    assert code == 2
    assert "config file b.yaml: base_seed at line 1: 010 is read as 8" in err, err


def test_fit_names_the_config_file_of_a_mistake_after_the_schema(tmp_path, monkeypatch, capsys):
    workdir = _toy_run(tmp_path)
    monkeypatch.chdir(workdir)
    second = "studies: {cmc: {grid: {rom_deg: [0]}}}\n"
    code, _, err = run(capsys, *_fit_over(workdir, "studies: {cmc: {trials: 3}}\n", second))
    assert code == 2
    assert "config: studies.cmc.grid.rom_deg: 0 is not allowed" in err, err
    assert "(set in b.yaml)" in err and "a.yaml" not in err, err


BROKEN_EXTENSIONS = {
    "import": (
        "import numpy as np\n\nimport jointbench_no_such_module\n",
        "line 3: ModuleNotFoundError: No module named 'jointbench_no_such_module'",
    ),
    "estimator": (
        "from jointbench.estimators import register\n\n\n"
        '@register("center", "NM")\ndef fit(markers):\n    return None\n',
        "line 4: ValueError: center estimator 'NM' is already registered",
    ),
    "study": (
        "import dataclasses\n\nfrom jointbench.configuration.studies import get_study\n\n"
        'STUDY = dataclasses.replace(get_study("cmc"))\n',
        "cannot be registered: ValueError: a different study named 'cmc' is already registered",
    ),
}


@pytest.mark.parametrize("broken", BROKEN_EXTENSIONS)
def test_an_extension_that_fails_to_import_or_register_is_named(
    tmp_path, monkeypatch, capsys, broken
):
    workdir = _toy_run(tmp_path)
    monkeypatch.chdir(workdir)
    source, reason = BROKEN_EXTENSIONS[broken]
    overlay = _overlay(workdir, source)
    # Twice: a module that failed is not kept as if it had been loaded.
    for _ in range(2):
        code, _, err = run(capsys, "fit", "markers.csv", "--configfile", overlay)
        assert code == 2
        assert f"config error at extensions: 'extension.py' ({workdir / 'extension.py'})" in err
        assert reason in err


def test_fit_reads_a_configfile_over_the_run_folders_config(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    markers, _ = sphere_markers()
    long_table(markers).to_csv(tmp_path / "markers.csv", index=False)
    (tmp_path / "mine.yaml").write_text("extensions: []\n")
    code, _, err = run(capsys, "fit", "markers.csv", "--configfile", "mine.yaml")
    assert code == 2
    assert f"config/config.yaml: no such file in {tmp_path}" in err
    # Without --configfile no config is read: a recording is fitted in any folder.
    code, out, _ = run(capsys, "fit", "markers.csv", "--format", "csv")
    assert code == 0 and csv_rows(out).iloc[0]["method"] == "NM"


# A workflow whose second rule is made from its first: a run in which the first failed, under
# keep-going, leaves the second's file from before and the first's removed.
_TWO_RULES = """\
rule all:
    input: "results/b.txt"
rule b:
    input: "results/a.txt"
    output: "results/b.txt"
    shell: "cp {input} {output}"
rule a:
    output: "results/a.txt"
    shell: "echo a > {output}"
"""


def test_results_a_failed_job_left_missing_are_stale(tmp_path, monkeypatch, capsys):
    """Snakemake does not remake a failed job's removed outputs while the files made from them
    are present, so its dry run has nothing to redo: the results still are not current, and
    the files missing are named with the command that makes them again."""
    (tmp_path / "Snakefile").write_text(_TWO_RULES)
    (tmp_path / "results").mkdir()
    (tmp_path / "results" / "b.txt").write_text("a\n")
    monkeypatch.chdir(tmp_path)
    args = argparse.Namespace(results=Path("results"), configfile=[])
    assert cli._stale(args, "snapshot")
    message = capsys.readouterr().err
    assert "1 file of the run is missing (results/a.txt)" in message
    assert "`snakemake -j2 --forcerun a`" in message
    (tmp_path / "results" / "a.txt").write_text("a\n")
    (tmp_path / "results" / "b.txt").touch()
    assert not cli._stale(args, "snapshot")


def test_results_a_run_would_redo_are_stale_naming_its_jobs(tmp_path, monkeypatch, capsys):
    """Where the run's dry run has jobs to do, the command says which, by rule and count, and
    the command that does them."""
    (tmp_path / "Snakefile").write_text(_TWO_RULES)
    (tmp_path / "results").mkdir()
    monkeypatch.chdir(tmp_path)
    args = argparse.Namespace(results=Path("results"), configfile=[])
    assert cli._stale(args, "snapshot")
    message = capsys.readouterr().err
    assert "`snakemake -j2` would redo a (1), b (1): run it first" in message


def test_the_guide_s_knee_numbers_are_what_its_command_prints(capsys):
    """docs/own-data.md states, for its own command on the shipped knee trial (the shank's six
    markers in the thigh's frame), the distances' lag-1 autocorrelation, the independent
    frames and the block length a bootstrap's blocks fall short of: each as that command's
    status prints it, not as another marker set's."""
    guide = (Path(__file__).resolve().parents[1] / "docs" / "own-data.md").read_text()
    command = re.search(
        r"jointbench fit data/functional-trials/right_knee\.c3d[^\n]*\n[^\n]*", guide
    )
    assert f"--reference {THIGH} --moving {SHANK}" in command.group(0)
    stated = re.search(
        r"lag-1 autocorrelation\s+(\S+), about (\d+)\s+independent frames of 922", guide
    )
    span = re.search(r"blocks of 31 frames against (\d+)\)", guide)
    code, out, _ = run(
        capsys, "fit", str(KNEE), "--kind", "axis", "--reference", THIGH, "--moving", SHANK,
        "--method", "SARA", "--bootstrap", "20", "--format", "json",
    )  # fmt: skip
    assert code == 0
    status = json.loads(out)[0]["status"]
    assert f"lag-1 autocorrelation {stated.group(1)})" in status
    assert f"where there are about {stated.group(2)}," in status
    assert f"blocks of 31 frames are shorter than {span.group(1)}," in status


def test_the_readme_command_says_which_blocks_it_rewrites(capsys):
    """Its one-line help named two of the README's generated blocks; it rewrites every one
    (README, "The README's generated blocks")."""
    top = " ".join(cli._parser().format_help().split())
    for block in ("reproduction summary", "STA ranking", "what stands out", "verdicts over seeds"):
        assert block in _help(capsys, "readme"), block
        assert block in top, block


# A user's config file as an editor leaves it: indented with a tab, a bracket left open, or
# saved empty (Snakemake's --configfile refuses each of these too).
BROKEN_CONFIG_FILES = {
    "tab": ("studies:\n\tcmc:\n\t\ttrials: 5\n", "not valid YAML", "line 2", "a tab"),
    "open bracket": ("studies: {cmc: [\n", "not valid YAML", "line 2"),
    "empty": ("", "empty", "no keys"),
    "comments only": ("# trials: 5\n", "empty", "no keys"),
}


@pytest.mark.parametrize("broken", BROKEN_CONFIG_FILES)
def test_a_configfile_that_is_no_yaml_mapping_is_refused_naming_it(
    tmp_path, monkeypatch, capsys, broken
):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "config").mkdir()
    (tmp_path / "config" / "config.yaml").write_text((ROOT / "config" / "config.yaml").read_text())
    text, *words = BROKEN_CONFIG_FILES[broken]
    (tmp_path / "mine.yaml").write_text(text)
    code, _, err = run(capsys, "fit", "markers.csv", "--configfile", "mine.yaml")
    assert code == 2
    assert "config file mine.yaml: " in err
    for word in words:
        assert word in err


def test_a_mistake_of_a_second_configfile_under_an_odd_key_names_that_file(
    tmp_path, monkeypatch, capsys
):
    """A key holding a dot or a comma, set by the second of two files: the refusal names it."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "config").mkdir()
    (tmp_path / "config" / "config.yaml").write_text((ROOT / "config" / "config.yaml").read_text())
    (tmp_path / "a.yaml").write_text("studies: {hinge: {trials: 3}}\n")
    (tmp_path / "b.yaml").write_text(
        'studies: {hinge: {protocol: {"knee.v2, b": {n_frames: 2}}}}\n'
    )
    arguments = ["fit", "markers.csv", "--configfile", "a.yaml", "--configfile", "b.yaml"]
    code, _, err = run(capsys, *arguments)
    assert code == 2
    assert "config: studies.hinge.protocol.knee.v2, b.n_frames: must be" in err, err
    assert "(set in b.yaml)" in err, err


# A config file naming a protocol of the sensitivity ensembles, and what `fit` says of it: the
# same as the workflow, which reads every named protocol's overlay as it starts.
NAMED_PROTOCOLS = {
    "missing": ("sensitivity: {named: {mine: absent.yaml}}\n", None, "absent.yaml): no such file"),
    "refused": (
        "sensitivity: {named: {mine: bad.yaml}}\n",
        "studies: {cmc: {trials: 0}}\n",
        "(bad.yaml): config error at studies/cmc/trials: 0 is less than the minimum of 1",
    ),
    "named as the default": (
        "sensitivity: {named: {default: bad.yaml}}\n",
        "studies: {cmc: {protocol: {n_frames: 100}}}\n",
        "named protocol 'default' takes the name of a default or drawn one",
    ),
}


@pytest.mark.parametrize("kind", NAMED_PROTOCOLS)
def test_fit_reads_the_named_protocols_as_the_workflow_does(tmp_path, monkeypatch, capsys, kind):
    monkeypatch.chdir(tmp_path)
    shutil.copytree(ROOT / "config", tmp_path / "config")
    text, overlay, words = NAMED_PROTOCOLS[kind]
    (tmp_path / "mine.yaml").write_text(text)
    if overlay is not None:
        (tmp_path / "bad.yaml").write_text(overlay)
    code, _, err = run(capsys, "fit", "markers.csv", "--configfile", "mine.yaml")
    assert code == 2, err
    assert words in err and "set in mine.yaml)" in err, err


def test_fit_reads_no_named_protocol_where_no_study_runs_an_ensemble(tmp_path, monkeypatch, capsys):
    """As the workflow, which reads them for the studies with a sensitivity ensemble alone."""
    monkeypatch.chdir(tmp_path)
    shutil.copytree(ROOT / "config", tmp_path / "config")
    (tmp_path / "mine.yaml").write_text(
        "sensitivity: {named: {mine: absent.yaml}}\n"
        "studies: {cmc: {enabled: false}, hinge: {enabled: false}, hip: {enabled: false}}\n"
    )
    markers, _ = sphere_markers()
    long_table(markers).to_csv(tmp_path / "markers.csv", index=False)
    arguments = ["markers.csv", "--configfile", "mine.yaml", "--format", "csv"]
    code, _, err = run(capsys, "fit", *arguments)
    assert code == 0, err
