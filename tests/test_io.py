"""Dataset files: round trips by blocks of trials, row-order checks, older files, memory."""

from __future__ import annotations

import json
import re
import tracemalloc
from pathlib import Path

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.parquet as pq
import pytest

from jointbench.configuration.config import load_config
from jointbench.estimators.segment_poses import POSE_MIN_FRAMES, trial_poses
from jointbench.resultfiles import parquet
from jointbench.resultfiles.parquet import (
    iter_dataset,
    read_dataset,
    read_metadata,
    write_dataset,
    write_dataset_blocks,
)
from jointbench.running import run
from jointbench.simulate import Trials


def _trials(n_trials: int, n_frames: int = 7) -> Trials:
    rng = np.random.default_rng(1)
    return Trials(
        segments={
            "proximal": rng.normal(size=(n_trials, n_frames, 3, 3)),
            "distal": rng.normal(size=(n_trials, n_frames, 4, 3)),
        },
        truth={"center": [1.0, 2.0, 3.0]},
        parameters={"note": "test"},
    )


def test_blocks_of_trials_reassemble_the_condition(tmp_path):
    trials = _trials(23)
    path = tmp_path / "d.parquet"
    write_dataset(path, trials, study="hip", condition={"n_frames": 7})
    per_trial = 8 * 7 * 7 * 3
    blocks = list(iter_dataset(path, block_bytes=5 * per_trial))
    assert [first for first, _ in blocks] == [0, 5, 10, 15, 20]
    for name, markers in trials.segments.items():
        joined = np.concatenate([block.segments[name] for _, block in blocks])
        np.testing.assert_array_equal(joined, markers)
    assert blocks[0][1].truth == trials.truth


def _old_format(path, trials: Trials, metadata: dict) -> None:
    """A dataset as the first writer made it: one long table, no shapes in the metadata."""
    parts = []
    for name, markers in trials.segments.items():
        n_trials, n_frames, n_markers, _ = markers.shape
        trial, frame, marker = np.meshgrid(
            np.arange(n_trials), np.arange(n_frames), np.arange(n_markers), indexing="ij"
        )
        xyz = markers.reshape(-1, 3)
        parts.append(
            pd.DataFrame(
                {
                    "segment": name,
                    "trial": trial.ravel(),
                    "frame": frame.ravel(),
                    "marker": marker.ravel(),
                    "x": xyz[:, 0],
                    "y": xyz[:, 1],
                    "z": xyz[:, 2],
                }
            )
        )
    table = pa.Table.from_pandas(pd.concat(parts, ignore_index=True), preserve_index=False)
    table = table.replace_schema_metadata({b"jointbench": json.dumps(metadata).encode()})
    pq.write_table(table, path)


def test_files_without_recorded_shapes_still_read(tmp_path):
    trials = _trials(4)
    path = tmp_path / "old.parquet"
    metadata = {"study": "hip", "condition": {}, "truth": trials.truth, "parameters": {}}
    _old_format(path, trials, metadata)
    back, _ = read_dataset(path)
    for name, markers in trials.segments.items():
        np.testing.assert_array_equal(back.segments[name], markers)


def test_rows_out_of_order_are_named(tmp_path):
    trials = _trials(3)
    path = tmp_path / "shuffled.parquet"
    write_dataset(path, trials, study="hip", condition={})
    table = pq.read_table(path)
    order = np.arange(table.num_rows)
    order[[4, 5]] = order[[5, 4]]
    pq.write_table(table.take(order), path)
    with pytest.raises(ValueError, match=r"shuffled\.parquet.*not in \(trial, frame, marker\)"):
        read_dataset(path)


def test_reading_by_blocks_holds_one_block(tmp_path):
    """Peak memory while streaming a condition is a block, not the condition."""
    trials = _trials(400, n_frames=300)
    path = tmp_path / "big.parquet"
    write_dataset(path, trials, study="hip", condition={})
    size = sum(markers.nbytes for markers in trials.segments.values())
    del trials
    block = 2 * 2**20
    tracemalloc.start()
    for _, part in iter_dataset(path, block_bytes=block):
        del part
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert size > 10 * 2**20
    assert peak < 4 * block


