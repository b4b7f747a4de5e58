"""The checked axis fit's statement that its cost has a second, distant minimum that the data
cannot tell from the answer (:func:`jointbench.estimators.precision.annotate_ambiguity`): the
radial cost's second minimum on noisy pure hinges, its rate of warnings about right answers,
noise-free data, the many-trial form and rigid transforms."""

from __future__ import annotations

import numpy as np
import pytest
from test_axis_sd import CENTRE, Z, hinge

import jointbench
from jointbench.estimators import precision, registry
from jointbench.geometry import angle_between_lines_deg, rotation_about_axis

AMBIGUOUS = "the direction is ambiguous"
SEEDS = range(40)


def error_deg(direction) -> float:
    return float(angle_between_lines_deg(np.asarray(direction), Z))


@pytest.fixture(scope="module")
def thirty_degree_hinges() -> dict[float, list]:
    """The radial checked answers of 30 degree hinges over 40 seeds, by noise [mm]."""
    return {
        noise: [
            jointbench.fit_axis(hinge(seed, 30.0, noise=noise), method="radial") for seed in SEEDS
        ]
        for noise in (0.3, 1.0)
    }


@pytest.mark.parametrize("noise", [0.3, 1.0])
def test_every_radial_answer_far_off_a_hinge_axis_says_the_direction_is_ambiguous(
    thirty_degree_hinges, noise
):
    far_off = [r for r in thirty_degree_hinges[noise] if error_deg(r.direction) > 45.0]
    # The case: 2 of 40 at 0.3 mm, 13 at 1 mm.
    assert len(far_off) >= 2
    for result in far_off:
        assert AMBIGUOUS in result.status
        assert result.converged  # left as the method set it
        other = result.diagnostics["other_minimum"]
        assert error_deg(other["direction"]) < 5.0  # the other minimum is the true axis's
        assert other["angle_deg"] > 45.0
        assert other["difference"] <= 3.1 * other["se"]


def test_right_answers_of_a_thirty_degree_hinge_rarely_say_so(thirty_degree_hinges):
    right = [r for r in thirty_degree_hinges[0.3] if error_deg(r.direction) < 5.0]
    warned = [r for r in right if AMBIGUOUS in r.status]
    # Measured: 1 of 38 (a ten-start answer 90 degrees off, replaced by the restart's, whose
    # cost is within the noise of it).
    assert len(right) >= 35
    assert len(warned) <= 3


def test_the_warning_states_the_angle_both_costs_and_the_standard_errors():
    result = jointbench.fit_axis(hinge(18, 30.0), method="radial")
    other = result.diagnostics["other_minimum"]
    assert other["cost"] > result.cost
    assert (
        f"warning: the radial cost has another minimum {other['angle_deg']:.0f} deg away whose "
        f"cost is within the noise of this one's ({other['cost']:.6g} against "
        f"{result.cost:.6g}, {other['difference'] / other['se']:.2f} standard errors of the "
        "difference, not above 3.09 at 0.001): the direction is ambiguous"
    ) in result.status
    assert result.status.startswith("warning: the radial cost has another minimum")


def test_noise_free_data_never_say_so_though_their_searches_end_in_distant_minima():
    rng = np.random.default_rng(7)
    distant = 0
    for _ in range(25):
        local = rng.uniform(-60.0, 60.0, (int(rng.integers(3, 6)), 3))
        axis = rng.normal(size=3)
        rotations = rotation_about_axis(
            axis / np.linalg.norm(axis), np.radians(np.linspace(0.0, rng.uniform(5.0, 90.0), 100))
        )
        markers = rng.normal(scale=30.0, size=3) + np.einsum("fij,mj->fmi", rotations, local)
        for method in ("radial", "combined"):
            result = jointbench.fit_axis(markers, method=method)
            distant += "other_minimum" in result.diagnostics
            assert AMBIGUOUS not in result.status
    assert distant >= 3  # the case: ten-start answers far off, replaced by the restart's


def test_the_many_trial_form_gives_each_trial_its_outcome_alone():
    trials = np.stack(
        [hinge(18, 30.0), hinge(23, 30.0), hinge(0, 30.0), hinge(26, 30.0, noise=1.0)]
    )
    warned = {}
    for method in ("radial", "combined"):
        together = registry.many("axis", method)(trials)
        for trial, outcome in zip(trials, together, strict=True):
            alone = registry.get("axis", method)(trial)
            assert outcome.status == alone.status
            assert outcome.diagnostics.get("other_minimum") == alone.diagnostics.get(
                "other_minimum"
            )
        warned[method] = [AMBIGUOUS in outcome.status for outcome in together]
    # The cases, in order: a radial answer 85 degrees off, a right one that replaced a ten-start
    # answer 90 degrees off, one without another minimum and one 88 degrees off; the combined
    # cost has none of them.
    assert warned == {"radial": [True, True, False, True], "combined": [False] * 4}


def test_the_statement_moves_with_a_rigid_transform():
    markers = hinge(26, 30.0)
    rotation = rotation_about_axis(np.array([1.0, -2.0, 0.5]) / np.sqrt(5.25), np.radians(37.0))
    moved = (markers - CENTRE) @ rotation.T + np.array([300.0, -120.0, 45.0])
    first = jointbench.fit_axis(markers, method="radial")
    second = jointbench.fit_axis(moved, method="radial")
    assert AMBIGUOUS in first.status and AMBIGUOUS in second.status
    a, b = first.diagnostics["other_minimum"], second.diagnostics["other_minimum"]
    # The searches follow the data to their tolerance (1e-4 rad), not to rounding, and both
    # minima's residuals move with them.
    assert b["angle_deg"] == pytest.approx(a["angle_deg"], abs=0.02)
    assert b["cost"] == pytest.approx(a["cost"], rel=1e-6)
    assert b["difference"] / b["se"] == pytest.approx(a["difference"] / a["se"], rel=1e-3)
    assert angle_between_lines_deg(np.array(b["direction"]), rotation @ a["direction"]) < 0.02


def test_frames_repeated_exactly_do_not_tell_the_two_minima_apart():
    markers = hinge(18, 30.0)
    once = registry.get("axis", "radial")(markers)
    five_times = registry.get("axis", "radial")(np.concatenate([markers] * 5))
    assert AMBIGUOUS in five_times.status
    a, b = once.diagnostics["other_minimum"], five_times.diagnostics["other_minimum"]
    assert type(b["angle_deg"]) is float
    assert (b["difference"], b["se"]) == (
        pytest.approx(a["difference"], rel=1e-9),
        pytest.approx(a["se"], rel=1e-9),
    )


def test_the_statistic_tells_a_uniformly_worse_fit_apart_and_an_equal_one_not():
    answer = np.random.default_rng(0).chisquare(1, size=(4, 120)) * 0.09
    difference, se = precision.ambiguity(answer, answer + 0.01)
    assert (difference, se) == (pytest.approx(4.8), pytest.approx(0.0, abs=1e-12))
    shuffled = np.random.default_rng(1).permutation(answer.ravel())
    difference, se = precision.ambiguity(answer, shuffled)
    assert difference == pytest.approx(0.0, abs=1e-9) and se > 0.0


def test_the_simulated_studies_bare_functions_carry_no_statement():
    result = registry.get("axis", "radial", checked=False)(hinge(18, 30.0))
    assert error_deg(result.direction) > 45.0
    assert result.status == "ok"
    assert "other_minimum" not in result.diagnostics
