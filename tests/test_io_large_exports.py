"""A lab's long capture is read in memory of the order of its file's size, not ten times it: a
TRC's rows are read line by line into one array, never all split into fields at once, and a
CSV's bytes go to the parser as they are."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from jointbench.io import read_csv, read_trc


def _write_trc(path, markers, rate=100.0):
    """Markers ``(n_frames, n, 3)`` [mm] to a TRC file, five decimals each, as labs export."""
    n_frames, n_markers, _ = markers.shape
    labels = [f"M{i:02d}" for i in range(1, n_markers + 1)]
    head = [
        f"PathFileType\t4\t(X/Y/Z)\t{path.name}",
        "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits",
        f"{rate:g}\t{rate:g}\t{n_frames}\t{n_markers}\tmm",
        "Frame#\tTime\t" + "\t\t\t".join(labels),
        "\t\t" + "\t".join(f"X{i}\tY{i}\tZ{i}" for i in range(1, n_markers + 1)),
    ]
    table = np.column_stack(
        [np.arange(1, n_frames + 1), np.arange(n_frames) / rate, markers.reshape(n_frames, -1)]
    )
    with path.open("w") as file:
        file.write("\n".join(head) + "\n")
        np.savetxt(file, table, fmt=["%d", "%.4f"] + ["%.5f"] * (3 * n_markers), delimiter="\t")
    return path


def _peak_bytes(read, path):
    """The most memory [bytes] ``read(path)`` holds at once, as Python and NumPy allocate it."""
    read(path)  # imports and compiled code loaded before the count starts
    tracemalloc.start()
    try:
        read(path)
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def _write_long_csv(path, markers):
    """Markers ``(n_frames, n, 3)`` [mm] to a long CSV ``frame,marker,x,y,z``, five decimals."""
    n_frames, n_markers, _ = markers.shape
    frames = np.repeat(np.arange(1, n_frames + 1), n_markers)
    labels = np.tile([f"M{i:02d}" for i in range(1, n_markers + 1)], n_frames)
    with path.open("w") as file:
        file.write("frame,marker,x,y,z\n")
        file.writelines(
            f"{frame},{label},{x:.5f},{y:.5f},{z:.5f}\n"
            for frame, label, (x, y, z) in zip(frames, labels, markers.reshape(-1, 3), strict=True)
        )
    return path


@pytest.mark.parametrize(
    ("write", "read", "n_frames", "most"),
    [(_write_trc, read_trc, 3000, 2.5), (_write_long_csv, read_csv, 1000, 3.5)],
    ids=["trc", "csv"],
)
def test_a_long_export_is_read_in_memory_of_a_few_times_its_size(
    tmp_path, write, read, n_frames, most
):
    """40 markers (a TRC of 3000 frames, 3.8 MB; a CSV of 1000, 1.6 MB): a TRC's fields as
    text took 9.5 times the file's size; a CSV's text, copied at four bytes a character for
    the parser, and its markers' text mapped to their columns, 5.7 times."""
    rng = np.random.default_rng(0)
    markers = rng.uniform(-1000.0, 1000.0, (n_frames, 40, 3))
    path = write(tmp_path / f"long.{read.__name__[-3:]}", markers)
    peak = _peak_bytes(read, path)
    assert peak < most * path.stat().st_size, peak / path.stat().st_size
    np.testing.assert_array_equal(read(path).markers, np.round(markers, 5))