def test_metadata_records_the_shapes(tmp_path):
    trials = _trials(2)
    path = tmp_path / "d.parquet"
    write_dataset(path, trials, study="hip", condition={"n_frames": 7})
    assert read_metadata(path)["shapes"] == {"proximal": [2, 7, 3, 3], "distal": [2, 7, 4, 3]}


def test_estimates_by_blocks_equal_the_whole_condition(tmp_path, monkeypatch):
    config = {"base_seed": 1, "studies": {"cmc": {"trials": 9, "options": {}}}}
    condition = {"marker_set": "M", "rom_deg": 15, "noise_mm": 1.0}
    trials = run.simulate_condition(config, "cmc", condition)
    path = tmp_path / "datasets" / "c.parquet"
    write_dataset(path, trials, study="cmc", condition=condition)
    whole = run.estimate("cmc", "LS", trials, condition)
    monkeypatch.setattr(parquet, "BLOCK_BYTES", 4 * trials.segments["moving"][0].nbytes)
    output = tmp_path / "estimates" / "c.parquet"
    run.run_estimate_files(config, "cmc", "LS", [str(path)], [str(output)])
    blocked = pd.read_parquet(output)
    assert blocked["trial"].tolist() == list(range(9))
    pd.testing.assert_frame_equal(blocked.drop(columns="seconds"), whole.drop(columns="seconds"))


def test_a_dataset_written_in_blocks_equals_one_written_at_once(tmp_path):
    """Simulation streams blocks of trials into the file: same file content, bounded memory."""
    config = load_config(Path(__file__).resolve().parents[1] / "config" / "config.yaml")
    config["studies"]["hip"]["trials"] = 7
    condition = {"n_frames": 16}
    whole = run.simulate_condition(config, "hip", condition)
    at_once, in_blocks = tmp_path / "once.parquet", tmp_path / "blocks.parquet"
    write_dataset(at_once, whole, study="hip", condition=condition)
    blocks = (
        run.simulate_condition(config, "hip", condition, range(a, min(a + 3, 7))) for a in (0, 3, 6)
    )
    write_dataset_blocks(in_blocks, blocks, 7, study="hip", condition=condition)
    assert read_metadata(in_blocks) == read_metadata(at_once)
    (a, _), (b, _) = read_dataset(at_once), read_dataset(in_blocks)
    for name in whole.segments:
        np.testing.assert_array_equal(a.segments[name], b.segments[name])
        np.testing.assert_array_equal(b.segments[name], whole.segments[name])
    assert not list(tmp_path.glob(".*.tmp"))
    with pytest.raises(ValueError, match="expected 8"):
        write_dataset_blocks(
            tmp_path / "short.parquet", [whole], 8, study="hip", condition=condition
        )


def _hip_dataset(tmp_path, n_trials: int, collinear_trial: int | None = None):
    """A small hip condition on disk (optionally one trial's proximal markers collinear)."""
    config = load_config(Path(__file__).resolve().parents[1] / "config" / "config.yaml")
    config["studies"]["hip"]["trials"] = n_trials
    condition = {"n_frames": 16}
    trials = run.simulate_condition(config, "hip", condition)
    if collinear_trial is not None:
        line = np.linspace(1.0, 2.0, trials.segments["proximal"].shape[2])[:, None] * [1, 2, 3]
        trials.segments["proximal"][collinear_trial] = line
    path = tmp_path / "datasets" / "n_frames-16.parquet"
    write_dataset(path, trials, study="hip", condition=condition)
    return config, condition, trials, path


