"""The two-segment verdict's rigid-body fits (:func:`jointbench.estimators.support._clusters`)
are the converged poses the pose-based estimators fit
(:func:`jointbench.estimators.segment_poses.trial_poses`), read, not refitted. Seeded trials
cover noisy, noise-free, static, nearly collinear and non-rigid clusters and relative rotations
near pi.

Guards: the numbers the verdict takes from the poses (residual, scatter, inertia, largest
coordinate) equal a plain NumPy computation from the same poses; a verdict given the poses an
estimator fitted equals the one that fits them itself, and poses fitted to other markers are
not used; poses that cannot be fitted are reported as such, not raised.
"""

from __future__ import annotations

import numpy as np
import pytest
from rigs import apply_pose, two_segments

from jointbench.estimators import support
from jointbench.estimators.segment_poses import trial_poses
from jointbench.geometry import rotation_matrix, unit


def _near_pi(seed: int, n_frames: int, noise_mm: float) -> tuple[np.ndarray, np.ndarray]:
    """A distal segment turned by nearly pi about a fixed axis relative to the proximal one,
    which sways."""
    rng = np.random.default_rng(seed)
    proximal, distal = two_segments(n_frames)
    axis = unit(rng.normal(size=3))
    angle = np.pi - 10.0 ** rng.uniform(-6.0, -1.0) * np.abs(np.sin(np.linspace(0, 5, n_frames)))
    centre = distal.mean(axis=(0, 1))
    turned = (distal - centre) @ np.swapaxes(rotation_matrix(angle[:, None] * axis), 1, 2)
    return _noisy(proximal, noise_mm, rng), _noisy(turned + centre, noise_mm, rng)


def _noisy(markers: np.ndarray, noise_mm: float, rng: np.random.Generator) -> np.ndarray:
    return markers + rng.normal(scale=noise_mm, size=markers.shape) if noise_mm else markers


def _nearly_collinear(seed: int, n_frames: int, off_line_mm: float, noise_mm: float):
    """A distal cluster whose markers lie ``off_line_mm`` off one line."""
    rng = np.random.default_rng(seed)
    proximal, _ = two_segments(n_frames)
    along = np.array([[0.0, 0.0, -100.0], [0.0, 0.0, -200.0], [0.0, 0.0, -300.0]])
    body = along + np.array([[0.0, 0.0, 0.0], [off_line_mm, 0.0, 0.0], [0.0, 0.0, 0.0]])
    t = np.linspace(0.0, 4.0, n_frames)
    rotation = rotation_matrix(np.stack([0.5 * np.sin(t), 0.3 * np.sin(1.7 * t), 0 * t], -1))
    distal = apply_pose(rotation, np.zeros((n_frames, 3)), body + np.array([10.0, 5.0, 800.0]))
    return _noisy(proximal, noise_mm, rng), _noisy(distal, noise_mm, rng)


def two_segment_cases() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Seeded two-segment trials ``(proximal, distal)``, each ``(N, n, 3)`` [mm]."""
    cases = {}
    for seed in range(4):
        rng = np.random.default_rng(seed)
        for relative in ("ball", "hinge", "none"):
            for noise_mm in (0.0, 0.05, 0.5, 2.0):
                n_frames = int(rng.choice([12, 150, 1200]))
                proximal, distal = two_segments(n_frames, relative=relative)
                cases[f"{relative}/{noise_mm}/{seed}"] = (
                    _noisy(proximal, noise_mm, rng),
                    _noisy(distal, noise_mm, rng),
                )
        proximal, distal = two_segments(150)
        extra = distal[:, :1] + rng.normal(scale=30.0, size=(1, 2, 3))
        cases[f"four-markers/{seed}"] = (
            _noisy(proximal, 0.3, rng),
            _noisy(np.concatenate([distal, np.broadcast_to(extra, (150, 2, 3))], 1), 0.3, rng),
        )
        cases[f"non-rigid/{seed}"] = (
            _noisy(proximal, 0.3, rng),
            _noisy(distal, 40.0, rng),
        )
        for noise_mm in (0.0, 0.5):
            cases[f"near-pi/{noise_mm}/{seed}"] = _near_pi(seed, 150, noise_mm)
        for off_line_mm in (0.0, 1e-3, 0.5, 5.0):
            for noise_mm in (0.0, 0.3):
                cases[f"nearly-collinear/{off_line_mm}/{noise_mm}/{seed}"] = _nearly_collinear(
                    seed, 150, off_line_mm, noise_mm
                )
    return cases


CASES = two_segment_cases()
NAMES = ("proximal", "distal")


def _poses(arrays: tuple[np.ndarray, ...]) -> dict:
    """One trial's converged poses of both segments, as an estimator fits them."""
    (fitted,) = trial_poses(
        {name: [a] for name, a in zip(NAMES, arrays, strict=True)}, min_frames=2
    )
    return fitted


