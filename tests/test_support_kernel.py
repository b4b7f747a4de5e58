"""The one-segment verdict's compiled numbers, pinned column by column.

``tests/snapshots/one_segment_numbers.npz`` holds what
:func:`jointbench.estimators.support._one_segment_numbers` computed, when it was written, on a
seeded set of trials: the pinned verdict cases and every eighth one-segment trial of the
support sweep, the calibration's hinges, static clusters, rotations about two axes, flat plates
and elongated clusters, and edge cases of its own (3 to 8 markers, 2 to 300 frames, collinear
and nearly collinear clusters, noise-free data, offsets of 1e6 mm and coordinates at 1e9 mm).
A faster kernel must compute the same numbers: to 1e-12 relative, or 1e-12 of the column's
largest finite value where a number is near zero; infinities where they were.
``python tests/test_support_kernel.py`` rewrites the file, for a deliberate change of the
verdict only.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from pinning import ROUNDING_TIMES, random_signs
from test_support_calibration import _draw, _elongated, _plate, _trial
from test_support_sweep import TRIALS as SWEEP
from test_support_verdicts import _one_segment_cases

from jointbench.estimators import support
from jointbench.estimators.noise_directions import row_length
from jointbench.geometry import rotation_matrix, unit
from jointbench.numerics import small

PINNED = Path(__file__).parent / "snapshots" / "one_segment_numbers.npz"
# The verdict's own columns, before the noise-direction test's.
VERDICT_COLUMNS = len(support._ONE_SEGMENT_COLUMNS)


def _calibration() -> list[np.ndarray]:
    """Trials drawn as the calibration draws them: a hinge, a static cluster, two axes, a
    flat plate on a hinge and standing still, and an elongated cluster on a hinge."""
    rng = np.random.default_rng(20261203)
    found = []
    for _ in range(30):
        t, body, noise_mm = _draw(rng)
        angle = 10.0 ** rng.uniform(-2.0, 0.3) * np.sin(2.0 * np.pi * rng.uniform(0.5, 2.0) * t)
        found.append(_trial(rng, np.outer(angle, unit(rng.normal(size=3))), body, noise_mm))
        found.append(_trial(rng, np.zeros((t.size, 3)), body, noise_mm))
        second = 10.0 ** rng.uniform(-3.0, 0.0) * np.cos(7.0 * t)
        vectors = np.outer(angle, unit(rng.normal(size=3)))
        found.append(_trial(rng, vectors + np.outer(second, unit(rng.normal(size=3))), body, 0.1))
    for _ in range(15):
        n_frames, noise_mm = int(rng.integers(30, 200)), 10.0 ** rng.uniform(-1.0, 0.3)
        plate = _plate(rng, noise_mm)
        angle = 10.0 ** rng.uniform(-2.0, 0.3) * np.sin(np.linspace(0.0, 9.0, n_frames))
        found.append(_trial(rng, np.outer(angle, unit(rng.normal(size=3))), plate, noise_mm))
        found.append(_trial(rng, np.zeros((n_frames, 3)), plate, noise_mm))
    for amplitude_deg in (1.0, 60.0, 120.0):
        angle = np.radians(amplitude_deg) * np.sin(np.linspace(0.0, 4.0 * np.pi, 150))
        axis = unit(np.array([0.2, 1.0, 0.3]))
        found.append(_trial(rng, np.outer(angle, axis), _elongated(0.5), 0.5))
    return found


def _edge_cases() -> list[np.ndarray]:
    """3 to 8 markers and 2 to 300 frames: static, hinged and two-axis clusters, wide, flat,
    collinear and nearly collinear, with and without noise, near the origin, 1e6 mm off it
    and at 1e9 mm."""
    rng = np.random.default_rng(20261204)
    found = []
    for k in range(120):
        n_markers = 3 + k % 6
        n_frames = int(rng.choice([2, 3, 5, 10, 30, 120, 300]))
        shape = k // 6 % 4
        body = rng.normal(scale=40.0, size=(n_markers, 3))
        if shape == 1:
            body[:, 2] = 0.0  # a flat plate
        elif shape == 2:
            body = np.outer(rng.uniform(-50.0, 50.0, n_markers), unit(rng.normal(size=3)))
        elif shape == 3:
            body = np.outer(rng.uniform(-50.0, 50.0, n_markers), unit(rng.normal(size=3)))
            body += rng.normal(scale=10.0 ** rng.uniform(-5.0, -1.0), size=body.shape)
        body = body + 80.0 * unit(rng.normal(size=3))
        t = np.linspace(0.0, 1.0, n_frames)
        motion = k // 24 % 3
        vectors = np.zeros((n_frames, 3))
        if motion >= 1:
            vectors += np.outer(0.6 * np.sin(5.0 * t), unit(rng.normal(size=3)))
        if motion == 2:
            vectors += np.outer(0.3 * np.cos(3.0 * t), unit(rng.normal(size=3)))
        markers = np.einsum("fij,mj->fmi", rotation_matrix(vectors), body)
        noise_mm = [0.0, 0.01, 0.5, 3.0][k % 4]
        markers = markers + rng.normal(scale=noise_mm / np.sqrt(3.0), size=markers.shape)
        found.append(markers + [0.0, 1e6, 1e9][k % 3])
    return found


def trials() -> list[np.ndarray]:
    """The pinned trials ``(N >= 2, n >= 3, 3)`` [mm]."""
    cases = [m for m in _one_segment_cases().values() if m.shape[0] >= 2 and m.shape[1] >= 3]
    sweep = [arrays[0] for kind, arrays in SWEEP if kind != "joint_center"][::8]
    return cases + sweep + _calibration() + _edge_cases()


TRIALS = trials()


def _numbers(markers: np.ndarray) -> np.ndarray:
    return support._one_segment_numbers(markers[None], support._FLEX)[0, :VERDICT_COLUMNS]


def _assert_same(found: np.ndarray, pinned: np.ndarray) -> None:
    """Equal to 1e-12 relative, or 1e-12 of each column's largest finite value."""
    finite = np.isfinite(pinned)
    assert np.array_equal(np.isfinite(found), finite)
    assert np.array_equal(found[~finite], pinned[~finite], equal_nan=True)
    found, pinned = np.where(finite, found, 0.0), np.where(finite, pinned, 0.0)
    tolerance = 1e-12 * np.maximum(np.abs(pinned), np.abs(pinned).max(axis=0))
    worst = np.abs(found - pinned) - tolerance
    assert worst.max() <= 0.0, np.unravel_index(np.argmax(worst), worst.shape)