def test_shared_poses_are_stored_exactly_and_give_the_same_estimates(tmp_path, monkeypatch):
    config, _, trials, dataset = _hip_dataset(tmp_path, 9, collinear_trial=4)
    monkeypatch.setattr(
        parquet, "BLOCK_BYTES", 4 * sum(m[0].nbytes for m in trials.segments.values())
    )
    poses = tmp_path / "poses" / "n_frames-16.parquet"
    run.run_poses_files("hip", [str(dataset)], [str(poses)])
    assert pq.ParquetFile(poses).num_row_groups == 3  # one per block of 4 trials
    fitted = trial_poses(dict(trials.segments), min_frames=POSE_MIN_FRAMES)
    stored = parquet.read_poses(poses, 0, trials.segments)
    assert str(stored[4]) == str(fitted[4]) and "collinear" in str(stored[4])
    for trial in (0, 8):
        for name in ("proximal", "distal"):
            a, b = fitted[trial][name], stored[trial][name]
            for field in ("rotation", "translation", "body", "markers"):
                np.testing.assert_array_equal(getattr(a, field), getattr(b, field))
            assert (a.residual_ss, a.dof) == (b.residual_ss, b.dof)
    for method in run.methods_sharing_poses(config, "hip"):
        own, shared = (tmp_path / part / method / dataset.name for part in ("own", "shared"))
        run.run_estimate_files(config, "hip", method, [str(dataset)], [str(own)])
        run.run_estimate_files(
            config, "hip", method, [str(dataset)], [str(shared)], poses=[str(poses)]
        )
        pd.testing.assert_frame_equal(
            pd.read_parquet(shared).drop(columns="seconds"),
            pd.read_parquet(own).drop(columns="seconds"),
        )
        assert pd.read_parquet(shared)["status"][4].startswith("error: ValueError")


def test_poses_of_another_dataset_are_refused_naming_the_file(tmp_path):
    _, _, trials, dataset = _hip_dataset(tmp_path, 3)
    poses = tmp_path / "poses" / dataset.name
    run.run_poses_files("hip", [str(dataset)], [str(poses)])
    named = re.escape(str(poses))
    with pytest.raises(ValueError, match=f"{named}.*another dataset"):
        parquet.read_poses(poses, 0, {k: v[:, :8] for k, v in trials.segments.items()})
    with pytest.raises(ValueError, match=f"{named}.*3 trials"):
        parquet.read_poses(poses, 2, trials.segments)
    with pytest.raises(ValueError, match="not a jointbench poses file"):
        parquet.read_poses(dataset, 0, trials.segments)


@pytest.mark.parametrize("damage", ["cut in half", "middle overwritten"])
def test_a_damaged_poses_file_is_named_with_the_command_that_regenerates_it(tmp_path, damage):
    _, _, trials, dataset = _hip_dataset(tmp_path, 3)
    poses = tmp_path / "poses" / dataset.name
    run.run_poses_files("hip", [str(dataset)], [str(poses)])
    data = poses.read_bytes()
    middle = len(data) // 2
    if damage == "cut in half":
        poses.write_bytes(data[:middle])
    else:
        poses.write_bytes(data[:100] + b"\xff" * (middle - 100) + data[middle:])
    with pytest.raises(ValueError) as error:
        parquet.read_poses(poses, 0, trials.segments)
    assert str(error.value).startswith(f"{poses}: cannot be read as parquet")
    assert f"--forcerun {poses}" in str(error.value)


@pytest.mark.parametrize("other", ["trials-reversed", "distal-moved", "proximal-noisier"])
def test_poses_of_other_markers_of_the_same_shapes_are_refused(tmp_path, other):
    """A poses file of another dataset whose shapes match (another seed, say): the poses do not
    leave the residual they were stored with on these markers."""
    _, _, trials, dataset = _hip_dataset(tmp_path, 3)
    poses = tmp_path / "poses" / dataset.name
    run.run_poses_files("hip", [str(dataset)], [str(poses)])
    segments = {k: v.copy() for k, v in trials.segments.items()}
    if other == "trials-reversed":
        segments = {k: v[::-1].copy() for k, v in segments.items()}
    elif other == "distal-moved":
        segments["distal"][1] += np.array([0.0, 0.0, 5.0])  # one trial's frames, rigidly
        segments["distal"][1, 3:] += np.array([1.0, 0.0, 0.0])
    else:
        rng = np.random.default_rng(0)
        segments["proximal"][2] += rng.normal(scale=0.5, size=segments["proximal"][2].shape)
    with pytest.raises(ValueError, match=f"{re.escape(str(poses))}: the poses of trial"):
        parquet.read_poses(poses, 0, segments)


