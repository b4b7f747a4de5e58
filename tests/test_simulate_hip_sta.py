"""The skin-marker hip study: rigid clusters without STA, the STA's documented amplitude and
rigid share, determinism by seed, pairing across conditions, and the bootstrap's covariances."""

from __future__ import annotations

import dataclasses
import itertools
import json

import numpy as np
import pandas as pd
import pytest

from jointbench.configuration.seeds import trial_rng
from jointbench.configuration.studies import get_study
from jointbench.geometry import skew
from jointbench.numerics.poses import rigid_fit
from jointbench.papers import paper_sta
from jointbench.simulate import hip_sta
from jointbench.simulate.hip_sta import (
    HipStaProtocol,
    hip_angles,
    nominal_recording,
    simulate,
    sta_displacements,
    sta_field,
)

PROTOCOL = HipStaProtocol()
QUIET = dataclasses.replace(PROTOCOL, noise_mm=0.0)


def _rngs(n: int, base: int = 11) -> list[np.random.Generator]:
    return [trial_rng(base, "hip_sta", {}, trial) for trial in range(n)]


def _condition(motion="star_arc", rom=45.0, sta=0.0) -> dict:
    return {"motion": motion, "rom_deg": rom, "sta_mm": sta}


def _bodies(protocol: HipStaProtocol) -> tuple[np.ndarray, np.ndarray]:
    joint = np.asarray(protocol.joint_mm)
    return joint + np.asarray(protocol.pelvis_markers_mm), joint + np.asarray(
        protocol.thigh_markers_mm
    )


def test_registered_with_its_shapes_truth_and_parameters():
    assert get_study("hip_sta") is hip_sta.STUDY
    trials = simulate(_condition(), PROTOCOL, _rngs(2))
    assert trials.segments["proximal"].shape == (2, PROTOCOL.n_frames, 4, 3)
    assert trials.segments["distal"].shape == (2, PROTOCOL.n_frames, 4, 3)
    assert trials.truth == {"center": list(PROTOCOL.joint_mm)}
    assert json.loads(json.dumps(trials.parameters)) == trials.parameters


@pytest.mark.parametrize("motion", hip_sta.MOTIONS)
def test_without_sta_or_noise_the_clusters_are_rigid_about_the_joint(motion):
    trials = simulate(_condition(motion, 30.0, 0.0), QUIET, _rngs(1))
    pelvis_body, thigh_body = _bodies(QUIET)
    for name, body in (("proximal", pelvis_body), ("distal", thigh_body)):
        markers = trials.segments[name][0]
        np.testing.assert_allclose(markers[0], body, atol=1e-12)
        rotation, translation = rigid_fit(body, markers)
        fitted = body @ np.swapaxes(rotation, -1, -2) + translation[:, None, :]
        np.testing.assert_allclose(fitted, markers, atol=1e-9)
    # The joint is where both segments put it in every frame.
    r0, d0, r1, d1 = nominal_recording(hip_angles(motion, 30.0, QUIET), QUIET)
    joint = np.asarray(QUIET.joint_mm)
    np.testing.assert_allclose(r0 @ joint + d0, r1 @ joint + d1, atol=1e-9)


@pytest.mark.parametrize("motion", hip_sta.MOTIONS)
def test_the_thigh_reaches_the_range_and_starts_in_neutral(motion):
    angles = hip_angles(motion, 45.0, PROTOCOL)
    np.testing.assert_allclose(angles[0], 0.0, atol=1e-12)
    excursion = np.degrees(np.linalg.norm(angles, axis=1))
    assert 44.9 < excursion.max() <= 45.0 + 1e-9


