"""Every registered estimator, found by discovery, held to the same rules.

For each kind the suite builds one rig (noise-free and noisy) and runs every method of
``jointbench.methods(kind)`` through the public API:

* bad input raises a ``ValueError`` naming the problem (and where it is);
* data that cannot support an answer (no rotation beyond noise, markers that are not one
  rigid body) give a result whose ``status`` says so;
* noise-free data are recovered to the method's registered ``recovery`` claim, also 1e9 mm
  from the origin;
* the answer follows translation, rotation, marker order and frame order of the data to the
  tolerance the method registered for each (those it does not claim are skipped).

An estimator registered later is held to all of this without a line added here.
"""

from __future__ import annotations

import functools
import re

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st
from rigs import HINGE, JOINT, one_segment, two_segments
from workflow_copy import readme_builtin_example

import jointbench
from jointbench.configuration.config import SCHEMA_PATH
from jointbench.estimators import axis as axis_costs
from jointbench.estimators import registry, support
from jointbench.estimators.results import CenterResult
from jointbench.geometry import angle_between_lines_deg, rotation_matrix, unit

KINDS = ("center", "axis", "joint_center")
CASES = [(kind, method) for kind in KINDS for method in jointbench.methods(kind)]
IDS = [f"{kind}-{method}" for kind, method in CASES]
N_FRAMES = 150
# A rigid motion of the whole recording and a far offset, both arbitrary.
ROTATION = rotation_matrix(np.array([0.4, -1.1, 0.7]))
SHIFT = np.array([250.0, -80.0, 40.0])
FAR = np.array([1e9, -1e9, 1e9])
# Where a bad value is planted: (frame, marker).
FRAME, MARKER = 7, 1


def clean(kind: str) -> tuple[np.ndarray, ...]:
    """Noise-free marker arrays for ``kind`` whose answer is JOINT (and HINGE for axes)."""
    if kind == "joint_center":
        return two_segments(N_FRAMES)
    return (one_segment(N_FRAMES, "hinge" if kind == "axis" else "ball"),)


def noisy(kind: str, sd_mm: float = 0.5, seed: int = 0) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    arrays = clean(kind)
    if kind == "axis":
        # A small secondary rotation, as in any real hinge, so that the sphere fit behind the
        # axis methods' default point is determined.
        t = np.linspace(0.0, 4.0, N_FRAMES)
        wobble = rotation_matrix(0.05 * np.sin(2.3 * t)[:, None] * unit(np.cross(HINGE, [0, 0, 1])))
        arrays = (np.einsum("fij,fmj->fmi", wobble, clean(kind)[0] - JOINT) + JOINT,)
    return tuple(
        array + rng.normal(scale=sd_mm / np.sqrt(3.0), size=array.shape) for array in arrays
    )


def fit(kind: str, method: str, arrays, **options):
    if kind == "center":
        return jointbench.fit_center(*arrays, method=method, **options)
    if kind == "axis":
        return jointbench.fit_axis(*arrays, method=method, **options)
    return jointbench.fit_joint_center(*arrays, method=method, **options)


def _last_replaced(arrays: tuple, last: np.ndarray) -> tuple:
    """``arrays`` with its last (for two segments: the distal) array replaced."""
    return (*arrays[:-1], last)


def _planted(kind: str, value) -> tuple:
    arrays = clean(kind)
    bad = arrays[-1].copy()
    bad[FRAME, MARKER] = value
    return _last_replaced(arrays, bad)


def _name(kind: str) -> str:
    return "distal" if kind == "joint_center" else "markers"


# --- bad input -------------------------------------------------------------------------------


def _complex(kind):
    return _last_replaced(clean(kind), clean(kind)[-1] + 1e-3j)


def _masked(kind):
    last = clean(kind)[-1]
    mask = np.zeros(last.shape, dtype=bool)
    mask[FRAME, MARKER, 2] = True
    return _last_replaced(clean(kind), np.ma.masked_array(last, mask=mask))


def _boolean(kind):
    last = clean(kind)[-1]
    return _last_replaced(clean(kind), last > np.median(last))


def _ragged(kind):
    last = clean(kind)[-1].tolist()
    last[FRAME] = last[FRAME][:2]
    return _last_replaced(clean(kind), last)


