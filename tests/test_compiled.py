"""Compiled kernels (jointbench.numerics.compiled): each computes what its Python source says.

The source is the specification (and what a job's code fingerprint tracks); Numba only makes it
fast. Each kernel is run compiled and as plain Python on the same inputs, including the cases
it must hand back to a slower path.
"""

from __future__ import annotations

import functools
import subprocess
import sys

import numpy as np
import pytest

from jointbench.estimators import axis, registry, sphere, validation
from jointbench.geometry import rotation_matrix, unit
from jointbench.numerics import compiled, poses
from jointbench.numerics.compiled import kernel_array
from jointbench.numerics.magnitudes import largest_coordinate, largest_magnitude


def _both(kernel, make_outputs, *inputs):
    """``kernel`` compiled and interpreted on ``inputs``: the two tuples of outputs."""
    runs = []
    for function in (kernel, kernel.__wrapped__):
        outputs = make_outputs()
        function(*inputs, *outputs)
        runs.append(outputs)
    return runs


def test_rotation_kernel():
    """The compiled kernel computes what its Python source says, to the last bits: the source
    is the specification the fingerprint tracks, Numba only makes it fast."""

    rng = np.random.default_rng(21)
    source = rng.normal(scale=30.0, size=(3, 3))
    target = source @ rotation_matrix(unit(rng.normal(size=(300, 3))) * 0.7).swapaxes(1, 2)
    target += rng.normal(scale=0.5, size=target.shape)
    centred_target = target - target.mean(1, keepdims=True)
    centred_source = source - source.mean(0)
    cross = np.concatenate(
        [
            np.einsum("fmi,mj->fij", centred_target, centred_source),
            rng.normal(size=(100, 3, 3)),
            np.outer([1.0, 2.0, 3.0], [1.0, 0.0, 0.0])[None],
            np.zeros((1, 3, 3)),
        ]
    )
    # The realistic fits start from the bound the pose fit passes, the others from |H|.
    bound = np.full(len(cross), np.inf)
    bound[:300] = 0.5 * (np.sum(centred_target**2, axis=(1, 2)) + np.sum(centred_source**2))
    outputs = []
    for kernel in (poses._horn_rotations, poses._horn_rotations.__wrapped__):
        rotation = np.empty_like(cross)
        unsettled = np.empty(len(cross), dtype=bool)
        kernel(cross, bound, rotation, unsettled)
        outputs.append((rotation, unsettled))
    (compiled, compiled_unsettled), (interpreted, interpreted_unsettled) = outputs
    np.testing.assert_array_equal(compiled_unsettled, interpreted_unsettled)
    assert compiled_unsettled[-2:].all() and not compiled_unsettled[:300].any()
    settled = ~compiled_unsettled
    np.testing.assert_allclose(compiled[settled], interpreted[settled], rtol=0, atol=1e-14)