def test_sta_has_the_documented_amplitude_and_rigid_share():
    _, thigh_body = _bodies(PROTOCOL)
    field = sta_field(thigh_body, np.random.default_rng(3), 20.0, 30.0, 0.8)
    directions = np.linspace(0.0, 2.0 * np.pi, 360, endpoint=False)
    angles = np.radians(30.0) * np.stack([np.cos(directions), np.sin(directions)], axis=-1)
    moved = sta_displacements(field, angles)
    assert np.sqrt(np.mean(np.sum(moved**2, axis=-1))) == pytest.approx(20.0, rel=1e-12)
    # Its rigid part: the best infinitesimal rigid motion of the cluster per angle.
    offsets = thigh_body - thigh_body.mean(axis=0)
    design = np.concatenate([np.tile(np.eye(3), (4, 1)), -np.concatenate(skew(offsets))], 1)
    rigid = [design @ np.linalg.lstsq(design, f.ravel(), rcond=None)[0] for f in field]
    share = sum(np.sum(r**2) for r in rigid) / np.sum(field**2)
    assert share == pytest.approx(0.8, rel=1e-9)
    # Linear in the angles: none in the neutral posture, twice the angle twice the displacement.
    np.testing.assert_allclose(sta_displacements(field, np.zeros((1, 2))), 0.0)
    np.testing.assert_allclose(sta_displacements(field, 2 * angles), 2 * moved)


def test_simulated_markers_carry_the_sta_in_the_bone_frame():
    rigid = simulate(_condition(sta=0.0), QUIET, _rngs(1))
    skin = simulate(_condition(sta=15.0), QUIET, _rngs(1))
    _, thigh_body = _bodies(QUIET)
    angles = hip_angles("star_arc", 45.0, QUIET)
    _, _, r1, _ = nominal_recording(angles, QUIET)
    field = sta_field(thigh_body, _rngs(1)[0], 15.0, QUIET.sta_reference_deg, QUIET.sta_rigid_share)
    in_bone = np.einsum(
        "fji,fnj->fni", r1, skin.segments["distal"][0] - rigid.segments["distal"][0]
    )
    np.testing.assert_allclose(in_bone, sta_displacements(field, angles), atol=1e-9)
    # No pelvis STA by default.
    np.testing.assert_allclose(skin.segments["proximal"], rigid.segments["proximal"], atol=1e-12)


def test_determinism_by_seed_and_pairing_across_conditions():
    first = simulate(_condition(sta=20.0), PROTOCOL, _rngs(3))
    again = simulate(_condition(sta=20.0), PROTOCOL, _rngs(3))
    for name in ("proximal", "distal"):
        np.testing.assert_array_equal(first.segments[name], again.segments[name])
    assert not np.allclose(first.segments["distal"][0], first.segments["distal"][1])
    # Trial k is the same subject and noise at every amplitude: frame 0 (neutral, no STA) agrees.
    other = simulate(_condition(sta=10.0), PROTOCOL, _rngs(3))
    np.testing.assert_array_equal(first.segments["distal"][:, 0], other.segments["distal"][:, 0])


def test_bad_conditions_are_refused():
    with pytest.raises(ValueError, match="rom_deg"):
        simulate(_condition(rom=120.0), PROTOCOL, _rngs(1))
    with pytest.raises(ValueError, match="motion"):
        simulate(_condition(motion="walk"), PROTOCOL, _rngs(1))
    with pytest.raises(ValueError, match="unknown"):
        simulate({**_condition(), "n_frames": 10}, PROTOCOL, _rngs(1))
    spec = hip_sta.STUDY.grid_spec
    assert not spec["sta_mm"].accepts(-1.0, PROTOCOL)
    assert not spec["sta_mm"].accepts(1e6, PROTOCOL)
    assert spec["motion"].accepts("circumduction", PROTOCOL)


def test_bootstrap_covariances_are_finite_and_widen_with_sta():
    sizes = []
    for sta in (0.0, 20.0):
        trials = simulate(_condition(sta=sta), PROTOCOL, _rngs(2))
        covariances = paper_sta.bootstrap_covariances(trials, 2, 6)
        assert covariances.shape == (2, 3, 3)
        assert np.isfinite(covariances).all()
        sizes.append(np.sqrt(np.trace(covariances, axis1=1, axis2=2)).mean())
    assert sizes[1] > sizes[0]


# --------------------------------------------------------------- centre methods on the thigh


def test_the_thigh_in_the_pelvis_frame_turns_about_the_true_centre():
    # Without noise or STA the pelvis frame is exact, so in it the thigh markers keep their
    # distances from the true centre while they move.
    trials = simulate(_condition(sta=0.0), QUIET, _rngs(2))
    thigh = trials.segments["thigh_in_pelvis"]
    assert thigh.shape == trials.segments["distal"].shape
    distances = np.linalg.norm(thigh - np.asarray(QUIET.joint_mm), axis=-1)
    np.testing.assert_allclose(
        distances, np.broadcast_to(distances[:, :1], distances.shape), atol=1e-9
    )
    assert np.ptp(thigh, axis=1).max() > 100.0  # they do move