def _sliding(kind):
    """Every marker of the moving segment slides along one straight line."""
    arrays = clean(kind)
    steps = np.linspace(0.0, 80.0, N_FRAMES)[:, None, None] * unit(np.array([0.3, 0.5, 0.8]))
    still = tuple(np.repeat(array[:1], N_FRAMES, axis=0) for array in arrays)
    return _last_replaced(still, still[-1] + steps)


BAD_INPUT = {
    "complex": (_complex, r"{name} is complex"),
    "masked": (_masked, r"{name} is a masked array .* marker 1, frame 7"),
    "bool": (_boolean, r"{name} has dtype bool"),
    "ragged": (_ragged, r"{name} is not a regular numeric array"),
    "nan": (lambda kind: _planted(kind, np.nan), r"{name} contains NaN .* marker 1, frame 7"),
    "inf": (
        lambda kind: _planted(kind, np.inf),
        r"{name} contains NaN or inf at marker 1, frame 7",
    ),
    "zero-gap": (
        lambda kind: _planted(kind, 0.0),
        r"{name} has a sample at exactly \(0, 0, 0\) at marker 1, frame 7 .* if these are gaps",
    ),
    "sliding": (_sliding, r"do not rotate"),
}


@pytest.mark.parametrize("case", list(BAD_INPUT))
@pytest.mark.parametrize(("kind", "method"), CASES, ids=IDS)
def test_bad_input_raises_a_value_error_naming_it(kind, method, case):
    make, message = BAD_INPUT[case]
    with pytest.raises(ValueError, match=message.format(name=_name(kind))):
        fit(kind, method, make(kind))


# --- data that cannot support an answer ------------------------------------------------------


def _static_with_noise(kind):
    rng = np.random.default_rng(1)
    still = tuple(np.repeat(array[:1], N_FRAMES, axis=0) for array in clean(kind))
    return tuple(array + rng.normal(scale=0.5 / np.sqrt(3.0), size=array.shape) for array in still)


def _sliding_with_noise(kind):
    rng = np.random.default_rng(2)
    return tuple(
        array + rng.normal(scale=0.5 / np.sqrt(3.0), size=array.shape) for array in _sliding(kind)
    )


def _random_cloud(kind):
    rng = np.random.default_rng(3)
    # Points drawn anew in every frame from a 50 mm cube where the segment was: no shape at all.
    where = clean(kind)[-1][0].mean(axis=0)
    cloud = where + rng.uniform(-25.0, 25.0, size=(N_FRAMES, 3, 3))
    return _last_replaced(clean(kind), cloud)


UNSUPPORTED = {
    "static-with-noise": (_static_with_noise, "range of motion too small"),
    "sliding-with-noise": (_sliding_with_noise, "range of motion too small"),
    "random-cloud": (_random_cloud, "not one rigid body"),
}


@pytest.mark.parametrize("case", list(UNSUPPORTED))
@pytest.mark.parametrize(("kind", "method"), CASES, ids=IDS)
def test_unsupported_data_are_flagged_in_the_status(kind, method, case):
    make, words = UNSUPPORTED[case]
    try:
        result = fit(kind, method, make(kind))
    except ValueError:
        return  # refusing is as honest as flagging
    assert words in result.status, result.status
    assert result.diagnostics["support_assessed"]


# --- known answers ---------------------------------------------------------------------------


def _errors(kind: str, result, offset: np.ndarray | None = None) -> tuple[float, ...]:
    """Errors against the rig's truth moved by ``offset``: [mm] for a centre; [rad] and [mm]
    for an axis (the angle to HINGE and the distance of the fitted point from the true axis)."""
    truth = JOINT if offset is None else JOINT + offset
    if kind == "axis":
        direction = np.asarray(result.direction)
        angle = float(np.radians(angle_between_lines_deg(direction, HINGE)))
        arm = np.asarray(result.point) - truth
        return angle, float(np.linalg.norm(arm - (arm @ HINGE) * HINGE))
    return (float(np.linalg.norm(np.asarray(result.center) - truth)),)


@pytest.mark.parametrize(("kind", "method"), CASES, ids=IDS)
def test_noise_free_data_are_recovered_to_the_claimed_tolerance(kind, method):
    recovery = registry.claims(kind, method).recovery
    result = fit(kind, method, clean(kind))
    # "restarted: ..." is the honest status of an answer found by the self-check's restart.
    assert result.converged, result.status
    assert result.status == "ok" or result.status.startswith("restarted: "), result.status
    if recovery is None:
        pytest.skip(f"{method} does not claim recovery with its default options")
    assert max(_errors(kind, result)) <= recovery


