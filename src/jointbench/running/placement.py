"""Each trial of a blind dataset file placed anew in the lab, and answers mapped back.

Every trial of a study is simulated with the same truth (the knee's axis through the origin,
the CMC centre at the protocol's point, the hip centre at the origin of frame 0), so an
estimator outside the package that ignored its data and answered that constant, or the origin
it starts from, would score no error. The blind copy an external estimator reads
(:func:`jointbench.resultfiles.parquet.write_blind_dataset`) therefore holds each trial under
a rigid motion of its own, ``x' = R x + p`` applied to every marker of every segment of the
trial (the relative motion of two segments unchanged): ``R`` uniform on SO(3), ``p`` uniform in
the cube of half-side ``translation_mm`` (:func:`draw_placements`), drawn from the trial's seed
and the digest of its markers as simulated (:func:`dataset_placements`): the seed alone is public
(the config's ``base_seed``, the study, condition and trial), and a motion drawn from it alone
would let a program recompute it from what it reads and answer the constant truth placed. The
digest is of the unplaced markers, which the blind copy does not hold; a program can reach it
only by running the simulation again (README, "Adding an estimator"). The motions are stored
apart from the blind copy (:func:`write_placements`), in a file only the package's rules read,
and an external estimator's answers are mapped back by the inverse motion before anything
scores them (:func:`unplaced_estimates`): centres and axis points ``c = R^T (c' - p)``,
directions ``d = R^T d'``, covariances ``S = R^T S' R``. An estimator that answers in the
coordinates of the data it reads is scored as it would be on the unplaced data; one that
answers a constant is scored at the constant moved by a motion it never saw.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from jointbench.configuration.bounds import translation_problem
from jointbench.configuration.seeds import trial_seed
from jointbench.resultfiles.parquet import (
    read_metadata,
    read_table,
    read_trial_numbers,
    rows_table,
    trial_digests,
    write_table,
)
from jointbench.running.scoring import (
    COVARIANCE_COLUMNS,
    COVARIANCE_MIRRORS,
    ESTIMATE_COLUMNS,
    PROXIMAL_COLUMNS,
    RADIUS_COLUMN,
)

__all__ = [
    "DEFAULT_TRANSLATION_MM",
    "ESTIMATE_GEOMETRY",
    "Placements",
    "dataset_placements",
    "draw_placements",
    "read_placements",
    "unplaced_estimates",
    "write_placements",
]

#: Half-side [mm] of the cube each trial's translation is drawn from when the config sets
#: none (``blind_placement.translation_mm``): lab coordinates run to metres, and a joint a few
#: hundred millimetres from wherever the constant answer lies makes that answer's error
#: hundreds of millimetres, while the coordinates stay of the size a lab records. The config's
#: value is bounded by :data:`jointbench.configuration.bounds.TRANSLATION_MM_RANGE`.
DEFAULT_TRANSLATION_MM = 500.0

# A stream of its own beside the simulation's, which draws from the trial's seed alone: the
# placements change no simulated marker.
_STREAM = 0x706C6163

_ROTATION = tuple(f"r{i}{j}" for i in range(3) for j in range(3))
_TRANSLATION = ("p_x", "p_y", "p_z")

#: Per kind, how each column of its estimate moves with the data: ``points`` (triples of
#: coordinates [mm]), ``directions`` (triples, free vectors), ``covariances`` (the six upper
#: entries of a 3x3 matrix [mm²], in :data:`COVARIANCE_COLUMNS` order), ``invariant`` (a
#: length). Every estimate column a kind's file may hold is listed (tests hold this to
#: :mod:`jointbench.running.scoring`), so none reaches scoring in the placed frame.
ESTIMATE_GEOMETRY = {
    "center": {
        "points": (ESTIMATE_COLUMNS["center"],),
        "directions": (),
        "covariances": (),
        "invariant": (RADIUS_COLUMN,),
    },
    "axis": {
        "points": (ESTIMATE_COLUMNS["axis"][:3],),
        "directions": (ESTIMATE_COLUMNS["axis"][3:],),
        "covariances": (),
        "invariant": (),
    },
    "joint_center": {
        "points": (ESTIMATE_COLUMNS["joint_center"], PROXIMAL_COLUMNS[:3]),
        "directions": (),
        "covariances": (COVARIANCE_COLUMNS, PROXIMAL_COLUMNS[3:]),
        "invariant": (),
    },
}


@dataclass(frozen=True)
class Placements:
    """The rigid motion of each trial of a condition: ``x' = R x + p``.

    ``trials`` ``(n,)`` int, ascending; ``rotations`` ``(n, 3, 3)`` proper rotations;
    ``translations`` ``(n, 3)`` [mm].
    """

    trials: np.ndarray
    rotations: np.ndarray
    translations: np.ndarray

    def rows(self, trials) -> tuple[np.ndarray, np.ndarray]:
        """``(R (m, 3, 3), p (m, 3))`` of each of ``trials`` ``(m,)``; ``ValueError`` for a
        trial without a placement."""
        trials = np.asarray(trials, dtype=np.int64)
        index = np.searchsorted(self.trials, trials)
        index = np.minimum(index, len(self.trials) - 1)
        if not len(self.trials) or np.any(self.trials[index] != trials):
            missing = sorted(set(trials.tolist()) - set(self.trials.tolist()))
            raise ValueError(f"no placement of trial {missing[0]}")
        return self.rotations[index], self.translations[index]


def _rotation(quaternion: np.ndarray) -> np.ndarray:
    """The rotation ``(3, 3)`` of a unit quaternion ``(w, x, y, z)``."""
    w, x, y, z = quaternion
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def draw_placements(
    base_seed: int,
    study: str,
    condition: Mapping[str, object],
    digests: Mapping[int, bytes],
    translation_mm: float = DEFAULT_TRANSLATION_MM,
) -> Placements:
    """The placement of each trial of ``digests`` (trial -> the digest of its markers as
    simulated, :func:`jointbench.resultfiles.parquet.trial_digests`) of a condition, from its
    trial's seed (:func:`jointbench.configuration.seeds.trial_seed`) and its digest in a stream
    of its own: a rotation uniform on SO(3) (a unit quaternion of four standard normals,
    uniform on the 3-sphere) and a translation uniform in ``[-translation_mm,
    translation_mm]^3`` [mm]. ``ValueError`` for an empty digest: without one the motion would
    be drawn from public numbers alone."""
    problem = translation_problem(translation_mm)
    if problem:
        raise ValueError(f"translation_mm: {problem}")
    trials = np.sort(np.asarray(list(digests), dtype=np.int64))
    rotations = np.empty((len(trials), 3, 3))
    translations = np.empty((len(trials), 3))
    for row, trial in enumerate(trials):
        digest = digests[int(trial)]
        if not digest:
            raise ValueError(f"trial {int(trial)}: no digest of its markers to draw its placement")
        seed = trial_seed(base_seed, study, condition, int(trial))
        rng = np.random.default_rng([seed, _STREAM, int.from_bytes(digest, "little")])
        quaternion = rng.standard_normal(4)
        rotations[row] = _rotation(quaternion / np.linalg.norm(quaternion))
        translations[row] = rng.uniform(-translation_mm, translation_mm, 3)
    return Placements(trials, rotations, translations)


def dataset_placements(
    dataset: str | Path, base_seed: int, translation_mm: float = DEFAULT_TRANSLATION_MM
) -> Placements:
    """The placements of every trial of the dataset file ``dataset`` (:func:`draw_placements`
    for its study, condition and its trials' digests). ``ValueError`` naming ``dataset`` when it
    is a blind copy, whose markers are placed already: its digests are not the trials'."""
    metadata = read_metadata(dataset)
    if metadata.get("blind"):
        raise ValueError(
            f"{dataset} is a blind copy: its trials' placements are drawn from the markers as "
            "simulated, which only the full dataset file holds"
        )
    digests = trial_digests(dataset)
    trials = read_trial_numbers(dataset)
    if sorted(digests) != trials.tolist():
        raise ValueError(
            f"{dataset}: its rows hold trials {sorted(digests)}, its metadata {trials.tolist()}"
        )
    return draw_placements(
        base_seed, metadata["study"], metadata["condition"], digests, translation_mm
    )


def write_placements(
    path: str | Path, placements: Placements, provenance: Mapping[str, object] | None = None
) -> None:
    """Store ``placements`` at ``path``: one row per trial, ``trial``, ``r00 .. r22`` (row
    major) and ``p_x, p_y, p_z`` [mm], exactly (float64)."""
    rows = [
        {
            "trial": int(trial),
            **dict(zip(_ROTATION, map(float, rotation.ravel()), strict=True)),
            **dict(zip(_TRANSLATION, map(float, translation), strict=True)),
        }
        for trial, rotation, translation in zip(
            placements.trials, placements.rotations, placements.translations, strict=True
        )
    ]
    write_table(rows_table(rows), path, provenance)


def read_placements(path: str | Path) -> Placements:
    """The placements :func:`write_placements` stored at ``path``, by trial."""
    table = read_table(path).sort_values("trial")
    return Placements(
        table["trial"].to_numpy(dtype=np.int64),
        table[list(_ROTATION)].to_numpy(dtype=float).reshape(-1, 3, 3),
        table[list(_TRANSLATION)].to_numpy(dtype=float),
    )


def _unrotated(rotations: np.ndarray, vectors: np.ndarray) -> np.ndarray:
    """``R^T v`` ``(n, 3)`` for rotations ``(n, 3, 3)`` and vectors ``(n, 3)``."""
    return np.einsum("nji,nj->ni", rotations, vectors)


def unplaced_estimates(frame, kind: str, placements: Placements):
    """``frame``, estimates of ``kind`` given in each trial's placed frame (a table with a
    ``trial`` column), with every estimate column (:data:`ESTIMATE_GEOMETRY`) mapped back to
    the dataset's frame by the inverse of its trial's placement: points ``R^T (c' - p)``,
    directions ``R^T d'``, covariances ``R^T S' R`` (their mirror columns, ``cov_yx`` and the
    like, set equal to the mapped entries they mirror). Columns the file does not give stay
    absent; NaN stays NaN."""
    geometry = ESTIMATE_GEOMETRY[kind]
    rotations, translations = placements.rows(frame["trial"].to_numpy())
    mapped = {}
    for columns in geometry["points"]:
        if all(column in frame for column in columns):
            placed = frame[list(columns)].to_numpy(dtype=float)
            mapped.update(zip(columns, _unrotated(rotations, placed - translations).T, strict=True))
    for columns in geometry["directions"]:
        placed = frame[list(columns)].to_numpy(dtype=float)
        mapped.update(zip(columns, _unrotated(rotations, placed).T, strict=True))
    for columns in geometry["covariances"]:
        if not any(column in frame for column in columns):
            continue
        prefix = columns[0].removesuffix(COVARIANCE_COLUMNS[0])
        matrices = np.full((len(frame), 3, 3), np.nan)
        upper = np.triu_indices(3)
        for column, i, j in zip(columns, *upper, strict=True):
            if column in frame:
                matrices[:, i, j] = matrices[:, j, i] = frame[column].to_numpy(dtype=float)
        back = np.einsum("nki,nkl,nlj->nij", rotations, matrices, rotations)
        for column, i, j in zip(columns, *upper, strict=True):
            if column in frame:
                mapped[column] = back[:, i, j]
        for mirror, entry in COVARIANCE_MIRRORS.items():
            if f"{prefix}{mirror}" in frame:
                mapped[f"{prefix}{mirror}"] = mapped[f"{prefix}{entry}"]
    return frame.assign(**mapped)
