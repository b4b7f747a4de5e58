"""Paper C: Stoddart et al. (1999), hip joint centre — Table 1, calibration, figure, C1–C5.

Each measurement returns the quantity its published entry's typed tolerance compares (see
``paper_c.yaml`` beside this module); drawing lives in :mod:`jointbench.figures.paper_c`.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from jointbench.comparison.published import Measurements
from jointbench.figures import paper_c as draw
from jointbench.numerics.poses import POSE_MAX_ITERATIONS
from jointbench.papers.base import (
    FrontPart,
    Inputs,
    Measured,
    Output,
    Paper,
    PublishedTable,
    Table,
)
from jointbench.papers.common import (
    RECORDED_COLUMN,
    Declared,
    NotMeasured,
    claims_headline,
    claims_output,
    measured_claims,
    none_measured,
    rows_at,
    with_columns,
)
from jointbench.resultfiles.formatting import number
from jointbench.running.scoring import covariance_from_entries
from jointbench.simulate.hip import POSE_FIT_COLUMNS

__all__ = [
    "PAPER",
    "calibration_sentence",
    "converged_after",
    "measure",
    "published_table1",
    "v_against_longest",
]

_ROW_PREFIX = "C-T1-"
#: Table 1 as printed: rows sqrt(tr Wc) and v, columns Nt; v at Nt = 1200 is left blank (the
#: paper's reference estimate).
TABLE1 = PublishedTable.grid(
    "Table 1",
    lambda row, n_frames: f"{_ROW_PREFIX}{row}-{n_frames}",
    ("sqrt_trace_cov_mm", "validation_index"),
    (4, 8, 16, 32, 75, 150, 300, 600, 1200),
    empty={("validation_index", 1200)},
)
_CENTRE = ("center_x", "center_y", "center_z")
METHOD = draw.METHOD
# Ours, not the paper's: gauss-markov with the noise of the frame-0 poses modelled.
FRAME0 = "gauss-markov-frame0"


# Paper C Table 1: sqrt(tr Wc) falls 15.2× from Nt = 75 to 1200 (3.04 to 0.20 mm). Frame count
# alone (the same angular range, sixteen times the frames) gives sqrt(16) = 4×; the rest is the
# growing angular range the paper names. A fall within the geometric midpoint of the two,
# sqrt(15.2 / 4) = 1.949, is closer to the paper's shape than to the count law.
FALL_FROM, FALL_TO = 75, 1200
#: The paper's longest sequence (20 s): C2's accuracy is read there, and its v (Table 1, C3) is
#: against each trial's estimate from it; a run without it measures neither.
REFERENCE_NT = 1200


def _require_reference(n_frames: pd.Series, what: str) -> None:
    """:class:`NotMeasured` naming ``what`` unless the run's longest Nt is :data:`REFERENCE_NT`."""
    if n_frames.empty or n_frames.max() != REFERENCE_NT:
        longest = "none" if n_frames.empty else int(n_frames.max())
        raise NotMeasured(
            f"{what} needs Nt = {REFERENCE_NT}; this run's longest is {longest}",
            {"n_frames": (REFERENCE_NT,)},
        )


def _c1(ours, rows, collected):
    series = ours.set_index("n_frames")["median_sqrt_trace_cov_mm"].sort_index().dropna()
    if not {FALL_FROM, FALL_TO} <= set(series.index):
        raise NotMeasured(
            f"C1 needs sqrt(tr Wc) at Nt = {FALL_FROM} and {FALL_TO}; this run has "
            f"{list(series.index)}",
            {"n_frames": (FALL_FROM, FALL_TO)},
        )
    values = series.to_numpy()
    steps = np.diff(values) < 0
    fall = float(series[FALL_FROM] / series[FALL_TO])
    text = (
        f"{values[0]:.3g} mm at Nt={series.index[0]} to {values[-1]:.3g} mm; falls at "
        f"{int(steps.sum())} of {len(steps)} steps; {fall:.1f}× from Nt = {FALL_FROM} to "
        f"{FALL_TO} (paper 15.2×, frame count alone 4×)"
    )
    return Measured({"steps_not_falling": int((~steps).sum()), "fall_75_to_1200": fall}, text)


