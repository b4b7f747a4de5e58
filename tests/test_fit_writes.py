"""A checked call judges the data its caller gave, whatever the method's fit does with the arrays
it was handed: a user's fit may write to them (normalise in place, fill a gap, reuse them as a
buffer) and the support verdict, the precision and the caller's arrays are those of the data
as given. The package's own fits never write to their input (every registered method is held
to that here), which is what lets them share the checks' sums (:mod:`jointbench.numerics.reuse`).
"""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest
from rigs import one_segment, two_segments

import jointbench
from jointbench import owncode
from jointbench.estimators import registry, twosegment

BUILT_IN = {"center": "LS", "axis": "planar", "joint_center": "SCoRE"}


def _noisy_trial(kind: str, seed: int, n_frames: int = 120) -> tuple[np.ndarray, ...]:
    """One trial of ``kind`` [mm] with 0.5 mm noise: a ball joint's distal segment for a
    centre, a hinge for an axis, both segments about a ball joint for a joint centre."""
    rng = np.random.default_rng(seed)
    if kind == "joint_center":
        arrays = two_segments(n_frames)
    else:
        arrays = (one_segment(n_frames, "hinge" if kind == "axis" else "ball"),)
    return tuple(array + rng.normal(scale=0.5, size=array.shape) for array in arrays)


def _scribbled(arrays: tuple) -> None:
    """Overwrite every frame with the first: the markers no longer move."""
    for array in arrays:
        array[...] = array[:1]


def _same_result(found, expected) -> None:
    """Every field of ``found`` equal to ``expected``'s but the method's name."""
    for field in dataclasses.fields(expected):
        if field.name != "method":
            np.testing.assert_equal(getattr(found, field.name), getattr(expected, field.name))


@pytest.fixture
def scribbling(request):
    """Register, for ``kind``, two fits that answer with the built-in method's unchecked fit,
    one trial and (``own_many``) a batch of their own: one then writes over the arrays it was
    handed, the other does not. Yields their names and removes them after the test."""
    kind, own_many = request.param
    fit_one = registry.get(kind, BUILT_IN[kind], checked=False)
    fit_many = registry.many(kind, BUILT_IN[kind], checked=False)

    def user_fit(scribbles: bool):
        def one(*arrays):
            result = fit_one(*arrays)
            if scribbles:
                _scribbled(arrays)
            return result

        def many(*segments):
            results = fit_many(*segments)
            if scribbles:
                _scribbled(segments)
            return results

        return one, many if own_many else None

    names = {}
    for scribbles in (True, False):
        one, many = user_fit(scribbles)
        names[scribbles] = f"{'scribbles' if scribbles else 'reads'}-{kind.replace('_', '-')}"
        registry.register(kind, names[scribbles], many=many)(one)
    yield kind, names[True], names[False]
    for name in names.values():
        registry.unregister(kind, name)


CASES = [(kind, own_many) for kind in BUILT_IN for own_many in (False, True)]


@pytest.mark.parametrize(
    "scribbling", CASES, ids=[f"{k}-{'own-many' if m else 'one'}" for k, m in CASES], indirect=True
)
def test_a_fit_writing_to_its_input_is_judged_on_the_callers_data(scribbling):
    kind, scribbles, reads = scribbling
    trials = [_noisy_trial(kind, seed) for seed in range(2)]
    stacked = tuple(np.stack(arrays) for arrays in zip(*trials, strict=True))
    expected = registry.get(kind, reads)(*trials[0])
    expected_many = registry.many(kind, reads)(*stacked)
    assert all(result.status == "ok" for result in (expected, *expected_many))

    given = tuple(array.copy() for array in trials[0])
    _same_result(registry.get(kind, scribbles)(*given), expected)
    given_many = tuple(array.copy() for array in stacked)
    found_many = registry.many(kind, scribbles)(*given_many)
    for result, alone in zip(found_many, expected_many, strict=True):
        _same_result(result, alone)
    # The caller's arrays are as they were given.
    for array, original in zip((*given, *given_many), (*trials[0], *stacked), strict=True):
        np.testing.assert_array_equal(array, original)


