"""Many-trial (batched) estimators agree with the one-trial functions on every study's data."""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

import numpy as np
import pytest

from jointbench.configuration.config import load_config
from jointbench.configuration.studies import get_study
from jointbench.estimators import registry
from jointbench.numerics.poses import rigid_poses
from jointbench.running import run

RTOL = 1e-9
CONFIG = Path(__file__).resolve().parents[1] / "config" / "config.yaml"

# A few conditions per study, chosen to include the hard ones (small RoM, few frames).
CONDITIONS = {
    "cmc": [
        {"marker_set": "M", "rom_deg": 5, "noise_mm": 2.0},
        {"marker_set": "H", "rom_deg": 45, "noise_mm": 0.5},
    ],
    "hinge": [
        {"protocol": "knee", "fe_rom_deg": 30, "aa_ratio": 0.1},
        {"protocol": "mcp", "fe_rom_deg": 90, "aa_ratio": 0.7},
    ],
    "hip": [{"n_frames": 4}, {"n_frames": 16}, {"n_frames": 300}],
}
N_TRIALS = 6


@functools.cache
def _trials(study: str, index: int):
    config = load_config(CONFIG)
    config["studies"][study]["trials"] = N_TRIALS
    return run.simulate_condition(config, study, CONDITIONS[study][index])


def _cases():
    for study, conditions in CONDITIONS.items():
        kind = get_study(study).kind
        for method in registry.methods(kind):
            if registry.has_own_many(kind, method):
                for index in range(len(conditions)):
                    yield study, method, index


def _assert_same(batched, single) -> None:
    if isinstance(single, Exception):
        assert type(batched) is type(single) and str(batched) == str(single)
        return
    assert not isinstance(batched, Exception), batched
    for field in dataclasses.fields(single):
        a, b = getattr(batched, field.name), getattr(single, field.name)
        if field.name == "diagnostics":
            assert a.keys() == b.keys()
            for key in b:
                _assert_close(a[key], b[key], key)
        else:
            _assert_close(a, b, field.name)


def _assert_close(a, b, name) -> None:
    if isinstance(b, dict):
        assert a.keys() == b.keys(), name
        for key in b:
            _assert_close(a[key], b[key], f"{name}.{key}")
    elif isinstance(b, str | bool | int) or b is None:
        assert a == b, name
    else:
        np.testing.assert_allclose(
            np.asarray(a, float), np.asarray(b, float), rtol=RTOL, err_msg=name
        )


@pytest.mark.parametrize(("study", "method", "index"), list(_cases()))
def test_batched_equals_one_trial(study, method, index):
    spec = get_study(study)
    fit = registry.get(spec.kind, method)
    trials = _trials(study, index)
    segments = [trials.segments[name] for name in spec.segments]
    outcomes = registry.many(spec.kind, method)(*segments)
    assert len(outcomes) == trials.n_trials
    for trial, outcome in enumerate(outcomes):
        try:
            single = fit(*spec.fit_arguments(trials, trial))
        except ValueError as error:
            single = error
        _assert_same(outcome, single)


def test_every_closed_form_and_pose_based_method_is_batched():
    expected = {
        "center": {"LS", "NM", "BC", "IS", "MA", "SCoRE"},
        "axis": {"planar", "radial", "combined", "SARA"},
        "joint_center": {"SCoRE", "analytic", "gauss-markov", "gauss-markov-frame0"},
    }
    for kind, names in expected.items():
        for name in names:
            assert registry.has_own_many(kind, name), (kind, name)


def test_rigid_poses_of_many_trials_equal_each_trial_alone():
    markers = _trials("hip", 2).segments["distal"]
    together = rigid_poses(markers)
    for trial in range(markers.shape[0]):
        alone = rigid_poses(markers[trial])
        for a, b in zip(together, alone, strict=True):
            np.testing.assert_allclose(a[trial], b, rtol=1e-12, atol=1e-9)


def test_shared_poses_give_the_same_answers():
    from jointbench.estimators.segment_poses import trial_poses

    trials = _trials("hip", 1)
    segments = {name: trials.segments[name] for name in ("proximal", "distal")}
    poses = trial_poses(segments, min_frames=3)
    for method in ("SCoRE", "analytic", "gauss-markov"):
        many = registry.many("joint_center", method)
        shared = many(*segments.values(), poses=poses)
        for a, b in zip(shared, many(*segments.values()), strict=True):
            _assert_same(a, b)