@pytest.mark.parametrize(
    "sample",
    [
        None,
        (3, 1, [np.nan, 0, 0]),
        (0, 2, [0, np.inf, 1]),
        (5, 0, [0, 0, 0]),
        (2, 2, [0, 0, 1]),
        (4, 1, [0, -1e200, 1]),
    ],
)
def test_input_check_kernels(sample):
    """The input checks' compiled pass finds what its Python source says, per trial: non-finite
    samples, coordinates beyond float64's sums, (0, 0, 0) samples, markers that stay at frame 0
    and markers that slide along lines."""
    rng = np.random.default_rng(22)
    markers = rng.normal(scale=100.0, size=(7, 3, 3))
    if sample is not None:
        frame, marker, value = sample
        markers[frame, marker] = value
    still = np.repeat(markers[:1], len(markers), axis=0)
    sliding = markers[0] + np.linspace(0.0, 50.0, 7)[:, None, None] * np.array([0.2, 0.5, -0.3])
    batch = np.stack([markers, still, sliding])
    runs, measured = [], []
    for function in (validation._first_failures, validation._first_failures.__wrapped__):
        failures = np.full(len(batch), -1, dtype=np.int8)
        spans = np.full(len(batch), -1.0)
        checks = validation._SAMPLES | validation._MOVES | validation._LINES
        # The probe for non-finite samples multiplies them by zero: NumPy's scalars warn of
        # inf * 0 where the compiled code, with the same answer, does not.
        with np.errstate(invalid="ignore"):
            first = function(batch, checks, 1e-9, failures, spans)
        assert first == failures[np.flatnonzero(failures)[0]] if failures.any() else first == 0
        runs.append(failures)
        measured.append(spans)
    np.testing.assert_array_equal(*runs)
    np.testing.assert_array_equal(*measured)
    # Each trial's size, failing or not, is typical_span's of it over the frames checked.
    expected_spans = [validation.typical_span(trial, validation._SPAN_FRAMES) for trial in batch]
    np.testing.assert_array_equal(measured[0], expected_spans)
    finite = np.isfinite(batch).all(axis=(1, 2, 3))
    origin = (~batch.any(axis=-1)).any(axis=(1, 2))
    with np.errstate(invalid="ignore"):  # inf - inf in the non-finite trials
        moved = [np.abs(t - t[0]).max() > 1e-9 * max(1.0, np.abs(t[0]).max()) for t in batch]
    # The first check failed, in the order their errors are raised; motion is measured only
    # on trials whose samples pass.
    too_large = np.abs(np.nan_to_num(batch)).max(axis=(1, 2, 3)) > largest_coordinate(7 * 3)
    expected = [
        validation._NOT_FINITE
        if not finite[t]
        else validation._TOO_LARGE
        if too_large[t]
        else validation._AT_ORIGIN
        if origin[t]
        else validation._STILL
        if not moved[t]
        else validation._STRAIGHT
        if t > 0
        else 0
        for t in range(len(batch))
    ]
    np.testing.assert_array_equal(runs[0], expected)


def _hinge_markers(rng, n_trials: int) -> np.ndarray:
    angles = np.linspace(0.0, 1.0, 121)[None, :, None] * rng.uniform(0.5, 1.0, (n_trials, 1, 1))
    tilt = 0.3 * angles * np.array([0.0, 1.0, 0.0])
    rotations = rotation_matrix(angles * np.array([1.0, 0.0, 0.0]) + tilt)
    body = rng.normal(scale=40.0, size=(3, 3))
    return np.einsum("tfij,pj->tfpi", rotations, body) + rng.normal(size=(n_trials, 121, 3, 3))


def test_radial_cost_kernel():
    rng = np.random.default_rng(3)
    markers = _hinge_markers(rng, 3)
    costs = axis.AxisCosts(markers, rng.normal(scale=5.0, size=(3, 3)))
    directions = unit(rng.normal(size=(40, 3)))
    trials = rng.integers(0, 3, 40).astype(np.intp)
    compiled, interpreted = _both(
        axis._radial_costs,
        lambda: (np.empty(40), np.empty((40, costs._w.shape[2]))),
        costs._w,
        costs._w_sq,
        directions,
        trials,
        3,
    )
    for a, b in zip(compiled, interpreted, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-12)


def test_nm_kernel():
    rng = np.random.default_rng(4)
    markers = _hinge_markers(rng, 4)[:, :40]
    # A noise-free trial has a singular scatter: handed back (code 3) to the SVD path.
    angles = np.linspace(0.0, 0.8, 40)[:, None] * unit(np.array([1.0, 2.0, 0.5]))
    markers[1] = np.einsum("fij,pj->fpi", rotation_matrix(angles), rng.normal(size=(3, 3)) * 30)
    n_trials = len(markers)
    compiled, interpreted = _both(
        sphere._nm_trials,
        lambda: (
            np.empty((n_trials, 3)),
            np.empty((n_trials, 3)),
            np.empty(n_trials),
            np.empty(n_trials, dtype=np.int64),
        ),
        np.ascontiguousarray(markers),
        sphere._EPS,
    )
    np.testing.assert_array_equal(compiled[3], interpreted[3])
    assert list(compiled[3]) == [0, 3, 0, 0]
    solved = compiled[3] == 0
    for a, b in zip(compiled[:3], interpreted[:3], strict=True):
        np.testing.assert_allclose(a[solved], b[solved], rtol=1e-12, atol=1e-9)


