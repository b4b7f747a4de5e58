"""The two-segment verdict's rigid-body fits (:func:`jointbench.estimators.support._clusters`)
equal, to the last bit, the step-by-step fit the module docstring describes: poses fitted to
frame 0 (:func:`jointbench.numerics.poses.best_rotation` on the cross-covariances), one
re-estimation of the body-fixed coordinates, poses fitted again, and the residual, scatter,
inertia and coordinate sums of those poses. Seeded trials cover noisy, noise-free, static,
nearly collinear and non-rigid clusters and relative rotations near pi."""

from __future__ import annotations

import numpy as np
import pytest
from rigs import apply_pose, two_segments

from jointbench.estimators import support
from jointbench.geometry import rotation_matrix, unit
from jointbench.numerics.compiled import kernel_array
from jointbench.numerics.poses import _horn_rotations, best_rotation


def _stepwise(markers: np.ndarray) -> tuple[np.ndarray, ...]:
    """The fit step by step: ``rotation, residual_ss, scatter, inertia_inv, weakest, largest``."""
    markers = kernel_array(markers)
    first = np.ascontiguousarray(markers[:, 0])
    cross, bound = support._cross_covariances(markers, first)
    body = support._reestimated_body(markers, best_rotation(cross, bound=bound), first, 1e-12)
    cross, bound = support._cross_covariances(markers, body)
    rotation = best_rotation(cross, bound=bound)
    return (rotation, *support._fit_numbers(markers, rotation, body))


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


@pytest.mark.parametrize("case", list(CASES))
def test_the_verdict_fits_are_the_stepwise_fits_to_the_last_bit(case):
    for markers in CASES[case]:
        markers = markers[None]
        if not support._poses_defined(markers):
            continue
        fitted = support._clusters(markers)
        rotation, residual_ss, scatter, inertia_inv, weakest, largest = _stepwise(markers)
        np.testing.assert_array_equal(fitted.rotation, rotation)
        np.testing.assert_array_equal(fitted.residual_ss, residual_ss)
        np.testing.assert_array_equal(fitted.inertia_inv, inertia_inv)
        np.testing.assert_array_equal(fitted.weakest_variance, weakest)
        np.testing.assert_array_equal(fitted.largest, largest)
        n_frames, n_markers = markers.shape[1:3]
        share = (residual_ss / fitted.dof) / (scatter / (3 * (n_markers - 1) * n_frames))
        np.testing.assert_array_equal(fitted.nonrigid_share, share)


def test_trials_fitted_together_are_fitted_as_each_alone():
    """A batch of trials of one shape, some with frames whose rotation Horn's method leaves to
    the SVD (collinear clusters), gives each trial the fit it has alone."""
    group = [
        arrays
        for arrays in CASES.values()
        if {a.shape for a in arrays} == {(150, 3, 3)}
        and all(support._poses_defined(a[None]) for a in arrays)
    ]
    for index in range(2):
        stacked = np.stack([arrays[index] for arrays in group])
        together = support._clusters(stacked)
        for trial, arrays in enumerate(group):
            alone = support._clusters(arrays[index][None])
            for field in ("rotation", "residual_ss", "inertia_inv", "largest", "nonrigid_share"):
                np.testing.assert_array_equal(
                    getattr(together, field)[trial], getattr(alone, field)[0]
                )


def test_the_cases_include_frames_horn_leaves_to_the_svd():
    """Some cases' clusters have frames whose rotation Horn's method leaves to the SVD, so the
    tests above hold there too."""
    unsettled = []
    for arrays in CASES.values():
        for markers in arrays:
            markers = kernel_array(markers[None])
            if support._poses_defined(markers):
                cross, bound = support._cross_covariances(markers, markers[:, 0].copy())
                rotation = np.empty_like(cross[0])
                flags = np.empty(cross.shape[1], dtype=bool)
                _horn_rotations(cross[0], bound[0], rotation, flags)
                unsettled.append(flags.any())
    assert any(unsettled)
