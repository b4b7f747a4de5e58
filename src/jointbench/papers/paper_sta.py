"""Paper S: what the soft-tissue-artefact literature found about functional hip joint centres.

The ``hip_sta`` study (:mod:`jointbench.simulate.hip_sta`) puts every estimator that finds a
centre on skin-marker trials of a functional hip motion: the joint-centre methods on both
clusters, the one-segment centre-of-rotation methods on the thigh in the pelvis frame. This
module draws each method's error against the STA amplitude, tabulates whether every predicted
uncertainty still covers the true centre under STA (Gauss–Markov, ``gauss-markov-frame0`` and
the moving-block bootstrap of :mod:`jointbench.uncertainty`), and measures the findings of the
papers listed in ``paper_sta.yaml`` beside it, each entry naming its source.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from jointbench.comparison.published import Measurements
from jointbench.comparison.tolerance import binomial_interval
from jointbench.estimators import registry
from jointbench.estimators.batching import failed_trial, mistakes_named
from jointbench.figures.common import method_style, pyplot
from jointbench.figures.extended import extended_table, mean_ranks
from jointbench.papers.base import Inputs, Measured, Output, Paper, Table
from jointbench.papers.common import (
    Declared,
    NotMeasured,
    at_levels,
    claims_output,
    measured_claims,
    with_columns,
)
from jointbench.running.scoring import CHI2_3DOF_95, score_columns
from jointbench.simulate import Trials
from jointbench.uncertainty import bootstrap

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "BOOTSTRAP_RESAMPLES",
    "BOOTSTRAP_TRIALS",
    "CALIBRATION",
    "PAPER",
    "bootstrap_covariances",
    "calibration_table",
    "measure",
    "ranking_table",
]

STUDY = "hip_sta"
_CENTRE = ["center_x", "center_y", "center_z"]
_COVARIANCE = ["cov_xx", "cov_xy", "cov_xz", "cov_yy", "cov_yz", "cov_zz"]

#: The uncertainty calibration is measured on the star-arc at 45° (Camomilla et al.'s protocol,
#: the widest range of the grid) at every STA amplitude of the default grid.
CALIBRATION = tuple(
    {"motion": "star_arc", "rom_deg": 45.0, "sta_mm": sta} for sta in (0.0, 10.0, 20.0, 30.0)
)
#: The bootstrap is Gauss–Markov refitted on moving-block resamples at the documented block
#: length (ceil(sqrt(N)) frames). Refitting every trial 200 times would cost minutes; the first
#: BOOTSTRAP_TRIALS trials of each condition with BOOTSTRAP_RESAMPLES resamples each keep the
#: render job to seconds, and a covariance of 25 refits is within about ±30 % of its value.
BOOTSTRAP_METHOD = "gauss-markov"
BOOTSTRAP_TRIALS = 20
BOOTSTRAP_RESAMPLES = 25


def bootstrap_covariances(trials: Trials, n_trials: int, n_resamples: int) -> np.ndarray:
    """Moving-block bootstrap covariances ``(n_trials, 3, 3)`` [mm²] of Gauss–Markov's centre on
    the first ``n_trials`` trials (NaN where the bootstrap fails).

    Frame 0 stays first in every resample: it defines the body frames in which the centre, and
    the truth, are expressed; the other frames are resampled in blocks.
    """
    fit = registry.many("joint_center", BOOTSTRAP_METHOD, checked=False)
    out = np.full((n_trials, 3, 3), np.nan)
    for trial in range(n_trials):
        proximal, distal = (trials.segments[name][trial] for name in ("proximal", "distal"))

        def refits(indices: np.ndarray, proximal=proximal, distal=distal) -> list:
            rows = np.concatenate([np.zeros((len(indices), 1), dtype=int), indices + 1], axis=1)
            results = fit(proximal[rows], distal[rows])
            return [_refit_center(result) for result in results]

        try:
            label = f"{STUDY} {BOOTSTRAP_METHOD} trial {trial}"
            with mistakes_named(f"{STUDY} {BOOTSTRAP_METHOD} bootstrap of trial {trial}"):
                boot = bootstrap(
                    refits, len(proximal) - 1, n_resamples=n_resamples, seed=trial, label=label
                )
        except ValueError:
            continue
        out[trial] = boot.covariance()
    return out


def _refit_center(result) -> np.ndarray | None:
    """A bootstrap refit's centre (3,) [mm]; ``None`` when it failed or did not converge (a
    mistake in the method's code is raised, not counted as a failed refit)."""
    if isinstance(result, Exception):
        failed_trial(result)
        return None
    return np.asarray(result.center, dtype=float) if result.converged else None