@pytest.mark.parametrize(("kind", "method"), CASES, ids=IDS)
def test_noise_free_data_far_from_the_origin_are_recovered(kind, method):
    """1e9 mm away the coordinates carry 1.2e-7 mm of rounding; the answer may lose at most
    1e-12 of the offset (1e-3 mm) to it, beyond the method's claims at the origin."""
    claims = registry.claims(kind, method)
    if claims.recovery is None:
        pytest.skip(f"{method} does not claim recovery with its default options")
    result = fit(kind, method, tuple(array + FAR for array in clean(kind)))
    allowed = claims.recovery + claims.invariances.get("translation", np.inf) + 1e-12 * 1e9
    assert max(_errors(kind, result, FAR)) <= allowed


@pytest.mark.parametrize(("kind", "method"), CASES, ids=IDS)
def test_the_claimed_fewest_frames_are_exactly_those_the_method_fits(kind, method):
    """The config check refuses a condition shorter than every listed method's claim, so the
    claim must be the method's own limit: it fits that many frames (spread over the motion)
    and refuses one fewer, naming the limit."""
    fewest = registry.claims(kind, method).min_frames
    arrays = noisy(kind)

    def spread(n_frames):
        keep = np.linspace(0, N_FRAMES - 1, n_frames).round().astype(int)
        return tuple(array[keep] for array in arrays)

    fit(kind, method, spread(fewest))
    if fewest > 1:
        with pytest.raises(ValueError, match=f"needs at least {fewest}"):
            fit(kind, method, spread(fewest - 1))


# --- invariances -----------------------------------------------------------------------------


def _answer(kind: str, result) -> tuple[np.ndarray, ...]:
    if kind == "axis":
        return np.asarray(result.point), np.asarray(result.direction)
    return (np.asarray(result.center),)


def _assert_same(kind, found, expected, tolerance, scale):
    """``found`` equals ``expected`` to ``tolerance`` plus rounding (1e-12 of the data's
    magnitude ``scale`` [mm]); axes are compared as lines."""
    allowed = tolerance + 1e-12 * scale
    if kind == "axis":
        (point, direction), (point_expected, direction_expected) = found, expected
        # From the sine and the cosine: arccos of the cosine alone cannot tell directions a
        # rounding error apart from ones 1.5e-8 rad apart.
        angle = float(np.radians(angle_between_lines_deg(direction, direction_expected)))
        offset = point_expected - point
        distance = float(np.linalg.norm(offset - (offset @ direction) * direction))
        assert angle <= allowed and distance <= allowed, (angle, distance, allowed)
    else:
        assert np.linalg.norm(found[0] - expected[0]) <= allowed, (found, expected, allowed)


def _moved(kind, answer, rotation, shift):
    if kind == "axis":
        return rotation @ answer[0] + shift, rotation @ answer[1]
    return (rotation @ answer[0] + shift,)


TRANSFORMS = {
    "translation": (lambda array: array + SHIFT, np.eye(3), SHIFT),
    "rotation": (lambda array: array @ ROTATION.T, ROTATION, np.zeros(3)),
}


@pytest.mark.parametrize("invariance", list(TRANSFORMS))
@pytest.mark.parametrize(("kind", "method"), CASES, ids=IDS)
def test_answers_move_with_the_data(kind, method, invariance):
    tolerance = registry.claims(kind, method).invariances.get(invariance)
    if tolerance is None:
        pytest.skip(f"{method} does not claim {invariance} invariance")
    transform, rotation, shift = TRANSFORMS[invariance]
    arrays = noisy(kind)
    before = fit(kind, method, arrays)
    after = fit(kind, method, tuple(transform(array) for array in arrays))
    scale = max(float(np.abs(array).max()) for array in arrays) + float(np.abs(shift).max())
    expected = _moved(kind, _answer(kind, before), rotation, shift)
    _assert_same(kind, _answer(kind, after), expected, tolerance, scale)


def _reordered(kind, arrays, what):
    rng = np.random.default_rng(4)
    if what == "marker_order":
        return tuple(array[:, rng.permutation(array.shape[1])] for array in arrays)
    # Frame 0 stays first: several methods anchor the body frame at it.
    order = np.concatenate([[0], 1 + rng.permutation(N_FRAMES - 1)])
    return tuple(array[order] for array in arrays)


