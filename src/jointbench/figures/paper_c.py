"""Paper C (Stoddart et al. 1999, hip joint centre): Table 1, covariance calibration, figure.

Our rig is synthetic, so unlike the paper we know the true centre: the validation index and the
calibration use it, which tests whether the predicted covariance is honest.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from jointbench.comparison.tolerance import binomial_interval
from jointbench.figures.common import method_style, pyplot
from jointbench.running.scoring import CHI2_3DOF_95, covariance_from_entries
from jointbench.simulate.hip import EXACT_FRAME0_COLUMNS

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "CALIBRATION_STATUSES",
    "CONTROL",
    "EXTENDED",
    "METHOD",
    "TABLE1_LABELS",
    "calibration_status",
    "calibration_table",
    "frame0_control_table",
    "per_frames",
    "table1",
    "uncertainty_figure",
]

METHOD = "gauss-markov"
EXTENDED = "gauss-markov-frame0"


def _paper_validation_index(rows: pd.DataFrame) -> pd.Series:
    """v as paper C computed it: against each trial's own estimate from all frames (eq. 16)."""
    longest = rows["n_frames"].max()
    reference = rows[rows["n_frames"] == longest].set_index("trial")[
        ["center_x", "center_y", "center_z"]
    ]
    shorter = rows[rows["n_frames"] < longest]
    offset = (
        shorter[["center_x", "center_y", "center_z"]].to_numpy()
        - reference.loc[shorter["trial"]].to_numpy()
    )
    covariance = covariance_from_entries(shorter)
    with np.errstate(invalid="ignore"):
        e = np.einsum("ni,ni->n", offset, np.linalg.solve(covariance, offset[..., None])[..., 0])
    return pd.Series(np.sqrt(e / 3.0), index=shorter.index).reindex(rows.index)


def per_frames(collected: pd.DataFrame, method: str = METHOD) -> pd.DataFrame:
    """Per Nt: trials, converged, median sqrt(tr Wc), RMS error, mean v (true centre and the
    paper's reference) and the share inside the 95 % ellipsoid, for one method; the median
    sqrt(tr Wc), RMS error and share again relative to the proximal markers."""
    rows = collected[collected["method"] == method].copy()
    rows["v_paper"] = _paper_validation_index(rows)
    grouped = rows.groupby("n_frames")
    return pd.DataFrame(
        {
            "trials": grouped.size(),
            "converged": grouped["converged"].sum().astype(int),
            "median_sqrt_trace_cov_mm": grouped["sqrt_trace_cov_mm"].median(),
            "rms_error_mm": grouped["error_mm"].apply(lambda e: float(np.sqrt(np.mean(e**2)))),
            "mean_validation_index": grouped["validation_index"].mean(),
            "mean_v_paper_reference": grouped["v_paper"].mean(),
            "inside_95": grouped["mahalanobis_sq"].apply(
                lambda m: float(np.mean(m <= CHI2_3DOF_95))
            ),
            "median_sqrt_trace_cov_proximal_mm": grouped["sqrt_trace_cov_proximal_mm"].median(),
            "rms_error_proximal_mm": grouped["error_proximal_mm"].apply(
                lambda e: float(np.sqrt(np.mean(e**2)))
            ),
            "inside_95_proximal": grouped["mahalanobis_sq_proximal"].apply(
                lambda m: float(np.mean(m <= CHI2_3DOF_95))
            ),
        }
    ).reset_index()


