"""Registry of estimators by kind and name.

Kinds:

* ``"center"``: ``fn(markers, **options) -> CenterResult``, one segment's markers in the
  reference frame;
* ``"axis"``: ``fn(markers, **options) -> AxisResult``, likewise;
* ``"joint_center"``: ``fn(proximal, distal, **options) -> JointCenterResult``, both segments'
  markers in the world frame.

:func:`get` returns the estimator wrapped in the checks every estimator of its kind is held
to: the input checks of :func:`jointbench.estimators.validation.check_input` and, for a call
with options, the option checks of :func:`check_options` before the fit, and the support
verdict of :func:`jointbench.estimators.support.assess` written into the result after it; a
method with a self-check (:mod:`jointbench.estimators.selfcheck`) or a statement of its
answer's precision (:mod:`jointbench.estimators.precision`; the Gauss–Markov fits test their
model instead, on the poses the call fitted, :mod:`jointbench.estimators.hjc`) has them applied
in between, and every answer is held to what the data say of its kind whatever the method:
an axis compared with the principal axis of the segment's rotations
(:func:`jointbench.estimators.precision.annotate_motion_axis`), a centre's precision and
whether it is the markers' common centre (:mod:`jointbench.estimators.centre_precision`). A
newly registered estimator gets them all without code of its own.
:func:`register` returns the function itself, unwrapped, for direct and internal use.

Every method has a one-trial and a many-trial form, each checked or not (:func:`get`,
:func:`many`). The many-trial form ``many(*segments, **options) -> list`` takes each marker
array with a leading trials axis, ``(n_trials, n_frames, n_markers, 3)`` (every segment the
same trials: a ``ValueError`` names each count otherwise), and returns per trial what the
one-trial function returns, or the numerical failure (``ValueError``, ``FloatingPointError``)
it raises. A pose-based method also takes ``poses=``, one entry per trial of
:func:`jointbench.estimators.segment_poses.trial_poses`. A method's own many-trial form fits
its trials as one batch, so they share their numbers of frames and markers (a ``ValueError``
names a trial that does not), but for a trial too short for the method, whose error is its
own outcome, the others fitted (:func:`jointbench.estimators.batching.isolated`, the pose fit
of :func:`jointbench.estimators.segment_poses.trial_poses`); given lists of trials of other
shapes, the checked form fits the trials of each shape as one batch (:func:`_shape_by_shape`).
A method states its own many-trial form at registration (``register(..., many=...)``, or
:func:`register_many` where the module defines it after the one-trial function); a method
without one, such as a newcomer's per-trial function, gets the one-trial function called trial
by trial.

At registration an estimator states its :class:`Claims`: the fewest frames it fits, how
closely it recovers a noise-free answer and under which transformations of the data its answer
moves with the data. The
conformance suite (``tests/test_conformance.py``) checks the claims of every registered
estimator, so the defaults are the strict ones and a method relaxes them only where its paper
makes it so.
"""

from __future__ import annotations

import contextlib
import copy
import functools
import inspect
import math
import re
from collections.abc import Callable, Mapping
from contextlib import AbstractContextManager
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from jointbench import declared, owncode
from jointbench.estimators import centre_precision, precision, support, validation
from jointbench.estimators.batching import (
    NUMERICAL_FAILURES,
    check_poses,
    check_same_trials,
    each_alone,
    one_trial,
    trial_shapes,
)
from jointbench.estimators.segment_poses import POSE_MIN_FRAMES, _trial_poses, pose_segments
from jointbench.numerics import reuse
from jointbench.registries import Registry

__all__ = [
    "INVARIANCES",
    "KINDS",
    "NAME_PATTERN",
    "Claims",
    "binding_error",
    "check_options",
    "claims",
    "get",
    "has_own_many",
    "many",
    "methods",
    "register",
    "register_many",
    "styles",
    "unregister",
]

KINDS = ("center", "axis", "joint_center")

#: What an estimator's name may be: the config lists it (``estimators``,
#: ``external_estimators``, whose schema patterns are this one) and its estimates go in a folder
#: of that name, so a space, a slash or a leading digit would be a name no run can use.
NAME_PATTERN = re.compile(r"[A-Za-z][A-Za-z0-9_-]*")