def _reference(frames: np.ndarray, rotation: np.ndarray, body: np.ndarray) -> tuple:
    """The fit's numbers of one segment's ``frames`` ``(N, n, 3)`` [mm] under its poses
    ``rotation`` ``(N, 3, 3)`` of ``body`` ``(n, 3)`` [mm], in plain NumPy: ``residual_ss``,
    ``scatter`` [mm^2], ``inertia_inv`` ``(3, 3)`` [mm^-2], ``weakest`` and ``largest`` [mm]."""
    centred = frames - frames.mean(axis=1, keepdims=True)
    u = body - body.mean(axis=0)
    residual_ss = np.sum((centred - np.einsum("fij,mj->fmi", rotation, u)) ** 2)
    inertia_inv = np.linalg.inv(np.sum(u**2) * np.eye(3) - u.T @ u)
    weakest = np.linalg.eigvalsh(inertia_inv)[2]
    return residual_ss, np.sum(centred**2), inertia_inv, weakest, np.abs(frames).max()


def _defined(arrays: tuple[np.ndarray, ...]) -> bool:
    return all(support._poses_defined(a[None]) for a in arrays)


@pytest.mark.parametrize("case", list(CASES))
def test_the_fits_are_the_poses_numbers(case):
    arrays = CASES[case]
    if not _defined(arrays):
        pytest.skip("no pose: judged without one")
    poses = _poses(arrays)
    for name, frames in zip(NAMES, arrays, strict=True):
        pose = poses[name]
        fitted = support._clusters(frames[None], [pose])
        residual_ss, scatter, inertia_inv, weakest, largest = _reference(
            frames, pose.rotation, pose.body
        )
        np.testing.assert_array_equal(fitted.rotation[0], pose.rotation)
        np.testing.assert_allclose(fitted.residual_ss[0], residual_ss, rtol=0, atol=1e-12 * scatter)
        np.testing.assert_allclose(
            fitted.inertia_inv[0], inertia_inv, rtol=0, atol=1e-10 * np.abs(inertia_inv).max()
        )
        np.testing.assert_allclose(fitted.weakest_variance[0], weakest, rtol=1e-10)
        assert fitted.largest[0] == largest
        dof = 3 * (frames.shape[1] - 2) * (len(frames) - 1)
        share = (fitted.residual_ss[0] / dof) / (
            scatter / (3 * (frames.shape[1] - 1) * len(frames))
        )
        np.testing.assert_allclose(fitted.nonrigid_share[0], share, rtol=1e-10)


@pytest.mark.parametrize("case", list(CASES))
def test_a_verdict_given_the_poses_is_the_verdict_that_fits_them(case):
    arrays = CASES[case]
    own = support.assess("joint_center", arrays)
    given = support.assess("joint_center", arrays, poses=_poses(arrays))
    assert given.warnings == own.warnings
    assert given.diagnostics == own.diagnostics


def test_the_verdict_reads_the_poses_it_is_given(monkeypatch):
    """Given the markers' own poses the verdict reads them and fits none of its own; poses of
    other markers (a joint that turns, for markers of one that does not) are refused, as they
    would judge motion the markers do not have."""
    still = two_segments(150, relative="none")
    turning = two_segments(150, relative="ball")
    expected = support.assess("joint_center", still)
    own = _poses(still)

    def no_fit(*_):
        raise AssertionError("the verdict fitted poses of its own")

    monkeypatch.setattr(support, "_fitted_poses", no_fit)
    assert support.assess("joint_center", still, poses=own) == expected
    with pytest.raises(ValueError, match=r"^poses: trial 0's distal poses were not fitted to"):
        support.assess("joint_center", still, poses=_poses(turning))


def test_a_pose_fit_that_fails_is_reported_not_raised():
    arrays = CASES["ball/0.5/0"]
    error = ValueError("distal (body-fixed coordinates): the markers are collinear")
    verdict = support.assess("joint_center", arrays, poses=error)
    assert verdict.diagnostics["assessed"] is False
    assert "the pose fit failed (distal (body-fixed coordinates)" in verdict.warnings[0]


