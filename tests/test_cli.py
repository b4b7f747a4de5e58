"""The command line: fitting a user's marker CSV, and clear errors for malformed files."""

from __future__ import annotations

import numpy as np
import pandas as pd

from jointbench.cli import main
from jointbench.geometry import rotation_matrix


def write_markers(path, markers: np.ndarray) -> None:
    n_frames, n_markers, _ = markers.shape
    frame, marker = np.meshgrid(np.arange(n_frames), np.arange(n_markers), indexing="ij")
    table = pd.DataFrame({"frame": frame.ravel(), "marker": marker.ravel()})
    table[["x", "y", "z"]] = markers.reshape(-1, 3)
    table.sample(frac=1.0, random_state=0).to_csv(path, index=False)  # row order must not matter


def test_fit_center_from_csv(tmp_path, capsys):
    rng = np.random.default_rng(3)
    center = np.array([12.0, -40.0, 7.0])
    body = rng.normal(size=(3, 3)) * 30.0
    rotations = rotation_matrix(rng.normal(size=(60, 3)) * 0.5)
    path = tmp_path / "markers.csv"
    write_markers(path, np.einsum("fij,pj->fpi", rotations, body) + center)
    assert main(["fit", "center", str(path), "--method", "NM"]) == 0
    printed = capsys.readouterr().out
    line = next(line for line in printed.splitlines() if line.startswith("centre (mm):"))
    numbers = np.array(line.split("[")[1].split("]")[0].split(), dtype=float)
    np.testing.assert_allclose(numbers, center, atol=1e-3)
    assert "converged: True" in printed


def test_fit_reports_a_malformed_file(tmp_path, capsys):
    path = tmp_path / "bad.csv"
    pd.DataFrame(
        {"frame": [0, 0, 1], "marker": [0, 1, 0], "x": [0.0] * 3, "y": [0.0] * 3, "z": [0.0] * 3}
    ).to_csv(path, index=False)
    assert main(["fit", "center", str(path)]) == 2
    assert "every frame needs every marker" in capsys.readouterr().err
    pd.DataFrame({"frame": [0], "x": [0.0]}).to_csv(path, index=False)
    assert main(["fit", "axis", str(path)]) == 2
    assert "missing columns ['marker', 'y', 'z']" in capsys.readouterr().err
