"""The centre's precision and score test on every checked centre call
(:mod:`jointbench.estimators.centre_precision`): known answers, calibration at the true centre,
honest SDs, invariances, repeated frames, and answers it must not pass as found, a method that
lies about its centre among them."""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy import stats
from scipy.optimize import least_squares
from test_checked_centre_calls import BODY, CENTRE, _trial

from jointbench.estimators import centre_precision, registry, support
from jointbench.estimators.centre_precision import MAX_CENTER_SD_MM, centre_statistics
from jointbench.estimators.results import CenterResult
from jointbench.geometry import rotation_matrix
from jointbench.simulate import cmc

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import blind_spots

_KEYS = ("center_sd_mm", "center_score_chi2", "center_score_p_value", "center_step_mm")


def _cap(rng, rom_deg, noise_mm, *, hinge=False, body=BODY) -> np.ndarray:
    """:func:`test_checked_centre_calls._trial` of 120 frames."""
    return _trial(rng, rom_deg, noise_mm, hinge=hinge, n_frames=120, body=body)


def _numbers(markers: np.ndarray, centre: np.ndarray) -> np.ndarray:
    """``(SD, chi2, step)`` of ``centre`` on ``markers`` with the support verdict's noise."""
    verdict = support.assess("center", (markers,))
    variance = verdict.diagnostics["rigid_residual_mm"] ** 2 / 3.0
    return centre_precision._statistics(markers[None], centre[None], np.array([variance]))[0][:3]


def test_noise_free_cap_is_exact_and_not_warned():
    markers = _cap(np.random.default_rng(0), 20.0, 0.0)
    result = registry.get("center", "NM")(markers)
    assert result.status == "ok"
    assert result.diagnostics["center_sd_mm"] < 1e-9
    assert result.diagnostics["center_step_mm"] < 1e-9


def test_a_centre_off_the_spheres_is_found_by_its_offset():
    """Noise-free data: the step from an answer moved by ``delta`` is ``|delta|`` to first
    order, whatever the direction, and the SD stays at rounding level."""
    markers = _cap(np.random.default_rng(0), 30.0, 0.0)
    rows = centre_statistics(
        markers[None].copy(), (CENTRE + np.array([0.01, -0.02, 0.005]))[None], np.array([1e-4])
    )
    assert rows[0, 2] == pytest.approx(math.hypot(0.01, 0.02, 0.005), rel=1e-2)


def test_score_test_is_calibrated_at_the_true_centre():
    """Rao's score test at the true centre rejects at its nominal level: chi-square with 3
    degrees of freedom (300 trials per cap; binomial bounds far from a miscalibrated test's)."""
    rng = np.random.default_rng(5)
    for rom_deg in (30.0, 10.0):
        p_values = [
            centre_precision._chi2_3_sf(_numbers(_cap(rng, rom_deg, 1.0), CENTRE)[1])
            for _ in range(300)
        ]
        share = np.mean(np.array(p_values) < 0.05)
        assert 0.02 < share < 0.10, (rom_deg, share)


def _grid_outcomes(method: str) -> list[tuple[object, float]]:
    """``(outcome, error [mm])`` of ``method``'s checked many-trial call on caps of 3 to 20
    degrees with 0.5 to 1.5 mm noise, markers near the centre (paper A's M set distances) and
    far from it, 40 trials each: where the SD holds and where it does not."""
    near = np.array([[2.7, 4.1, 13.0], [0.0, 2.9, 28.9], [-4.6, 3.1, 15.1]])
    rng = np.random.default_rng(7)
    found = []
    for body in (near, BODY):
        for rom_deg, noise_mm in ((20.0, 1.0), (12.0, 1.0), (7.0, 0.5), (4.0, 1.0), (3.0, 1.5)):
            trials = np.stack([_cap(rng, rom_deg, noise_mm, body=body) for _ in range(40)])
            for outcome in registry.many("center", method)(trials):
                found.append((outcome, float(np.linalg.norm(outcome.center - CENTRE))))
    return found


@pytest.mark.parametrize("method", ["NM", "BC"])
def test_an_ok_centre_is_within_four_sds(method):
    """Among the answers a checked call passes as "ok", the error is beyond 4 SDs along the
    least determined direction about as rarely as the SD says (chi-square with 3 degrees of
    freedom beyond 16: 0.1%); among those whose noise share is too large for the SD to hold,
    it is not (without the share's warning, those would pass as "ok")."""
    found = _grid_outcomes(method)
    passed = [(o, e) for o, e in found if o.status == "ok"]
    beyond = [e > 4.0 * o.diagnostics["center_sd_mm"] for o, e in passed]
    assert len(passed) > 100
    assert np.mean(beyond) <= 0.01, np.mean(beyond)
    shared = [
        (o, e)
        for o, e in found
        if o.diagnostics.get("center_sd_noise_share", 0) >= centre_precision.MAX_SD_NOISE_SHARE
        and math.isfinite(o.diagnostics["center_sd_mm"])
    ]
    assert np.mean([e > 4.0 * o.diagnostics["center_sd_mm"] for o, e in shared]) > 0.03


def test_a_biased_answer_is_not_passed_as_the_centre():
    """Paper A's LS sphere fit on a 10 degree cap with 1 mm noise lies tens of millimetres from
    the centre, biased the same way every time: its checked call now says so."""
    rng = np.random.default_rng(3)
    for _ in range(5):
        result = registry.get("center", "LS")(_cap(rng, 10.0, 1.0))
        assert np.linalg.norm(result.center - CENTRE) > 10.0
        assert "not the markers' common centre of rotation" in result.status
        assert result.diagnostics["center_step_mm"] > 10.0


