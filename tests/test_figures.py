"""Figure and table builders on small synthetic collected tables: wording, marks, choices."""

from __future__ import annotations

import itertools

import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest
from mpl_toolkits.mplot3d.art3d import Line3D, Poly3DCollection

from jointbench.figures import extended, paper_a, paper_b, paper_c
from jointbench.figures.common import (
    SAVE_DPI,
    equal_3d_limits,
    median_trial,
    method_style,
    method_styles,
    save_figure,
)
from jointbench.papers import paper_b as papers_b
from jointbench.papers.base import Inputs
from jointbench.resultfiles.tables import markdown_table
from jointbench.running import run

PAPER_A_SECONDS = {"MA": 1.2, "LS": 0.0056, "IS": 0.079, "BC": 0.12, "NM": 0.00076}


def _cmc(n_trials=5, seed=0, methods=("MA", "LS", "IS", "BC", "NM", "SCoRE")):
    rng = np.random.default_rng(seed)
    rows = []
    for marker_set, rom, noise, trial, method in itertools.product(
        ("M", "H"), (5, 15, 45), (0.5, 1.0, 2.0), range(n_trials), methods
    ):
        error = rng.gamma(2.0, noise * 10 / rom) + (5 if method == "LS" else 0)
        rows.append(
            {
                "marker_set": marker_set,
                "rom_deg": rom,
                "noise_mm": noise,
                "trial": trial,
                "method": method,
                "center_x": rng.normal(0, error),
                "center_y": rng.normal(0, error),
                "center_z": rng.normal(0, error),
                "error_mm": error,
                # BC fails to converge on some small-RoM trials, as in paper A.
                "converged": not (method == "BC" and rom == 5 and trial % 2 == 1),
                "iterations": 10,
                "seconds": {"NM": 0.00165, "MA": 0.002}.get(method, 0.0001),
                "status": "ok",
                "local_minimum": bool(method == "IS" and trial == 0),
            }
        )
    return pd.DataFrame(rows)


def _hinge(n_trials=4, seed=1, methods=("planar", "radial", "combined", "SARA")):
    rng = np.random.default_rng(seed)
    rows = []
    for protocol, fe, ratio, trial, method in itertools.product(
        ("knee", "mcp"), (30, 60, 90), (0.1, 0.3, 0.5, 0.7), range(n_trials), methods
    ):
        rows.append(
            {
                "protocol": protocol,
                "fe_rom_deg": fe,
                "aa_ratio": ratio,
                "trial": trial,
                "method": method,
                "error_deg": rng.gamma(2.0, 10 * ratio),
                "converged": True,
                "iterations": 5,
                "seconds": 0.001,
                "status": "ok",
            }
        )
    return pd.DataFrame(rows)


def _hip(n_trials=20, seed=2):
    rng = np.random.default_rng(seed)
    rows = []
    for n_frames, trial, method in itertools.product(
        (4, 8, 16, 32, 75, 150, 300, 600, 1200),
        range(n_trials),
        ("gauss-markov", "gauss-markov-frame0", "analytic"),
    ):
        sd = 30.0 / np.sqrt(n_frames)
        offset = rng.normal(0, sd, 3)
        rows.append(
            {
                "n_frames": n_frames,
                "trial": trial,
                "method": method,
                "center_x": offset[0],
                "center_y": offset[1],
                "center_z": offset[2],
                "error_mm": float(np.linalg.norm(offset)),
                "sqrt_trace_cov_mm": sd * np.sqrt(3),
                "mahalanobis_sq": float(offset @ offset) / sd**2,
                "validation_index": float(np.sqrt(offset @ offset / sd**2 / 3)),
                # Relative to the proximal markers: the same numbers, as for a rig whose
                # frame-0 markers are exact.
                "error_proximal_mm": float(np.linalg.norm(offset)),
                "sqrt_trace_cov_proximal_mm": sd * np.sqrt(3),
                "mahalanobis_sq_proximal": float(offset @ offset) / sd**2,
                "cov_xx": sd**2,
                "cov_xy": 0.0,
                "cov_xz": 0.0,
                "cov_yy": sd**2,
                "cov_yz": 0.0,
                "cov_zz": sd**2,
                "converged": True,
                "iterations": 3,
                "seconds": 0.01,
                "status": "ok",
            }
        )
    return pd.DataFrame(rows)


CMC_PAPER = ("A", paper_a.PAPER_METHODS)


