"""An axis answer whose cost's model of a fixed axis the markers leave by more than their noise
(:func:`jointbench.estimators.precision.misfit`), enough that a misfit of that size could tilt
it beyond 10 degrees, held to the principal axis of the segment's rotations within 5 degrees
instead of 30
(:func:`jointbench.estimators.precision.annotate_motion_axis`): motion the cost does not model,
such as a hinge's independent wobble about another axis, tilts the planar and combined answers
by tens of degrees while their SDs, which count that motion as independent noise, stay at one
or two."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from test_axis_motion_check import paper_b_trials
from test_axis_sd import hinge

import jointbench
from jointbench.estimators import axis, precision, registry, support
from jointbench.estimators.results import AxisResult, with_warnings
from jointbench.geometry import angle_between_lines_deg, rotation_matrix
from jointbench.numerics.poses import best_rotation

Z = np.array([0.0, 0.0, 1.0])
MISFIT = "since the markers leave"
LEAST_SQUARES = ("planar", "radial", "combined")


def wobbling_hinge(
    seed: int,
    ratio: float,
    *,
    arc_deg: float = 30.0,
    noise: float = 0.5,
    n_frames: int = 60,
    about: int = 0,
) -> np.ndarray:
    """Markers ``(n_frames, 4, 3)`` [mm] of a flexion about z over ``arc_deg`` and back, with an
    independent rotation about the world axis ``about`` (0: x, 1: y) of ``ratio`` times the
    arc (1.7 cycles, a random phase), markers about 150 mm from the axis along x, isotropic
    noise ``noise`` [mm]."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, n_frames)
    arc = np.radians(arc_deg)
    rotation_vectors = np.zeros((n_frames, 3))
    rotation_vectors[:, 2] = arc * np.sin(np.pi * t)
    rotation_vectors[:, about] = (
        ratio * arc * np.sin(2.0 * np.pi * 1.7 * t + rng.uniform(0.0, 2.0 * np.pi))
    )
    body = rng.normal(scale=20.0, size=(4, 3)) + np.array([150.0, 0.0, 0.0])
    markers = np.einsum("kij,pj->kpi", rotation_matrix(rotation_vectors), body)
    return markers + rng.normal(scale=noise, size=markers.shape)