def _far_swing(rng) -> np.ndarray:
    """``benchmarks/blind_spots.py``'s first case about ``CENTRE``: four markers 500 mm out,
    scattered by 20 mm, swung by up to 10 degrees about two axes (and 3 about a third) over 120
    frames, with 0.5 mm noise: ``(120, 4, 3)`` [mm]."""
    markers, centre = blind_spots.swing(rng, 500.0, 10.0, 0.5)
    return markers - centre + CENTRE


def test_a_bias_the_score_test_passes_is_not_passed_as_the_centre():
    """The LS sphere fit with its markers 500 mm out on a 10 degree swing lies about three of its
    SDs from the spheres' centre, where the score test, first order and at 0.001 (about four),
    passes it: its SD, the scatter of that centre, does not describe its error. The checked
    call measures the distance to the geometric fit's answer (IS, by the simplex) and says so,
    and no LS answer more than 10 mm off reads ``ok``."""
    rng = np.random.default_rng(1)
    trials = [_far_swing(rng) for _ in range(20)]
    results = [registry.get("center", "LS")(markers) for markers in trials]
    errors = [np.linalg.norm(result.center - CENTRE) for result in results]
    passed = [e for r, e in zip(results, errors, strict=True) if r.status == "ok" and e > 10.0]
    assert passed == []
    off_beyond_its_sd = 0
    for markers, result in zip(trials, results, strict=True):
        numbers = result.diagnostics
        step = np.linalg.norm(result.center - registry.get("center", "IS")(markers).center)
        assert numbers["center_step_mm"] == pytest.approx(step, abs=0.05)
        if step > centre_precision.MIN_REJECTED_STEP_MM:
            assert "not the markers' common centre of rotation" in result.status
            assert f"{numbers['center_step_sds']:.2g} of its SDs" in result.status
            off_beyond_its_sd += numbers["center_score_p_value"] > support.ROTATION_ALPHA
    # Answers the score test alone passes: the case, not a rarity.
    assert off_beyond_its_sd >= 5


def test_the_bias_rule_spares_geometric_answers_and_well_posed_trials():
    """NM's and BC's fits of the spheres and IS's of their radial residuals: on the same far
    swings their answers lie a fraction of an SD from the spheres' centre and read ``ok``; and
    on a well-posed cap (30 degrees, markers 50 to 90 mm out, 0.5 mm noise) every method's
    does."""
    rng = np.random.default_rng(1)
    for _ in range(20):
        markers = _far_swing(rng)
        for method in ("NM", "BC", "IS"):
            result = registry.get("center", method)(markers)
            assert result.status == "ok", (method, result.status)
            assert result.diagnostics["center_step_sds"] < centre_precision.MAX_STEP_SDS
    rng = np.random.default_rng(14)
    for _ in range(5):
        markers = _cap(rng, 30.0, 0.5)
        for method in ("LS", "NM", "BC", "IS", "MA", "SCoRE"):
            result = registry.get("center", method)(markers)
            assert result.status == "ok", (method, result.status)


def test_a_method_that_lies_about_its_centre_is_caught():
    """A newcomer's method that returns a centre 20 mm away from the one it fitted, with
    status "ok", is warned about by the checked call, one trial and many."""
    name = "lying-centre"

    @registry.register("center", name, recovery=None, invariances={})
    def lying(markers, *, max_iterations: int = 200):
        honest = registry.get("center", "NM")(markers)
        return CenterResult(
            center=honest.center + np.array([20.0, 0.0, 0.0]),
            converged=True,
            iterations=honest.iterations,
            status="ok",
            method=name,
        )

    try:
        rng = np.random.default_rng(2)
        trials = np.stack([_cap(rng, 30.0, 1.0) for _ in range(3)])
        for outcome in [
            registry.get("center", name)(trials[0]),
            *registry.many("center", name)(trials),
        ]:
            assert "not the markers' common centre of rotation" in outcome.status
            # First order in the offset: 20 mm of 60 to 90 mm radii is not small.
            assert 10.0 < outcome.diagnostics["center_step_mm"] < 25.0
    finally:
        registry.unregister("center", name)


def test_rigid_motions_marker_order_and_frame_order_leave_the_numbers():
    """The statistics of an answer, for a given noise level (the support verdict's estimate of
    it is tested for its own invariances)."""
    rng = np.random.default_rng(4)
    markers = _cap(rng, 15.0, 1.0)
    centre = CENTRE + np.array([1.0, 2.0, -1.5])

    def numbers(markers, centre):
        return centre_statistics(markers[None].copy(), centre[None], np.array([0.4]))[0, :3]

    reference = numbers(markers, centre)
    turn = rotation_matrix(np.array([0.3, -1.1, 0.7]))
    shift = np.array([500.0, -250.0, 1000.0])
    moved = numbers(markers @ turn.T + shift, turn @ centre + shift)
    reordered = numbers(markers[rng.permutation(len(markers))][:, [2, 0, 3, 1]], centre)
    np.testing.assert_allclose(moved, reference, rtol=1e-7)
    np.testing.assert_allclose(reordered, reference, rtol=1e-9)


def test_repeated_frames_carry_no_new_information():
    """Each frame given four times (a gap filled by holding a value does that) is the same
    data: the SD must not shrink by half, nor the score test sharpen."""
    markers = _cap(np.random.default_rng(6), 10.0, 1.0)
    result = registry.get("center", "NM")(markers)
    repeated = registry.get("center", "NM")(np.repeat(markers, 4, axis=0))
    # Equal but for the support verdict's noise estimate, whose degrees of freedom count the
    # repeated frames (a fraction of a percent here); counted four times, the SD would halve.
    for key in ("center_sd_mm", "center_score_chi2", "center_step_mm"):
        assert repeated.diagnostics[key] == pytest.approx(result.diagnostics[key], rel=1e-2)