#: Transformations of the data an answer may be claimed to follow: a rigid translation or
#: rotation of all markers, and a permutation of the markers or of the frames after the first
#: (several methods anchor the body frame at frame 0).
INVARIANCES = ("translation", "rotation", "marker_order", "frame_order")

_EXACT = 1e-9


def _all_exact() -> Mapping[str, float]:
    return MappingProxyType(dict.fromkeys(INVARIANCES, _EXACT))


@dataclass(frozen=True)
class Claims:
    """What an estimator promises about its answers.

    ``min_frames``: the fewest frames it fits (fewer raise ``ValueError``), so that a study
    whose conditions have fewer frames than all of its estimators take is refused before it
    runs. ``recovery``: the largest error of its answer on noise-free data, with default options
    ([mm] for a centre or the distance of an axis's point from the true axis, [rad] for an
    axis direction); ``None`` where the method's defaults do not recover every noise-free
    case (say why at the registration). ``invariances``: for each transformation in
    :data:`INVARIANCES` that the answer follows (moves with the data, or is unchanged by a
    permutation), the tolerance to which it does on noisy data, in the same units and relative
    to the data's magnitude where rounding sets it; a transformation left out is not claimed.
    """

    recovery: float | None = _EXACT
    invariances: Mapping[str, float] = field(default_factory=_all_exact)
    min_frames: int = 1

    def __post_init__(self) -> None:
        if isinstance(self.min_frames, bool) or not (
            isinstance(self.min_frames, int) and self.min_frames >= 1
        ):
            raise ValueError(f"min_frames must be an integer >= 1, got {self.min_frames!r}")
        unknown = set(self.invariances) - set(INVARIANCES)
        if unknown:
            raise ValueError(
                f"unknown invariance {sorted(unknown)}; choose from {', '.join(INVARIANCES)}"
            )
        object.__setattr__(self, "invariances", MappingProxyType(dict(self.invariances)))


@dataclass
class _Entry:
    """A registered method of ``kind``: its one-trial function ``fn``, its claims, its figure
    style and its own many-trial form (``None`` until stated, or for none); derived from
    those, the function's signature, whether it binds a call's arrays and options (``binds``,
    by their count and names, :func:`_binds`) and its checked forms: for any input and options
    (``checked``), for any input and options its caller checked (``inputs_checked``: each
    trial of :func:`many`, which checks the options once for all trials), and for input and
    options that passed their checks (``valid``, :func:`get_for_valid`), and for the very
    arrays :func:`jointbench.estimators.validation.check_input` returned to the package's own
    caller just now (``passed``, :func:`get_for_passed`)."""

    kind: str
    name: str
    fn: Callable
    claims: Claims
    style: Mapping[str, str]
    many: Callable[..., list] | None = None
    signature: inspect.Signature = field(init=False)
    binds: dict[tuple, bool] = field(init=False, default_factory=dict)
    checked: Callable = field(init=False)
    inputs_checked: Callable = field(init=False)
    valid: Callable = field(init=False)
    passed: Callable = field(init=False)

    def __post_init__(self) -> None:
        self.signature = inspect.signature(self.fn)
        self.valid = functools.partial(_fit_valid, self)
        self.passed = functools.partial(_fit_passed, self)

        @functools.wraps(self.fn)
        def checked(*arrays: object, **options: object):
            clean = validation.check_input(self.kind, arrays)
            if options:  # a call without options, the common one, pays nothing for the check
                _check_entry_options(self, options)
            return _fit_passed(self, clean, **options)

        @functools.wraps(self.fn)
        def inputs_checked(*arrays: object, **options: object):
            return _fit_passed(self, validation.check_input(self.kind, arrays), **options)

        self.checked = checked
        self.inputs_checked = inputs_checked


_REGISTRY: dict[str, Registry[_Entry]] = {
    kind: Registry(f"{kind} method", lambda entry: entry.name) for kind in KINDS
}


def _check_kind(kind: str) -> None:
    if kind not in _REGISTRY:
        raise ValueError(f"unknown estimator kind {kind!r}; choose one of {', '.join(KINDS)}")


