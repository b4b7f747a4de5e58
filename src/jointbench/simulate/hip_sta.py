"""Hip functional calibration on skin markers: pelvis and thigh clusters with soft-tissue artefact.

The three papers test their estimators against white marker noise. On skin markers the error
that dominates is soft-tissue artefact (STA): "STA is greater than the instrumental error
associated with stereophotogrammetry, has a frequency content similar to the actual bone
movement, is task dependent and not reproducible among subjects and, of lower limb segments, is
greatest at the thigh" (Leardini et al. 2005, Gait Posture 21:212). This study simulates a
functional hip trial of a standing subject and corrupts it with an STA model from the
literature, then with the white noise of paper C. Every choice below is a field of
:class:`HipStaProtocol`.

World frame (ours): ``x`` anterior, ``y`` left, ``z`` up; the right hip joint centre (HJC) at
``joint_mm``. Both body frames coincide with the world at frame 0 (the neutral posture), so the
true centre in them is ``joint_mm`` (paper C's convention, as in :mod:`jointbench.simulate.hip`).

Markers (relative to the HJC) [mm]:

* pelvis: right and left ASIS and PSIS, the pelvis markers of clinical gait models (Davis et al.
  1991, Hum Mov Sci 10:575). The ASIS sit where Bell et al. (1989, Hum Mov Sci 8:3) place the
  HJC from them: "30% distal, 14% medial, and 22% posterior to the ASIS" as shares of the
  inter-ASIS distance, taken as 240 mm (our choice, an adult pelvis); the PSIS 160 mm behind
  the ASIS, 90 mm apart, 13 mm higher (our choice);
* thigh: four skin markers on the lateral thigh, two proximal and two distal, 150–350 mm below
  the HJC and 80–95 mm lateral to it, the four-marker thigh cluster of the bone-pose literature
  (Cereatti et al. 2006, J NeuroEng Rehabil 3:7; Cappozzo et al. 1995, Clin Biomech 10:171).

Motion. Hip angles as a rotation vector of the thigh relative to the pelvis, flexion ``f``
about the medio-lateral axis and abduction ``a`` about the antero-posterior axis (rotation
vector ``(-a, -f, 0)`` for the right hip, so that flexion brings the knee forward and abduction
moves it laterally); no axial rotation. The thigh's excursion from neutral is the condition's
``rom_deg``. Two motions, as the grid's ``motion``:

* ``star_arc``, Camomilla et al. (2006, J Biomech 39:1096): "a star-like sequence of
  flexion–extension/abduction–adduction movements on vertical planes of different orientation
  followed by a circumduction" -- each of the ``star_azimuths_deg`` planes (0° flexion,
  90° abduction, 180° extension) swept out to ``rom_deg`` and back, ``(1 - cos)/2`` in time,
  over the first ``star_fraction`` of the trial, then an arc: ``arc_turns`` circumductions at
  ``rom_deg``;
* ``circumduction``: ``circumduction_turns`` flexion/abduction circumductions at ``rom_deg``
  over the whole trial.

Each arc's amplitude rises from and returns to neutral as ``1 - (2u - 1)^8`` over its time
``u`` in [0, 1], so both motions start (and end) in the neutral posture. The pelvis sways
slightly, as a subject standing on one leg does: ``pelvis_sway_mm`` / ``pelvis_sway_deg``
amplitudes per world axis, ``sin(2 pi f t)`` at ``pelvis_sway_hz`` (our choices), about the
pelvis markers' centroid.

Soft-tissue artefact. Each marker's displacement relative to its bone, in the bone's frame, is a
linear function of the hip angles: Bonci et al. (2014, J Biomech 47:2354) model thigh STA on the
hypotheses "that the artefact mostly depends on skin sliding, and thus on the angles of hip
and knee" and "that the relevant relationship is linear" (no knee motion here, so the hip
angles alone; Camomilla et al. 2013, J Biomech 46:625, drive thigh STA by hip kinematics the same
way). Following the decomposition of Dumas et al. (2014, J Biomech 47:476) into the cluster's
rigid motion and its deformation, the displacement of marker ``i`` is

    s_i(t) = sum_k theta_k(t) [ rho^1/2 g (t_k + w_k x (q_i - q_mean)) + (1 - rho)^1/2 h n_ik ]

over the hip angles ``theta_k`` (flexion, abduction) [rad]: a rigid part (a translation
``t_k`` and a small rotation ``w_k`` of the whole cluster per radian) and a non-rigid part
(``n_ik``, with its rigid component projected out). The rigid part dominates: "within the
ARFs, marker cluster STA is governed by rigid-body translations and rotations rather than
deformations" (Andersen et al. 2012, Gait Posture 35:606; likewise Barré et al. 2017, J Biomech
62:21). The share ``rho`` of the mean squared displacement it carries is not one published
number; we take ``sta_rigid_share`` = 0.8.

Each trial is a subject: its coefficients ``t_k``, ``w_k`` (times the cluster's RMS radius) and
``n_ik`` are independent standard normal draws, then ``g`` and ``h`` scale the two parts so
that, at a hip excursion of ``sta_reference_deg`` in any direction of the flexion–abduction
plane, the RMS displacement over the cluster's markers and over directions is exactly the
condition's ``sta_mm`` (each part carrying its share). Thigh STA of "up to 27.0 mm" (walking,
Andersen et al. 2012) and RMS values of 2.5–23.0 mm (thigh, step up/down; Camomilla et al.
2009, J Biomech 42:931) are reported; the grid spans 0 (white noise only) to 30 mm at
``sta_reference_deg`` = 30°, a typical hip excursion of those tasks (our choice). STA is zero
in the neutral posture (frame 0) and grows linearly with the excursion, so a wider range of
motion gives more rotation and more artefact (Begon et al. 2007, Gait Posture 25:353: "noise
increases as a function of the range of a motion"). The pelvis markers get the same model with
the amplitude ``pelvis_sta_ratio`` times the thigh's (0 by default: the thigh's artefact is the
largest, and the studies above model the thigh only).

White noise: :func:`jointbench.simulate.noise.isotropic_noise` with ``noise_mm`` = 1.7 mm, paper
C's "sqrt(tr Wy) = 1.7 mm", on every marker and frame, after the STA.

Random numbers: every condition's trial ``k`` uses the same generator (``seed_keys`` is empty),
drawing the thigh's STA coefficients, then the pelvis's, then the noise of every frame. Trial
``k`` is therefore the same subject with the same camera noise in every condition, and the
conditions differ only in what they set (STA amplitude, range, motion): their differences are
paired.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Annotated

import numpy as np

from jointbench.declared import Length, NonNegative, Positive, Range, Vector3
from jointbench.declared import check_fields as check_declared
from jointbench.estimators.segment_poses import stopped_fit
from jointbench.geometry import rotation_matrix, skew
from jointbench.numerics.poses import fit_rigid_poses
from jointbench.screening import to_local
from jointbench.simulate import GridValues, Study, Trials
from jointbench.simulate.hip import _jsonable, _triple, _triples
from jointbench.simulate.noise import check_noise_level, isotropic_noise, largest_noise_mm
from jointbench.simulate.ranges import (
    Angle,
    Duration,
    FrameRate,
    LabPoint,
    MarkerOffset,
    Rotations,
    check_marker_offsets,
)

__all__ = [
    "AMPLITUDE_FIELDS",
    "FRAME_FIELDS",
    "MOTIONS",
    "MOTION_FIELDS",
    "STUDY",
    "HipStaProtocol",
    "hip_angles",
    "nominal_recording",
    "recording_values",
    "simulate",
    "sta_displacements",
    "sta_field",
    "thigh_in_pelvis_frame",
    "thigh_rotation",
]

MOTIONS = ("star_arc", "circumduction")
#: The fields of :class:`HipStaProtocol` each motion reads that the other does not
#: (:func:`hip_angles`); every other field both read. The config refuses one of these that no
#: motion of its grid reads (it would change no data):
#: :func:`jointbench.configuration.bounds.study_problem`.
MOTION_FIELDS: dict[str, tuple[str, ...]] = {
    "star_arc": ("star_azimuths_deg", "star_fraction", "arc_turns"),
    "circumduction": ("circumduction_turns",),
}
#: The fields of :class:`HipStaProtocol` that shape the trials only through the soft-tissue
#: artefact, by the grid key that sets its amplitude: where ``sta_mm`` is 0 every marker's
#: artefact is 0 whatever its reference excursion, rigid share or pelvis ratio
#: (:func:`sta_field`; its draws, and so the noise after them, do not depend on them either).
#: Where every ``sta_mm`` of the grid is 0 no trial reads them; the config refuses one written
#: there, as it does a field no motion of the grid reads:
#: :func:`jointbench.configuration.bounds.study_problem`.
AMPLITUDE_FIELDS: dict[str, tuple[str, ...]] = {
    "sta_mm": ("sta_reference_deg", "sta_rigid_share", "pelvis_sta_ratio"),
}
#: The protocol fields a trial's frames are read from (:attr:`HipStaProtocol.n_frames`).
FRAME_FIELDS = ("duration_s", "fps")
_CONDITION_KEYS = ("motion", "rom_deg", "sta_mm")


@dataclass(frozen=True)
class HipStaProtocol:
    """Modelling choices of the skin-marker hip study; every field can be set from the config.

    Geometry [mm], world frame at frame 0 (``x`` anterior, ``y`` left, ``z`` up): ``joint_mm``
    the right HJC; ``pelvis_markers_mm`` (RASI, LASI, RPSI, LPSI) and ``thigh_markers_mm``
    relative to it. Recording: ``duration_s`` at ``fps``, white noise ``noise_mm`` =
    ``sqrt(tr W_y)``. Motion: ``star_azimuths_deg`` (0 flexion, 90 abduction, 180 extension),
    ``star_fraction`` of the trial for the star, ``arc_turns`` after it;
    ``circumduction_turns`` for the circumduction; pelvis sway ``pelvis_sway_mm``,
    ``pelvis_sway_deg`` per world axis at ``pelvis_sway_hz``. STA: amplitude defined at
    ``sta_reference_deg``, rigid share ``sta_rigid_share``, pelvis amplitude
    ``pelvis_sta_ratio`` times the thigh's; none of these three shapes a trial without
    artefact (``sta_mm`` 0, :data:`AMPLITUDE_FIELDS`). See the module docstring for the
    formulas.
    """

    duration_s: Duration = 12.0
    fps: FrameRate = 50.0
    noise_mm: NonNegative = 1.7
    joint_mm: LabPoint = (0.0, -90.0, 900.0)
    # Bell et al. (1989) from the ASIS, inter-ASIS distance 240 mm; PSIS our choice.
    pelvis_markers_mm: Annotated[tuple[MarkerOffset, ...], Length(3)] = (
        (52.8, -33.6, 72.0),
        (52.8, 206.4, 72.0),
        (-107.2, 41.4, 85.0),
        (-107.2, 131.4, 85.0),
    )
    # Four skin markers on the lateral right thigh (lateral is -y).
    thigh_markers_mm: Annotated[tuple[MarkerOffset, ...], Length(3)] = (
        (40.0, -95.0, -150.0),
        (-40.0, -95.0, -170.0),
        (45.0, -85.0, -330.0),
        (-35.0, -80.0, -350.0),
    )
    star_azimuths_deg: Annotated[tuple[Angle, ...], Length(1)] = (0.0, 45.0, 90.0, 135.0, 180.0)
    star_fraction: Annotated[float, Range(0, 1, exclusive_minimum=True)] = 0.7
    arc_turns: Positive = 1.0
    circumduction_turns: Positive = 3.0
    pelvis_sway_mm: LabPoint = (8.0, 8.0, 4.0)
    pelvis_sway_deg: Rotations = (2.0, 2.0, 3.0)
    pelvis_sway_hz: Vector3 = (0.13, 0.21, 0.17)
    sta_reference_deg: Annotated[float, Range(0, 180, exclusive_minimum=True)] = 30.0
    sta_rigid_share: Annotated[float, Range(0, 1)] = 0.8
    pelvis_sta_ratio: NonNegative = 0.0

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        set_(self, "pelvis_markers_mm", _triples(self.pelvis_markers_mm))
        set_(self, "thigh_markers_mm", _triples(self.thigh_markers_mm))
        set_(self, "star_azimuths_deg", tuple(float(a) for a in self.star_azimuths_deg))
        for name in ("joint_mm", "pelvis_sway_mm", "pelvis_sway_deg", "pelvis_sway_hz"):
            set_(self, name, _triple(getattr(self, name)))
        check_marker_offsets("pelvis_markers_mm", self.pelvis_markers_mm)
        check_marker_offsets("thigh_markers_mm", self.thigh_markers_mm)
        clusters = ("pelvis_markers_mm", "thigh_markers_mm")
        check_noise_level("noise_mm", self.noise_mm, self.markers_from_joint(), clusters)

    @classmethod
    def from_config(cls, overrides: Mapping[str, object] | None = None) -> HipStaProtocol:
        """Defaults updated by the config's ``protocol`` mapping."""
        overrides = dict(overrides or {})
        check_declared(cls, overrides)
        return cls(**overrides)

    @property
    def n_frames(self) -> int:
        """Frames of a trial: ``round(duration_s * fps)``."""
        return round(self.duration_s * self.fps)

    def markers_from_joint(self) -> np.ndarray:
        """Every marker relative to the HJC ``(n_pelvis + n_thigh, 3)`` [mm]."""
        return np.array([*self.pelvis_markers_mm, *self.thigh_markers_mm])


