"""Hinge (knee / index-MCP) simulation of paper B §3.1."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from jointbench.configuration.seeds import trial_rng
from jointbench.estimators.axis import fit_combined
from jointbench.geometry import angle_between_lines_deg
from jointbench.simulate import Trials, hinge

CONDITION = {"protocol": "knee", "fe_rom_deg": 60, "aa_ratio": 0.3}


def rngs(condition, n_trials=3):
    return [trial_rng(0, "hinge", condition, trial) for trial in range(n_trials)]


def distance_to_axis(points: np.ndarray, point: np.ndarray, direction: np.ndarray) -> np.ndarray:
    offset = points - point
    return np.linalg.norm(offset - np.multiply.outer(offset @ direction, direction), axis=-1)


@pytest.mark.parametrize("name", ["knee", "mcp"])
def test_shapes_and_truth(name):
    condition = dict(CONDITION, protocol=name)
    protocol = hinge.HINGE_PROTOCOLS[name]
    trials = hinge.simulate(condition, protocol, rngs(condition, 4))
    assert isinstance(trials, Trials)
    n_markers = len(protocol.markers_mm)
    assert trials.segments["moving"].shape == (4, 121, n_markers, 3)
    assert trials.segments["moving"].dtype == np.float64
    assert trials.n_trials == 4
    direction = np.array(trials.truth["axis_direction"])
    assert np.linalg.norm(direction) == pytest.approx(1.0, abs=1e-15)
    assert len(trials.truth["axis_point"]) == 3
    assert trials.parameters["noise_sd_mm"] == 1.0
    assert trials.parameters["condition"] == condition


def test_reproducible_from_seeds_and_independent_of_trial_batching():
    protocol = hinge.HINGE_PROTOCOLS["knee"]
    first = hinge.simulate(CONDITION, protocol, rngs(CONDITION, 3)).segments["moving"]
    again = hinge.simulate(CONDITION, protocol, rngs(CONDITION, 3)).segments["moving"]
    np.testing.assert_array_equal(first, again)
    alone = hinge.simulate(CONDITION, protocol, [trial_rng(0, "hinge", CONDITION, 2)])
    np.testing.assert_array_equal(alone.segments["moving"][0], first[2])
    assert not np.array_equal(first[0], first[1])


def test_noise_has_the_requested_size():
    protocol = dataclasses.replace(hinge.HINGE_PROTOCOLS["knee"], noise_sd_mm=2.0)
    trials = hinge.simulate(CONDITION, protocol, rngs(CONDITION, 20))
    noise = trials.segments["moving"] - hinge.nominal_markers(CONDITION, protocol)
    rms_length = np.sqrt(np.mean(np.sum(noise**2, axis=-1)))
    assert rms_length == pytest.approx(2.0, rel=0.05)
    quiet = dataclasses.replace(protocol, noise_sd_mm=0.0)
    silent = hinge.simulate(CONDITION, quiet, rngs(CONDITION, 1)).segments["moving"][0]
    np.testing.assert_array_equal(silent, hinge.nominal_markers(CONDITION, quiet))


@pytest.mark.parametrize("name", ["knee", "mcp"])
def test_pure_fe_keeps_every_marker_at_a_constant_distance_from_the_axis(name):
    condition = {"protocol": name, "fe_rom_deg": 90, "aa_ratio": 0.0}
    protocol = hinge.HINGE_PROTOCOLS[name]
    nominal = hinge.nominal_markers(condition, protocol)
    trials = hinge.simulate(condition, protocol, [])
    point = np.array(trials.truth["axis_point"])
    direction = np.array(trials.truth["axis_direction"])
    distance = distance_to_axis(nominal, point, direction)
    np.testing.assert_allclose(distance, np.broadcast_to(distance[0], distance.shape), atol=1e-9)
    # ... and in a fixed plane normal to the axis, and the markers move.
    height = (nominal - point) @ direction
    np.testing.assert_allclose(height, np.broadcast_to(height[0], height.shape), atol=1e-9)
    assert np.ptp(nominal[..., 1]) > 1.0


@pytest.mark.parametrize("name", ["knee", "mcp"])
@pytest.mark.parametrize("motion", hinge.MOTIONS)
@pytest.mark.parametrize("convention", hinge.ROM_CONVENTIONS)
def test_angle_ranges_follow_the_rom_convention(name, motion, convention):
    protocol = dataclasses.replace(
        hinge.HINGE_PROTOCOLS[name], motion=motion, rom_convention=convention
    )
    fe, aa = hinge.joint_angles({"fe_rom_deg": 60, "aa_ratio": 0.5}, protocol)
    excursion = 60.0 if convention == "full" else 120.0
    assert fe.shape == aa.shape == (121,)
    assert np.degrees(np.ptp(fe)) == pytest.approx(excursion, rel=2e-3)
    # FE starts from the neutral pose (full extension); sampled sinusoids may miss the peak.
    assert np.degrees(fe.min()) == pytest.approx(0.0, abs=2e-2 * excursion)
    assert np.degrees(np.ptp(aa)) == pytest.approx(0.5 * excursion, rel=2e-2)
    assert np.degrees(aa.max()) == pytest.approx(-np.degrees(aa.min()), rel=2e-2)


def test_markers_stay_rigid_and_on_spheres_about_the_joint_centre():
    protocol = hinge.HINGE_PROTOCOLS["knee"]
    nominal = hinge.nominal_markers({"fe_rom_deg": 90, "aa_ratio": 0.7}, protocol)
    radii = np.linalg.norm(nominal, axis=-1)
    np.testing.assert_allclose(radii, np.broadcast_to(radii[0], radii.shape), rtol=1e-12)
    gaps = np.linalg.norm(nominal[:, :, None] - nominal[:, None], axis=-1)
    np.testing.assert_allclose(gaps, np.broadcast_to(gaps[0], gaps.shape), atol=1e-9)


def test_fe_axis_stays_fixed_in_the_reference_frame():
    """With the default rotation order AA is about the floating axis; FE is about fixed x."""
    protocol = hinge.HINGE_PROTOCOLS["knee"]
    assert protocol.rotation_order == "fe_aa"
    condition = {"fe_rom_deg": 60, "aa_ratio": 0.0}
    fe, _ = hinge.joint_angles(condition, protocol)
    nominal = hinge.nominal_markers(condition, protocol)
    result = fit_combined(nominal, point=np.zeros(3))
    assert angle_between_lines_deg(result.direction, hinge.FE_AXIS) < 0.01
    assert np.ptp(fe) > 0


def test_protocols_are_plausible_and_documented():
    knee, mcp = hinge.HINGE_PROTOCOLS["knee"], hinge.HINGE_PROTOCOLS["mcp"]
    assert knee.marker_names == ("L1", "L2", "L3")
    assert mcp.marker_names == ("P1", "P2", "P3")
    knee_distance = np.linalg.norm(knee.markers, axis=1)
    mcp_distance = np.linalg.norm(mcp.markers, axis=1)
    # Lower-leg markers within a shank length of the knee; phalanx markers within ~45 mm.
    assert np.all((knee_distance > 50) & (knee_distance < 450))
    assert np.all((mcp_distance > 5) & (mcp_distance < 50))
    # Markers below the joint (distal segment hangs along -z in the neutral pose).
    assert np.all(knee.markers[:, 2] < 0) and np.all(mcp.markers[:, 2] < 0)
    for protocol in (knee, mcp):
        assert (protocol.n_frames, protocol.noise_sd_mm) == (121, 1.0)
        assert protocol.motion == knee.motion
        assert protocol.rom_convention == knee.rom_convention


def test_protocol_from_config_overrides_fields():
    protocol = hinge.protocol_from_config(
        {
            "name": "mcp",
            "rom_convention": "half",
            "noise_sd_mm": 0.5,
            "markers_mm": [[1, 2, -3]],
            "marker_names": ["A"],
        }
    )
    assert protocol.rom_convention == "half"
    assert protocol.noise_sd_mm == 0.5
    assert protocol.markers_mm == ((1.0, 2.0, -3.0),)
    assert protocol.motion == hinge.HINGE_PROTOCOLS["mcp"].motion
    assert hinge.protocol_from_config("knee") == hinge.HINGE_PROTOCOLS["knee"]


@pytest.mark.parametrize(
    ("config", "message"),
    [
        ({"rom_convention": "full"}, "name"),
        ({"name": "knee", "speed": 3}, "speed: HingeProtocol has no such field"),
        ({"name": "knee", "motion": "zigzag"}, "motion: must be one of"),
        ({"name": "knee", "rom_convention": "quarter"}, "rom_convention: must be one of"),
        ({"name": "knee", "rotation_order": "xyz"}, "rotation_order: must be one of"),
        ({"name": "knee", "noise_sd_mm": -1}, "noise_sd_mm"),
        ({"name": "knee", "n_frames": 2}, "n_frames"),
        ({"name": "knee", "motion": "grid", "n_frames": 120}, "square"),
        ({"name": "knee", "marker_names": ["a"]}, "marker_names"),
        ({"name": "elbow"}, "not built in"),
    ],
)
def test_bad_config_raises_value_error(config, message):
    with pytest.raises(ValueError, match=message):
        hinge.protocol_from_config(config)


@pytest.mark.parametrize(
    ("condition", "message"),
    [
        ({"protocol": "knee", "aa_ratio": 0.1}, "fe_rom_deg"),
        ({"protocol": "knee", "fe_rom_deg": -30, "aa_ratio": 0.1}, "fe_rom_deg must be > 0"),
        ({"protocol": "knee", "fe_rom_deg": 30, "aa_ratio": -0.1}, "aa_ratio must be >= 0"),
        ({"protocol": "mcp", "fe_rom_deg": 30, "aa_ratio": 0.1}, "protocol 'mcp'"),
    ],
)
def test_bad_condition_raises_value_error(condition, message):
    with pytest.raises(ValueError, match=message):
        hinge.simulate(condition, hinge.HINGE_PROTOCOLS["knee"], rngs(CONDITION, 1))


@settings(max_examples=30, deadline=None)
@given(
    st.sampled_from(["knee", "mcp"]),
    st.floats(5.0, 120.0),
    st.floats(0.0, 1.0),
    st.sampled_from(hinge.MOTIONS),
    st.sampled_from(hinge.ROTATION_ORDERS),
)
def test_nominal_motion_is_a_rotation_about_the_joint_centre(name, rom, ratio, motion, order):
    protocol = dataclasses.replace(hinge.HINGE_PROTOCOLS[name], motion=motion, rotation_order=order)
    nominal = hinge.nominal_markers({"fe_rom_deg": rom, "aa_ratio": ratio}, protocol)
    assert nominal.shape == (121, len(protocol.markers_mm), 3)
    assert np.all(np.isfinite(nominal))
    np.testing.assert_allclose(
        np.linalg.norm(nominal, axis=-1),
        np.broadcast_to(np.linalg.norm(protocol.markers, axis=-1), nominal.shape[:2]),
        rtol=1e-12,
    )


# A value of each field some motions read and others not, other than its default.
_MOTION_FIELD_VALUES = {"fe_cycles": 1.5, "aa_cycles": 3.0, "aa_phase_deg": 40.0}


@pytest.mark.parametrize("motion", hinge.MOTIONS)
def test_each_motion_reads_the_fields_it_declares_and_no_other(motion):
    """:data:`hinge.MOTION_FIELDS`, against which the config's check refuses a field the
    chosen motion does not read, is what :func:`hinge.simulate` reads: a change of a field the
    motion lists changes its noisy trials, a change of another changes nothing. The whole
    simulation is compared, not the joint angles alone: a field read through the markers or
    the noise changes data as much."""
    assert set(_MOTION_FIELD_VALUES) == set().union(*hinge.MOTION_FIELDS.values())
    assert set(hinge.MOTION_FIELDS) == set(hinge.MOTIONS)
    base = dataclasses.replace(hinge.HINGE_PROTOCOLS["knee"], motion=motion)
    condition = {"protocol": "knee", "fe_rom_deg": 60.0, "aa_ratio": 0.3}

    def trials(protocol: hinge.HingeProtocol) -> np.ndarray:
        rngs = [np.random.default_rng(seed) for seed in range(2)]
        return hinge.simulate(condition, protocol, rngs).segments["moving"]

    simulated = trials(base)
    for field, value in _MOTION_FIELD_VALUES.items():
        other = trials(dataclasses.replace(base, **{field: value}))
        read = not np.array_equal(other, simulated)
        assert read == (field in hinge.MOTION_FIELDS[motion]), (motion, field)


# A value other than its default of each field of a joint's protocol that could shape its
# trials; the others only name them (its name, its markers' names).
_FIELD_VALUES = {
    "markers_mm": ((62.5, 36.0, -143.5), (-32.5, -23.5, -151.0), (43.5, -2.0, -171.0)),
    "rom_convention": "half",
    "fe_cycles": 1.5,
    "aa_cycles": 3.0,
    "aa_phase_deg": 40.0,
    "rotation_order": "aa_fe",
    "noise_sd_mm": 0.5,
    "n_frames": 144,
}
_NAMING_FIELDS = ("name", "marker_names")


@pytest.mark.parametrize("motion", hinge.MOTIONS)
def test_the_aa_fields_change_the_trials_only_where_aa_ratio_is_above_0(motion):
    """:data:`hinge.AMPLITUDE_FIELDS`, against which the config's check refuses a field
    written under a grid whose every ``aa_ratio`` is 0, is what :func:`hinge.simulate` reads:
    at a ratio of 0 a change of one of them changes no trial, and a change of any other field
    of the protocol (the motion included) that the motion reads changes them; at 0.3 each
    changes them. Every field is tried, so a field the simulation leaves unread without
    abduction-adduction and the declaration leaves out fails as one it lists but reads."""
    fields = {field.name for field in dataclasses.fields(hinge.HingeProtocol)}
    assert set(_FIELD_VALUES) | {"motion"} == fields - set(_NAMING_FIELDS)
    assert set(hinge.AMPLITUDE_FIELDS) == {"aa_ratio"}
    base = dataclasses.replace(hinge.HINGE_PROTOCOLS["knee"], motion=motion)
    other_motion = next(other for other in hinge.MOTIONS if other != motion)
    motion_fields = set().union(*hinge.MOTION_FIELDS.values())

    def trials(protocol: hinge.HingeProtocol, ratio: float) -> np.ndarray:
        condition = {"protocol": "knee", "fe_rom_deg": 60.0, "aa_ratio": ratio}
        rngs = [np.random.default_rng(seed) for seed in range(2)]
        return hinge.simulate(condition, protocol, rngs).segments["moving"]

    for ratio in (0.0, 0.3):
        simulated = trials(base, ratio)
        for field, value in {**_FIELD_VALUES, "motion": other_motion}.items():
            if field in motion_fields and field not in hinge.MOTION_FIELDS[motion]:
                continue
            other = trials(dataclasses.replace(base, **{field: value}), ratio)
            read = not np.array_equal(other, simulated)
            without_aa = ratio == 0 and field in hinge.AMPLITUDE_FIELDS["aa_ratio"]
            assert read == (not without_aa), (motion, ratio, field)