def table1(collected: pd.DataFrame, paper: pd.DataFrame) -> pd.DataFrame:
    """Per Nt: the paper's sqrt(tr Wc) and v beside ours for gauss-markov (paper C's method)
    and gauss-markov-frame0; v against the true centre and, as the paper did, against each
    trial's own 1200-frame estimate."""
    paper = paper.rename(
        columns={"sqrt_trace_cov_mm": "paper_sqrt_trace_cov_mm", "validation_index": "paper_v"}
    )
    gm = per_frames(collected)[
        [
            "n_frames",
            "median_sqrt_trace_cov_mm",
            "rms_error_mm",
            "rms_error_proximal_mm",
            "mean_v_paper_reference",
            "mean_validation_index",
            "converged",
            "trials",
        ]
    ].rename(
        columns={
            "median_sqrt_trace_cov_mm": "gm_sqrt_trace_cov_mm",
            "rms_error_mm": "gm_rms_error_mm",
            "rms_error_proximal_mm": "gm_rms_error_proximal_mm",
            "mean_v_paper_reference": "gm_v_vs_own_1200",
            "mean_validation_index": "gm_v_vs_truth",
            "converged": "gm_converged",
        }
    )
    table = paper.merge(gm, on="n_frames", how="left")
    if EXTENDED in set(collected["method"]):
        f0 = per_frames(collected, EXTENDED)[
            [
                "n_frames",
                "median_sqrt_trace_cov_mm",
                "rms_error_mm",
                "mean_validation_index",
                "median_sqrt_trace_cov_proximal_mm",
                "rms_error_proximal_mm",
            ]
        ].rename(
            columns={
                "median_sqrt_trace_cov_mm": "f0_sqrt_trace_cov_mm",
                "rms_error_mm": "f0_rms_error_mm",
                "median_sqrt_trace_cov_proximal_mm": "f0_sqrt_trace_cov_proximal_mm",
                "rms_error_proximal_mm": "f0_rms_error_proximal_mm",
                "mean_validation_index": "f0_v_vs_truth",
            }
        )
        table = table.merge(f0, on="n_frames", how="left")
    return table.rename(columns=TABLE1_LABELS)


#: The short names :data:`TABLE1_LABELS` uses, in words for the table's note.
TABLE1_ABBREVIATIONS = (
    f"GM: {METHOD}, paper C's method; GM-f0: {EXTENDED}, which also models the noise of the "
    "frame-0 poses each body frame is pinned to."
)
#: :func:`table1`'s column headers (:data:`TABLE1_ABBREVIATIONS`), keyed by the quantity each
#: holds.
TABLE1_LABELS = {
    "n_frames": "frames used, Nt",
    "paper_sqrt_trace_cov_mm": "paper: sqrt(tr Wc) (mm)",
    "paper_v": "paper: v (vs its own 1200-frame estimate)",
    "gm_sqrt_trace_cov_mm": "GM: median sqrt(tr Wc) (mm)",
    "gm_rms_error_mm": "GM: RMS error vs true centre (mm)",
    "gm_rms_error_proximal_mm": "GM: RMS error relative to the proximal markers (mm)",
    "gm_v_vs_own_1200": "GM: mean v vs own 1200-frame estimate",
    "gm_v_vs_truth": "GM: mean v vs true centre",
    "gm_converged": "GM: trials converged",
    "trials": "trials",
    "f0_sqrt_trace_cov_mm": "GM-f0: median sqrt(tr Wc) (mm)",
    "f0_rms_error_mm": "GM-f0: RMS error vs true centre (mm)",
    "f0_v_vs_truth": "GM-f0: mean v vs true centre",
    "f0_sqrt_trace_cov_proximal_mm": "GM-f0: median sqrt(tr Wc) relative to the proximal "
    "markers (mm)",
    "f0_rms_error_proximal_mm": "GM-f0: RMS error relative to the proximal markers (mm)",
}


def calibration_table(collected: pd.DataFrame) -> pd.DataFrame:
    """Per method and Nt: share of trials whose true centre is inside the predicted 95 %
    ellipsoid ``(c - c_true)' Wc^-1 (c - c_true) <= chi2_3(0.95)``; ``binomial_low`` and
    ``binomial_high`` bound what an honest covariance gives over that many trials (central
    95 % of Binomial(n, 0.95) / n), ``calibrated`` says whether the share is inside (edges
    included) and ``status`` says it in one word (:func:`calibration_status`);
    ``inside_95_proximal`` is the share relative to the proximal markers."""
    methods = [m for m in (METHOD, EXTENDED) if m in set(collected["method"])]
    parts = []
    for method in methods:
        ours = per_frames(collected, method)
        part = ours[
            ["n_frames", "trials", "inside_95", "mean_validation_index", "inside_95_proximal"]
        ].copy()
        part.insert(0, "method", method)
        part["binomial_low"], part["binomial_high"] = _honest_band(part["trials"])
        part["calibrated"] = part["inside_95"].between(part["binomial_low"], part["binomial_high"])
        part["status"] = _statuses(part)
        parts.append(part)
    return pd.concat(parts, ignore_index=True)