def test_sphere_kernels():
    """LS's moments and solution and BC's iteration, compiled and interpreted, on noisy trials
    and on a pure hinge (a singular ``A``, whose null direction the pseudo-inverse drops)."""
    rng = np.random.default_rng(7)
    markers = _hinge_markers(rng, 3)[:, :40] + rng.normal(size=(3, 40, 3, 3)) * 0.5
    angles = np.linspace(0.0, 0.8, 40)[:, None] * np.array([0.0, 0.0, 1.0])
    markers[2] = np.einsum("fij,pj->fpi", rotation_matrix(angles), rng.normal(size=(3, 3)) * 30)
    data = np.ascontiguousarray(markers)
    n_trials = len(data)
    origins = np.ascontiguousarray(data[:, 0, 0])
    moments = _both(
        sphere._sphere_moments,
        lambda: (np.empty((n_trials, 3, 4)), np.empty((n_trials, 3, 4, 4))),
        data,
        origins,
    )
    for a, b in zip(*moments, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-9)
    means, grams = moments[0]
    solutions = _both(
        sphere._ls_solve,
        lambda: (np.empty((n_trials, 3, 3)), np.empty((n_trials, 3))),
        grams,
        40,
        sphere.RCOND,
    )
    for a, b in zip(*solutions, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-12)
    a_pinv = solutions[0][0]
    # The hinge's A has rank 2: A^+ A projects onto the plane of rotation.
    total = grams[2].sum(axis=0) / 40
    np.testing.assert_allclose(
        a_pinv[2] @ (2.0 * total[:3, :3]), np.diag([1.0, 1.0, 0.0]), atol=1e-9
    )
    fits = _both(
        sphere._algebraic_fits,
        lambda: (np.empty((n_trials, 3)), np.empty(n_trials)),
        data,
        origins,
        means,
        np.ascontiguousarray(solutions[0][1]),
    )
    for a, b in zip(*fits, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-10)
    # Radii and f2 are those of the LS definition (paper A eq. 4 with r_p profiled out).
    centers = origins + solutions[0][1]
    distances = np.sum((data - centers[:, None, None]) ** 2, axis=-1)
    np.testing.assert_allclose(fits[0][0], np.sqrt(distances.mean(axis=1)), rtol=1e-9)
    deviations = distances - distances.mean(axis=1, keepdims=True)
    np.testing.assert_allclose(fits[0][1], (deviations**2).sum(axis=(1, 2)), rtol=1e-6, atol=1e-9)
    sum_of_means = means[..., :3].sum(axis=1)
    limits = np.full(n_trials, 1e6)
    b_vector = np.ascontiguousarray(grams.sum(axis=1)[:, :3, 3] / 40)
    iterations = _both(
        sphere._bc_iterations,
        lambda: (
            np.empty((n_trials, 3)),
            np.empty(n_trials),
            np.empty(n_trials, dtype=np.int64),
            np.empty(n_trials, dtype=np.int64),
        ),
        grams,
        means,
        sum_of_means,
        a_pinv,
        b_vector,
        limits,
        40,
        600,
        1e-4,
        1e-4,
    )
    np.testing.assert_array_equal(iterations[0][2], iterations[1][2])
    np.testing.assert_array_equal(iterations[0][3], iterations[1][3])
    for a, b in zip(iterations[0][:2], iterations[1][:2], strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-12)