def hinge_in_a_noisy_reference(
    seed: int, *, arc_deg: float = 10.0, noise: float = 1.0, n_frames: int = 300
) -> np.ndarray:
    """Markers ``(n_frames, 4, 3)`` [mm] of a pure hinge about z (4 markers about 150 mm out
    along x) beside a reference cluster of 3 markers 20 mm about a point 120 mm along z, both
    moving in the world with noise ``noise`` [mm], the moving markers expressed in the
    reference cluster's frame fitted frame by frame, as a recording's are: the reference's pose
    noise moves the whole moving cluster from frame to frame."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, n_frames)
    hinge_turn = rotation_matrix(np.outer(np.radians(arc_deg) * np.sin(2.0 * np.pi * t), Z))
    moving = rng.normal(scale=20.0, size=(4, 3)) + np.array([150.0, 0.0, 0.0])
    reference = rng.normal(scale=20.0, size=(3, 3)) + np.array([0.0, 0.0, 120.0])
    swing = np.radians(10.0) * np.column_stack([np.sin(8 * t), np.sin(4 * t), np.sin(2.5 * t)])
    world = rotation_matrix(swing)
    origin = 30.0 * np.column_stack([np.sin(3 * t), np.sin(2 * t), t])
    seen_reference = np.einsum("kij,pj->kpi", world, reference) + origin[:, None]
    seen_moving = np.einsum("kij,kjl,pl->kpi", world, hinge_turn, moving) + origin[:, None]
    seen_reference += rng.normal(scale=noise, size=seen_reference.shape)
    seen_moving += rng.normal(scale=noise, size=seen_moving.shape)
    centred = reference - reference.mean(axis=0)
    seen_centre = seen_reference.mean(axis=1, keepdims=True)
    turns = best_rotation(np.einsum("kpi,pj->kij", seen_reference - seen_centre, centred))
    return np.einsum("kji,kpj->kpi", turns, seen_moving - seen_centre) + reference.mean(axis=0)


def error_deg(result) -> float:
    return float(angle_between_lines_deg(np.asarray(result.direction), Z))


@pytest.mark.parametrize("method", ["planar", "combined"])
@pytest.mark.parametrize("ratio", [0.1, 0.2])
def test_a_wobbling_hinges_answers_far_off_are_warned_about(method, ratio):
    """Every one more than 15 degrees off; of those 10 to 15 degrees off, the ones that lie
    within 5 degrees and three of its SDs of the principal axis pass (``benchmarks/axis_misfit.py``
    counts them)."""
    results = registry.many("axis", method)(np.stack([wobbling_hinge(s, ratio) for s in range(12)]))
    far = [result for result in results if error_deg(result) > 10.0]
    assert len(far) >= 3  # the case: planar and combined answers tens of degrees off
    for result in far:
        found = result.diagnostics["motion_axis_check"]
        within = found["angle_deg"] - 5.0 <= 3.09 * found["principal_axis_sd_deg"]
        assert within or result.status != "ok"
        assert result.status != "ok" or error_deg(result) < 15.0
    for result in results:
        assert precision.unsupported_by_its_cost(result.diagnostics["axis_misfit"])
        assert result.diagnostics["motion_axis_check"]["band_deg"] == precision.MISFIT_BAND_DEG


def test_the_warning_states_the_misfit_and_its_scale():
    markers = wobbling_hinge(1, 0.1)
    result = jointbench.fit_axis(markers, method="planar")
    assert error_deg(result) > 30.0  # the case: an SD of 2 degrees
    misfit, found = result.diagnostics["axis_misfit"], result.diagnostics["motion_axis_check"]
    assert result.status == (
        f"warning: axis not the motion's: the answer lies {found['angle_deg']:.0f} deg from the "
        f"principal axis of the segment's rotations, beyond 5 deg by {found['z']:.2f} times that "
        f"axis's SD of {found['principal_axis_sd_deg']:.2g} deg (above 3.09 at 0.001); 5 deg, not "
        f"30, {MISFIT} the planar cost's model of a fixed axis by more than their rigid-body "
        f"noise (its residuals' variance {misfit['ratio']:.3g} times that noise's, p = "
        f"{misfit['p_value']:.2g}: the whole cluster moves off the model, by a wobble or by a "
        "reference segment's pose noise carried into its frame; a misfit that size can tilt "
        f"its answer by {misfit['tilt_scale_deg']:.0f} deg)"
    )
    assert result.converged  # left as the method set it
    bare = registry.get("axis", "planar", checked=False)(markers)
    np.testing.assert_array_equal(result.direction, bare.direction)


# A misfit that leaves an answer unsupported by its cost.
UNSUPPORTED = {"ratio": 4.0, "p_value": 1e-9, "tilt_scale_deg": 25.0}


def planar_answer(direction: np.ndarray) -> AxisResult:
    """An ``ok`` planar answer along ``direction`` (3,) with no diagnostics."""
    return AxisResult(
        point=np.zeros(3),
        direction=direction,
        radii=np.ones(3),
        converged=True,
        iterations=1,
        status="ok",
        method="planar",
        cost=1.0,
        diagnostics={},
    )


def test_only_an_answer_its_cost_cannot_vouch_for_is_held_to_the_narrow_band():
    """A newcomer's method states no misfit: the 30 degree band holds for it."""
    reference = support.MotionAxis(Z, 0.5, 0.01, 0.1, 0.1)
    tilted = np.array([np.sin(np.radians(12.0)), 0.0, np.cos(np.radians(12.0))])
    answer = planar_answer(tilted)
    assert precision.annotate_motion_axis(answer, reference).status == "ok"
    supported = {**UNSUPPORTED, "tilt_scale_deg": 9.0}
    for misfit, warned in ((UNSUPPORTED, True), (supported, False)):
        noted = with_warnings(answer, (), {"axis_misfit": misfit})
        status = precision.annotate_motion_axis(noted, reference).status
        assert (MISFIT in status) is warned, status


def test_an_answer_nothing_checks_says_so():
    """Its cost cannot vouch for it and the principal axis is not determined (the noise's
    share of the rotations' scatter reaches its eigen-gap): paper B's MCP, FE 10 degrees, AA 0.5
    times it, has planar answers 80 degrees off with SDs of 3."""
    undetermined = support.MotionAxis(Z, 12.0, 1.5, 0.1, 0.1)
    answer = planar_answer(Z)
    noted = with_warnings(answer, (), {"axis_misfit": UNSUPPORTED})
    status = precision.annotate_motion_axis(noted, undetermined).status
    assert status.startswith("warning: axis not determined: the markers leave the planar cost's")
    assert status.endswith(
        "the principal axis of the segment's rotations is not determined: the noise's share of "
        "their scatter is 1.5 of its eigen-gap (not below 1), so nothing checks the answer"
    )
    assert precision.annotate_motion_axis(answer, undetermined).status == "ok"