def test_repeated_frames_are_flagged_wherever_two_keys_are_equal():
    """The repeated-frames flag, compiled and as plain Python, is 1 exactly where two frames'
    keys are equal: noisy frames all distinct, one frame repeated far from the first, frames
    in a regular progression, and those with one of them repeated at the end."""
    rng = np.random.default_rng(31)
    noisy = _cap(rng, 20.0, 0.5)
    repeated = noisy.copy()
    repeated[97] = repeated[4]
    grid = np.arange(120.0)[:, None, None] * np.array([[1.0, 0.0, 2.0], [0.0, 3.0, 1.0]])
    for markers, expected in (
        (noisy, 0.0),
        (repeated, 1.0),
        (grid, 0.0),
        (grid[[*range(120), 60]], 1.0),
    ):
        markers = np.ascontiguousarray(markers)
        weights = np.sqrt(np.arange(2.0, 2.0 + 3 * markers.shape[1]))
        keys = markers.reshape(len(markers), -1) @ weights
        assert (len(np.unique(keys)) < len(keys)) == bool(expected)
        for repeats in (centre_precision._repeats, centre_precision._repeats.__wrapped__):
            slots = centre_precision._table_for(len(markers))
            assert repeats(markers, weights, np.empty(len(markers)), slots) == expected


def _sorted_repeats(markers: np.ndarray, weights: np.ndarray) -> float:
    """The repeated-frames flag of ``markers`` ``(N, n, 3)`` as first written: each frame's key
    summed coordinate after coordinate as :func:`centre_precision._repeats` sums it, the keys
    sorted and neighbours compared (NaN equal to nothing)."""
    flat = markers.reshape(len(markers), -1)
    keys = np.zeros(len(markers))
    for j in range(flat.shape[1]):
        keys = keys + weights[j] * flat[:, j]
    keys.sort()
    return float(bool(np.any(~(keys[1:] != keys[:-1]))))


def _one_slot_keys(n_frames: int) -> np.ndarray:
    """``n_frames`` distinct keys (up to 2^17) that :func:`centre_precision._repeats`' table
    puts in one slot for any table of up to 2^17 slots: a key's bits ``j`` and ``j + 17``
    flipped together, which its fold onto the lower bits cancels."""
    patterns = np.arange(n_frames, dtype=np.int64)
    flips = np.zeros(n_frames, dtype=np.int64)
    for j in range(17):
        bit = (patterns >> j) & 1
        flips |= (bit << j) | (bit << (j + 17))
    return (np.float64(1234.5678).view(np.int64) ^ flips).view(np.float64)


def _frames_to_flag(rng: np.random.Generator):
    """``(markers (N, n, 3), weights (3 n,))`` on which the repeated-frames flag must be the
    sorted keys': frames from a few values (signed zeros among them, so that frames and keys
    repeat often), one coordinate a unit in the last place from another frame's, a frame
    repeated first or last, NaN and infinite coordinates, 1 to 3 frames, keys that all fall in
    one slot of the table (the weights then picking the first coordinate alone), and 100,000
    frames."""
    pool = np.array([-1.0, -0.0, 0.0, 0.5, 1.0, 2.0])
    for _ in range(3000):
        n_frames, n_markers = int(rng.integers(1, 40)), int(rng.integers(1, 4))
        markers = rng.choice(pool, size=(n_frames, n_markers, 3))
        yield markers, np.sqrt(np.arange(2.0, 2.0 + 3 * n_markers))
    for _ in range(3000):
        n_frames, n_markers = int(rng.integers(1, 4)), int(rng.integers(1, 3))
        markers = rng.choice(pool, size=(n_frames, n_markers, 3))
        yield markers, np.sqrt(np.arange(2.0, 2.0 + 3 * n_markers))
    for kind in range(4000):
        n_frames, n_markers = int(rng.integers(2, 200)), int(rng.integers(1, 5))
        markers = rng.normal(scale=100.0, size=(n_frames, n_markers, 3))
        first, second = rng.choice(n_frames, size=2, replace=False)
        if kind % 4 == 0:
            markers[second] = markers[first]
            where = (int(rng.integers(n_markers)), int(rng.integers(3)))
            markers[second][where] = np.nextafter(markers[first][where], rng.choice([-1, 1]) * 1e9)
        elif kind % 4 == 1:
            markers[[0, -1][kind % 8 == 1]] = markers[first]
        elif kind % 4 == 2:
            markers[first, 0, int(rng.integers(3))] = rng.choice([np.nan, np.inf, -np.inf])
            markers[second] = markers[first]
        yield markers, np.sqrt(np.arange(2.0, 2.0 + 3 * n_markers))
    only_first = np.array([1.0, 0.0, 0.0])
    for n_frames in (2, 3, 300, 2000):
        markers = np.zeros((n_frames, 1, 3))
        markers[:, 0, 0] = _one_slot_keys(n_frames)
        yield markers, only_first
        markers[-1] = markers[0]
        yield markers, only_first
    markers = rng.normal(scale=100.0, size=(100_000, 4, 3))
    yield markers, np.sqrt(np.arange(2.0, 14.0))
    markers[-1] = markers[0]
    yield markers, np.sqrt(np.arange(2.0, 14.0))