def _longest(method_rows: pd.DataFrame) -> pd.Series:
    """The row of :func:`per_frames` at the longest Nt."""
    return method_rows.loc[method_rows["n_frames"].idxmax()]


def _c2(ours, rows, collected):
    # Paper C's 0.20 mm is sqrt(tr Wc) conditional on the frame-0 poses: the uncertainty of
    # the centre in the body frame, i.e. relative to the markers that place it.
    _require_reference(ours["n_frames"], "C2")
    longest = _longest(ours)
    value = float(longest["rms_error_proximal_mm"])
    text = (
        f"{METHOD} at Nt = {int(longest['n_frames'])}: RMS error relative to the proximal "
        f"markers {value:.3g} mm, against the true centre in the world "
        f"{longest['rms_error_mm']:.3g} mm, predicted sqrt(tr Wc) "
        f"{longest['median_sqrt_trace_cov_mm']:.3g} mm (median)"
    )
    if FRAME0 in set(collected["method"]):
        other = _longest(draw.per_frames(collected, FRAME0))
        text += (
            f"; {FRAME0}: relative to the proximal markers RMS error "
            f"{other['rms_error_proximal_mm']:.3g} mm, predicted "
            f"{other['median_sqrt_trace_cov_proximal_mm']:.3g} mm, "
            f"{other['inside_95_proximal']:.0%} inside the 95 % ellipsoid; in the world "
            f"{other['rms_error_mm']:.3g} mm, predicted {other['median_sqrt_trace_cov_mm']:.3g} mm"
        )
    return Measured(value, text)


def v_against_longest(rows: pd.DataFrame) -> pd.Series:
    """v of each shorter-Nt estimate against the same trial's estimate from all frames, as
    paper C computed it (eq. 16 with the 1200-frame estimate as reference); NaN at the longest."""
    longest = rows["n_frames"].max()
    reference = rows[rows["n_frames"] == longest].set_index("trial")[list(_CENTRE)]
    shorter = rows[rows["n_frames"] < longest]
    offset = shorter[list(_CENTRE)].to_numpy() - reference.loc[shorter["trial"]].to_numpy()
    covariance = covariance_from_entries(shorter)
    with np.errstate(invalid="ignore"):
        e = np.einsum("ni,ni->n", offset, np.linalg.solve(covariance, offset[..., None])[..., 0])
    return pd.Series(np.sqrt(e / 3.0), index=shorter.index).reindex(rows.index)


def _c3(ours, rows, collected):
    _require_reference(rows["n_frames"], "C3")
    shorter = rows[rows["n_frames"] < rows["n_frames"].max()]
    if shorter.empty:
        # An Nt below the longest, whichever: a lack no name says.
        raise NotMeasured("C3 needs an Nt below the longest; this run has none", {})
    v = v_against_longest(rows).loc[shorter.index]
    # E[v²] = k² when the true covariance is k² times the predicted one (any error shape):
    # the RMS of v estimates k, each Nt weighted equally as the paper's eight rows are.
    mean_square = (v**2).groupby(shorter["n_frames"]).mean()
    k = float(np.sqrt(mean_square.mean()))
    per_nt = ", ".join(f"{n}: {np.sqrt(m):.2f}" for n, m in mean_square.items())
    return Measured(
        k,
        f"RMS v against each trial's own {rows['n_frames'].max()}-frame estimate {k:.2f} "
        f"(paper's eight v: 2.49); by Nt {per_nt}",
    )