def _arc_envelope(u: np.ndarray) -> np.ndarray:
    """``1 - (2u - 1)^8``: 0 at ``u`` = 0 and 1, near 1 in between."""
    return 1.0 - (2.0 * u - 1.0) ** 8


def _circle(u: np.ndarray, turns: float, rom: float) -> np.ndarray:
    """Flexion and abduction ``(n, 2)`` [rad] of ``turns`` circumductions at ``rom`` [rad]."""
    phase = 2.0 * np.pi * turns * u
    return rom * _arc_envelope(u)[:, None] * np.stack([np.cos(phase), np.sin(phase)], axis=-1)


def hip_angles(motion: str, rom_deg: float, protocol: HipStaProtocol) -> np.ndarray:
    """Flexion and abduction ``(n_frames, 2)`` [rad] of ``motion`` at excursion ``rom_deg``."""
    if motion not in MOTIONS:
        raise ValueError(f"motion must be one of {', '.join(MOTIONS)}, got {motion!r}")
    n = protocol.n_frames
    u = np.arange(n) / max(n - 1, 1)
    rom = np.radians(rom_deg)
    if motion == "circumduction":
        return _circle(u, protocol.circumduction_turns, rom)
    angles = np.empty((n, 2))
    star = u < protocol.star_fraction
    # The star: each plane swept out and back in an equal share of the star's time.
    s = u[star] / protocol.star_fraction * len(protocol.star_azimuths_deg)
    plane = np.minimum(s.astype(int), len(protocol.star_azimuths_deg) - 1)
    azimuth = np.radians(np.asarray(protocol.star_azimuths_deg))[plane]
    reach = rom * (1.0 - np.cos(2.0 * np.pi * (s - plane))) / 2.0
    angles[star] = reach[:, None] * np.stack([np.cos(azimuth), np.sin(azimuth)], axis=-1)
    arc_u = (u[~star] - protocol.star_fraction) / (1.0 - protocol.star_fraction)
    angles[~star] = _circle(arc_u, protocol.arc_turns, rom)
    return angles


