"""Gather a study's estimates files into its collected results, and one estimator's summary.

Both score every estimates file themselves (:func:`scored_estimates`): the errors a ranking is
made of are computed here from each row's estimate and the truth in its condition's dataset,
for built-in and external estimators alike. An external estimator answers in the frame of the
blind copy it read, each trial placed anew (:mod:`jointbench.running.placement`): its answers
are mapped back to the dataset's frame here, before anything checks or scores them.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from jointbench.configuration.studies import get_study, method_kind
from jointbench.estimators import registry
from jointbench.resultfiles.parquet import (
    check_blind_copy,
    iter_dataset,
    read_metadata,
    read_provenance,
    read_source,
    read_table,
    read_trial_numbers,
    read_truth,
    write_table,
)
from jointbench.resultfiles.schema import (
    check_against_dataset,
    check_claimed_estimates,
    check_covariances,
    check_estimates,
    check_not_negative,
    check_scores,
)
from jointbench.running.placement import Placements, read_placements, unplaced_estimates
from jointbench.running.scoring import ERROR_COLUMN, proximal_at_frame0, score_columns
from jointbench.running.summary import summarise
from jointbench.simulate import PROXIMAL_TRUTH, Study

__all__ = [
    "collect",
    "is_external",
    "require_results",
    "scored_estimates",
    "summarise_estimates",
]


def scored_estimates(
    frame: pd.DataFrame,
    *,
    kind: str,
    truth: Mapping[str, list[float]],
    source: str,
    proximal_frame0: np.ndarray | None = None,
) -> pd.DataFrame:
    """``frame``, one estimates file checked by :func:`check_estimates`, with its score columns
    computed from its estimate columns and its dataset's ``truth``
    (:func:`jointbench.running.scoring.score_columns`); ``proximal_frame0`` ``(n_rows, k, 3)``,
    each row's proximal markers at frame 0 in a two-segment study.

    ``ValueError`` naming ``source`` and the trial when the file claims success without a
    finite estimate (:func:`check_claimed_estimates`), gives a score that disagrees
    (:func:`check_scores`), a negative time or iteration count (:func:`check_not_negative`) or
    a predicted covariance that is not one (:func:`check_covariances`).
    """
    check_not_negative(frame, source=source)
    check_covariances(frame, kind, source=source)
    scores = score_columns(kind, frame, truth, proximal_frame0)
    check_claimed_estimates(frame, kind, scores[ERROR_COLUMN[kind]], source=source)
    check_scores(frame, scores, source=source)
    return frame.assign(**scores)


def require_results(
    frame: pd.DataFrame, study: str, source: str, methods: Sequence[str] = ()
) -> None:
    """Raise ``ValueError`` naming ``study`` and ``source`` when no trial of any estimator has
    a finite error, or when every trial of one of ``methods`` (those of them in ``frame``)
    failed: a figure, table or verdict made of them would show nothing as if it were a result.
    The message gives the most frequent reasons, from ``status``."""
    error = ERROR_COLUMN[get_study(study).kind]
    finite = np.isfinite(frame[error].to_numpy(dtype=float))
    if not finite.any():
        everyone = ", ".join(sorted(map(str, frame["method"].unique()))) or "no estimator"
        raise ValueError(
            f"{source}: study {study!r}: none of its {len(frame)} trials ({everyone}) has a "
            f"finite {error}: every trial failed, so there is nothing to rank, draw or compare "
            f"with a paper. Most frequent reasons: {_reasons(frame)}"
        )
    present, scored = set(frame["method"]), set(frame.loc[finite, "method"])
    failed = [m for m in methods if m in present and m not in scored]
    if failed:
        rows = frame[frame["method"].isin(failed)]
        raise ValueError(
            f"{source}: study {study!r}: every trial of {', '.join(failed)} failed (no finite "
            f"{error}), and the figures, tables and verdicts of the study's papers compare "
            f"{'it' if len(failed) == 1 else 'them'} with the others: none is made of nothing. "
            f"Most frequent reasons: {_reasons(rows)}"
        )


def _reasons(rows: pd.DataFrame, most: int = 3) -> str:
    """The ``most`` most frequent statuses of ``rows`` with their counts."""
    counts = rows["status"].astype(str).value_counts().head(most)
    return "; ".join(f"{count} × {reason!r}" for reason, count in counts.items()) or "none"


def _scored_file(path, spec: Study, datasets: Mapping[str, dict]) -> pd.DataFrame:
    """One estimates file of study ``spec`` read, its schema checked, held to its dataset (of
    ``datasets``, :func:`_datasets`: the ``trials``, ``condition``, ``truth`` and
    ``placements`` of its condition's dataset file), mapped back to the dataset's frame when
    its estimator is external (:func:`_unplaced`) and scored as its method's kind.

    Its refusals name the file its estimator wrote (:func:`read_source`): an external
    estimator's CSV, which it was converted from, else the file itself."""
    source = read_source(path)
    dataset = _dataset_of(path, datasets, source)
    frame = read_table(path)
    method = Path(path).parent.name
    kind = method_kind(spec, method)
    check_estimates(frame, kind=kind, condition_keys=spec.grid_keys, method=method, source=source)
    check_against_dataset(
        frame, trials=dataset["trials"], condition=dataset["condition"], source=source
    )
    if is_external(spec, method):
        frame = _unplaced(frame, kind, dataset["placements"], method, source)
    frame0 = dataset["proximal_frame0"]
    if frame0 is not None:
        frame0 = frame0[np.searchsorted(dataset["trials"], frame["trial"].to_numpy())]
    return scored_estimates(
        frame, kind=kind, truth=dataset["truth"], source=source, proximal_frame0=frame0
    )


def _scored_files(paths, spec: Study, datasets: Mapping[str, dict]) -> pd.DataFrame:
    """The estimates files at ``paths`` scored (:func:`_scored_file`) in one table.

    ``ValueError`` naming the column and both files when two of them give a column with other
    kinds of value (text in one, numbers in the other: a column of an estimator's own named as
    another's), which one table cannot hold; a column missing in every row of a file gives
    none."""
    frames, kinds = [], {}
    for path in paths:
        frame = _scored_file(path, spec, datasets)
        source = read_source(path)
        for column in frame.columns:
            kind = _value_kind(frame[column])
            if kind is None:
                continue
            first_kind, first_source = kinds.setdefault(column, (kind, source))
            if kind != first_kind:
                raise ValueError(
                    f"{source}: column {column!r} holds {kind}, but {first_source} gives it "
                    f"{first_kind}: a column of the collected results holds one kind of value; "
                    "give it the same kind in every file, or another name"
                )
        frames.append(frame)
    return pd.concat(frames, ignore_index=True)


def _value_kind(column: pd.Series) -> str | None:
    """What a column holds, ``numbers``, ``booleans`` or ``text`` (else pandas' name for it),
    ``None`` when every value is missing."""
    values = column.dropna()
    if values.empty:
        return None
    kind = pd.api.types.infer_dtype(values, skipna=True)
    if kind in ("integer", "floating", "mixed-integer-float", "decimal"):
        return "numbers"
    return {"boolean": "booleans", "string": "text"}.get(kind, kind)


def is_external(spec: Study, method: str) -> bool:
    """Whether ``method`` is an estimator outside the package, run by a rule of its own on the
    blind copies: no kind of ``spec`` registers the name (the config refuses an external
    estimator named as a registered one, and a built-in one that is not)."""
    return not any(method in registry.methods(kind) for kind in spec.kinds)


def _unplaced(
    frame: pd.DataFrame, kind: str, placements: Placements | None, method: str, source: str
) -> pd.DataFrame:
    """An external estimator's ``frame``, given in each trial's placed frame, mapped back to
    the dataset's (:func:`jointbench.running.placement.unplaced_estimates`). Times, counts
    and covariances are checked first, as written, which a refusal quotes (mapping sets each
    mirror equal to its entry). ``ValueError`` naming ``source`` without the condition's
    ``placements``."""
    if placements is None:
        raise ValueError(
            f"{source}: {method!r} is an external estimator, which answers in the frame of the "
            "blind copy it read, each trial placed anew; its condition's placements file "
            "(results/placements/) was not given, so its answers cannot be mapped back to be "
            "scored"
        )
    check_not_negative(frame, source=source)
    check_covariances(frame, kind, source=source)
    try:
        return unplaced_estimates(frame, kind, placements)
    except ValueError as error:
        raise ValueError(f"{source}: {error}") from None


def _datasets(
    datasets: Sequence[str | Path],
    segments: Sequence[str],
    placements: Sequence[str | Path] = (),
) -> dict[str, dict]:
    """Per condition (a dataset file's stem): its trial numbers (sorted), condition, truth,
    the placements of its blind copy (from the file of ``placements`` of the same stem, else
    ``None``) and, when its truth scores a centre relative to the proximal markers, those
    markers at frame 0 of each trial (:func:`jointbench.running.scoring.proximal_at_frame0`),
    else ``None``."""
    placed = {Path(path).stem: path for path in placements}
    out = {}
    for path in datasets:
        metadata, truth = read_metadata(path), read_truth(path)
        trials = read_trial_numbers(path)
        frame0 = None
        if PROXIMAL_TRUTH in truth:
            frame0 = np.concatenate(
                [proximal_at_frame0(block.segments, segments) for _, block in iter_dataset(path)]
            )[np.argsort(trials)]
        stem = Path(path).stem
        out[stem] = {
            "path": path,
            "trials": np.sort(trials),
            "condition": metadata["condition"],
            "truth": truth,
            "proximal_frame0": frame0,
            "placements": read_placements(placed[stem]) if stem in placed else None,
        }
    return out


def _check_blind_copies(blinds: Sequence[str | Path], datasets: Mapping[str, dict]) -> None:
    """Each blind copy of ``blinds`` held to what was written from its condition's dataset and
    placements (of ``datasets``, :func:`_datasets`): ``ValueError`` naming the copy when it
    changed, or when its placements were not given and it cannot be checked."""
    for blind in blinds:
        dataset = _dataset_of(blind, datasets, str(blind))
        if dataset["placements"] is None:
            raise ValueError(
                f"{blind}: its placements file (results/placements/) was not given, so the "
                "blind copy cannot be held to what was written from its dataset"
            )
        check_blind_copy(blind, dataset["path"], dataset["placements"])


def _dataset_of(path, datasets: Mapping[str, dict], source: str) -> dict:
    if Path(path).stem not in datasets:
        raise ValueError(f"{source}: no dataset file of condition {Path(path).stem!r}")
    return datasets[Path(path).stem]


def collect(
    study: str,
    paths: Sequence[str | Path],
    output: str,
    datasets: Sequence[str | Path],
    provenance: Mapping[str, object] | None = None,
    placements: Sequence[str | Path] = (),
    blinds: Sequence[str | Path] = (),
) -> pd.DataFrame:
    """Concatenate a study's estimates files after checking each one's schema, holding it to
    the dataset file of its condition (same trials, each once, same condition values), mapping
    an external estimator's answers back from its blind copy's placements (``placements``: a
    placements file per condition, named as its dataset file; required for every condition
    an external estimator answered) and scoring it against that dataset's truth
    (:func:`scored_estimates`); refuse a study with no finite error at all
    (:func:`require_results`), and a blind copy of ``blinds`` (named as its dataset file) that
    is no longer what was written from its dataset and placements
    (:func:`jointbench.resultfiles.parquet.check_blind_copy`): the external estimators that
    read it may have fit other markers.

    The collected file's provenance adds, per estimator, the provenance of its estimates files
    (an external estimator's files have none)."""
    spec = get_study(study)
    # Each dataset is read once, whatever the number of estimators.
    expected = _datasets(datasets, spec.segments, placements)
    _check_blind_copies(blinds, expected)
    estimators: dict[str, dict] = {}
    for path in paths:
        estimators.setdefault(Path(path).parent.name, read_provenance(path))
    collected = _scored_files(paths, spec, expected)
    collected = collected.sort_values([*spec.grid_keys, "method", "trial"], kind="stable")
    require_results(collected, study, output)
    write_table(collected, output, {**(provenance or {}), "estimators": estimators})
    return collected


def summarise_estimates(
    study: str,
    paths: Sequence[str],
    output: str,
    datasets: Sequence[str | Path],
    placements: Sequence[str | Path] = (),
) -> None:
    """One estimator's mean and median error per condition, from its estimates files scored
    against their conditions' ``datasets`` (an external estimator's mapped back by the
    ``placements``) as :func:`collect` scores them."""
    spec = get_study(study)
    expected = _datasets(datasets, spec.segments, placements)
    summarise(_scored_files(paths, spec, expected), study).to_csv(output, index=False)
