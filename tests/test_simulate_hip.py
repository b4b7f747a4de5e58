"""The paper C rig simulation: shapes, truth, rigidity, the prefix property, reproducibility."""

from __future__ import annotations

import json

import numpy as np
import pytest

from jointbench.configuration.seeds import trial_rng
from jointbench.geometry import rotation_vector
from jointbench.numerics.poses import rigid_fit
from jointbench.simulate import PROXIMAL_TRUTH, noise
from jointbench.simulate.hip import HipProtocol, marker_layout, nominal_recording, simulate
from jointbench.simulate.noise import isotropic_noise

PROTOCOL = HipProtocol()


def _rngs(n: int, base: int = 7) -> list[np.random.Generator]:
    return [trial_rng(base, "hip", {}, trial) for trial in range(n)]


@pytest.fixture(scope="module")
def nominal():
    return nominal_recording(PROTOCOL)


def _poses(markers: np.ndarray, body: np.ndarray):
    return rigid_fit(body, markers)


def test_shapes_truth_and_parameters():
    trials = simulate({"n_frames": 75}, PROTOCOL, _rngs(4))
    assert trials.n_trials == 4
    assert trials.segments["proximal"].shape == (4, 75, 3, 3)
    assert trials.segments["distal"].shape == (4, 75, 3, 3)
    assert trials.truth["center"] == [0.0, 0.0, 1000.0]
    # The proximal markers' noise-free frame-0 positions, for scoring relative to them.
    np.testing.assert_allclose(
        np.asarray(trials.truth[PROXIMAL_TRUTH]) - trials.truth["center"],
        [[90.0, 0.0, 500.0], [-60.0, 90.0, 520.0], [-50.0, -100.0, 480.0]],
    )
    assert trials.parameters["n_frames"] == 75
    assert trials.parameters["n_frames_recorded"] == 1200
    assert trials.parameters["noise_mm"] == 1.7
    # Truth and parameters survive JSON unchanged (they go into the dataset metadata).
    assert json.loads(json.dumps(trials.parameters)) == trials.parameters
    assert json.loads(json.dumps(trials.truth)) == trials.truth


def test_default_condition_is_the_whole_recording():
    trials = simulate({}, PROTOCOL, _rngs(1))
    assert trials.segments["proximal"].shape == (1, 1200, 3, 3)


def test_frame0_is_the_body_frame_and_motion_is_rigid(nominal):
    proximal, distal = nominal
    proximal_body, distal_body = marker_layout(PROTOCOL)
    np.testing.assert_allclose(proximal[0], proximal_body, atol=1e-12)
    np.testing.assert_allclose(distal[0], distal_body, atol=1e-12)
    for markers, body in ((proximal, proximal_body), (distal, distal_body)):
        rotation, translation = _poses(markers, body)
        fitted = body @ np.swapaxes(rotation, -1, -2) + translation[:, None, :]
        np.testing.assert_allclose(fitted, markers, atol=1e-9)


def test_ball_joint_constraint_holds_at_the_truth(nominal):
    """The true centre, fixed in both bodies, has one world position in every frame."""
    proximal, distal = nominal
    proximal_body, distal_body = marker_layout(PROTOCOL)
    joint = np.asarray(PROTOCOL.joint_mm)
    r0, d0 = _poses(proximal, proximal_body)
    r1, d1 = _poses(distal, distal_body)
    np.testing.assert_allclose(r0 @ joint + d0, r1 @ joint + d1, atol=1e-9)


def test_rig_geometry_matches_paper_c():
    """Clusters 100–200 mm across, about 1 m apart, joint half-way."""
    proximal_body, distal_body = marker_layout(PROTOCOL)
    joint = np.asarray(PROTOCOL.joint_mm)
    for body in (proximal_body, distal_body):
        sides = np.linalg.norm(body[:, None] - body[None], axis=-1)[np.triu_indices(3, 1)]
        assert np.all((sides >= 100) & (sides <= 200))
    separation = np.linalg.norm(proximal_body.mean(0) - distal_body.mean(0))
    assert 900 <= separation <= 1100
    assert abs(np.linalg.norm(proximal_body.mean(0) - joint) - separation / 2) < 50


def test_motion_starts_slowly_and_covers_two_axes(nominal):
    """Nt = 4 spans very little rotation; the whole recording rotates about >= 2 axes."""
    proximal, distal = nominal
    proximal_body, distal_body = marker_layout(PROTOCOL)
    r0, _ = _poses(proximal, proximal_body)
    r1, _ = _poses(distal, distal_body)
    relative = rotation_vector(np.swapaxes(r0, -1, -2) @ r1)
    first4 = np.degrees(np.linalg.norm(relative[:4], axis=-1)).max()
    assert first4 < 1.5
    spread = np.linalg.svd(relative - relative.mean(0), compute_uv=False)
    assert spread[1] > 0.3 * spread[0]
    assert np.degrees(np.linalg.norm(relative, axis=-1)).max() > 45


def test_prefix_property_same_recording_for_every_nt():
    full = simulate({"n_frames": 1200}, PROTOCOL, _rngs(3))
    for nt in (4, 32, 300):
        part = simulate({"n_frames": nt}, PROTOCOL, _rngs(3))
        for name in ("proximal", "distal"):
            np.testing.assert_array_equal(part.segments[name], full.segments[name][:, :nt])