def test_the_repeated_frames_table_flags_what_sorting_the_keys_flags():
    """The hash table's flag, compiled and (on up to 300 frames) as plain Python, is the one
    the sorted keys give, on 10,000 random and adversarial sets of frames, with the table as
    :func:`centre_statistics` sizes it."""
    rng = np.random.default_rng(37)
    flagged = 0
    for markers, weights in _frames_to_flag(rng):
        markers = np.ascontiguousarray(markers)
        n_frames = len(markers)
        expected = _sorted_repeats(markers, weights)
        flagged += expected == 1.0
        repeats = [centre_precision._repeats]
        if n_frames <= 300:
            repeats.append(centre_precision._repeats.__wrapped__)
        for flag in repeats:
            table = centre_precision._table_for(n_frames)
            assert flag(markers, weights, np.empty(n_frames), table) == expected, markers
    assert 1000 < flagged < 9000


def test_a_cap_within_the_noise_is_not_determined():
    """A 3 degree cap with 1 mm noise: the rotation is resolved (the support verdict passes
    it) but the data hold the centre to tens of millimetres, which the status says."""
    rng = np.random.default_rng(8)
    seen = 0
    for _ in range(10):
        markers = _cap(rng, 3.0, 1.0)
        result = registry.get("center", "NM")(markers)
        if support.assess("center", (markers,)).warnings:
            continue
        seen += 1
        numbers = result.diagnostics
        assert (
            numbers["center_sd_mm"] > MAX_CENTER_SD_MM
            or numbers["center_sd_noise_share"] >= centre_precision.MAX_SD_NOISE_SHARE
        )
        assert "not determined by the data" in result.status
    assert seen >= 5


def test_a_hinge_is_warned_once():
    """A hinge fixes no centre along its axis: along it the directions vary by noise alone, so
    the SD does not hold (or is unbounded), and the support verdict's warning says why; the
    precision adds no second warning about the same thing."""
    result = registry.get("center", "NM")(_cap(np.random.default_rng(9), 40.0, 0.5, hinge=True))
    assert result.diagnostics["center_sd_noise_share"] >= 1.0
    assert result.status.count("warning:") == 1
    assert "rotation about a single axis" in result.status


def test_unassessed_and_failed_answers_say_why_they_are_not_checked():
    markers = _cap(np.random.default_rng(10), 30.0, 0.5)[:, :2]
    result = registry.get("center", "NM")(markers)
    assert "did not assess" in result.diagnostics["center_precision_not_checked"]
    assert "center_sd_mm" not in result.diagnostics
    full = _cap(np.random.default_rng(1), 30.0, 0.5)
    failed = CenterResult(
        center=np.full(3, np.nan), converged=False, iterations=0, status="failed", method="NM"
    )
    (annotated,) = centre_precision.annotate_many(
        [failed], full[None], [support.assess("center", (full,))]
    )
    assert annotated.diagnostics["center_precision_not_checked"] == "the answer is not finite"
    assert annotated.status == "failed"
    claimed = CenterResult(
        center=np.full(3, np.nan), converged=True, iterations=3, status="ok", method="NM"
    )
    (annotated,) = centre_precision.annotate_many(
        [claimed], full[None], [support.assess("center", (full,))]
    )
    assert annotated.status == "warning: the answer is not finite: no centre was found"
    # A centre of another shape is refused as it is made (a method's mistake, of which no
    # precision can be judged): tests/test_programming_errors.py.
    with pytest.raises(TypeError, match=r"CenterResult: center of shape \(3, 1\), not \(3,\)"):
        CenterResult(
            center=np.zeros((3, 1)), converged=True, iterations=1, status="ok", method="column"
        )


@pytest.mark.parametrize("method", ["LS", "NM", "BC", "IS", "MA", "SCoRE"])
def test_every_centre_method_states_its_precision(method):
    result = registry.get("center", method)(_cap(np.random.default_rng(12), 30.0, 0.5))
    assert set(_KEYS) <= result.diagnostics.keys()
    assert result.diagnostics["center_sd_mm"] < 1.0


def test_a_marker_at_the_centre_carries_no_direction():
    """A virtual marker at the joint centre (common in a lab's C3D files) moves by noise alone:
    its direction from the centre is noise, and it neither spoils nor sharpens the numbers."""
    rng = np.random.default_rng(13)
    markers = _cap(rng, 20.0, 0.5)
    at_centre = CENTRE + rng.normal(scale=0.5, size=(len(markers), 1, 3))
    with_virtual = np.concatenate([markers, at_centre], axis=1)
    variance = np.array([0.25])
    plain = centre_statistics(markers[None].copy(), CENTRE[None], variance)[0]
    extra = centre_statistics(with_virtual[None].copy(), CENTRE[None], variance)[0]
    np.testing.assert_allclose(extra[:3], plain[:3], rtol=1e-12)
    exact = np.concatenate([markers, np.broadcast_to(CENTRE, (len(markers), 1, 3))], axis=1)
    # An answer 2 mm from it (a biased method's): the marker's direction is then constant.
    off = (CENTRE + np.array([2.0, 0.0, 0.0]))[None]
    np.testing.assert_allclose(
        centre_statistics(exact[None].copy(), off, variance)[0, :3],
        centre_statistics(markers[None].copy(), off, variance)[0, :3],
        rtol=1e-12,
    )
    np.testing.assert_allclose(
        centre_statistics(exact[None].copy(), CENTRE[None], variance)[0, :3], plain[:3], rtol=1e-12
    )