@pytest.mark.parametrize("invariance", ["marker_order", "frame_order"])
@pytest.mark.parametrize(("kind", "method"), CASES, ids=IDS)
def test_answers_ignore_the_order_of_markers_and_frames(kind, method, invariance):
    tolerance = registry.claims(kind, method).invariances.get(invariance)
    if tolerance is None:
        pytest.skip(f"{method} does not claim {invariance} invariance")
    arrays = noisy(kind)
    before = fit(kind, method, arrays)
    after = fit(kind, method, _reordered(kind, arrays, invariance))
    scale = max(float(np.abs(array).max()) for array in arrays)
    _assert_same(kind, _answer(kind, after), _answer(kind, before), tolerance, scale)


# --- the rules hold for an estimator registered later ----------------------------------------


@pytest.fixture
def naive_estimator():
    """A centre estimator with no checks of its own: the centroid, always "converged"."""

    def centroid(markers, **options):
        return CenterResult(
            center=np.asarray(markers).reshape(-1, 3).mean(axis=0),
            converged=True,
            iterations=0,
            status="ok",
            method="centroid",
        )

    registry.register("center", "centroid")(centroid)
    yield "centroid"
    registry.unregister("center", "centroid")


@pytest.mark.parametrize("name", ["1st-centre", "my centre", "lab/centre", "", "café"])
def test_a_name_the_config_cannot_list_is_refused_at_registration(name):
    """The README's rule for names (a letter, then letters, digits, '_' and '-') is the
    config's: a name outside it, which no study could list and which would name an estimates
    folder, is refused as the estimator registers, naming the rule, not first at a run."""
    with pytest.raises(ValueError, match="starts with a letter"):
        registry.register("center", name)(lambda markers: None)
    assert name not in registry.methods("center")


def test_the_estimator_name_rule_is_the_config_schema_s():
    """One rule for a name: the config schema's patterns for its estimator lists are the
    registry's."""
    schema = yaml.safe_load(SCHEMA_PATH.read_text())
    study = schema["properties"]["studies"]["additionalProperties"]["properties"]
    for key in ("estimators", "external_estimators"):
        assert study[key]["items"]["pattern"] == f"^{registry.NAME_PATTERN.pattern}$"


def test_a_new_estimator_gets_the_checks_without_code_of_its_own(naive_estimator):
    with pytest.raises(ValueError, match="markers contains NaN or inf at marker 1, frame 7"):
        jointbench.fit_center(*_planted("center", np.nan), method=naive_estimator)
    result = jointbench.fit_center(*_static_with_noise("center"), method=naive_estimator)
    assert "range of motion too small" in result.status
    # Data that support a centre do not make the centroid one: the centre check says so.
    result = jointbench.fit_center(*clean("center"), method=naive_estimator)
    assert "support" not in result.status
    assert "not the markers' common centre of rotation" in result.status


@pytest.fixture
def readme_estimator():
    """The README's built-in example ("Built in: one function"), registered as it is written."""
    code, _ = readme_builtin_example()
    name = re.search(r'@register\("center", "([^"]+)"', code).group(1)
    if name in jointbench.methods("center"):
        # Copied into the package, as the README says: held to the suite as registered there.
        yield name
        return
    exec(compile(code, "README.md", "exec"), {})
    yield name
    registry.unregister("center", name)


def _readme_checks() -> dict:
    """Every per-method check of this suite, by name, with its own parameter bound."""
    checks = {
        "noise-free": test_noise_free_data_are_recovered_to_the_claimed_tolerance,
        "far-from-origin": test_noise_free_data_far_from_the_origin_are_recovered,
        "fewest-frames": test_the_claimed_fewest_frames_are_exactly_those_the_method_fits,
    }
    for name in TRANSFORMS:
        checks[name] = functools.partial(test_answers_move_with_the_data, invariance=name)
    for name in ("marker_order", "frame_order"):
        checks[name] = functools.partial(
            test_answers_ignore_the_order_of_markers_and_frames, invariance=name
        )
    for case in BAD_INPUT:
        checks[f"bad-{case}"] = functools.partial(
            test_bad_input_raises_a_value_error_naming_it, case=case
        )
    for case in UNSUPPORTED:
        checks[f"unsupported-{case}"] = functools.partial(
            test_unsupported_data_are_flagged_in_the_status, case=case
        )
    return checks


@pytest.mark.parametrize("check", list(_readme_checks()))
def test_the_readme_builtin_example_meets_its_claims(readme_estimator, check):
    """The README's built-in example ("Built in: one function"), registered as it is written,
    passes every per-method check of this suite, as any method copied into the package must."""
    _readme_checks()[check]("center", readme_estimator)


