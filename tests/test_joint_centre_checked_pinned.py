"""Checked joint-centre calls, pinned on a corpus of hips.

``tests/snapshots/joint_centre_checked.json`` holds, for every case below and every
registered joint-centre method, what the checked one-trial call
(:func:`jointbench.estimators.registry.get`) answered when it was written: each trial's error,
or its centre, covariance, ``converged``, ``iterations``, status (with its warnings), cost and
diagnostics. A trial's answer does not depend on the others of a call, so the checked
many-trial call (:func:`jointbench.estimators.registry.many`) is held to the same pin. A
faster implementation must answer the same: the same errors, statuses and
warnings word for word (their numbers printed to four digits, so to rounding, and compared
relative to their size however small), the same numbers to 1e-9 (relative where large) or, for
a number that rounding alone moves by more, to ten times what rounding moved it when the pin
was written: its largest change under three perturbations of the markers by one unit in the
last place (``rounding`` in the file). Those are the numbers of ill-conditioned fits (a hinge
all but for 1e-6 rad, whose covariance rounding moves by 1e-5) and the chi^2 of noise-free
data, rounding over rounding; no implementation that orders one sum differently answers them
closer.

Cases: paper C's hip protocol at Nt = 4, 20, 200 and 1200 frames, noisy, noise-free and with
an exact frame 0, with a cluster that slides with the hip angles and with a noisy pelvis
beside a clean thigh; the two-segment rig noise-free, as a hinge (degenerate motion) and
nearly one; the noise given, given as 0, and too few iterations to converge.
``python tests/test_joint_centre_checked_pinned.py --rewrite`` rewrites the file, for a
deliberate change of the answers only.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from pinning import (
    all_answers,
    assert_case_as_pinned,
    assert_changed_number_fails,
    checked_calls,
    one_trial,
    rounding_moves,
)
from rigs import two_segments

from jointbench.configuration.studies import get_study
from jointbench.simulate.hip import HipProtocol, nominal_recording

PINNED = Path(__file__).parent / "snapshots" / "joint_centre_checked.json"
METHODS = ("SCoRE", "analytic", "gauss-markov", "gauss-markov-frame0")
HIP = get_study("hip")


def _hip(n_frames: int, n_trials: int, **protocol) -> tuple[np.ndarray, np.ndarray]:
    """``n_trials`` noisy hips of paper C's protocol, the first ``n_frames`` frames:
    ``(n_trials, n_frames, 3, 3)`` [mm] each."""
    rngs = [np.random.default_rng(seed) for seed in range(n_trials)]
    trials = HIP.simulate({"n_frames": n_frames}, HIP.protocol(protocol), rngs)
    return trials.segments["proximal"], trials.segments["distal"]


def _sliding_thigh(n_frames: int) -> tuple[np.ndarray, np.ndarray]:
    """A hip whose thigh markers slide along the thigh with the swing (skin), 1 mm noise."""
    proximal, distal = nominal_recording(HipProtocol(n_frames=n_frames))
    swing = np.linspace(0.0, 1.0, n_frames) ** 2
    distal = distal + 15.0 * swing[:, None, None] * np.array([0.2, 0.3, -0.9])
    rng = np.random.default_rng(7)
    noise = rng.normal(scale=1.0 / math.sqrt(3.0), size=(2, *proximal.shape))
    return (proximal + noise[0])[None], (distal + noise[1])[None]


def _noisy_pelvis(n_frames: int) -> tuple[np.ndarray, np.ndarray]:
    """A hip with 4 mm noise on the pelvis and 0.3 mm on the thigh."""
    proximal, distal = nominal_recording(HipProtocol(n_frames=n_frames))
    rng = np.random.default_rng(11)
    proximal = proximal + rng.normal(scale=4.0 / math.sqrt(3.0), size=proximal.shape)
    distal = distal + rng.normal(scale=0.3 / math.sqrt(3.0), size=distal.shape)
    return proximal[None], distal[None]


def _rig(relative: str, n_frames: int, noise_mm: float = 0.0, off_axis: float = 0.0):
    """The two-segment rig (``tests/rigs.py``), its distal markers turned ``off_axis`` [rad]
    further about an axis across the hinge, with noise of ``noise_mm`` RMS."""
    proximal, distal = two_segments(n_frames, relative=relative)
    if off_axis:
        _, ball = two_segments(n_frames, relative="ball")
        distal = distal + off_axis * (ball - distal)
    rng = np.random.default_rng(3)
    scale = noise_mm / math.sqrt(3.0)
    return (
        (proximal + rng.normal(scale=scale, size=proximal.shape))[None],
        (distal + rng.normal(scale=scale, size=distal.shape))[None],
    )


def _cases() -> dict[str, tuple[tuple[np.ndarray, np.ndarray], dict]]:
    """Name -> (the trials' proximal and distal markers ``(T, N, n, 3)``, the options)."""
    return {
        "hip Nt=4": (_hip(4, 3), {}),
        "hip Nt=20": (_hip(20, 3), {}),
        "hip Nt=200": (_hip(200, 2), {}),
        "hip Nt=1200": (_hip(1200, 1), {}),
        "hip Nt=200 noise given": (_hip(200, 2), {"noise_mm": 1.7}),
        "hip Nt=200 noise given as 0": (_hip(200, 1), {"noise_mm": 0.0}),
        "hip Nt=200 one iteration": (_hip(200, 2), {"max_iterations": 1}),
        "hip Nt=20 two iterations": (_hip(20, 2), {"max_iterations": 2}),
        "hip Nt=200 noise-free": (_hip(200, 1, noise_mm=0.0), {}),
        "hip Nt=200 exact frame 0": (_hip(200, 2, noise_free_frame0=True), {}),
        "hip Nt=300 sliding thigh": (_sliding_thigh(300), {}),
        "hip Nt=300 noisy pelvis": (_noisy_pelvis(300), {}),
        "rig ball noise-free": (_rig("ball", 60), {}),
        "rig ball Nt=4": (_rig("ball", 4, noise_mm=0.5), {}),
        "rig hinge": (_rig("hinge", 60, noise_mm=0.5), {}),
        "rig hinge noise-free": (_rig("hinge", 60), {}),
        "rig nearer hinge noise-free": (_rig("hinge", 60, off_axis=4e-6), {}),
        "rig near hinge": (_rig("hinge", 60, noise_mm=0.5, off_axis=1e-3), {}),
        "rig near hinge noise-free": (_rig("hinge", 60, off_axis=1e-5), {}),
    }


def _options_for(method: str, options: dict) -> dict:
    """The case's options that ``method`` takes (the iteration's only the Gauss–Markov fits)."""
    if method.startswith("gauss-markov"):
        return options
    return {key: value for key, value in options.items() if key == "noise_mm"}


#: What the pin holds of a trial's outcome beside its diagnostics.
FIELDS = ("center", "covariance", "converged", "iterations", "status", "cost", "method")


def _called(method: str, markers: tuple[np.ndarray, np.ndarray], options: dict) -> dict:
    """Every trial of a case, one at a time and in one many-trial call, checked, with the
    case's options ``method`` takes."""
    return checked_calls("joint_center", method, markers, _options_for(method, options), FIELDS)


@pytest.fixture(scope="module")
def answers() -> dict:
    return all_answers(_cases(), METHODS, _called)


@pytest.fixture(scope="module")
def pinned() -> dict:
    return json.loads(PINNED.read_text())


@pytest.mark.parametrize("case", list(_cases()))
def test_checked_joint_centre_calls_answer_as_pinned(answers, pinned, case):
    assert_case_as_pinned(answers, pinned, case)


#: The cases whose fits are ill-conditioned (four frames, a hinge or nearly one) or whose
#: chi^2 is rounding over rounding (noise-free): the only ones rounding may move by more than
#: :data:`pinning.AGREE`.
ROUNDING_BOUND = (
    "hip Nt=4",
    "hip Nt=200 noise-free",
    "rig ball noise-free",
    "rig hinge",
    "rig near hinge",
    "rig near hinge noise-free",
    "rig nearer hinge noise-free",
)


def test_rounding_moves_only_the_ill_conditioned_beyond_the_agreement(pinned):
    """The allowance for rounding is the exception, never a well-conditioned answer's."""
    assert pinned["rounding"]
    for where in pinned["rounding"]:
        assert where.split("/")[1] in ROUNDING_BOUND, where


def test_the_pin_covers_every_kind_of_answer():
    """The corpus is not all one outcome: it holds errors, unconverged fits, model-test
    rejections and untested fixed centres, each of which the pin must see."""
    text = json.dumps(json.loads(PINNED.read_text())["answers"])
    for words in (
        "degenerate motion",
        "single axis",
        "did not converge",
        "does not fit the data",
        "not_tested",
        "noise_mm = 0 was given",
    ):
        assert words in text, words


def test_a_changed_number_fails_the_comparison(pinned):
    held = pinned["answers"]["hip Nt=200"]["gauss-markov"]["one"][0]
    assert_changed_number_fails(held, ("center", 0), pinned["rounding"])


if __name__ == "__main__" and sys.argv[1:] == ["--rewrite"]:
    written = one_trial(all_answers(_cases(), METHODS, _called))
    moved = rounding_moves(written, _cases(), METHODS, _called)
    pin = {"answers": written, "rounding": moved}
    PINNED.write_text(json.dumps(pin, indent=1, sort_keys=True) + "\n")