def test_the_compiled_sums_compute_what_their_source_says():
    """The spheres' sums and the statistics built on them, compiled and as plain Python
    (``kernel.__wrapped__``), to the last bit: on a cap with a marker exactly at the answer in
    one frame (no direction there), a virtual marker near the joint (left out of the
    iterations and of the fits they compare, kept in the answer's), with the lack of fit's
    sums asked for or not, and with every marker allowed or one left out."""
    rng = np.random.default_rng(29)
    markers = _cap(rng, 20.0, 0.5)
    near_joint = CENTRE + rng.normal(scale=0.5, size=(len(markers), 1, 3))
    near_joint[7, 0] = CENTRE
    markers = np.concatenate([markers, near_joint], axis=1)
    coordinates = np.empty((markers.shape[1], 3, len(markers)))
    centre_precision._transposed_into(markers, coordinates)
    np.testing.assert_array_equal(coordinates, markers.transpose(1, 2, 0))
    runs = []
    for marker_sums in (centre_precision._marker_sums, centre_precision._marker_sums.__wrapped__):
        outputs = (np.empty(len(markers)), np.empty((6, len(markers))), np.empty(3), np.empty(3))
        outputs += (np.empty((3, 3)),)
        radius = marker_sums(coordinates[-1], CENTRE, *outputs)
        runs.append((radius, outputs[0], *outputs[2:]))
    for compiled, interpreted in zip(*runs, strict=True):
        np.testing.assert_array_equal(compiled, interpreted)
    assert runs[0][1][7] == 0.0
    every, one_out = np.ones(markers.shape[1]), np.ones(markers.shape[1])
    one_out[1] = 0.0
    for nearest, fit, allowed in ((0.0, True, every), (1.5, False, one_out)):
        runs = []
        for sums_at in (centre_precision._sums_at, centre_precision._sums_at.__wrapped__):
            scratch = centre_precision._scratch_for(*markers.shape[:2])
            returned = sums_at(coordinates, CENTRE + 0.3, 0.25, nearest, allowed, fit, scratch)
            # The sums, their parts and the markers kept (the first row of the last array).
            written = [scratch[i].copy() for i in (0, 1, 2, 3, 11, 12)] + [scratch[19][0].copy()]
            runs.append((returned, written))
        assert runs[0][0] == runs[1][0]
        for compiled, interpreted in zip(runs[0][1], runs[1][1], strict=True):
            np.testing.assert_array_equal(compiled, interpreted)
    rows = [
        statistics(markers[None].copy(), (CENTRE + 2.0)[None], np.array([0.25]))
        for statistics in (centre_statistics, centre_statistics.__wrapped__)
    ]
    np.testing.assert_array_equal(rows[0], rows[1])


def _bits(value: float) -> int:
    """The bits of the float ``value``: equal only where the floats are the same to the last
    bit, sign of zero and NaN included."""
    return int(np.float64(value).view(np.int64))


def test_the_p_values_are_the_distributions_tails_at_every_extreme():
    """The score test's and the lack of fit's p-values, compiled, are their closed forms as
    written to the last bit, and SciPy's tails to 1e-12 (or both below the smallest normal
    float), from 0 to the largest float and infinity: a chi-square too large for its closed
    form's terms is still a tail of 0, not NaN, which no rejection reads."""
    chi2_3_sf, normal_sf = centre_precision._chi2_3_sf, centre_precision._normal_sf
    largest = sys.float_info.max
    for x in (0.0, 5e-324, 1e-300, 1e-8, 1.0, 7.8, 100.0, 1400.0, 1480.0, 1e300, largest, math.inf):
        p = chi2_3_sf(x)
        assert _bits(p) == _bits(chi2_3_sf.__wrapped__(x)), x
        assert p == pytest.approx(stats.chi2.sf(x, 3), rel=1e-12, abs=1e-300), x
    assert math.isnan(chi2_3_sf(math.nan))
    for z in (-math.inf, -40.0, -8.0, -1.0, -0.0, 0.0, 1e-300, 1.0, 8.0, 37.0, 40.0, math.inf):
        p = normal_sf(z)
        assert _bits(p) == _bits(normal_sf.__wrapped__(z)), z
        assert p == pytest.approx(stats.norm.sf(z), rel=1e-12, abs=1e-300), z
    assert math.isnan(normal_sf(math.nan))


def _mixed_and_refined(markers: np.ndarray, centre: np.ndarray, s2: float) -> tuple[bool, bool]:
    """Whether, on one trial's ``markers`` ``(N, n, 3)`` [mm] about the answer ``centre``
    ``(3,)`` [mm] with noise ``s2`` [mm^2], some markers lie within three noise SDs of the
    answer and others beyond, and whether the Gauss–Newton iterations end where the spheres fit
    better, as :func:`centre_statistics` finds them."""
    coordinates = np.empty((markers.shape[1], 3, len(markers)))
    centre_precision._transposed_into(markers, coordinates)
    scratch = centre_precision._scratch_for(*markers.shape[:2])
    row = np.empty(17)
    mixed = centre_precision._row_at(coordinates, centre, s2, row, scratch)
    return mixed, centre_precision._refine(coordinates, centre, s2, mixed, row, scratch)