def test_claims_name_only_known_invariances():
    with pytest.raises(ValueError, match="unknown invariance"):
        registry.Claims(invariances={"scale": 1e-9})


# --- the support verdict ---------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["center", "joint_center"])
def test_the_rotation_test_is_calibrated_on_static_clusters(kind):
    """With no rotation the p-value is uniform: about half the trials fall below 0.5 (the
    bounds are four binomial standard deviations)."""
    rng = np.random.default_rng(6)
    still = tuple(np.repeat(array[:1], 60, axis=0) for array in clean(kind))
    p_values = [
        support.assess(kind, tuple(a + rng.normal(size=a.shape) for a in still)).diagnostics[
            "rotation_p_value"
        ]
        for _ in range(200)
    ]
    assert 0.36 <= np.mean(np.array(p_values) < 0.5) <= 0.64


def test_rotation_about_a_single_axis_is_flagged_for_centres_only():
    rng = np.random.default_rng(8)
    hinge = (clean("axis")[0] + rng.normal(scale=0.5 / np.sqrt(3.0), size=(N_FRAMES, 3, 3)),)
    assert "rotation about a single axis" in fit("center", "LS", hinge).status
    assert fit("axis", "planar", hinge).status == "ok"


@pytest.mark.parametrize("offset_mm", [0.0, 1e6])
def test_a_noise_free_hinge_is_flagged_as_rotation_about_a_single_axis(offset_mm):
    """Without noise the rigid-body residual is rounding, and so is the off-axis rotation:
    their ratio means nothing, and the hinge is a hinge (also far from the origin)."""
    hinge = (clean("axis")[0] + offset_mm,)
    result = fit("center", "LS", hinge)
    assert "rotation about a single axis" in result.status, result.status
    assert result.diagnostics["support_off_axis_rotation_rms_deg"] < 1e-5


def test_noise_free_segments_that_do_not_rotate_relative_to_each_other_are_flagged():
    """Noise-free, the relative rotation of two rigidly joined segments is rounding only."""
    rng = np.random.default_rng(3)
    rotations = rotation_matrix(rng.normal(scale=0.3, size=(50, 3)))
    shifts = rng.normal(scale=100.0, size=(50, 1, 3)) + np.array([500.0, 800.0, 1000.0])
    proximal_body = rng.normal(scale=40.0, size=(4, 3))
    distal_body = rng.normal(scale=40.0, size=(4, 3)) + np.array([0.0, 0.0, -300.0])
    proximal, distal = (
        np.einsum("fij,mj->fmi", rotations, body) + shifts for body in (proximal_body, distal_body)
    )
    verdict = support.assess("joint_center", (proximal, distal))
    assert any("range of motion too small" in warning for warning in verdict.warnings), verdict


def test_a_small_cluster_with_large_noise_is_still_one_rigid_body():
    """Paper A's M marker set (13.8, 29.0, 15.7 mm from the centre) with 2 mm noise is a hard
    but legitimate recording, not a non-rigid one."""
    body = unit(np.array([[0.2, 0.3, 1.0], [0.0, 0.1, 1.0], [-0.3, 0.2, 1.0]]))
    body = body * np.array([[13.8], [29.0], [15.7]])
    t = np.linspace(0.0, 4.0, 120)
    rotvec = np.stack([0.6 * np.sin(1.9 * t), 0.4 * np.sin(1.3 * t), 0.1 * np.sin(t)], -1)
    markers = np.einsum("fij,pj->fpi", rotation_matrix(rotvec), body) + JOINT
    rng = np.random.default_rng(7)
    result = fit(
        "center", "NM", (markers + rng.normal(scale=2.0 / np.sqrt(3), size=markers.shape),)
    )
    assert result.status == "ok", result.status
    assert result.diagnostics["support_nonrigid_share"] < support.MAX_NONRIGID_SHARE


def test_support_leaves_converged_as_the_method_set_it():
    arrays = _static_with_noise("center")
    raw = registry.get("center", "LS", checked=False)(*arrays)
    checked = fit("center", "LS", arrays)
    assert raw.converged and checked.converged and raw.status == "ok"
    assert checked.status.startswith("warning: range of motion too small")
    np.testing.assert_array_equal(checked.center, raw.center)


