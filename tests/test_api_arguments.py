"""The public calls refuse a bad argument of their own, naming it, before any fit.

The bootstrap's ``n_bootstrap``, ``block_length`` and ``seed``, a recording's ``method``,
``frames`` and ``rules``, :func:`jointbench.screen`'s arrays and rules and a bootstrap
interval's ``level`` are the caller's: a value that is not what they must be is a
``ValueError`` naming the argument, not truncated, coerced, replaced by a default or blamed on
the estimator as a :class:`~jointbench.estimators.batching.ProgrammingError`. A marker array
that looks transposed (more markers than frames) is refused or flagged saying that it must be
``(frames, markers, 3)``.
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest
from rigs import two_segments
from test_bootstrap import hip_trial
from test_cli import SHANK, THIGH, run, sphere_markers
from test_io_recordings import KNEE

import jointbench as jb
from jointbench import api
from jointbench.estimators import registry
from jointbench.geometry import rotation_matrix
from jointbench.io.fit import Prepared
from jointbench.io.segments import ArtefactRules
from jointbench.uncertainty import Bootstrap, bootstrap

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def no_fit(monkeypatch):
    """Fail the test if a recording's estimator is called: the refusal must come first."""

    def solve(*_args, **_kwargs):
        raise AssertionError("the estimator ran before the argument was refused")

    monkeypatch.setattr(Prepared, "solve", solve)


@pytest.fixture(scope="module")
def hip():
    recording, _ = hip_trial(0, 120)
    return recording


def _fit(recording, **arguments):
    return jb.fit(recording, "center", "D1,D2,D3", "P1,P2,P3", **arguments)


BAD_BOOTSTRAP = {
    "a negative seed": ({"n_bootstrap": 5, "seed": -1}, "seed"),
    "a text seed": ({"n_bootstrap": 5, "seed": "abc"}, "seed"),
    "a fractional seed": ({"n_bootstrap": 5, "seed": 1.5}, "seed"),
    "a flag for a seed": ({"n_bootstrap": 5, "seed": True}, "seed"),
    "a seed without resamples": ({"seed": -1}, "seed"),
    "fractional resamples": ({"n_bootstrap": 2.9}, "n_bootstrap"),
    "text resamples": ({"n_bootstrap": "20"}, "n_bootstrap"),
    "a flag for resamples": ({"n_bootstrap": True}, "n_bootstrap"),
    "negative resamples": ({"n_bootstrap": -3}, "n_bootstrap"),
    "one resample": ({"n_bootstrap": 1}, "n_bootstrap"),
    "a fractional block": ({"n_bootstrap": 3, "block_length": 2.9}, "block_length"),
    "a flag for a block": ({"n_bootstrap": 3, "block_length": True}, "block_length"),
    "no block": ({"n_bootstrap": 3, "block_length": 0}, "block_length"),
    "a block longer than the frames": ({"n_bootstrap": 3, "block_length": 121}, "block_length"),
}


@pytest.mark.parametrize("case", BAD_BOOTSTRAP)
def test_a_bad_bootstrap_argument_is_named_before_the_fit(hip, no_fit, case):
    arguments, name = BAD_BOOTSTRAP[case]
    with pytest.raises(ValueError, match=rf"\b{name}: must be") as raised:
        _fit(hip, **arguments)
    assert "programming error" not in str(raised.value)


def test_the_knee_with_a_negative_seed_is_the_callers_mistake():
    knee = jb.read(KNEE)
    with pytest.raises(ValueError, match=r"seed: must be an integer >= 0, got -1"):
        jb.fit(knee, "axis", SHANK, THIGH, n_bootstrap=5, seed=-1)


def test_good_bootstrap_arguments_still_fit(hip):
    fitted = _fit(hip, method="LS", n_bootstrap=np.int64(4), block_length=np.int32(10), seed=7)
    assert fitted.bootstrap.block_length == 10 and len(fitted.bootstrap.samples) == 4
    again = _fit(hip, method="LS", n_bootstrap=4, block_length=10, seed=np.uint8(7))
    np.testing.assert_array_equal(fitted.bootstrap.samples, again.bootstrap.samples)


