"""The fitted marker radii of the centre methods, scored against the simulated truth (paper A's
LS radius underestimation)."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from jointbench.comparison.published import comparison_rows, load_published
from jointbench.configuration.studies import get_study
from jointbench.papers import Inputs, get_paper
from jointbench.resultfiles.schema import check_estimates
from jointbench.running.run import estimate
from jointbench.running.scoring import RADIUS_COLUMN, score_columns
from jointbench.simulate import RADII_TRUTH

CMC = get_study("cmc")


def _trials(rom_deg: float, noise_mm: float, n_trials: int = 4):
    condition = {"marker_set": "M", "rom_deg": rom_deg, "noise_mm": noise_mm}
    rngs = [np.random.default_rng(seed) for seed in range(n_trials)]
    return condition, CMC.simulate(condition, CMC.protocol(), rngs)


def test_the_truth_holds_each_markers_distance_from_the_centre():
    _, trials = _trials(15, 0.0, n_trials=1)
    moving = trials.segments["moving"][0]
    distances = np.linalg.norm(moving - np.asarray(trials.truth["center"]), axis=-1)
    np.testing.assert_allclose(
        distances, np.broadcast_to(trials.truth[RADII_TRUTH], distances.shape)
    )


@pytest.mark.parametrize("method", ["LS", "NM", "BC", "IS"])
def test_a_sphere_fit_recovers_the_radii_of_noise_free_markers(method):
    condition, trials = _trials(15, 0.0)
    rows = estimate("cmc", method, trials, condition)
    check_estimates(rows, kind="center", condition_keys=CMC.grid_keys, method=method)
    true_mean = np.mean(trials.truth[RADII_TRUTH])
    np.testing.assert_allclose(rows[RADIUS_COLUMN], true_mean, rtol=1e-6)
    np.testing.assert_allclose(rows["radius_error_mm"], 0.0, atol=1e-5)


def test_a_method_without_radii_has_no_radius_error():
    condition, trials = _trials(15, 0.0, n_trials=1)
    rows = estimate("cmc", "MA", trials, condition)
    assert rows[RADIUS_COLUMN].isna().all()
    assert rows["radius_error_mm"].isna().all()


def test_the_radius_error_is_signed_and_needs_the_true_radii():
    estimates = {
        "center_x": [0.0, 0.0],
        "center_y": [0.0, 0.0],
        "center_z": [0.0, 0.0],
        RADIUS_COLUMN: [18.0, 22.0],
    }
    truth = {"center": [0.0, 0.0, 0.0], RADII_TRUTH: [10.0, 20.0, 30.0]}
    np.testing.assert_allclose(
        score_columns("center", estimates, truth)["radius_error_mm"], [-2, 2]
    )
    without = score_columns("center", estimates, {"center": [0.0, 0.0, 0.0]})
    assert np.isnan(without["radius_error_mm"]).all()


def test_ls_underestimates_the_radii_at_a_small_range_of_motion_and_nm_less():
    """Paper A §2: the LS cost 'results in underestimation of the radius r_p when the data has
    reduced RoM'; the Pratt-normalised constraint 'reduces the potential' for it."""
    condition, trials = _trials(5, 1.0, n_trials=10)
    ls = estimate("cmc", "LS", trials, condition)["radius_error_mm"].mean()
    nm = estimate("cmc", "NM", trials, condition)["radius_error_mm"].mean()
    assert ls < 0
    assert abs(nm) < abs(ls)


# ------------------------------------------------------------------------ claim A13 (paper A)


def _radius_world(ls_small=-8.0, nm_small=0.5, ls_large=-0.5) -> pd.DataFrame:
    """Collected cmc rows of LS and NM with their signed radius errors [mm]: ``*_small`` at the
    smallest RoM, ``ls_large`` LS's at the largest (NM's there 0.05), between them halfway."""
    rows = []
    for marker_set in ("M", "H"):
        for rom in (5, 15, 45):
            for noise in (0.5, 1.0, 2.0):
                ls = {5: ls_small, 15: (ls_small + ls_large) / 2, 45: ls_large}[rom]
                nm = {5: nm_small, 15: nm_small / 2, 45: 0.05}[rom]
                for trial in range(3):
                    for method, error in (("LS", ls), ("NM", nm), ("MA", np.nan)):
                        rows.append(
                            {
                                "marker_set": marker_set,
                                "rom_deg": rom,
                                "noise_mm": noise,
                                "trial": trial,
                                "method": method,
                                "error_mm": 1.0,
                                "converged": True,
                                "radius_error_mm": error + 0.1 * (trial - 1),
                            }
                        )
    return pd.DataFrame(rows)


def _a13(collected):
    document = load_published(get_paper("paper_a").published)
    measured = get_paper("paper_a").measure(
        Inputs(collected=collected, published=document, config={"studies": {}})
    )
    return comparison_rows(document, measured).set_index("id").loc["A13"]


def test_a13_holds_when_ls_underestimates_at_small_rom_and_nm_less():
    row = _a13(_radius_world())
    assert row["status"] == "reproduced"
    assert "±5°: LS -8.00, NM +0.50" in row["reproduced"]
    assert "6 of 6 cells" in row["reproduced"]


def test_a13_reads_underestimation_only():
    """An NM overestimate larger than LS's underestimate does not contradict "reduces the
    potential for radius underestimation"."""
    row = _a13(_radius_world(ls_small=-2.0, nm_small=5.0))
    assert row["status"] == "reproduced"


@pytest.mark.parametrize(
    "wrong",
    [
        {"ls_small": 2.0},  # LS overestimates
        {"ls_small": -0.4, "nm_small": -0.6},  # NM underestimates more than LS
        {"ls_small": -0.5, "ls_large": -3.0},  # LS underestimates more at the largest RoM
    ],
)
def test_a13_fails_when_the_sentence_does_not_hold(wrong):
    row = _a13(_radius_world(**wrong))
    assert row["status"] == "not reproduced"
    assert "0 of 6 cells" in row["reproduced"]


def test_a13_is_not_applicable_without_fitted_radii():
    row = _a13(_radius_world().drop(columns="radius_error_mm"))
    assert row["status"] == "not applicable"