@pytest.fixture(scope="module")
def pinned() -> np.ndarray:
    with np.load(PINNED) as stored:
        return stored["numbers"]


def test_the_trials_span_the_kernels_range(pinned):
    assert len(pinned) == len(TRIALS)
    assert {m.shape[1] for m in TRIALS} == set(range(3, 9))
    assert {2, 300} <= {m.shape[0] for m in TRIALS}
    assert pinned[:, 3].any() and not pinned[:, 3].all()  # collinear and not
    assert np.isinf(pinned[:, 6::3]).any() and (pinned[:, 6::3] == 0.0).any()


def test_every_trial_computes_the_pinned_numbers(pinned):
    _assert_same(np.array([_numbers(markers) for markers in TRIALS]), pinned)


def test_a_batch_computes_each_trials_numbers(pinned):
    groups: dict[tuple, list[int]] = {}
    for index, markers in enumerate(TRIALS):
        groups.setdefault(markers.shape, []).append(index)
    batches = [group for group in groups.values() if len(group) > 1]
    assert batches
    for group in batches:
        stacked = np.stack([TRIALS[index] for index in group])
        verdict = support._one_segment_numbers(stacked, support._FLEX)[:, :VERDICT_COLUMNS]
        _assert_same(verdict, pinned[group])


def _frame_number_cases() -> list[np.ndarray]:
    """Trials ``(T, N, n, 3)`` beyond the pinned ones' range: 8 to 20 markers, 3 to 5000
    frames, a marker at the centre of rotation, every frame the same, and mixed batches of
    noisy, noise-free and collinear trials."""
    rng = np.random.default_rng(20261206)
    found = []
    for n_markers, n_frames in ((20, 3), (12, 4), (12, 5000), (8, 300)):
        body = rng.normal(scale=40.0, size=(n_markers, 3)) + 100.0
        body[0] = 0.0  # at the centre of rotation: it does not move
        line = np.outer(rng.uniform(-50.0, 50.0, n_markers), unit(rng.normal(size=3))) + 80.0
        angle = 0.8 * np.sin(np.linspace(0.0, 6.0, n_frames))
        turning = rotation_matrix(np.outer(angle, unit(rng.normal(size=3))))
        moved = np.einsum("fij,mj->fmi", turning, np.stack([body, line]).reshape(-1, 3))
        clean, collinear = np.split(moved, 2, axis=1)
        noisy = clean + rng.normal(scale=0.3, size=clean.shape)
        still = np.repeat(noisy[:1], n_frames, axis=0)
        trials = [noisy, clean, collinear + 0.2 * noisy - 0.2 * clean, still]
        # Twenty markers' pair distances cost seconds a trial (MAX_DISTANCE_MARKERS): one.
        found.append(np.stack(trials[2:3] if n_markers == 20 else trials))
    return found