def test_the_pelvis_frame_follows_the_recorded_pelvis_not_the_world():
    # A pelvis that sways carries the thigh with it: in the pelvis frame the sway is gone.
    still = dataclasses.replace(QUIET, pelvis_sway_mm=(0.0, 0.0, 0.0), pelvis_sway_deg=(0, 0, 0))
    swaying = simulate(_condition(), QUIET, _rngs(1))
    fixed = simulate(_condition(), still, _rngs(1))
    assert np.abs(swaying.segments["distal"] - fixed.segments["distal"]).max() > 5.0
    np.testing.assert_allclose(
        swaying.segments["thigh_in_pelvis"], fixed.segments["thigh_in_pelvis"], atol=1e-9
    )


@pytest.mark.parametrize("method", ["LS", "NM", "BC", "MA", "IS"])
def test_every_centre_method_runs_on_the_study_and_recovers_the_centre(method):
    from jointbench.configuration.studies import method_kind
    from jointbench.running.run import estimate_table

    study = get_study("hip_sta")
    assert method_kind(study, method) == "center"
    trials = simulate(_condition(), QUIET, _rngs(2))
    table = estimate_table("hip_sta", method, trials, _condition()).to_pandas()
    assert list(table["method"]) == [method, method]
    assert table["converged"].all(), table["status"].tolist()
    assert table["error_mm"].max() < 1e-6


def test_each_name_runs_as_the_first_kind_that_has_it():
    from jointbench.configuration.studies import method_kind

    study = get_study("hip_sta")
    assert study.kinds == ("joint_center", "center")
    # SCoRE exists in both kinds: the study's own kind comes first.
    assert method_kind(study, "SCoRE") == "joint_center"
    assert method_kind(study, "gauss-markov") == "joint_center"
    assert study.segments_of("center") == ("thigh_in_pelvis",)
    assert study.all_segments == ("proximal", "distal", "thigh_in_pelvis")
    with pytest.raises(
        ValueError, match="runs no axis estimators; its kinds: joint_center, center"
    ):
        study.segments_of("axis")


def test_a_study_refuses_kinds_scored_against_different_truths():
    with pytest.raises(ValueError, match="scored against different truths"):
        dataclasses.replace(hip_sta.STUDY, more_kinds={"axis": ("distal",)})
    with pytest.raises(ValueError, match="repeats its kind"):
        dataclasses.replace(hip_sta.STUDY, more_kinds={"joint_center": ("distal",)})
    with pytest.raises(ValueError, match="kind 'knee' is not one of"):
        dataclasses.replace(hip_sta.STUDY, more_kinds={"knee": ("distal",)})


def test_the_findings_count_the_joint_centre_methods_whatever_else_runs():
    # The ensembles run only the methods a paper measures; the default run runs every listed
    # estimator. A finding must read the same in both.
    from jointbench.papers.base import Inputs

    rows = []
    for method, motion, rom, sta in itertools.product(
        (*paper_sta.MEASURED, "LS"), hip_sta.MOTIONS, (20.0, 45.0), (0.0, 10.0)
    ):
        # LS far worse than everyone, everywhere: were it counted, S1 would change.
        error = 50.0 if method == "LS" else 1.0 + sta + (rom == 20.0)
        rows.append(
            {"method": method, "motion": motion, "rom_deg": rom, "sta_mm": sta, "error_mm": error}
        )
    collected = pd.DataFrame(rows)
    every = paper_sta.measure(Inputs(collected, {}, {}))
    measured = paper_sta.measure(
        Inputs(collected[collected["method"].isin(paper_sta.MEASURED)], {}, {})
    )
    assert every.keys() == measured.keys() and "S1" in every
    for key in every:
        assert every[key].value == measured[key].value, key
    assert every["S1"].value == 1.0
    assert set(paper_sta.PAPER.methods) | set(paper_sta.PAPER.also_measures) == set(
        paper_sta.MEASURED
    )


