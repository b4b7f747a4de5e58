"""Simulate a condition, fit its trials' poses, run an estimator over its trials.

These are the many small jobs of a run, so this module and what it imports stay clear of
pandas: estimates are built and written as Arrow tables (:mod:`jointbench.running.collected`
gathers them into frames).
"""

from __future__ import annotations

import dataclasses
import logging
import os
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import pyarrow as pa

from jointbench.configuration.config import condition_id, estimator_names, parse_condition_id
from jointbench.configuration.seeds import trial_rng
from jointbench.configuration.studies import get_study, method_kind
from jointbench.estimators import registry
from jointbench.estimators.batching import ProgrammingError, failed_trial, mistakes_named
from jointbench.estimators.segment_poses import POSE_MIN_FRAMES, pose_segments, trial_poses
from jointbench.resultfiles.parquet import (
    iter_dataset,
    read_metadata,
    read_poses,
    rows_table,
    write_dataset_blocks,
    write_poses_blocks,
    write_table,
)
from jointbench.resultfiles.schema import check_estimates, estimates_columns
from jointbench.running.scoring import proximal_at_frame0, score
from jointbench.simulate import Diagnostic, Study, Trials

if TYPE_CHECKING:
    import pandas as pd

log = logging.getLogger(__name__)

__all__ = [
    "estimate",
    "estimate_table",
    "methods_sharing_poses",
    "progress_line",
    "run_estimate_files",
    "run_poses_files",
    "run_simulate_files",
    "simulate_condition",
]


#: Trials simulated at once when writing a dataset: memory stays bounded whatever the trials.
SIMULATE_BLOCK_TRIALS = 250


def simulate_condition(
    config: Mapping, study: str, condition: Mapping[str, object], trials: range | None = None
) -> Trials:
    """The trials of one condition (all, or the ``trials`` range), each from its own seed (see
    :mod:`jointbench.configuration.seeds`), so a trial is the same whichever others are
    simulated. :class:`~jointbench.estimators.batching.ProgrammingError` where a study that
    declares its trials' frames (:attr:`~jointbench.simulate.Study.frame_count`, which the
    config's check trusts without simulating) simulates others."""
    spec = get_study(study)
    settings = config["studies"][study]
    protocol = spec.protocol(settings.get("protocol"))
    seed_condition = {key: condition[key] for key in spec.seed_keys}
    numbers = range(int(settings["trials"])) if trials is None else trials
    rngs = [trial_rng(config["base_seed"], study, seed_condition, trial) for trial in numbers]
    simulated = spec.simulate(condition, protocol, rngs)
    _check_frame_count(spec, condition, protocol, simulated)
    return simulated


def _check_frame_count(
    spec: Study, condition: Mapping[str, object], protocol: object, trials: Trials
) -> None:
    """Refuse ``trials`` whose frames are not those ``spec`` declares for ``condition`` under
    ``protocol``: the config's check held the declared count, not these, against the
    estimators' fewest frames."""
    declared = spec.frame_count(condition, protocol)
    frames = trials.segments[spec.segments[0]].shape[1]
    if frames != declared:
        raise ProgrammingError(
            f"study {spec.name!r}: condition {condition_id(condition)}: its frame_count "
            f"declares {declared} frames a trial, its simulator gave {frames}"
        )


def _outcome(result) -> tuple[object, str, bool, int]:
    """Row fields of one fit's result, or of the exception a many-trial form returned for a
    trial: a failure the method states (bad geometry, a singular system, an overflow:
    :func:`jointbench.estimators.batching.numerical_failure`) is a failed row; any other
    exception is a bug in the estimator or its options, raised as a
    :class:`~jointbench.estimators.batching.ProgrammingError`."""
    if isinstance(result, BaseException):
        failed_trial(result)
        return None, f"error: {type(result).__name__}: {result}", False, 0
    return result, str(result.status), bool(result.converged), int(result.iterations)


