"""The artefact screen of marker arrays (jointbench.screening) and its cost in the public fits.

``find_artefacts`` (what the public fits run) must find exactly what the whole ``screen``
finds, on hard cases and on seeded random trials with injected artefacts; the bound that lets
it skip the cluster's mean shape must hold; its compiled kernels compute what their Python
source says; and the screen must cost less than the fit it guards.
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

import jointbench
from jointbench import screening
from jointbench.geometry import rotation_matrix
from jointbench.numerics.poses import _horn_rotations

RULES = screening.ArtefactRules()


def _labels(n_markers: int) -> tuple[str, ...]:
    return tuple(f"m[:, {column}]" for column in range(n_markers))


def _cluster(rng, n_markers=3, n_frames=120, noise_mm=1.0, rom_deg=30.0):
    """A rigid cluster ``(n_frames, n_markers, 3)`` [mm] turning and drifting, with noise."""
    body = rng.normal(scale=30.0, size=(n_markers, 3))
    t = np.linspace(0.0, 1.0, n_frames)[:, None]
    rotvec = np.radians(rom_deg) * np.hstack(
        [np.sin(2 * np.pi * t), 0.5 * np.cos(3 * np.pi * t), 0.2 * t]
    )
    markers = np.einsum("fij,mj->fmi", rotation_matrix(rotvec), body)
    markers += 20.0 * t[:, :, None] + np.array([10.0, -40.0, 25.0])
    return markers + rng.normal(scale=noise_mm, size=markers.shape)


def _outcome(artefacts, swaps):
    return (
        [(a.kind, a.label, a.frame, a.size_mm, a.level_mm) for a in artefacts],
        [(s.labels, s.start, s.stop, s.n_frames) for s in swaps],
    )


def _same_as_screen(markers):
    labels = _labels(markers.shape[1])
    whole = screening.screen(markers, labels, "m")
    fast = screening.find_artefacts(markers, labels, "m")
    assert _outcome(*fast) == _outcome(whole.artefacts, whole.swaps)
    return fast


def test_swaps_at_several_frames_are_found_as_the_whole_screen_finds_them():
    markers = _cluster(np.random.default_rng(1), n_markers=4)
    markers[20:30, [0, 2]] = markers[20:30, [2, 0]]
    markers[80:90, [1, 3]] = markers[80:90, [3, 1]]
    artefacts, swaps = _same_as_screen(markers)
    # The second swap, which the rigidity check flags only frame by frame, is recognised by
    # the distance test.
    assert [(s.labels, s.start, s.stop) for s in swaps] == [
        (("m[:, 0]", "m[:, 2]"), 20, 30),
        (("m[:, 1]", "m[:, 3]"), 80, 90),
    ]
    assert {a.frame for a in artefacts} == set(range(20, 30)) | set(range(80, 90))


@pytest.mark.parametrize("n_markers", [1, 2, 3, 4])
def test_one_marker_jumping_is_named_at_its_frame(n_markers):
    markers = _cluster(np.random.default_rng(2), n_markers=n_markers)
    markers[70:, -1] += [0.0, 150.0, 0.0]
    artefacts, swaps = _same_as_screen(markers)
    assert artefacts and not swaps
    assert f"m[:, {n_markers - 1}]" in {a.label for a in artefacts}
    assert 70 in {a.frame for a in artefacts}


@pytest.mark.parametrize("rows", [slice(0, 10), slice(110, 120), slice(50, 60)])
def test_gaps_at_the_start_end_or_middle_are_no_artefact(rows):
    markers = _cluster(np.random.default_rng(3), n_markers=4)
    markers[rows, 1] = np.nan
    assert _same_as_screen(markers) == ((), ())
    assert not screening.surely_rigid(markers, _labels(4), "m", RULES)


@pytest.mark.parametrize("broken", [False, True])
def test_the_whole_screen_reuses_the_fitted_bounds_typical_frame_and_pose_fit(monkeypatch, broken):
    """Where the marker-frame bounds do not clear a complete cluster and the distance test
    finds no swap, the whole screen starts from the typical frame and pose fit the fitted
    bounds found, and from no swapped frame: it finds what it finds on its own without
    looking for them again."""
    markers = _cluster(np.random.default_rng(24), n_markers=4, noise_mm=1.5)
    if broken:
        markers[60:66, 2] += [0.0, 150.0, 0.0]
    labels = _labels(4)
    typical, cleared, _ = screening._screen_sums(markers, screening._rigid_limit(RULES))
    assert typical >= 0 and not cleared
    whole = screening.screen(markers, labels, "m")
    assert bool(whole.artefacts) == broken
    calls = []

    def recorded(name, function):
        def call(*arguments):
            calls.append(name)
            return function(*arguments)

        return call

    for name in ("find_exchanges", "typical_shape", "mean_shape", "_posed"):
        monkeypatch.setattr(screening, name, recorded(name, getattr(screening, name)))
    assert _outcome(*screening.find_artefacts(markers, labels, "m")) == _outcome(
        whole.artefacts, whole.swaps
    )
    # One pose fit of the typical frame, for the bounds, then straight to the mean shape.
    assert calls[:2] == ["_posed", "mean_shape"] and "find_exchanges" not in calls


@pytest.mark.parametrize("noise_mm", [0.0, 0.3, 0.6])
def test_clean_clusters_are_cleared_by_the_bound(noise_mm):
    markers = _cluster(np.random.default_rng(4), noise_mm=noise_mm)
    assert screening.surely_rigid(markers, _labels(3), "m", RULES)
    assert _same_as_screen(markers) == ((), ())


@pytest.mark.parametrize("seed", [4, 8])
def test_a_clean_cluster_just_past_the_marker_frame_bound_needs_no_pose_fit_of_every_frame(
    monkeypatch, seed
):
    """5000 frames whose marker-frame bounds just exceed the limit: the few frames that
    exceed it, each posed alone, clear the cluster, and the screen finds what the whole
    screen finds without fitting a pose to every frame."""
    markers = _cluster(np.random.default_rng(seed), n_frames=5000, noise_mm=0.7)
    typical, cleared, _ = screening._screen_sums(markers, screening._rigid_limit(RULES))
    assert typical >= 0 and not cleared
    whole = screening.screen(markers, _labels(3), "m")
    assert np.nanmax(whole.residuals) <= RULES.min_residual_mm
    posed = []
    monkeypatch.setattr(screening, "_posed", lambda *arguments: posed.append(arguments))
    assert screening.surely_rigid(markers, _labels(3), "m", RULES)
    found = screening.find_artefacts(markers, _labels(3), "m")
    assert _outcome(*found) == _outcome(whole.artefacts, whole.swaps)
    assert posed == []


def test_markers_on_a_line_leave_the_bound_to_the_fitted_poses():
    """A 3-marker cluster two of whose markers coincide gives no marker frame: that bound
    fails (NaN), and the typical frame's fitted poses clear it."""
    markers = _cluster(np.random.default_rng(14), noise_mm=0.3)
    markers[:, 2] = markers[:, 1]
    typical = screening._most_typical(markers)
    assert np.isnan(screening._rigid_misfits(markers, typical, False)[1])
    assert screening.surely_rigid(markers, _labels(3), "m", RULES)
    assert _same_as_screen(markers) == ((), ())