def _c4(ours, rows, collected):
    band = ours[ours["n_frames"] >= 75]
    values = band["mean_validation_index"]
    if values.empty:
        # An Nt in the band the sentence reads, whichever: a lack no name says.
        raise NotMeasured("C4 needs an Nt ≥ 75; this run has none", {})
    text = ", ".join(f"Nt={n}: {v:.2f}" for n, v in zip(band["n_frames"], values, strict=True))
    squares = (
        rows[rows["n_frames"] >= 75]
        .groupby("n_frames")["validation_index"]
        .apply(lambda v: float(np.mean(v**2)))
    )
    text = (
        f"mean v vs true centre: {text}; the covariance too small by {squares.min():.0f}–"
        f"{squares.max():.0f}× (mean v²)"
    )
    if FRAME0 in set(collected["method"]):
        other = draw.per_frames(collected, FRAME0)
        other = other[other["n_frames"] >= 75]
        text += (
            f"; {FRAME0}: mean v {other['mean_validation_index'].min():.2f}–"
            f"{other['mean_validation_index'].max():.2f}, share inside the 95 % ellipsoid "
            f"{other['inside_95'].min():.2f}–{other['inside_95'].max():.2f}"
        )
    return Measured(values.tolist(), text)


def converged_after(rows: pd.DataFrame) -> pd.DataFrame:
    """Per trial (rows of ``rows``) and segment (columns ``proximal``, ``distal``), the
    iterations of the pose alternation after which the body-fixed coordinates had converged:
    one fewer than it made when the last changed them by less than the fit's limit (that one
    confirmed it), else all it made."""
    out = {}
    for segment in ("proximal", "distal"):
        made = rows[f"pose_iterations_{segment}"].astype(float)
        confirmed = rows[f"pose_converged_{segment}"].astype(bool)
        out[segment] = made.where(~confirmed, made - 1)
    return pd.DataFrame(out, index=rows.index)


def _c5(ours, rows, collected):
    with_columns(rows, POSE_FIT_COLUMNS, RECORDED_COLUMN)
    counts = converged_after(rows.dropna(subset=list(POSE_FIT_COLUMNS)))
    if counts.empty:
        # The columns are there, empty in every trial.
        raise NotMeasured(
            "no trial with a pose fit in this run", {RECORDED_COLUMN: POSE_FIT_COLUMNS}
        )
    largest = int(counts.to_numpy().max())
    tally = counts.stack().astype(int).value_counts().sort_index()
    shown = ", ".join(f"{n}: {k}" for n, k in tally.items())
    stopped = int((counts.to_numpy() >= POSE_MAX_ITERATIONS).sum())
    return Measured(
        largest,
        "iterations to converge (change below the fit's limit in the next), per trial and "
        f"segment over every Nt: {shown}; largest {largest}"
        + (f"; {stopped} stopped at {POSE_MAX_ITERATIONS} unconverged" if stopped else ""),
    )


_CLAIMS = {"C1": _c1, "C2": _c2, "C3": _c3, "C4": _c4, "C5": _c5}


def published_table1(published) -> pd.DataFrame:
    """The paper's Table 1 rows: ``n_frames``, ``sqrt_trace_cov_mm`` and ``validation_index``."""
    rows: dict[int, dict[str, float]] = {}
    for entry in published["values"]:
        if entry["id"].startswith(_ROW_PREFIX):
            column, n_frames = entry["id"].removeprefix(_ROW_PREFIX).rsplit("-", 1)
            rows.setdefault(int(n_frames), {})[column] = entry["published"]
    table = pd.DataFrame.from_dict(rows, orient="index").rename_axis("n_frames").reset_index()
    return table[["n_frames", "sqrt_trace_cov_mm", "validation_index"]]