def _drawn(fig) -> bool:
    """Whether ``fig`` is a figure with axes; closes it."""
    ok = isinstance(fig, plt.Figure) and len(fig.axes) > 0
    fig.canvas.draw()
    plt.close(fig)
    return ok


# ----------------------------------------------------------------------------- Table 2 wording


@pytest.mark.parametrize(
    ("ours", "paper", "expected"),
    [
        (0.00165, 0.00076, "2.2× slower"),  # NM: about twice the paper's time
        (0.0018, 1.2, "667× faster"),
        (0.05, 0.079, "1.6× faster"),
        (0.079, 0.079, "as fast (within 5 %)"),
        (0.0, 0.079, "not applicable"),
    ],
)
def test_speed_wording_names_the_direction(ours, paper, expected):
    assert paper_a.speed_wording(ours, paper) == expected


def test_speed_wording_never_writes_a_ratio_below_one():
    for ours in np.geomspace(1e-5, 10, 60):
        text = paper_a.speed_wording(ours, 0.01)
        number = text.split("×")[0]
        if "×" in text:
            assert float(number) >= 1.0, text


def test_table2_words_agree_with_its_ratios():
    table = paper_a.table2(_cmc(), PAPER_A_SECONDS)
    for statistic in ("median", "mean"):
        ratios, words = table[f"speedup_{statistic}"], table[f"vs_paper_{statistic}"]
        for ratio, said in zip(ratios, words, strict=True):
            assert ("faster" in said) == (ratio > 1.05), (ratio, said)
            assert ("slower" in said) == (ratio < 1 / 1.05), (ratio, said)
    nm = table.set_index("method").loc["NM"]
    assert nm["vs_paper_median"].endswith("slower")


def test_table2_headline_says_slower_where_the_table_does():
    table = paper_a.table2(_cmc(), PAPER_A_SECONDS)
    headline = paper_a.table2_headline(table)
    for method, words in zip(table["method"], table["vs_paper_median"], strict=True):
        assert f"{method} {words}" in headline
    assert "NM 0×" not in headline


def test_table2_headline_goes_by_the_median_when_a_few_slow_calls_reverse_the_mean():
    """One slow NM trial makes NM's mean slower than the paper's while its median is faster: the
    headline is worded by the median, says so, and gives the mean beside it."""
    collected = _cmc()
    nm = collected.index[collected["method"] == "NM"]
    collected.loc[nm, "seconds"] = 0.00076 / 30  # 30× faster than the paper, trial by trial
    collected.loc[nm[0], "seconds"] = 1.0  # but one call was slow
    table = paper_a.table2(collected, PAPER_A_SECONDS).set_index("method")
    assert table.loc["NM", "vs_paper_median"] == "30× faster"
    assert table.loc["NM", "vs_paper_mean"].endswith("slower")
    headline = paper_a.table2_headline(table.reset_index())
    assert headline.startswith("Median time per trial")
    assert "the paper reports means" in headline
    assert f"NM 30× faster (by mean: {table.loc['NM', 'vs_paper_mean']})" in headline


def test_table2_shows_the_paper_methods_the_run_estimated():
    collected = _cmc()
    table = paper_a.table2(collected[collected["method"].isin(["NM", "LS"])], PAPER_A_SECONDS)
    assert list(table["method"]) == ["LS", "NM"]


def test_timing_note_says_how_and_where_times_were_measured():
    note = paper_a.timing_note()
    assert "inside the estimate job" in note
    assert "timed on its own" in note or "batched call" in note
    assert "(:" not in note and "(;" not in note  # no empty list of methods
    assert f"NumPy {np.__version__}" in note
    assert "2 cores" not in note
    assert "Python 3" in note


# ----------------------------------------------------------------------------- Paper A Fig 3


def test_fig3_trial_is_the_median_by_nm_error_among_bc_converged_trials():
    collected = _cmc(n_trials=6)
    cell = (
        (collected["marker_set"] == "M")
        & (collected["rom_deg"] == 5)
        & (collected["noise_mm"] == 1.0)
    )
    nm = cell & (collected["method"] == "NM")
    # NM errors by trial; BC did not converge on the odd trials 1, 3, 5.
    collected.loc[nm, "error_mm"] = [0.1, 9.0, 3.0, 9.0, 2.0, 9.0]
    # Candidates 0, 2, 4 with NM errors 0.1, 3.0, 2.0: the median is trial 4 (2.0 mm).
    assert paper_a.choose_fig3_trial(collected) == 4