def test_large_noise_is_left_to_the_whole_screen():
    markers = _cluster(np.random.default_rng(5), noise_mm=5.0)
    assert not screening.surely_rigid(markers, _labels(3), "m", RULES)
    _same_as_screen(markers)


def test_two_segments_name_the_array_with_the_swap():
    rng = np.random.default_rng(6)
    proximal, distal = _cluster(rng), _cluster(rng, rom_deg=60.0)
    distal[40:60, [0, 1]] = distal[40:60, [1, 0]]
    named = r"^distal\[:, 0\] and distal\[:, 1\] exchange labels at frame 40 and back at "
    with pytest.raises(ValueError, match=named + "frame 60; ") as error:
        jointbench.fit_joint_center(proximal, distal)
    assert "proximal" not in str(error.value)


@pytest.mark.parametrize(
    ("labels", "one", "both", "listed"),
    [
        (
            ("markers[:, 0]", "markers[:, 1]", "markers[:, 2]"),
            "markers[:, 0]",
            "markers[:, 0] and markers[:, 2]",
            "markers[:, 0], markers[:, 1], markers[:, 2]",
        ),
        (
            ("TM1", "TM2", "TM3"),
            "marker TM1",
            "markers TM1 and TM3",
            "markers TM1, TM2, TM3",
        ),
    ],
    ids=["array-columns", "names"],
)
def test_array_columns_name_themselves_where_names_follow_the_word_marker(
    labels, one, both, listed
):
    """An array's column (``markers[:, 0]``) is named by an expression that already says it is
    a marker, so no message puts "marker" before it ("markers markers[:, 0]"); a name (TM1)
    keeps the word."""
    frames = screening.Numbering()
    jump = screening.Artefact("jump", labels[0], 5, 30.0, 20.0)
    broken = screening.Artefact("rigidity", labels[0], 5, 9.0, 5.0)
    exchanged = screening.Artefact("swap", labels[0], 5, 9.0, 5.0, labels[2])
    swap = screening.Swap((labels[0], labels[2]), 5, 9, 20)
    ambiguous = screening.Swap((labels[0], labels[2]), 5, 9, 20, ((labels[1], labels[2]),))
    assert jump.describe(frames).startswith(f"{one} jumps 30.0 mm at frame 5")
    assert broken.describe(frames).startswith(f"{one} leaves its cluster's rigid shape")
    assert exchanged.describe(frames).startswith(f"{both} exchange labels at frame 5")
    assert swap.describe(frames).startswith(f"{both} exchange labels at frame 5")
    assert ambiguous.describe(frames).startswith(f"{both}, or {labels[1]} and {labels[2]} (")
    flagged = [screening.Artefact("rigidity", label, 5, 9.0, 5.0) for label in labels]
    assert screening.summarise(flagged, [], frames).endswith(f"frames 5 to 5, {listed}")
    unseen = np.zeros((4, 3, 3))
    unseen[:, 0] = np.nan
    with pytest.raises(ValueError, match=re.escape(f"m: {one} is never visible")):
        screening.typical_shape(unseen, labels, "m")
    unseen = np.zeros((4, 3, 3))
    unseen[[0, 1], 0] = np.nan
    unseen[[2, 3], 1] = np.nan
    with pytest.raises(ValueError, match=re.escape(f"m: {listed} are never all visible")):
        screening.typical_shape(unseen, labels, "m")