def _coverage_row(method: str, sta_mm: float, mahalanobis_sq, sqrt_trace, error) -> dict:
    finite = np.isfinite(mahalanobis_sq)
    n = int(finite.sum())
    inside = float(np.mean(mahalanobis_sq[finite] <= CHI2_3DOF_95)) if n else np.nan
    low, high = (np.array(binomial_interval(n, 0.95)) / n) if n else (np.nan, np.nan)
    return {
        "method": method,
        "sta_mm": sta_mm,
        "trials": n,
        "inside_95": inside,
        "binomial_low": low,
        "binomial_high": high,
        "calibrated": bool(low <= inside <= high) if n else False,
        "median_sqrt_trace_cov_mm": float(np.nanmedian(sqrt_trace)) if n else np.nan,
        "rms_error_mm": float(np.sqrt(np.nanmean(np.asarray(error) ** 2))),
    }


def calibration_table(collected: pd.DataFrame, datasets) -> pd.DataFrame:
    """Per predicted uncertainty and STA amplitude (star-arc, 45°): the share of trials whose
    true centre lies inside the predicted 95 % ellipsoid, the band an honest covariance gives
    over that many trials (central 95 % of Binomial(n, 0.95) / n), the median predicted
    sqrt(tr C) and the RMS error [mm].

    Gauss–Markov and ``gauss-markov-frame0`` use their own covariances from ``collected``; the
    bootstrap row uses Gauss–Markov's estimate with the covariance of its moving-block refits
    (:func:`bootstrap_covariances`) on the first :data:`BOOTSTRAP_TRIALS` trials.
    """
    rows = []
    for trials, meta in datasets:
        condition = meta["condition"]
        sta = float(condition["sta_mm"])
        mine = collected[
            (collected["motion"] == condition["motion"])
            & np.isclose(collected["rom_deg"], float(condition["rom_deg"]))
            & np.isclose(collected["sta_mm"], sta)
        ]
        for method in ("gauss-markov", "gauss-markov-frame0"):
            part = mine[mine["method"] == method]
            if not part.empty:
                rows.append(
                    _coverage_row(
                        method,
                        sta,
                        part["mahalanobis_sq"].to_numpy(float),
                        part["sqrt_trace_cov_mm"].to_numpy(float),
                        part["error_mm"].to_numpy(float),
                    )
                )
        part = mine[mine["method"] == BOOTSTRAP_METHOD].sort_values("trial")
        n = min(BOOTSTRAP_TRIALS, trials.n_trials, len(part))
        if n == 0:
            continue
        covariances = bootstrap_covariances(trials, n, BOOTSTRAP_RESAMPLES)
        estimates = {c: part[c].to_numpy(float)[:n] for c in _CENTRE}
        upper = np.triu_indices(3)
        estimates |= {
            name: covariances[:, i, j] for name, i, j in zip(_COVARIANCE, *upper, strict=True)
        }
        scores = score_columns("joint_center", estimates, trials.truth)
        rows.append(
            _coverage_row(
                f"{BOOTSTRAP_METHOD} + block bootstrap",
                sta,
                scores["mahalanobis_sq"],
                scores["sqrt_trace_cov_mm"],
                scores["error_mm"],
            )
        )
    return pd.DataFrame(rows).sort_values(["method", "sta_mm"], kind="stable", ignore_index=True)


def _calibration(inputs: Inputs) -> Table:
    return Table(
        calibration_table(inputs.collected, inputs.datasets),
        title="Do the predicted 95 % intervals cover the true centre under STA? (star-arc, 45°)",
        note=f"bootstrap: Gauss–Markov refitted on {BOOTSTRAP_RESAMPLES} moving-block resamples "
        f"(block ceil(sqrt(N)) frames) on the first {BOOTSTRAP_TRIALS} trials of each condition; "
        "calibrated: the share lies in the band an honest covariance gives over this many trials.",
    )


def _calibration_headline(tables) -> str:
    (table,) = tables.values()
    worst = table.groupby("method", sort=False)["inside_95"].agg(["min", "max"])
    parts = [
        f"{method}: {row['min']:.0%}–{row['max']:.0%} of trials inside its 95 % interval"
        for method, row in worst.iterrows()
    ]
    return "; ".join(parts) + " (0 mm to the largest STA)."