def test_the_lag_1_statements_numbers_are_the_frame_numbers_kernels():
    """The columns the one-segment kernel ends with are :func:`support._frame_numbers` of
    each trial, alone and in batches: the lag-1 statement reads them in its place. The kernel
    takes them from the cluster's own distances, which it centres on each frame's centroid
    first, and their scatter, which it sums from frame 0's distances: they agree to rounding
    (within 1e-10, relative where above 1), NaN where the others are, and its dependence
    columns are the verdict's own to the last bit."""
    groups: dict[tuple, list[np.ndarray]] = {}
    for markers in TRIALS:
        groups.setdefault(markers.shape, []).append(markers)
    batches = [np.stack(group) for group in groups.values()] + _frame_number_cases()
    for batch in batches:
        numbers = support._one_segment_numbers(batch, support._FLEX)
        expected = support._frame_numbers(batch)
        assert numbers.shape[1] == VERDICT_COLUMNS + row_length(batch.shape[2]) + expected.shape[1]
        found = numbers[:, -support._FRAME_COLUMNS :]
        assert np.array_equal(np.isnan(found), np.isnan(expected))
        np.testing.assert_allclose(found, expected, rtol=1e-10, atol=1e-10)
        assert np.array_equal(found[:, :4], numbers[:, support._DEPENDENCE], equal_nan=True)
        for t in range(len(batch)):
            alone = support._one_segment_numbers(batch[t : t + 1], support._FLEX)
            assert np.array_equal(alone, numbers[t : t + 1], equal_nan=True)


def test_each_frames_noise_is_the_packages_one_sandwich(monkeypatch):
    """Each frame's noise ``J S J'`` (:func:`support._frame_noise_into`, both segments') is
    formed by the package's one ``3 x 3`` sandwich, :func:`small.rotated9_upper`, and the
    compiled kernel computes what its Python source does, to the last bit."""
    rng = np.random.default_rng(11)
    vectors = rng.normal(scale=0.8, size=(6, 3))
    vectors[0] = 0.0  # the series branch
    spread = rng.normal(size=(2, 3, 3))
    moving, reference = spread @ np.swapaxes(spread, 1, 2)
    columns = np.ascontiguousarray(vectors.T)  # each coordinate over the frames
    compiled = np.empty((6, 6))
    support._frame_noise_into(columns, moving, reference, compiled)
    sandwiches = []

    def counted(jacobian: tuple, covariance: tuple) -> tuple:
        sandwiches.append(covariance)
        return small.rotated9_upper(jacobian, covariance)

    monkeypatch.setattr(support, "rotated9_upper", counted)
    python = np.empty((6, 6))
    support._frame_noise_into.__wrapped__(columns, moving, reference, python)
    assert len(sandwiches) == 2 * len(vectors)
    np.testing.assert_array_equal(compiled, python)


def test_the_hinge_weights_read_the_packages_upper_triangle():
    """``u' S v`` is the dot product of :func:`support._upper_weights` with ``S``'s upper
    triangle as the package stores it (:func:`small.rotated9_upper`'s order), for ``u = v`` and
    for two vectors: the frames' noise and the hinge fit read one layout."""
    rng = np.random.default_rng(5)
    u, v = rng.normal(size=(2, 3))
    spread = rng.normal(size=(3, 3))
    symmetric = spread @ spread.T
    upper = np.array(small.rotated9_upper(tuple(np.eye(3).ravel()), tuple(symmetric.ravel())))
    for left, right in ((u, u), (u, v), (v, u)):
        weights = np.array(support._upper_weights(tuple(left), tuple(right)))
        np.testing.assert_allclose(weights @ upper, left @ symmetric @ right, rtol=1e-12)


