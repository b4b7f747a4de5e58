"""Simulate a condition, run an estimator over its trials, collect the results."""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from pathlib import Path

import pandas as pd

from jointbench.estimators import registry
from jointbench.simulate import Trials
from jointbench.study.config import parse_condition_id
from jointbench.study.diagnostics import DIAGNOSTICS
from jointbench.study.io import iter_dataset, read_metadata, write_dataset, write_table
from jointbench.study.schema import check_estimates
from jointbench.study.scoring import score
from jointbench.study.seeds import trial_rng
from jointbench.study.studies import get_study

__all__ = ["collect", "estimate", "run_estimate_files", "run_simulate_files", "simulate_condition"]


def simulate_condition(config: Mapping, study: str, condition: Mapping[str, object]) -> Trials:
    """All trials of one condition, each from its own seed (see :mod:`jointbench.study.seeds`)."""
    spec = get_study(study)
    settings = config["studies"][study]
    protocol = spec.protocol(settings.get("protocol"))
    seed_condition = {key: condition[key] for key in spec.seed_keys}
    rngs = [
        trial_rng(config["base_seed"], study, seed_condition, trial)
        for trial in range(int(settings["trials"]))
    ]
    return spec.simulate(condition, protocol, rngs)


def _fit_one(fit, arguments, options) -> tuple[object, str, bool, int]:
    """Run one fit; an exception becomes a failed row rather than a failed run."""
    try:
        result = fit(*arguments, **options)
    except Exception as error:
        return _outcome(error)
    return _outcome(result)


def _outcome(result) -> tuple[object, str, bool, int]:
    if isinstance(result, Exception):
        return None, f"error: {type(result).__name__}: {result}", False, 0
    return result, str(result.status), bool(result.converged), int(result.iterations)


def _fit_all(fit, spec, trials: Trials, options) -> tuple[list, float] | None:
    """All trials at once through the estimator's ``batched`` form, if it has one.

    ``fit.batched(*segments, **options)`` takes each segment as ``(n_trials, ...)`` and returns
    per trial what ``fit`` returns or the exception it raises. Returns the outcomes and the
    batch's wall time divided by the trials, or ``None`` to fit one trial at a time.
    """
    batched = getattr(fit, "batched", None)
    if batched is None:
        return None
    start = time.perf_counter()
    outcomes = batched(*(trials.segments[name] for name in spec.segments), **options)
    return outcomes, (time.perf_counter() - start) / max(trials.n_trials, 1)


def estimate(
    study: str,
    method: str,
    trials: Trials,
    condition: Mapping[str, object],
    options: Mapping[str, object] | None = None,
) -> pd.DataFrame:
    """One row per trial: condition, estimate, error, converged, iterations, seconds, status.

    Estimators with a ``batched`` form fit all trials in one call; their ``seconds`` is the
    batch's wall time divided by the number of trials.
    """
    spec = get_study(study)
    fit = registry.get(spec.kind, method)
    diagnose = DIAGNOSTICS.get((study, method))
    batch = _fit_all(fit, spec, trials, options or {})
    rows = []
    for trial in range(trials.n_trials):
        arguments = spec.fit_arguments(trials, trial)
        if batch is None:
            start = time.perf_counter()
            result, status, converged, iterations = _fit_one(fit, arguments, options or {})
            seconds = time.perf_counter() - start
        else:
            result, status, converged, iterations = _outcome(batch[0][trial])
            seconds = batch[1]
        extra = diagnose(arguments, result, trials.truth) if diagnose and result else {}
        rows.append(
            {
                **condition,
                "trial": trial,
                "method": method,
                **score(spec.kind, result, trials.truth),
                "converged": converged,
                "iterations": iterations,
                "seconds": seconds,
                "status": status,
                **extra,
            }
        )
    frame = pd.DataFrame(rows)
    check_estimates(frame, kind=spec.kind, condition_keys=spec.grid_keys, method=method)
    return frame


def run_simulate_files(config: Mapping, study: str, outputs: Sequence[str]) -> None:
    """Simulate the condition each output file is named after (see ``condition_id``)."""
    for output in outputs:
        condition = parse_condition_id(config, study, Path(output).stem)
        trials = simulate_condition(config, study, condition)
        write_dataset(output, trials, study=study, condition=condition)


def run_estimate_files(
    config: Mapping, study: str, method: str, datasets: Sequence[str], outputs: Sequence[str]
) -> None:
    """Run one built-in estimator over each dataset file, writing the estimates file of the
    same condition."""
    options = config["studies"][study].get("options", {}).get(method, {})
    by_condition = {Path(path).stem: path for path in datasets}
    for output in outputs:
        path = by_condition[Path(output).stem]
        condition = read_metadata(path)["condition"]
        # A block of trials at a time, so memory does not grow with the number of trials.
        frames = [
            estimate(study, method, block, condition, options).assign(
                trial=lambda frame, first=first: frame["trial"] + first
            )
            for first, block in iter_dataset(path)
        ]
        write_table(pd.concat(frames, ignore_index=True), output)


def collect(study: str, paths: Sequence[str | Path], output: str) -> pd.DataFrame:
    """Concatenate a study's estimates files after checking each one's schema."""
    spec = get_study(study)
    frames = []
    for path in paths:
        frame = pd.read_parquet(path)
        method = Path(path).parent.name
        check_estimates(
            frame, kind=spec.kind, condition_keys=spec.grid_keys, method=method, source=str(path)
        )
        frames.append(frame)
    collected = pd.concat(frames, ignore_index=True)
    collected = collected.sort_values([*spec.grid_keys, "method", "trial"], kind="stable")
    write_table(collected, output)
    return collected