def _fit_valid(entry: _Entry, clean: tuple[np.ndarray, ...], **options: object):
    """``entry``'s method on ``clean``, arrays that passed the input checks, then its
    self-check, the precision its cost implies and the support verdict. A pose-based method
    of two segments has the segments'
    poses fitted once, for its fit (its many-trial form on a batch of one, which is what its
    one-trial function is) and for the verdict. The stages after the fit share the sums over
    the frames that more than one of them reads (:mod:`jointbench.numerics.reuse`), and with the
    package's own fit (:func:`jointbench.owncode.package_code`), which writes to none of the
    arrays it reads, those it formed. Any other fit may be a user's code that writes to the
    arrays it is handed (normalises them in place, refills them as a buffer): it fits copies
    of its own, outside that scope, and the checks judge the data as the caller gave them.
    The package's fit still makes its own input checks: nothing shows that these arrays, as
    they are now, are the ones that passed (:func:`_fit_passed`)."""
    return _stages(entry, clean, options, passed=False)


def _fit_passed(entry: _Entry, clean: tuple[np.ndarray, ...], **options: object):
    """:func:`_fit_valid` of ``clean``, the very arrays
    :func:`jointbench.estimators.validation.check_input` returned just now, untouched since:
    the package's own fit does not repeat their checks
    (:func:`jointbench.estimators.validation.passed`)."""
    return _stages(entry, clean, options, passed=True)


def _stages(entry: _Entry, clean: tuple[np.ndarray, ...], options: dict, *, passed: bool):
    """The stages of :func:`_fit_valid`; ``passed``: ``clean`` are the arrays the input checks
    returned just now (:func:`_fit_passed`)."""
    names = _pose_names(entry, len(clean))
    shared = None
    if names is not None and _binds(entry, clean, options):
        # The arrays passed the input checks just now: their samples are not scanned again.
        shared = _shared_poses(names, tuple([array] for array in clean), samples_checked=True)
    if owncode.package_code(entry.fn):
        # The package's own fits write to none of the arrays they read: the stages after the
        # fit read the sums it formed (paper B's S) instead of forming them again.
        # Nor do they check again the arrays the input checks passed just now.
        with reuse.one_call():
            if passed:
                validation.passed(entry.kind, clean)
            result = _fit(entry, clean, shared, options)
            return _checked_stages(entry, result, clean, shared, options)
    result = _fit(entry, copy.deepcopy(clean), shared, options)
    with reuse.one_call():
        return _checked_stages(entry, result, clean, shared, options)


def _fit(entry: _Entry, clean: tuple[np.ndarray, ...], shared: object, options: dict):
    """``entry``'s fit of the trial ``clean``: its one-trial function, or its many-trial form on
    a batch of one given the segments' poses ``shared`` (``None``: not fitted for it)."""
    if shared is None:
        return entry.fn(*clean, **options)
    return one_trial(entry.many, *clean, poses=shared, **options)


def _checked_stages(
    entry: _Entry, result: object, clean: tuple[np.ndarray, ...], shared: object, options: dict
):
    """The stages of :func:`_stages` after the fit ``result`` of the trial ``clean`` (poses
    ``shared`` and ``options`` as for :func:`_fit`), inside the scope of one call."""
    stacked = tuple(array[None] for array in clean)  # the trial as a batch of one
    # Its arrays passed the input checks: the verdict's own check of them is not repeated.
    (verdict,) = support.assess_many(entry.kind, stacked, poses=shared)
    result = _self_checked(entry.fn, result, clean, options)
    if hasattr(entry.fn, "precision_many"):
        poses = _fitted_to(shared, [0])
        (result,) = _precision_checked(entry.fn, [result], stacked, poses, [verdict])
    (result,) = _answers_checked(entry.kind, [result], stacked, [verdict])
    return support.annotate(result, verdict)


def _pose_names(entry: _Entry, n_segments: int) -> tuple[str, ...] | None:
    """The segments whose poses ``entry``'s fit and the support verdict can share: those of
    its pose-based many-trial form, when the verdict reads poses (two segments); else None."""
    if n_segments < 2 or entry.many is None:
        return None
    return pose_segments(entry.many)


