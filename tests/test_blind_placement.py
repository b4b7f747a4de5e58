"""Each trial of a blind copy is placed anew, and an external estimator's answers are mapped back
before scoring: a contestant that answers a constant (the study's truth, which the config and
the protocol give away, or the origin it starts from) scores the error of a constant, and one
that answers in the coordinates of the data it reads scores as on the unplaced data.
"""

from __future__ import annotations

import hashlib
import json
import re
import shutil
import subprocess
import sys

import numpy as np
import pandas as pd
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq
import pytest
import yaml
from workflow_copy import ROOT

from jointbench.configuration.bounds import TRANSLATION_MM_RANGE
from jointbench.configuration.seeds import trial_seed
from jointbench.configuration.studies import get_study
from jointbench.resultfiles.interchange import read_estimates_csv, write_dataset_csv
from jointbench.resultfiles.parquet import (
    check_blind_copy,
    read_dataset,
    read_metadata,
    read_table,
    trial_digests,
    write_blind_dataset,
    write_dataset,
    write_table,
)
from jointbench.resultfiles.schema import KIND_COLUMNS, OPTIONAL_COLUMNS
from jointbench.running import placement
from jointbench.running.collected import collect
from jointbench.running.placement import (
    DEFAULT_TRANSLATION_MM,
    ESTIMATE_GEOMETRY,
    Placements,
    dataset_placements,
    draw_placements,
    read_placements,
    unplaced_estimates,
    write_placements,
)
from jointbench.running.run import estimate, simulate_condition
from jointbench.running.scoring import (
    COVARIANCE_COLUMNS,
    COVARIANCE_MIRRORS,
    ESTIMATE_COLUMNS,
    PROXIMAL_COLUMNS,
    SCORE_COLUMNS,
)

CONFIG = yaml.safe_load((ROOT / "config" / "config.yaml").read_text())
STUDIES = ("cmc", "hinge", "hip", "hip_sta")
SEED = CONFIG["base_seed"]
TRANSLATION_MM = CONFIG["blind_placement"]["translation_mm"]


def _config(study: str, trials: int) -> dict:
    config = json.loads(json.dumps(CONFIG))
    config["studies"][study]["trials"] = trials
    return config


def _condition(study: str) -> dict:
    grid = CONFIG["studies"][study]["grid"]
    return {key: values[-1] for key, values in grid.items()}


def _blind_condition(tmp_path, study: str, trials: int = 12):
    """A condition of ``study`` written as the workflow writes it: its dataset file, its blind
    copy and the copy's placements file; their paths and the simulated trials."""
    config, condition = _config(study, trials), _condition(study)
    simulated = simulate_condition(config, study, condition)
    dataset = tmp_path / "datasets" / study / "c.parquet"
    write_dataset(dataset, simulated, study=study, condition=condition)
    placements = dataset_placements(dataset, SEED, TRANSLATION_MM)
    blind = tmp_path / "blind" / study / "c.parquet"
    write_blind_dataset(dataset, blind, placements)
    placed = tmp_path / "placements" / study / "c.parquet"
    write_placements(placed, placements)
    return dataset, blind, placed, simulated


def _digests(trials, markers: str = "") -> dict[int, bytes]:
    """Stand-ins for the digests of ``trials``' markers (one per trial, differing with
    ``markers``), for draws that need no dataset."""
    return {t: hashlib.sha256(f"{markers} trial {t}".encode()).digest() for t in trials}


def _rows(study: str, method: str, answers: dict[str, np.ndarray]) -> pd.DataFrame:
    """An estimates file's rows: the condition, one row per trial of ``answers`` (column ->
    ``(n,)``), every trial claiming success."""
    n = len(next(iter(answers.values())))
    return pd.DataFrame(
        {
            **{key: [value] * n for key, value in _condition(study).items()},
            "trial": np.arange(n),
            "method": method,
            **answers,
            "converged": True,
            "iterations": 0,
            "seconds": 0.0,
            "status": "ok",
        }
    )


def _collected(tmp_path, study, dataset, placed, method, rows) -> pd.DataFrame:
    path = tmp_path / "estimates" / study / method / "c.parquet"
    write_table(rows, path)
    return collect(
        study, [path], str(tmp_path / "collected.parquet"), [dataset], placements=[placed]
    )