def _fit_trials(many, segments, trials: Trials, options, poses=None) -> list[tuple]:
    """``(result, status, converged, iterations, seconds)`` of every trial, fitted on its
    ``segments`` (names, in argument order), all trials in one call of the method's many-trial
    form ``many`` (:func:`jointbench.estimators.registry.many`: its own, or its one-trial
    function trial by trial); a pose-based method also takes the trials' fitted ``poses``.
    ``seconds`` [s] is that call's wall time divided by the trials: every estimator, built-in
    or not, is timed this one way."""
    if poses is not None:
        options = {**options, "poses": poses}
    start = time.perf_counter()
    outcomes = many(*(trials.segments[name] for name in segments), **options)
    seconds = (time.perf_counter() - start) / max(trials.n_trials, 1)
    return [(*_outcome(outcome), seconds) for outcome in outcomes]


def _warm_up(many, segments, trials: Trials, options, poses=None) -> float:
    """Fit the first trial on its own, before any fit is timed; returns its wall time [s].

    An estimator's first call in a process does one-time work besides fitting: Numba compiles
    its kernels (or loads them from its cache), modules imported on first use load, caches
    fill. Timed with the first trials, that work inflated the first condition of every job by up
    to seconds per trial, and with it the means of paper A Table 2. The warm-up takes the same
    path as the timed fits (the same many-trial form and array types), so nothing is compiled
    after it.
    """
    first = dataclasses.replace(trials, segments={k: v[:1] for k, v in trials.segments.items()})
    start = time.perf_counter()
    _fit_trials(many, segments, first, options, None if poses is None else poses[:1])
    return time.perf_counter() - start


def methods_sharing_poses(config: Mapping, study: str) -> list[str]:
    """The study's built-in estimators that share one pose fit per trial: its pose-based ones
    (see :func:`jointbench.estimators.segment_poses.pose_segments`) when there are two or more.

    Their estimate jobs read the poses that one job fitted (:func:`run_poses_files`) instead of
    each fitting them again; a single pose-based method fits its own.
    """
    spec = get_study(study)
    pose_based = [
        method
        for method in estimator_names(config, study, source="builtin")
        if pose_segments(registry.many(method_kind(spec, method), method, checked=False))
        == spec.segments
    ]
    return pose_based if len(pose_based) >= 2 else []


def estimate(
    study: str,
    method: str,
    trials: Trials,
    condition: Mapping[str, object],
    options: Mapping[str, object] | None = None,
    poses: list | None = None,
) -> pd.DataFrame:
    """One row per trial: condition, estimate, error, converged, iterations, seconds, status.

    ``seconds`` is the fit's wall time [s], after a warm-up fit whose one-time costs it leaves
    out (:func:`_warm_up`; its time goes to the log). Every estimator fits all trials in one call
    of its many-trial form, and ``seconds`` is that call's wall time divided by the trials.
    ``poses``, the trials' pose fits (see :func:`run_poses_files`), are passed to a pose-based
    method instead of fitting them again. The frame of :func:`estimate_table`.
    """
    return estimate_table(study, method, trials, condition, options, poses).to_pandas()