def test_only_a_study_with_two_pose_based_methods_shares_poses():
    config = load_config(Path(__file__).resolve().parents[1] / "config" / "config.yaml")
    assert run.methods_sharing_poses(config, "hip") == config["studies"]["hip"]["estimators"]
    assert run.methods_sharing_poses(config, "cmc") == []  # SCoRE alone fits its own
    config["studies"]["hip"]["estimators"] = ["SCoRE"]
    assert run.methods_sharing_poses(config, "hip") == []


def test_stored_poses_are_refused_by_a_method_that_fits_none():
    config = {"base_seed": 1, "studies": {"cmc": {"trials": 2}}}
    condition = {"marker_set": "M", "rom_deg": 15, "noise_mm": 1.0}
    trials = run.simulate_condition(config, "cmc", condition)
    with pytest.raises(ValueError, match="LS: not a pose-based method"):
        run.estimate("cmc", "LS", trials, condition, poses=[])


def test_rows_table_stores_what_a_pandas_frame_of_the_rows_stores(tmp_path):
    rows = [
        {"name": "a", "n": 1, "x": 1.5, "flag": True, "note": None},
        {"name": "b", "n": np.int64(2), "x": np.nan, "flag": np.bool_(False), "extra": 3},
        {"name": "c", "n": 3, "x": np.float64(2), "flag": None, "note": "ok", "extra": 4.5},
    ]
    table = parquet.rows_table(rows)
    assert table.column_names == ["name", "n", "x", "flag", "note", "extra"]
    assert [table.schema.field(c).type for c in table.column_names] == [
        pa.string(),
        pa.int64(),
        pa.float64(),
        pa.bool_(),
        pa.string(),
        pa.float64(),
    ]
    ours, theirs = tmp_path / "rows.parquet", tmp_path / "pandas.parquet"
    parquet.write_table(table, ours)
    parquet.write_table(pd.DataFrame(rows), theirs)
    pd.testing.assert_frame_equal(parquet.read_table(ours), parquet.read_table(theirs))
    # NaN and None are both missing, as pandas stores them.
    assert table.column("x").null_count == 1 and table.column("extra").to_pylist()[0] is None


def test_rows_table_refuses_a_column_of_mixed_or_unstorable_values():
    with pytest.raises(TypeError, match="column 'v' mixes integer and text"):
        parquet.rows_table([{"v": 1}, {"v": "1"}])
    with pytest.raises(TypeError, match="column 'v': list values cannot be stored"):
        parquet.rows_table([{"v": [1, 2]}])
    assert parquet.rows_table([{"v": None}]).column("v").type == pa.null()


def test_a_pose_fit_that_failed_with_an_empty_message_stays_failed(tmp_path):
    block = parquet._poses_block([ValueError("")], 0, {"moving": (4, 3)})
    assert block.column("error").to_pylist() == [""]


def test_numpy_arrays_of_any_byte_order_are_stored_and_others_refused():
    swapped = np.arange(4.0).astype(">f8")
    assert parquet._to_numpy(parquet._from_numpy(swapped)).tolist() == [0.0, 1.0, 2.0, 3.0]
    with pytest.raises(TypeError, match="bool"):
        parquet._from_numpy(np.zeros(3, dtype=bool))
    with pytest.raises(ValueError, match="1-D"):
        parquet._from_numpy(np.zeros((2, 2)))


@pytest.mark.parametrize("one_path", ["d/c.parquet", Path("d/c.parquet")], ids=["str", "Path"])
def test_one_path_where_a_list_of_files_is_expected_is_refused(one_path):
    """A rule giving one dataset rather than a list of them is named, not read letter by letter."""
    config = {"base_seed": 1, "studies": {"cmc": {"trials": 1}}}
    with pytest.raises(TypeError, match="dataset files must be a list of paths, not one path"):
        run.run_estimate_files(config, "cmc", "LS", one_path, ["e/c.parquet"])
    with pytest.raises(TypeError, match="output files must be a list of paths"):
        run.run_poses_files("hip", ["d/c.parquet"], one_path)