def test_fig3_trial_takes_the_lower_middle_for_an_even_count():
    collected = _cmc(n_trials=4)
    collected["converged"] = True
    nm = (
        (collected["marker_set"] == "M")
        & (collected["rom_deg"] == 5)
        & (collected["noise_mm"] == 1.0)
        & (collected["method"] == "NM")
    )
    collected.loc[nm, "error_mm"] = [4.0, 1.0, 3.0, 2.0]
    assert paper_a.choose_fig3_trial(collected) == 3


def test_fig3_trial_skips_trials_with_a_failed_method():
    collected = _cmc(n_trials=3)
    collected["converged"] = True
    cell = (
        (collected["marker_set"] == "M")
        & (collected["rom_deg"] == 5)
        & (collected["noise_mm"] == 1.0)
    )
    collected.loc[cell & (collected["method"] == "NM"), "error_mm"] = [1.0, 2.0, 3.0]
    collected.loc[cell & (collected["method"] == "MA") & (collected["trial"] == 1), "error_mm"] = (
        np.nan
    )
    assert paper_a.choose_fig3_trial(collected) == 0


def test_median_trial_orders_equal_errors_by_trial():
    assert median_trial(pd.Series([1.0, 1.0, 1.0], index=[7, 3, 5])) == 5
    with pytest.raises(ValueError):
        median_trial(pd.Series([np.nan]))


# ----------------------------------------------------------------------------- extended


def _tied_cmc():
    collected = _cmc(n_trials=2)
    # LM repeats IS exactly: every condition is a tie between them, never a double win.
    lm = collected[collected["method"] == "IS"].assign(method="LM")
    return pd.concat([collected, lm], ignore_index=True)


def test_ties_are_shared_not_counted_twice():
    table = extended.extended_table(_tied_cmc(), "cmc", CMC_PAPER)
    ranks = extended.mean_ranks(table).set_index("method")
    n_conditions = table[["marker_set", "rom_deg", "noise_mm"]].drop_duplicates().shape[0]
    assert ranks.loc["LM", "best_alone"] == 0
    assert ranks.loc["IS", "best_alone"] == 0
    assert ranks.loc["LM", "best_tied"] == ranks.loc["IS", "best_tied"]
    # Each condition has one sole winner or a tie; never more sole winners than conditions.
    assert ranks["best_alone"].sum() <= n_conditions
    assert (ranks["best_in"] == ranks["best_alone"] + ranks["best_tied"]).all()


def test_best_headline_counts_each_condition_once(tmp_path):
    table = extended.extended_table(_tied_cmc(), "cmc", CMC_PAPER)
    # As the caption builder reads it: from the CSV.
    table.to_csv(tmp_path / "extended.csv", index=False)
    headline = extended.best_headline(pd.read_csv(tmp_path / "extended.csv"))
    counts = [
        int(part.rsplit(" ", 1)[1]) for part in headline.rstrip(".").split(": ")[1].split(", ")
    ]
    assert sum(counts) == 18
    assert "IS = LM tied in" in headline
    assert "IS alone" not in headline and "LM alone" not in headline


def test_best_text_shows_ties_separately():
    assert extended.best_text(8, 2, 18) == "best in 8 of 18, tied in 2"
    assert extended.best_text(3, 0, 18) == "best in 3 of 18"


@pytest.mark.parametrize(
    ("trials", "converged", "failed", "flagged"),
    [(30, 30, 0, False), (30, 11, 0, True), (30, 30, 2, True), (30, 28, 2, True)],
)
def test_cells_with_failed_or_non_converged_trials_are_marked(trials, converged, failed, flagged):
    assert extended.incomplete(trials, converged, failed) is flagged
    assert (
        extended.cell_text(430.0, extended.incomplete(trials, converged, failed)).endswith("†")
        is flagged
    )


def test_heat_map_marks_a_non_converged_cell():
    collected = _cmc(n_trials=2)
    table = extended.extended_table(collected, "cmc", CMC_PAPER)
    methods = list(extended.mean_ranks(table)["method"])
    fig, ax = plt.subplots()
    extended._heatmap(ax, table, "cmc", methods, CMC_PAPER[1])
    marked = [t.get_text() for t in ax.texts if t.get_text().endswith("†")]
    plt.close(fig)
    # BC did not converge on trial 1 at every ±5° condition: 6 cells, nothing failed outright.
    assert len(marked) == 6
    assert (table["failed"] == 0).all()