def _constant(study: str, truth: dict, answer: str, n: int) -> dict[str, np.ndarray]:
    """Every trial's answer of a contestant that answers the study's ``truth`` or the origin."""
    kind = get_study(study).kind
    if kind == "axis":
        point = truth["axis_point"] if answer == "truth" else [0.0, 0.0, 0.0]
        direction = truth["axis_direction"] if answer == "truth" else [0.0, 0.0, 1.0]
        values = [*point, *direction]
    else:
        values = truth["center"] if answer == "truth" else [0.0, 0.0, 0.0]
    return {c: np.full(n, float(v)) for c, v in zip(ESTIMATE_COLUMNS[kind], values, strict=True)}


def _drawn_from_public_numbers(blind) -> list[Placements]:
    """Every way a program given the blind copy ``blind`` and the config (``base_seed``,
    ``blind_placement``) can draw placements from them: the package's own function on the copy
    (refused, once the motions depend on more than the copy holds) and the trial's seed in the
    module's stream, by hand."""
    metadata = read_metadata(blind)
    drawn = []
    try:
        drawn.append(dataset_placements(blind, SEED, TRANSLATION_MM))
    except ValueError as error:
        assert str(error).startswith(f"{blind} is a blind copy"), str(error)
    trials = range(metadata["shapes"]["moving"][0])
    rotations, translations = [], []
    for trial in trials:
        seed = trial_seed(SEED, metadata["study"], metadata["condition"], trial)
        rng = np.random.default_rng([seed, placement._STREAM])
        quaternion = rng.standard_normal(4)
        rotations.append(placement._rotation(quaternion / np.linalg.norm(quaternion)))
        translations.append(rng.uniform(-TRANSLATION_MM, TRANSLATION_MM, 3))
    drawn.append(Placements(np.arange(len(trials)), np.array(rotations), np.array(translations)))
    return drawn


def test_a_program_cannot_draw_its_placements_from_the_public_seed(tmp_path):
    """A trial's seed is public: the config's base seed, the study, condition and trial, all in
    or beside the blind copy. A program drawing the placements from it and answering the
    study's constant truth placed by them is scored as any constant: its answers are mapped
    back by motions drawn from the markers as simulated too, which the copy does not hold."""
    dataset, blind, placed, simulated = _blind_condition(tmp_path, "cmc", trials=6)
    truth = np.asarray(simulated.truth["center"], dtype=float)
    for guess in _drawn_from_public_numbers(blind):
        centres = np.einsum("nij,j->ni", guess.rotations, truth) + guess.translations
        answers = dict(zip(ESTIMATE_COLUMNS["center"], centres.T, strict=True))
        rows = _rows("cmc", "seeded", answers)
        collected = _collected(tmp_path, "cmc", dataset, placed, "seeded", rows)
        assert (collected["error_mm"] > 20.0).all(), collected["error_mm"].tolist()


def test_the_placements_of_a_blind_copy_are_refused_by_name(tmp_path):
    """Its markers are placed already: the placements drawn from them would not be its own."""
    _, blind, _, _ = _blind_condition(tmp_path, "cmc", trials=2)
    with pytest.raises(ValueError, match=re.escape(f"{blind} is a blind copy")):
        dataset_placements(blind, SEED, TRANSLATION_MM)


@pytest.mark.parametrize("answer", ["truth", "origin"])
@pytest.mark.parametrize("study", STUDIES)
def test_a_contestant_answering_a_constant_scores_the_error_of_a_constant(tmp_path, study, answer):
    """The cheat reads the truth where the config and the protocol give it away (every trial
    of a study has the same); the broken contestant answers the origin it starts from. Today
    each of them would score no error at all in some studies and top the ranking."""
    dataset, _, placed, simulated = _blind_condition(tmp_path, study)
    rows = _rows(study, "cheat", _constant(study, simulated.truth, answer, 12))
    collected = _collected(tmp_path, study, dataset, placed, "cheat", rows)
    error = collected[SCORE_COLUMNS[get_study(study).kind][0]].to_numpy()
    if get_study(study).kind == "axis":
        # A random rotation turns a line by 50° or more in two thirds of the draws.
        assert error.min() > 2.0 and np.median(error) > 30.0, error
    else:
        assert error.min() > 20.0 and np.median(error) > 200.0, error


def test_the_default_translation_is_the_configs_and_the_schemas():
    schema = yaml.safe_load((ROOT / "src/jointbench/schemas/config.schema.yaml").read_text())
    default = schema["properties"]["blind_placement"]["properties"]["translation_mm"]["default"]
    assert DEFAULT_TRANSLATION_MM == default == TRANSLATION_MM
    assert schema["properties"]["blind_placement"]["default"] == {"translation_mm": default}