@pytest.mark.parametrize(
    ("arguments", "name"),
    [({"n_resamples": 2.9}, "n_resamples"), ({"n_resamples": 5, "seed": -1}, "seed")],
)
def test_bootstrap_refuses_its_arguments_before_it_refits(arguments, name):
    refitted = []

    def statistic(resamples):
        refitted.append(len(resamples))
        return [np.array([rows.mean()]) for rows in resamples]

    with pytest.raises(ValueError, match=rf"\b{name}: must be"):
        bootstrap(statistic, 50, label="a mean", **arguments)
    assert not refitted


@pytest.mark.parametrize("method", ["all", "LS"])
def test_cli_names_a_negative_seed_in_one_line(capsys, method):
    code, _, err = run(
        capsys, "fit", str(KNEE), "--kind", "center", "--reference", THIGH, "--moving", SHANK,
        "--method", method, "--bootstrap", "5", "--seed", "-1",
    )  # fmt: skip
    assert code == 2
    assert err.strip().splitlines() == ["jointbench: --seed: must be an integer >= 0, got -1"]


def test_cli_names_a_single_resample(capsys):
    code, _, err = run(capsys, "fit", str(KNEE), "--bootstrap", "1")
    assert code == 2 and "--bootstrap: must be 0 (none) or an integer >= 2, got 1" in err


def test_an_empty_method_name_is_not_the_default(hip, no_fit):
    with pytest.raises(ValueError, match="unknown center method ''"):
        _fit(hip, method="")


@pytest.mark.parametrize("frames", [(100, 200), [0, 50], 50, slice(1.5, 40)])
def test_frames_other_than_the_documented_ones_are_named(hip, no_fit, frames):
    with pytest.raises(ValueError, match=r"frames must be"):
        _fit(hip, frames=frames)


def test_the_documented_frames_still_fit(hip):
    assert len(_fit(hip, method="LS", frames=slice(10, 90)).frames_used) == 80
    assert len(_fit(hip, method="LS", frames="10:90").frames_used) == 80


@pytest.mark.parametrize("rules", [{}, {"min_jump_mm": 5.0}, 5.0])
def test_rules_other_than_artefact_rules_are_named(hip, no_fit, rules):
    with pytest.raises(ValueError, match=r"rules must be an ArtefactRules"):
        _fit(hip, rules=rules)
    with pytest.raises(ValueError, match=r"rules must be an ArtefactRules"):
        jb.screen(sphere_markers()[0], rules=rules)


def test_artefact_rules_are_still_taken(hip):
    strict = ArtefactRules(min_jump_mm=21.0)
    assert _fit(hip, method="LS", rules=strict).result.converged
    assert not jb.screen(sphere_markers()[0], rules=strict)["markers"].artefacts


@pytest.mark.parametrize(
    ("markers", "problem"),
    [
        (np.zeros((10, 3)), r"markers must be shaped \(n_frames, n_markers, 3\)"),
        (np.zeros((10, 4, 2)), r"markers must be shaped \(n_frames, n_markers, 3\)"),
        (np.full((10, 4, 3), np.nan), "markers contains NaN or inf"),
        (np.zeros((10, 4, 3)), r"markers has a sample at exactly \(0, 0, 0\)"),
        (np.ones((10, 4, 3), dtype=complex), "markers"),
        (np.empty((0, 4, 3)), "markers is empty"),
    ],
)
def test_screen_checks_its_arrays_as_the_fits_do(markers, problem):
    with pytest.raises(ValueError, match=problem):
        jb.screen(markers)


def test_screen_names_the_array_and_checks_every_one():
    proximal, distal = two_segments()
    with pytest.raises(ValueError, match="distal must be shaped"):
        jb.screen(proximal, distal[:, :, :2])
    with pytest.raises(ValueError, match="thigh contains NaN"):
        jb.screen(
            proximal, np.where(np.arange(3)[:, None] == 1, np.nan, distal), names=("p", "thigh")
        )
    assert set(jb.screen(proximal, distal)) == {"proximal", "distal"}


