"""Protocol ensembles: every published value and claim judged over plausible protocols.

The papers leave choices unsaid (marker directions, the motion's shape, where the joint sits,
the rig's swing) and each simulator fills them with one value. A protocol ensemble reruns a
study's papers on ``N`` protocols drawn from the study's prior
(:data:`PRIORS`, :mod:`jointbench.simulate.prior`), judging every value and claim as the
comparison does (:func:`jointbench.ensembles.members.judge`). Members, by name:

* ``default``: the config's own protocol, the run that the comparison reports;
* ``draw-k`` (``k = 1..N``): the ``k``-th draw of the prior, fixed by the base seed, the study
  and ``k`` (:func:`draw_seed`);
* a named variant: the protocol of a config overlay (e.g. the anatomy-first knee layout).

Every member simulates its trials from the run's base seed, so members differ by their
protocol alone. The share of draws reproducing a value is its share of plausible protocols;
:func:`split_half_effects` says which choice it depends on most.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from jointbench.comparison.published import load_published
from jointbench.configuration.config import read_yaml
from jointbench.ensembles.members import _member_config, collect_member, judge
from jointbench.ensembles.named import DEFAULT, DRAW_PREFIX, PRIORS, member_names
from jointbench.ensembles.verdicts import TESTED, quantities_of, seed_verdict, share_columns
from jointbench.figures.paper_a import condition_means
from jointbench.figures.paper_c import calibration_table
from jointbench.resultfiles.tables import markdown_table, write_tables
from jointbench.simulate.prior import default_values, draw_values

__all__ = [
    "CURVES",
    "DEFAULT",
    "DEPENDENCE_MEASURE",
    "PRIORS",
    "SUMMARY_COLUMNS",
    "depends_most_on",
    "draw_seed",
    "member_names",
    "member_protocol",
    "member_values",
    "prior_table",
    "protocol_verdict",
    "run_member",
    "split_half_effects",
    "summarise",
    "write_member",
    "write_summary",
]

DEPENDENCE_MEASURE = (
    "the choice whose draws split at its median give the largest difference in the share of "
    "draws reproducing the value (upper half minus lower half; the sign says which way)"
)
SUMMARY_COLUMNS = [
    "paper",
    "entry",
    "id",
    "quantity",
    "draws",
    "reproduced_in",
    "share",
    "interval_95",
    "verdict",
    "default",
    "default_margin",
    "draws_below_default",
    "depends_most_on",
    "difference",
]


#: Per study, the per-member curve the sensitivity figures draw bands of: paper A's Fig 4
#: means, paper C's calibration table.
CURVES: dict[str, Callable[[pd.DataFrame], pd.DataFrame]] = {
    "cmc": condition_means,
    "hip": calibration_table,
}


def draw_seed(base_seed: int, study: str, draw: int) -> int:
    """The seed of draw ``draw`` of ``study``'s prior: 63 bits of SHA-256 of the three, the
    same whatever ``N`` and job order."""
    text = f"jointbench-protocol:{int(base_seed)}:{study}:{int(draw)}"
    return int.from_bytes(hashlib.sha256(text.encode()).digest()[:8], "little") >> 1


def member_values(base_seed: int, study: str, member: str) -> dict[str, float]:
    """The value of each of ``study``'s choices in ``member`` (``default`` or ``draw-k``)."""
    prior = PRIORS[study]
    if member == DEFAULT:
        return default_values(prior)
    if member.startswith(DRAW_PREFIX) and member[len(DRAW_PREFIX) :].isdigit():
        return draw_values(prior, draw_seed(base_seed, study, int(member[len(DRAW_PREFIX) :])))
    raise ValueError(f"member {member!r} of {study!r} is neither {DEFAULT!r} nor 'draw-<k>'")


def _merged(base: Mapping, overrides: Mapping) -> dict:
    """``base`` updated by ``overrides``, mappings under a key merged one level down (a hinge
    joint's or a marker set's fields), other values replaced."""
    merged = dict(base)
    for key, value in overrides.items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), Mapping):
            merged[key] = {**merged[key], **value}
        else:
            merged[key] = value
    return merged