def ranking_table(collected: pd.DataFrame) -> pd.DataFrame:
    """Mean rank of every method over the conditions of each STA amplitude (1 = lowest mean
    error; ranks from :func:`jointbench.figures.extended.extended_table`), with its mean error
    over those conditions [mm]."""
    table = extended_table(collected, STUDY)
    rows = []
    for sta, part in table.groupby("sta_mm", sort=True):
        ranks = mean_ranks(part).set_index("method")
        errors = part.groupby("method")["mean_error_mm"].mean()
        for method in ranks.index:
            rows.append(
                {
                    "sta_mm": sta,
                    "method": method,
                    "mean_rank": float(ranks.loc[method, "mean_rank"]),
                    "mean_error_mm": float(errors[method]),
                    "conditions": int((part["method"] == method).sum()),
                }
            )
    out = pd.DataFrame(rows)
    return out.sort_values(["sta_mm", "mean_rank", "method"], ignore_index=True)


def _ranking(inputs: Inputs) -> Table:
    return Table(
        ranking_table(inputs.collected),
        title="Ranking of every centre estimator by STA amplitude",
        note="mean rank over the motions and ranges of motion of each amplitude; 0 mm is white "
        "noise only.",
    )


def ranking_headline(tables) -> str:
    """The order of the methods by mean rank at no STA and at the largest STA, from the
    ranking table."""
    (table,) = tables.values()

    def order(sta: float) -> str:
        part = table[table["sta_mm"] == sta]
        return " < ".join(
            f"{row.method} ({row.mean_error_mm:.1f} mm)" for row in part.itertuples(index=False)
        )

    low, high = table["sta_mm"].min(), table["sta_mm"].max()
    return (
        "By mean rank over the motions and ranges (mean error in parentheses), white noise only: "
        f"{order(low)}; at {high:g} mm STA: {order(high)}."
    )


def errors_figure(inputs: Inputs) -> Figure:
    """Mean centre error [mm] against STA amplitude [mm], one panel per motion and range."""
    plt = pyplot()
    collected = inputs.collected
    panels = collected[["motion", "rom_deg"]].drop_duplicates().sort_values(["motion", "rom_deg"])
    fig, axes = plt.subplots(
        1,
        len(panels),
        figsize=(3.2 * len(panels), 3.4),
        sharey=True,
        squeeze=False,
        layout="constrained",
    )
    methods = list(dict.fromkeys(collected["method"]))
    for ax, (motion, rom) in zip(axes[0], panels.itertuples(index=False), strict=True):
        part = collected[(collected["motion"] == motion) & (collected["rom_deg"] == rom)]
        means = part.groupby(["method", "sta_mm"])["error_mm"].mean()
        for index, method in enumerate(methods):
            if method in means.index.get_level_values(0):
                series = means[method]
                ax.plot(
                    series.index, series.to_numpy(), label=method, **method_style(method, index)
                )
        ax.set_title(f"{motion.replace('_', '-')}, {rom:g}°")
        ax.set_xlabel("STA amplitude at 30° (mm)")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("mean centre error (mm)")
    axes[0][-1].legend(fontsize=7)
    return fig


# Claims: each returns what its entry's typed tolerance compares.


def _means(collected: pd.DataFrame) -> pd.Series:
    return collected.groupby(["method", "motion", "rom_deg", "sta_mm"])["error_mm"].mean()


def _s1(means):
    # Ehrig et al. (2006): most techniques within 3 mm at a range of 45°, under white noise.
    cell = at_levels(means, rom_deg=45.0, sta_mm=0.0)
    share = float(np.mean(cell <= 3.0))
    text = ", ".join(f"{m}/{mo}: {v:.2f} mm" for (m, mo), v in cell.items())
    return Measured(share, f"share of methods and motions within 3 mm: {share:.2f} ({text})")


def _s2(means):
    cell = {"motion": "star_arc", "rom_deg": 20.0, "sta_mm": 0.0}
    score = float(at_levels(means, method="SCoRE", **cell).item())
    stoddart = float(at_levels(means, method="gauss-markov", **cell).item())
    return Measured(
        {"SCoRE_mm": score, "SCoRE_minus_stoddart_mm": score - stoddart},
        f"SCoRE {score:.2f} mm, Gauss–Markov (Stoddart) {stoddart:.2f} mm, star-arc 20°, no STA",
    )


def _paired_share(means, level: str, better, worse, what: str):
    wide = means.unstack(level)
    wide = wide[wide.index.get_level_values("sta_mm") > 0]
    # A cell run at only one of the two levels compares nothing.
    pairs = with_columns(wide, (better, worse), level).dropna()
    if pairs.empty:
        lack = {level: (better, worse)}
        raise NotMeasured(f"no cell with STA > 0 at both {better} and {worse} in this run", lack)
    wins = pairs[better] < pairs[worse]
    return Measured(
        float(wins.mean()),
        f"{what} in {int(wins.sum())} of {len(wins)} cells (method × other factors, STA > 0)",
    )