def test_reproducible_and_trials_differ():
    first = simulate({"n_frames": 16}, PROTOCOL, _rngs(2))
    again = simulate({"n_frames": 16}, PROTOCOL, _rngs(2))
    other = simulate({"n_frames": 16}, PROTOCOL, _rngs(2, base=8))
    np.testing.assert_array_equal(first.segments["distal"], again.segments["distal"])
    assert not np.array_equal(first.segments["distal"][0], first.segments["distal"][1])
    assert not np.array_equal(first.segments["distal"], other.segments["distal"])


def test_noise_level_is_sqrt_trace_wy(nominal):
    """RMS 3-D error length = noise_mm = sqrt(tr W_y): per-coordinate SD noise_mm / sqrt(3)."""
    trials = simulate({}, PROTOCOL, _rngs(2))
    error = np.concatenate(
        [trials.segments["proximal"] - nominal[0], trials.segments["distal"] - nominal[1]], axis=2
    )
    rms_length = np.sqrt(np.mean(np.sum(error**2, axis=-1)))
    assert rms_length == pytest.approx(1.7, rel=0.02)
    assert error.reshape(-1, 3).std(axis=0) == pytest.approx(1.7 / np.sqrt(3), rel=0.03)


def test_noise_free_and_noise_override(nominal):
    clean = simulate({"n_frames": 10, "noise_mm": 0.0}, PROTOCOL, _rngs(1))
    np.testing.assert_allclose(clean.segments["proximal"][0], nominal[0][:10])
    assert clean.parameters["noise_mm"] == 0.0


def test_bad_conditions():
    with pytest.raises(ValueError, match="unknown hip condition keys"):
        simulate({"n_frame": 4}, PROTOCOL, _rngs(1))
    with pytest.raises(ValueError, match="n_frames must be an integer"):
        simulate({"n_frames": 1201}, PROTOCOL, _rngs(1))
    with pytest.raises(ValueError, match="noise_mm"):
        simulate({"noise_mm": -1.0}, PROTOCOL, _rngs(1))


def test_protocol_from_config():
    protocol = HipProtocol.from_config({"swing_deg": 20, "joint_mm": [1, 2, 3], "n_frames": 600})
    assert protocol.swing_deg == 20
    assert protocol.joint_mm == (1.0, 2.0, 3.0)
    truth = simulate({}, protocol, _rngs(1)).truth
    assert truth["center"] == [1.0, 2.0, 3.0]
    np.testing.assert_allclose(
        np.asarray(truth[PROXIMAL_TRUTH]) - truth["center"],
        [[90.0, 0.0, 500.0], [-60.0, 90.0, 520.0], [-50.0, -100.0, 480.0]],
    )
    layout = [[0, 0, 500], [100, 0, 500], [0, 100, 500], [50, 50, 550]]
    four = HipProtocol.from_config({"proximal_markers_mm": layout})
    assert simulate({"n_frames": 5}, four, _rngs(1)).segments["proximal"].shape == (1, 5, 4, 3)
    with pytest.raises(ValueError, match="swing: HipProtocol has no such field"):
        HipProtocol.from_config({"swing": 20})
    with pytest.raises(ValueError, match="proximal_markers_mm"):
        HipProtocol.from_config({"proximal_markers_mm": [[0, 0, 1], [1, 0, 1]]})


def test_study_spec_uses_this_simulator():
    from jointbench.configuration.studies import get_study

    spec = get_study("hip")
    protocol = spec.protocol({"n_frames": 300})
    trials = spec.simulate({"n_frames": 8}, protocol, _rngs(2))
    assert spec.fit_arguments(trials, 1)[0].shape == (8, 3, 3)


def test_noise_from_a_generator_state_seen_before_is_drawn_once_and_equals_a_new_draw():
    """Paper C's Nt conditions share each trial's generator: the noise is drawn once per job."""
    first = isotropic_noise(np.random.default_rng(11), (50, 6), 1.7)
    again_rng = np.random.default_rng(11)
    again = isotropic_noise(again_rng, (50, 6), 1.7)
    assert again is first and not again.flags.writeable
    fresh_rng = np.random.default_rng(11)
    fresh = noise._draw(fresh_rng, (50, 6), 1.7)
    assert np.array_equal(fresh, again)
    # The generator is left where the draw leaves it.
    assert again_rng.bit_generator.state == fresh_rng.bit_generator.state
    assert isotropic_noise(np.random.default_rng(11), (50, 6), 1.0) is not first


def test_noise_from_any_bit_generator_is_remembered():
    """The state of a Mersenne Twister holds an array; it keys a draw like any other."""
    first = isotropic_noise(np.random.Generator(np.random.MT19937(3)), (40, 6), 1.0)
    again = isotropic_noise(np.random.Generator(np.random.MT19937(3)), (40, 6), 1.0)
    assert again is first
    assert isotropic_noise(np.random.Generator(np.random.MT19937(4)), (40, 6), 1.0) is not first


def test_remembered_noise_is_bounded_in_bytes():
    remembered = noise._Remembered(max_bytes=3 * 800)
    for key in range(5):
        remembered.put((key,), np.zeros(100), {})
    assert remembered.nbytes == 2400 and [k for (k,) in remembered.draws] == [2, 3, 4]
    assert remembered.get((2,)) is not None and remembered.get((0,)) is None