def test_bad_options_fail_every_trial_as_one_trial_does():
    trials = _trials("hip", 1)
    segments = (trials.segments["proximal"], trials.segments["distal"])
    # The method's own refusal; the checked form refuses the call before the fit, as the
    # checked one-trial form does (tests/test_checked_option_values.py).
    many = registry.many("joint_center", "gauss-markov", checked=False)
    outcomes = many(*segments, noise_mm=-1.0)
    assert all(isinstance(o, ValueError) and "noise_mm" in str(o) for o in outcomes)
    with pytest.raises(ValueError, match="noise_mm") as whole_call:
        registry.many("joint_center", "gauss-markov")(*segments, noise_mm=-1.0)
    with pytest.raises(ValueError) as one_trial:
        registry.get("joint_center", "gauss-markov")(*(s[0] for s in segments), noise_mm=-1.0)
    assert str(whole_call.value) == str(one_trial.value)


@pytest.mark.parametrize(("study", "method"), [("cmc", "LS"), ("hip", "gauss-markov")])
def test_estimate_uses_the_batched_form_and_keeps_its_table(study, method, monkeypatch):
    spec = get_study(study)
    # The studies run the registered function itself (their data are valid by construction).
    entry = registry._REGISTRY[spec.kind].get(method)
    trials = _trials(study, 0)
    condition = CONDITIONS[study][0]
    calls = []
    original = entry.many

    def spy(*segments, **options):
        calls.append((len(segments), len(segments[0])))
        return original(*segments, **options)

    monkeypatch.setattr(entry, "many", spy)
    batched = run.estimate(study, method, trials, condition)
    # The untimed warm-up on the first trial, then every trial in one call; a method with a
    # diagnostic of its study (gauss-markov: paper C's frame-0 control, run after the timed call)
    # refits every trial once more.
    expected = [(len(spec.segments), 1), (len(spec.segments), trials.n_trials)]
    if method in spec.diagnostics:
        expected.append((len(spec.segments), trials.n_trials))
    assert calls == expected
    monkeypatch.setattr(entry, "many", None)  # the one-trial function, trial by trial
    alone = run.estimate(study, method, trials, condition)
    assert list(batched.columns) == list(alone.columns)
    for column in alone.columns.drop("seconds"):
        if alone[column].dtype.kind == "f":
            np.testing.assert_allclose(batched[column], alone[column], rtol=RTOL, err_msg=column)
        else:
            assert (batched[column] == alone[column]).all(), column


def test_bc_at_its_iteration_limit_reports_as_one_trial():
    trials = _trials("cmc", 0)
    markers = trials.segments["moving"]
    fit = registry.get("center", "BC")
    outcomes = registry.many("center", "BC")(markers, max_iterations=3)
    assert any(not o.converged for o in outcomes)
    for trial, outcome in enumerate(outcomes):
        _assert_same(outcome, fit(markers[trial], max_iterations=3))


