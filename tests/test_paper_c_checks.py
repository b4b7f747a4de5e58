"""Paper C's method checked per trial: the pose alternation's convergence (§5) and the
frame-0 control (the same trials with frame 0 recorded exactly)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from jointbench.comparison.published import comparison_rows, load_published
from jointbench.configuration.studies import get_study
from jointbench.figures.paper_c import CONTROL, frame0_control_table
from jointbench.numerics.poses import fit_rigid_poses, rigid_poses
from jointbench.papers import Inputs, get_paper
from jointbench.papers.paper_c import converged_after
from jointbench.running.run import estimate
from jointbench.running.scoring import CHI2_3DOF_95
from jointbench.simulate.hip import EXACT_FRAME0_COLUMNS, POSE_FIT_COLUMNS

HIP = get_study("hip")


def _trials(n_frames: int, n_trials: int, **protocol):
    condition = {"n_frames": n_frames}
    rngs = [np.random.default_rng(seed) for seed in range(n_trials)]
    return condition, HIP.simulate(condition, HIP.protocol(protocol), rngs)


def _rms(values) -> float:
    return float(np.sqrt(np.mean(np.asarray(values) ** 2)))


def test_the_pose_fit_says_how_its_alternation_ended():
    _, trials = _trials(75, 6)
    markers = trials.segments["distal"]
    fit = fit_rigid_poses(markers)
    for mine, plain in zip(fit[:3], rigid_poses(markers), strict=True):
        np.testing.assert_array_equal(mine, plain)
    assert fit.iterations.shape == fit.change_mm.shape == (6,)
    assert (fit.iterations >= 2).all() and (fit.iterations < 20).all()
    assert (fit.change_mm < 1e-12).all()
    # Stopped early: the last change is the one of the last iteration made, above tolerance.
    once = fit_rigid_poses(markers, max_iterations=1)
    np.testing.assert_array_equal(once.iterations, 1)
    assert (once.change_mm > 1e-3).all()


def test_exact_markers_need_one_iteration_to_confirm_their_coordinates():
    _, trials = _trials(32, 2, noise_mm=0.0)
    fit = fit_rigid_poses(trials.segments["proximal"])
    np.testing.assert_array_equal(fit.iterations, 1)


@pytest.fixture(scope="module")
def gauss_markov_rows():
    condition, trials = _trials(1200, 40)
    return estimate("hip", "gauss-markov", trials, condition)


def test_gauss_markov_rows_carry_the_pose_fits(gauss_markov_rows):
    rows = gauss_markov_rows
    for column in POSE_FIT_COLUMNS:
        assert rows[column].notna().all(), column
    for segment in ("proximal", "distal"):
        fit = fit_rigid_poses(_trials(1200, 40)[1].segments[segment])
        np.testing.assert_array_equal(rows[f"pose_iterations_{segment}"], fit.iterations)
        assert (rows[f"pose_change_mm_{segment}"] < 1e-12).all()


def test_the_frame0_control_removes_the_bias_of_eq2s_single_centre(gauss_markov_rows):
    """With a noisy frame 0 gauss-markov's error is many times its predicted sqrt(tr Wc);
    with frame 0 exact (the control) its error matches the prediction and the 95 % ellipsoid
    holds the true centre in most trials."""
    rows = gauss_markov_rows
    error, predicted, e = (rows[EXACT_FRAME0_COLUMNS[c]] for c in EXACT_FRAME0_COLUMNS)
    default_ratio = _rms(rows["error_mm"]) / rows["sqrt_trace_cov_mm"].median()
    control_ratio = _rms(error) / predicted.median()
    assert default_ratio > 5
    assert 0.7 < control_ratio < 1.4
    assert np.mean(e <= CHI2_3DOF_95) > 0.8
    assert np.mean(rows["mahalanobis_sq"] <= CHI2_3DOF_95) < 0.2


def test_the_control_is_the_noise_free_frame0_run(gauss_markov_rows):
    """The control refits the same draws as the protocol option ``noise_free_frame0``
    simulates them: its scores are that run's gauss-markov scores."""
    condition, trials = _trials(1200, 40, noise_free_frame0=True)
    variant = estimate("hip", "gauss-markov", trials, condition)
    for column, control in EXACT_FRAME0_COLUMNS.items():
        np.testing.assert_allclose(gauss_markov_rows[control], variant[column], rtol=1e-9)


