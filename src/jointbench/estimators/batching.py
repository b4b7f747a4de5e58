"""Many-trial forms that keep one trial's numerical failure to that trial.

A ``batched`` form fits ``T`` trials with array operations over all of them, so a LAPACK routine
that fails on one trial's values (an eigen-decomposition that does not converge on coordinates
near 1e200, say) fails the call for every trial. :func:`isolated` turns that into the failing
trial's own outcome: the batch is redone one trial at a time, each trial through the same
batched form (whose one-trial batch equals the one-trial function), and a trial that still
fails carries its exception. A batch without a failure pays nothing.

A trial's outcome may also be a ``ValueError`` that is no numerical failure but a mistake in
the method's code (:func:`numerical_failure` tells them apart): a many-trial form returns it
like any other, as the input checks may yet replace it with their own error, and the estimate
jobs stop on it (:func:`mistakes_named`) rather than record a failed trial.
"""

from __future__ import annotations

import contextlib
import dis
import functools
from collections.abc import Callable, Iterator

import numpy as np

__all__ = [
    "NUMERICAL_FAILURES",
    "ProgrammingError",
    "check_poses",
    "check_same_trials",
    "each_alone",
    "failed_trial",
    "isolated",
    "mistakes_named",
    "numerical_failure",
    "one_trial",
]

#: The types of what a fit raises when a trial's values defeat it (``LinAlgError`` is a
#: ``ValueError``); anything else is a bug and propagates, and so is a ``ValueError`` of these
#: that :func:`numerical_failure` does not pass.
NUMERICAL_FAILURES = (ValueError, FloatingPointError)

_RAISE_STATEMENT = dis.opmap["RAISE_VARARGS"]


class ProgrammingError(RuntimeError):
    """A fit stopped by a mistake in its code, not by its trial's data."""


def numerical_failure(error: BaseException) -> bool:
    """Whether ``error`` is a trial's numerical failure: a ``LinAlgError`` or a
    ``FloatingPointError``, or a ``ValueError`` raised by a ``raise`` statement (a method, or
    a library it calls, saying why the data defeat it) or never raised at all (an outcome
    made as such). A ``ValueError`` that the interpreter or NumPy raise inside an expression
    (arrays that do not broadcast, an unpacking of the wrong length, a reshape to the wrong
    size) is a mistake in the code, as a ``TypeError`` is."""
    if isinstance(error, (np.linalg.LinAlgError, FloatingPointError)):
        return True
    if not isinstance(error, ValueError):
        return False
    innermost = _innermost(error)
    if innermost is None:
        return True
    return innermost.tb_frame.f_code.co_code[innermost.tb_lasti] == _RAISE_STATEMENT


def _innermost(error: BaseException):
    """The traceback entry where ``error`` was raised, or ``None`` if it never was."""
    entry = error.__traceback__
    while entry is not None and entry.tb_next is not None:
        entry = entry.tb_next
    return entry


@contextlib.contextmanager
def mistakes_named(label: str) -> Iterator[None]:
    """Prefix ``label`` to a :class:`ProgrammingError` raised inside, and turn a ``ValueError``
    raised inside that is no :func:`numerical_failure` into one."""
    try:
        yield
    except ProgrammingError as error:
        raise ProgrammingError(f"{label}: {error}") from error.__cause__
    except ValueError as error:
        if numerical_failure(error):
            raise
        raise ProgrammingError(f"{label}: {_mistake(error)}") from error


def failed_trial(error: BaseException) -> BaseException:
    """``error``, a trial's outcome, when it is a :func:`numerical_failure`; otherwise a
    :class:`ProgrammingError` that says so, raised from it (not a ``ValueError``, which a
    caller might take for the trial's failure once more)."""
    if isinstance(error, ValueError) and not numerical_failure(error):
        raise ProgrammingError(_mistake(error)) from error
    if not isinstance(error, NUMERICAL_FAILURES):
        raise error
    return error


def _mistake(error: BaseException) -> str:
    """``error`` and where it was raised, as a programming error."""
    innermost = _innermost(error)
    where = ""
    if innermost is not None:
        code = innermost.tb_frame.f_code
        where = f" (at {code.co_filename}:{innermost.tb_lineno}, in {code.co_name})"
    return (
        f"{type(error).__name__}: {error}{where}: a programming error, not a failure of the "
        "trial's data (a method that cannot fit a trial raises a ValueError saying why)"
    )


def one_trial(fit_trials: Callable[..., list], *segments: object, **options: object):
    """The one-trial function of a method written over trials: ``fit_trials`` on a batch of one.

    Each segment is passed as a list holding the caller's object, so the trial's input checks
    see it as given (its dtype, its mask) and name the problem as for one trial. Returns the
    trial's result; a trial that fails raises its ``ValueError``.
    """
    (outcome,) = fit_trials(*([segment] for segment in segments), **options)
    if isinstance(outcome, Exception):
        raise outcome
    return outcome