def _binds(entry: _Entry, arrays: tuple, options: dict) -> bool:
    """Whether ``entry``'s one-trial function takes ``arrays`` and ``options``: where it does
    not, calling it raises the ``TypeError`` a caller should see. Remembered per method: a
    signature binds by the arrays' count and the options' names alone, and binding it costs a
    checked one-trial call several microseconds."""
    asked = (len(arrays), tuple(options))
    binds = entry.binds.get(asked)
    if binds is None:
        unbound = _binding_error(entry, (None,) * len(arrays), dict.fromkeys(options))
        binds = entry.binds[asked] = unbound is None
    return binds


def _binding_error(entry: _Entry, arrays: tuple, options: dict) -> TypeError | None:
    """The ``TypeError`` of calling ``entry``'s one-trial function with ``arrays`` and
    ``options`` that its signature alone gives, or ``None`` where it takes them."""
    try:
        entry.signature.bind(*arrays, **options)
    except TypeError as error:
        return error
    return None


def binding_error(kind: str, name: str, arrays: tuple, options: dict) -> TypeError | None:
    """:func:`_binding_error` of the estimator ``name`` of ``kind``: what its signature says
    of a call with ``arrays`` and ``options`` (``None``: it takes them)."""
    return _binding_error(_entry(kind, name), arrays, options)


def check_options(kind: str, name: str, options: Mapping[str, object], label: str) -> None:
    """Refuse, before the fit, the first of ``options`` that is not what the estimator ``name``
    of ``kind`` declares for it (its parameter's annotation, :mod:`jointbench.declared`): a
    ``ValueError`` with ``label`` in front naming the option, the value, what is declared and
    the method, as the config check refuses it before a run. An option the method does not
    declare (no annotation, one it does not take, ``**options``, annotations that cannot be
    read) is left to the method. The checked forms of :func:`get` and :func:`many` call it,
    labelled ``"{kind} method {name}"``, as the public fit functions do."""
    _check_declared(_entry(kind, name).fn, kind, name, options, label)


def _check_entry_options(entry: _Entry, options: Mapping[str, object]) -> None:
    """:func:`check_options` of a call of ``entry``'s checked forms, labelled as a public fit
    call labels it (:func:`jointbench.api.fit_center`)."""
    _check_declared(entry.fn, entry.kind, entry.name, options, f"{entry.kind} method {entry.name}")


def _check_declared(
    fn: Callable, kind: str, name: str, options: Mapping[str, object], label: str
) -> None:
    """:func:`check_options` of ``fn``, the one-trial function of the method ``name``."""
    n_arrays = len(validation.ARRAY_NAMES[kind])
    for option, value in options.items():
        # Whether a number, text or flag fits is remembered by its type and value (1, 1.0 and
        # True are equal but not alike); a list or an array is checked each time.
        if type(value) in _SCALARS and _scalar_fits(fn, n_arrays, option, type(value), value):
            continue
        refused = _refusal(fn, n_arrays, option, value)
        if refused is not None:
            raise ValueError(f"{label}: option {refused} (as {name} declares it)")


#: Types of the option values whose outcome :func:`check_options` remembers.
_SCALARS = frozenset({int, float, bool, str, type(None)})


def _refusal(fn: Callable, n_arrays: int, option: str, value: object) -> str | None:
    """Why ``value`` is not what ``fn`` declares for ``option`` (:func:`_declared_options`);
    ``None`` when it is, or nothing is declared."""
    annotation = _declared_options(fn, n_arrays).get(option, inspect.Parameter.empty)
    if annotation is inspect.Parameter.empty:
        return None
    try:
        declared.check(value, annotation, (option,))
    except declared.DeclarationError as error:
        return str(error)
    return None


@functools.lru_cache(maxsize=1024)
def _scalar_fits(fn: Callable, n_arrays: int, option: str, _type: type, value: object) -> bool:
    """Whether :func:`_refusal` finds nothing against ``value``, a scalar of type ``_type``,
    remembered: right after a fit the check's many small calls run cold (several microseconds),
    and a call with options should cost next to nothing."""
    return _refusal(fn, n_arrays, option, value) is None


@functools.cache
def _declared_options(fn: Callable, n_arrays: int) -> Mapping[str, object]:
    """The annotation of each keyword option of ``fn`` that has one, after its ``n_arrays``
    marker arrays; none for a function taking ``**options`` or whose annotations cannot be read
    (the config check names those). Read once per registered function: a call with options
    then pays a look-up, not ``inspect.signature`` and ``typing.get_type_hints``."""
    try:
        accepted = declared.keyword_types(fn, n_arrays)
    except NameError:
        return MappingProxyType({})
    return MappingProxyType(
        {
            option: annotation
            for option, annotation in (accepted or {}).items()
            if annotation is not inspect.Parameter.empty
        }
    )