def _honest_band(trials: pd.Series) -> tuple[np.ndarray, np.ndarray]:
    """The central 95 % range of the share inside the 95 % ellipsoid that an honest covariance
    gives over each count of ``trials``: ``(low, high)``, each ``(n,)``."""
    bounds = np.array([np.array(binomial_interval(n, 0.95)) / n for n in trials])
    return bounds[:, 0], bounds[:, 1]


def _statuses(part: pd.DataFrame) -> list[str]:
    """:func:`calibration_status` of each row's ``inside_95`` over its ``trials``."""
    low, high = _honest_band(part["trials"])
    return [
        calibration_status(*values) for values in zip(part["inside_95"], low, high, strict=True)
    ]


#: The frame-0 control's name in tables: gauss-markov on the same trials with frame 0 exact.
CONTROL = f"{METHOD}, frame 0 exact"


def frame0_control_table(collected: pd.DataFrame) -> pd.DataFrame:
    """Per variant and Nt: gauss-markov with frame 0 recorded (the default), gauss-markov-frame0
    and the frame-0 control (:data:`CONTROL`, gauss-markov's ``exact_frame0_*`` columns: the
    same trials with frame 0 exact), each with its RMS error against the true centre [mm],
    median predicted ``sqrt(tr Wc)`` [mm], their ratio (1 for an honest prediction), the share
    of trials inside the 95 % ellipsoid and its calibration ``status``
    (:func:`calibration_status`). A variant absent from the run is left out."""
    present = set(collected["method"])
    scores = ("error_mm", "sqrt_trace_cov_mm", "mahalanobis_sq")
    variants = [(m, m, dict(zip(scores, scores, strict=True))) for m in (METHOD, EXTENDED)]
    variants.append((CONTROL, METHOD, EXACT_FRAME0_COLUMNS))
    parts = []
    for name, method, columns in variants:
        rows = collected[collected["method"] == method]
        if method not in present or not set(columns.values()) <= set(rows.columns):
            continue
        rows = rows[[*columns.values(), "n_frames"]].rename(
            columns={v: k for k, v in columns.items()}
        )
        grouped = rows.groupby("n_frames")
        part = pd.DataFrame(
            {
                "trials": grouped.size(),
                "rms_error_mm": grouped["error_mm"].apply(lambda e: float(np.sqrt(np.mean(e**2)))),
                "median_sqrt_trace_cov_mm": grouped["sqrt_trace_cov_mm"].median(),
                "inside_95": grouped["mahalanobis_sq"].apply(
                    lambda m: float(np.mean(m <= CHI2_3DOF_95))
                ),
            }
        ).reset_index()
        part.insert(0, "variant", name)
        part.insert(
            5, "error_over_predicted", part["rms_error_mm"] / part["median_sqrt_trace_cov_mm"]
        )
        part["status"] = _statuses(part)
        parts.append(part)
    if not parts:
        raise KeyError(f"no {METHOD} results in this run")
    return pd.concat(parts, ignore_index=True)


#: One word per calibration verdict, for the tables and the report's sentences.
CALIBRATION_STATUSES = {
    "calibrated": "inside the band an honest covariance gives",
    "borderline": "on an edge of that band: inside, only just",
    "overconfident": "below the band: the ellipsoid is too small",
    "conservative": "above the band: the ellipsoid is too large",
}


def calibration_status(share: float, low: float, high: float) -> str:
    """The share of trials inside the 95 % ellipsoid against the band ``[low, high]`` an honest
    covariance gives, in one word of :data:`CALIBRATION_STATUSES`."""
    if share < low:
        return "overconfident"
    if share > high:
        return "conservative"
    return "borderline" if share in (low, high) else "calibrated"


def _frames_axis(ax, n_frames) -> None:
    """Log x axis ticked at the Nt values of the run, not at powers of ten."""
    ax.set_xscale("log")
    ax.set_xticks(list(n_frames), [str(n) for n in n_frames])
    ax.xaxis.set_minor_locator(pyplot().NullLocator())
    ax.set_xlabel("frames used, Nt (log scale)")