def test_kernels_load_numba_only_when_called():
    code = (
        "import sys, numpy as np\n"
        "from jointbench.estimators import registry\n"
        "from jointbench.numerics import poses\n"
        "before = 'numba' in sys.modules\n"
        "poses.best_rotation(np.eye(3))\n"
        "print(before, 'numba' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["False", "True"]


def test_each_kernel_is_compiled_once_whatever_its_inputs_look_like():
    """Numba compiles a kernel once per argument type, and a read-only or strided array is a
    type of its own: callers hand the kernels writable contiguous copies, so one signature
    serves every call."""
    rng = np.random.default_rng(5)
    cross = rng.normal(size=(5, 3, 3))
    read_only_cross = cross.copy()
    read_only_cross.setflags(write=False)
    poses.best_rotation(cross)
    poses.best_rotation(read_only_cross, bound=np.full(5, 1e3))
    poses.best_rotation(cross[::2], bound=np.full(3, 1e3)[None][0])
    markers = _hinge_markers(rng, 4)[:, :40]
    read_only = markers.copy()
    read_only.setflags(write=False)
    for name in ("NM", "LS", "BC"):
        registry.many("center", name, checked=False)(markers)
        registry.many("center", name, checked=False)(read_only)
    sphere.fit_bc(markers[0], max_iterations=np.int64(50), tol_x=1)
    costs = axis.AxisCosts(markers, rng.normal(size=(4, 3)))
    directions = unit(rng.normal(size=(6, 3)))
    frozen_directions = directions.copy()
    frozen_directions.setflags(write=False)
    costs.radial(directions, np.arange(6) % 4)
    costs.radial(frozen_directions, (np.arange(12) % 4)[::2])
    costs.radial_distances(frozen_directions[0], 1)
    kernels = (
        poses._horn_rotations,
        sphere._nm_trials,
        sphere._sphere_moments,
        sphere._ls_solve,
        sphere._algebraic_fits,
        sphere._bc_iterations,
        axis._radial_costs,
    )
    for kernel in kernels:
        assert len(kernel._compiled.signatures) == 1, (kernel.__name__, kernel._compiled.signatures)


def test_radial_costs_refuse_trials_that_do_not_fit():
    rng = np.random.default_rng(6)
    costs = axis.AxisCosts(_hinge_markers(rng, 4)[:, :40], rng.normal(size=(4, 3)))
    directions = unit(rng.normal(size=(3, 3)))
    with pytest.raises(ValueError, match="one per direction"):
        costs.radial(directions, np.array([0, 1]))
    with pytest.raises(ValueError, match=r"trial 7 .*4 trials"):
        costs.radial(directions, np.array([0, 1, 7]))
    with pytest.raises(ValueError, match="4 trials"):
        costs.radial_distances(directions[0], trial=7)


def test_symmetric_eigen_agrees_with_lapack_compiled_and_as_written():
    """The Jacobi eigen-decomposition of the small matrices a kernel decomposes per trial: to
    rounding against LAPACK, on random, diagonal, rank-deficient and repeated-eigenvalue
    matrices of 1 to 15 rows and magnitudes from 1e-8 to 1e8."""
    from jointbench.numerics.small import symmetric_eigen

    rng = np.random.default_rng(5)
    cases = []
    for n in (1, 2, 3, 4, 6, 15):
        random = rng.normal(size=(n, n)) * 10.0 ** rng.uniform(-8, 8)
        basis = np.linalg.qr(rng.normal(size=(n, n)))[0]
        cases += [
            random + random.T,
            np.diag(rng.normal(size=n)),
            basis @ np.diag(np.r_[np.ones(min(n, 2)), np.zeros(n - min(n, 2))]) @ basis.T,
            np.zeros((n, n)),
        ]
    for matrix in cases:
        expected = np.linalg.eigvalsh(matrix)
        scale = max(np.abs(expected).max(), 1e-300)
        for function in (symmetric_eigen, symmetric_eigen.__wrapped__):
            values, vectors = function(matrix)
            np.testing.assert_allclose(values, expected, rtol=0, atol=1e-13 * scale)
            assert np.all(np.diff(values) >= 0)
            np.testing.assert_allclose(vectors.T @ vectors, np.eye(len(matrix)), atol=1e-13)
            np.testing.assert_allclose(
                vectors @ np.diag(values) @ vectors.T, matrix, rtol=0, atol=1e-13 * scale
            )


def test_the_three_by_three_jacobi_gives_the_general_loops_bits():
    """The unrolled 3 x 3 Jacobi sweeps are the general ones to the bit, rotation by rotation:
    on random symmetric matrices, nearly isotropic and rank-deficient ones, diagonal and zero
    matrices, magnitudes from 1e-200 to 1e200, and the non-finite. Compiled, as the verdict
    calls them."""
    from jointbench.numerics.small import _jacobi, _jacobi3

    rng = np.random.default_rng(33)
    random = rng.normal(size=(400, 3, 3))
    cases = list(random + np.swapaxes(random, 1, 2))
    cases += list(np.eye(3) + 1e-9 * (random[:50] + np.swapaxes(random[:50], 1, 2)))
    basis = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    cases += [basis @ np.diag(values) @ basis.T for values in ([1.0, 1.0, 0.0], [2.0, 0.0, 0.0])]
    cases += [np.diag([3.0, 1.0, 2.0]), np.zeros((3, 3)), np.full((3, 3), np.nan)]
    cases += [scale * (m + m.T) for m in random[:40] for scale in (1e-200, 1e200)]
    for matrix in cases:
        general, unrolled = matrix.copy(), matrix.copy()
        general_vectors, unrolled_vectors = np.eye(3), np.eye(3)
        _jacobi(general, general_vectors)
        _jacobi3(unrolled, unrolled_vectors)
        np.testing.assert_array_equal(unrolled, general)
        np.testing.assert_array_equal(unrolled_vectors, general_vectors)


def test_a_kernel_calls_another_kernel_compiled_and_as_written():
    """A kernel may call another: compiled, it calls the other's compiled form; as written,
    the other kernel as a Python object."""
    from jointbench.estimators import support

    markers = np.random.default_rng(2).normal(scale=30.0, size=(2, 8, 4, 3))
    compiled = support._one_segment_numbers(markers, support._FLEX)
    interpreted = support._one_segment_numbers.__wrapped__(markers, support._FLEX)
    np.testing.assert_allclose(compiled, interpreted, rtol=1e-9, atol=1e-12)


def test_the_line_check_decides_as_the_eigenvalues_do_near_its_threshold():
    """Trajectories bent off a line by a middle/largest eigenvalue ratio from far below to far
    above the threshold (1e-12): the kernel, which skips the eigenvalue solver for clearly bent
    ones, calls a trial straight exactly when every marker's scatter eigenvalues say so."""
    rng = np.random.default_rng(8)
    n_frames = 50
    along = rng.uniform(-40.0, 40.0, n_frames)
    across = rng.normal(size=n_frames)
    across -= along * (across @ along) / (along @ along) + across.mean()
    direction, normal = unit(np.array([0.3, -0.5, 0.8])), unit(np.array([1.0, 1.0, 0.5 / 0.8]))
    normal = unit(normal - direction * (normal @ direction))
    trials = []
    for exponent in np.arange(-16.1, -4.0, 0.25):
        bend = np.sqrt(10.0**exponent * (along @ along) / (across @ across))
        line = 500.0 + along[:, None] * direction + bend * across[:, None] * normal
        trials.append(np.stack([line, line + 7.0, line - 3.0], axis=1))
        curved = np.stack([line, line + 7.0, 500.0 + 30.0 * rng.normal(size=(n_frames, 3))], 1)
        trials.append(curved)
    batch = np.stack(trials)
    failures = np.empty(len(batch), dtype=np.int8)
    validation._first_failures(batch, validation._LINES, 1e-9, failures, np.empty(0))

    def straight(trial):
        for marker in np.moveaxis(trial, 1, 0):
            centred = marker - marker.mean(axis=0)
            eigenvalues = np.linalg.eigvalsh(centred.T @ centred)
            if eigenvalues[1] > 1e-12 * eigenvalues[2]:
                return False
        return True

    expected = [validation._STRAIGHT if straight(trial) else 0 for trial in batch]
    np.testing.assert_array_equal(failures, expected)
    assert 0 < np.count_nonzero(failures) < len(batch) // 2


def test_a_kernel_is_compiled_on_its_first_call_and_then_called_directly(monkeypatch):
    """Compiled on the first call, not before; later calls reach the compiled dispatcher
    without asking for it again (a checked fit calls several kernels of microseconds)."""
    from jointbench.numerics.compiled import kernel

    def twice(x):
        return 2.0 * x

    doubled = kernel(twice)
    assert doubled._compiled is None
    asked = []
    compiled = type(doubled).compiled
    monkeypatch.setattr(
        type(doubled), "compiled", lambda self: asked.append(self) or compiled(self)
    )
    assert doubled(1.5) == 3.0
    assert asked == [doubled] and doubled._compiled is not None
    assert doubled(2.5) == 5.0 and doubled(np.float64(0.5)) == 1.0
    assert asked == [doubled]


def test_a_kernel_array_is_the_array_itself_only_where_it_is_already_a_kernels_input():
    markers = np.random.default_rng(9).normal(size=(4, 3, 3))
    assert kernel_array(markers) is markers
    counts = np.arange(5)
    assert kernel_array(counts, np.int64) is counts
    read_only = markers.copy()
    read_only.setflags(write=False)
    big_endian = markers.astype(">f8")
    for other in (read_only, markers[::2], markers.astype(np.float32), big_endian, counts):
        ready = kernel_array(other)
        assert ready is not other and ready.dtype == np.float64
        assert ready.flags.c_contiguous and ready.flags.writeable
        np.testing.assert_array_equal(ready, other)
    assert kernel_array(markers, np.int64).dtype == np.int64
    assert kernel_array([[1.0, 2.0]]).flags.carray


def test_a_centres_input_checks_are_one_kernel_call(monkeypatch):
    """check_input's checks of one segment's markers (samples, motion, lines and the cluster's
    size) run in one compiled pass: a checked call pays one kernel dispatch for them."""
    called = []
    kernel_type = type(validation._first_failures)
    call = kernel_type.__call__
    monkeypatch.setattr(
        kernel_type, "__call__", lambda self, *a: called.append(self) or call(self, *a)
    )
    rng = np.random.default_rng(12)
    validation.check_input("center", (_hinge_markers(rng, 1)[0],))
    assert [kernel.__name__ for kernel in called] == ["_first_failures"]
    for scale, refused in ((1e-3, "metres read as millimetres"), (1e2, "read as centimetres")):
        with pytest.raises(ValueError, match=refused):
            validation.check_input("center", (scale * _hinge_markers(rng, 1)[0],))


def _doubled(x: float) -> float:
    return 2.0 * x


def test_a_kernels_cache_entry_is_named_by_how_it_is_compiled(monkeypatch):
    """Machine code compiled under other options (``fastmath``, say) is never loaded from the
    cache as this code's: the options are part of the entry's name, and are the ones used."""
    plain = compiled.kernel(_doubled)
    assert plain.compiled().targetoptions.items() >= compiled.COMPILE_OPTIONS.items()
    monkeypatch.setattr(compiled, "COMPILE_OPTIONS", {**compiled.COMPILE_OPTIONS, "fastmath": True})
    fast = compiled.kernel(_doubled)
    assert fast.digest() != plain.digest()
    assert fast.compiled().targetoptions["fastmath"]


def test_the_largest_magnitude_is_a_running_maximum_read_in_any_order():
    """:func:`largest_magnitude` keeps three running maxima where the verdict's pass kept one:
    the same number, a NaN passed over and an infinity kept as that one kept them."""
    rng = np.random.default_rng(5)
    for trial in range(300):
        markers = rng.normal(size=(rng.integers(1, 40), rng.integers(1, 5), 3))
        markers *= 10.0 ** rng.integers(-6, 7)
        if trial % 3 == 1:
            markers.flat[rng.integers(markers.size)] = np.nan
        if trial % 5 == 2:
            markers.flat[rng.integers(markers.size)] = -np.inf
        running = functools.reduce(lambda largest, x: max(largest, abs(x)), markers.flat, 0.0)
        assert largest_magnitude(markers) == running
        if np.isfinite(markers).all():
            assert largest_magnitude(markers) == max(markers.max(), -markers.min())


@pytest.mark.parametrize("axis", range(3))
@pytest.mark.parametrize("checks", ["samples", "lines"])
def test_a_coordinate_too_large_on_any_one_axis_is_refused(axis, checks):
    """The input checks read the largest coordinate per axis: one beyond float64's sums on
    any single axis, the others small, is refused by the sample checks, and by the line test
    (whose sums it would overflow) where that test alone is asked for."""
    rng = np.random.default_rng(23)
    batch = rng.normal(scale=100.0, size=(1, 9, 3, 3))
    bound = largest_coordinate(9 * 3)
    batch[0, 6, 2, axis] = -2.0 * bound
    asked = validation._SAMPLES if checks == "samples" else validation._LINES
    failures = np.zeros(1, dtype=np.int8)
    assert validation._first_failures(batch, asked, 1e-9, failures, np.empty(0)) == (
        validation._TOO_LARGE
    )
    if checks == "samples":
        with pytest.raises(ValueError, match=r"at marker 2, frame 6 \(1 in all\), beyond the "):
            validation.check_markers(batch[0])