def _shared_poses(
    names: tuple[str, ...], segments: tuple, *, samples_checked: bool = False
) -> list | None:
    """Per trial of ``segments`` (in ``names`` order, each ``(T, N, n, 3)`` or a list of
    trials), its poses as every pose-based method fits them, or its ``ValueError``; ``None``
    when they cannot be fitted as one batch (another number of arrays, trials of other
    shapes). ``samples_checked``: as
    :func:`~jointbench.estimators.segment_poses._trial_poses` takes it."""
    try:
        segments_by_name = dict(zip(names, segments, strict=True))
        return _trial_poses(
            segments_by_name, min_frames=POSE_MIN_FRAMES, samples_checked=samples_checked
        )
    except NUMERICAL_FAILURES:
        # The many-trial form fits them inside :func:`batching.isolated`, which answers for
        # such a failure in its own way (each trial alone, or the call's error): sharing
        # nothing leaves that answer to it, as when it fits alone.
        return None


def _fitted_to(poses: list | None, trials: list[int]) -> list | None:
    """``poses`` of the ``trials`` the fit answered, for the verdict (the fit's input checks,
    :func:`jointbench.estimators.batching.check_poses`, refused poses of other markers); else
    ``None``, and the verdict fits its own."""
    if poses is None:
        return None
    chosen = [poses[trial] for trial in trials]
    return chosen if all(isinstance(trial_poses_, dict) for trial_poses_ in chosen) else None


def _self_checked(fn: Callable, result, arrays: tuple, options: dict):
    """``result`` after ``fn``'s self-check (:mod:`jointbench.estimators.selfcheck`), if
    it has one (options the fit took are passed on; ``poses`` are the fit's own business)."""
    check = getattr(fn, "self_check", None)
    if check is None:
        return result
    return check(result, *arrays, **{k: v for k, v in options.items() if k != "poses"})


def _self_checked_many(fn: Callable, results: list, stacked: tuple, options: dict) -> list:
    """:func:`_self_checked` of many trials' ``results`` on their arrays ``stacked``
    ``(T, N, n, 3)`` each: all trials in one call where the method has ``self_check_many``."""
    check_many = getattr(fn, "self_check_many", None)
    if check_many is None:
        if not hasattr(fn, "self_check"):
            return results  # no self-check: not even each trial's arrays are needed
        return [
            _self_checked(fn, result, tuple(array[t] for array in stacked), options)
            for t, result in enumerate(results)
        ]
    return check_many(results, *stacked, **{k: v for k, v in options.items() if k != "poses"})


def _precision_checked(
    fn: Callable, results: list, stacked: tuple, poses: list | None, verdicts: list
) -> list:
    """``results`` of the trials of ``stacked`` ``(T, N, n, 3)`` each with the precision of
    their answers that ``fn``'s own cost implies, where it states one
    (``fn.precision_many``, :mod:`jointbench.estimators.precision`), or the test of its model
    (the Gauss–Markov fits, :mod:`jointbench.estimators.hjc`), given the trials' support
    ``verdicts``, whose rigid-body noise a cost's residuals are held to. A check that reads
    poses (:func:`jointbench.estimators.segment_poses.pose_segments`) is given ``poses``,
    those the fit read (per trial, or ``None`` where the call shared none)."""
    check = getattr(fn, "precision_many", None)
    if check is None:
        return results
    if pose_segments(check) is None:
        return check(results, *stacked, verdicts=verdicts)
    return check(results, *stacked, verdicts=verdicts, poses=poses)


