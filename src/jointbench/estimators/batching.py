"""Many-trial forms that keep one trial's numerical failure to that trial.

A ``batched`` form fits ``T`` trials with array operations over all of them, so a LAPACK routine
that fails on one trial's values (an eigen-decomposition that does not converge on coordinates
near 1e200, say) fails the call for every trial. :func:`isolated` turns that into the failing
trial's own outcome: the batch is redone one trial at a time, each trial through the same
batched form (whose one-trial batch equals the one-trial function), and a trial that still
fails carries its exception. A batch without a failure pays nothing.

A trial's outcome may also be a ``ValueError`` that is no failure the method states but a
mistake in its code (:func:`numerical_failure` is the one rule that tells them apart): a
many-trial form returns it like any other, as the input checks may yet replace it with their
own error. Every place that runs an estimator (the estimate jobs, a recording's fit and its
bootstrap refits, the ``hip_sta`` bootstrap) applies the rule the same way: a stated failure is
the trial's (:func:`failed_trial`), and anything else, returned or raised, stops the caller as a
:class:`ProgrammingError` naming the study or recording, the method and the line
(:func:`mistakes_named`).
"""

from __future__ import annotations

import ast
import contextlib
import dis
import functools
import linecache
from collections.abc import Callable, Iterator

import numpy as np

from jointbench.numerics.compiled import kernel_called
from jointbench.owncode import own_code

__all__ = [
    "NUMERICAL_FAILURES",
    "ProgrammingError",
    "check_one_shape",
    "check_poses",
    "check_same_trials",
    "each_alone",
    "failed_trial",
    "isolated",
    "mistakes_named",
    "numerical_failure",
    "one_trial",
    "trial_shapes",
]

#: The types of what a fit raises when a trial's values defeat it (``LinAlgError`` is a
#: ``ValueError``), which a many-trial form keeps as the trial's outcome; whether one is a failed
#: trial or a mistake in the code is :func:`numerical_failure`'s to say.
NUMERICAL_FAILURES = (ValueError, FloatingPointError)

_RAISE_STATEMENT = dis.opmap["RAISE_VARARGS"]

#: NumPy's checks of a linear-algebra call's dimensions: the ``LinAlgError`` they raise says
#: how the function was called (a matrix that is not square), not what the values did.
_DIMENSION_CHECKS = frozenset({"_assert_2d", "_assert_stacked_2d", "_assert_stacked_square"})

#: What stops a job for the machine's sake, neither the data's nor the code's: raised as it is.
_ENVIRONMENT_ERRORS = (MemoryError, OSError)


class ProgrammingError(RuntimeError):
    """A fit stopped by a mistake in its code, not by its trial's data."""


def numerical_failure(error: BaseException) -> bool:
    """Whether ``error`` is a trial's failure that the method states, the one rule by which a
    fit's exception is a failed trial (the run goes on) rather than a programming error (the job
    stops, :func:`failed_trial`, :func:`mistakes_named`).

    A failure is stated when it is

    * a ``FloatingPointError``, or a ``LinAlgError`` from anywhere (a singular system, an
      eigen-decomposition that does not converge) but NumPy's checks of the dimensions it was
      called with;
    * a ``ValueError`` raised by a ``raise`` statement of the method's own code: the package,
      or any file outside the standard library and the installed third-party packages (a
      user's extension). A ``raise`` in a Numba-compiled function counts as written (Numba
      reports the line); a ``ValueError`` never raised at all is an outcome made as such.

    Any other exception is a mistake in the code: a ``TypeError`` or an ``IndexError``, and a
    ``ValueError`` that the interpreter, C code or a library raises (arrays that do not
    broadcast, an unpacking of the wrong length, ``np.stack`` of other shapes, the domain error
    of ``math.sqrt``, SciPy's ``brentq`` finding no change of sign). A library cannot say
    whether its error is the data's or the caller's: a method whose data can make a library
    call fail catches that error and raises a ``ValueError`` saying why.
    """
    if isinstance(error, np.linalg.LinAlgError):
        innermost = _innermost(error)
        return innermost is None or innermost.tb_frame.f_code.co_name not in _DIMENSION_CHECKS
    if isinstance(error, FloatingPointError):
        return True
    if not isinstance(error, ValueError):
        return False
    innermost = _innermost(error)
    if innermost is None:
        return True
    return own_code(innermost.tb_frame.f_code.co_filename) and _at_raise_statement(innermost)