@settings(max_examples=30, deadline=None)
@given(
    frame=st.integers(0, N_FRAMES - 1), marker=st.integers(0, 2), gap=st.sampled_from([np.nan, 0.0])
)
def test_a_gap_anywhere_is_named_by_marker_and_frame(frame, marker, gap):
    markers = clean("center")[0].copy()
    markers[frame, marker] = gap
    with pytest.raises(ValueError, match=rf"at marker {marker}, frame {frame}\b"):
        jointbench.fit_center(markers, method="NM")


# --- noise-free and near-degenerate families ---------------------------------------------------


def random_hinge(rng: np.random.Generator, n_frames: int = 150):
    """Noise-free markers ``(N, P, 3)`` [mm] of a hinge at a random orientation: 3-5 markers
    30-150 mm from the axis and up to 100 mm along it from a random point, 20-120 degrees of
    flexion; returns the markers, the axis direction and a point on it."""
    axis = unit(rng.normal(size=3))
    point = rng.normal(scale=200.0, size=3)
    radial = unit(np.cross(axis, rng.normal(size=3)))
    body = np.array(
        [
            point
            + rng.uniform(30.0, 150.0) * rotation_matrix(rng.uniform(0, 2 * np.pi) * axis) @ radial
            + rng.uniform(-100.0, 100.0) * axis
            for _ in range(int(rng.integers(3, 6)))
        ]
    )
    t = np.linspace(0.0, 1.0, n_frames)
    angle = np.radians(rng.uniform(20.0, 120.0)) * 0.5 * (1.0 - np.cos(2 * np.pi * t))
    rotation = rotation_matrix((angle + rng.uniform(-1.0, 1.0))[:, None] * axis)
    return np.einsum("fij,pj->fpi", rotation, body - point) + point, axis, point


# Hinges (seeds of random_hinge) among which the ten-start searches of radial and combined stop
# in a local minimum on some machines; 5 is an ordinary one. Which seeds trap a search depends on
# the last bits of the arithmetic (the BLAS kernels a processor gets), so the test of the
# restart below scans a range of seeds instead of naming one.
HINGE_SEEDS = (2, 5, 11, 69)
TRAP_SCAN_SEEDS = range(80)


@pytest.mark.parametrize("seed", HINGE_SEEDS)
@pytest.mark.parametrize("method", jointbench.methods("axis"))
def test_noise_free_hinges_at_any_orientation_are_recovered_or_flagged(method, seed):
    """The claim holds on every noise-free hinge: the checked call's answer is within the
    claimed recovery, and "ok" only when the first search found it."""
    markers, axis, _ = random_hinge(np.random.default_rng(seed))
    result = jointbench.fit_axis(markers, method=method)
    recovery = registry.claims("axis", method).recovery
    angle = float(np.radians(angle_between_lines_deg(result.direction, axis)))
    assert result.status == "ok" or result.status.startswith("restarted: "), result.status
    assert angle <= recovery, (angle, result.status)


@pytest.mark.parametrize("method", ["radial", "combined"])
def test_a_trapped_axis_search_says_it_restarted(method):
    """Every search of the scan that its ten starts leave in a local minimum (more than 5 deg
    off the hinge) is restarted by the checked call, which says so and keeps the lower cost;
    the scan must meet such a search, or it tests nothing."""
    trapped = 0
    for seed in TRAP_SCAN_SEEDS:
        markers, axis, _ = random_hinge(np.random.default_rng(seed))
        raw = registry.get("axis", method, checked=False)(markers)
        if angle_between_lines_deg(raw.direction, axis) <= 5.0:
            continue
        trapped += 1
        result = jointbench.fit_axis(markers, method=method)
        assert result.status.startswith("restarted: the search stopped in a local minimum"), (
            seed,
            result.status,
        )
        assert result.cost < raw.cost, seed
        assert result.diagnostics["local_minimum_cost"] == raw.cost, seed
    assert trapped > 0, f"no {method} search of the scan was trapped"


def _one_segment_methods():
    return [(kind, method) for kind in ("center", "axis") for method in jointbench.methods(kind)]


def _few_markers(n_markers: int, seed: int) -> np.ndarray:
    """Random positions (a cloud, no motion to speak of) of ``n_markers`` markers."""
    return np.random.default_rng(seed).normal(size=(N_FRAMES, n_markers, 3)) * 50.0 + 100.0