@pytest.mark.parametrize(
    ("methods", "absent"),
    [
        # The sphere fits' compiled kernels load Numba, whose start-up imports SciPy's BLAS
        # bindings (scipy.linalg); the optimisers are still not paid for.
        (("LS", "NM", "BC"), ("scipy.optimize",)),
    ],
)
def test_batched_fits_do_not_import_what_they_do_not_use(methods, absent):
    """An estimate job that fits whole batches does not pay for importing them."""
    import subprocess
    import sys

    code = (
        "import sys, numpy as np\n"
        "from jointbench.estimators import registry, sphere\n"
        "import jointbench.running.run\n"
        "rng = np.random.default_rng(0)\n"
        "markers = rng.normal(size=(3, 20, 3, 3)) + rng.normal(size=(3, 1, 3, 3)) * 10\n"
        f"for name in {methods!r}:\n"
        "    registry.many('center', name, checked=False)(markers)\n"
        f"print(sorted(m for m in {absent!r} if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"


def test_rigid_poses_in_chunks_equal_one_call(monkeypatch):
    from jointbench.numerics import poses

    markers = _trials("hip", 1).segments["proximal"]
    whole = poses.rigid_poses(markers)
    monkeypatch.setattr(poses, "_BLOCK_FRAMES", 2 * markers.shape[1])
    chunked = poses.rigid_poses(markers)
    for a, b in zip(whole, chunked, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("checked", [True, False])
@pytest.mark.parametrize(("kind", "method"), [("center", "LS"), ("center", "NM"), ("center", "BC")])
def test_a_bad_trial_fails_alone_with_the_one_trial_error(kind, method, checked):
    markers = _trials("cmc", 1).segments["moving"].copy()
    markers[2, 5, 1, 0] = np.nan
    markers[4] = markers[4, :1]  # does not move
    markers[5, 7, 2] = 0.0  # a gap stored as (0, 0, 0)
    markers[1, 3, 0, 1] = 0.0  # one coordinate at zero is data
    fit = registry.get(kind, method, checked=checked)
    outcomes = registry.many(kind, method, checked=checked)(markers)
    for trial, outcome in enumerate(outcomes):
        try:
            single = fit(markers[trial])
        except ValueError as error:
            single = error
        _assert_same(outcome, single)
    assert isinstance(outcomes[2], ValueError) and isinstance(outcomes[4], ValueError)
    assert "(0, 0, 0)" in str(outcomes[5])
    assert not isinstance(outcomes[3], ValueError) and not isinstance(outcomes[1], ValueError)


def test_a_bad_trial_fails_alone_in_a_two_segment_batch():
    trials = _trials("hip", 1)
    proximal = trials.segments["proximal"].copy()
    distal = trials.segments["distal"].copy()
    proximal[1, 0, 2] = proximal[1, 0, 0] + 2.0 * (proximal[1, 0, 1] - proximal[1, 0, 0])
    distal[3, 2, 0, 1] = np.inf
    fit = registry.get("joint_center", "SCoRE")
    outcomes = registry.many("joint_center", "SCoRE")(proximal, distal)
    for trial, outcome in enumerate(outcomes):
        try:
            single = fit(proximal[trial], distal[trial])
        except ValueError as error:
            single = error
        _assert_same(outcome, single)
    assert "collinear" in str(outcomes[1]) and "NaN or inf" in str(outcomes[3])


def test_local_minimum_diagnostic_equals_one_restart_per_trial():
    """Claim A7's restarts from the truth run as one batch, with the one-trial searches' answers."""
    from jointbench.estimators.sphere import fit_is, geometric_cost
    from jointbench.simulate.cmc import is_local_minimum

    trials = _trials("cmc", 0)
    markers = trials.segments["moving"]
    results = [fit_is(data) for data in markers]
    rows = is_local_minimum((markers,), results, trials.truth)
    for data, result, row in zip(markers, results, rows, strict=True):
        restart = fit_is(data, start=np.asarray(trials.truth["center"], dtype=float))
        gap = geometric_cost(data, result.center) - geometric_cost(data, restart.center)
        assert row["f1_gap"] == gap
    assert is_local_minimum((markers[:1],), [None], trials.truth) == [{}]


def test_a_noise_free_trial_leaves_the_nm_fits_of_the_others_as_they_are_alone():
    """A noise-free trial's NM scatter is singular and is solved from the data matrix's SVD
    instead; the trials beside it keep the answers they have in any other batch, and every
    trial's answer is the one-trial function's to the last bit (one implementation)."""
    fit_nm = registry.get("center", "NM")
    many_nm = registry.many("center", "NM")
    noisy = _trials("cmc", 0).segments["moving"][:3]
    rng = np.random.default_rng(7)
    directions = rng.normal(size=(noisy.shape[1], noisy.shape[2], 3))
    exact = 40.0 * directions / np.linalg.norm(directions, axis=-1, keepdims=True)
    batch = np.concatenate([noisy[:1], exact[None], noisy[1:]])
    outcomes = many_nm(batch)
    alone = [many_nm(trial[None])[0] for trial in batch]
    for outcome, single in zip(outcomes, alone, strict=True):
        assert np.array_equal(outcome.center, single.center) and outcome.cost == single.cost
    np.testing.assert_allclose(outcomes[1].center, 0.0, atol=1e-9)
    for outcome, trial in zip(outcomes, batch, strict=True):
        assert np.array_equal(outcome.center, fit_nm(trial).center)


def _batched_cases():
    for study in CONDITIONS:
        kind = get_study(study).kind
        for method in registry.methods(kind):
            if registry.has_own_many(kind, method):
                yield study, method


@pytest.mark.parametrize("checked", [False, True], ids=["unchecked", "checked"])
@pytest.mark.parametrize(("study", "method"), list(_batched_cases()))
def test_one_trial_near_1e200_fails_alone(study, method, checked):
    """A trial whose values overflow the fit's arithmetic is that trial's failed outcome; the
    other trials get exactly what they get alone."""
    kind = get_study(study).kind
    fit = registry.many(kind, method, checked=checked)
    index = len(CONDITIONS[study]) - 1
    segments = [np.array(s[:3]) for s in _trials(study, index).segments.values()]
    segments[-1][1] *= 1e200 / np.abs(segments[-1][1]).max()
    with np.errstate(all="ignore"):
        outcomes = fit(*segments)
        alone = [fit(*(s[[trial]] for s in segments))[0] for trial in (0, 2)]
    assert isinstance(outcomes[1], ValueError | FloatingPointError), outcomes[1]
    for batched, single in zip((outcomes[0], outcomes[2]), alone, strict=True):
        _assert_same(batched, single)