def _rigid_basis(body: np.ndarray) -> np.ndarray:
    """Orthonormal basis ``(6, n * 3)`` of the cluster's infinitesimal rigid motions (three
    translations, three rotations about the centroid) of markers ``body`` ``(n, 3)``."""
    offsets = body - body.mean(axis=0)
    translations = np.tile(np.eye(3), (len(body), 1)).T  # (3, n*3)
    rotations = -np.concatenate(skew(offsets), axis=0).T  # w x r = -[r]x w, (3, n*3)
    q, _ = np.linalg.qr(np.concatenate([translations, rotations]).T)
    return q[:, : np.linalg.matrix_rank(np.concatenate([translations, rotations]))].T


def sta_field(
    body: np.ndarray,
    rng: np.random.Generator,
    amplitude_mm: float,
    reference_deg: float,
    rigid_share: float,
) -> np.ndarray:
    """One subject's STA coefficients ``(2, n, 3)`` [mm/rad]: the displacement of each of the
    markers ``body`` ``(n, 3)`` [mm] per radian of flexion (row 0) and abduction (row 1).

    Draws ``2 * 6 + 2 * n * 3`` standard normal numbers from ``rng`` (rigid coefficients, then
    non-rigid) whatever the amplitude, so the draws that follow do not depend on it. Scaled so
    that at ``reference_deg`` in any direction of the flexion–abduction plane the RMS
    displacement over markers and directions is ``amplitude_mm``, the rigid part carrying
    ``rigid_share`` of its square (see the module docstring).
    """
    n = len(body)
    offsets = body - body.mean(axis=0)
    radius = float(np.sqrt(np.mean(np.sum(offsets**2, axis=1))))
    translation = rng.standard_normal((2, 3))
    rotation = rng.standard_normal((2, 3)) / radius
    rigid = translation[:, None, :] + np.cross(rotation[:, None, :], offsets[None])
    basis = _rigid_basis(body)
    free = rng.standard_normal((2, n * 3))
    deformation = (free - (free @ basis.T) @ basis).reshape(2, n, 3)

    def unit(field: np.ndarray) -> np.ndarray:
        # RMS over markers and over directions (cos, sin) of the flexion–abduction plane.
        return field / np.sqrt(np.sum(field**2) / (2.0 * n))

    per_radian = amplitude_mm / np.radians(reference_deg)
    return per_radian * (
        np.sqrt(rigid_share) * unit(rigid) + np.sqrt(1.0 - rigid_share) * unit(deformation)
    )