@pytest.mark.parametrize("translation_mm", TRANSLATION_MM_RANGE)
def test_a_centre_placed_and_mapped_back_keeps_its_coordinates_at_the_bounds(translation_mm):
    """The rounding of ``R c + p`` and ``R^T (c' - p)`` grows with the translation: at the largest
    the config accepts, a centre at (10, 20, 30) comes back within the 1e-9 mm the results are
    compared at (at 1e30 mm it came back as 0)."""
    n = 200
    placements = draw_placements(SEED, "x", {"k": 1}, _digests(range(n)), translation_mm)
    centre = np.array([10.0, 20.0, 30.0])
    placed = np.einsum("nij,j->ni", placements.rotations, centre) + placements.translations
    assert np.abs(placements.translations).max() > 0.8 * translation_mm
    columns = ESTIMATE_COLUMNS["center"]
    frame = pd.DataFrame({"trial": np.arange(n), **dict(zip(columns, placed.T, strict=True))})
    back = unplaced_estimates(frame, "center", placements)
    np.testing.assert_allclose(
        back[list(columns)].to_numpy(float),
        np.broadcast_to(centre, (n, 3)),
        rtol=0,
        atol=1e-9,
    )


@pytest.mark.parametrize("translation_mm", [float("nan"), float("inf"), 1e30, 1e-12, 0.0])
def test_a_translation_out_of_its_bounds_draws_no_placement(translation_mm):
    with pytest.raises(ValueError, match=r"^translation_mm: .* is not a finite number in"):
        draw_placements(SEED, "x", {"k": 1}, _digests(range(3)), translation_mm)


def test_placements_are_proper_rotations_reproducible_and_differ_by_trial():
    condition = _condition("cmc")
    one = draw_placements(SEED, "cmc", condition, _digests(range(50)), TRANSLATION_MM)
    again = draw_placements(SEED, "cmc", condition, _digests([3, 1]), TRANSLATION_MM)
    rotations = one.rotations
    identity = np.broadcast_to(np.eye(3), rotations.shape)
    np.testing.assert_allclose(rotations @ rotations.transpose(0, 2, 1), identity, atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(rotations), 1.0, atol=1e-12)
    assert np.abs(one.translations).max() <= TRANSLATION_MM
    assert np.abs(one.translations).max() > 0.8 * TRANSLATION_MM
    np.testing.assert_array_equal(again.rotations, rotations[[1, 3]])
    np.testing.assert_array_equal(again.translations, one.translations[[1, 3]])
    assert len({tuple(r.ravel().round(6)) for r in rotations}) == 50
    other = draw_placements(
        SEED, "cmc", {**condition, "noise_mm": 0.5}, _digests(range(50)), TRANSLATION_MM
    )
    assert not np.allclose(other.translations, one.translations)
    # Other markers, the same seeds: other motions.
    moved = draw_placements(SEED, "cmc", condition, _digests(range(50), "other"), TRANSLATION_MM)
    assert not np.allclose(moved.translations, one.translations)


def test_a_trial_without_a_digest_of_its_markers_draws_no_placement():
    """Its motion would be drawn from the public seed alone."""
    with pytest.raises(ValueError, match="trial 1: no digest of its markers"):
        draw_placements(SEED, "cmc", _condition("cmc"), {0: b"x", 1: b""}, TRANSLATION_MM)


