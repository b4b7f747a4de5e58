"""An axis is not reported as "ok" for a motion no single axis describes.

The support verdict measures, for an axis whose rotation off the main axis is resolved, the share
of the rotation's sum of squares about axes other than its principal one
(:data:`jointbench.estimators.support.MAX_OFF_AXIS_SHARE`), from the rotations themselves, so
that it does not depend on where the markers sit. Paper B's motions (every FE angle with every AA
angle, AA ``ratio`` times FE) leave ``ratio^2 / (1 + ratio^2)`` off the FE axis whatever the
joint's markers; a ball-and-socket motion leaves about half.
"""

from __future__ import annotations

import numpy as np
import pytest

import jointbench
from jointbench.estimators import support
from jointbench.geometry import rotation_matrix
from jointbench.simulate import hinge
from jointbench.simulate.noise import isotropic_noise

WARNING = "rotation about more than one axis"
BODY = np.array([[40.0, 10, 5], [10, 50, -10], [-5, 15, 60], [30, -20, 40]])
CENTRE = np.array([20.0, -25.0, -30.0])


def _moved(rotation_vectors: np.ndarray, noise_mm: float, seed: int = 0) -> np.ndarray:
    """``BODY`` turned by ``rotation_vectors`` ``(N, 3)`` [rad] about ``CENTRE``, with
    isotropic noise of RMS length ``noise_mm``: ``(N, 4, 3)`` [mm]."""
    markers = np.einsum("fij,mj->fmi", rotation_matrix(rotation_vectors), BODY) + CENTRE
    rng = np.random.default_rng(seed)
    return markers + isotropic_noise(rng, markers.shape[:2], noise_mm) if noise_mm else markers


def _ball(n_frames: int = 120, amplitude_deg: float = 30.0) -> np.ndarray:
    """Circumduction and axial rotation at once: ``(N, 3)`` rotation vectors [rad]."""
    t = np.linspace(0.0, 2.0 * np.pi, n_frames)
    a = np.radians(amplitude_deg)
    return np.stack([a * np.cos(t), a * np.sin(2 * t), a / 2 * np.sin(t)], axis=1)


def _hinge(n_frames: int = 120, arc_deg: float = 60.0) -> np.ndarray:
    return np.outer(np.radians(np.linspace(0.0, arc_deg, n_frames)), [0.0, 0.0, 1.0])


def _share(markers: np.ndarray) -> float | None:
    return support.assess("axis", (markers,)).diagnostics.get("off_principal_axis_share")


@pytest.mark.parametrize("noise_mm", [0.0, 0.5])
@pytest.mark.parametrize("method", ["planar", "radial", "combined", "SARA"])
def test_ball_and_socket_motion_is_not_reported_as_an_axis(method, noise_mm):
    result = jointbench.fit_axis(_moved(_ball(), noise_mm), method=method)
    assert WARNING in result.status
    assert result.diagnostics["support_off_principal_axis_share"] == pytest.approx(0.55, abs=0.05)


def test_a_centre_from_the_same_motion_is_not_warned_about():
    result = jointbench.fit_center(_moved(_ball(), 0.5), method="LS")
    assert result.status == "ok"


@pytest.mark.parametrize("noise_mm", [0.0, 1.0])
@pytest.mark.parametrize("arc_deg", [10.0, 60.0, 120.0])
def test_a_hinge_is_an_axis(arc_deg, noise_mm):
    for method in ("planar", "combined"):
        result = jointbench.fit_axis(_moved(_hinge(arc_deg=arc_deg), noise_mm), method=method)
        assert WARNING not in result.status


@pytest.mark.parametrize("seed", range(4))
def test_a_small_noisy_arc_is_not_called_two_axes(seed):
    """Rotation off a 2-degree hinge is noise, not resolved: no share is claimed for it."""
    markers = _moved(_hinge(arc_deg=2.0), 0.5, seed)
    assert _share(markers) is None
    assert WARNING not in support.assess("axis", (markers,)).warnings


@pytest.mark.parametrize("joint", ["knee", "mcp"])
@pytest.mark.parametrize("ratio", [0.1, 0.3, 0.5, 0.7])
def test_paper_b_motions_share_what_their_ratio_puts_off_the_fe_axis(joint, ratio):
    """Noise-free, the share is the AA rotation's, the same for either joint's markers."""
    protocol = hinge.protocol_from_config(joint)
    condition = {"protocol": joint, "fe_rom_deg": 60, "aa_ratio": ratio}
    share = _share(hinge.nominal_markers(condition, protocol))
    assert share == pytest.approx(ratio**2 / (1 + ratio**2), abs=0.01)


@pytest.mark.parametrize("joint", ["knee", "mcp"])
def test_paper_b_warns_where_every_cost_fails_and_not_where_they_hold(joint):
    """Paper B Table 1: every cost 17 to 81 deg off at AA/FE 0.7; combined within 5 deg at 0.3."""
    protocol = hinge.protocol_from_config(joint)
    rng = np.random.default_rng(7)
    for ratio, warned in ((0.3, False), (0.7, True)):
        condition = {"protocol": joint, "fe_rom_deg": 60, "aa_ratio": ratio}
        clean = hinge.nominal_markers(condition, protocol)
        markers = clean + isotropic_noise(rng, clean.shape[:2], 1.0)
        assert (WARNING in jointbench.fit_axis(markers, method="combined").status) == warned