def test_rows_are_labelled_with_units():
    assert extended.condition_label("cmc", ("H", 5, 0.5)) == "H set, ±5°, 0.5 mm noise"
    assert extended.condition_label("hinge", ("knee", 30, 0.5)) == "knee, FE 30°, AA/FE 0.5"


def test_rank_axis_stops_at_the_number_of_methods():
    table = extended.extended_table(_tied_cmc(), "cmc", CMC_PAPER)
    ranks = extended.mean_ranks(table)
    fig, ax = plt.subplots()
    extended._rank_bars(ax, ranks, method_styles(ranks["method"]), CMC_PAPER[1])
    assert ax.get_xlim() == (0, len(ranks))
    plt.close(fig)


@pytest.mark.parametrize(("study", "make"), [("cmc", _tied_cmc), ("hinge", _hinge), ("hip", _hip)])
def test_extended_figure_runs(study, make):
    assert _drawn(extended.extended_figure(make(), study))


@pytest.mark.parametrize("far", [1e300, np.inf], ids=["1e300", "inf"])
def test_extended_figure_draws_a_mean_error_far_off_beyond_its_scale(tmp_path, far):
    collected = _cmc(n_trials=2)
    collected.loc[collected["method"] == "SCoRE", "error_mm"] = far
    fig = extended.extended_figure(collected, "cmc", CMC_PAPER)
    heat = fig.axes[0]
    assert heat.images[0].norm.vmax < 1e3  # the others keep their colours
    assert f"{far:.3g}" in [text.get_text() for text in heat.texts]
    assert "beyond the colour scale" in fig.get_suptitle()
    save_figure(fig, {"png": str(tmp_path / "extended.png")})
    assert (tmp_path / "extended.png").stat().st_size > 10_000


# ----------------------------------------------------------------------------- paper figures


def test_paper_a_figures_run():
    collected = _cmc()
    assert _drawn(paper_a.fig4(collected))
    trial = paper_a.choose_fig3_trial(collected)
    rows = collected[
        (collected["marker_set"] == "M")
        & (collected["rom_deg"] == 5)
        & (collected["noise_mm"] == 1.0)
        & (collected["trial"] == trial)
    ]
    t = np.linspace(0, 4 * np.pi, 120)
    markers = np.stack(
        [np.stack([20 * np.cos(t) + k, 20 * np.sin(t), 10 * k + 0 * t], -1) for k in range(3)], 1
    )
    fig = paper_a.fig3(
        markers,
        np.zeros(3),
        rows,
        {"LS": 10.9, "NM": 0.3, "MA": 3.7, "IS": 1.4, "BC": 3.7},
        chosen=paper_a.fig3_chosen_text(collected, trial),
    )
    assert _drawn(fig)


def test_paper_a_fig3_lists_an_estimate_far_off_and_marks_its_bar():
    collected = _cmc(n_trials=1)
    rows = collected[
        (collected["marker_set"] == "M")
        & (collected["rom_deg"] == 5)
        & (collected["noise_mm"] == 1.0)
    ].copy()
    far = rows["method"] == "BC"
    rows.loc[far, ["center_x", "center_y", "center_z"]] = 1e300
    rows.loc[far, "error_mm"] = np.sqrt(3) * 1e300
    t = np.linspace(0, 4 * np.pi, 120)
    markers = np.stack(
        [np.stack([20 * np.cos(t), 20 * np.sin(t), 10 * k + 0 * t], -1) for k in range(3)], 1
    )
    fig = paper_a.fig3(markers, np.zeros(3), rows, {"BC": 3.7})
    view, bars = fig.axes
    labels = [text.get_text() for text in view.get_legend().get_texts()]
    assert "BC: 1.73e+300 mm, outside the view" in labels
    assert abs(np.diff(view.get_xlim())[0]) < 1e3  # the view keeps to the data
    assert "1.73e+300 (beyond the scale)" in [text.get_text() for text in bars.texts]
    assert _drawn(fig)


def test_paper_b_figures_run():
    assert _drawn(paper_b.fig5(_hinge()))
    assert _drawn(paper_b.fig2(_fig2_examples()))


def _fig2_of_a_run(config: dict, methods) -> bool:
    """Whether paper B's Fig 2 draws from a hinge run of ``config`` whose estimate jobs made
    the answers of ``methods`` on Fig 2's conditions."""
    datasets, frames = [], []
    for condition in papers_b.FIG2_CONDITIONS:
        trials = run.simulate_condition(config, "hinge", condition)
        datasets.append((trials, {"truth": trials.truth}))
        frames += [run.estimate("hinge", m, trials, condition) for m in methods]
    collected = pd.concat(frames, ignore_index=True)
    inputs = Inputs(collected=collected, published={}, config=config, datasets=datasets)
    fig = papers_b.PAPER.output("paper_b_fig2").render(inputs)
    drawn = _drawn(fig)
    plt.close(fig)
    return drawn