def estimate_table(
    study: str,
    method: str,
    trials: Trials,
    condition: Mapping[str, object],
    options: Mapping[str, object] | None = None,
    poses: list | None = None,
    first_trial: int = 0,
    warm_up: bool = True,
) -> pa.Table:
    """:func:`estimate` as an Arrow table, its trials numbered from ``first_trial``.

    ``warm_up=False`` leaves out the warm-up fit (:func:`_warm_up`): for a process that has
    already fitted ``method`` once, whose one-time work is done.
    """
    spec = get_study(study)
    # The estimator alone: simulated data are valid by construction, and the seconds column
    # (paper A Table 2) times the estimator, not the input checks a user's call goes through.
    kind = method_kind(spec, method)
    segments = spec.segments_of(kind)
    many = registry.many(kind, method, checked=False)
    if poses is not None and pose_segments(many) != spec.segments:
        raise ValueError(f"{study} {method}: not a pose-based method; it takes no fitted poses")
    diagnose = spec.diagnostics.get(method)
    options = options or {}
    # Before the warm-up: a direct call's options have passed no config check.
    registry.check_options(kind, method, options, f"{study} {method}")
    with mistakes_named(f"{study} {method}"):
        if warm_up:
            log.info(
                "%s %s: warm-up fit of trial %d in %.3f s (compilation, first-call imports), "
                "not counted in any trial's seconds",
                study,
                method,
                first_trial,
                _warm_up(many, segments, trials, options, poses),
            )
        fitted = _fit_trials(many, segments, trials, options, poses)
        extras = [{}] * trials.n_trials
        if diagnose:
            arrays = tuple(trials.segments[name] for name in segments)
            written = estimates_columns(kind, spec.grid_keys)
            extras = _diagnosed(
                diagnose, written, arrays, [row[0] for row in fitted], trials.truth, first_trial
            )
    frame0 = proximal_at_frame0(trials.segments, spec.segments)
    rows = []
    for trial, ((result, status, converged, iterations, seconds), extra) in enumerate(
        zip(fitted, extras, strict=True)
    ):
        rows.append(
            {
                **condition,
                "trial": first_trial + trial,
                "method": method,
                **score(kind, result, trials.truth, None if frame0 is None else frame0[trial]),
                "converged": converged,
                "iterations": iterations,
                "seconds": seconds,
                "status": status,
                **extra,
            }
        )
    table = rows_table(rows)
    check_estimates(table, kind=kind, condition_keys=spec.grid_keys, method=method)
    return table


def _diagnosed(
    check: Diagnostic, written: Sequence[str], arguments, results, truth, first_trial: int = 0
) -> list[dict[str, object]]:
    """The rows of ``check`` (:class:`~jointbench.simulate.Diagnostic`) for one condition's
    trials, numbered from ``first_trial``; :class:`~jointbench.estimators.batching.ProgrammingError`
    naming a column it declares among those the estimate job writes itself (``written``: its
    rows would replace the estimator's status or score), one it writes and does not declare,
    which a claim could not select as one its study records, or one it declares and leaves
    out of a row it writes (a trial with no result has an empty one), which would read as not
    measured in that trial where the diagnostic measured nothing and said so in no value."""
    name = getattr(check.diagnose, "__name__", repr(check.diagnose))
    taken = [column for column in check.columns if column in written]
    if taken:
        raise ProgrammingError(
            f"its diagnostic {name} declares the columns {', '.join(taken)}, which the "
            "estimate job writes itself; name its own columns otherwise"
        )
    rows = check.diagnose(arguments, results, truth)
    found = {column for row in rows for column in row}
    undeclared = sorted(found - set(check.columns))
    if undeclared:
        raise ProgrammingError(
            f"its diagnostic {name} writes the columns {', '.join(undeclared)}, which it does "
            f"not declare (it declares {', '.join(check.columns) or 'none'})"
        )
    # A trial with no result has an empty row: no column tells of the diagnostic there.
    for trial, row in enumerate(rows, start=first_trial):
        unwritten = [column for column in check.columns if column not in row]
        if row and unwritten:
            raise ProgrammingError(
                f"its diagnostic {name} declares the columns {', '.join(unwritten)}, which it "
                f"does not write in the row of trial {trial} (it writes {', '.join(row)})"
            )
    return rows


def run_simulate_files(
    config: Mapping,
    study: str,
    outputs: Sequence[str],
    provenance: Mapping[str, object] | None = None,
) -> None:
    """Simulate the condition each output file is named after (see ``condition_id``)."""
    n_trials = int(config["studies"][study]["trials"])
    for output in outputs:
        condition = parse_condition_id(config, study, Path(output).stem)
        blocks = (
            simulate_condition(
                config, study, condition, range(first, min(first + SIMULATE_BLOCK_TRIALS, n_trials))
            )
            for first in range(0, n_trials, SIMULATE_BLOCK_TRIALS)
        )
        write_dataset_blocks(
            output, blocks, n_trials, study=study, condition=condition, provenance=provenance
        )