def _s3(means):
    return _paired_share(means, "rom_deg", 45.0, 20.0, "45° more accurate than 20°")


def _s4(means):
    return _paired_share(
        means, "motion", "star_arc", "circumduction", "star-arc more accurate than circumduction"
    )


def _s6(means):
    above = sorted(level for level in means.index.get_level_values("sta_mm").unique() if level > 0)
    if not above:
        # An amplitude above 0 mm, whichever: a lack no name says.
        raise NotMeasured("S6 needs an STA amplitude above 0 mm; this run has none", {})
    lowest = above[0]
    ratio = at_levels(means, sta_mm=lowest) / at_levels(means, sta_mm=0.0)
    return Measured(
        float(ratio.min()),
        f"mean error at {lowest:g} mm STA / without STA: {ratio.min():.1f}–{ratio.max():.1f}×",
    )


def _s7(means):
    cell = at_levels(means, motion="star_arc", rom_deg=20.0)
    top = at_levels(cell, sta_mm=cell.index.get_level_values("sta_mm").max()).sort_values()
    ranked = "SCoRE"
    if ranked not in top.index:
        lack = {"method": (ranked,)}
        raise NotMeasured(f"S7 ranks {ranked}; this run has no {ranked} at the star-arc, 20°", lack)
    rank = int(list(top.index).index(ranked)) + 1
    text = ", ".join(f"{m} {v:.1f} mm" for m, v in top.items())
    return Measured(rank, f"SCoRE ranks {rank} of {len(top)}: {text}")


_CLAIMS = {"S1": _s1, "S2": _s2, "S3": _s3, "S4": _s4, "S6": _s6, "S7": _s7}


#: The methods the findings are measured over: the two-segment joint-centre methods. The
#: one-segment centre methods are ranked beside them (ranking table, figure) but not counted in
#: the findings, so a finding reads the same in the default run and in every member of the
#: ensembles, which run only the methods a paper measures.
MEASURED = ("SCoRE", "gauss-markov", "gauss-markov-frame0", "analytic")


def measure(inputs: Inputs) -> Measurements:
    """Every finding of ``paper_sta.yaml`` that this run's grid can measure, over the
    :data:`MEASURED` methods."""
    means = _means(inputs.collected[inputs.collected["method"].isin(MEASURED)])
    return measured_claims(_CLAIMS, means, declared=Declared(PAPER, inputs.published))


PAPER = Paper(
    key="paper_sta",
    letter="S",
    title="Paper S: soft-tissue artefact",
    citation="Ehrig et al. (2006), J Biomech 39:2798; Begon et al. (2007), Gait Posture 25:353; "
    "Camomilla et al. (2006), J Biomech 39:1096; Leardini et al. (2005), Gait Posture 21:212",
    study=STUDY,
    methods=MEASURED[:2],
    also_measures=MEASURED[2:],
    published=Path(__file__).with_name("paper_sta.yaml"),
    measure=measure,
    declares=tuple(_CLAIMS),
    outputs=(
        Output(
            "paper_sta_errors",
            "figure",
            errors_figure,
            caption="Mean hip-centre error of every estimator (joint-centre methods on both "
            "clusters, one-segment centre methods on the thigh in the pelvis frame) against the "
            "soft-tissue-artefact amplitude (RMS skin-marker displacement at a 30° hip "
            "excursion; 0 = white noise only), per motion and range of motion.",
        ),
        Output(
            "paper_sta_ranking",
            "table",
            _ranking,
            caption="Every estimator ranked within each STA amplitude (mean rank "
            "over motions and ranges; per-condition ranks in the extended ranking).",
            summarises=("paper_sta_ranking",),
            headline=ranking_headline,
            in_readme=True,
        ),
        Output(
            "paper_sta_calibration",
            "table",
            _calibration,
            caption="Under STA, the share of trials whose true centre lies inside each predicted "
            "95 % interval: Gauss–Markov's covariance, gauss-markov-frame0's and the moving-block "
            "bootstrap of Gauss–Markov; an honest interval gives 95 % within the band shown.",
            conditions=CALIBRATION,
            summarises=("paper_sta_calibration",),
            headline=_calibration_headline,
        ),
        claims_output(
            "paper_sta",
            measure,
            "Findings of the soft-tissue-artefact literature, each recomputed from the hip_sta "
            "study with the criterion stated in the table.",
        ),
    ),
)