def sta_displacements(field: np.ndarray, angles: np.ndarray) -> np.ndarray:
    """Displacements ``(n_frames, n, 3)`` [mm, bone frame] of coefficients ``field``
    ``(2, n, 3)`` [mm/rad] at hip ``angles`` ``(n_frames, 2)`` [rad]."""
    return np.einsum("fk,kni->fni", angles, field)


def thigh_rotation(angles: np.ndarray) -> np.ndarray:
    """The thigh's rotation vectors ``(n_frames, 3)`` [rad] relative to the pelvis (pelvis
    frame) at hip ``angles`` ``(n_frames, 2)`` [rad]: flexion about ``-y``, abduction about
    ``-x``."""
    flexion, abduction = angles[:, 0], angles[:, 1]
    return np.stack([-abduction, -flexion, np.zeros_like(flexion)], axis=-1)


def nominal_recording(
    angles: np.ndarray, protocol: HipStaProtocol
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Bone poses of a trial: pelvis and thigh rotations ``(n_frames, 3, 3)`` and translations
    ``(n_frames, 3)`` [mm] mapping body-fixed points (= world at frame 0) to the world."""
    t = np.arange(len(angles)) / protocol.fps
    joint = np.asarray(protocol.joint_mm)
    pelvis_body = joint + np.asarray(protocol.pelvis_markers_mm)
    sway = np.sin(2.0 * np.pi * np.asarray(protocol.pelvis_sway_hz) * t[:, None])
    r0 = rotation_matrix(np.radians(protocol.pelvis_sway_deg) * sway)
    centroid = pelvis_body.mean(axis=0)
    d0 = centroid + np.asarray(protocol.pelvis_sway_mm) * sway - r0 @ centroid
    relative = rotation_matrix(thigh_rotation(angles))
    r1 = r0 @ relative
    # The ball joint: R0 c + d0 = R1 c + d1.
    d1 = r0 @ joint + d0 - r1 @ joint
    return r0, d0, r1, d1


def _placed(body: np.ndarray, rotation: np.ndarray, translation: np.ndarray) -> np.ndarray:
    """Body-frame points ``(n_frames, n, 3)`` to the world."""
    return body @ np.swapaxes(rotation, -1, -2) + translation[:, None, :]


def thigh_in_pelvis_frame(pelvis: np.ndarray, thigh: np.ndarray) -> np.ndarray:
    """Thigh markers ``(n_trials, n_frames, n, 3)`` [mm] in the pelvis frame, as a lab gives them
    to a one-segment centre method: per trial, the pelvis cluster's pose in every frame is
    fitted from its recorded markers ``(n_trials, n_frames, 4, 3)`` (paper C §5,
    :func:`~jointbench.numerics.poses.fit_rigid_poses`: the frame coincides with the world at frame
    0), and the thigh markers are carried into it.

    Any other pelvis-fixed frame differs from this one by a constant rigid motion, to which
    the centre methods are invariant; this one makes the true centre the same point,
    ``joint_mm``, as in the two-segment methods' frame-0 body frames. The pelvis markers'
    noise and artefact go into the frame, as they do in the lab. A pelvis pose fit that stops
    before converging (a protocol whose pelvis cluster is thin or small against its noise)
    is refused, naming the trial: the frame, and every answer in it, would depend on the first
    frame. The config's check refuses such a protocol before any job, from its pelvis cluster,
    noise and artefact (:func:`jointbench.configuration.bounds.pelvis_poses_problem`); this
    refusal stands for what that check does not foresee.
    """
    fit = fit_rigid_poses(pelvis)
    if not fit.converged.all():
        trial = int(np.flatnonzero(~fit.converged)[0])
        stopped = stopped_fit("proximal", fit.iterations[trial], fit.change_mm[trial])
        raise ValueError(
            f"hip_sta trial {trial}: {stopped} (the pelvis frame the thigh markers are given "
            "in): the protocol's pelvis cluster does not determine its poses"
        )
    rotation, translation = fit.rotation, fit.translation
    return np.stack(
        [
            to_local(r, t, markers)
            for r, t, markers in zip(rotation, translation, thigh, strict=True)
        ]
    )


def simulate(
    condition: Mapping[str, object], protocol: HipStaProtocol, rngs: Sequence[np.random.Generator]
) -> Trials:
    """Trials of one condition: ``motion`` (one of :data:`MOTIONS`), ``rom_deg`` (the thigh's
    excursion from neutral [deg]) and ``sta_mm`` (the STA amplitude at
    ``protocol.sta_reference_deg`` [mm]), one generator per trial.

    Returns :class:`~jointbench.simulate.Trials` with ``segments["proximal"]`` (pelvis)
    ``(n_trials, n_frames, 4, 3)`` and ``segments["distal"]`` (thigh) ``(n_trials, n_frames, 4,
    3)`` [mm] in the world frame, ``segments["thigh_in_pelvis"]`` the thigh markers in the
    pelvis frame (:func:`thigh_in_pelvis_frame`), and ``truth["center"]`` the HJC in the body
    frames shared at frame 0.
    """
    unknown = set(condition) - set(_CONDITION_KEYS)
    if unknown:
        raise ValueError(
            f"unknown hip_sta condition keys {sorted(unknown)}; known: {', '.join(_CONDITION_KEYS)}"
        )
    motion = str(condition.get("motion", MOTIONS[0]))
    rom_deg = float(condition.get("rom_deg", 30.0))
    sta_mm = float(condition.get("sta_mm", 0.0))
    if not (np.isfinite(rom_deg) and 0 < rom_deg <= 90):
        raise ValueError(f"rom_deg must be in (0, 90], got {rom_deg!r}")
    if not (np.isfinite(sta_mm) and sta_mm >= 0):
        raise ValueError(f"sta_mm must be finite and >= 0, got {sta_mm!r}")

    angles = hip_angles(motion, rom_deg, protocol)
    r0, d0, r1, d1 = nominal_recording(angles, protocol)
    joint = np.asarray(protocol.joint_mm)
    pelvis_body = joint + np.asarray(protocol.pelvis_markers_mm)
    thigh_body = joint + np.asarray(protocol.thigh_markers_mm)
    n_pelvis = len(pelvis_body)
    share, reference = protocol.sta_rigid_share, protocol.sta_reference_deg
    trials = []
    for rng in rngs:
        thigh_sta = sta_field(thigh_body, rng, sta_mm, reference, share)
        pelvis_sta = sta_field(
            pelvis_body, rng, protocol.pelvis_sta_ratio * sta_mm, reference, share
        )
        pelvis = _placed(pelvis_body + sta_displacements(pelvis_sta, angles), r0, d0)
        thigh = _placed(thigh_body + sta_displacements(thigh_sta, angles), r1, d1)
        markers = np.concatenate([pelvis, thigh], axis=1)
        trials.append(markers + isotropic_noise(rng, markers.shape[:2], protocol.noise_mm))
    stacked = np.stack(trials)
    pelvis, thigh = stacked[:, :, :n_pelvis], stacked[:, :, n_pelvis:]
    parameters = {
        **asdict(protocol),
        "n_frames": protocol.n_frames,
        "motion": motion,
        "rom_deg": rom_deg,
        "sta_mm": sta_mm,
    }
    return Trials(
        segments={
            "proximal": pelvis,
            "distal": thigh,
            "thigh_in_pelvis": thigh_in_pelvis_frame(pelvis, thigh),
        },
        truth={"center": [float(x) for x in joint]},
        parameters=_jsonable(parameters),
    )


def frame_count(condition: Mapping[str, object], protocol: HipStaProtocol) -> int:
    """The frames of every trial of ``condition`` under ``protocol``: the protocol's, whatever
    the motion, excursion or artefact."""
    return protocol.n_frames


def frame_keys(condition: Mapping[str, object], overrides: Mapping) -> list[tuple[str, str]]:
    """Where the config sets the frames :func:`frame_count` gives: :data:`FRAME_FIELDS`."""
    return [("protocol", field) for field in FRAME_FIELDS]


def recording_values(protocol: HipStaProtocol) -> dict[str, float]:
    """The values of :data:`FRAME_FIELDS` under ``protocol``, which a refusal of a count of
    frames gives, since the count is neither one of them."""
    return {field: getattr(protocol, field) for field in FRAME_FIELDS}


def frame_values(condition: Mapping[str, object], protocol: HipStaProtocol) -> dict[str, float]:
    """The values of the fields :func:`frame_keys` names (:func:`recording_values`), whatever
    the condition."""
    return recording_values(protocol)


STUDY = Study(
    name="hip_sta",
    # The two-segment estimators see both clusters as recorded; the one-segment centre methods
    # the thigh in the pelvis frame, with the same true centre.
    kind="joint_center",
    grid_keys=_CONDITION_KEYS,
    # Trial k is the same subject and camera noise in every condition (module docstring).
    seed_keys=(),
    segments=("proximal", "distal"),
    more_kinds={"center": ("thigh_in_pelvis",)},
    protocol_class=HipStaProtocol,
    simulate=simulate,
    frame_count=frame_count,
    frame_keys=frame_keys,
    frame_values=frame_values,
    grid_spec={
        "motion": GridValues(
            str,
            choices=MOTIONS,
            label="motion",
            text="{}",
            names={"star_arc": "star-arc", "circumduction": "circumduction"},
        ),
        "rom_deg": GridValues(
            float, minimum=0, exclusive_minimum=True, maximum=90, label="RoM", text="RoM {:g}°"
        ),
        # As for white noise: an artefact beyond the farthest marker's distance from the joint
        # moves markers over more than the whole segment.
        "sta_mm": GridValues(
            float,
            minimum=0,
            maximum=lambda p: largest_noise_mm(p.markers_from_joint()),
            label="STA amplitude",
            text="STA {:g} mm",
        ),
    },
    title="hip on skin markers",
)