def test_fig2_draws_the_collected_answers_of_a_valid_protocol_whatever_its_steps():
    """At 0.5 mm of noise (a protocol the config check takes) the knee's 90° grid motion moves
    a marker 29 mm in one frame, which a recording's screening reads as a jump: Fig 2 draws
    the answers the estimate jobs made and the ranking holds, not a screened fit again."""
    config = {"base_seed": 1, "studies": {"hinge": {"trials": 3}}}
    config["studies"]["hinge"]["protocol"] = {"knee": {"noise_sd_mm": 0.5}}
    assert _fig2_of_a_run(config, papers_b.METHODS)


def test_fig2_draws_the_methods_the_study_lists():
    """A hinge study listing only some of paper B's costs (here the combined one) draws those
    in Fig 2, as before it drew the collected answers."""
    assert _fig2_of_a_run({"base_seed": 1, "studies": {"hinge": {"trials": 3}}}, ["combined"])


def test_fig2_trial_is_the_median_by_combined_error():
    collected = _hinge()
    cell = (collected["protocol"] == "knee") & (collected["fe_rom_deg"] == 30)
    cell &= (collected["aa_ratio"] == 0.5) & (collected["method"] == "combined")
    collected.loc[cell, "error_deg"] = [5.0, 1.0, 3.0, 4.0]
    condition = {"protocol": "knee", "fe_rom_deg": 30, "aa_ratio": 0.5}
    assert paper_b.choose_fig2_trial(collected, condition) == 2


def test_axis_error_ignores_the_sign_of_the_direction():
    assert paper_b.axis_error_deg(np.array([0, 0, -1.0]), np.array([0, 0, 2.0])) == 0.0
    assert paper_b.axis_error_deg(np.array([1.0, 0, 0]), np.array([0, 0, 1.0])) == pytest.approx(
        90.0
    )


def test_paper_c_outputs_run_with_readable_headers():
    collected = _hip()
    paper = pd.DataFrame(
        [
            {"n_frames": n, "sqrt_trace_cov_mm": 50.0 / n, "validation_index": 1.0}
            for n in (4, 8, 16, 32, 75, 150, 300, 600, 1200)
        ]
    )
    header = markdown_table(paper_c.table1(collected, paper)).splitlines()[0]
    assert "gm_v_vs_own_1200" not in header
    assert "GM: mean v vs own 1200-frame estimate" in header
    assert "frames used, Nt" in header
    assert _drawn(paper_c.uncertainty_figure(collected, paper))


def test_fig2_draws_the_model_each_cost_fits():
    t = np.linspace(-0.5, 0.5, 30)
    trajectory = np.stack([60 * np.cos(t), 60 * np.sin(t), 0 * t], -1)
    point, direction = np.zeros(3), np.array([0.0, 0.0, 1.0])
    fig = plt.figure()
    kinds = {}
    for method, (label, draw) in paper_b._MODELS.items():
        ax = fig.add_subplot(projection="3d")
        draw(ax, trajectory, point, direction, "C0")
        kinds[method] = (label, {type(a) for a in [*ax.collections, *ax.lines]})
    plt.close(fig)
    assert kinds["planar"] == ("best-fitting planes", {Poly3DCollection})
    assert kinds["radial"] == ("best-fitting cylinders", {Poly3DCollection})
    assert kinds["combined"] == ("best-fitting circles", {Line3D})


def test_3d_axes_get_equal_scales():
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    equal_3d_limits(ax, np.array([[0, 0, 0], [25.0, 10.0, 60.0]]))
    spans = [np.ptp(ax.get_xlim()), np.ptp(ax.get_ylim()), np.ptp(ax.get_zlim())]
    plt.close(fig)
    assert spans == pytest.approx([spans[0]] * 3)


def _labelled_figure():
    fig = plt.figure(figsize=(4, 3), layout="constrained")
    ax = fig.add_subplot()
    ax.plot([0, 1], [0, 1])
    ax.set_title("a title that sets the crop")
    ax.set_xlabel("x label")
    return fig