def _collinear_translation(seed: int = 0) -> np.ndarray:
    """Three collinear markers translating along their own line, with 0.3 mm noise."""
    rng = np.random.default_rng(seed)
    line = unit(np.array([1.0, 0.5, 0.2]))
    body = np.array([0.0, 40.0, 100.0])[:, None] * line + 300.0
    steps = np.linspace(0.0, 80.0, N_FRAMES)[:, None, None] * line
    return body + steps + rng.normal(scale=0.3, size=(N_FRAMES, 3, 3))


def _one_marker_arc(n_markers: int) -> np.ndarray:
    """Noise-free markers of the ball rig, only the first ``n_markers``."""
    return clean("center")[0][:, :n_markers]


DEGENERATE = {
    "one-marker-cloud": lambda: _few_markers(1, 0),
    "two-marker-cloud": lambda: _few_markers(2, 1),
    "collinear-translation": _collinear_translation,
    "one-marker-arc": lambda: _one_marker_arc(1),
    "two-marker-arc": lambda: _one_marker_arc(2),
}


@pytest.mark.parametrize("case", list(DEGENERATE))
@pytest.mark.parametrize(("kind", "method"), _one_segment_methods())
def test_too_few_markers_or_collinear_ones_are_never_ok(kind, method, case):
    """Without three non-collinear markers there is no pose to check rigidity or the rotation
    with: the status says what was not verified (and why the data fail, where they do)."""
    try:
        result = fit(kind, method, (DEGENERATE[case](),))
    except ValueError:
        return  # refusing is as honest as flagging
    assert result.status != "ok" and "not verified" in result.status, result.status
    if case == "collinear-translation":
        assert "range of motion too small" in result.status, result.status


@pytest.mark.parametrize("kind", ["center", "axis"])
def test_one_marker_on_its_sphere_is_recovered_and_says_what_it_did_not_check(kind):
    method = "NM" if kind == "center" else "planar"
    arrays = (_one_marker_arc(2),) if kind == "center" else (clean("axis")[0][:, :1],)
    result = fit(kind, method, arrays)
    assert "not verified" in result.status and "range of motion" not in result.status
    assert max(_errors(kind, result)) <= registry.claims(kind, method).recovery


def test_ma_ignores_the_order_of_the_frames_even_reversed():
    """The body frame no longer follows frame 0, so reversing the recording moves nothing."""
    markers = noisy("center")[0]
    forward = jointbench.fit_center(markers, method="MA")
    reverse = jointbench.fit_center(markers[::-1], method="MA")
    tolerance = registry.claims("center", "MA").invariances["frame_order"]
    assert np.linalg.norm(forward.center - reverse.center) <= tolerance + 1e-12 * 1e3


@pytest.mark.parametrize("method", ["IS", "BC", "MA"])
def test_search_based_centres_carry_their_self_check(method):
    result = fit("center", method, noisy("center"))
    assert result.status == "ok" and "self_check" in result.diagnostics


def test_is_stopped_away_from_its_minimum_is_restarted():
    """Started far away with a tiny iteration budget, IS stops short; the self-check finds
    lower f1 at the NM centre and restarts from there."""
    markers = noisy("center")[0]
    raw = registry.get("center", "IS", checked=False)(markers, start=JOINT + 40.0)
    result = jointbench.fit_center(markers, method="IS", start=JOINT + 40.0)
    assert result.cost <= raw.cost
    if raw.cost > result.cost + 1e-4:
        assert result.status.startswith("restarted: ")


def _same_value(found, expected, name: str) -> None:
    """Two results' fields (``name``) equal: numbers to 1e-9 relative (a batch's array
    operations may round otherwise than one trial's), dicts entry by entry, anything else
    exactly."""
    if isinstance(expected, np.ndarray | float):
        np.testing.assert_allclose(found, expected, rtol=1e-9, atol=1e-12, err_msg=name)
    elif isinstance(expected, dict):
        assert found.keys() == expected.keys(), name
        for key, value in expected.items():
            _same_value(found[key], value, f"{name}[{key}]")
    else:
        assert found == expected, name