def _innermost(error: BaseException):
    """The traceback entry where ``error`` was raised, or ``None`` if it never was."""
    entry = error.__traceback__
    while entry is not None and entry.tb_next is not None:
        entry = entry.tb_next
    return entry


def _at_raise_statement(entry) -> bool:
    """Whether the traceback ``entry`` stopped at a ``raise`` statement."""
    if entry.tb_lasti > 0:
        return entry.tb_frame.f_code.co_code[entry.tb_lasti] == _RAISE_STATEMENT
    # A frame that ran no bytecode is compiled code's (Numba gives the line a kernel raised at
    # a frame of its own): the statement is read from the source.
    filename = entry.tb_frame.f_code.co_filename
    return entry.tb_lineno in _raise_lines(filename, "".join(linecache.getlines(filename)))


@functools.lru_cache(maxsize=64)
def _raise_lines(filename: str, source: str) -> frozenset[int]:
    """The lines of ``source`` (the text of ``filename``) where a ``raise`` statement starts."""
    try:
        tree = ast.parse(source, filename)
    except (SyntaxError, ValueError):
        return frozenset()
    return frozenset(node.lineno for node in ast.walk(tree) if isinstance(node, ast.Raise))


@contextlib.contextmanager
def mistakes_named(label: str) -> Iterator[None]:
    """Turn an exception raised inside that is no :func:`numerical_failure` into a
    :class:`ProgrammingError` naming ``label`` (the study and the method, or the recording and
    the method) and where the method went wrong; a :class:`ProgrammingError` raised inside gets
    ``label`` in front. A numerical failure, and an error of the machine (``MemoryError``,
    ``OSError``), are raised as they are. An option that is not what the method declares is
    refused before the method runs (:func:`jointbench.estimators.registry.check_options`), so
    what fails inside is the method's."""
    try:
        yield
    except ProgrammingError as error:
        raise ProgrammingError(f"{label}: {error}") from error.__cause__
    except _ENVIRONMENT_ERRORS:
        raise
    except Exception as error:
        if numerical_failure(error):
            raise
        raise ProgrammingError(f"{label}: {_mistake(error)}") from error


def failed_trial(error: BaseException) -> BaseException:
    """``error``, a trial's outcome, when it is a :func:`numerical_failure`; otherwise a
    :class:`ProgrammingError` that says so, raised from it (not a ``ValueError``, which a
    caller might take for the trial's failure once more)."""
    if numerical_failure(error):
        return error
    raise ProgrammingError(_mistake(error)) from error


def _mistake(error: BaseException) -> str:
    """``error`` as a programming error: where in the method's own code it went wrong (the
    innermost such frame) and, when a library raised it, where; when compiled code of a kernel
    raised it, which kernel (:func:`_inside_kernel`)."""
    entries = []
    entry = error.__traceback__
    while entry is not None:
        entries.append(entry)
        entry = entry.tb_next
    calls = [kernel_called(entry.tb_frame) for entry in entries]
    # A kernel's wrapper is no line of the method: the kernel's call in the method is.
    own = [
        entry
        for entry, call in zip(entries, calls, strict=True)
        if call is None and own_code(entry.tb_frame.f_code.co_filename)
    ]
    where = [_place("at", own[-1])] if own else []
    if entries and (not own or own[-1] is not entries[-1]) and calls[-1] is None:
        where.append(_place("raised in", entries[-1]))
    kernel = _inside_kernel(entries, calls, own)
    if kernel is not None:
        where.append(kernel)
    said = f" ({', '.join(where)})" if where else ""
    return (
        f"{type(error).__name__}: {error}{said}: a programming error, not a failure of the "
        "trial's data. A method that cannot fit a trial raises a ValueError saying why; where "
        "the data can make a library call fail, catch its error and raise a ValueError that "
        "says why"
    )