# A value of each field one motion reads and the other not, other than its default.
_MOTION_FIELD_VALUES = {
    "star_azimuths_deg": (0.0, 90.0),
    "star_fraction": 0.5,
    "arc_turns": 2.0,
    "circumduction_turns": 2.0,
}


@pytest.mark.parametrize("motion", hip_sta.MOTIONS)
def test_each_motion_reads_the_fields_it_declares_and_no_other(motion):
    """:data:`hip_sta.MOTION_FIELDS`, against which the config's check refuses a field no
    motion of the grid reads, is what :func:`hip_sta.simulate` reads: a change of a field the
    motion lists changes its trials, a change of another changes nothing. Every segment of
    the whole simulation is compared, with artefact and noise, not the hip angles alone: a
    field read through the markers, the artefact or the noise changes data as much."""
    assert set(_MOTION_FIELD_VALUES) == set().union(*hip_sta.MOTION_FIELDS.values())
    assert set(hip_sta.MOTION_FIELDS) == set(hip_sta.MOTIONS)
    base = dataclasses.replace(PROTOCOL, duration_s=2.0)
    condition = _condition(motion, rom=30.0, sta=10.0)

    def trials(protocol: HipStaProtocol) -> dict[str, np.ndarray]:
        return simulate(condition, protocol, _rngs(2)).segments

    simulated = trials(base)
    for field, value in _MOTION_FIELD_VALUES.items():
        other = trials(dataclasses.replace(base, **{field: value}))
        read = any(not np.array_equal(other[name], simulated[name]) for name in simulated)
        assert read == (field in hip_sta.MOTION_FIELDS[motion]), (motion, field)


# A value other than its default of each field of the protocol the motions read alike.
_SHARED_FIELD_VALUES = {
    "duration_s": 2.5,
    "fps": 60.0,
    "noise_mm": 1.0,
    "joint_mm": (0.0, -90.0, 905.0),
    "pelvis_markers_mm": ((57.8, -33.6, 72.0), *PROTOCOL.pelvis_markers_mm[1:]),
    "thigh_markers_mm": ((45.0, -95.0, -150.0), *PROTOCOL.thigh_markers_mm[1:]),
    "pelvis_sway_mm": (6.0, 8.0, 4.0),
    "pelvis_sway_deg": (1.0, 2.0, 3.0),
    "pelvis_sway_hz": (0.2, 0.21, 0.17),
    "sta_reference_deg": 20.0,
    "sta_rigid_share": 0.5,
    "pelvis_sta_ratio": 0.3,
}


@pytest.mark.parametrize("motion", hip_sta.MOTIONS)
def test_the_artefact_fields_change_the_trials_only_where_sta_mm_is_above_0(motion):
    """:data:`hip_sta.AMPLITUDE_FIELDS`, against which the config's check refuses a field
    written under a grid whose every ``sta_mm`` is 0, is what :func:`hip_sta.simulate` reads:
    at an artefact of 0 a change of one of them changes no segment of the trials, and a change
    of any other field of the protocol that the motion reads changes them; at 10 mm each
    changes them. Every field is tried, so a field the simulation leaves unread without
    artefact and the declaration leaves out fails as one it lists but reads."""
    fields = {field.name for field in dataclasses.fields(HipStaProtocol)}
    assert set(_SHARED_FIELD_VALUES) | set(_MOTION_FIELD_VALUES) == fields
    assert set(hip_sta.AMPLITUDE_FIELDS) == {"sta_mm"}
    base = dataclasses.replace(PROTOCOL, duration_s=2.0)

    def trials(protocol: HipStaProtocol, sta: float) -> dict[str, np.ndarray]:
        return simulate(_condition(motion, rom=30.0, sta=sta), protocol, _rngs(2)).segments

    values = {
        **{f: v for f, v in _MOTION_FIELD_VALUES.items() if f in hip_sta.MOTION_FIELDS[motion]},
        **_SHARED_FIELD_VALUES,
    }
    for sta in (0.0, 10.0):
        simulated = trials(base, sta)
        for field, value in values.items():
            other = trials(dataclasses.replace(base, **{field: value}), sta)
            read = any(not np.array_equal(other[name], simulated[name]) for name in simulated)
            without_sta = sta == 0 and field in hip_sta.AMPLITUDE_FIELDS["sta_mm"]
            assert read == (not without_sta), (motion, sta, field)