@pytest.mark.parametrize("checked", [False, True])
@pytest.mark.parametrize(("kind", "method"), CASES, ids=IDS)
def test_the_many_trial_form_answers_as_the_one_trial_function(kind, method, checked):
    """Each trial of a many-trial call gets what the one-trial function gives it: a method's
    own many-trial form (a newcomer's too) is held to the function it stands for, checked or
    not, on noisy, noise-free and unsupported trials together."""
    trials = [noisy(kind, seed=1), clean(kind), noisy(kind, sd_mm=0.2, seed=2), _sliding(kind)]
    one = registry.get(kind, method, checked=checked)
    outcomes = registry.many(kind, method, checked=checked)(
        *(np.stack(arrays) for arrays in zip(*trials, strict=True))
    )
    assert len(outcomes) == len(trials)
    for arrays, found in zip(trials, outcomes, strict=True):
        try:
            expected = one(*arrays)
        except ValueError as error:
            assert type(found) is type(error) and str(found) == str(error)
            continue
        assert type(found) is type(expected), (found, expected)
        _same_value(vars(found), vars(expected), "result")


@pytest.mark.parametrize("method", ["planar", "radial", "combined"])
def test_an_unchecked_axis_search_left_above_the_eigenvectors_cost_does_not_say_ok(method):
    """A method's own call (the simulated studies run it without the checks) says ``ok`` only
    where its answer is its cost's minimum as far as the planar cost's eigenvector tells: where
    the cost there is lower, the ten starts did not find the minimum, and the status says so
    (naming both costs) while the answer stays the method's. For paper B's three costs on
    noisy hinges that trap the radial search in about half the trials, every trial whose
    restart from that eigenvector finds a lower minimum is one of them, and no other."""
    flagged = 0
    for seed in TRAP_SCAN_SEEDS[:30]:
        rng = np.random.default_rng(seed)
        markers = one_segment(120, "hinge") + rng.normal(scale=0.5, size=(120, 3, 3))
        raw = registry.get("axis", method, checked=False)(markers)
        restarted = axis_costs._self_check(raw, markers).status.startswith("restarted: ")
        assert raw.converged, (seed, raw.status)
        if raw.status == "ok":
            assert not restarted, seed
            continue
        flagged += 1
        assert raw.status.startswith("warning: not the cost's minimum: "), (seed, raw.status)
        assert f"{raw.cost:.6g}" in raw.status, (seed, raw.status)
        assert restarted, seed
    if method == "radial":
        assert flagged >= 10, flagged  # the scan meets trapped searches, or it tests nothing


@pytest.mark.parametrize("parameterisation", ["angles", "vector"])
@pytest.mark.parametrize("method", ["planar", "radial", "combined"])
def test_a_restart_from_the_eigenvector_is_not_said_to_stop_above_it(method, parameterisation):
    """The checked call's restart starts from the planar cost's eigenvector, so it ends at most
    at the cost it starts from: its status never says the eigenvector undercuts it, even at
    ``fatol = 0`` where the eigenvector's cost, taken over another parameterisation than the
    search's, differs from the start's by rounding alone. Held to what the checked call said
    before the unchecked status compared the eigenvector: a restart its iteration limit stops
    says that and no more."""
    for seed in range(8):
        rng = np.random.default_rng(seed)
        markers = one_segment(120, "hinge") + rng.normal(scale=0.5, size=(120, 3, 3))
        found = registry.get("axis", method)(
            markers, fatol=0.0, max_iter=3, parameterisation=parameterisation
        )
        assert "not the cost's minimum" not in found.status, (seed, found.status)


@pytest.mark.parametrize(
    ("converged", "at_eigenvector", "said"),
    [
        (True, 100.0 - 2e-4, ["warning: not the cost's minimum: "]),
        (True, 100.0 - 1e-4, []),
        (True, 100.0 + 1.0, []),
        (True, float("nan"), []),
        (False, 100.0 - 1e-4, ["winning start stopped at the iteration/evaluation limit"]),
        (
            False,
            50.0,
            [
                "winning start stopped at the iteration/evaluation limit",
                "warning: not the cost's minimum: ",
            ],
        ),
    ],
)
def test_an_axis_search_says_ok_unless_stopped_or_undercut_by_more_than_fatol(
    converged, at_eigenvector, said
):
    """The status of a search that ended at cost 100 with fatol 1e-4: the eigenvector's cost
    lower by more than fatol (not by fatol itself, nor a NaN cost) says it, after the limit
    where the search stopped there; nothing said is ``"ok"``."""
    status = axis_costs._search_status(converged, 100.0, at_eigenvector, 1e-4)
    parts = status.split("; ")
    assert len(parts) == max(len(said), 1), status
    if not said:
        assert status == "ok"
    for part, start in zip(parts, said, strict=False):
        assert part.startswith(start), status
    if "minimum" in status:
        assert f"{at_eigenvector:.6g}" in status and "100" in status, status