def member_protocol(config: Mapping, study: str, member: str, overlay: Mapping | None) -> dict:
    """The ``protocol`` overrides ``study`` runs in ``member``: the config's own for the
    default, updated by the draw for ``draw-k``, by ``overlay`` (a config document) for a
    named variant."""
    own = dict(config["studies"][study].get("protocol") or {})
    if overlay is not None:
        settings = overlay.get("studies", {}).get(study, {})
        if "protocol" not in settings:
            raise ValueError(f"variant {member!r} sets no protocol of study {study!r}")
        return _merged(own, settings["protocol"])
    if member == DEFAULT:
        return own
    values = member_values(config["base_seed"], study, member)
    return _merged(own, PRIORS[study].build(values))


def run_member(
    config: Mapping, study: str, member: str, overlay: Mapping | None = None
) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``study``'s papers judged in protocol ``member``, from the run's base seed: the rows of
    :func:`jointbench.ensembles.members.judge` with ``member``, and the member's curve
    (:data:`CURVES`; empty for a study without one)."""
    settings = {**config["studies"][study]}
    settings["protocol"] = member_protocol(config, study, member, overlay)
    protocol_config = {**config, "studies": {**config["studies"], study: settings}}
    run_config = _member_config(protocol_config, study, config["base_seed"])
    collected = collect_member(run_config, study)
    rows = judge(run_config, study, collected, f"protocol member {member}")
    curve = CURVES[study](collected) if study in CURVES else pd.DataFrame()
    return rows.assign(member=member, study=study), curve.assign(member=member, study=study)


def protocol_verdict(reproduced_in: int, draws: int) -> str:
    """The verdict over protocols, by the rule of the verdict over seeds
    (:data:`jointbench.ensembles.verdicts.VERDICT_RULE`) with protocols for seeds."""
    return seed_verdict(reproduced_in, draws).replace("seed-", "protocol-")


def split_half_effects(reproduced: pd.Series, values: pd.DataFrame) -> pd.Series:
    """Per choice (a column of ``values``, one row per draw, aligned with the booleans
    ``reproduced``): the share reproducing among the draws above the choice's median minus the
    share among those at or below it; 0 where one half is empty."""
    effects = {}
    for name in values.columns:
        upper = values[name] > values[name].median()
        if upper.all() or not upper.any():
            effects[name] = 0.0
            continue
        effects[name] = float(reproduced[upper].mean() - reproduced[~upper].mean())
    return pd.Series(effects, dtype=float)


def depends_most_on(reproduced: pd.Series, values: pd.DataFrame) -> tuple[str, float]:
    """The choice with the largest split-half difference (:func:`split_half_effects`) and the
    difference; ``("", 0.0)`` when no choice changes the share."""
    effects = split_half_effects(reproduced, values)
    if effects.empty or not effects.abs().max() > 0:
        return "", 0.0
    name = str(effects.abs().idxmax())
    return name, float(effects[name])


def _where_default(default_margin: float, draw_margins: pd.Series) -> float:
    """The share of draws whose margin is below the default's: where it sits among them."""
    margins = pd.to_numeric(draw_margins, errors="coerce").dropna()
    if margins.empty or not np.isfinite(default_margin):
        return np.nan
    return float((margins < default_margin).mean())


def summarise(
    rows: pd.DataFrame, values: pd.DataFrame, quantities: Mapping[str, str]
) -> pd.DataFrame:
    """Per value and claim (``rows``: every member's comparison rows), over the ``draw-k``
    members: the share reproducing it with its Wilson 95 % interval and verdict
    (:func:`protocol_verdict`), the default member's status and margin and the share of draws
    with a smaller margin, and the choice it depends on most (:func:`depends_most_on`;
    ``values``: one row per study and member, one column per choice). Columns
    :data:`SUMMARY_COLUMNS`."""
    summary = []
    for (paper, entry, entry_id), part in rows.groupby(
        ["paper", "entry", "id"], sort=False, observed=True
    ):
        study = part["study"].iloc[0]
        draws = part[part["member"].str.startswith(DRAW_PREFIX) & part["status"].isin(TESTED)]
        held = (draws["status"] == "reproduced").reset_index(drop=True)
        k, n = int(held.sum()), len(held)
        drawn = values[values["study"] == study].drop(columns="study").set_index("member")
        drawn = drawn.reindex(draws["member"]).dropna(axis=1, how="all").reset_index(drop=True)
        choice, difference = depends_most_on(held, drawn)
        default = part[part["member"] == DEFAULT]
        margin = pd.to_numeric(default["margin"], errors="coerce")
        default_margin = float(margin.iloc[0]) if len(margin) else np.nan
        summary.append(
            {
                "paper": paper,
                "entry": entry,
                "id": entry_id,
                "quantity": quantities.get(entry_id, ""),
                "draws": n,
                **share_columns(k, n),
                "verdict": protocol_verdict(k, n),
                "default": default["status"].iloc[0] if len(default) else "",
                "default_margin": default_margin,
                "draws_below_default": _where_default(default_margin, draws["margin"]),
                "depends_most_on": choice,
                "difference": difference,
            }
        )
    return pd.DataFrame(summary, columns=SUMMARY_COLUMNS)