def _inside_kernel(entries: list, calls: list, own: list) -> str | None:
    """Words for the compiled kernel the error was raised in, whose lines no traceback reaches
    (Numba runs them as machine code): the last kernel called (``calls``, per traceback entry
    of ``entries``) when no line of ``own`` code ran after its call; ``None`` otherwise."""
    called = [index for index, call in enumerate(calls) if call is not None]
    if not called or (own and entries.index(own[-1]) > called[-1]):
        return None
    kernel = calls[called[-1]]
    name = f"{kernel.__module__}.{kernel.__qualname__}"
    code = kernel.__wrapped__.__code__
    return (
        f"inside the Numba-compiled kernel {name} ({code.co_filename}:{code.co_firstlineno}), "
        "whose lines a traceback does not reach: its Python source is its specification, and "
        f"{kernel.__qualname__}.__wrapped__ called with the same arguments raises at the line"
    )


def _place(preposition: str, entry) -> str:
    """``preposition file:line, in function`` of a traceback entry."""
    code = entry.tb_frame.f_code
    return f"{preposition} {code.co_filename}:{entry.tb_lineno}, in {code.co_name}"


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
    names = _segment_names(names, len(segments))
    others = ", ".join(f"{name} {count}" for name, count in zip(names[1:], counts[1:], strict=True))
    raise ValueError(
        f"{names[0]} holds {counts[0]} trials, {others}: give every segment the same trials"
    )


def trial_shapes(segments: tuple) -> list[tuple] | None:
    """Per trial, the shapes of its arrays in ``segments`` (each ``(n_trials, ...)`` or a list
    of trials), where some segment is a list or tuple of trials, whose trials may differ in
    shape; ``None`` where every segment is an array (its trials share one shape), or where
    the segments are no sequences of trials or hold other numbers of them (left to the
    checks that name those). A trial that is no array of one shape has the shape ``None``.
    Reads the trials' shapes, not their samples."""
    if not any(isinstance(segment, list | tuple) for segment in segments):
        return None
    columns = [_shapes_of(segment) for segment in segments]
    if any(column is None for column in columns) or len({len(c) for c in columns}) > 1:
        return None
    return list(zip(*columns, strict=True))


def _shapes_of(segment: object) -> list[tuple[int, ...] | None] | None:
    """The shape of each trial of ``segment`` (:func:`trial_shapes`), or ``None`` where it is
    no array or sequence of trials."""
    if isinstance(segment, np.ndarray):
        return [segment.shape[1:]] * len(segment) if segment.ndim else None
    if not isinstance(segment, list | tuple):
        return None
    shapes: list[tuple[int, ...] | None] = []
    for trial in segment:
        if isinstance(trial, np.ndarray):  # the common case, without np.shape's conversion
            shapes.append(trial.shape)
            continue
        try:
            shapes.append(np.shape(trial))
        except ValueError:  # nested sequences of other lengths: no array at all
            shapes.append(None)
    return shapes


def check_one_shape(names: tuple[str, ...], shapes: dict[int, tuple]) -> None:
    """``ValueError`` naming the first trial of ``shapes`` (per trial, the shapes of its
    segments' arrays in ``names`` order, :func:`trial_shapes`) shaped otherwise than the first,
    with the segment and both shapes: trials fitted as one batch share their numbers of frames
    and markers."""
    if not shapes:
        return
    names = _segment_names(names, len(next(iter(shapes.values()))))
    first, *others = shapes
    for trial in others:
        for name, shape, first_shape in zip(names, shapes[trial], shapes[first], strict=True):
            if shape != first_shape:
                raise ValueError(
                    f"{name} of trial {trial} {_extents(shape, first_shape, first)}: the "
                    "trials of one call share their numbers of frames and markers; fit the "
                    "others in a call of their own (the checked many-trial form fits each "
                    "shape as a batch of its own)"
                )