# ------------------------------------------------------------------------ claim C5 (paper C)


def _c5(rows):
    document = load_published(get_paper("paper_c").published)
    measured = get_paper("paper_c").measure(
        Inputs(collected=rows, published=document, config={"studies": {}})
    )
    return comparison_rows(document, measured).set_index("id").loc["C5"]


def test_c5_counts_the_iterations_before_the_one_that_confirms_convergence(gauss_markov_rows):
    row = _c5(gauss_markov_rows)
    counts = converged_after(gauss_markov_rows)
    made = gauss_markov_rows[["pose_iterations_proximal", "pose_iterations_distal"]]
    np.testing.assert_array_equal(counts.to_numpy(), made.to_numpy() - 1)
    assert row["status"] == "reproduced"
    assert f"largest {int(counts.to_numpy().max())}" in row["reproduced"]


@pytest.mark.parametrize(
    ("iterations", "change_mm", "status"),
    [
        (5, 1e-13, "reproduced"),  # converged after 4, confirmed by the 5th
        (5, 1e-11, "not reproduced"),  # still changing after 5
        (6, 1e-13, "not reproduced"),  # converged after 5
        (20, 1e-6, "not reproduced"),  # never converged
    ],
)
def test_c5_fails_when_one_trial_needs_5_iterations(
    gauss_markov_rows, iterations, change_mm, status
):
    rows = gauss_markov_rows.copy()
    rows.loc[rows.index[3], "pose_iterations_distal"] = iterations
    rows.loc[rows.index[3], "pose_change_mm_distal"] = change_mm
    rows.loc[rows.index[3], "pose_converged_distal"] = change_mm < 1e-12
    assert _c5(rows)["status"] == status


def test_c5_is_not_applicable_without_recorded_pose_fits(gauss_markov_rows):
    rows = gauss_markov_rows.drop(columns=list(POSE_FIT_COLUMNS))
    assert _c5(rows)["status"] == "not applicable"


def test_one_trial_without_a_trial_axis_has_scalar_counts():
    _, trials = _trials(16, 1)
    fit = fit_rigid_poses(trials.segments["proximal"][0])
    assert fit.rotation.shape == (16, 3, 3) and fit.body.shape == (3, 3)
    assert fit.iterations.shape == fit.change_mm.shape == ()


# ----------------------------------------------------------- the frame-0 control, reported


def test_the_control_is_reported_beside_the_default(gauss_markov_rows):
    condition, trials = _trials(1200, 40)
    frame0 = estimate("hip", "gauss-markov-frame0", trials, condition)
    collected = pd.concat([gauss_markov_rows, frame0], ignore_index=True)
    output = {o.name: o for o in get_paper("paper_c").outputs}["paper_c_frame0_control"]
    document = load_published(get_paper("paper_c").published)
    table = output.render(Inputs(collected=collected, published=document, config={})).frame
    ratio = table.set_index("variant")["error_over_predicted"]
    assert list(ratio.index) == ["gauss-markov", "gauss-markov-frame0", CONTROL]
    assert ratio["gauss-markov"] > 5
    assert 0.7 < ratio[CONTROL] < 1.4
    control = table.set_index("variant").loc[CONTROL]
    assert control["rms_error_mm"] == pytest.approx(
        _rms(gauss_markov_rows["exact_frame0_error_mm"])
    )
    headline = output.headline({output.name: table})
    assert f"{CONTROL} {ratio[CONTROL]:.2f}×" in headline
    assert f"gauss-markov {ratio['gauss-markov']:.2f}×" in headline


def test_a_run_without_the_control_columns_reports_the_variants_it_has(gauss_markov_rows):
    rows = gauss_markov_rows.drop(columns=list(EXACT_FRAME0_COLUMNS.values()))
    table = frame0_control_table(rows)
    assert set(table["variant"]) == {"gauss-markov"}