def test_figures_are_laid_out_once_and_cropped_as_a_tight_save_crops(tmp_path, monkeypatch):
    from matplotlib.figure import Figure
    from PIL import Image

    reference = tmp_path / "tight.png"
    _labelled_figure().savefig(reference, dpi=SAVE_DPI, bbox_inches="tight")
    draws = []
    original = Figure.draw
    monkeypatch.setattr(
        Figure, "draw", lambda self, renderer: draws.append(1) or original(self, renderer)
    )
    outputs = {"png": str(tmp_path / "f.png"), "pdf": str(tmp_path / "f.pdf")}
    save_figure(_labelled_figure(), outputs)
    # One drawing per format: the layout and the crop are computed once, without drawing (a
    # tight save draws every format twice).
    assert len(draws) == 2
    with Image.open(reference) as tight, Image.open(outputs["png"]) as ours:
        assert abs(ours.size[0] - tight.size[0]) <= 1 and abs(ours.size[1] - tight.size[1]) <= 1
    assert (tmp_path / "f.pdf").read_bytes().startswith(b"%PDF")


def test_every_method_has_one_colour_of_its_own():
    known = ["NM", "LS", "BC", "MA", "IS", "SCoRE", "LM", "planar", "radial", "combined"]
    known += ["SARA", "gauss-markov", "gauss-markov-frame0", "analytic"]
    colours = [method_style(m)["color"] for m in known]
    assert len(set(colours)) == len(colours)
    # A newcomer's colour follows its name, and two newcomers in one figure never share one.
    assert method_style("mine") == method_style("mine")
    styles = method_styles([*known, *(f"new{i}" for i in range(6))])
    assert len({s["color"] for s in styles.values()}) == len(styles)


# ----------------------------------------------------------------------------- figure defects


def _published(paper):
    from jointbench.comparison.published import load_published

    return load_published(paper.published)


def _fig3_on_one_trial():
    collected = _cmc(n_trials=1)
    rows = collected[
        (collected["marker_set"] == "M")
        & (collected["rom_deg"] == 5)
        & (collected["noise_mm"] == 1.0)
    ]
    t = np.linspace(0, 4 * np.pi, 120)
    markers = np.stack(
        [np.stack([20 * np.cos(t), 20 * np.sin(t), 10 * k + 0 * t], -1) for k in range(3)], 1
    )
    example = {"LS": 10.9, "NM": 0.3, "MA": 3.7, "IS": 1.4, "BC": 3.7}
    return paper_a.fig3(markers, np.zeros(3), rows, example), rows


def _method_colours():
    from matplotlib.colors import to_rgb

    return {to_rgb(method_style(m)["color"]) for m in paper_a.PAPER_METHODS}


def test_fig3_errors_are_points_on_a_log_axis_not_bars():
    from matplotlib.colors import to_rgb
    from matplotlib.patches import Rectangle

    fig, rows = _fig3_on_one_trial()
    _, errors = fig.axes
    assert errors.get_yscale() == "log"
    # On a log axis a bar's length means nothing: no bars at all.
    assert not [p for p in errors.patches if isinstance(p, Rectangle)]
    drawn = {round(float(y), 9) for line in errors.lines for y in line.get_ydata()}
    ours = rows.loc[rows["method"].isin(paper_a.PAPER_METHODS), "error_mm"]
    assert {round(float(e), 9) for e in ours} <= drawn
    # The legend's "this trial" entry is not in any method's colour.
    legend = errors.get_legend()
    entries = dict(zip(legend.get_texts(), legend.legend_handles, strict=True))
    (this_trial,) = [h for t, h in entries.items() if t.get_text().startswith("this trial")]
    assert to_rgb(this_trial.get_markerfacecolor()) not in _method_colours()
    plt.close(fig)


def test_fig3_estimates_are_hollow_so_one_does_not_hide_another():
    fig, _ = _fig3_on_one_trial()
    view = fig.axes[0]
    names = paper_a.PAPER_METHODS
    estimates = [c for c in view.collections if c.get_label().split(":")[0] in names]
    assert len(estimates) == 5
    for scatter in estimates:
        assert (scatter.get_facecolor()[:, 3] == 0).all(), scatter.get_label()
    plt.close(fig)


