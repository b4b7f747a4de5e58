"""Seed ensembles: every published value and claim judged over independent base seeds.

One run of the benchmark draws its trials from one base seed, so each verdict of the comparison
is one draw. An ensemble reruns each study's papers from ``K`` base seeds (member 0 is the
run's own ``base_seed``, so the default run is one named member), judges every value and claim
in each member exactly as the comparison does
(:func:`jointbench.comparison.published.comparison_rows`) and writes each member's rows
(:data:`MEMBER_COLUMNS`).

:mod:`jointbench.ensembles.verdicts` turns the members' rows into the verdict over seeds.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping

import pandas as pd

from jointbench.comparison.published import comparison_rows, load_published
from jointbench.configuration.config import conditions, estimator_names
from jointbench.configuration.studies import get_study
from jointbench.estimators.segment_poses import POSE_MIN_FRAMES, trial_poses
from jointbench.papers import Inputs, papers_of_study
from jointbench.running.collected import require_results
from jointbench.running.run import estimate_table, methods_sharing_poses, simulate_condition

__all__ = [
    "MEMBER_COLUMNS",
    "collect_member",
    "judge",
    "measured_methods",
    "member_seed",
    "run_member",
]

MEMBER_COLUMNS = [
    "member",
    "base_seed",
    "paper",
    "study",
    "entry",
    "id",
    "status",
    "margin",
    "reproduced",
]


def member_seed(base_seed: int, member: int) -> int:
    """The base seed of ensemble member ``member``: ``base_seed`` itself for member 0 (the
    default run), otherwise 63 bits of SHA-256 of both, independent of ``K`` and job order."""
    if member == 0:
        return int(base_seed)
    digest = hashlib.sha256(f"jointbench-ensemble:{int(base_seed)}:{int(member)}".encode())
    return int.from_bytes(digest.digest()[:8], "little") >> 1


def measured_methods(config: Mapping, study: str) -> list[str]:
    """The built-in estimators of ``study`` in ``config`` that its papers' measures read (their
    ``methods`` and ``also_measures``), in config order: all a member needs to run."""
    read = {m for paper in papers_of_study(study) for m in (*paper.methods, *paper.also_measures)}
    return [m for m in estimator_names(config, study, source="builtin") if m in read]


def _member_config(config: Mapping, study: str, seed: int) -> dict:
    """``config`` with base seed ``seed`` and ``study``'s estimators cut to those its papers
    measure (:func:`measured_methods`)."""
    settings = dict(config["studies"][study])
    settings["estimators"] = measured_methods(config, study)
    settings.pop("external_estimators", None)
    return {**config, "base_seed": int(seed), "studies": {**config["studies"], study: settings}}


def collect_member(config: Mapping, study: str) -> pd.DataFrame:
    """Every condition of ``study`` simulated and estimated in memory by the estimators of
    ``config``, scored as the collected results are (one row per trial and method)."""
    spec = get_study(study)
    methods = estimator_names(config, study, source="builtin")
    shared = set(methods_sharing_poses(config, study))
    options = config["studies"][study].get("options", {})
    frames = []
    # One warm-up per method: its one-time work (compilation, first-call imports) is done
    # after its first condition, and a warm-up fit costs up to a third of a batch.
    warmed: set[str] = set()
    for condition in conditions(config, study):
        trials = simulate_condition(config, study, condition)
        poses = None
        if shared:
            poses = trial_poses(
                {name: trials.segments[name] for name in spec.segments},
                min_frames=POSE_MIN_FRAMES,
            )
        for method in methods:
            table = estimate_table(
                study,
                method,
                trials,
                condition,
                options.get(method, {}),
                poses if method in shared else None,
                warm_up=method not in warmed,
            )
            warmed.add(method)
            frames.append(table.to_pandas())
    collected = pd.concat(frames, ignore_index=True)
    return collected.sort_values([*spec.grid_keys, "method", "trial"], kind="stable")


def run_member(config: Mapping, study: str, member: int) -> pd.DataFrame:
    """Every published value and claim of ``study``'s papers judged in ensemble member
    ``member`` (columns :data:`MEMBER_COLUMNS`)."""
    seed = member_seed(config["base_seed"], member)
    member_config = _member_config(config, study, seed)
    collected = collect_member(member_config, study)
    rows = judge(member_config, study, collected, f"ensemble member {member}")
    return rows.assign(member=member, base_seed=seed)[MEMBER_COLUMNS]


def judge(config: Mapping, study: str, collected: pd.DataFrame, label: str) -> pd.DataFrame:
    """Every published value and claim of ``study``'s papers judged on ``collected`` (the
    results of ``config``) as the comparison judges them; ``label`` names the results in an
    error."""
    frames = []
    for paper in papers_of_study(study):
        require_results(collected, study, label, paper.methods)
        document = load_published(paper.published, paper.declares, paper.tables)
        inputs = Inputs(collected=collected, published=document, config=config)
        frames.append(comparison_rows(document, paper.measure(inputs)))
    return pd.concat(frames, ignore_index=True)