def _table1_values(ours: pd.DataFrame) -> dict[str, Measured]:
    # Paper C's v used the 1200-frame estimate as reference, so ours is set beside it only
    # against the same reference; it has none at the reference itself, nor a cell without trials.
    columns = {"sqrt_trace_cov_mm": "median_sqrt_trace_cov_mm"}
    if not ours.empty and ours["n_frames"].max() == REFERENCE_NT:
        columns["validation_index"] = "mean_v_paper_reference"
    out = {}
    for row in ours.to_dict("records"):
        for cell, column in columns.items():
            value = row[column]
            if np.isfinite(value):
                out[f"{_ROW_PREFIX}{cell}-{row['n_frames']}"] = Measured(
                    float(value), f"{value:.3g}"
                )
    return out


def measure(inputs: Inputs) -> Measurements:
    """Every Table 1 value and claim of paper C, measured from the collected hip results."""
    declared = Declared(PAPER, inputs.published)
    try:
        rows = rows_at(inputs.collected, method=draw.METHOD)
    except NotMeasured as lack:
        return none_measured(_CLAIMS, lack, declared)
    ours = draw.per_frames(inputs.collected)
    claims = measured_claims(_CLAIMS, ours, rows, inputs.collected, declared=declared)
    return claims.with_values(_table1_values(ours))


def _table1(inputs: Inputs) -> Table:
    return Table(
        draw.table1(inputs.collected, published_table1(inputs.published)),
        title="Paper C Table 1: predicted uncertainty and validation index vs frames used",
        note=f"{draw.TABLE1_ABBREVIATIONS} {inputs.published['notes']['table1']}",
    )


def _calibration(inputs: Inputs) -> Table:
    return Table(
        draw.calibration_table(inputs.collected),
        title="Coverage of the predicted 95 % ellipsoid, against the true centre",
        note="status: "
        + "; ".join(f"{k}, {v}" for k, v in draw.CALIBRATION_STATUSES.items())
        + " (the band: the central 95 % range of the share an honest covariance gives over "
        "this many trials).",
    )


def _calibration_headline(tables) -> str:
    (table,) = tables.values()
    parts = []
    for method, part in table.groupby("method", sort=False):
        ok = part[part["status"] == "calibrated"]["n_frames"].tolist()
        parts.append(
            f"{method}: share inside {part['inside_95'].min():.3g}–{part['inside_95'].max():.3g}, "
            f"calibrated at Nt = {', '.join(map(str, ok)) or 'none'}"
        )
    return "; ".join(parts) + "."


def calibration_sentence(calibration: pd.DataFrame) -> str:
    """What the calibration table says about each method, in one sentence."""
    parts = []
    for method, rows in calibration.groupby("method", sort=False):
        rows = rows.sort_values("n_frames")
        good = rows[rows["status"] == "calibrated"]["n_frames"].tolist()
        if len(good) == len(rows):
            parts.append(f"{method} is calibrated at every Nt")
        elif good and rows["n_frames"].tolist()[-len(good) :] == good:
            text = f"{method} is calibrated at every Nt from {good[0]} on"
            others = rows[rows["n_frames"] < good[0]]
            notes = [
                f"{o.status} at Nt = {o.n_frames} (coverage {number(o.inside_95)})"
                for o in others.itertuples()
            ]
            parts.append(text + (f", {', '.join(notes)}" if notes else ""))
        else:
            low, high = rows["inside_95"].min(), rows["inside_95"].max()
            parts.append(
                f"{method}'s 95 % ellipsoid holds the true centre in {low:.1%} to {high:.1%} "
                "of trials"
            )
    return "; ".join(parts) + "."


def _front_page(tables) -> FrontPart:
    """The calibration in the report's findings and as a table of its own."""
    calibration = tables.get("paper_c_calibration")
    if calibration is None:
        return FrontPart()
    shown = calibration[["method", "n_frames", "trials", "inside_95", "status"]].rename(
        columns={"n_frames": "Nt", "inside_95": "share inside"}
    )
    return FrontPart(
        finding=calibration_sentence(calibration),
        sections=(
            (
                "Calibration of the predicted covariance",
                "share of trials whose true centre is inside the 95 % ellipsoid",
                shown,
            ),
        ),
    )