def _mark_not_converged(ax, coverage: pd.DataFrame, color) -> None:
    """Ring each Nt where some trials did not converge, on the coverage curve, and print how
    many: their estimates count in the coverage as the method returned them."""
    for row in coverage.itertuples():
        missing = int(row.trials - row.converged)
        if missing:
            ax.plot(row.n_frames, row.inside_95, "o", ms=11, mfc="none", mec=color)
            ax.annotate(
                f"{missing} of {row.trials} not converged",
                (row.n_frames, row.inside_95),
                xytext=(12, -24),
                textcoords="offset points",
                fontsize=9,
                color=color,
                va="top",
            )


def uncertainty_figure(collected: pd.DataFrame, paper: pd.DataFrame) -> Figure:
    """Predicted sqrt(tr Wc) and the actual RMS error against Nt (log–log), and coverage."""
    calibration = calibration_table(collected)
    n_frames = sorted(set(collected["n_frames"]) | set(paper["n_frames"]))
    fig, (ax, cal) = pyplot().subplots(1, 2, figsize=(10.4, 6.6))
    for method in (METHOD, EXTENDED):
        if method not in set(collected["method"]):
            continue
        color = method_style(method)["color"]
        ours = per_frames(collected, method)
        ax.plot(
            ours["n_frames"],
            ours["median_sqrt_trace_cov_mm"],
            "-o",
            color=color,
            ms=4,
            label=f"{method}: predicted sqrt(tr Wc), median",
        )
        ax.plot(
            ours["n_frames"],
            ours["rms_error_mm"],
            "--x",
            color=color,
            label=f"{method}: actual RMS error vs true centre",
        )
        part = calibration[calibration["method"] == method]
        cal.plot(part["n_frames"], part["inside_95"], "-o", color=color, ms=4, label=method)
        _mark_not_converged(cal, part.merge(ours[["n_frames", "converged"]], on="n_frames"), color)
    ax.plot(
        paper["n_frames"],
        paper["sqrt_trace_cov_mm"],
        ":s",
        color="0.5",
        ms=4,
        label="paper C: sqrt(tr Wc) (its rig)",
    )
    _frames_axis(ax, n_frames)
    ax.set_yscale("log")
    ax.set_ylabel("predicted uncertainty or actual error (mm, log scale)")
    ax.grid(True, which="both", alpha=0.3)
    ax.set_title("(a) Predicted uncertainty vs actual error", fontsize=10)
    band = calibration.drop_duplicates("n_frames")
    trials = int(band["trials"].median())
    cal.fill_between(
        band["n_frames"],
        band["binomial_low"],
        band["binomial_high"],
        color="0.85",
        label="range an honest covariance gives:\n"
        f"central 95 % of Binomial({trials}, 0.95) / {trials}",
    )
    cal.axhline(0.95, color="k", lw=0.8, label="0.95, the ellipsoid's nominal coverage")
    _frames_axis(cal, n_frames)
    cal.set_ylim(0, 1.02)
    cal.set_ylabel("share of trials with the true centre\ninside the predicted 95 % ellipsoid")
    cal.grid(True, which="both", alpha=0.3)
    cal.set_title("(b) Coverage of the predicted 95 % ellipsoid", fontsize=10)
    fig.suptitle("Paper C Table 1 extended: is the Gauss–Markov covariance honest?", fontsize=11)
    fig.tight_layout(rect=(0, _LEGEND_ROOM, 1, 1))
    # Below each panel: inside, they would hide the points at large Nt, the finding itself.
    # Figure legends, which the layout leaves out, so the panels keep their width.
    for panel in (ax, cal):
        box = panel.get_position()
        fig.legend(
            *panel.get_legend_handles_labels(),
            fontsize=9,
            loc="upper center",
            bbox_to_anchor=((box.x0 + box.x1) / 2, _LEGEND_ROOM),
            ncol=1,
        )
    return fig


#: Share of the figure's height below the panels kept for their legends.
_LEGEND_ROOM = 0.25