def _answers_checked(kind: str, results: list, stacked: tuple, verdicts: list) -> list:
    """``results`` of the trials of ``stacked`` ``(T, ...)`` held to what the data say of their
    kind, whatever the method, given their support ``verdicts``: an axis compared with the
    principal axis of the segment's rotations that its verdict took from the data
    (:func:`jointbench.estimators.precision.annotate_motion_axis`), a centre's precision and
    whether it is the markers' common centre
    (:func:`jointbench.estimators.centre_precision.annotate_many`), and how far the noise in
    a joint centre's poses pulls it
    (:func:`jointbench.estimators.centre_precision.annotate_joint_centres`)."""
    if kind == "axis":
        return [
            precision.annotate_motion_axis(
                result,
                verdict.motion_axis,
                verdict.diagnostics.get("reason", ""),
                verdict.diagnostics.get("off_axis_p_value", math.nan),
            )
            for result, verdict in zip(results, verdicts, strict=True)
        ]
    if kind == "center":
        return centre_precision.annotate_many(results, stacked[0], verdicts)
    if kind == "joint_center":
        return centre_precision.annotate_joint_centres(results, verdicts)
    return results


def _checked_many(entry: _Entry) -> Callable[..., list]:
    """``entry``'s many-trial form (``many(*segments, **options)`` over ``(n_trials, ...)``
    arrays, returning per trial a result or the exception) with the checks of its checked
    one-trial form per trial: the input checks of all trials in one pass
    (:func:`jointbench.estimators.validation.check_input_many`) and the support verdict of all
    trials in one call, reading the poses the fit read where it is pose-based. Its options
    are checked before the fit, once for all trials (:func:`check_options`). As for one trial,
    the stages share the sums over the frames that more than one of them reads
    (:mod:`jointbench.numerics.reuse`)."""

    @functools.wraps(entry.many)
    def checked_many(*segments: object, **options: object) -> list:
        if options:  # a call without options, the common one, pays nothing for the check
            _check_entry_options(entry, options)
        return _many_stages(entry, segments, options)

    return checked_many


def _many_stages(entry: _Entry, segments: tuple, options: dict) -> list:
    """The stages of :func:`_checked_many`'s call of ``entry`` on ``segments``, after the
    check of its ``options``; trials of other shapes :func:`_shape_by_shape`."""
    shapes = trial_shapes(segments)
    if shapes is not None and len(set(shapes)) > 1:
        return _shape_by_shape(entry, segments, options)
    names = _pose_names(entry, len(segments))
    shared = None
    if names is not None and options.get("poses") is None:
        shared = _shared_poses(names, segments)
    if shared is not None:
        options["poses"] = shared
    if owncode.package_code(entry.many):
        # As for one trial (:func:`_stages`): the package's own fit shares its sums.
        with reuse.one_call():
            return _fitted_many(entry, segments, segments, options, names, contextlib.nullcontext())
    # As for one trial (:func:`_fit_valid`): copies of its own, the checks after it.
    handed = copy.deepcopy(segments)
    return _fitted_many(entry, segments, handed, options, names, reuse.one_call())


def _fitted_many(
    entry: _Entry,
    segments: tuple,
    handed: tuple,
    options: dict,
    names: tuple[str, ...] | None,
    scope: AbstractContextManager,
) -> list:
    """The stages of :func:`_many_stages` from the fit of ``entry``'s many-trial form on
    ``handed`` (``segments`` or copies of them; ``options`` with the poses it shares, of the
    segments ``names``), the checks of ``segments`` after it in ``scope``."""
    outcomes = list(entry.many(*handed, **options))
    checked = validation.check_input_many(entry.kind, segments, len(outcomes))
    fitted = []
    for trial, (outcome, error) in enumerate(zip(outcomes, checked.errors, strict=True)):
        # As for one trial: the input checks come first and their error wins.
        if error is not None:
            outcomes[trial] = error
        elif not isinstance(outcome, Exception):
            fitted.append(trial)
    if fitted:
        with scope:
            _judge_fitted(entry, outcomes, fitted, checked.stacked(fitted), options, names)
    return outcomes