def test_trials_judged_together_are_judged_as_each_alone():
    """A batch of trials of one shape, some failing their pose fit, gives each trial the
    verdict it has alone."""
    group = [
        arrays
        for arrays in CASES.values()
        if {a.shape for a in arrays} == {(150, 3, 3)} and _defined(arrays)
    ]
    stacked = tuple(np.stack(arrays) for arrays in zip(*group, strict=True))
    poses = [_poses(arrays) for arrays in group]
    poses[1] = ValueError("distal: the pose fit failed on purpose")
    together = support.assess_many("joint_center", stacked, poses=poses)
    for trial, arrays in enumerate(group):
        alone = support.assess("joint_center", arrays, poses=poses[trial])
        assert together[trial].warnings == alone.warnings
        assert together[trial].diagnostics == alone.diagnostics


def test_markers_that_do_not_move_get_a_verdict():
    """Still markers with too few of them for a pose: judged without one, not divided by zero."""
    proximal, distal = two_segments(20)
    still = np.broadcast_to(distal[:1, :2], (20, 2, 3)).copy()
    verdict = support.assess("joint_center", (proximal, still))
    assert verdict.diagnostics["assessed"] is False
    assert any("range of motion too small" in warning for warning in verdict.warnings)


def test_poses_that_are_not_the_segments_poses_are_refused():
    """Poses of a one-segment fit, or of another number of trials, are named, not indexed."""
    arrays = CASES["ball/0.5/0"]
    (one_segment,) = trial_poses({"markers": [arrays[1]]}, min_frames=3)
    with pytest.raises(ValueError, match=r"^poses: trial 0 holds the segments markers; give"):
        support.assess("joint_center", arrays, poses=one_segment)
    stacked = tuple(np.stack([array] * 2) for array in arrays)
    with pytest.raises(ValueError, match=r"^poses: 1 entries for 2 trials; give one per trial"):
        support.assess_many("joint_center", stacked, poses=[_poses(arrays)])


def test_a_compact_cluster_is_not_charged_with_its_noisier_neighbours_noise():
    """A compact pelvis cluster (markers 8 mm about their centre) with 0.1 mm noise beside a
    wide thigh cluster with 3 mm, swung 30 deg about two axes: the rotation off the main axis
    is resolved in every one of 48 trials. With the pooled noise charged to both poses, the
    compact cluster's rotation SD read some 20 times too large, and 12 were refused as rotating
    about a single axis."""
    from test_pose_noise import _hip, _noisy

    for geometry in range(3, 9):
        clean = _hip(geometry, ratio=1.0, spreads_mm=(8.0, 60.0))
        for seed in range(8):
            verdict = support.assess("joint_center", _noisy(clean, seed, (0.1, 3.0)))
            assert not verdict.warnings, (geometry, seed, verdict.warnings)


def test_a_pure_hinge_with_unequal_noise_resolves_no_second_axis():
    """A pure hinge between two segments whose noise differs (0.2 and 1 mm, or 1 mm on a
    compact cluster beside 0.1 mm on a wide one): the rotation off the hinge is resolved at the
    verdict's level, a thousandth, in at most 3 of 100 trials each, near the none in 200 this
    generator gives with equal noise. With the
    pooled noise charged to both poses it was resolved in most of them (85 to 182 of 200),
    passing a hinge as fixing a joint centre."""
    from test_pose_noise import second_axes_resolved

    for spreads_mm, noise_mm in (((40.0, 20.0), (0.2, 1.0)), ((15.0, 60.0), (1.0, 0.1))):
        resolved = second_axes_resolved(spreads_mm, noise_mm, 10)
        assert resolved <= 3, (spreads_mm, noise_mm, resolved)


@pytest.mark.parametrize(
    ("kind", "names"), [("axis", ("markers",)), ("joint_center", ("proximal", "distal"))]
)
def test_markers_with_a_gap_are_refused_naming_the_sample(kind, names):
    """The verdict is a public function: a gap (NaN) is refused naming the array, the marker
    and the frame, not met as an error of the linear algebra."""
    rng = np.random.default_rng(0)
    arrays = tuple(rng.normal(scale=30.0, size=(20, 3, 3)) for _ in names)
    arrays[-1][7, 1, 2] = np.nan
    with pytest.raises(ValueError, match=rf"^{names[-1]}.*NaN") as raised:
        support.assess(kind, arrays)
    assert "frame 7" in str(raised.value), raised.value