@pytest.mark.parametrize("level", [-0.5, 0.0, 1.0, 95, float("nan"), "0.95", True])
def test_an_interval_level_outside_0_1_is_named(level):
    boot = Bootstrap(np.random.default_rng(0).normal(size=(50, 3)), 5, 0)
    with pytest.raises(ValueError, match=r"level must be a number in \(0, 1\)"):
        boot.interval(level)


def test_an_interval_level_inside_0_1_orders_its_bounds():
    boot = Bootstrap(np.random.default_rng(0).normal(size=(50, 3)), 5, 0)
    low, high = boot.interval(np.float32(0.5))
    assert np.all(low < high)


def test_an_axis_cone_level_outside_0_1_is_named():
    knee = jb.read(KNEE)
    fitted = jb.fit(knee, "axis", SHANK, THIGH, method="SARA", frames="100:400", n_bootstrap=4)
    with pytest.raises(ValueError, match=r"level must be a number in \(0, 1\)"):
        fitted.bootstrap_cone_deg(95)


def _ball(n_frames: int, n_markers: int) -> np.ndarray:
    """Markers ``(n_frames, n_markers, 3)`` [mm] of a body turning about a fixed point."""
    rng = np.random.default_rng(5)
    body = rng.normal(size=(n_markers, 3)) * 40.0 + np.array([0.0, 0.0, 300.0])
    rotations = rotation_matrix(rng.normal(size=(n_frames, 3)) * 0.4)
    return np.einsum("fij,pj->fpi", rotations, body) + np.array([10.0, -20.0, 5.0])


TRANSPOSED = r"may be \(markers, frames, 3\); it must be \(frames, markers, 3\)"


@pytest.mark.parametrize("method", registry.methods("center"))
def test_too_few_frames_of_many_markers_are_refused_as_maybe_transposed(method):
    min_frames = registry.claims("center", method).min_frames
    if min_frames == 1:
        pytest.skip(f"{method} fits one frame")
    markers = np.swapaxes(_ball(200, min_frames - 1), 0, 1)  # min_frames - 1 frames
    with pytest.raises(ValueError, match=TRANSPOSED):
        jb.fit_center(markers, method)


def test_more_markers_than_frames_is_a_warning_in_status():
    markers = np.swapaxes(_ball(200, 4), 0, 1)  # 4 frames of 200 markers
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = jb.fit_center(markers, "LS", artefacts="warn")
        ignored = jb.fit_center(markers, "LS", artefacts="ignore")
    assert "warning:" in result.status and "200 markers over 4 frames" in result.status
    assert "may be (markers, frames, 3); it must be (frames, markers, 3)" in result.status
    assert "(markers, frames, 3)" in ignored.status
    assert any("(markers, frames, 3)" in w for w in result.diagnostics["maybe_transposed"])


def test_a_transposed_joint_centre_pair_is_named():
    proximal, distal = two_segments(n_frames=2)
    with pytest.raises(ValueError, match=rf"proximal .*{TRANSPOSED}"):
        jb.fit_joint_center(
            np.tile(proximal, (1, 4, 1)), np.tile(distal, (1, 4, 1)), artefacts="ignore"
        )


def test_frames_at_least_markers_are_not_flagged():
    markers = _ball(60, 5)
    assert jb.fit_center(markers, "LS").status == "ok"
    assert "maybe_transposed" not in jb.fit_center(markers, "LS").diagnostics
    square = _ball(6, 6)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert "(markers, frames, 3)" not in jb.fit_center(square, "LS").status


def test_ok_is_not_said_to_mean_accurate():
    """'ok' means the data support an answer and the method found its minimum; accuracy is in
    the precision diagnostics."""
    for text in (api.__doc__, (ROOT / "README.md").read_text()):
        assert "for a clean answer" not in text
    assert "accura" in api.__doc__ and "precision" in api.__doc__
    readme = (ROOT / "README.md").read_text()
    assert '`status == "ok"` does not say the answer is accurate' in readme


def test_a_prepared_recording_refuses_before_its_fit(hip, no_fit):
    prepared = jb.prepare(hip, "center", "D1,D2,D3", "P1,P2,P3")
    with pytest.raises(ValueError, match="seed: must be"):
        prepared.fit("LS", n_bootstrap=4, seed=-2)
