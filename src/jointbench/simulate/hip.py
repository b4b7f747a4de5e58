"""Two-segment rig swung like a pendulum: the experiment of paper C (§8), simulated.

Paper C: "One of the authors held by hand a two segment mechanical test rig on which the
markers were mounted and swung it like a pendulum making sure that over the 20 second time
interval the second segment moved around at least 2 of the axes." 1200 frames (60 Hz), 3
markers per segment, "The individual sets of 3 markers were about 100-200mm apart and the two
sets were about 1m apart with the joint halfway between", marker noise ``sqrt(tr W_y)`` =
1.7 mm. The motion itself is not published; everything below is our choice, kept in
:class:`HipProtocol`.

World frame (ours): ``z`` up. The ball joint sits at ``joint_mm`` at frame 0; the proximal
(hand-held) segment's markers are about 500 mm above it, the distal (swinging) segment's about
500 mm below, each cluster a scalene triangle with sides of 150–200 mm. Both body-fixed frames
coincide with the world at frame 0 (paper C's convention), so the true centre, the ``truth``,
is ``joint_mm`` in that frame.

Motion, everything starting from rest at frame 0 (the holder steadies the rig, then lets the
lower segment swing), so that, as in the paper, the first frames span very little rotation
(Nt = 4 frames is 0.05 s):

* proximal (hand): a slow wandering translation, ``A_k sin(2 pi f_k t)`` per axis (tens of mm,
  0.1–0.3 Hz), and small rotations about the grip (the proximal cluster's centroid), rotation
  vector components ``A_k (1 - cos(2 pi f_k t)) / 2`` (a few degrees, 0.1–0.3 Hz);
* distal, relative to the proximal segment, a rotation vector (proximal frame) of: the main
  swing released from rest at one extreme, ``A (cos(2 pi f t) - 1)`` (a 2A arc at the
  pendulum frequency of a ~0.5 m segment, ~0.75 Hz); a cross swing about the second horizontal
  axis that the hand builds up, ``B (1 - exp(-t / tau)) sin(2 pi f2 t)``; and a small twist
  about the long axis, ``C (1 - cos(2 pi f3 t)) / 2``.

The nominal motion is the same in every trial; only the noise differs, so the spread of the
estimates over trials is the sampling distribution that the predicted covariance should match.

Noise: :func:`jointbench.simulate.noise.isotropic_noise` with ``sd_mm = noise_mm``: its RMS
error length is ``sd_mm``, i.e. ``sqrt(tr W_y)`` (per-coordinate SD ``noise_mm / sqrt(3)``),
exactly paper C's "sqrt(tr Wy) = 1.7 mm". Each trial draws the noise of the full ``n_frames``
recording (proximal markers, then distal, per frame) before the condition's first ``Nt``
frames are kept, so the trial of any ``Nt`` is a prefix of the same recording -- with the same
generator, the first ``Nt`` frames are identical for every ``Nt`` (paper C analyses "the first
Nt frames" of one 1200-frame recording).

:data:`PRIOR` spans the plausible rig motions (the swings' amplitudes and frequencies, the
twist and how much the hand moves); the motion above is one of its members.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Annotated

import numpy as np

from jointbench.declared import Length, NonNegative, Range, Vector3
from jointbench.declared import check_fields as check_declared
from jointbench.estimators.batching import failed_trial
from jointbench.estimators.registry import many
from jointbench.geometry import rotation_matrix
from jointbench.numerics.poses import fit_rigid_poses
from jointbench.running.scoring import score
from jointbench.simulate import PROXIMAL_TRUTH, Diagnostic, GridValues, Study, Trials
from jointbench.simulate.noise import check_noise_level, isotropic_noise
from jointbench.simulate.prior import Choice, Prior
from jointbench.simulate.ranges import (
    FrameRate,
    LabPoint,
    MarkerOffset,
    Rotation,
    Rotations,
    TimeConstant,
    check_marker_offsets,
)

__all__ = [
    "DISTAL_TRUTH",
    "EXACT_FRAME0_COLUMNS",
    "POSE_FIT_COLUMNS",
    "PRIOR",
    "STUDY",
    "HipProtocol",
    "distal_rotation",
    "marker_layout",
    "nominal_recording",
    "paper_c_checks",
    "simulate",
]

_CONDITION_KEYS = ("n_frames", "noise_mm")
#: The ``truth`` key of the distal markers at frame 0, noise-free ``(3, 3)`` [mm].
DISTAL_TRUTH = "distal_frame0"
#: gauss-markov's scores on the frame-0 control: the trial refitted with frame 0 exact.
EXACT_FRAME0_COLUMNS = {
    "error_mm": "exact_frame0_error_mm",
    "sqrt_trace_cov_mm": "exact_frame0_sqrt_trace_cov_mm",
    "mahalanobis_sq": "exact_frame0_mahalanobis_sq",
}
#: How paper C's alternation of SVD poses and body-fixed coordinates (§5, eq. 5) ended, per
#: segment: the re-estimations made, the last one's largest change [mm] and whether that was
#: below the fit's limit (:func:`~jointbench.numerics.poses.change_limit`).
POSE_FIT_COLUMNS = tuple(
    f"pose_{what}_{segment}"
    for segment in ("proximal", "distal")
    for what in ("iterations", "change_mm", "converged")
)


def _triples(rows: Sequence[Sequence[float]]) -> tuple[Vector3, ...]:
    return tuple(_triple(row) for row in rows)


def _triple(row: Sequence[float]) -> Vector3:
    return tuple(float(x) for x in row)


@dataclass(frozen=True)
class HipProtocol:
    """Modelling choices of the hip-rig study; every field can be overridden from the config.

    Geometry [mm], world frame at frame 0 (``z`` up): ``joint_mm`` the ball joint;
    ``proximal_markers_mm`` / ``distal_markers_mm`` the markers relative to the joint.
    Recording: ``n_frames`` (1200) at ``fps`` (60 Hz), marker noise ``noise_mm`` =
    ``sqrt(tr W_y)`` (1.7 mm). Hand (proximal) motion: translation amplitudes
    ``hand_translation_mm`` and frequencies ``hand_translation_hz`` per world axis; rotation
    amplitudes ``hand_rotation_deg`` and frequencies ``hand_rotation_hz`` per axis, about the
    proximal cluster's centroid. Pendulum (distal relative to proximal): main swing about ``x``
    (``swing_deg``, ``swing_hz``), cross swing about ``y`` (``cross_swing_deg``,
    ``cross_swing_hz``, build-up time constant ``cross_swing_rise_s``), twist about ``z``
    (``twist_deg``, ``twist_hz``). See the module docstring for the formulas.
    """

    # Three frames: the fewest in which two segments' relative rotation can be seen at all.
    n_frames: Annotated[int, Range(3)] = 1200
    fps: FrameRate = 60.0
    noise_mm: NonNegative = 1.7
    joint_mm: LabPoint = (0.0, 0.0, 1000.0)
    # Three markers: the fewest that give a segment's pose.
    proximal_markers_mm: Annotated[tuple[MarkerOffset, ...], Length(3)] = (
        (90.0, 0.0, 500.0),
        (-60.0, 90.0, 520.0),
        (-50.0, -100.0, 480.0),
    )
    distal_markers_mm: Annotated[tuple[MarkerOffset, ...], Length(3)] = (
        (80.0, 20.0, -500.0),
        (-70.0, 80.0, -470.0),
        (-30.0, -90.0, -530.0),
    )
    hand_translation_mm: LabPoint = (40.0, 30.0, 20.0)
    hand_translation_hz: Vector3 = (0.21, 0.13, 0.31)
    hand_rotation_deg: Rotations = (4.0, 3.0, 5.0)
    hand_rotation_hz: Vector3 = (0.17, 0.29, 0.11)
    swing_deg: Rotation = 35.0
    swing_hz: float = 0.75
    cross_swing_deg: Rotation = 25.0
    cross_swing_hz: float = 0.7
    cross_swing_rise_s: TimeConstant = 3.0
    twist_deg: Rotation = 8.0
    twist_hz: float = 0.23
    # The frame-0 control: the same trials (the same draws) with frame 0 recorded exactly, so
    # that both body frames are placed without error and eq. 2's single centre exists.
    noise_free_frame0: bool = False

    def __post_init__(self) -> None:
        # Lists from the config become tuples: a protocol is immutable and hashable.
        set_ = object.__setattr__
        set_(self, "proximal_markers_mm", _triples(self.proximal_markers_mm))
        set_(self, "distal_markers_mm", _triples(self.distal_markers_mm))
        for name in (
            "joint_mm",
            "hand_translation_mm",
            "hand_translation_hz",
            "hand_rotation_deg",
            "hand_rotation_hz",
        ):
            set_(self, name, _triple(getattr(self, name)))
        check_marker_offsets("proximal_markers_mm", self.proximal_markers_mm)
        check_marker_offsets("distal_markers_mm", self.distal_markers_mm)
        markers = (*self.proximal_markers_mm, *self.distal_markers_mm)  # relative to the joint
        clusters = ("proximal_markers_mm", "distal_markers_mm")
        check_noise_level("noise_mm", self.noise_mm, np.array(markers), clusters)

    @classmethod
    def from_config(cls, overrides: Mapping[str, object] | None = None) -> HipProtocol:
        """Defaults updated by the config's ``protocol`` mapping."""
        overrides = dict(overrides or {})
        check_declared(cls, overrides)
        return cls(**overrides)