def test_fig4_draws_the_papers_stated_values_read_from_its_published_values():
    from jointbench.papers.paper_a import PAPER

    published = _published(PAPER)
    claims = {c["id"]: c["published"] for c in published["claims"]}
    stated = paper_a.fig4_stated(published)
    assert sorted(stated["value_mm"]) == sorted([*claims["A3"], claims["A9"]])
    fig = paper_a.fig4(_cmc(), published)
    m_panel, h_panel = fig.axes
    m_values = {round(float(y), 6) for line in m_panel.lines for y in line.get_ydata()}
    h_values = {round(float(y), 6) for line in h_panel.lines for y in line.get_ydata()}
    assert set(claims["A3"]) <= m_values
    assert claims["A9"] in h_values
    assert m_panel.get_ylim()[1] > max(claims["A3"])
    texts = [t.get_text() for t in m_panel.texts]
    assert f"paper: all > {claims['A3'][0]:g}" in texts
    plt.close(fig)


def _legends_off_the_data(fig) -> list[str]:
    """The data points (of every line, in display coordinates) that some legend of ``fig``
    covers, as "axes title: x, y"; empty when every legend is off the data."""
    fig.canvas.draw()
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend()] + list(fig.legends)
    boxes = [legend.get_window_extent() for legend in legends]
    covered = []
    for ax in fig.axes:
        for line in ax.lines:
            xy = np.column_stack([line.get_xdata(), line.get_ydata()]).astype(float)
            xy = xy[np.isfinite(xy).all(axis=1)]
            for x, y in ax.transData.transform(xy) if len(xy) else []:
                if any(box.contains(x, y) for box in boxes):
                    covered.append(f"{ax.get_title()}: {x:.0f}, {y:.0f}")
    return covered


def _paper_b_cells():
    from jointbench.papers.paper_b import PAPER

    entries = [e for e in _published(PAPER)["values"] if e["id"].startswith("B-T1-")]
    keys = [e["id"].removeprefix("B-T1-").split("-") for e in entries]
    cells = pd.DataFrame(keys, columns=paper_b.CELL)
    cells["fe_rom_deg"] = cells["fe_rom_deg"].astype(int)
    cells["aa_ratio"] = cells["aa_ratio"].astype(float)
    cells["published"] = [e["published"] for e in entries]
    cells["within_tolerance"] = [i % 10 != 0 for i in range(len(cells))]
    return cells


def test_fig5_legend_covers_no_data():
    # The planar curve's rise from ratio 0.1 to 0.3 runs through the axes' left middle.
    collected = _hinge()
    planar = collected["method"] == "planar"
    collected.loc[planar, "error_deg"] = 10 + 100 * collected.loc[planar, "aa_ratio"]
    for cells in (None, _paper_b_cells()):
        fig = paper_b.fig5(collected, *([] if cells is None else [cells]))
        assert _legends_off_the_data(fig) == []
        plt.close(fig)


def test_fig5_draws_every_published_mean_and_rings_the_cells_outside_tolerance():
    cells = _paper_b_cells()
    fig = paper_b.fig5(_hinge(), cells)
    for ax, protocol in zip(fig.axes, ("knee", "mcp"), strict=True):
        drawn = {round(float(y), 6) for line in ax.lines for y in line.get_ydata()}
        published = cells.loc[cells["protocol"] == protocol, "published"]
        assert {round(float(v), 6) for v in published} <= drawn
        rings = [line for line in ax.lines if line.get_markeredgecolor() == "red"]
        missed = cells[(cells["protocol"] == protocol) & ~cells["within_tolerance"]]
        assert sum(len(line.get_xdata()) for line in rings) == len(missed)
    within = int(cells["within_tolerance"].sum())
    assert f"{within} of {len(cells)} Table 1 means within tolerance" in fig.get_suptitle()
    assert "mcp" not in " ".join(ax.get_title() for ax in fig.axes)
    plt.close(fig)


def _fig2_examples():
    t = np.linspace(-0.5, 0.5, 60)
    markers = np.stack(
        [
            np.stack([r * np.cos(t), r * np.sin(t), 20.0 * k + 0 * t], -1)
            for k, r in enumerate((60, 80, 70))
        ],
        1,
    )
    truth = {"axis_point": [0.0, 0.0, 0.0], "axis_direction": [0.0, 0.0, 1.0]}
    fits = {
        "planar": (np.zeros(3), np.array([0.3, 0.0, 1.0])),
        "radial": (np.zeros(3), np.array([0.0, 0.2, 1.0])),
        "combined": (np.zeros(3), np.array([0.0, 0.0, 1.0])),
    }
    # The second row's trial is smaller and tilted: its planes face another way.
    tilted = markers[..., [2, 1, 0]] * 0.5
    tilted_fits = {m: (p, d[[2, 1, 0]]) for m, (p, d) in fits.items()}
    tilted_truth = {"axis_point": [0.0, 0.0, 0.0], "axis_direction": [1.0, 0.0, 0.0]}
    return [("a", markers, truth, fits), ("b", tilted, tilted_truth, tilted_fits)]