def _same_condition(paths: Sequence[str], outputs: Sequence[str], what: str) -> list[str]:
    """The file of ``paths`` named like each output (its condition), in the outputs' order."""
    for files, kind in ((paths, what), (outputs, "output")):
        # A string is a sequence too: iterated, it would give one "file" per character.
        if isinstance(files, str | os.PathLike):
            raise TypeError(f"{kind} files must be a list of paths, not one path: {files!r}")
    by_condition = {Path(path).stem: path for path in paths}
    missing = [Path(output).stem for output in outputs if Path(output).stem not in by_condition]
    if missing:
        raise ValueError(f"no {what} file of condition {missing[0]!r} among {list(paths)}")
    return [by_condition[Path(output).stem] for output in outputs]


def run_poses_files(
    study: str,
    datasets: Sequence[str],
    outputs: Sequence[str],
    provenance: Mapping[str, object] | None = None,
) -> None:
    """Fit the poses of every trial of each dataset file once (paper C §5, see
    :func:`jointbench.estimators.segment_poses.trial_poses`), writing the poses file of the same
    condition for the pose-based estimators to share."""
    spec = get_study(study)
    start = time.perf_counter()
    paths = _same_condition(datasets, outputs, "dataset")
    for done, (path, output) in enumerate(zip(paths, outputs, strict=True), start=1):
        shapes = read_metadata(path)["shapes"]
        blocks = (
            trial_poses(
                {name: block.segments[name] for name in spec.segments},
                min_frames=POSE_MIN_FRAMES,
            )
            for _, block in iter_dataset(path)
        )
        write_poses_blocks(
            output,
            blocks,
            shapes={name: shapes[name] for name in spec.segments},
            provenance=provenance,
        )
        trials = shapes[spec.segments[0]][0]
        log.info(progress_line(f"{study} poses", done, len(outputs), start, trials))


def run_estimate_files(
    config: Mapping,
    study: str,
    method: str,
    datasets: Sequence[str],
    outputs: Sequence[str],
    provenance: Mapping[str, object] | None = None,
    poses: Sequence[str] | None = None,
) -> None:
    """Run one built-in estimator over each dataset file, writing the estimates file of the
    same condition; a pose-based method given the conditions' ``poses`` files (from
    :func:`run_poses_files`) uses the poses stored there."""
    options = config["studies"][study].get("options", {}).get(method, {})
    segments = get_study(study).segments
    paths = _same_condition(datasets, outputs, "dataset")
    poses_paths = _same_condition(poses, outputs, "poses") if poses else [None] * len(outputs)
    start = time.perf_counter()
    for done, (path, poses_path, output) in enumerate(
        zip(paths, poses_paths, outputs, strict=True), start=1
    ):
        condition = read_metadata(path)["condition"]
        # A block of trials at a time, so memory does not grow with the number of trials.
        tables = []
        for first, block in iter_dataset(path):
            stored = None
            if poses_path is not None:
                stored = read_poses(poses_path, first, {s: block.segments[s] for s in segments})
            tables.append(
                estimate_table(study, method, block, condition, options, stored, first_trial=first)
            )
        # A column missing in every row of one block, or integer in one and float in another,
        # takes the type that holds both.
        table = pa.concat_tables(tables, promote_options="permissive")
        write_table(table, output, provenance)
        log.info(progress_line(f"{study} {method}", done, len(outputs), start, len(table)))


def progress_line(what: str, done: int, total: int, start: float, trials: int) -> str:
    """A progress bar with the time left, for a job's log: ``[####------] 4/10 conditions``."""
    elapsed = time.perf_counter() - start
    left = elapsed / done * (total - done)
    filled = round(20 * done / total)
    return (
        f"{what}: [{'#' * filled}{'-' * (20 - filled)}] {done}/{total} conditions "
        f"({trials} trials in the last), {elapsed:.1f} s elapsed, about {left:.0f} s left"
    )