def _shape_by_shape(entry: _Entry, segments: tuple, options: dict) -> list:
    """:func:`_many_stages` of trials of other numbers of frames or markers (lists of trials):
    each trial's input checks, whose error is its outcome, then the trials that passed, those
    of one shape as one regular batch of :func:`_many_stages` (``poses=`` split with them), so
    a method's many-trial form fits each shape at once; outcomes in the trials' order."""
    check_same_trials(segments, validation.ARRAY_NAMES[entry.kind])
    n_trials = len(segments[0])
    poses = options.get("poses")
    check_poses(segments, poses, None)  # one entry per trial, before they are split
    checked = validation.check_input_many(entry.kind, segments, n_trials)
    groups: dict[tuple, list[int]] = {}
    for trial, error in enumerate(checked.errors):
        if error is None:
            shapes = tuple(array.shape for array in checked.arrays(trial))
            groups.setdefault(shapes, []).append(trial)
    outcomes: list = list(checked.errors)
    for group in groups.values():
        alike = dict(options)
        if poses is not None:
            alike["poses"] = [poses[trial] for trial in group]
        fitted = _many_stages(entry, checked.stacked(group), alike)
        for trial, outcome in zip(group, fitted, strict=True):
            outcomes[trial] = outcome
    return outcomes


def _judge_fitted(
    entry: _Entry,
    outcomes: list,
    fitted: list[int],
    stacked: tuple,
    options: dict,
    names: tuple[str, ...] | None,
) -> None:
    """The checks of :func:`_many_stages` after the fit, on the trials ``fitted`` (their
    arrays ``stacked``), each outcome replaced in ``outcomes`` by its checked result."""
    results = _self_checked_many(entry.fn, [outcomes[t] for t in fitted], stacked, options)
    poses = _fitted_to(options.get("poses"), fitted) if names else None
    verdicts = support.assess_many(entry.kind, stacked, poses=poses)
    results = _precision_checked(entry.fn, results, stacked, poses, verdicts)
    results = _answers_checked(entry.kind, results, stacked, verdicts)
    for trial, result, verdict in zip(fitted, results, verdicts, strict=True):
        outcomes[trial] = support.annotate(result, verdict)


def register(
    kind: str,
    name: str,
    *,
    recovery: float | None = _EXACT,
    invariances: float | Mapping[str, float] = _EXACT,
    min_frames: int = 1,
    many: Callable[..., list] | None = None,
    color: str | None = None,
    marker: str | None = None,
) -> Callable[[Callable], Callable]:
    """Decorator registering ``fn`` as estimator ``name`` of ``kind`` with its :class:`Claims`
    and, if it has one, its many-trial form ``many`` (module docstring).

    ``invariances`` as a number claims every transformation of :data:`INVARIANCES` to that
    tolerance; the default claims them all at rounding level (1e-9). ``color`` and ``marker``
    (matplotlib's) draw the method in every figure; a method without a colour gets one no
    registered method has (:func:`jointbench.figures.common.method_style`).
    """
    _check_kind(kind)
    if not isinstance(invariances, Mapping):
        invariances = dict.fromkeys(INVARIANCES, float(invariances))
    stated = Claims(recovery, invariances, min_frames)
    style = MappingProxyType(
        {k: v for k, v in (("color", color), ("marker", marker)) if v is not None}
    )

    if not (isinstance(name, str) and NAME_PATTERN.fullmatch(name)):
        raise ValueError(
            f"{kind} estimator name {name!r}: a name starts with a letter and holds only "
            "letters, digits, '_' and '-', as the config's estimator lists take it"
        )

    def decorate(fn: Callable) -> Callable:
        if name in _REGISTRY[kind].names():
            raise ValueError(f"{kind} estimator {name!r} is already registered")
        _REGISTRY[kind].register(_Entry(kind, name, fn, stated, style, many))
        owncode.claim(fn)
        if many is not None:
            owncode.claim(many)
        return fn

    return decorate


def register_many(kind: str, name: str, many: Callable[..., list]) -> Callable[..., list]:
    """State the many-trial form ``many`` of the registered estimator ``name`` of ``kind``
    (module docstring), for a module that defines it after registering the one-trial
    function; a method has one many-trial form. Returns ``many``."""
    entry = _entry(kind, name)
    if entry.many is not None:
        raise ValueError(f"{kind} estimator {name!r} already has a many-trial form")
    entry.many = many
    owncode.claim(many)
    return many


def unregister(kind: str, name: str) -> None:
    """Remove the estimator ``name`` of ``kind`` (a test's or a session's own estimator)."""
    _entry(kind, name)
    _REGISTRY[kind].remove(name)


def _entry(kind: str, name: str) -> _Entry:
    _check_kind(kind)
    return _REGISTRY[kind].get(name)