def _unlike_trials() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Trials of 120 frames of four markers ``(T, N, n, 3)`` [mm], their answers ``(T, 3)``
    [mm] and noise ``(T,)`` [mm^2], each unlike the one before: iterations that end where the
    spheres fit better, a marker within three noise SDs of the answer (the iterations then
    start from it), iterations that stop on a step that is not finite (the noise as large as
    the cap), noise-free frames, a hinge, and frames repeated."""
    rng = np.random.default_rng(43)
    near = BODY.copy()
    near[0] = [0.5, 0.0, 0.0]
    cap = _cap(rng, 30.0, 0.5)
    markers = [cap, _cap(rng, 30.0, 0.5, body=near), cap, _cap(rng, 30.0, 0.0)]
    markers += [_cap(rng, 40.0, 0.5, hinge=True), cap[np.arange(120) // 2]]
    answers = CENTRE + np.array([[3.0, -2.0, 1.0], [0.5, 0.5, 0.0], [3.0, -2.0, 1.0]] * 2)
    return np.stack(markers), answers, np.array([0.25, 0.25, 1e6, 1e-4, 0.25, 0.25])


def _same_bits(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether the float arrays ``a`` and ``b`` are the same to the last bit."""
    return a.shape == b.shape and np.array_equal(a.view(np.int64), b.view(np.int64))


def test_a_trials_row_in_a_batch_is_its_row_alone():
    """The scratch one batch's trials share leaves nothing of one trial in the next: each
    trial's row, to the last bit, whatever trials come before it, is its row alone, in either
    order of the batch, and through :func:`centre_precision._statistics` from markers neither
    contiguous nor writable."""
    markers, answers, variances = _unlike_trials()
    paths = [_mixed_and_refined(*trial) for trial in zip(markers, answers, variances, strict=True)]
    assert paths[:3] == [(False, True), (True, True), (False, False)]
    alone = np.concatenate(
        [
            centre_statistics(markers[t : t + 1], answers[t : t + 1], variances[t : t + 1])
            for t in range(len(markers))
        ]
    )
    for order in (np.arange(len(markers)), np.arange(len(markers))[::-1]):
        together = centre_statistics(markers[order], answers[order], variances[order])
        for t, row in zip(order, together, strict=True):
            assert _same_bits(row, alone[t]), t
    strided = np.zeros((len(markers), 120, 8, 3))
    strided[:, :, ::2] = markers
    strided.setflags(write=False)
    rows = centre_precision._statistics(strided[:, :, ::2], answers, variances)
    assert _same_bits(
        np.array(rows), np.array(centre_precision._statistics(markers, answers, variances))
    )


def test_the_p_value_columns_are_the_tails_of_their_statistics():
    """Each p-value of :func:`centre_statistics`' rows is its closed form, as written, of its
    own statistic: the score test's of the chi-square, the lack of fit's of its z, and the lack
    of fit's about the spheres' centre of that z, on trials where those z differ."""
    markers, answers, variances = _unlike_trials()
    rows = centre_statistics(markers, answers, variances)
    sources = {
        centre_precision._SCORE_P: (centre_precision._CHI2, centre_precision._chi2_3_sf),
        centre_precision._FIT_P: (centre_precision._FIT_Z, centre_precision._normal_sf),
        centre_precision._SPHERES_P: (centre_precision._SPHERES_Z, centre_precision._normal_sf),
    }
    assert np.any(rows[:, centre_precision._FIT_Z] != rows[:, centre_precision._SPHERES_Z])
    for column, (statistic, tail) in sources.items():
        expected = np.array([tail.__wrapped__(value) for value in rows[:, statistic].tolist()])
        assert _same_bits(rows[:, column], expected), column


def _marker_sums_in_frame_order(track: np.ndarray, centre: np.ndarray) -> tuple:
    """One marker's distances ``(N,)`` from ``centre`` and its sums over its ``track``
    ``(N, 3)`` [mm] as :func:`centre_precision._marker_sums` states them, each summed frame
    after frame in one loop: ``(radius, distances, sum u, sum d u, sum u u')``."""
    distances = np.empty(len(track))
    sum_d, sum_u, sum_du, sum_uu = 0.0, [0.0] * 3, [0.0] * 3, [[0.0] * 3 for _ in range(3)]
    for k, point in enumerate(track.tolist()):
        offset = [point[i] - centre[i] for i in range(3)]
        d = math.sqrt(offset[0] * offset[0] + offset[1] * offset[1] + offset[2] * offset[2])
        distances[k] = d
        inverse = 1.0 / d if d > 0.0 else 0.0
        u = [offset[i] * inverse for i in range(3)]
        sum_d += d
        for i in range(3):
            sum_u[i] += u[i]
            sum_du[i] += offset[i]
            for j in range(3):
                sum_uu[i][j] += u[i] * u[j]
    return sum_d / len(track), distances, np.array(sum_u), np.array(sum_du), np.array(sum_uu)


def test_a_markers_sums_are_taken_frame_after_frame():
    """:func:`centre_precision._marker_sums`, compiled, gives every sum to the last bit as one
    loop over the frames in their order gives it, on a marker of 5,000 frames and on one
    exactly at the centre in one frame: a sum taken in another order (in blocks, or
    pairwise) moves the numbers in their last bits, which the pins' tolerance does not see."""
    rng = np.random.default_rng(47)
    markers = _cap(rng, 30.0, 0.5)
    wide = CENTRE + rng.normal(scale=50.0, size=(5000, 3))
    wide[11] = CENTRE
    for track in (wide, markers[:, 2]):
        coordinates = np.ascontiguousarray(track.T)
        outputs = (np.empty(len(track)), np.empty((6, len(track))), np.empty(3), np.empty(3))
        outputs += (np.empty((3, 3)),)
        radius = centre_precision._marker_sums(coordinates, CENTRE, *outputs)
        expected = _marker_sums_in_frame_order(track, CENTRE)
        computed = (np.float64(radius), outputs[0], *outputs[2:])
        for got, want in zip(computed, expected, strict=True):
            assert _same_bits(np.asarray(got), np.asarray(want))