def test_a_frames_noise_not_positive_definite_across_the_axis_leaves_no_hinge_residual():
    """A frame whose noise across the hinge axis is indefinite, its first diagonal entry
    positive but its determinant negative, makes the residual against each frame's own noise
    NaN (the verdict then reads the mean pose's), in the compiled kernel and its source."""
    n_frames = 8
    axis = unit(np.array([1.0, 2.0, 3.0]))
    basis = np.empty((3, 2))
    small.tangent_basis_into(axis, basis)
    u0, u1 = basis.T
    # About the axis, and a little off it, so that something is left: the fit's axis stays
    # near it, and so its basis U near (u0, u1).
    angles = np.linspace(-0.5, 0.5, n_frames)
    columns = np.outer(axis, angles) + np.outer(u0, 1e-3 * np.cos(7.0 * angles))
    identity = np.zeros((6, n_frames))
    identity[[0, 3, 5]] = 1.0  # in the order of the upper triangle (s00, s01, s02, s11, s12, s22)
    # U' S U = diag(1, -2): its first entry positive, its determinant negative.
    indefinite = np.outer(u0, u0) - 2.0 * np.outer(u1, u1) + np.outer(axis, axis)
    noise = identity.copy()
    noise[:, 3] = indefinite[np.triu_indices(3)]
    for residual in (support._hinge_residual, support._hinge_residual.__wrapped__):
        assert np.isfinite(residual(columns, identity))
        assert np.isnan(residual(columns, noise))


def _write() -> None:
    np.savez_compressed(PINNED, numbers=np.array([_numbers(markers) for markers in TRIALS]))


if __name__ == "__main__":
    _write()


def test_the_lag_1_numbers_near_rounding_differ_by_rounding_alone():
    """Where the noise is a few times the rounding of the coordinates, near the origin and
    far from it, the one-segment kernel's lag-1 columns and :func:`support._frame_numbers`,
    whose distances are formed from other differences, may differ by more than 1e-10 of
    their size, but by no more than :data:`pinning.ROUNDING_TIMES` what a change of the
    markers by one unit in the last place moves the latter: NaN in the same places."""
    rng = np.random.default_rng(1)
    for offset in (1.0, 1e3, 1e6):
        for relative_noise in (1e-12, 1e-11, 1e-10):
            body = rng.normal(scale=40.0, size=(4, 3))
            turns = rotation_matrix(rng.normal(scale=0.5, size=(200, 3)))
            markers = np.einsum("fij,mj->fmi", turns, body) + offset * unit(rng.normal(size=3))
            markers += rng.normal(0.0, relative_noise * max(offset, 40.0), markers.shape)
            found = support._one_segment_numbers(markers[None], support._FLEX)[0]
            found = found[-support._FRAME_COLUMNS :]
            expected = support._frame_numbers(markers[None])[0]
            assert np.array_equal(np.isnan(found), np.isnan(expected))
            moved = np.zeros(support._FRAME_COLUMNS)
            for seed in range(3):
                nudged = support._frame_numbers(random_signs(markers, seed)[None])[0]
                moved = np.fmax(moved, np.abs(nudged - expected))
            allowed = np.fmax(1e-10 * np.fmax(np.abs(expected), 1.0), ROUNDING_TIMES * moved)
            known = ~np.isnan(expected)
            assert (np.abs(found - expected)[known] <= allowed[known]).all(), (found, expected)


def _arc_sd_in_frame_order(markers, variance, principal_rms, off_rms) -> np.ndarray:
    """:func:`support._arc_rotation_sd_deg` read plainly: per coordinate its mean and its
    squares, every sum from 0 in frame order, then the three coordinates' squares added."""
    n_trials, n_frames, n_markers, _ = markers.shape
    found = np.empty((n_trials, n_markers))
    for t in range(n_trials):
        noise = 3.0 * float(variance[t]) * (n_frames - 1) / n_frames
        rotation_sq = float(principal_rms[t]) ** 2 + float(off_rms[t]) ** 2
        for i in range(n_markers):
            squares = [0.0, 0.0, 0.0]
            for c in range(3):
                values = [float(x) for x in markers[t, :, i, c]]
                mean = 0.0
                for x in values:
                    mean += x
                mean /= n_frames
                for x in values:
                    squares[c] += (x - mean) * (x - mean)
            travel = (squares[0] + squares[1] + squares[2]) / n_frames - noise
            ratio = np.inf if travel <= 0.0 else float(variance[t]) * rotation_sq / travel
            found[t, i] = np.degrees(np.sqrt(ratio))
    return found