def marker_layout(protocol: HipProtocol) -> tuple[np.ndarray, np.ndarray]:
    """Body-fixed (= world at frame 0) markers ``(n, 3)`` [mm] of the proximal and distal
    segments."""
    joint = np.asarray(protocol.joint_mm)
    return (
        joint + np.asarray(protocol.proximal_markers_mm),
        joint + np.asarray(protocol.distal_markers_mm),
    )


def _from_rest(amplitude: np.ndarray, hz: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``A (1 - cos(2 pi f t)) / 2``: 0 with zero velocity at ``t = 0``."""
    return np.asarray(amplitude) * (1.0 - np.cos(2.0 * np.pi * np.asarray(hz) * t[:, None])) / 2.0


def distal_rotation(protocol: HipProtocol, t: np.ndarray) -> np.ndarray:
    """The distal segment's rotation vector relative to the proximal one ``(len(t), 3)`` [rad]
    (proximal frame) at times ``t`` [s]: the main swing about ``x``, the cross swing about
    ``y``, the twist about ``z`` (see the module docstring)."""
    swing = np.radians(protocol.swing_deg) * (np.cos(2.0 * np.pi * protocol.swing_hz * t) - 1.0)
    cross = (
        np.radians(protocol.cross_swing_deg)
        * (1.0 - np.exp(-t / protocol.cross_swing_rise_s))
        * np.sin(2.0 * np.pi * protocol.cross_swing_hz * t)
    )
    twist = _from_rest(np.radians([protocol.twist_deg]), np.array([protocol.twist_hz]), t)[:, 0]
    return np.stack([swing, cross, twist], axis=-1)


def nominal_recording(protocol: HipProtocol) -> tuple[np.ndarray, np.ndarray]:
    """Noise-free proximal and distal markers ``(n_frames, n, 3)`` [mm] of the whole recording
    (world frame; frame 0 equals :func:`marker_layout`)."""
    t = np.arange(protocol.n_frames) / protocol.fps
    proximal_body, distal_body = marker_layout(protocol)
    joint = np.asarray(protocol.joint_mm)

    # Proximal pose: rotation about the grip (cluster centroid) plus the wandering translation.
    hand_rotvec = _from_rest(np.radians(protocol.hand_rotation_deg), protocol.hand_rotation_hz, t)
    r0 = rotation_matrix(hand_rotvec)
    wander = np.asarray(protocol.hand_translation_mm) * np.sin(
        2.0 * np.pi * np.asarray(protocol.hand_translation_hz) * t[:, None]
    )
    grip = proximal_body.mean(axis=0)
    d0 = grip + wander - r0 @ grip

    r1 = r0 @ rotation_matrix(distal_rotation(protocol, t))
    # Ball joint: the joint's world position is shared, R0 c + d0 = R1 c + d1.
    d1 = r0 @ joint + d0 - r1 @ joint

    proximal = proximal_body @ np.swapaxes(r0, -1, -2) + d0[:, None, :]
    distal = distal_body @ np.swapaxes(r1, -1, -2) + d1[:, None, :]
    return proximal, distal


def simulate(
    condition: Mapping[str, object], protocol: HipProtocol, rngs: Sequence[np.random.Generator]
) -> Trials:
    """Trials of one condition: the first ``Nt`` frames of the noisy recording.

    ``condition`` keys: ``n_frames`` (Nt, ``1 <= Nt <= protocol.n_frames``; default the whole
    recording) and ``noise_mm`` (default ``protocol.noise_mm``). One generator per trial; each
    draws the noise of all ``protocol.n_frames`` frames, so the trials of different Nt from the
    same generators share their first frames exactly.

    Returns :class:`~jointbench.simulate.Trials` with ``segments["proximal"]`` and
    ``segments["distal"]`` ``(n_trials, Nt, 3, 3)`` [mm] in the world frame and
    ``truth["center"]`` the joint in the body-fixed frame shared at frame 0 and
    ``truth["proximal_frame0"]`` and ``truth["distal_frame0"]`` the proximal and distal
    markers there, noise-free ``(3, 3)`` [mm].
    """
    unknown = set(condition) - set(_CONDITION_KEYS)
    if unknown:
        raise ValueError(
            f"unknown hip condition keys {sorted(unknown)}; known: {', '.join(_CONDITION_KEYS)}"
        )
    n_used = condition.get("n_frames", protocol.n_frames)
    if int(n_used) != n_used or not 1 <= n_used <= protocol.n_frames:
        raise ValueError(
            f"n_frames must be an integer in [1, {protocol.n_frames}] (the recording), "
            f"got {n_used!r}"
        )
    n_used = int(n_used)
    noise_mm = float(condition.get("noise_mm", protocol.noise_mm))
    if not (np.isfinite(noise_mm) and noise_mm >= 0):
        raise ValueError(f"noise_mm must be finite and >= 0, got {noise_mm!r}")

    proximal, distal = nominal_recording(protocol)
    n_proximal = proximal.shape[1]
    recording = np.concatenate([proximal, distal], axis=1)
    noise = np.stack([isotropic_noise(rng, recording.shape[:2], noise_mm) for rng in rngs])
    if protocol.noise_free_frame0:
        noise[:, 0] = 0.0
    noisy = (recording + noise)[:, :n_used]
    parameters = {
        **asdict(protocol),
        "n_frames_recorded": protocol.n_frames,
        "n_frames": n_used,
        "noise_mm": noise_mm,
        "duration_s": n_used / protocol.fps,
    }
    return Trials(
        segments={"proximal": noisy[:, :, :n_proximal], "distal": noisy[:, :, n_proximal:]},
        truth={
            "center": [float(x) for x in protocol.joint_mm],
            PROXIMAL_TRUTH: proximal[0].tolist(),
            DISTAL_TRUTH: distal[0].tolist(),
        },
        parameters=_jsonable(parameters),
    )


def paper_c_checks(arguments, results: Sequence, truth: Mapping) -> list[dict[str, object]]:
    """Paper C's method checked against what the paper says of it, per trial: the pose fit's
    convergence and the frame-0 control.

    The check of :attr:`Study.diagnostics` for gauss-markov: ``arguments`` is ``(proximal,
    distal)``, each ``(n_trials, Nt, 3, 3)`` [mm]. Columns :data:`POSE_FIT_COLUMNS`: how the
    alternation of poses and body-fixed coordinates of each segment ended
    (:func:`~jointbench.numerics.poses.fit_rigid_poses`, as the poses gauss-markov used were
    fitted). Columns :data:`EXACT_FRAME0_COLUMNS`: gauss-markov's error, predicted
    ``sqrt(tr Wc)`` and ``e`` (eq. 16) on the same trial with frame 0 replaced by the exact
    markers (:data:`PROXIMAL_TRUTH`, :data:`DISTAL_TRUTH`), the run the protocol option
    ``noise_free_frame0`` simulates: both body frames placed without error, so that eq. 2's
    single centre exists. The control uses gauss-markov's default options.
    """
    proximal, distal = (np.asarray(markers, dtype=float) for markers in arguments)
    fits = [fit_rigid_poses(markers) for markers in (proximal, distal)]
    exact = []
    for markers, key in ((proximal, PROXIMAL_TRUTH), (distal, DISTAL_TRUTH)):
        markers = markers.copy()
        markers[:, 0] = truth[key]
        exact.append(markers)
    controls = many("joint_center", "gauss-markov", checked=False)(*exact)
    rows: list[dict[str, object]] = []
    for trial, (result, control) in enumerate(zip(results, controls, strict=True)):
        if result is None:
            rows.append({})
            continue
        row: dict[str, object] = {}
        for fit, segment in zip(fits, ("proximal", "distal"), strict=True):
            row[f"pose_iterations_{segment}"] = int(fit.iterations[trial])
            row[f"pose_change_mm_{segment}"] = float(fit.change_mm[trial])
            row[f"pose_converged_{segment}"] = bool(fit.converged[trial])
        if isinstance(control, BaseException):
            failed_trial(control)  # a bug is raised; a stated failure leaves no control
            control = None
        scores = score("joint_center", control, truth)
        row.update({name: scores[column] for column, name in EXACT_FRAME0_COLUMNS.items()})
        rows.append(row)
    return rows


def _jsonable(value: object) -> object:
    """Tuples to lists, recursively, so the parameters survive a JSON round trip unchanged."""
    if isinstance(value, dict):
        return {key: _jsonable(item) for key, item in value.items()}
    if isinstance(value, (tuple, list)):
        return [_jsonable(item) for item in value]
    return value


def frame_count(condition: Mapping[str, object], protocol: HipProtocol) -> int:
    """The frames of every trial of ``condition`` under ``protocol``: its ``Nt``, the first
    frames of the recording (:func:`simulate`)."""
    return int(condition.get("n_frames", protocol.n_frames))


def recorded_frames(protocol: HipProtocol) -> int:
    """The frames each trial's simulation draws under ``protocol``, whatever ``Nt`` it keeps:
    the whole recording (:func:`simulate`)."""
    return protocol.n_frames


def frame_keys(condition: Mapping[str, object], overrides: Mapping) -> list[tuple[str, str]]:
    """Where the config sets the frames :func:`recorded_frames` gives (the grid's ``n_frames``
    sets each trial's, :func:`frame_count`)."""
    return [("protocol", "n_frames")]


STUDY = Study(
    name="hip",
    kind="joint_center",
    grid_keys=("n_frames",),
    # Paper C §8 analyses the first Nt frames of one recording: Nt selects a view, not a trial.
    seed_keys=(),
    segments=("proximal", "distal"),
    protocol_class=HipProtocol,
    simulate=simulate,
    frame_count=frame_count,
    recorded_frames=recorded_frames,
    frame_keys=frame_keys,
    # Nt frames of a recording of the protocol's n_frames.
    grid_spec={
        "n_frames": GridValues(
            int,
            minimum=1,
            maximum=lambda protocol: protocol.n_frames,
            frames=True,
            label="frames used",
            text="Nt = {}",
        )
    },
    title="hip joint centre",
    diagnostics={
        "gauss-markov": Diagnostic(
            (*POSE_FIT_COLUMNS, *EXACT_FRAME0_COLUMNS.values()), paper_c_checks
        )
    },
)


_SWUNG = (
    "One of the authors held by hand a two segment mechanical test rig on which the markers "
    "were mounted and swung it like a pendulum making sure that over the 20 second time "
    "interval the second segment moved around at least 2 of the axes."
)
_PENDULUM = "a pendulum of a 0.4–0.7 m segment swings at 0.6–0.9 Hz"
# (field, low, high, reason); the hand's amplitudes are scaled together by ``hand_scale``.
_MOTION_BOUNDS = (
    ("swing_deg", 20.0, 50.0, "a main swing of 40–100° peak to peak"),
    ("swing_hz", 0.6, 0.9, _PENDULUM),
    ("cross_swing_deg", 10.0, 40.0, "the second axis moves at least 10° (2 of the axes)"),
    ("cross_swing_hz", 0.5, 0.9, _PENDULUM),
    ("cross_swing_rise_s", 1.0, 6.0, "the hand builds the cross swing up in 1–6 s"),
    ("twist_deg", 0.0, 15.0, "a ball joint lets the lower segment twist a little"),
    ("twist_hz", 0.1, 0.4, "the twist drifts slowly"),
)


def _hip_choices() -> tuple[Choice, ...]:
    default = HipProtocol()
    choices = [
        Choice(name, low, high, getattr(default, name), _SWUNG, reason)
        for name, low, high, reason in _MOTION_BOUNDS
    ]
    choices.append(
        Choice(
            "hand_scale",
            0.5,
            2.0,
            1.0,
            _SWUNG,
            "the holding hand wanders half to twice as much as the default (every translation "
            "and rotation amplitude scaled together); log-uniform",
            log=True,
        )
    )
    return tuple(choices)


def _hip_protocol(values: Mapping[str, float]) -> dict:
    """The ``protocol`` overrides of one member of :data:`PRIOR`."""
    default = HipProtocol()
    scale = values["hand_scale"]
    return {
        **{name: values[name] for name, *_ in _MOTION_BOUNDS},
        "hand_translation_mm": [scale * x for x in default.hand_translation_mm],
        "hand_rotation_deg": [scale * x for x in default.hand_rotation_deg],
    }


#: The plausible rig motions of paper C's experiment.
PRIOR = Prior(study="hip", choices=_hip_choices(), build=_hip_protocol)