CASES_ALL = [(kind, method) for kind in BUILT_IN for method in jointbench.methods(kind)]


@pytest.mark.parametrize(("kind", "method"), CASES_ALL, ids=[f"{k}-{m}" for k, m in CASES_ALL])
def test_a_built_in_fit_writes_to_none_of_its_input(kind, method):
    """The package's own fits read their input and never write to it: handed arrays no one can
    write to, checked or not, one trial or a batch, they answer as they do on writable ones."""
    trials = [_noisy_trial(kind, seed) for seed in range(2)]
    stacked = tuple(np.stack(arrays) for arrays in zip(*trials, strict=True))
    for fit, arrays in (
        (registry.get(kind, method, checked=False), trials[0]),
        (registry.get(kind, method), trials[0]),
        (registry.many(kind, method, checked=False), stacked),
        (registry.many(kind, method), stacked),
    ):
        expected = fit(*arrays)
        locked = tuple(array.copy() for array in arrays)
        for array in locked:
            array.flags.writeable = False
        found = fit(*locked)
        for result, alone in zip(
            found if isinstance(found, list) else [found],
            expected if isinstance(expected, list) else [expected],
            strict=True,
        ):
            _same_result(result, alone)


def _users_finish(*stacks, **options):
    """A user's last step of a pose-based fit (what ``twosegment.batched`` closes over)."""
    raise NotImplementedError


class _UsersCallable:
    def __call__(self, *stacks, **options):
        raise NotImplementedError


@dataclasses.dataclass
class _UnhashableCallable(_UsersCallable):  # eq without frozen: no __hash__
    n_trials: int = 1


@dataclasses.dataclass(frozen=True)
class _FrozenHoldingAList(_UsersCallable):  # its class states a hash its list cannot give
    weights: list = dataclasses.field(default_factory=lambda: [1.0])


class _UsersFit:
    def fit(self, markers):
        raise NotImplementedError


@pytest.mark.parametrize(
    "made",
    [
        lambda: twosegment.batched(_users_finish, ("markers",)),
        lambda: twosegment.batched_all(_users_finish, ("proximal", "distal")),
        lambda: twosegment.batched(functools.partial(_users_finish, 1), ("markers",)),
        lambda: twosegment.batched(_UsersCallable(), ("markers",)),
        lambda: _UnhashableCallable(),
        lambda: _FrozenHoldingAList(),
        lambda: _UsersFit().fit,
        lambda: functools.partial(registry.get("center", "LS", checked=False), _users_finish),
    ],
    ids=[
        "batched",
        "batched-all",
        "partial",
        "callable",
        "unhashable",
        "hash-of-a-list",
        "bound-method",
        "partial-passing-users",
    ],
)
def test_a_package_closure_over_a_users_function_is_not_the_package_s_own_code(made):
    """A many-trial form the package builds around a user's function (a closure, no
    ``__wrapped__`` to say so) runs that user's code: it is not the package's own fit, which
    alone shares the checks' sums and is handed the caller's arrays."""
    assert not owncode.package_code(made())


def test_the_package_s_closures_over_its_own_functions_are_its_own_code():
    for kind in BUILT_IN:
        for method in jointbench.methods(kind):
            if registry.has_own_many(kind, method):
                assert owncode.package_code(registry.many(kind, method, checked=False))
            assert owncode.package_code(registry.get(kind, method, checked=False))
    # Nothing of a user's in it: the fit with some of its arguments given.
    assert owncode.package_code(functools.partial(registry.get("center", "LS", checked=False)))


def test_the_package_s_checked_form_of_a_users_fit_is_not_the_package_s_own_code():
    """A checked form closes over its method's entry, not its fit: only the ``__wrapped__``
    it states tells the user's function it runs."""
    registry.register("center", "users-checked")(_users_finish)
    try:
        assert not owncode.package_code(registry.get("center", "users-checked"))
    finally:
        registry.unregister("center", "users-checked")
