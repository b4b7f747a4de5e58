"""The two-segment verdict's rigid-body fits (:func:`jointbench.estimators.support._clusters`):
poses fitted to frame 0, one re-estimation of the body-fixed coordinates, poses fitted again,
and the residual, scatter, inertia and coordinate sums of those poses. Seeded trials cover
noisy, noise-free, static, nearly collinear and non-rigid clusters and relative rotations near
pi.

Two guards: the fits agree with a plain NumPy fit (SVD rotations) to rounding where the
rotations are well determined, and they equal, to 1e-12 relative, the numbers pinned in
``tests/snapshots/two_segment_fits.npz`` when it was written (the rotations by their sums over
the frames, plain and weighted by the frame's index, which any change of a frame's rotation
moves). ``python tests/test_support_two_segment_fits.py`` rewrites the file, for a deliberate
change of the fits only.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from rigs import apply_pose, two_segments

from jointbench.estimators import support
from jointbench.geometry import rotation_matrix, unit
from jointbench.numerics.compiled import kernel_array
from jointbench.numerics.poses import POSE_TOL_MM

PINNED = Path(__file__).parent / "snapshots" / "two_segment_fits.npz"


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


def _kabsch(cross: np.ndarray) -> np.ndarray:
    """Proper rotations maximising ``trace(R' H)`` of ``cross`` ``(..., 3, 3)``, by the SVD."""
    u, _, vt = np.linalg.svd(cross)
    sign = np.sign(np.linalg.det(u @ vt))
    return u @ (np.stack([np.ones_like(sign), np.ones_like(sign), sign], -1)[..., None] * vt)


def _reference(frames: np.ndarray) -> tuple:
    """The fits of one trial's ``frames`` ``(N, n, 3)`` [mm] in plain NumPy: ``rotation``
    ``(N, 3, 3)``, ``residual_ss``, ``scatter`` [mm^2], ``inertia_inv`` ``(3, 3)`` [mm^-2],
    ``weakest`` and ``largest`` [mm]."""
    centred = frames - frames.mean(axis=1, keepdims=True)

    def poses(body):
        u = body - body.mean(axis=0)
        return u, _kabsch(np.einsum("fmi,mj->fij", centred, u))

    body = frames[0]
    u, rotation = poses(body)
    local = np.einsum("fmi,fij->mj", centred, rotation) / len(frames)
    updated = frames[0].mean(axis=0) + local @ rotation[0].T
    if np.abs(updated - body).max() >= POSE_TOL_MM:
        u, rotation = poses(updated)
    residual_ss = np.sum((centred - np.einsum("fij,mj->fmi", rotation, u)) ** 2)
    inertia_inv = np.linalg.inv(np.sum(u**2) * np.eye(3) - u.T @ u)
    weakest = np.linalg.eigvalsh(inertia_inv)[2]
    return rotation, residual_ss, np.sum(centred**2), inertia_inv, weakest, np.abs(frames).max()


def _fitted(case: str) -> list[support._Clusters]:
    """The fits of each segment of ``case`` whose clusters define poses."""
    return [
        support._clusters(markers[None])
        for markers in CASES[case]
        if support._poses_defined(markers[None])
    ]


def _pinned_numbers(fitted: support._Clusters) -> np.ndarray:
    """The fit's numbers as pinned: residual, non-rigid share, weakest variance, largest
    coordinate and the inverse inertia ``(13,)``."""
    scalars = [fitted.residual_ss, fitted.nonrigid_share, fitted.weakest_variance, fitted.largest]
    return np.concatenate([*scalars, fitted.inertia_inv.ravel()])


def _rotation_sums(rotation: np.ndarray) -> np.ndarray:
    """``rotation`` ``(1, N, 3, 3)`` summed over its frames, plain and weighted by the frame's
    index over ``N`` ``(2, 3, 3)``: a frame's rotation cannot change without moving them."""
    frames = rotation[0]
    weights = np.arange(1, len(frames) + 1) / len(frames)
    return np.stack([frames.sum(axis=0), np.einsum("k,kij->ij", weights, frames)])


def _assert_pinned(found: np.ndarray, pinned: np.ndarray) -> None:
    """``found`` equals ``pinned`` to 1e-12 relative, or 1e-12 of the column's largest value
    where a value is near zero."""
    assert found.shape == pinned.shape
    scale = np.max(np.abs(pinned), axis=0, keepdims=True, initial=0.0)
    off = np.abs(found - pinned) > 1e-12 * np.maximum(np.abs(pinned), scale)
    assert not off.any(), f"{off.sum()} numbers moved, first at {np.argwhere(off)[0]}"


@pytest.fixture(scope="module")
def pinned() -> dict[str, np.ndarray]:
    with np.load(PINNED) as stored:
        return dict(stored)


@pytest.mark.parametrize("case", [c for c in CASES if not c.startswith("nearly-collinear")])
def test_the_fits_are_numpys_to_rounding(case):
    """Nearly collinear clusters are left out: their rotations about the line are ill
    determined, so Horn's method and the SVD may differ far beyond rounding."""
    for markers in CASES[case]:
        if not support._poses_defined(markers[None]):
            continue
        fitted = support._clusters(markers[None])
        rotation, residual_ss, scatter, inertia_inv, weakest, largest = _reference(markers)
        np.testing.assert_allclose(fitted.rotation[0], rotation, rtol=0, atol=1e-12)
        np.testing.assert_allclose(fitted.residual_ss[0], residual_ss, rtol=0, atol=1e-14 * scatter)
        np.testing.assert_allclose(fitted.inertia_inv[0], inertia_inv, rtol=1e-12)
        np.testing.assert_allclose(fitted.weakest_variance[0], weakest, rtol=1e-12)
        assert fitted.largest[0] == largest


@pytest.mark.parametrize("case", list(CASES))
def test_the_fits_are_the_pinned_fits(case, pinned):
    fitted = _fitted(case)
    numbers = np.array([_pinned_numbers(f) for f in fitted]).reshape(-1, 13)
    _assert_pinned(numbers, pinned[f"{case}/numbers"])
    rotations = np.array([_rotation_sums(f.rotation) for f in fitted]).reshape(-1, 18)
    _assert_pinned(rotations, pinned[f"{case}/rotations"])


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
    settled = [
        support._cluster_fits(kernel_array(markers[None]), POSE_TOL_MM)[0][0]
        for arrays in CASES.values()
        for markers in arrays
        if support._poses_defined(markers[None])
    ]
    assert not all(settled)


def _write() -> None:
    stored = {}
    for case in CASES:
        fitted = _fitted(case)
        stored[f"{case}/numbers"] = np.array([_pinned_numbers(f) for f in fitted]).reshape(-1, 13)
        sums = [_rotation_sums(f.rotation) for f in fitted]
        stored[f"{case}/rotations"] = np.array(sums).reshape(-1, 18)
    np.savez_compressed(PINNED, **stored)


if __name__ == "__main__":
    _write()