def test_an_answer_among_the_markers_is_caught_at_its_distance():
    """The markers' centroid, 18 mm from the centre of paper A's M set on a 3 degree cap with
    0.1 mm noise: the first-order step from it is 4 mm, under the 5 mm a method's bias is
    allowed, but Gauss–Newton iterations from it end at the spheres' centre 18-20 mm away, and
    the spheres about the centroid leave residuals many times the noise."""
    protocol = cmc.CmcProtocol(n_frames=30)
    condition = {"marker_set": "M", "rom_deg": 3, "noise_mm": 0.1}
    for seed in range(3):
        trial = cmc.simulate(condition, protocol, [np.random.default_rng(seed)])
        markers = trial.segments["moving"][0]
        error = np.linalg.norm(markers.reshape(-1, 3).mean(axis=0) - trial.truth["center"])
        verdict = support.assess("center", (markers,))
        centroid = CenterResult(
            center=markers.reshape(-1, 3).mean(axis=0),
            converged=True,
            iterations=0,
            status="ok",
            method="centroid",
        )
        (result,) = centre_precision.annotate_many([centroid], markers[None], [verdict])
        assert "not the markers' common centre of rotation" in result.status
        assert result.diagnostics["center_step_mm"] == pytest.approx(error, rel=0.25)
        assert result.diagnostics["center_fit_p_value"] < 1e-3


@pytest.mark.parametrize("distance_mm", [0.0, 0.5])
def test_a_virtual_marker_at_the_joint_does_not_unsettle_a_methods_answer(distance_mm):
    """A virtual marker at the joint (or at a point half a millimetre from it), beside markers
    that fix the centre well: its directions from a method's answer (not the true centre, which
    no method returns) are noise far beyond first order. It must not turn a well-determined
    centre into an undetermined one, nor shrink the SD of the scatter the other markers give
    (the SD stated adds a step to the spheres' centre where one is stated as a bias:
    :func:`test_a_virtual_marker_at_the_joint_hides_no_step_bias`)."""
    rng = np.random.default_rng(21)
    body = np.vstack([BODY, [[distance_mm, 0.0, 0.0]]])
    for _ in range(12):
        markers = _cap(rng, 30.0, 0.5, body=body)
        for method in ("NM", "BC", "LS"):
            alone = registry.get("center", method)(markers[:, : len(BODY)])
            beside = registry.get("center", method)(markers)
            assert alone.status == "ok", alone.status
            assert beside.status == "ok", (method, beside.status)
            scatter = _numbers(markers, beside.center)[0]
            assert scatter >= 0.8 * _numbers(markers[:, : len(BODY)], alone.center)[0]
            assert beside.diagnostics["center_sd_mm"] >= scatter


@pytest.mark.parametrize("distance_mm", [0.0, 0.5])
def test_a_virtual_marker_at_the_joint_hides_no_step_bias(distance_mm):
    """LS's answer 1.5 to 2.6 of its scatter's SDs from the spheres' centre on a 30 degree cap
    states that step as a bias (:func:`centre_precision.annotate_many`), and so it must beside
    a virtual marker at the joint."""
    rng = np.random.default_rng(21)
    body = np.vstack([BODY, [[distance_mm, 0.0, 0.0]]])
    hidden = 0
    for _ in range(12):
        markers = _cap(rng, 30.0, 0.5, body=body)
        alone = registry.get("center", "LS")(markers[:, : len(BODY)])
        beside = registry.get("center", "LS")(markers)
        stated = "center_step_bias_mm" in alone.diagnostics
        hidden += stated and "center_step_bias_mm" not in beside.diagnostics
    assert hidden == 0


@pytest.mark.parametrize(
    "near",
    [[[1.0, 0.0, 0.0]], [[0.0, 0.0, 0.0], [0.3, -0.4, 0.2]], [[0.0, 2.0, 0.0]], [[0.0, 0.0, 3.0]]],
    ids=["1 mm", "two virtual markers", "2 mm", "3 mm"],
)
def test_markers_near_the_joint_hide_no_step_bias_of_any_method(near):
    """Markers 1 to 3 mm from the joint, or two virtual markers, beside markers that fix the
    centre well (0.5 mm noise, 30 degrees): an answer whose step to the spheres' centre is
    stated as a bias without them, clear of :data:`centre_precision.MAX_STEP_SDS`, states it
    beside them too wherever it reads ``ok``, with an SD no smaller than the spheres' centre's
    scatter; where the near markers' directions are too noisy for the SD, the status says its
    precision is not determined, never an ``ok`` of the scatter alone."""
    rng = np.random.default_rng(21)
    body = np.vstack([BODY, near])
    clear = 2.0 * centre_precision.MAX_STEP_SDS
    for _ in range(8):
        markers = _cap(rng, 30.0, 0.5, body=body)
        for method in ("LS", "NM", "BC"):
            alone = registry.get("center", method)(markers[:, : len(BODY)])
            beside = registry.get("center", method)(markers)
            if beside.status != "ok":
                assert "not determined" in beside.status, (method, beside.status)
                continue
            assert beside.diagnostics["center_sd_mm"] >= _numbers(markers, beside.center)[0]
            if alone.status == "ok" and alone.diagnostics["center_step_sds"] >= clear:
                assert "center_step_bias_mm" in beside.diagnostics, method