def test_the_share_does_not_depend_on_the_frame_or_the_marker_order():
    markers = _moved(_ball(), 0.5)
    turn = rotation_matrix(np.array([0.3, -1.1, 0.7]))
    moved = markers @ turn.T + np.array([500.0, -200.0, 80.0])
    reference = _share(markers)
    assert _share(moved) == pytest.approx(reference, abs=1e-9)
    assert _share(markers[:, ::-1]) == pytest.approx(reference, abs=1e-9)
    # Another first frame and order only change which noise the poses carry.
    assert _share(markers[::-1]) == pytest.approx(reference, abs=0.01)


def test_long_recordings_are_sampled_to_the_same_share():
    markers = _moved(_ball(n_frames=6000), 0.5)
    assert _share(markers) == pytest.approx(_share(markers[::25]), abs=0.01)


def test_many_trials_are_judged_each_as_alone():
    trials = np.stack(
        [
            _moved(_ball(), 0.5, seed=1),
            _moved(_hinge(), 0.5, seed=2),
            _moved(_hinge(arc_deg=2.0), 0.5, seed=3),
            _moved(_ball(amplitude_deg=8.0), 0.5, seed=4),
        ]
    )
    together = support.assess_many("axis", (trials,))
    for trial, verdict in zip(trials, together, strict=True):
        alone = support.assess("axis", (trial,))
        assert verdict.warnings == alone.warnings
        assert verdict.diagnostics == pytest.approx(alone.diagnostics, rel=1e-12, abs=1e-15)


#: The numbers of a MotionAxis besides its direction, in the order _step_by_step gives them.
MOTION_NUMBERS = ("sd_deg", "noise_share", "pose_sd_deg")


def _step_by_step(
    markers: np.ndarray, variance: np.ndarray, central: np.ndarray
) -> list[np.ndarray]:
    """The motion axes and shares of one segment's trials ``(T, N, n, 3)`` taken a NumPy step
    at a time from their sampled rotations from the ``central`` frames ``(T,)``: the way the
    one-call kernel must match."""
    rotations = support._one_segment_rotations(markers, variance, central)
    directions, sd_deg, noise_share = support._motion_axis_numbers(
        rotations.own, rotations.mean, rotations.noise, rotations.n_frames
    )
    values = rotations.values
    off = values[:, 0] + values[:, 1]
    total = off + values[:, 2]
    return [
        directions,
        sd_deg,
        noise_share,
        np.degrees(np.sqrt(np.linalg.eigvalsh(rotations.noise)[:, -1])),
        np.divide(off, total, out=np.zeros_like(total), where=total > 0.0),
        np.sqrt(values[:, 2] / rotations.n_frames),
        np.sqrt(off / rotations.n_frames),
    ]


def _at_pi(noise_mm: float) -> np.ndarray:
    """Two thirds of the frames at rest and a third turned by pi about z: the mean pose is the
    rest, a third of the rotations are pi from it."""
    angles = np.where(np.arange(90) < 60, 0.0, np.pi)
    return _moved(np.outer(angles, [0.0, 0.0, 1.0]), noise_mm)


@pytest.mark.parametrize(
    ("make", "in_one_call"),
    [
        (lambda: _moved(_hinge(), 0.5), True),
        (lambda: _moved(_ball(), 0.5), True),
        (lambda: _moved(_ball(n_frames=1200), 1.0), True),
        (lambda: _moved(_hinge(arc_deg=0.01), 0.0), True),
        (lambda: _at_pi(0.0), False),
    ],
    ids=["hinge", "ball", "sampled", "noise-free", "at-pi"],
)
def test_the_motion_axis_in_one_call_is_the_step_by_step_one(make, in_one_call):
    markers = np.stack([make(), make()[::-1].copy()])
    variance = np.array([0.25, 1e-30])
    step = support._frame_step(markers.shape[1])
    central = support._one_segment_numbers(markers, support._FLEX)[:, support._CENTRAL_FRAME]
    assert support._sampled_axis_numbers(markers, step, variance, central)[0] == in_one_call
    axes, shares = support._one_segment_axes(markers, variance, central)
    expected = _step_by_step(markers, variance, central)
    found = [
        np.array([axis.direction for axis in axes]),
        *(np.array([getattr(axis, name) for axis in axes]) for name in MOTION_NUMBERS),
        *shares,
    ]
    for got, want in zip(found, expected, strict=True):
        np.testing.assert_array_equal(got, want)


def _nearest_mean_frame(markers: np.ndarray) -> int:
    """The frame of ``markers`` ``(N, n, 3)`` whose centred markers are nearest (sum of squares)
    the markers' mean centred positions, in NumPy: the rule the verdict's central frame follows."""
    centred = markers - markers.mean(axis=1, keepdims=True)
    return int(np.argmin(((centred - centred.mean(axis=0)) ** 2).sum(axis=(1, 2))))


@pytest.mark.parametrize(
    "make",
    [lambda: _moved(_hinge(), 0.5), lambda: _moved(_ball(n_frames=1200), 1.0)],
    ids=["hinge", "sampled"],
)
def test_the_central_frame_comes_from_the_verdicts_pass_over_the_frames(make):
    markers = make()
    order = np.random.default_rng(3).permutation(markers.shape[0])
    trials = np.stack([markers, markers[order]])
    central = support._one_segment_numbers(trials, support._FLEX)[:, support._CENTRAL_FRAME]
    assert central[0] == _nearest_mean_frame(markers)
    # The same frame of the motion, wherever the frames' order puts it.
    assert order[int(central[1])] == int(central[0])