def _frame0_control(inputs: Inputs) -> Table:
    return Table(
        draw.frame0_control_table(inputs.collected),
        title="The frame-0 control: gauss-markov on the same trials with frame 0 exact",
        note="error_over_predicted: RMS error against the true centre over the median predicted "
        "sqrt(tr Wc), 1 for an honest prediction; status: "
        + "; ".join(f"{k}, {v}" for k, v in draw.CALIBRATION_STATUSES.items())
        + ".",
    )


def _frame0_control_headline(tables) -> str:
    (table,) = tables.values()
    longest = table[table["n_frames"] == table["n_frames"].max()]
    parts = [
        f"{row.variant} {row.error_over_predicted:.2f}× ({row.inside_95:.0%} inside)"
        for row in longest.itertuples()
    ]
    return (
        f"RMS error over predicted sqrt(tr Wc) at Nt = {int(longest['n_frames'].iloc[0])}: "
        + ", ".join(parts)
        + "."
    )


def _uncertainty(inputs: Inputs):
    return draw.uncertainty_figure(inputs.collected, published_table1(inputs.published))


PAPER = Paper(
    key="paper_c",
    letter="C",
    title="Paper C: hip joint centre",
    citation="Stoddart et al. (1999), A computational method for hip joint centre location "
    "from optical markers, BMVC",
    study="hip",
    methods=("gauss-markov", "analytic"),
    published=Path(__file__).with_name("paper_c.yaml"),
    measure=measure,
    declares=tuple(_CLAIMS),
    tables=(TABLE1,),
    also_measures=(FRAME0,),
    front_page=_front_page,
    outputs=(
        Output(
            "paper_c_table1",
            "table",
            _table1,
            caption="Paper C Table 1 (Stoddart et al. 1999): the predicted uncertainty "
            "sqrt(tr Wc) and the validation index v against the number of frames Nt, the "
            "paper's values beside our median sqrt(tr Wc), RMS actual error and mean v over the "
            "Monte Carlo trials (v against the true centre, which the paper did not know).",
            summarises=("paper_c_claims",),
            headline=claims_headline,
        ),
        Output(
            "paper_c_calibration",
            "table",
            _calibration,
            caption="Beyond paper C: the share of trials whose true centre lies inside the "
            "predicted 95 % ellipsoid, per Nt; an honest covariance gives 0.95 within the "
            "binomial band shown.",
            summarises=("paper_c_calibration",),
            headline=_calibration_headline,
        ),
        Output(
            "paper_c_frame0_control",
            "table",
            _frame0_control,
            caption="Beyond paper C: eq. 2's single centre against the frame-0 control. The same "
            "trials are fitted by gauss-markov as recorded (frame 0 noisy, which places both body "
            "frames) and with frame 0 replaced by the exact markers, beside gauss-markov-frame0, "
            "which models the noise of frame 0: per Nt the RMS error, the median predicted "
            "sqrt(tr Wc), their ratio and the share of trials inside the 95 % ellipsoid.",
            summarises=("paper_c_frame0_control",),
            headline=_frame0_control_headline,
        ),
        Output(
            "paper_c_uncertainty",
            "figure",
            _uncertainty,
            caption="Paper C Table 1 as a picture: predicted sqrt(tr Wc) and actual RMS error "
            "against Nt (log–log), with the paper's values, and the coverage of the predicted "
            "95 % ellipsoid; the grey band is the coverage an honest covariance gives over this "
            "many trials (central 95 % of Binomial(n, 0.95)/n).",
            summarises=("paper_c_calibration",),
            headline=_calibration_headline,
        ),
        claims_output(
            "paper_c",
            measure,
            "Claims C1–C5 of paper C §5, §8 and Table 1, each recomputed from our results with the "
            "criterion stated in the table.",
        ),
    ),
)
