"""An SD whose result's status says its precision is not determined is no precision: every
producer of that warning says it in one phrase
(:data:`jointbench.estimators.results.PRECISION_NOT_DETERMINED`), and
:meth:`jointbench.RecordingFit.stated_sd` reads it, whatever the SD's size."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from test_axis_sd_validity import Z, swing
from test_centre_precision import _far_swing
from test_gauss_markov_fit import _skin_thigh
from test_pose_noise import _PULLED, _hip, _noisy
from test_user_recordings import KNEE, KNEE_LEG, KNEE_THIGH

import jointbench
from jointbench.estimators import precision, registry, results, support
from jointbench.estimators.centre_precision import (
    MAX_CENTER_SD_MM,
    MAX_POSE_NOISE_PULL_MM,
    MAX_STEP_SDS,
)
from jointbench.estimators.registry import KINDS
from jointbench.geometry import angle_between_lines_deg, rotation_about_axis
from jointbench.io import read
from jointbench.io.fit import NOT_DETERMINED, SD_NAMES, RecordingFit

SOURCE = Path(jointbench.__file__).resolve().parent


def planar_ok():
    """A planar axis on a 60 deg swing: ``ok``, its SD well under the bound."""
    result = jointbench.fit_axis(swing(0, 60.0), "planar")
    assert result.status == "ok"
    assert result.diagnostics["axis_sd_deg"] < precision.MAX_AXIS_SD_DEG
    return result


def stated_sd(result) -> float | str | None:
    frames = np.arange(50)
    return RecordingFit("axis", result.method, result, None, frames, 0).stated_sd()


def eigen_gap_within_the_noise(result):
    return precision.annotate_validity(result, 3.0, 2.0, "the planar cost's scatter")


def anisotropic_pull(result):
    return precision.annotate_validity(result, 1.0, 2.0, "SARA's normal matrix", bias_deg=50.0)


def no_marker_reads_the_rotation(result):
    arcs = np.array([6.0, 7.0, 8.0, 9.0])  # every lever reads it to more than 5 deg a frame
    reference = support.MotionAxis(result.direction, 1.0, 0.1, 1.0, arcs)
    return precision.annotate_motion_axis(result, reference)


def too_few_first_order_markers(result):
    first_order = np.array([True, False, False, False])
    return precision.annotate_first_order(result, 20.0, first_order)


def frames_not_independent(result):
    """The support verdict's caveat as the real knee trial reads it: 922 frames, about 22 of
    them independent."""
    frames = support._Frames(0.98, 35.0, 64.0, 20.0, 922, "markers", 22.0)
    assert frames.dependent()  # the case
    return support.annotate(result, support.Support((), {}, caveats=frames.caveats()))


@pytest.mark.parametrize(
    "warn",
    [
        eigen_gap_within_the_noise,
        anisotropic_pull,
        no_marker_reads_the_rotation,
        too_few_first_order_markers,
        frames_not_independent,
    ],
)
def test_a_status_saying_the_precision_is_not_determined_states_no_sd(warn):
    result = planar_ok()
    assert isinstance(stated_sd(result), float)
    warned = warn(result)
    assert results.PRECISION_NOT_DETERMINED in warned.status  # the case
    assert not results.states_precision(warned)
    assert stated_sd(warned) == NOT_DETERMINED
    assert results.stated_sd(warned) is None


def test_a_status_saying_nothing_of_the_precision_keeps_the_sd():
    result = planar_ok()
    assert results.states_precision(result)
    assert stated_sd(result) == result.diagnostics["axis_sd_deg"]
    # Another warning (the answer's cost against another's) leaves the SD as it is.
    crossed = precision.annotate_agreement(result, result.direction, 1.0, "a", "b")
    assert stated_sd(crossed) == result.diagnostics["axis_sd_deg"]


def test_every_kind_names_its_sd():
    assert SD_NAMES.keys() == set(KINDS)


def test_every_producer_of_the_warning_says_it_in_the_one_phrase():
    """The reader recognises a status by :data:`~results.PRECISION_NOT_DETERMINED`: a warning
    typing the words itself would pass unrecognised the day they drift apart."""
    phrase = results.PRECISION_NOT_DETERMINED
    typed = [
        path.relative_to(SOURCE)
        for path in SOURCE.rglob("*.py")
        if path != Path(results.__file__).resolve() and phrase in path.read_text()
    ]
    assert typed == []
    # The producers this names read the constant (their wording is kept to the letter).
    producers = ("precision.py", "centre_precision.py", "hjc.py", "support.py")
    for module in (f"estimators/{name}" for name in producers):
        assert "PRECISION_NOT_DETERMINED" in (SOURCE / module).read_text()


def joint_centre_sd(result) -> float | str | None:
    frames = np.arange(60)
    return RecordingFit("joint_center", result.method, result, None, frames, 0).stated_sd()


@pytest.mark.parametrize("method", ["SCoRE", "gauss-markov-frame0"])
def test_a_joint_centre_the_poses_noise_pulled_states_no_sd(method):
    """Nearly a hinge, 0.5 mm noise: the noise in the poses pulls the answer tens of
    millimetres towards the markers, a bias its SD of a few millimetres (the scatter's) does
    not contain, so that SD is no statement of the answer's precision."""
    result = jointbench.fit_joint_center(*_noisy(_hip(0, ratio=0.06), 100), method=method)
    assert _PULLED in result.status  # the case
    assert result.diagnostics["center_pose_noise_pull_mm"] > MAX_POSE_NOISE_PULL_MM
    assert result.diagnostics["center_sd_mm"] < MAX_CENTER_SD_MM
    assert joint_centre_sd(result) == NOT_DETERMINED


def _states_no_sd(result, method: str) -> None:
    """``result``, a joint centre of ``method`` on 60 frames whose SD is within its bound,
    states none: not in the table, the array API, the summary's flag nor its covariances."""
    assert result.diagnostics["center_sd_mm"] < MAX_CENTER_SD_MM
    assert joint_centre_sd(result) == NOT_DETERMINED
    assert results.stated_sd(result) is None
    summary = RecordingFit("joint_center", method, result, None, np.arange(60), 0).to_dict()
    assert summary["sd_stated"] is False
    assert summary["center_covariance_mm2"] is None
    assert summary.get("covariance_mm2") is None


@pytest.mark.parametrize("method", ["SCoRE", "analytic", "gauss-markov", "gauss-markov-frame0"])
def test_a_joint_centre_whose_model_the_data_reject_states_no_sd(method):
    """A thigh cluster sliding with the hip angles: the fixed-centre model's test rejects
    (gauss-markov-frame0's own, and its fit to the same poses for the others, whose SDs assume
    that model), and the status says the SD does not describe the answer's error; it is no
    precision, nor is the covariance it is read from."""
    result = jointbench.fit_joint_center(*_skin_thigh(0)[:2], method=method)
    assert "the Gauss–Markov model does not fit the data" in result.status  # the case
    _states_no_sd(result, method)


def test_a_zero_noise_given_states_no_sd():
    """``noise_mm=0`` given to paper C's fit on noisy data: a zero covariance, which its status
    says does not describe the error, is no precision of 0 mm."""
    result = jointbench.fit_joint_center(*_skin_thigh(0)[:2], method="gauss-markov", noise_mm=0.0)
    assert "noise_mm = 0 was given" in result.status  # the case
    assert result.diagnostics["center_sd_mm"] == 0.0
    assert joint_centre_sd(result) == NOT_DETERMINED
    # Its own test and the frame-0 extension's it is held to, at the same noise, say it once.
    assert result.status.count("noise_mm = 0 was given") == 1


@pytest.mark.parametrize("method", ["SCoRE", "gauss-markov-frame0"])
def test_a_joint_centre_whose_data_the_verdict_refuses_states_no_sd(method):
    """A noisy pure hinge: the support verdict says the centre is not determined along the
    hinge's axis, so the SD the method computes (a few millimetres, from a covariance that
    takes the centre as determined) is no statement of its precision."""
    result = jointbench.fit_joint_center(*_noisy(_hip(1, ratio=0.0), 3), method=method)
    assert "the centre is not determined along it" in result.status  # the case
    assert result.diagnostics["center_sd_mm"] < MAX_CENTER_SD_MM
    assert joint_centre_sd(result) == NOT_DETERMINED


def test_a_centre_whose_data_the_verdict_refuses_states_no_sd():
    """One segment held still: the verdict refuses a centre (no rotation), whatever SD the
    method's precision step would give."""
    result = jointbench.fit_axis(swing(0, 60.0), "planar")
    refused = support.annotate(result, support.Support(("range of motion too small",), {}))
    assert stated_sd(refused) == NOT_DETERMINED
    caveat = support.annotate(result, support.Support((), {}, caveats=("frames not independent",)))
    # A caveat is no refusal: one that says nothing of the precision leaves the SD.
    assert stated_sd(caveat) == result.diagnostics["axis_sd_deg"]


def test_an_answer_off_the_spheres_centre_states_no_sd():
    """The LS sphere fit with its markers 500 mm out on a 10 degree swing: the answer lies
    several of its SDs from the spheres' centre, whose scatter its SD states; the answer's
    error is that scatter and the step, so its SD is no precision."""
    rng = np.random.default_rng(1)
    result = registry.get("center", "LS")(_far_swing(rng))
    assert "the answer is not the markers' common centre of rotation" in result.status  # the case
    assert result.diagnostics["center_step_sds"] >= MAX_STEP_SDS
    assert result.diagnostics["center_sd_mm"] < MAX_CENTER_SD_MM
    frames = np.arange(120)
    assert RecordingFit("center", "LS", result, None, frames, 0).stated_sd() == NOT_DETERMINED
    assert results.stated_sd(result) is None


def test_the_array_api_reads_the_sd_as_a_recording_fit_does():
    """:func:`results.stated_sd` is the rule :meth:`RecordingFit.stated_sd` prints: the SD where
    it is stated, ``None`` where the method states none or where it states no precision."""
    kept = planar_ok()
    cases = [kept, eigen_gap_within_the_noise(kept), frames_not_independent(kept)]
    for result in cases:
        printed = stated_sd(result)
        assert results.stated_sd(result) == (printed if isinstance(printed, float) else None)
    assert results.stated_sd(kept) == kept.diagnostics["axis_sd_deg"]
    silent = results.with_fields(kept, diagnostics={})
    assert stated_sd(silent) is None and results.stated_sd(silent) is None
    wide = results.with_fields(kept, diagnostics={"axis_sd_deg": 2 * precision.MAX_AXIS_SD_DEG})
    assert stated_sd(wide) == NOT_DETERMINED and results.stated_sd(wide) is None


@pytest.mark.parametrize("method", ["planar", "radial", "combined", "SARA"])
def test_the_real_knee_trials_axes_state_no_sd(method):
    """The shipped knee trial: every axis reads the caveat that its 922 frames hold about 22
    independent ones, so the SD that counts all 922 is no statement of the answer's error (an
    SD of a regression on the smooth flexion is not a mean's, and no factor of the frames
    corrects it): "not determined", in the table and the CSV alike."""
    fitted = jointbench.fit(read(KNEE), "axis", KNEE_LEG, KNEE_THIGH, method=method)
    assert "the frames are not independent" in fitted.result.status  # the case
    assert fitted.result.diagnostics["axis_sd_deg"] < precision.MAX_AXIS_SD_DEG
    assert fitted.stated_sd() == NOT_DETERMINED
    assert fitted.sd_fields() == {"sd_deg": None, "sd_stated": False}


def _ar1_hinge(rng: np.random.Generator, cycles: int, correlation: float) -> np.ndarray:
    """:func:`swing`'s four markers flexed to 60 degrees and back ``cycles`` times over 240
    frames, under noise of 0.5 mm that keeps ``correlation`` of itself from frame to frame
    (AR(1), stationary): ``(240, 4, 3)`` [mm]; the true axis is z."""
    local = rng.normal(size=(4, 3)) * 30.0 + np.array([100.0, 0.0, 0.0])
    t = np.linspace(0.0, 1.0, 240)
    angles = np.radians(30.0) * (1.0 - np.cos(2.0 * np.pi * cycles * t))
    markers = np.einsum("fij,mj->fmi", rotation_about_axis(Z, angles), local)
    shocks = rng.normal(scale=0.5 * np.sqrt(1.0 - correlation**2), size=markers.shape)
    noise = np.empty_like(markers)
    noise[0] = shocks[0] / np.sqrt(1.0 - correlation**2)
    for k in range(1, len(noise)):
        noise[k] = correlation * noise[k - 1] + shocks[k]
    return markers + noise


def _error_over_inflated_sd(cycles: int) -> float:
    """Over 100 seeds of :func:`_ar1_hinge` (0.97 kept), the planar axes' RMS angle error over
    their RMS SD inflated by ``sqrt(N / N_independent)``, the caveat's own count: 1 where that
    factor corrects the SD."""
    rng = np.random.default_rng(cycles)
    trials = np.stack([_ar1_hinge(rng, cycles, 0.97) for _ in range(100)])
    errors, inflated = [], []
    for result in registry.many("axis", "planar")(trials):
        assert "the frames are not independent" in result.status  # the case
        independent = result.diagnostics["support_independent_frames"]
        errors.append(angle_between_lines_deg(result.direction, Z))
        inflated.append(result.diagnostics["axis_sd_deg"] * np.sqrt(240 / independent))
    return float(np.sqrt(np.mean(np.square(errors)) / np.mean(np.square(inflated))))


def test_no_factor_of_the_independent_frames_corrects_an_axis_sd():
    """Why the caveat states no SD rather than one inflated by ``sqrt(N / N_independent)``: that
    is a mean's factor, and an axis is fitted to the motion's course. The same correlated noise
    (0.97 kept from frame to frame) on a swing made once is about that factor short of its
    error, and on one made eight times, whose regressors vary within the noise's correlation
    time, several times over it."""
    slow, fast = _error_over_inflated_sd(1), _error_over_inflated_sd(8)
    assert 0.8 < slow < 1.3
    assert fast < 0.5


def test_paper_cs_sd_stands_where_only_its_exact_frame0_poses_are_rejected():
    """A hip whose centre is fixed in both segments, the pelvis moving: paper C's own test
    rejects its exact frame-0 poses in most trials, which says its ``W_c`` leaves their
    errors out; the SD it states adds them (the frame-0 extension's model), which the data do
    not reject, so that SD stands and the answer is not warned of the model. Where the thigh
    cluster slides (:func:`test_a_joint_centre_whose_model_the_data_reject_states_no_sd`) it
    does not; nor where the noise in the poses pulls the answer by more than the SD holds
    beside it (two trials here, pulled 2.1 and 4.3 mm with SDs of 3.4 and 3.2 mm), which is not
    this case."""
    own_rejections = model_warned = stated = pulled = 0
    for seed in range(40):
        proximal, distal, _ = _skin_thigh(seed, mm_per_rad=0.0)
        result = jointbench.fit_joint_center(proximal, distal, method="gauss-markov")
        own_rejections += result.diagnostics["chi2_p"] < support.ROTATION_ALPHA
        # Only where the frame-0 extension's test is not made does paper C's own warn (one
        # trial here, whose segments' rigid-body noise differs at p = 8e-5).
        model_warned += "the Gauss–Markov model does not fit the data" in result.status
        stated += results.stated_sd(result) is not None
        pulled += "the noise in the poses pulls" in result.status
    assert own_rejections >= 10  # the case
    assert model_warned <= 2
    assert pulled <= 3
    assert stated + pulled >= 39


@pytest.mark.parametrize("method", ["gauss-markov", "gauss-markov-frame0"])
def test_a_fit_that_did_not_converge_states_no_sd(method):
    """A Gauss–Markov fit stopped after one iteration, its centre still moving: the covariance
    at that iterate is no statement of the answer's error, however small its SD, and the
    covariances it is read from are no more."""
    proximal, distal, _ = _skin_thigh(0, mm_per_rad=0.0)
    result = jointbench.fit_joint_center(proximal, distal, method=method, max_iterations=1)
    assert not result.converged and "did not converge" in result.status  # the case
    _states_no_sd(result, method)


def test_paper_cs_sd_from_a_noise_given_too_small_is_held_to_that_noise():
    """Paper C's fit given a marker noise several times smaller than the data's: its SD, read
    from that noise, is several times smaller than its error, and paper C's own test (of exact
    frame-0 poses, which leaves the SD standing) rejects as it does on most long trials. The
    frame-0 extension's test it is held to must be of the same noise, whose rejection says the
    SD is no precision, as it says for ``gauss-markov-frame0`` given that noise."""
    proximal, distal, _ = _skin_thigh(0, mm_per_rad=0.0)
    estimated = jointbench.fit_joint_center(proximal, distal, method="gauss-markov")
    assert results.stated_sd(estimated) is not None  # the case: with the data's noise it holds
    small = estimated.diagnostics["noise_mm"] / 5.0
    frame0 = jointbench.fit_joint_center(
        proximal, distal, method="gauss-markov-frame0", noise_mm=small
    )
    assert results.stated_sd(frame0) is None  # the case: that noise is rejected
    result = jointbench.fit_joint_center(proximal, distal, method="gauss-markov", noise_mm=small)
    assert result.diagnostics["center_sd_mm"] < estimated.diagnostics["center_sd_mm"] / 3.0
    assert result.diagnostics["fixed_centre_test"]["chi2_p"] < support.ROTATION_ALPHA
    assert results.stated_sd(result) is None


@pytest.mark.parametrize("sd", [-1.0, -0.0001, -math.inf])
def test_a_negative_sd_states_no_precision(sd):
    """An SD below zero (an extension's sign error, a variance's root taken of a negative
    number by other means) is no spread of anything: no output prints it as a number."""
    assert results.stated_center_sd(sd) is None
    assert results.stated_axis_sd(sd) is None