def test_a_marker_1_mm_from_the_joint_hides_no_step_bias_of_ls():
    """A marker 1 mm from the joint (two noise SDs, within the iterations' clear radius) beside
    four that fix the centre well (0.5 mm, 30 degrees): LS's answer without it states its step
    to the spheres' centre (1.9 of its SDs) as a bias, and so must its answer beside it, which
    lies 3.1 of the SDs of its scatter from the joint."""
    rng = np.random.default_rng(1234)
    body = np.vstack([BODY, [[1.0, 0.0, 0.0]]])
    for _ in range(6):
        markers = _cap(rng, 30.0, 0.5, body=body)
    alone = registry.get("center", "LS")(markers[:, : len(BODY)])
    beside = registry.get("center", "LS")(markers)
    assert alone.status == "ok" and "center_step_bias_mm" in alone.diagnostics
    assert beside.status != "ok" or "center_step_bias_mm" in beside.diagnostics


def _spheres_centre(markers: np.ndarray, start: np.ndarray) -> np.ndarray:
    """The point ``(3,)`` [mm] about which the radial residuals of ``markers`` ``(N, n, 3)``
    [mm] (each marker's distances less their mean) have the least sum of squares, by SciPy's
    least squares from ``start`` ``(3,)`` [mm]: not the check's own iterations."""

    def residuals(centre: np.ndarray) -> np.ndarray:
        distances = np.linalg.norm(markers - centre, axis=-1)
        return (distances - distances.mean(axis=0)).ravel()

    return least_squares(residuals, start, xtol=1e-12, ftol=1e-12, gtol=1e-12).x


def test_the_iterations_settle_where_the_far_markers_fit_best():
    """A marker 1 mm from the joint lies about three noise SDs (the clear radius) from the
    four far markers' spheres' centre: left out near the joint and let back in there, it made
    the iterations from LS's answer cycle between the four's centre and the five's, and end
    at neither. Where they do not settle, a marker left out stays out: they end, in every
    draw, where SciPy puts the least of the four far markers' radial sum of squares, to the
    share of the step they settle to."""
    rng = np.random.default_rng(1234)
    body = np.vstack([BODY, [[1.0, 0.0, 0.0]]])
    for _ in range(12):
        markers = _cap(rng, 30.0, 0.5, body=body)
        answer = registry.get("center", "LS")(markers).center
        variance = support.assess("center", (markers,)).diagnostics["rigid_residual_mm"] ** 2
        row = centre_statistics(markers[None].copy(), answer[None], np.array([variance / 3]))[0]
        end = answer + row[centre_precision._TOWARDS]
        four = _spheres_centre(markers[:, : len(BODY)], end)
        step, sd = row[centre_precision._STEP], row[centre_precision._SD]
        settled = centre_precision._REFINED_TO * max(step, sd)
        assert np.linalg.norm(end - four) <= settled


def _sliding_cluster(rng, slide_mm: float) -> np.ndarray:
    """:func:`_cap`'s markers on a 40 degree cap with 0.3 mm noise, the whole cluster sliding
    rigidly on its segment by up to ``slide_mm`` as the segment turns (a skin-mounted plate):
    the markers stay one rigid body, but not at fixed distances from the centre."""
    t = np.linspace(0.0, 1.0, 120)
    spiral = 6 * np.pi * t
    vectors = math.radians(40.0) * np.stack(
        [t * np.cos(spiral), t * np.sin(spiral), 0.3 * t], axis=-1
    )
    slide = slide_mm * np.sin(spiral)[:, None, None] * np.array([1.0, 0.0, 0.0])
    markers = np.einsum("kij,kmj->kmi", rotation_matrix(vectors), BODY + slide) + CENTRE
    return markers + rng.normal(scale=0.3, size=markers.shape)


def test_a_cluster_sliding_on_its_segment_has_no_noise_only_precision():
    """A plate of markers sliding rigidly by 2 mm on its segment: the rigid-body residual sees
    only the noise, and the SD from it (0.16 mm) claims a precision the sliding belies (the
    answer lies 4 mm off). The spheres fit worse than that noise even about their own centre,
    and the status says so; without the sliding the same trials are ok."""
    rng = np.random.default_rng(31)
    for _ in range(5):
        for method in ("NM", "BC"):
            sliding = registry.get("center", method)(_sliding_cluster(rng, 2.0))
            assert "precision not determined" in sliding.status, sliding.status
            assert "about their own centre" in sliding.status
            assert sliding.diagnostics["center_spheres_fit_p_value"] < 1e-3
            still = registry.get("center", method)(_sliding_cluster(rng, 0.0))
            assert still.status == "ok", still.status


def test_the_largest_sd_is_numpys_largest_eigenvalue_to_rounding():
    """A joint centre's SD along its least determined direction reads the largest eigenvalue of
    its covariance as NumPy's ``eigvalsh`` gives it (its lower triangle), from a compiled call:
    to a few units in the last place; ``inf`` where an entry is not finite, NaN where no
    variance is positive."""
    rng = np.random.default_rng(7)
    for scale in (1e-6, 1.0, 1e6):
        factor = rng.normal(size=(3, 3))
        covariance = scale * factor @ factor.T
        covariance[0, 2] += 1e-9 * scale  # the upper triangle is not read
        largest = float(np.linalg.eigvalsh(covariance)[-1])
        # NumPy's LAPACK and the kernel's (SciPy's) may round differently: a few units in the
        # last place.
        rounding = 8 * np.finfo(float).eps * largest
        assert abs(centre_precision._largest_variance(covariance) - largest) <= rounding
        assert centre_precision._largest_sd(covariance) == pytest.approx(
            math.sqrt(largest), rel=8 * np.finfo(float).eps, abs=0
        )
    for entry in (math.nan, math.inf):
        broken = np.eye(3)
        broken[1, 2] = entry
        assert centre_precision._largest_sd(broken) == math.inf
    assert math.isnan(centre_precision._largest_sd(-np.eye(3)))