def get(kind: str, name: str, *, checked: bool = True) -> Callable:
    """The one-trial estimator ``name`` of ``kind`` with its checks; ``ValueError`` listing the
    known names otherwise.

    The checked form refuses, before the fit, an option that is not what the method declares
    for it (:func:`check_options`, labelled ``"{kind} method {name}"``). ``checked=False``
    gives the registered function itself: for the simulated studies, whose data are valid by
    construction, whose options passed the config check and whose timings must be the
    estimator's alone.
    """
    entry = _entry(kind, name)
    return entry.checked if checked else entry.fn


def get_for_valid(kind: str, name: str) -> Callable:
    """The checked estimator ``name`` of ``kind`` (:func:`get`) taking one tuple of arrays that
    already passed :func:`jointbench.estimators.validation.check_input`, and options that
    passed :func:`check_options`, whose checks it does not repeat: for a caller that ran them
    itself, with its own label. The package's own fit still checks the arrays it reads, as
    nothing shows they are, as they are now, the ones that passed (an array checked once and
    refilled as a buffer is refused by it, not fitted)."""
    return _entry(kind, name).valid


def get_for_passed(kind: str, name: str) -> Callable:
    """:func:`get_for_valid`, for a caller of the package's own that hands it the very arrays
    :func:`jointbench.estimators.validation.check_input` returned, untouched since: the
    package's own fit does not repeat their checks either
    (:func:`jointbench.estimators.validation.passed`)."""
    return _entry(kind, name).passed


def many(kind: str, name: str, *, checked: bool = True) -> Callable[..., list]:
    """The many-trial form of estimator ``name`` of ``kind`` (module docstring), with the checks
    of :func:`get` per trial (its options checked once, before any trial is fitted) or,
    ``checked=False``, without; every method has one."""
    entry = _entry(kind, name)
    if entry.many is not None:
        return _checked_many(entry) if checked else entry.many
    each = _trial_by_trial(
        entry.inputs_checked if checked else entry.fn, validation.ARRAY_NAMES[entry.kind]
    )
    return _options_checked(entry, each) if checked else each


def _options_checked(entry: _Entry, each: Callable[..., list]) -> Callable[..., list]:
    """``each``, a many-trial form of ``entry`` fitting trial by trial, refusing options that
    are not what ``entry`` declares before any trial (not as every trial's failure)."""

    @functools.wraps(each)
    def checked(*segments: object, **options: object) -> list:
        if options:  # a call without options, the common one, pays nothing for the check
            _check_entry_options(entry, options)
        return each(*segments, **options)

    return checked


def has_own_many(kind: str, name: str) -> bool:
    """Whether estimator ``name`` of ``kind`` stated a many-trial form of its own."""
    return _entry(kind, name).many is not None


def _trial_by_trial(fn: Callable, names: tuple[str, ...]) -> Callable[..., list]:
    """The many-trial form of a method without its own: ``fn`` on each trial of the segments
    ``names``, a numerical failure kept as that trial's outcome."""

    @functools.wraps(fn)
    def each(*segments: object, **options: object) -> list:
        check_same_trials(segments, names)
        # A list's trials reach ``fn`` as given: they may differ in shape, fitted one by one.
        arrays = [
            segment if isinstance(segment, list | tuple) else np.asarray(segment)
            for segment in segments
        ]
        return each_alone(lambda t: fn(*(array[t] for array in arrays), **options), len(arrays[0]))

    # The checked form applies them, once.
    each.__dict__.pop("self_check", None)
    each.__dict__.pop("precision_many", None)
    return each


def claims(kind: str, name: str) -> Claims:
    """The :class:`Claims` estimator ``name`` of ``kind`` registered with."""
    return _entry(kind, name).claims


def styles() -> dict[str, Mapping[str, str]]:
    """The ``color`` and ``marker`` each estimator registered with, by name, for those that
    registered either (a name registered under several kinds: its first registration's)."""
    found: dict[str, Mapping[str, str]] = {}
    for entries in _REGISTRY.values():
        for entry in entries.values():
            if entry.style and entry.name not in found:
                found[entry.name] = entry.style
    return found


def methods(kind: str) -> tuple[str, ...]:
    """Names of the registered estimators of ``kind``, in registration order."""
    _check_kind(kind)
    return _REGISTRY[kind].names()