@pytest.mark.parametrize("study", ["hip", "hip_sta"])
def test_a_trials_digest_is_of_its_coordinates_as_little_endian_doubles_in_the_files_order(
    tmp_path, study
):
    """Each trial's digest is the SHA-256 of ``x, y, z`` of its rows in the file's order as
    little-endian float64, whatever the host's byte order and however the file is cut into row
    groups (a trial across several); one sample moved by one ulp changes its trial's digest
    alone."""
    dataset, _, _, _ = _blind_condition(tmp_path, study, trials=3)
    table = pq.read_table(dataset)
    frame = table.select(["trial", "x", "y", "z"]).to_pandas()
    expected = {
        int(trial): hashlib.sha256(
            rows[["x", "y", "z"]].to_numpy().astype("<f8", order="C").tobytes()
        ).digest()
        for trial, rows in frame.groupby("trial", sort=True)
    }
    assert trial_digests(dataset) == expected
    cut = tmp_path / "cut.parquet"
    pq.write_table(table, cut, row_group_size=len(frame) // 5 + 1)
    assert pq.ParquetFile(cut).num_row_groups > 3
    assert trial_digests(cut) == expected
    x = table.column("x").to_numpy().copy()
    row = int(np.flatnonzero(np.isfinite(x) & (frame["trial"].to_numpy() == 1))[-1])
    x[row] = np.nextafter(x[row], np.inf)
    moved = tmp_path / "moved.parquet"
    pq.write_table(table.set_column(table.schema.get_field_index("x"), "x", pa.array(x)), moved)
    changed = trial_digests(moved)
    assert [t for t in expected if changed[t] != expected[t]] == [1]


def test_a_dataset_whose_rows_lack_a_trial_its_metadata_counts_draws_no_placements(tmp_path):
    """A trial without rows has no digest to draw its placement from: the file is refused,
    naming it and both lists of trials, not placed with the trials it holds."""
    dataset, _, _, _ = _blind_condition(tmp_path, "hip", trials=3)
    table = pq.read_table(dataset)
    kept = table.filter(pc.not_equal(table.column("trial"), 1))
    cut = tmp_path / "cut.parquet"
    pq.write_table(kept, cut)
    assert read_metadata(cut) == read_metadata(dataset)
    with pytest.raises(ValueError, match=re.escape(f"{cut}: its rows hold trials [0, 2], its")):
        dataset_placements(cut, SEED, TRANSLATION_MM)


def test_the_blind_copy_holds_each_trial_placed_and_every_segment_moved_alike(tmp_path):
    """Both segments of a two-segment trial under the same motion: their relative motion, what
    a joint-centre method fits, is unchanged."""
    _, blind, placed, simulated = _blind_condition(tmp_path, "hip", trials=3)
    placements = read_placements(placed)
    read, _ = read_dataset(blind)
    for name, markers in simulated.segments.items():
        back = np.einsum(
            "nji,nfmj->nfmi",
            placements.rotations,
            read.segments[name] - placements.translations[:, None, None, :],
        )
        np.testing.assert_allclose(back, markers, rtol=0, atol=1e-9)
        assert np.abs(read.segments[name] - markers).max() > 10.0


def test_a_blind_copy_changed_after_it_was_written_is_refused_naming_the_trial(tmp_path):
    """The blind copy every external estimator reads, rewritten in place by one of them: as
    written it passes, changed in one sample it is refused, naming the file and the trial."""
    dataset, blind, placed, _ = _blind_condition(tmp_path, "hip", trials=3)
    placements = read_placements(placed)
    check_blind_copy(blind, dataset, placements)
    table = pq.read_table(blind)
    x = table.column("x").to_numpy().copy()
    row = table.num_rows - 1
    x[row] += 1e-9
    pq.write_table(table.set_column(table.schema.get_field_index("x"), "x", pa.array(x)), blind)
    trial = table.column("trial")[row].as_py()
    message = f"{blind}: trial {trial}: column 'x' is not what the blind copy of {dataset} holds"
    with pytest.raises(ValueError, match=re.escape(message)) as error:
        check_blind_copy(blind, dataset, placements)
    assert "--forcerun" in str(error.value)


def test_the_placements_are_not_in_the_blind_copy_nor_its_csv(tmp_path):
    _, blind, placed, _ = _blind_condition(tmp_path, "cmc", trials=3)
    placements = read_placements(placed)
    footer = pq.ParquetFile(blind).metadata.metadata
    text = b"".join(footer.values()).decode(errors="replace")
    assert "placement" not in text and "rotation" not in text and "translation" not in text
    csv = tmp_path / "blind.csv"
    write_dataset_csv(blind, csv)
    written = csv.read_text()
    assert written.splitlines()[0] == "trial,segment,frame,marker,x,y,z"
    for value in [*placements.translations.ravel(), *placements.rotations.ravel()]:
        for shown in (repr(float(value)), f"{value:.6f}"):
            assert shown not in text and shown not in written


def _forward(kind: str, answers: dict, placements: Placements) -> dict:
    """``answers`` of ``kind`` in the dataset's frame, moved into each trial's placed frame."""
    rotations, translations = placements.rotations, placements.translations
    out = dict(answers)
    geometry = ESTIMATE_GEOMETRY[kind]
    for columns in geometry["points"]:
        points = np.column_stack([answers[c] for c in columns])
        out.update(
            zip(columns, (np.einsum("nij,nj->ni", rotations, points) + translations).T, strict=True)
        )
    for columns in geometry["directions"]:
        vectors = np.column_stack([answers[c] for c in columns])
        out.update(zip(columns, np.einsum("nij,nj->ni", rotations, vectors).T, strict=True))
    for columns in geometry["covariances"]:
        prefix = columns[0].removesuffix("cov_xx")
        matrices = np.zeros((len(rotations), 3, 3))
        for column, i, j in zip(columns, *np.triu_indices(3), strict=True):
            matrices[:, i, j] = matrices[:, j, i] = answers[column]
        moved = np.einsum("nik,nkl,njl->nij", rotations, matrices, rotations)
        for column, i, j in zip(columns, *np.triu_indices(3), strict=True):
            out[column] = moved[:, i, j]
        for mirror, entry in COVARIANCE_MIRRORS.items():
            out[f"{prefix}{mirror}"] = out[f"{prefix}{entry}"]
    return out


@pytest.mark.parametrize("translation_mm", [TRANSLATION_MM, TRANSLATION_MM_RANGE[1]])
@pytest.mark.parametrize("kind", ["center", "axis", "joint_center"])
def test_mapping_back_undoes_the_placement_exactly(kind, translation_mm):
    """At the default translation and at the largest the config accepts."""
    n = 40
    rng = np.random.default_rng(7)
    placements = draw_placements(SEED, "x", {"k": 1}, _digests(range(n)), translation_mm)
    answers = {c: rng.normal(0, 100, n) for c in ESTIMATE_COLUMNS[kind]}
    if kind == "joint_center":
        for prefix in ("", "proximal_"):
            factor = rng.normal(0, 3, (n, 3, 3))
            matrices = factor @ factor.transpose(0, 2, 1)
            for column, i, j in zip(COVARIANCE_COLUMNS, *np.triu_indices(3), strict=True):
                answers[f"{prefix}{column}"] = matrices[:, i, j]
            for mirror, entry in COVARIANCE_MIRRORS.items():
                answers[f"{prefix}{mirror}"] = answers[f"{prefix}{entry}"]
        answers.update({c: rng.normal(0, 100, n) for c in PROXIMAL_COLUMNS[:3]})
    if kind == "center":
        answers["mean_radius_mm"] = rng.uniform(10, 60, n)
    order = rng.permutation(n)
    placed = pd.DataFrame({"trial": np.arange(n), **_forward(kind, answers, placements)})
    back = unplaced_estimates(placed.iloc[order], kind, placements)
    expected = pd.DataFrame({"trial": np.arange(n), **answers}).iloc[order]
    assert list(back.columns) == list(expected.columns)
    np.testing.assert_allclose(back.to_numpy(float), expected.to_numpy(float), rtol=0, atol=1e-9)
    # The placed answers were far from these: mapping back did the work.
    assert np.abs(placed.iloc[order].to_numpy(float) - expected.to_numpy(float)).max() > 1.0


@pytest.mark.parametrize("kind", ["center", "axis", "joint_center"])
def test_every_estimate_column_a_file_may_give_is_mapped_or_invariant(kind):
    """A column a kind's estimates file may give besides the scores the benchmark computes
    (schema.KIND_COLUMNS, OPTIONAL_COLUMNS) is a point, a direction, a covariance entry or
    its mirror, or invariant: none reaches scoring in the placed frame."""
    geometry = ESTIMATE_GEOMETRY[kind]
    mirrors = {f"{p}{m}" for p in ("", "proximal_") for m in COVARIANCE_MIRRORS}
    listed = {
        c for group in ("points", "directions", "covariances") for t in geometry[group] for c in t
    }
    listed |= set(geometry["invariant"])
    if geometry["covariances"]:
        listed |= mirrors
    given = set(KIND_COLUMNS[kind]) | set(OPTIONAL_COLUMNS[kind]) - set(SCORE_COLUMNS[kind])
    assert given <= listed, sorted(given - listed)
    for columns in geometry["covariances"]:
        assert [c.removeprefix("proximal_") for c in columns] == list(COVARIANCE_COLUMNS)


# The built-in estimator each study runs as if it were external: fed the blind copy's placed
# markers, its answers mapped back must score as its answers on the unplaced data do.
EQUIVARIANT = {
    "cmc": ("LS", 1e-6),
    "hinge": ("SARA", 1e-6),
    "hip": ("gauss-markov-frame0", 1e-6),
    "hip_sta": ("gauss-markov", 1e-6),
}


@pytest.mark.parametrize("study", STUDIES)
def test_an_answer_in_the_placed_frame_scores_as_on_the_unplaced_data(tmp_path, study):
    """Every score column, the joint centre's relative to the proximal markers at frame 0
    included, equals the built-in's on the full dataset."""
    method, tolerance = EQUIVARIANT[study]
    dataset, blind, placed, simulated = _blind_condition(tmp_path, study, trials=4)
    condition, kind = _condition(study), get_study(study).kind
    ours = estimate(study, method, simulated, condition)
    blind_trials, _ = read_dataset(blind)
    theirs = estimate(
        study,
        method,
        type(simulated)(blind_trials.segments, simulated.truth, simulated.parameters),
        condition,
    )
    given = [c for c in theirs.columns if c not in SCORE_COLUMNS[kind]]
    rows = theirs[given].assign(method="mine")
    collected = _collected(tmp_path, study, dataset, placed, "mine", rows)
    for column in SCORE_COLUMNS[kind]:
        np.testing.assert_allclose(
            collected[column].to_numpy(float),
            ours[column].to_numpy(float),
            rtol=1e-6,
            atol=tolerance,
            err_msg=column,
        )


def _lm_errors(tmp_path, dataset, blind, placed) -> tuple[np.ndarray, np.ndarray]:
    """LM's errors on the blind copy, mapped back and collected, and on the full dataset."""
    program = ROOT / "workflow" / "external" / "lm_sphere.py"
    errors = []
    for source, folder in ((blind, "LM"), (dataset, "LM-full")):
        out = tmp_path / "estimates" / "cmc" / folder
        subprocess.run(
            [sys.executable, str(program), "--out-dir", str(out), str(source)], check=True
        )
        rows = read_table(out / "c.parquet").assign(method=folder)
        write_table(rows, out / "c.parquet")
        placements = [placed] if folder == "LM" else []
        path = tmp_path / f"{folder}.parquet"
        errors.append(
            collect("cmc", [out / "c.parquet"], str(path), [dataset], placements=placements)[
                "error_mm"
            ].to_numpy()
        )
    return errors[0], errors[1]


def test_the_worked_example_reading_parquet_scores_as_on_the_unplaced_data(tmp_path, monkeypatch):
    dataset, blind, placed, _ = _blind_condition(tmp_path, "cmc", trials=4)
    # The unplaced run answers as a built-in: scored without placements.
    monkeypatch.setattr("jointbench.running.collected.is_external", lambda spec, m: m == "LM")
    placed_errors, full_errors = _lm_errors(tmp_path, dataset, blind, placed)
    np.testing.assert_allclose(placed_errors, full_errors, rtol=0, atol=1e-6)


@pytest.mark.skipif(shutil.which("cc") is None, reason="no C compiler (cc) on this machine")
def test_the_worked_example_reading_csv_scores_as_on_the_unplaced_data(tmp_path, monkeypatch):
    dataset, blind, placed, _ = _blind_condition(tmp_path, "cmc", trials=4)
    program = tmp_path / "ls_sphere"
    source = ROOT / "workflow" / "external" / "ls_sphere.c"
    subprocess.run(["cc", "-std=c99", "-O2", "-o", str(program), str(source), "-lm"], check=True)
    monkeypatch.setattr("jointbench.running.collected.is_external", lambda spec, m: m == "LS-C")
    errors = []
    for markers, method in ((blind, "LS-C"), (dataset, "LS-full")):
        csv = tmp_path / f"{method}.markers.csv"
        write_dataset_csv(markers, csv)
        answers = tmp_path / "estimates" / "cmc" / method / "c.csv"
        answers.parent.mkdir(parents=True)
        with answers.open("w") as stream:
            subprocess.run([str(program), str(csv)], stdout=stream, check=True)
        converted = answers.with_suffix(".parquet")
        read_estimates_csv(answers, markers, converted)
        placements = [placed] if method == "LS-C" else []
        path = str(tmp_path / f"{method}.parquet")
        errors.append(collect("cmc", [converted], path, [dataset], placements=placements))
    np.testing.assert_allclose(errors[0]["error_mm"], errors[1]["error_mm"], rtol=0, atol=1e-6)


def test_an_external_answer_without_its_placements_is_refused(tmp_path):
    dataset, _, _, simulated = _blind_condition(tmp_path, "cmc", trials=3)
    path = tmp_path / "estimates" / "cmc" / "cheat" / "c.parquet"
    write_table(_rows("cmc", "cheat", _constant("cmc", simulated.truth, "truth", 3)), path)
    with pytest.raises(ValueError, match=r"external estimator.*placements") as error:
        collect("cmc", [path], str(tmp_path / "collected.parquet"), [dataset])
    assert str(path) in str(error.value)