def _extents(shape: tuple | None, first_shape: tuple | None, first: int) -> str:
    """How a trial's ``shape`` differs from ``first_shape``, trial ``first``'s: in frames and
    markers where both are ``(N, n, 3)``."""
    if all(s is not None and len(s) == 3 and s[2] == 3 for s in (shape, first_shape)):
        return (
            f"has {shape[0]} frames and {shape[1]} markers, of trial {first} "
            f"{first_shape[0]} and {first_shape[1]}"
        )
    return f"is shaped {_shape_text(shape)}, trial {first} {_shape_text(first_shape)}"


def _shape_text(shape: tuple | None) -> str:
    return "as no array" if shape is None else str(shape)


def _segment_names(names: tuple[str, ...], n_segments: int) -> tuple[str, ...]:
    """``names`` of ``n_segments`` segments, or their positions where they are not as many."""
    if len(names) == n_segments:
        return names
    return tuple(f"marker array {index + 1}" for index in range(n_segments))


def isolated(batched: Callable[..., list], *, min_frames: int = 1) -> Callable[..., list]:
    """``batched(*segments, **options)`` (segments ``(n_trials, ...)``, one outcome per trial)
    that, when the whole call fails numerically, returns per trial the outcome it has alone.

    ``poses=`` (a list with one entry per trial, see
    :func:`jointbench.estimators.segment_poses.trial_poses`) is split with the trials; a list
    of another length, or an entry that is neither the poses of ``batched``'s segments (its
    ``pose_segments``) nor a ``ValueError``, is refused.

    Given lists of trials, a form that is not pose-based fits each trial with fewer than
    ``min_frames`` frames (the method's fewest) alone, its error its outcome, and the others
    as one batch (:func:`_short_apart`): a trial too short for the method fails alone, as a
    pose-based form's pose fit refuses it alone, and as the checked form does; trials of other
    shapes that are long enough are refused, as by the pose fit.
    """
    names = getattr(batched, "pose_segments", None)

    @functools.wraps(batched)
    def run(*segments: object, **options: object) -> list:
        if names is not None:
            check_same_trials(segments, names)
        else:
            # A pose-based form names trials of other shapes after their checks
            # (:func:`jointbench.estimators.segment_poses.trial_poses`); the others stack them.
            shapes = trial_shapes(segments)
            if shapes is not None:
                short = {t for t, shape in enumerate(shapes) if _too_short(shape, min_frames)}
                long_enough = {t: shape for t, shape in enumerate(shapes) if t not in short}
                check_one_shape(("markers",), long_enough)
                if short and len(shapes) > 1:
                    return _short_apart(run, segments, options, sorted(short))
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


def _too_short(shape: tuple, min_frames: int) -> bool:
    """Whether a trial of the shapes ``shape`` (:func:`trial_shapes`, one per segment) has
    fewer than ``min_frames`` frames in some segment."""
    return any(s is not None and len(s) > 0 and s[0] < min_frames for s in shape)


def _short_apart(
    run: Callable[..., list], segments: tuple, options: dict, short: list[int]
) -> list:
    """``run(*segments, **options)`` (lists of trials) with the trials ``short`` (increasing)
    each called alone and the others, if any, in one call (``poses=`` split with them):
    outcomes in the trials' order."""
    n_trials = len(segments[0])
    poses = options.get("poses")
    check_poses(segments, poses, None)  # one entry per trial, before they are split

    def called(trials: list[int]) -> list:
        part = dict(options)
        if poses is not None:
            part["poses"] = [poses[t] for t in trials]
        return run(*([segment[t] for t in trials] for segment in segments), **part)

    outcomes: list = [None] * n_trials
    alone = set(short)
    rest = [t for t in range(n_trials) if t not in alone]
    for trials in [*([t] for t in short), *([rest] if rest else [])]:
        for trial, outcome in zip(trials, called(trials), strict=True):
            outcomes[trial] = outcome
    return outcomes


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
    # np.array_equal's own test, without its conversions of arrays that are already arrays:
    # a checked call makes it on every segment of every trial.
    return (
        isinstance(fitted, np.ndarray)
        and fitted.shape == given.shape
        and bool((fitted == given).all())
    )