@pytest.mark.parametrize("method", LEAST_SQUARES)
def test_pure_hinges_fit_their_model_at_the_tests_level(method):
    """Arcs of 10 to 90 degrees, 0.3 and 1 mm, 5, 120 and 2,000 frames: at the level of 0.001,
    one rejection in 180 trials is already unlikely (p = 0.16)."""
    trials = [
        hinge(seed, arc, noise=noise, n_frames=n_frames)
        for seed in range(5)
        for arc in (10.0, 30.0, 90.0)
        for noise in (0.3, 1.0)
        for n_frames in (5, 120, 2000)
    ]
    rejected = 0
    for markers in trials:
        result = registry.get("axis", method)(markers)
        misfit = result.diagnostics["axis_misfit"]
        # Not checked where the cost does not rise in every direction (the radial cost on a
        # short arc): its SD is then said to be unbounded.
        assert "p_value" in misfit or "axis not determined by" in result.status
        rejected += misfit.get("p_value", 1.0) < support.ROTATION_ALPHA
        assert MISFIT not in result.status
        assert not precision.unsupported_by_its_cost(misfit)
    assert rejected <= 1


def test_few_frames_are_not_taken_for_misfit():
    """Four frames of a 30 degree hinge, 200 draws: the F distribution's tail, which a normal
    approximation to the ratio understates over so few degrees of freedom."""
    rejected = sum(
        registry.get("axis", "planar")(hinge(seed, 30.0, noise=0.5, n_frames=4)).diagnostics[
            "axis_misfit"
        ]["p_value"]
        < support.ROTATION_ALPHA
        for seed in range(200)
    )
    assert rejected <= 1


def test_heavy_tailed_noise_is_not_taken_for_misfit():
    """Student's t on 5 degrees of freedom (excess kurtosis 6), as the noise's kurtosis in the
    test's spread allows."""
    rejected = 0
    for seed in range(40):
        clean = hinge(seed, 30.0, noise=0.0)
        noise = np.random.default_rng(100 + seed).standard_t(5, size=clean.shape) * 0.4
        result = registry.get("axis", "planar")(clean + noise)
        rejected += result.diagnostics["axis_misfit"]["p_value"] < support.ROTATION_ALPHA
    assert rejected <= 1


def test_paper_b_near_hinges_answers_near_the_axis_keep_the_wide_band():
    """Paper B's knee and MCP: FE over 30 and 60 degrees with AA 0.1 times FE, 1 mm, as the
    hinge study simulates it. The markers leave a fixed axis, by enough to tilt a planar or
    combined answer far; their answers stay within a few degrees of the true axis (x) and of
    the principal axis, and are not warned about. None more than 10 degrees off reads ok."""
    narrowed = 0
    for protocol, rom, method in itertools.product(("knee", "mcp"), (30.0, 60.0), LEAST_SQUARES):
        for result in registry.many("axis", method)(paper_b_trials(protocol, rom, 0.1, 10)):
            error = angle_between_lines_deg(np.asarray(result.direction), [1.0, 0.0, 0.0])
            assert result.status != "ok" or error <= 10.0
            narrowed += error <= 5.0 and MISFIT in result.status
    assert narrowed <= 1  # of 120 answers


def test_noise_free_data_misfit_only_when_the_motion_leaves_the_model():
    exact = registry.get("axis", "planar")(hinge(0, 30.0, noise=0.0))
    assert not precision.unsupported_by_its_cost(exact.diagnostics["axis_misfit"])
    wobble = registry.get("axis", "planar")(wobbling_hinge(0, 0.2, noise=0.0))
    assert precision.unsupported_by_its_cost(wobble.diagnostics["axis_misfit"])


@pytest.mark.parametrize("method", LEAST_SQUARES)
def test_the_misfit_does_not_depend_on_the_frame_or_the_order(method):
    """At one axis carried with the data: the methods' answers are searches, which move within
    their tolerances."""
    markers = wobbling_hinge(5, 0.05)
    point, direction = np.array([0.0, 0.0, 3.0]), np.array([0.05, 0.02, 1.0]) / 1.0015
    turn = rotation_matrix(np.array([0.3, -0.2, 0.5]))
    shift = np.array([120.0, -40.0, 800.0])
    moves = {
        "moved": (markers @ turn.T + shift, turn @ point + shift, turn @ direction),
        "markers reordered": (markers[:, ::-1], point, direction),
        "frames reversed": (markers[::-1], point, direction),
    }

    def found(data, at, along):
        at_axis = axis._cost_at(data, at, along / np.linalg.norm(along), method)
        return precision.misfit(at_axis, 0.25, precision.rigid_dof(4, 60))

    reference = found(markers, point, direction)
    assert reference.ratio > 1.0
    for name, (moved, at, along) in moves.items():
        np.testing.assert_allclose(found(moved, at, along), reference, rtol=1e-9, err_msg=name)