def each_alone(fit_one: Callable[[int], object], n_trials: int) -> list:
    """``fit_one(trial)`` for every trial, a numerical failure kept as that trial's outcome."""
    outcomes: list = []
    for trial in range(n_trials):
        try:
            outcomes.append(fit_one(trial))
        except NUMERICAL_FAILURES as error:
            outcomes.append(error)
    return outcomes


def check_same_trials(segments: tuple, names: tuple[str, ...]) -> None:
    """``ValueError`` unless the marker arrays ``segments`` (each ``(n_trials, ...)`` or a list
    of trials, named ``names`` in order) hold the same number of trials: a segment's extra
    trials would be left out unsaid, or fail an index. Arrays of no length are left to the
    input checks, which name them."""
    try:
        counts = [len(segment) for segment in segments]
    except TypeError:
        return
    if len(set(counts)) < 2:
        return
    if len(names) != len(segments):
        names = tuple(f"marker array {index + 1}" for index in range(len(segments)))
    others = ", ".join(f"{name} {count}" for name, count in zip(names[1:], counts[1:], strict=True))
    raise ValueError(
        f"{names[0]} holds {counts[0]} trials, {others}: give every segment the same trials"
    )


def isolated(batched: Callable[..., list]) -> Callable[..., list]:
    """``batched(*segments, **options)`` (segments ``(n_trials, ...)``, one outcome per trial)
    that, when the whole call fails numerically, returns per trial the outcome it has alone.

    ``poses=`` (a list with one entry per trial, see
    :func:`jointbench.estimators.segment_poses.trial_poses`) is split with the trials; a list
    of another length, or an entry that is neither the poses of ``batched``'s segments (its
    ``pose_segments``) nor a ``ValueError``, is refused.
    """
    names = getattr(batched, "pose_segments", None)

    @functools.wraps(batched)
    def run(*segments: object, **options: object) -> list:
        if names is not None:
            check_same_trials(segments, names)
        check_poses(segments, options.get("poses"), names)
        try:
            return batched(*segments, **options)
        except NUMERICAL_FAILURES as error:
            try:
                arrays = [np.asarray(segment) for segment in segments]
            except ValueError:
                # Trials of other shapes are no array to split: the call's error stands (the
                # pose fit of many trials names such trials).
                raise error from None
            n_trials = arrays[0].shape[0] if arrays and arrays[0].ndim else 0
            if n_trials == 0:
                raise
            if n_trials == 1:
                return [error]

        poses = options.get("poses")

        def alone(trial: int):
            one = dict(options)
            if poses is not None:
                one["poses"] = poses[trial : trial + 1]
            (outcome,) = batched(*(array[trial : trial + 1] for array in arrays), **one)
            return outcome

        return each_alone(alone, n_trials)

    return run


def check_poses(segments: tuple, poses: list | None, names: tuple[str, ...] | None) -> None:
    """``ValueError`` unless ``poses`` (when given) has one entry per trial of ``segments``,
    each the poses of the segments ``names`` (a dict by name) fitted to that trial's markers,
    or the ``ValueError`` of their fit: a trial fitted with another trial's poses, or with
    poses of its markers before an edit, would answer confidently about other data, and an
    entry of another kind (another method's segments, ``None``) would fail the fit with no
    word of why."""
    if poses is None or not segments:
        return
    n_trials = len(segments[0])
    if len(poses) != n_trials:
        raise ValueError(f"poses: {len(poses)} entries for {n_trials} trials; give one per trial")
    if names is None:
        return
    for trial, entry in enumerate(poses):
        if isinstance(entry, ValueError):
            continue
        if not isinstance(entry, dict):
            held = type(entry).__name__
        elif set(entry) != set(names):
            held = f"the segments {', '.join(map(str, entry))}"
        else:
            continue
        raise ValueError(
            f"poses: trial {trial} holds {held}; give per trial the poses of "
            f"{', '.join(names)} as trial_poses fits them, or the ValueError of their fit"
        )
    for trial, entry in enumerate(poses):
        if isinstance(entry, ValueError):
            continue
        for name, segment in zip(names, segments, strict=True):
            if not _fitted_to_markers(entry[name], segment[trial]):
                markers = name if name == "markers" else f"{name} markers"
                raise ValueError(
                    f"poses: trial {trial}'s {name} poses were not fitted to the trial's "
                    f"{markers} (they are another trial's, or of these markers before an "
                    "edit); give per trial the poses trial_poses fits to the markers of this call"
                )


def _fitted_to_markers(pose: object, markers: object) -> bool:
    """Whether ``pose`` (a segment's poses) holds ``markers`` as the markers it was fitted to,
    to the bit; markers that are no array of numbers are left to the input checks."""
    try:
        given = np.asarray(markers, dtype=float)
    except (TypeError, ValueError):
        return True
    fitted = getattr(pose, "markers", None)
    return isinstance(fitted, np.ndarray) and np.array_equal(fitted, given)