def test_fig2_shares_axis_limits_within_a_row():
    fig = paper_b.fig2(_fig2_examples())
    for row in (fig.axes[:3], fig.axes[3:]):
        for get in ("get_xlim", "get_ylim", "get_zlim"):
            limits = {tuple(np.round(getattr(ax, get)(), 9)) for ax in row}
            assert len(limits) == 1, (get, limits)
    plt.close(fig)


def test_fig2_draws_each_cost_in_one_colour_in_every_row():
    fig = paper_b.fig2(_fig2_examples())
    for column in range(3):
        colours = {
            tuple(np.round(face, 6))
            for ax in fig.axes[column::3]
            for surface in ax.collections
            if isinstance(surface, Poly3DCollection)
            for face in surface.get_facecolor()
        }
        assert len(colours) <= 1, (column, colours)
    plt.close(fig)


#: The report shows a figure this wide [px]; every text of a figure must then be at least
#: READABLE_PX tall (its font size in display pixels).
REPORT_WIDTH_PX = 870
READABLE_PX = 9.0


def _text_px(fig) -> dict[str, float]:
    """Every visible, non-empty text of ``fig`` and its font size [px] when the figure, cropped
    as saved, is shown REPORT_WIDTH_PX wide."""
    from matplotlib.text import Text

    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    width_in = fig.get_tightbbox(renderer).padded(0.1).width
    scale = REPORT_WIDTH_PX / (72 * width_in)
    return {
        text.get_text(): text.get_fontsize() * scale
        for text in fig.findobj(Text)
        if text.get_visible() and text.get_text().strip() and text.get_window_extent().width > 0
    }


def _hip_paper():
    return pd.DataFrame(
        [
            {"n_frames": n, "sqrt_trace_cov_mm": 50.0 / n, "validation_index": 1.0}
            for n in (4, 8, 16, 32, 75, 150, 300, 600, 1200)
        ]
    )


def _paper_a_published():
    from jointbench.papers.paper_a import PAPER

    return _published(PAPER)


PAPER_FIGURES = {
    "paper_a_fig4": lambda: paper_a.fig4(_cmc(), _paper_a_published()),
    "paper_a_fig3": lambda: _fig3_on_one_trial()[0],
    "paper_b_fig5": lambda: paper_b.fig5(_hinge(), _paper_b_cells()),
    "paper_b_fig2": lambda: paper_b.fig2(_fig2_examples()),
    "paper_c_uncertainty": lambda: paper_c.uncertainty_figure(_hip(), _hip_paper()),
}


@pytest.mark.parametrize("name", PAPER_FIGURES)
def test_paper_figure_text_is_readable_at_the_report_width(name):
    fig = PAPER_FIGURES[name]()
    small = {text: round(px, 1) for text, px in _text_px(fig).items() if px < READABLE_PX}
    plt.close(fig)
    assert small == {}


#: Names of the code that a reader of a figure should never meet.
INTERNAL_NAMES = ("mcp", "cmc", "hinge", "hip_sta", "center", "axis_point", "marker_set")


@pytest.mark.parametrize("name", PAPER_FIGURES)
def test_paper_figures_use_no_internal_names(name):
    import re

    fig = PAPER_FIGURES[name]()
    texts = " ".join(_text_px(fig))
    plt.close(fig)
    found = [word for word in INTERNAL_NAMES if re.search(rf"\b{word}\b", texts)]
    assert found == []


def test_paper_c_panels_keep_their_width_and_legends_stay_apart():
    fig = paper_c.uncertainty_figure(_hip(), _hip_paper())
    fig.canvas.draw()
    width = fig.get_tightbbox(fig.canvas.get_renderer()).width * fig.dpi
    for ax in fig.axes:
        # A panel squeezed by its legends shows Nt's tick labels on top of each other.
        assert ax.get_window_extent().width > 0.33 * width, ax.get_title()
    boxes = [legend.get_window_extent() for legend in fig.legends]
    boxes += [ax.get_legend().get_window_extent() for ax in fig.axes if ax.get_legend()]
    assert len(boxes) == 2
    assert not boxes[0].overlaps(boxes[1])
    assert _legends_off_the_data(fig) == []
    plt.close(fig)