def named_statuses(rows: pd.DataFrame) -> pd.DataFrame:
    """Per value and claim measured by a named variant, the status in each named member and
    in the default (one column per member)."""
    named = rows[~rows["member"].str.startswith(DRAW_PREFIX)]
    variants = set(named["member"]) - {DEFAULT}
    named = named[named["study"].isin(named.loc[named["member"].isin(variants), "study"])]
    return named.pivot_table(
        index=["paper", "id"], columns="member", values="status", aggfunc="first", sort=False
    ).reset_index()


def prior_table() -> pd.DataFrame:
    """Every choice of every prior: its bounds, default, how it is drawn, the sentence it
    fills in and the reason for its bounds."""
    return pd.DataFrame(
        [
            {
                "study": study,
                "choice": choice.name,
                "low": choice.low,
                "high": choice.high,
                "default": choice.default,
                "drawn": "log-uniform" if choice.log else "uniform",
                "bounds": choice.reason,
                "sentence": choice.sentence,
            }
            for study, prior in PRIORS.items()
            for choice in prior.choices
        ]
    )


def write_member(
    config: Mapping, study: str, member: str, overlays: Sequence[str], outputs
) -> None:
    """Run ``member`` of ``study`` (:func:`run_member`; a named one's protocol from its config
    overlay, the one path in ``overlays``) and write its ``rows``, its ``curve`` and its
    ``values`` (one row: the study, the member and each drawn choice; none for a named one)."""
    if len(overlays) > 1:
        raise ValueError(f"member {member!r} of {study!r} has {len(overlays)} overlays, not one")
    overlay = read_yaml(Path(overlays[0]).read_text()) if overlays else None
    rows, curve = run_member(config, study, member, overlay)
    rows.to_csv(outputs.rows, index=False)
    curve.to_csv(outputs.curve, index=False)
    values = {} if overlay is not None else member_values(config["base_seed"], study, member)
    pd.DataFrame([{"study": study, "member": member, **values}]).to_csv(outputs.values, index=False)


def _read(paths: Sequence[str]) -> pd.DataFrame:
    return pd.concat([pd.read_csv(path) for path in paths], ignore_index=True)


def write_summary(
    members: Sequence[str], values: Sequence[str], published: Sequence[str], outputs
) -> pd.DataFrame:
    """Read the members' rows and drawn values, write the summary over protocols, the named
    variants' statuses and the prior as CSV, Markdown and HTML, and return the summary."""
    rows = _read(members)
    drawn = _read(values)
    documents = [load_published(path) for path in published]
    summary = summarise(rows, drawn, quantities_of(documents))
    draws = drawn.loc[drawn["member"].str.startswith(DRAW_PREFIX), "member"].nunique()
    note = (
        f"Over {draws} protocols drawn per study from its prior (results/tables/"
        "sensitivity_prior.md), every trial from the run's base seed. Verdict over protocols: "
        "the verdict rule over seeds with drawn protocols for seeds. `default` is the "
        "default protocol's status, `draws_below_default` the share of draws whose margin is "
        f"smaller than the default's. Depends most on: {DEPENDENCE_MEASURE}.\n\n"
        "## Verdicts by paper\n\n"
        + markdown_table(summary.groupby(["paper", "verdict"]).size().reset_index(name="count"))
    )
    write_tables(
        summary,
        {kind: outputs[kind] for kind in ("csv", "md", "html")},
        title=f"Published values and claims over {draws} protocols",
        note=note,
    )
    write_tables(
        named_statuses(rows),
        {kind: outputs[f"named_{kind}"] for kind in ("csv", "md", "html")},
        title="Published values and claims under the named protocols",
        note="Each named variant's status beside the default protocol's.",
    )
    write_tables(
        prior_table(),
        {kind: outputs[f"prior_{kind}"] for kind in ("csv", "md", "html")},
        title="The prior over every unpublished choice",
        note="Each choice is drawn within its bounds; the default is the simulator's own value.",
    )
    return summary