def _random_trial(rng):
    """A cluster of 1-5 markers with noise from none to large and, in most trials, an injected
    swap, jump, step or gap."""
    n_markers = int(rng.integers(1, 6))
    markers = _cluster(
        rng,
        n_markers=n_markers,
        n_frames=int(rng.choice([6, 30, 120])),
        noise_mm=float(rng.choice([0.0, 0.3, 1.0, 2.0, 5.0])),
        rom_deg=float(rng.choice([5.0, 30.0, 60.0])),
    )
    n_frames = len(markers)
    kind = rng.choice(["clean", "swap", "jump", "step", "gap"])
    marker, frame = int(rng.integers(n_markers)), int(rng.integers(n_frames))
    if kind == "swap" and n_markers >= 2:
        i, j = rng.choice(n_markers, 2, replace=False)
        stop = int(rng.integers(frame, n_frames + 1))
        markers[frame:stop, [i, j]] = markers[frame:stop, [j, i]]
    elif kind == "jump":
        markers[frame, marker] += rng.normal(scale=float(rng.choice([3.0, 40.0])), size=3)
    elif kind == "step":
        markers[frame:, marker] += rng.normal(scale=float(rng.choice([3.0, 40.0])), size=3)
    elif kind == "gap":
        markers[frame : frame + n_frames // 5 + 1, marker] = np.nan
    return markers


def test_random_trials_with_artefacts_find_what_the_whole_screen_finds():
    rng = np.random.default_rng(20071392)
    cleared = 0
    for _ in range(150):
        markers = _random_trial(rng)
        labels = _labels(markers.shape[1])
        try:
            whole = screening.screen(markers, labels, "m")
        except ValueError as error:
            with pytest.raises(ValueError, match=re.escape(str(error))):
                screening.find_artefacts(markers, labels, "m")
            continue
        fast = screening.find_artefacts(markers, labels, "m")
        assert _outcome(*fast) == _outcome(whole.artefacts, whole.swaps)
        complete = np.isfinite(markers).all()
        if markers.shape[1] >= 3 and complete:
            _assert_bounded(markers)
        if markers.shape[1] >= 3 and screening.surely_rigid(markers, labels, "m", RULES):
            cleared += 1
            # The bound holds for the mean shape the whole screen iterated to.
            assert np.nanmax(whole.residuals) <= RULES.min_residual_mm
    assert cleared >= 3  # the bound does clear clean clusters


def _one_frame_stretched(rng, n_markers, n_frames, size_mm, noise_mm=0.0):
    """A rigid cluster turning and drifting in which, at the middle frame, one marker stands
    ``size_mm`` further out from the centroid and the others ``size_mm / (n - 1)`` back: a
    misfit with no net shift or turn, all of one frame, where the bounds of
    :func:`surely_rigid` are nearly attained. The marker is one that the marker frame is not
    built on (with 3 markers, the one off the line of the other two), so that the frame does
    not turn."""
    body = rng.normal(scale=30.0, size=(n_markers, 3))
    body -= body.mean(axis=0)
    apart = np.linalg.norm(body[:, None] - body[None], axis=-1)
    a, b = np.unravel_index(np.argmax(apart), apart.shape)
    off_line = np.linalg.norm(np.cross(body[b] - body[a], body - body[a]), axis=-1)
    on_frame = {int(a), int(b), int(np.argmax(off_line))}
    moved = (
        next(iter(on_frame - {a, b})) if n_markers == 3 else min(set(range(n_markers)) - on_frame)
    )
    bodies = np.repeat(body[None], n_frames, axis=0)
    out = size_mm * body[moved] / np.linalg.norm(body[moved])
    bodies[n_frames // 2] -= out / (n_markers - 1)
    bodies[n_frames // 2, moved] += out * n_markers / (n_markers - 1)
    t = np.linspace(0.0, 1.0, n_frames)[:, None]
    rotvec = np.radians(30.0) * np.hstack(
        [np.sin(2 * np.pi * t), 0.5 * np.cos(3 * np.pi * t), 0.2 * t]
    )
    markers = np.einsum("fij,fmj->fmi", rotation_matrix(rotvec), bodies)
    markers += 20.0 * t[:, :, None] + np.array([10.0, -40.0, 25.0])
    return markers + rng.normal(scale=noise_mm, size=markers.shape)


def _true_misfits(markers):
    """The largest residuals [mm] of a complete cluster from its typical frame and from its
    mean shape (NaN if that does not converge), each in its best poses: what
    :func:`screening._rigid_misfits` bounds."""
    labels = _labels(markers.shape[1])
    shapes = [screening.typical_shape(markers, labels, "m")]
    try:
        shapes.append(screening.mean_shape(markers, labels, "m"))
    except ValueError:
        pass
    misfits = [np.nan, np.nan]
    for k, shape in enumerate(shapes):
        rotation, translation = screening.fit_poses(shape, markers)
        misfits[k] = float(np.max(screening.residuals(shape, rotation, translation, markers)))
    return misfits


def _assert_bounded(markers):
    """Both bounds of :func:`screening._rigid_misfits` hold (to rounding) on ``markers``."""
    true = _true_misfits(markers)
    typical = screening._most_typical(screening.kernel_array(markers))
    for fitted in (False, True):
        bounds = screening._rigid_misfits(markers, typical, fitted)
        for bound, misfit in zip(bounds, true, strict=True):
            assert misfit <= bound * (1.0 + 1e-9) or not np.isfinite(bound * misfit)


def _largest_residual(markers):
    """The largest residual [mm] the whole screen finds from its mean shape."""
    return float(np.nanmax(screening.screen(markers, _labels(markers.shape[1]), "m").residuals))


@pytest.mark.parametrize("n_markers", [3, 4, 5])
def test_the_bound_clears_just_below_the_threshold_and_not_just_above(n_markers):
    """10000 frames, one stretched: the bound exceeds the largest residual by about 1 %, so
    a trial 2 % below ``min_residual_mm`` is cleared and one 0.2 % above is not (a bound
    1.2 % looser would clear it, and miss the flag)."""
    n_frames = 10_000
    per_mm = _largest_residual(
        _one_frame_stretched(np.random.default_rng(11), n_markers, n_frames, 1.0)
    )
    sizes = {}
    for factor in (0.98, 1.002):
        size = factor * RULES.min_residual_mm / per_mm
        markers = _one_frame_stretched(np.random.default_rng(11), n_markers, n_frames, size)
        sizes[factor] = _largest_residual(markers) / RULES.min_residual_mm
        cleared = screening.surely_rigid(markers, _labels(n_markers), "m", RULES)
        artefacts, _ = _same_as_screen(markers)
        assert cleared == (factor < 1.0)
        assert [(a.kind, a.frame) for a in artefacts] == (
            [] if factor < 1.0 else [("rigidity", n_frames // 2)]
        )
    assert sizes[0.98] == pytest.approx(0.98, abs=1e-3)
    assert sizes[1.002] == pytest.approx(1.002, abs=2e-4)


@pytest.mark.parametrize("n_markers", [3, 4, 5])
def test_the_bounds_hold_and_are_nearly_attained(n_markers):
    """On the stretched frame of 10000, both pairs of bounds lie within 1.1 % above the
    largest residuals they bound: bounds 1.5 % lower would fail to bound them."""
    markers = _one_frame_stretched(np.random.default_rng(12), n_markers, 10_000, 3.0)
    true = _true_misfits(markers)
    typical = screening._most_typical(markers)
    for fitted in (False, True):
        bounds = screening._rigid_misfits(markers, typical, fitted)
        for bound, misfit in zip(bounds, true, strict=True):
            assert misfit <= bound * (1.0 + 1e-9)  # surely_rigid's margin for rounding
            assert bound <= 1.011 * misfit
    assert true[0] == pytest.approx(3.0, rel=1e-9)  # the typical frame is a clean one


def test_trials_near_the_threshold_find_what_the_whole_screen_finds():
    """One frame stretched to about ``min_residual_mm`` in clusters of 3-5 markers with little
    noise, a few to a few thousand frames: the bound clears only what the screen clears."""
    rng = np.random.default_rng(20071393)
    cleared = 0
    for _ in range(300):
        n_markers = int(rng.integers(3, 6))
        n_frames = int(rng.choice([8, 120, 2000]))
        noise_mm = float(rng.choice([0.0, 0.02, 0.2]))
        factor = float(rng.uniform(0.8, 1.2))
        markers = _one_frame_stretched(
            rng, n_markers, n_frames, factor * RULES.min_residual_mm, noise_mm
        )
        labels = _labels(n_markers)
        whole = screening.screen(markers, labels, "m")
        fast = screening.find_artefacts(markers, labels, "m")
        assert _outcome(*fast) == _outcome(whole.artefacts, whole.swaps)
        _assert_bounded(markers)
        if screening.surely_rigid(markers, labels, "m", RULES):
            cleared += 1
            assert np.nanmax(whole.residuals) <= RULES.min_residual_mm
    assert cleared >= 30


def _jumps_by_definition(markers, labels, rules):
    """:func:`find_jumps` as its docstring defines it, in NumPy: ``(label, frame, size)``."""
    step = np.diff(markers, axis=0)
    change = np.linalg.norm(np.diff(step, axis=0), axis=-1)
    size = np.fmin(change[:-1], change[1:])  # frames 2 to n_frames - 2
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all NaN
        level = max(rules.min_jump_mm, rules.jump_factor * np.nanmedian(size))
    row, marker = np.nonzero(size > level)
    return [(labels[m], int(k) + 2, float(size[k, m])) for k, m in zip(row, marker, strict=True)]


def test_jumps_just_below_and_above_their_level_are_found_as_defined():
    """Spikes 2 % below or above the level: ``min_jump_mm`` under little noise, where no median
    is needed, or ``jump_factor`` times the median step change under much noise."""
    rng = np.random.default_rng(20071394)
    flagged = {(noisy, above): 0 for noisy in (False, True) for above in (False, True)}
    for _ in range(200):
        n_markers = int(rng.integers(1, 5))
        noisy, above = bool(rng.integers(2)), bool(rng.integers(2))
        markers = _cluster(
            rng,
            n_markers=n_markers,
            n_frames=int(rng.choice([120, 1000])),
            noise_mm=1.2 if noisy else 0.02,
        )
        change = np.linalg.norm(np.diff(markers, n=2, axis=0), axis=-1)
        typical = float(np.median(np.fmin(change[:-1], change[1:])))
        level = max(RULES.min_jump_mm, RULES.jump_factor * typical)
        direction = rng.normal(size=3)
        frame, marker = int(rng.integers(len(markers))), int(rng.integers(n_markers))
        markers[frame, marker] += (
            (1.02 if above else 0.98) * level * direction / np.linalg.norm(direction)
        )
        labels = _labels(n_markers)
        expected = _jumps_by_definition(markers, labels, RULES)
        found = screening.find_jumps(markers, labels, RULES)
        assert [(a.label, a.frame) for a in found] == [(label, k) for label, k, _ in expected]
        np.testing.assert_allclose(
            [a.size_mm for a in found], [size for *_, size in expected], rtol=1e-12
        )
        flagged[noisy, above] += bool(found)
    # Under little noise the spike alone decides (at the first or last frame it is no jump).
    assert flagged[False, False] == 0 and flagged[False, True] >= 30
    assert flagged[True, True] >= 20


def test_kernels_compute_what_their_source_says():
    rng = np.random.default_rng(7)
    markers = _cluster(rng, n_markers=4, n_frames=40)
    markers[5:9, 2] = np.nan
    markers[30, :2] = np.nan
    shape = markers[0].copy()

    def both(kernel, outputs, *inputs):
        runs = []
        for function in (kernel, kernel.__wrapped__):
            made = [np.empty(size) for size in outputs]
            value = function(*inputs, *made)
            runs.append((value, made))
        (value, made), (expected_value, expected) = runs
        assert value == expected_value or (np.isnan(value) and np.isnan(expected_value))
        for got, want in zip(made, expected, strict=True):
            np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
        return runs[0][1]

    _, centroids, _ = both(screening._pose_sums, [(40, 3, 3), (40, 2, 3), (40,)], shape, markers)
    rotation, translation = screening.fit_poses(shape, markers)
    both(screening._translations, [(40, 3)], rotation.copy(), centroids)
    both(screening._residuals, [(40, 4)], shape, rotation, translation, markers)
    both(screening._mean_local, [(4, 3)], rotation, translation, markers)
    both(screening._jump_sizes, [(37, 4)], markers)
    complete = markers[np.isfinite(markers).all(axis=(1, 2))]
    rotation, translation = screening.fit_poses(shape, complete)
    (local,) = both(screening._fitted_local, [complete.shape], rotation, translation, complete)
    both(screening._triad_local, [complete.shape], complete, 3)
    np.testing.assert_allclose(
        screening._spread(local, 3), screening._spread.__wrapped__(local, 3), rtol=1e-12
    )
    assert screening._most_typical(complete) == screening._most_typical.__wrapped__(complete)


def _mean_shape_fit_by_fit(markers, labels, most=screening._MAX_ITERATIONS):
    """The mean shape as one pose fit per iteration from Python (:func:`screening.fit_poses`,
    whose rotations an unsettled Horn fit leaves to the SVD), and its last change [mm]."""
    shape = screening.typical_shape(markers, labels, "m")
    change = np.nan
    for _ in range(most):
        rotation, translation = screening.fit_poses(shape, markers)
        new = np.empty_like(shape)
        screening._mean_local(rotation, translation, markers, new)
        change = float(np.max(np.abs(new - shape)))
        shape = new
        if change < screening._TOL_MM * max(1.0, float(np.abs(shape).max())):
            return shape, change
    return None, change


def _unsettled_cluster(rng):
    """A cluster with gaps in which some frames show three collinear markers, whose rotation
    Horn's method leaves to the SVD."""
    markers = _cluster(rng, n_markers=4, n_frames=60)
    markers[10:14, 3] = np.nan
    markers[20:23, 0] = np.nan
    for f in (20, 21, 22):
        markers[f, 3] = 0.5 * (markers[f, 1] + markers[f, 2])
    return markers


@pytest.mark.parametrize("case", ["clean", "gaps", "unsettled"])
def test_a_shapes_poses_and_residuals_are_those_of_the_pose_fit(case):
    """One compiled call poses a shape and finds its residuals, bit for bit as the pose fit
    and the residuals do, where Horn's method settles every frame it poses (frames of fewer
    than three markers it does not pose); where a frame needs the SVD, the pose fit runs."""
    rng = np.random.default_rng(25)
    if case == "unsettled":
        markers = _unsettled_cluster(rng)
    else:
        markers = _cluster(rng, n_markers=4, n_frames=80)
        if case == "gaps":
            markers[10:20, 1:3] = np.nan
            markers[30, :3] = np.nan
    shape = screening.typical_shape(markers, _labels(4), "m")
    rotation, translation = screening.fit_poses(shape, markers)
    want = (rotation, translation, screening.residuals(shape, rotation, translation, markers))
    got = screening._posed(shape, markers)
    assert all(np.array_equal(a, b, equal_nan=True) for a, b in zip(got, want, strict=True))
    assert screening._posed_by_horn(shape, markers)[3] is (case != "unsettled")


@pytest.mark.parametrize("case", ["clean", "gaps", "unsettled", "large"])
def test_the_mean_shape_is_its_fit_by_fit_iteration(case, monkeypatch):
    """The compiled iterations of the mean shape give the shape, bit for bit, and the error
    that fitting each iteration's poses from Python gives, where Horn's method settles every
    frame and where it leaves some to the SVD."""
    rng = np.random.default_rng(23)
    if case == "unsettled":
        markers = _unsettled_cluster(rng)
        cross = np.empty((60, 3, 3))
        shape = markers[0].copy()
        screening._pose_sums(shape, markers, cross, np.empty((60, 2, 3)), np.empty(60))
        unsettled = np.empty(60, dtype=bool)
        _horn_rotations(cross, np.full(60, np.inf), np.empty((60, 3, 3)), unsettled)
        assert unsettled.any()
    else:
        markers = _cluster(rng, n_markers=5 if case == "large" else 3, n_frames=200)
        if case == "gaps":
            markers[40:50, 1] = np.nan
            markers[70, :2] = np.nan
        if case == "large":
            markers = markers * 1e4
    labels = _labels(markers.shape[1])
    want, _ = _mean_shape_fit_by_fit(markers, labels)
    assert np.array_equal(screening.mean_shape(markers, labels, "m"), want)
    # Cut short, both fail alike, naming the last change.
    _, change = _mean_shape_fit_by_fit(markers, labels, most=2)
    monkeypatch.setattr(screening, "_MAX_ITERATIONS", 2)
    with pytest.raises(ValueError, match=re.escape(f"(last change {change:.3g} mm)")):
        screening.mean_shape(markers, labels, "m")
    steps = screening._mean_shape_steps(
        screening.typical_shape(markers, labels, "m"), markers, 200, screening._TOL_MM
    )
    assert steps[3] is (case != "unsettled")


@pytest.mark.parametrize("artefacts", ["refuse", "warn", "ignore"])
def test_the_public_fits_check_their_inputs_once(monkeypatch, artefacts):
    from jointbench import api
    from jointbench.estimators import validation

    calls = []

    def counted(check):
        def check_input(kind, arrays):
            calls.append(kind)
            return check(kind, arrays)

        return check_input

    monkeypatch.setattr(api, "check_input", counted(api.check_input))
    monkeypatch.setattr(validation, "check_input", counted(validation.check_input))
    rng = np.random.default_rng(9)
    jointbench.fit_center(_cluster(rng, noise_mm=0.5), "LS", artefacts=artefacts)
    jointbench.fit_joint_center(_cluster(rng), _cluster(rng, rom_deg=60.0), artefacts=artefacts)
    assert calls == ["center", "joint_center"]


def test_rigidity_breaks_just_below_and_above_their_level_are_found_as_defined():
    """Residuals with one sample 2 % below or above the level: ``min_residual_mm`` for small
    residuals (where no quartile is needed) or ``residual_factor`` times the lower quartile
    for large ones; some samples missing."""
    rng = np.random.default_rng(20071395)
    flagged = {(large, above): 0 for large in (False, True) for above in (False, True)}
    for _ in range(400):
        large, above = bool(rng.integers(2)), bool(rng.integers(2))
        shape = (int(rng.integers(2, 300)), int(rng.integers(3, 6)))
        residuals = rng.uniform(0.5, 1.0, size=shape) * (0.8 if large else 0.2)
        residuals[rng.random(shape) < 0.05] = np.nan
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # all NaN
            level = max(
                RULES.min_residual_mm, RULES.residual_factor * np.nanpercentile(residuals, 25)
            )
        frame, marker = int(rng.integers(shape[0])), int(rng.integers(shape[1]))
        residuals[frame, marker] = (1.02 if above else 0.98) * level
        labels = _labels(shape[1])
        found = screening.find_rigidity_breaks(residuals, labels, RULES)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            level = max(
                RULES.min_residual_mm, RULES.residual_factor * np.nanpercentile(residuals, 25)
            )
        expected = [
            (labels[m], int(f)) for f, m in zip(*np.nonzero(residuals > level), strict=True)
        ]
        assert [(a.label, a.frame) for a in found] == expected
        assert all(a.level_mm == level for a in found)
        flagged[large, above] += bool(found)
    assert flagged[False, False] == flagged[True, False] == 0
    assert flagged[False, True] >= 50 and flagged[True, True] >= 50


def test_lower_quartile_is_numpys_to_the_last_bit():
    rng = np.random.default_rng(10)
    for _ in range(300):
        shape = (int(rng.integers(1, 200)), int(rng.integers(1, 5)))
        values = rng.exponential(scale=float(rng.choice([0.01, 1.0, 100.0])), size=shape)
        values[rng.random(shape) < rng.random()] = np.nan
        values[rng.random(shape) < 0.02] = np.inf
        with np.errstate(invalid="ignore"), warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            expected = np.nanpercentile(values, 25)
        for quartile in (screening._lower_quartile, screening._lower_quartile.__wrapped__):
            with np.errstate(invalid="ignore"):
                np.testing.assert_array_equal(quartile(values), expected)


def test_the_clean_cluster_kernels_compute_what_their_source_says():
    """The one compiled call of :func:`screening.find_artefacts` on a cluster and the largest
    step it finds: as their Python source gives them and, for the step, as
    :func:`screening._jump_sizes` returns it; with gaps it names no typical frame and no
    step."""
    rng = np.random.default_rng(21)
    limit = RULES.min_residual_mm / (1.0 + 1e-9)
    for n_frames in (1, 2, 3, 4, 5, 40):
        markers = _cluster(rng, n_markers=4, n_frames=n_frames, noise_mm=0.5)
        if n_frames == 40:
            markers[17, 2] += [0.0, 80.0, 0.0]
        found = screening._screen_sums(markers, limit)
        assert found == screening._screen_sums.__wrapped__(markers, limit)
        assert found[0] == screening._most_typical(markers)
        size = np.empty((max(n_frames - 3, 0), 4))
        largest = screening._jump_sizes(markers, size)
        assert found[2] == largest
        bounds = screening._rigid_misfits(markers, found[0], False)
        assert bounds == screening._frame_misfits.__wrapped__(markers, found[0])
        assert found[1] == all(bound <= limit for bound in bounds)
        markers[n_frames // 2, 1] = np.nan
        typical, cleared, largest = screening._screen_sums(markers, limit)
        assert typical == -1 and not cleared and np.isnan(largest)