def test_the_arc_sd_sums_every_coordinate_in_frame_order_to_the_bit():
    """The arc SD's sums keep their order (each coordinate's frame by frame, then the three
    added) to the last bit, on frames reversed, far from the origin, with a NaN frame and of
    many markers: the tolerance of the pinned numbers would let a reordered sum through."""
    rng = np.random.default_rng(11)
    base = TRIALS[0]
    nan_frame = base.copy()
    nan_frame[1] = np.nan
    many = rng.normal(scale=50.0, size=(40, 12, 3))
    for trial in (base, base[::-1], base + 1e6, nan_frame, base[:3], many):
        stacked = np.ascontiguousarray(trial[None])
        variance, principal, off = rng.uniform(0.1, 1.0, size=(3, 1))
        found = support._arc_rotation_sd_deg(stacked, variance, principal, off)
        expected = _arc_sd_in_frame_order(stacked, variance, principal, off)
        assert found.tobytes() == expected.tobytes()


@pytest.mark.parametrize("n_frames", [3, 2, 1200])
def test_the_rotation_ratios_are_numpys_to_the_bit(n_frames):
    """The compiled RMS rotations and F ratios of the two-segment rotation test
    (:func:`support._rotation_ratios`) are the NumPy expressions they stand for, to the bit: the
    sums of ``raw`` in order over the frames, each test's sum over its degrees of freedom (the
    hinge test's at least 1) over the noise, 1 for a trial of rounding only."""
    rng = np.random.default_rng(3)
    raw = np.sort(rng.uniform(0.0, 2.0, (4, 3)), axis=1) * [[1e-9], [1.0], [1e3], [1.0]]
    sums = rng.uniform(1.0, 5e3, (4, 2))
    variance = rng.uniform(0.01, 2.0, 4)
    exact = np.array([False, True, False, False])
    any_dof, off_axis = 3 * (n_frames - 1), 2 * (n_frames - 2)
    rms, second, ratios = support._rotation_ratios(
        raw, sums, variance, exact, n_frames, any_dof, off_axis
    )
    noise = np.where(exact, 1.0, variance)
    expected = np.stack([sums[:, 0] / any_dof, sums[:, 1] / max(off_axis, 1)]) / noise
    assert np.array_equal(rms, np.sqrt(raw.sum(axis=1) / n_frames))
    assert np.array_equal(second, np.sqrt(raw[:, :2].sum(axis=1) / n_frames))
    assert np.array_equal(ratios, expected)


def test_each_clusters_own_noise_scales_its_inertia_as_numpy_would():
    """:func:`support._scaled_to_own_noise` scales each trial's inverse inertia and its largest
    eigenvalue by the cluster's own residual variance over the pooled one, to the bit of the
    NumPy form, and leaves a trial whose pooled residual is not positive unscaled; its inputs
    are not written to."""
    rng = np.random.default_rng(5)
    residual_ss, dof = rng.uniform(1.0, 50.0, 4), 7
    pooled = np.array([0.3, 0.0, 2.5, np.nan])
    inertia_inv, weakest = rng.normal(size=(4, 3, 3)), rng.uniform(1e-6, 1e-3, 4)
    before = inertia_inv.copy(), weakest.copy()
    scaled, scaled_weakest = support._scaled_to_own_noise(
        residual_ss / dof, pooled, inertia_inv, weakest
    )
    weight = np.divide(residual_ss / dof, pooled, out=np.ones_like(pooled), where=pooled > 0.0)
    assert np.array_equal(scaled, inertia_inv * weight[:, None, None])
    assert np.array_equal(scaled_weakest, weakest * weight)
    assert np.array_equal(scaled[1], inertia_inv[1]) and np.array_equal(scaled[3], inertia_inv[3])
    assert np.array_equal(inertia_inv, before[0]) and np.array_equal(weakest, before[1])
