"""Bounds on a study's config that its own declarations do not state, each with its reason.

The studies declare their grid values' types and ranges (:class:`jointbench.simulate.GridValues`)
and their protocol fields' (:mod:`jointbench.declared`); what lies within those and still makes
no experiment is refused here, before any job, by :func:`study_problem` (called by
:func:`jointbench.configuration.config.check_config`). Each bound comes from what the papers
simulate or from geometry, and none refuses a value the papers' own grids use
(``tests/test_config_validation.py`` runs the shipped configs through them). The blind copies'
``blind_placement.translation_mm``, which the schema bounds only from below, is bounded here
too (:func:`translation_problem`).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping, Sequence

import numpy as np

from jointbench.simulate.hinge import AMPLITUDE_FIELDS as HINGE_AMPLITUDE_FIELDS
from jointbench.simulate.hinge import MOTION_FIELDS as HINGE_MOTION_FIELDS
from jointbench.simulate.hinge import sine_waves
from jointbench.simulate.hinge_study import placed_fields
from jointbench.simulate.hip import distal_rotation
from jointbench.simulate.hip_sta import AMPLITUDE_FIELDS as HIP_STA_AMPLITUDE_FIELDS
from jointbench.simulate.hip_sta import (
    FRAME_FIELDS,
    hip_angles,
    recording_values,
    thigh_rotation,
)
from jointbench.simulate.hip_sta import MOTION_FIELDS as HIP_STA_MOTION_FIELDS
from jointbench.simulate.noise import largest_noise_mm
from jointbench.simulate.ranges import RESOLUTION_MM

__all__ = [
    "AA_RATIO_BELOW",
    "CMC_EARLIEST_TILT_POWER",
    "CMC_LATEST_TILT_POWER",
    "CMC_TILT_SHARE_BY_MIDDLE",
    "HIP_RESOLUTION_MM",
    "PELVIS_LENGTH_PER_WIDTH",
    "PELVIS_WIDTH_PER_DEPARTURE",
    "TRANSLATION_MM_RANGE",
    "field_values",
    "line_spreads",
    "pelvis_departure",
    "pelvis_poses_problem",
    "study_problem",
    "translation_problem",
]

#: A bound's refusal: the paths of keys below ``studies.<study>`` of the values it is at, each
#: a tuple (``("protocol", "all", "noise_sd_mm")``), and what is wrong and why.
Problem = tuple[list[tuple], str]

#: ``blind_placement.translation_mm`` [mm], the half-side of the cube each trial of a blind copy
#: is translated within (:mod:`jointbench.running.placement`), lies in ``[low, high]``, finite.
#: Low: the rotation turns the data about the origin, so a truth at the origin (the knee's axis
#: passes through it) moves by the translation alone and a contestant answering it scores the
#: translation's length; at 100 mm that averages about 96 mm and is below 10 mm (an error the
#: estimators make at the studies' 0.5-2 mm marker noise) in one trial in 2000
#: (``(pi / 6) 0.1^3``), so no constant answer ranks near an estimator.
#: High: the answers are mapped back by ``R^T (c' - p)``, whose rounding is about 1e-16
#: times the translation; at 1e5 mm (100 m) that is 1e-11 mm, a hundredth of the 1e-9 mm the
#: mapped-back answers are held to, while 1e30 mm leaves nothing of a centre at (10, 20, 30).
TRANSLATION_MM_RANGE = (100.0, 1e5)

#: The hinge study's AA/FE ratio is below 1. The estimators find the flexion–extension axis,
#: the motion's principal axis only while abduction–adduction is the smaller rotation: a share
#: ``ratio^2 / (1 + ratio^2)`` of the rotation lies off the FE axis (0.33 at paper B's largest
#: ratio, 0.7), half at ratio 1, where FE and AA are equal and no axis is the motion's, and
#: most above it (at 50, abduction of 50 times the flexion). Paper B's grid is 0.1 to 0.7.
AA_RATIO_BELOW = 1.0

#: The thumb CMC's circumduction spiral circles out over the trial: by its middle the tilt
#: has reached at least this share of the RoM its condition names, and is still at least this
#: share short of it. Paper A: "The generated marker trajectories simulated thumb
#: circumduction by beginning from a nominal mean position and circling out to increasing
#: angles relative to the mean position." A thumb still within a tenth of its RoM of the mean
#: half-way through (an order of magnitude short of the excursion its condition names) has not
#: begun to circle out over the recording: it stays near its mean position and reaches its RoM
#: only in the trial's last frames (at tilt_power 82 it barely leaves the mean before them).
#: One already within a tenth of its RoM of it half-way through has circled out in the
#: trial's first frames and stays at its RoM: it does not begin from its mean position and
#: circle out to increasing angles over the recording (at tilt_power 1e-6 it is at its RoM
#: from the first frame after the start). The tilt grows as the trial's fraction to
#: ``tilt_power`` (:func:`~jointbench.simulate.cmc.spiral_rotations`), so the rule bounds
#: ``tilt_power`` to [:data:`CMC_EARLIEST_TILT_POWER`, :data:`CMC_LATEST_TILT_POWER`]; a
#: linear spiral (1) reaches half the RoM by the middle, the prior's earliest-growing spiral
#: (0.5) 1/sqrt(2) of it, its latest-growing (2) a quarter.
CMC_TILT_SHARE_BY_MIDDLE = 0.1
#: The largest ``tilt_power`` whose spiral reaches :data:`CMC_TILT_SHARE_BY_MIDDLE` of its RoM
#: by the middle of the trial: ``0.5 ** tilt_power >= share``.
CMC_LATEST_TILT_POWER = math.log(CMC_TILT_SHARE_BY_MIDDLE) / math.log(0.5)
#: The smallest ``tilt_power`` whose spiral is still :data:`CMC_TILT_SHARE_BY_MIDDLE` of its
#: RoM short of it by the middle of the trial: ``0.5 ** tilt_power <= 1 - share``.
CMC_EARLIEST_TILT_POWER = math.log(1.0 - CMC_TILT_SHARE_BY_MIDDLE) / math.log(0.5)

#: The hip rig's pendulum rotations (distal relative to proximal, about x, y, z): paper C's rig
#: was swung so that "the second segment moved around at least 2 of the axes" (§8); with fewer,
#: the recording is a hinge's, whose centre lies anywhere on its axis. A rotation counts as
#: moving when, somewhere in the recording (``n_frames`` at ``fps``), it alone turns a distal
#: marker further than the marker noise ``noise_mm`` (the RMS length of a marker's error), and
#: than :data:`HIP_RESOLUTION_MM` whatever the noise: one that moves none further is not seen in
#: any frame beside the noise, or without noise in any recording. This one rule covers each
#: way a rotation can be configured yet not happen: an amplitude of 1e-9°, a frequency whose
#: swing has barely started when the recording ends (1e-9 Hz), or a cross swing whose build-up
#: time (1e9 s) is so much longer than the recording that it never develops. Half a cycle of a
#: slow swing still counts: it turns the markers as far as a full one.
HIP_ROTATIONS = ("swing_deg", "cross_swing_deg", "twist_deg")
HIP_FEWEST_AXES = 2
#: [mm] The least turn of a distal marker that counts a hip rig rotation as moving, whatever
#: the noise: with ``noise_mm`` 0 the noise no longer sets a floor, and a rotation turning no
#: marker by :data:`~jointbench.simulate.ranges.RESOLUTION_MM` (a tenth of what optical motion
#: capture resolves) is no motion a recording of the rig could show; the estimators would read
#: it from the rounding of the simulated coordinates alone.
HIP_RESOLUTION_MM = RESOLUTION_MM
#: Frequencies [Hz] of a study's periodic motions: a motion happens at a frequency above 0 (one
#: that does not happen has amplitude 0) and below half the frame rate, beyond which the frames
#: cannot show it (the sampling theorem: it would be recorded as a slower motion than the one
#: configured). The hip rig's hand translations and rotations (one per world axis) and its
#: pendulum rotations; the skin-marker study's pelvis sway, one per world axis.
HIP_FREQUENCIES = (
    "hand_translation_hz",
    "hand_rotation_hz",
    "swing_hz",
    "cross_swing_hz",
    "twist_hz",
)
HIP_STA_FREQUENCIES = ("pelvis_sway_hz",)
#: The skin-marker study's protocol fields that set the directions each motion moves the thigh
#: in (:func:`jointbench.simulate.hip_sta.hip_angles`): about at least :data:`HIP_FEWEST_AXES`
#: axes, as paper C's rig (:func:`_hip_sta_axes_problem`).
HIP_STA_DIRECTIONS = {
    "circumduction": ("circumduction_turns",),
    "star_arc": ("star_azimuths_deg", "arc_turns"),
}
#: Turns (or cycles) of a periodic motion over a stretch of a trial's frames are fewer than
#: half those frames, as a frequency is below half the frame rate: the frames cannot show a
#: faster motion (it would be recorded as a slower one than configured), and at 1e13 turns its
#: phases are rounding alone. Checked for the motions the grid runs: the thumb's circumduction
#: spiral; a hinge joint's FE and AA cycles where its motion uses them (the AA's where some
#: ``aa_ratio`` of the grid is above 0); the skin-marker study's circumduction, and its star
#: (one sweep per plane) and the arc after it, each over its share of the trial
#: (``star_fraction``).
SAMPLED_PER_TURN = 2.0

#: Marker clusters, each fitted as one rigid body (:func:`cluster_problem`): the hip rig's, and
#: the skin-marker study's pelvis and thigh.
HIP_CLUSTERS = ("proximal_markers_mm", "distal_markers_mm")
HIP_STA_CLUSTERS = ("pelvis_markers_mm", "thigh_markers_mm")

#: The skin-marker study's pelvis cluster must determine its poses in every trial
#: (:func:`pelvis_poses_problem`): its width, the RMS distance of its markers from their common
#: line, at least this many times their RMS departure from one rigid shape over a trial
#: (:func:`pelvis_departure`), and its length along that line at most
#: :data:`PELVIS_LENGTH_PER_WIDTH` times its width. Both are measured, not reasoned:
#: ``benchmarks/pelvis_pose_convergence.py`` fits the simulated pelvis of
#: :data:`~jointbench.configuration.config.MAX_TRIALS` trials of clusters ever narrower against
#: their noise or their length, in recordings of 4 and 600 frames; each bound is the least
#: measured ratio at which no trial's fit stopped short, the other ratio far from its bound
#: (white noise in the shortest recordings sets this one; the artefact's deformation stops
#: fits only at narrower clusters). A cluster near both bounds at once, in the shortest
#: recordings, can still stop a few fits in 10 000 (the benchmark's ``corner``): the simulate
#: job's refusal stays for those.
PELVIS_WIDTH_PER_DEPARTURE = 4.0
#: See :data:`PELVIS_WIDTH_PER_DEPARTURE`: a long, narrow cluster stops its fit even at little
#: noise, through the arithmetic (the fit's last change stays above its 1e-12 mm tolerance as
#: rounding in the rotation about the cluster's line is amplified).
PELVIS_LENGTH_PER_WIDTH = 30.0


def study_problem(study: str, settings: Mapping, protocol: object) -> Problem | None:
    """``(paths, what is wrong and why)`` for the first value of a study's checked ``settings``
    or its ``protocol`` that a bound of this module refuses, ``paths`` the keys below
    ``studies.<study>`` of each value the bound is at (``[("grid", "aa_ratio")]``); None for a
    study without such bounds or within them."""
    check = _CHECKS.get(study)
    return check(settings, protocol) if check else None


def translation_problem(value: float) -> str | None:
    """What keeps ``value`` from being a ``blind_placement.translation_mm`` within
    :data:`TRANSLATION_MM_RANGE` (NaN and inf, which the schema's bound lets through, included),
    in words giving the reason; None if nothing."""
    low, high = TRANSLATION_MM_RANGE
    if low <= value <= high:  # False for NaN
        return None
    return (
        f"{value!r} is not a finite number in [{low:g}, {high:g}] mm: below {low:g} mm a "
        "contestant answering a constant (the truth, or the origin) scores near no error; "
        f"above {high:g} mm the rounding of the placed coordinates no longer maps an answer "
        "back to within 1e-9 mm"
    )


def _protocol_fields(*fields: str) -> list[tuple[str, str]]:
    """The paths below ``studies.<study>`` of the protocol's ``fields``."""
    return [("protocol", field) for field in fields]


def _cmc(settings: Mapping, protocol: object) -> Problem | None:
    return _turns_problem(
        _protocol_fields("spiral_turns", "n_frames"),
        protocol.spiral_turns,
        protocol.n_frames,
        "spiral turns",
    ) or _tilt_problem(protocol.tilt_power)


def _tilt_problem(tilt_power: float) -> Problem | None:
    """``(paths, why)`` (:data:`Problem`) when the thumb's spiral has not reached
    :data:`CMC_TILT_SHARE_BY_MIDDLE` of its RoM by the middle of the trial, or is no longer that
    share short of it, else None."""
    # Unrounded: near a bound, a share or a bound rounded to a few digits would read as the
    # bound itself, or be refused when typed back.
    share = 0.5**tilt_power
    if tilt_power > CMC_LATEST_TILT_POWER:
        return _protocol_fields("tilt_power"), (
            f"{tilt_power!r} leaves the thumb's tilt at {share!r} of its RoM by the middle of "
            f"the trial, less than {CMC_TILT_SHARE_BY_MIDDLE:g}: it would stay near its mean "
            "position and reach its RoM only in the last frames, not circle out over the "
            f"recording ({_CIRCLING_OUT}); at most {CMC_LATEST_TILT_POWER!r}"
        )
    if tilt_power < CMC_EARLIEST_TILT_POWER:
        return _protocol_fields("tilt_power"), (
            f"{tilt_power!r} takes the thumb's tilt to {share!r} of its RoM by the middle of "
            f"the trial, more than {1.0 - CMC_TILT_SHARE_BY_MIDDLE:g}: it would reach its RoM "
            "in the first frames and stay there, not circle out over the recording "
            f"({_CIRCLING_OUT}); at least {CMC_EARLIEST_TILT_POWER!r}"
        )
    return None


_CIRCLING_OUT = (
    "paper A: 'beginning from a nominal mean position and circling out to increasing angles'"
)


def _hinge(settings: Mapping, protocol: object) -> Problem | None:
    return (
        _hinge_unread_problem(settings, protocol)
        or _hinge_cycles_problem(settings, protocol)
        or _aa_ratio_problem(settings)
    )


def _unread_field(
    written: Mapping, motions: Sequence[str], motion_fields: Mapping[str, Sequence[str]]
) -> tuple[str, list[str]] | None:
    """``(field, the motions that read it)`` for the first of the fields ``written`` that some
    motion of ``motion_fields`` (motion -> the fields only some motions read) reads and none
    of ``motions`` does; None if there is none. Such a value changes no data: a user who
    writes it believes the trials follow it."""
    read = {field for motion in motions for field in motion_fields[motion]}
    for field in written:
        readers = _readers(field, motion_fields)
        if readers and field not in read:
            return field, readers
    return None


def _silenced_fields(
    grid: Mapping, amplitude_fields: Mapping[str, Sequence[str]]
) -> dict[str, str]:
    """The fields no trial of ``grid`` reads, each with its grid key: those that shape the
    trials only through an amplitude the grid sets (``amplitude_fields``: grid key -> the
    fields read only where its value is above 0) while every value of that key in ``grid`` is
    0, whatever the motion."""
    return {
        field: key
        for key, fields in amplitude_fields.items()
        if all(value == 0 for value in grid[key])
        for field in fields
    }


def _silenced_field(
    written: Mapping, grid: Mapping, amplitude_fields: Mapping[str, Sequence[str]]
) -> tuple[str, str] | None:
    """``(field, grid key)`` for the first of the fields ``written`` that no trial of ``grid``
    reads (:func:`_silenced_fields`); None if there is none. Like a field no motion of the run
    reads (:func:`_unread_field`), a user who writes it believes the trials follow it."""
    silenced = _silenced_fields(grid, amplitude_fields)
    field = next((field for field in written if field in silenced), None)
    return None if field is None else (field, silenced[field])


def _silenced_words(field: str, value: object, key: str, grid: Mapping) -> str:
    """Why ``value`` written for ``field`` changes no data: every value of the grid's ``key``,
    the amplitude through which alone it shapes the trials, is 0 (:func:`_silenced_field`)."""
    return (
        f"{value!r} is not read: every {key} of the grid is 0 (grid.{key} {list(grid[key])!r}), "
        f"and {field} shapes the trials only where {key} is above 0: a value no trial reads "
        f"changes no data; remove it, or add a value above 0 to grid.{key}"
    )


def _readers(field: str, motion_fields: Mapping[str, Sequence[str]]) -> list[str]:
    """The motions of ``motion_fields`` that read ``field``; none for a field every motion
    reads."""
    return [motion for motion, fields in motion_fields.items() if field in fields]


def _hinge_unread_problem(settings: Mapping, protocol: object) -> Problem | None:
    """A field the config writes for the joints the grid runs that no trial of theirs reads
    from where it is written: under a joint's own entry or ``all``, a field of
    :data:`~jointbench.simulate.hinge.AMPLITUDE_FIELDS` where every ``aa_ratio`` of the grid
    is 0 (no joint reads it then); under a joint's own entry, a field of
    :data:`~jointbench.simulate.hinge.MOTION_FIELDS` its motion does not read; under ``all``,
    a field that each of those joints either sets again under its own entry or, by its motion,
    does not read. Defaults are not written and not refused; nor is a field written for a
    joint the grid does not run, whose whole entry that run leaves unread."""
    overrides = settings.get("protocol") or {}
    grid = settings["grid"]
    run = list(grid["protocol"])
    for entry in [*run, "all"]:
        written = overrides.get(entry) or {}
        silenced = _silenced_field(written, grid, HINGE_AMPLITUDE_FIELDS)
        if silenced:
            field, key = silenced
            return [("protocol", entry, field)], _silenced_words(field, written[field], key, grid)
    for joint in run:
        motion = protocol.joints[joint].motion
        unread = _unread_field(overrides.get(joint) or {}, (motion,), HINGE_MOTION_FIELDS)
        if unread:
            field = unread[0]
            return [("protocol", joint, field)], _hinge_unread_words(
                field, overrides[joint][field], {motion: [joint]}
            )
    return _hinge_all_unread_problem(overrides, run, protocol)


def _hinge_all_unread_problem(
    overrides: Mapping, run: Sequence[str], protocol: object
) -> Problem | None:
    """A field under the hinge protocol ``overrides``' ``all`` that no joint of ``run`` (the
    joints the grid runs) reads from there: each sets it again under its own entry or, by its
    motion (:data:`~jointbench.simulate.hinge.MOTION_FIELDS`), does not read it."""
    for field, value in (overrides.get("all") or {}).items():
        taking = [joint for joint in run if field not in (overrides.get(joint) or {})]
        if not taking:
            again = ", ".join(f"{joint}.{field}" for joint in run)
            return [("protocol", "all", field)], (
                f"{value!r} is set again by every joint the grid runs ({again}), so no trial "
                "reads it: a value no trial reads changes no data; remove it"
            )
        readers = _readers(field, HINGE_MOTION_FIELDS)
        motions = {joint: protocol.joints[joint].motion for joint in taking}
        if readers and not set(motions.values()) & set(readers):
            unread: dict[str, list[str]] = {}
            for joint, motion in motions.items():
                unread.setdefault(motion, []).append(joint)
            return [("protocol", "all", field)], _hinge_unread_words(field, value, unread)
    return None


def _hinge_unread_words(field: str, value: object, joints: Mapping[str, Sequence[str]]) -> str:
    """Why ``value`` written for ``field`` changes no data: no motion of ``joints`` (motion ->
    the joints the grid runs that take ``field`` from where it is written) reads it."""
    every = list(dict.fromkeys(f for fields in HINGE_MOTION_FIELDS.values() for f in fields))
    unread = " nor by ".join(
        f"motion {motion!r} (joint {', '.join(map(repr, names))}), which reads "
        + (", ".join(HINGE_MOTION_FIELDS[motion]) or f"none of {', '.join(every)}")
        for motion, names in joints.items()
    )
    readers = " and ".join(map(repr, _readers(field, HINGE_MOTION_FIELDS)))
    return (
        f"{value!r} is not read by {unread}; {field} is read by motion {readers}: a value the "
        "motion does not read changes no data; remove it, or choose a motion that reads it"
    )


def _hinge_cycles_problem(settings: Mapping, protocol: object) -> Problem | None:
    """For each sine wave of each joint the grid runs (:func:`sine_waves`): its cycles
    :data:`SAMPLED_PER_TURN` over the frames, and its reach of both ends of its excursion
    (:func:`_wave_ends_problem`); named where the config sets them (:func:`placed_fields`).
    A wave whose amplitude the grid sets to 0 everywhere (the AA wave where every
    ``aa_ratio`` is 0) is not checked: no trial runs it, and the config may not set its
    cycles there (:func:`_silenced_field`)."""
    overrides = settings.get("protocol") or {}
    silenced = _silenced_fields(settings["grid"], HINGE_AMPLITUDE_FIELDS)
    for joint in settings["grid"]["protocol"]:
        hinge = protocol.joints[joint]
        for name, (cycles, phase) in sine_waves(hinge).items():
            if name in silenced:
                continue
            paths = _placed(overrides, joint, (name, "n_frames"))
            what = f"{joint} {hinge.motion} cycles"
            problem = _turns_problem(paths, cycles, hinge.n_frames, what)
            if problem:
                return problem
            # The FE wave's phase is the motion's (full extension), the AA wave's the config's.
            fields = (name,) if name == "fe_cycles" else (name, "aa_phase_deg")
            what = f"{joint} {hinge.motion} {name.split('_')[0].upper()} cycles"
            problem = _wave_ends_problem(_placed(overrides, joint, fields), cycles, phase, what)
            if problem:
                return problem
    return None


def _placed(overrides: Mapping, joint: str, fields: Sequence[str]) -> list[tuple[str, ...]]:
    """The paths below ``studies.hinge`` of ``joint``'s ``fields`` where the protocol
    ``overrides`` set them (:func:`placed_fields`)."""
    return [("protocol", *at) for at in placed_fields(overrides, joint, fields)]


def _wave_ends_problem(
    paths: list[tuple], cycles: float, phase: float, what: str
) -> Problem | None:
    """``(paths, why)`` when ``sin(2 pi cycles t + phase)``, ``t`` in ``[0, 1]``, does not reach
    both +1 and -1, else None: the trial would not reach the excursion its condition names
    (at 1e-300 FE cycles the knee never flexes, and the axis methods find the AA axis)."""
    end = phase + 2.0 * math.pi * cycles
    # Each peak's first occurrence at or after the start, within the rounding of the phases.
    firsts = [
        peak + 2.0 * math.pi * math.ceil((phase - peak) / (2.0 * math.pi) - _ROUNDING)
        for peak in (math.pi / 2.0, 3.0 * math.pi / 2.0)
    ]
    if all(first <= end + _ROUNDING * max(1.0, abs(end)) for first in firsts):
        return None
    return paths, (
        f"{cycles!r} {what} (phase {math.degrees(phase):g} deg) do not reach both ends of the "
        "excursion the condition names: the trial would not move over the range of motion its "
        "results are labelled with; a wave reaches both ends within one cycle, from an end "
        "within half of one"
    )


def _aa_ratio_problem(settings: Mapping) -> Problem | None:
    for ratio in settings["grid"]["aa_ratio"]:
        if not ratio < AA_RATIO_BELOW:
            return [("grid", "aa_ratio")], (
                f"{ratio!r} is not < {AA_RATIO_BELOW:g}: at a ratio of 1 or more "
                "abduction-adduction is as large as the flexion-extension whose axis the "
                "estimators find, so that axis is not the motion's (paper B: 0.1 to 0.7)"
            )
    return None


def _hip(settings: Mapping, protocol: object) -> Problem | None:
    return (
        _clusters_problem(protocol, HIP_CLUSTERS)
        # The frequencies first: the rotations are laid out at them, over the frame rate.
        or _frequencies_problem(protocol, HIP_FREQUENCIES)
        or _rotations_problem(protocol)
    )


def _hip_sta(settings: Mapping, protocol: object) -> Problem | None:
    return (
        _hip_sta_unread_problem(settings)
        or _clusters_problem(protocol, HIP_STA_CLUSTERS)
        or _hip_sta_turns_problem(settings, protocol)
        or _hip_sta_axes_problem(settings, protocol)
        or _sta_reach_problem(settings, protocol)
        or pelvis_poses_problem(settings, protocol)
        or _frequencies_problem(protocol, HIP_STA_FREQUENCIES)
    )


def _hip_sta_unread_problem(settings: Mapping) -> Problem | None:
    """A field the config writes that no trial of the grid reads: one of
    :data:`~jointbench.simulate.hip_sta.AMPLITUDE_FIELDS` where every ``sta_mm`` of the grid
    is 0, or of :data:`~jointbench.simulate.hip_sta.MOTION_FIELDS` that no motion of the grid
    reads. Defaults are not written and not refused."""
    grid = settings["grid"]
    motions = grid["motion"]
    written = settings.get("protocol") or {}
    silenced = _silenced_field(written, grid, HIP_STA_AMPLITUDE_FIELDS)
    if silenced:
        field, key = silenced
        return _protocol_fields(field), _silenced_words(field, written[field], key, grid)
    unread = _unread_field(written, motions, HIP_STA_MOTION_FIELDS)
    if not unread:
        return None
    field, readers = unread
    return _protocol_fields(field), (
        f"{written[field]!r} is not read by the motions the grid runs, grid.motion "
        f"{', '.join(motions)}; {field} is read by {' and '.join(readers)}: a value no motion "
        f"of the run reads changes no data; remove it, or add {' or '.join(readers)} to "
        "grid.motion"
    )


def _hip_sta_turns_problem(settings: Mapping, protocol: object) -> Problem | None:
    """:data:`SAMPLED_PER_TURN` for the skin-marker study's motions the grid runs."""
    motions = settings["grid"]["motion"]
    n_frames, star = protocol.n_frames, protocol.star_fraction
    recording = f"from {field_values(recording_values(protocol))}"
    stretches = []
    if "star_arc" in motions:
        stretches += [
            (
                _protocol_fields("star_azimuths_deg", "star_fraction", *FRAME_FIELDS),
                len(protocol.star_azimuths_deg),
                star * n_frames,
                "star sweeps (one per azimuth)",
                f"star_fraction {star!r} of the {n_frames} {recording}",
            ),
            (
                _protocol_fields("arc_turns", "star_fraction", *FRAME_FIELDS),
                protocol.arc_turns,
                (1 - star) * n_frames,
                "arc turns",
                f"1 - star_fraction {star!r} of the {n_frames} {recording}",
            ),
        ]
    if "circumduction" in motions:
        paths = _protocol_fields("circumduction_turns", *FRAME_FIELDS)
        turns = protocol.circumduction_turns
        stretches.append((paths, turns, n_frames, "circumduction turns", recording))
    return next((p for p in (_turns_problem(*stretch) for stretch in stretches) if p), None)


def _hip_sta_axes_problem(settings: Mapping, protocol: object) -> Problem | None:
    """Each motion the grid runs, at its smallest ``rom_deg``, turning a thigh marker about
    fewer than :data:`HIP_FEWEST_AXES` axes further than the floor of :func:`_turn_floor` (the
    axes: the principal ones of the thigh's rotation vectors, :func:`principal_turns_mm`);
    named at the fields that set the motion's directions (and the noise where it sets the
    floor) where it is seen about one axis, at ``grid.rom_deg`` where about none."""
    rom_deg = min(settings["grid"]["rom_deg"])
    floor, floor_words = _turn_floor(protocol.noise_mm, protocol.thigh_markers_mm)
    for motion in settings["grid"]["motion"]:
        rotation = thigh_rotation(hip_angles(motion, rom_deg, protocol))
        turns = np.sort(principal_turns_mm(rotation, protocol.thigh_markers_mm))[::-1]
        seen = int(np.sum(turns > floor))
        if seen >= HIP_FEWEST_AXES:
            continue
        # The noise is as much the culprit where it sets the floor.
        noise = ("noise_mm",) if floor == protocol.noise_mm else ()
        fields = (*HIP_STA_DIRECTIONS[motion], *noise)
        paths = _protocol_fields(*fields) if seen else [("grid", "rom_deg")]
        return paths, (
            f"the thigh's {motion} at rom_deg {rom_deg:g} turns its markers about {seen} "
            f"axis(es): about the next by {turns[seen]:.3g} mm at most, not above "
            f"{floor_words}; a hip moved about fewer than {HIP_FEWEST_AXES} axes has no single "
            f"centre (paper C's rig 'moved around at least {HIP_FEWEST_AXES} of the axes')"
        )
    return None


def principal_turns_mm(rotation: np.ndarray, markers_mm: Sequence[Sequence[float]]) -> np.ndarray:
    """:func:`largest_turn_mm` ``(3,)`` [mm] about the principal axes of the rotation vectors
    ``rotation`` ``(n, 3)`` [rad] (the eigenvectors of their ``(3, 3)`` second moment, about
    the joint), so that a swing in one plane at any azimuth turns the markers about one axis
    alone."""
    rotation = np.asarray(rotation, dtype=float)
    _, axes = np.linalg.eigh(rotation.T @ rotation)
    return largest_turn_mm(rotation @ axes, np.asarray(markers_mm, dtype=float) @ axes)


def _turns_problem(
    paths: list[tuple], turns: float, frames: float, what: str, source: str = ""
) -> Problem | None:
    """``(paths, why)`` when ``turns`` of a periodic motion over ``frames`` frames are not fewer
    than ``frames`` / :data:`SAMPLED_PER_TURN`, else None; ``source``, where the frames are
    read from several fields, gives their values after the count."""
    if turns < frames / SAMPLED_PER_TURN:
        return None
    return paths, (
        f"{turns!r} {what} over {frames:.4g} frames{f' ({source})' if source else ''} are not "
        "fewer than half those frames: the frames cannot show a motion of more than one turn "
        "per two frames (it would be recorded as a slower one than configured)"
    )


def field_values(values: Mapping[str, object]) -> str:
    """``values`` (protocol field -> value) in words, ``"duration_s 12.0, fps 50.0"``: what
    a refusal naming several fields gives of each."""
    return ", ".join(f"{field} {value!r}" for field, value in values.items())


def _sta_reach_problem(settings: Mapping, protocol: object) -> Problem | None:
    """The skin-marker study's artefact at the grid's largest ``sta_mm`` and ``rom_deg`` (it
    grows linearly with the excursion, ``sta_mm`` at ``sta_reference_deg``) reaching further
    than the farthest marker is from the joint: like noise that large
    (:func:`~jointbench.simulate.noise.largest_noise_mm`), it measures nothing, and at a
    reference excursion of 1e-300 deg it throws the markers 1e303 mm."""
    grid = settings["grid"]
    sta_mm, rom_deg = max(grid["sta_mm"]), max(grid["rom_deg"])
    reach = sta_mm * rom_deg / protocol.sta_reference_deg
    bound = largest_noise_mm(protocol.markers_from_joint())
    if reach <= bound:
        return None
    return _protocol_fields("sta_reference_deg"), (
        f"{protocol.sta_reference_deg!r} makes the grid's sta_mm {sta_mm:g} (defined at this "
        f"excursion) reach {reach:.3g} mm RMS at its rom_deg {rom_deg:g}, further than the "
        f"farthest marker is from the joint ({bound:.3g} mm): an artefact beyond the whole "
        "segment's size measures nothing; raise sta_reference_deg or lower the grid's sta_mm"
    )


def pelvis_poses_problem(settings: Mapping, protocol: object) -> Problem | None:
    """``(paths, what is wrong and why)`` (:data:`Problem`) when the skin-marker study's
    pelvis cluster cannot determine its poses in every trial of ``settings`` (the study's
    checked config) under ``protocol`` (a :class:`~jointbench.simulate.hip_sta.HipStaProtocol`),
    else None.

    The simulate job gives the one-segment centre methods the thigh in the pelvis frame, whose
    poses it fits in every frame by paper C §5's alternation of SVD poses and body-fixed
    coordinates; it refuses a trial whose fit stops before converging
    (:func:`~jointbench.simulate.hip_sta.thigh_in_pelvis_frame`). Paper C: the SVD "provides a
    unique solution provided that neither set of points is collinear and that there are at
    least 3 points", and the alternation "always converges to 15 decimals of precision in less
    than 5 iterations" -- on its rig. A cluster near a line resolves the rotation about that
    line only through its markers' distances from it, its width (:func:`line_spreads`): against
    markers that depart from one rigid shape by as much (frame 0, where the fit starts, by its
    noise; every frame by its noise and the artefact's deformation), the alternation slows and
    stops short, and so does it, through rounding alone, for a cluster much longer than wide.
    Refused, before any job: a width not above :data:`PELVIS_WIDTH_PER_DEPARTURE` times the
    markers' departure from one rigid shape (:func:`pelvis_departure`), or a length along the
    line above :data:`PELVIS_LENGTH_PER_WIDTH` times the width. Nothing is simulated.
    """
    along, width = line_spreads(protocol.pelvis_markers_mm)
    departure, deformation, worst = pelvis_departure(settings, protocol)
    if width <= PELVIS_WIDTH_PER_DEPARTURE * departure:
        keys = ["pelvis_markers_mm", "noise_mm"] if protocol.noise_mm > 0 else ["pelvis_markers_mm"]
        parts = (
            [f"the white noise noise_mm {protocol.noise_mm:g} mm"] if protocol.noise_mm > 0 else []
        )
        if deformation > 0:
            keys.append("pelvis_sta_ratio")
            share = 1.0 - protocol.sta_rigid_share
            parts.append(
                f"the artefact's deformation, {deformation:.3g} mm RMS over the frames of the "
                f"grid's sta_mm {worst['sta_mm']:g} at rom_deg {worst['rom_deg']:g} "
                f"({worst['motion']}) with pelvis_sta_ratio {protocol.pelvis_sta_ratio:g}, its "
                f"non-rigid share 1 - sta_rigid_share = {share:g}"
            )
        return _protocol_fields(*keys), (
            f"the pelvis markers' RMS distance from their common line, {width:.3g} mm, is not "
            f"above {PELVIS_WIDTH_PER_DEPARTURE:g} times their RMS departure from one rigid "
            f"shape, {departure:.3g} mm ({' and '.join(parts)}): the pelvis pose fit (paper C "
            "§5) would stop before converging in some trials, which the simulate job refuses; "
            "spread the pelvis markers further from their line, or lower the noise or the "
            "pelvis artefact"
        )
    if along > PELVIS_LENGTH_PER_WIDTH * width:
        return _protocol_fields("pelvis_markers_mm"), (
            f"the pelvis markers lie {along / width:.3g} times further along their common line "
            f"than off it (RMS {along:.3g} mm along, {width:.3g} mm off), more than "
            f"{PELVIS_LENGTH_PER_WIDTH:g} times: the pelvis pose fit (paper C §5) cannot settle "
            "the rotation about that line to its tolerance and would stop before converging, "
            "which the simulate job refuses; spread the pelvis markers further from their line"
        )
    return None


def pelvis_departure(settings: Mapping, protocol: object) -> tuple[float, float, dict]:
    """``(departure [mm], deformation [mm], condition)``: how far, RMS over markers and frames,
    the skin-marker study's recorded pelvis markers depart from one rigid shape in the grid's
    condition of the largest artefact, and that condition.

    The white noise departs by ``noise_mm`` (the RMS length of a marker's error) in every
    frame. Of the artefact, the rigid share moves the whole cluster, which its pose follows;
    the rest, ``1 - sta_rigid_share`` of its mean square, deforms it: at the hip angles
    ``theta`` of a frame its RMS is ``sqrt(1 - sta_rigid_share)`` times the pelvis amplitude
    per radian (``pelvis_sta_ratio`` times ``sta_mm`` at ``sta_reference_deg``) times
    ``|theta|`` (:mod:`jointbench.simulate.hip_sta`), here RMS over the frames of the grid's
    largest ``sta_mm`` and ``rom_deg`` in the motion that turns furthest. The two add in
    quadrature (independent). Computed from the protocol's motion, without simulating."""
    grid = settings["grid"]
    sta_mm, rom_deg = max(grid["sta_mm"]), max(grid["rom_deg"])
    per_radian = protocol.pelvis_sta_ratio * sta_mm / np.radians(protocol.sta_reference_deg)
    excursions = {
        motion: float(np.sqrt(np.mean(np.sum(hip_angles(motion, rom_deg, protocol) ** 2, -1))))
        for motion in grid["motion"]
    }
    motion = max(excursions, key=excursions.get)
    deformation = np.sqrt(1.0 - protocol.sta_rigid_share) * per_radian * excursions[motion]
    condition = {"motion": motion, "rom_deg": rom_deg, "sta_mm": sta_mm}
    return float(np.hypot(protocol.noise_mm, deformation)), float(deformation), condition


def line_spreads(markers_mm: Sequence[Sequence[float]]) -> tuple[float, float]:
    """``(along, off)`` [mm]: the RMS distance of markers ``markers_mm`` ``(n, 3)`` [mm] from
    their centroid along their best-fit line, and from that line (the square root of the
    centred markers' first, and of their other two, squared singular values over ``n``)."""
    markers = np.asarray(markers_mm, dtype=float)
    singular = np.linalg.svd(markers - markers.mean(axis=0), compute_uv=False)
    along = float(singular[0] / np.sqrt(len(markers)))
    return along, float(np.sqrt(np.sum(singular[1:] ** 2) / len(markers)))


def _clusters_problem(protocol: object, names: Sequence[str]) -> Problem | None:
    """The first of the clusters ``names`` (protocol fields) that :func:`cluster_problem`
    refuses at the protocol's ``noise_mm``, naming ``noise_mm`` too where the cluster is
    refused only beside that noise."""
    for name in names:
        problem = cluster_problem(getattr(protocol, name), protocol.noise_mm)
        if problem:
            alone = cluster_problem(getattr(protocol, name), 0.0)
            return _protocol_fields(name, *(() if alone else ("noise_mm",))), problem
    return None


def _frequencies_problem(protocol: object, names: Sequence[str]) -> Problem | None:
    """The first of the frequencies ``names`` (protocol fields, each a number or one per axis)
    not above 0 and below half the protocol's frame rate."""
    nyquist = protocol.fps / 2
    for name in names:
        value = getattr(protocol, name)
        per_axis = isinstance(value, Sequence)
        for part in value if per_axis else [value]:
            if not 0 < part < nyquist:
                shown = f"{part!r} (of {list(value)!r})" if per_axis else f"{part!r}"
                return _protocol_fields(name, "fps"), (
                    f"{shown} is not > 0 and < {nyquist:g} Hz (half the frame rate, fps "
                    f"{protocol.fps:g}): a motion has a positive frequency (set its amplitude "
                    "to 0 for none), and the frames cannot show one at half the frame rate or "
                    "faster"
                )
    return None


def _rotations_problem(protocol: object) -> Problem | None:
    """Fewer than :data:`HIP_FEWEST_AXES` of the hip rig's rotations moving
    (:func:`largest_turn_mm`), in words naming those configured that do not move and why."""
    t = np.arange(protocol.n_frames) / protocol.fps
    turns = largest_turn_mm(distal_rotation(protocol, t), protocol.distal_markers_mm)
    configured = [name for name in HIP_ROTATIONS if getattr(protocol, name) != 0]
    floor, floor_words = _turn_floor(protocol.noise_mm, protocol.distal_markers_mm)
    seen = [n for n, turn in zip(HIP_ROTATIONS, turns, strict=True) if turn > floor]
    if len(seen) >= HIP_FEWEST_AXES:
        return None
    which = f"only {', '.join(seen)}" if seen else "none"
    unseen = [name for name in configured if name not in seen]
    detail, keys = "", list(HIP_ROTATIONS)
    if unseen:
        # The recording's length is as much the culprit as the rotations configured in it.
        keys += ["n_frames", "fps"]
        turned = ", ".join(f"{n} {turns[HIP_ROTATIONS.index(n)]:.3g} mm" for n in unseen)
        detail = (
            f"; the largest turn of a distal marker over the recording ({protocol.n_frames} "
            f"frames at {protocol.fps:g} fps), {turned}, is not above {floor_words}: "
            "too small an amplitude, too slow a frequency or (the cross swing) too long a rise, "
            "cross_swing_rise_s, to be seen"
        )
    return _protocol_fields(*keys), (
        f"{which} moving: the rig must rotate about at least {HIP_FEWEST_AXES} of the axes "
        "(paper C: the second segment 'moved around at least 2 of the axes'); about one, its "
        f"centre lies anywhere on that axis{detail}"
    )


def _turn_floor(noise_mm: float, markers_mm: Sequence[Sequence[float]]) -> tuple[float, str]:
    """``(floor [mm], it in words)``: the turn of a marker of ``markers_mm`` (relative to the
    joint) a rotation must exceed to be seen, the largest of the marker noise ``noise_mm``,
    :data:`HIP_RESOLUTION_MM` (which sets it without noise) and the rounding of the markers'
    coordinates (which passes it only for markers ten kilometres from the joint)."""
    rounding = _ROUNDING * float(np.abs(np.asarray(markers_mm, dtype=float)).max())
    return max(
        (noise_mm, f"the marker noise noise_mm ({noise_mm:g} mm)"),
        (
            HIP_RESOLUTION_MM,
            f"HIP_RESOLUTION_MM ({HIP_RESOLUTION_MM:g} mm), the least turn a recording "
            f"resolves (noise_mm is {noise_mm:g} mm)",
        ),
        (rounding, f"the rounding of the markers' coordinates ({rounding:.3g} mm)"),
        key=lambda candidate: candidate[0],
    )


def largest_turn_mm(rotation: np.ndarray, markers_mm: Sequence[Sequence[float]]) -> np.ndarray:
    """``(3,)`` [mm]: for each component ``k`` of the rotation vectors ``rotation`` ``(n, 3)``
    [rad] (about axis ``k`` through the joint), the farthest any of ``markers_mm`` ``(m, 3)``
    (relative to the joint) is turned by that component alone in any of the ``n`` poses: the
    chord ``2 r sin(|angle| / 2)`` at the marker's distance ``r`` from the axis, the angle
    capped at a half turn."""
    markers = np.asarray(markers_mm, dtype=float)
    angles = np.minimum(np.abs(np.asarray(rotation, dtype=float)).max(axis=0), np.pi)
    # Distance from axis k: the marker's length with its k-th coordinate left out.
    radii = np.sqrt(np.sum(markers**2, axis=1)[:, None] - markers**2).max(axis=0)
    return 2.0 * radii * np.sin(angles / 2.0)


def cluster_problem(markers_mm: Sequence[Sequence[float]], noise_mm: float) -> str | None:
    """What keeps ``markers_mm`` (``(n, 3)`` [mm], ``n >= 3``) from giving a rigid body's pose,
    or None: two markers in one place, or markers on one line, or so near one that their RMS
    distance from their best-fit line is no more than the marker noise ``noise_mm`` (the RMS
    length of a marker's error): the rotation about that line is then unresolved (an error of a
    radian or more), and every pose fit of the cluster with it."""
    markers = np.asarray(markers_mm, dtype=float)
    for (i, a), (j, b) in itertools.combinations(enumerate(markers, start=1), 2):
        if np.array_equal(a, b):
            return f"markers {i} and {j} coincide: a rigid body's pose needs 3 distinct markers"
    along, off_line = line_spreads(markers)
    unresolved = "so the rotation about that line, and the cluster's pose, cannot be resolved"
    # Relative to the cluster's size: markers on one line leave rounding error off it.
    if off_line <= _ROUNDING * along:
        return f"the markers are collinear (on one line), {unresolved}"
    if off_line <= noise_mm:
        return (
            f"the markers are nearly collinear: their RMS distance from their common line is "
            f"{off_line:.3g} mm, not above the marker noise noise_mm ({noise_mm:g} mm), "
            + unresolved
        )
    return None


_ROUNDING = 1e-9


_CHECKS: dict[str, Callable[[Mapping, object], Problem | None]] = {
    "cmc": _cmc,
    "hinge": _hinge,
    "hip": _hip,
    "hip_sta": _hip_sta,
}
