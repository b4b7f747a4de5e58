"""Public entry points: fit a centre, an axis or a two-segment joint centre by method name.

Every method is reached through the registry, which holds it to the same rules:

* bad input raises ``ValueError`` naming the problem and where it is: complex, boolean or
  non-numeric arrays, masked arrays with masked values, a wrong shape, NaN/inf or a sample at
  exactly ``(0, 0, 0)`` (marker and frame named), markers that do not move or that only slide
  along straight lines (see :mod:`jointbench.estimators.validation`);
* data that cannot support an answer — markers that are not one rigid body, a rotation not
  resolved above the rigid-body residual, or (for a centre) rotation about a single axis — give
  a result whose ``status`` starts with or carries ``"warning: ..."``, with the numbers in
  ``diagnostics["support_..."]`` (see :mod:`jointbench.estimators.support`). ``converged`` keeps
  the meaning the method's paper gives it. ``status == "ok"`` says that the data support an
  answer (they resolve a rotation) and that the method found its minimum, not that the answer
  is accurate: on a ball joint swung 5 deg with 2 mm noise, LS, MA and SCoRE centres more than
  60 mm from the truth are ``"ok"``. How well the data determine the answer is in the precision
  diagnostics where a method states them (an axis's ``diagnostics["axis_sd_deg"]``, below; a
  covariance where the result has one, e.g. Gauss–Markov's), or in a recording's bootstrap
  (:func:`jointbench.fit`). Those SDs, covariances and the support verdict's p-values count
  each frame's noise as independent: frames that are not (interpolated, filtered, skin markers)
  are said so in ``status`` (``"warning: the frames are not independent: ..."``), with about
  how many independent frames they hold in ``diagnostics["support_independent_frames"]``.
  Where that test does not say so, its lag-1 autocorrelation is read too: unless it is
  clearly below :data:`jointbench.estimators.support.DEPENDENT_CORRELATION`, ``status``
  says, for fewer than :data:`jointbench.estimators.support.MIN_TESTED_FRAMES` frames (too
  few for the test), ``"warning: the frames' independence was not tested: ..."`` with the
  frames in ``diagnostics["frames_independence_untested"]``, and for more (a few dozen leave
  the test little power) ``"warning: the frames' dependence test did not reject their
  independence over N frames, but ..."`` with the frames in
  ``diagnostics["frames_independence_unconfirmed"]``
  (:class:`jointbench.estimators.support.Untested`);
* an array with more markers than frames may be a ``(markers, frames, 3)`` array passed
  transposed: with fewer frames than the method takes
  (:func:`jointbench.estimators.registry.claims`' ``min_frames``) it is refused with a
  ``ValueError`` saying so; otherwise it is fitted and ``status`` carries ``"warning: ... may be
  (markers, frames, 3); it must be (frames, markers, 3)"`` (``diagnostics["maybe_transposed"]``
  the same words). Nothing is transposed for the caller: the shape may be meant;
* an axis whose direction the method's own cost leaves undetermined (the SD of the direction
  that the cost's curvature and residuals imply, ``diagnostics["axis_sd_deg"]``, above
  :data:`jointbench.estimators.precision.MAX_AXIS_SD_DEG`) gets a warning in ``status`` the
  same way (see :mod:`jointbench.estimators.precision`); so does an axis whose point the data
  leave undetermined across the axis (``diagnostics["axis_point_sd_mm"]`` above
  :data:`jointbench.estimators.results.MAX_AXIS_POINT_SD_MM`, with its covariance in
  ``diagnostics["axis_point_covariance_mm2"]``; ``"warning: point not determined: ..."``),
  or, for the combined cost, where under the noise the support verdict states the noise's own
  term in the curvature that covariance is read from is not below what it leaves of it
  (``diagnostics["axis_point_noise_share"]`` not below 1),
  whatever its direction's SD: a short arc can fix an axis's direction and leave where it lies
  open by tens of millimetres;
* a mistake in a method's code (a ``TypeError``, an ``IndexError``, arrays that do not
  broadcast: any error but a failure the method states with a ``ValueError`` of its own, a
  ``LinAlgError`` or a ``FloatingPointError``) raises
  :class:`~jointbench.estimators.batching.ProgrammingError` naming the method and the line, as
  in the estimate jobs (:func:`jointbench.estimators.batching.numerical_failure`).

Before the fit, the arrays are screened for artefacts as a recording is
(:func:`screen`, :func:`jointbench.screening.screen`): a label swap, a marker that falls off
(a cluster of >= 3 markers leaving its rigid shape in some frames) or a jump of a marker outside
a cluster. By default (``artefacts="refuse"``) the fit raises ``ValueError`` naming the markers
(``distal[:, 1]``: array, column) and the frame (row); ``"warn"`` fits, warns, and writes
the same words into the result's ``status`` (``"warning: artefacts in the data: ..."``) and the
artefacts into ``diagnostics["artefacts"]`` (one dict per flagged sample: ``kind``, ``label``,
``frame``, ``size_mm``, ``level_mm``, ``partner``), so a result read or saved without the
Python warning still carries them; ``"ignore"`` skips the screen, for data known to be clean:
nothing is looked for, so nothing is reported. An array of more than
:data:`jointbench.screening.MAX_EXCHANGE_MARKERS` markers is screened without the label-exchange
test; its result's ``status`` then says ``"warning: not verified in markers: ..."`` and
``diagnostics["artefacts_untested"]`` holds the same words (``diagnostics["artefacts"]`` the
samples flagged by the checks that ran).
"""

from __future__ import annotations

import dataclasses
import functools
import warnings

import numpy as np

from jointbench.estimators import registry
from jointbench.estimators.batching import ProgrammingError, mistakes_named
from jointbench.estimators.results import (
    AxisResult,
    CenterResult,
    JointCenterResult,
    with_warnings,
)
from jointbench.estimators.validation import check_input, check_markers
from jointbench.screening import (
    ArtefactRules,
    Numbering,
    Screening,
    _find_artefacts,
    checked_rules,
    column_label,
    exchanges_untested,
    summarise,
)
from jointbench.screening import screen as screen_markers

__all__ = [
    "ARRAY_POLICIES",
    "describe_screening",
    "fit_axis",
    "fit_center",
    "fit_joint_center",
    "methods",
    "screen",
]

#: What the fit functions do with an artefact found by :func:`screen`.
ARRAY_POLICIES = ("refuse", "warn", "ignore")

_NAMES = {"center": ("markers",), "axis": ("markers",), "joint_center": ("proximal", "distal")}


def screen(
    *segments: np.ndarray, names: tuple[str, ...] | None = None, rules: ArtefactRules | None = None
) -> dict[str, Screening]:
    """Artefacts of marker arrays, found as in a recording: per array, label swaps and rigidity
    breaks of a cluster of >= 3 markers, or jumps of fewer markers.

    Parameters
    ----------
    segments : (n_frames, n_markers, 3) arrays [mm], complete (no NaN), e.g. ``markers`` or
        ``proximal, distal``. Each is held to the fits' checks of one array
        (:func:`jointbench.estimators.validation.check_markers`: shape, real numbers, no NaN,
        inf or ``(0, 0, 0)`` sample): a ``ValueError`` names the array and the problem.
    names : a name per array (default ``markers``, or ``proximal``, ``distal`` for two); the
        markers are labelled ``name[:, column]`` and frames are rows.
    rules : thresholds (:class:`jointbench.io.ArtefactRules`), or ``None`` for the default;
        anything else is a ``ValueError``.

    Returns
    -------
    ``{name: Screening}``; a :class:`~jointbench.screening.Screening` lists ``artefacts`` and
    ``swaps``. :func:`describe_screening` words them.
    """
    names = names or (("markers",) if len(segments) == 1 else ("proximal", "distal"))
    if len(names) != len(segments):
        raise ValueError(f"{len(segments)} arrays but {len(names)} names {list(names)}")
    rules = checked_rules(rules)
    # Every array is checked before any is screened, with the fits' own checks of one array.
    checked = [check_markers(array, name=name) for name, array in zip(names, segments, strict=True)]
    found = {}
    for name, markers in zip(names, checked, strict=True):
        labels = _column_labels(name, markers.shape[1])
        found[name] = screen_markers(markers, labels, name, rules)
    return found


@functools.cache
def _column_labels(name: str, n_markers: int) -> tuple[str, ...]:
    """The labels of the ``n_markers`` columns of the array ``name`` in messages:
    ``name[:, column]``."""
    return tuple(column_label(name, column) for column in range(n_markers))


def describe_screening(found: dict[str, Screening]) -> str | None:
    """One message for what :func:`screen` found; ``None`` when it found nothing."""
    artefacts = sorted(
        (a for screening in found.values() for a in screening.artefacts),
        key=lambda a: (a.frame, a.label),
    )
    if not artefacts:
        return None
    swaps = [swap for screening in found.values() for swap in screening.swaps]
    text = summarise(artefacts, swaps, Numbering())
    if swaps:
        first = swaps[0]
        name = first.labels[0].split("[")[0]
        sides = " or ".join(f"{name}[{a}:{b}]" for a, b in first.sides())
        text += f". Fit one side ({sides})"
    return text


def _fit(kind: str, method: str, arrays: tuple[object, ...], artefacts: str, options: dict):
    """Check the inputs of a ``kind`` fit once, screen them as ``artefacts`` says (module
    docstring) and fit them with the checked ``method``."""
    if artefacts not in ARRAY_POLICIES:
        raise ValueError(f"artefacts must be one of {', '.join(ARRAY_POLICIES)}, got {artefacts!r}")
    if artefacts == "ignore":
        fit = registry.get_for_passed(kind, method)  # an unknown method is named first, as ever
        clean = check_input(kind, arrays)
    else:
        # The input checks come first, so bad input gets their message, not the screen's.
        clean = check_input(kind, arrays)
        fit = registry.get_for_passed(kind, method)
    transposed = _maybe_transposed(kind, clean, registry.claims(kind, method).min_frames)
    if artefacts == "ignore":
        result = _called(fit, kind, method, clean, options)
        if not transposed:
            return result
        return with_warnings(result, transposed, {"maybe_transposed": list(transposed)})
    found = _screen_valid(kind, clean, artefacts)
    result = _called(fit, kind, method, clean, options)
    untested = _untested(kind, clean)
    if not found and not untested and not transposed:
        return result
    flagged = [dataclasses.asdict(a) for screening in found.values() for a in screening.artefacts]
    diagnostics: dict = {"artefacts": flagged}
    if untested:
        diagnostics["artefacts_untested"] = list(untested)
    if transposed:
        diagnostics["maybe_transposed"] = list(transposed)
    warned = (_warned(found),) if found else ()
    return with_warnings(result, (*transposed, *warned, *untested), diagnostics)


def _maybe_transposed(kind: str, clean: tuple[np.ndarray, ...], min_frames: int) -> tuple[str, ...]:
    """What the shapes of ``clean``, the checked inputs ``(n_frames, n, 3)`` of a ``kind`` fit,
    suggest: an array with more markers than frames may have been passed as ``(markers, frames,
    3)``. A segment carries a handful of markers over many frames, so the shape is named, not
    changed: a ``ValueError`` when it also has fewer frames than the method takes
    (``min_frames``), where the method would refuse it without the hint; otherwise its words
    (one per such array, ``()`` for none) for the result's ``status``."""
    words = []
    for name, markers in zip(_NAMES[kind], clean, strict=True):
        n_frames, n_markers, _ = markers.shape
        if n_markers <= n_frames:
            continue
        shape = (
            f"{name} has {n_markers} markers over {n_frames} frames: the array may be "
            "(markers, frames, 3); it must be (frames, markers, 3)"
        )
        if n_frames < min_frames:
            raise ValueError(f"{shape}, and this method needs at least {min_frames} frames")
        words.append(shape)
    return tuple(words)


def _called(fit, kind: str, method: str, clean: tuple[np.ndarray, ...], options: dict):
    """``fit``, the checked form of the ``kind`` method ``method``, on ``clean`` with
    ``options``, holding it to the estimate jobs' rule
    (:func:`jointbench.estimators.batching.numerical_failure`): a failure the method states
    reaches the caller as it is, any other error inside it is a ``ProgrammingError`` naming the
    method and the line. An option that is not what the method declares for it is the
    caller's ``ValueError``, refused before the fit
    (:func:`jointbench.estimators.registry.check_options`); one the method does not take, the
    caller's ``TypeError``, its signature consulted only once the call has failed, so a fit
    that succeeds pays nothing for it."""
    if options:  # a call with none, the common one, pays nothing for the check
        registry.check_options(kind, method, options, f"{kind} method {method}")
    try:
        with mistakes_named(f"{kind} method {method}"):
            return fit(clean, **options)
    except ProgrammingError as error:
        unbound = registry.binding_error(kind, method, clean, options)
        if isinstance(error.__cause__, TypeError) and unbound is not None:
            raise TypeError(f"{kind} method {method}: {unbound}") from None
        raise


def _untested(kind: str, clean: tuple[np.ndarray, ...]) -> tuple[str, ...]:
    """What the screen did not test in each of ``clean``, the checked inputs ``(n_frames, n,
    3)`` of a ``kind`` fit, in words (:func:`jointbench.screening.exchanges_untested`)."""
    return tuple(
        f"not verified in {name}: {why}"
        for name, markers in zip(_NAMES[kind], clean, strict=True)
        if (why := exchanges_untested(markers.shape[1]))
    )


def _screen_valid(kind: str, clean: tuple[np.ndarray, ...], artefacts: str) -> dict[str, Screening]:
    """Refuse or warn (``artefacts``) what the screen finds in ``clean``, the checked inputs of
    a ``kind`` fit; returns the screenings that found artefacts (``{}`` when none did). Only
    the artefacts are needed, not the clusters' fits a Screening keeps."""
    found = {}
    for name, markers in zip(_NAMES[kind], clean, strict=True):
        labels = _column_labels(name, markers.shape[1])
        # The input checks refused every coordinate the screen's magnitude check would.
        flagged, swaps = _find_artefacts(markers, labels, name)
        if flagged:  # swaps come only with the artefacts they explain
            found[name] = Screening(flagged, swaps)
    if not found:
        return found
    if artefacts == "refuse":
        raise ValueError(
            f"{describe_screening(found)}. Pass artefacts='warn' or 'ignore' to fit the data "
            "as they are"
        )
    warnings.warn(_warned(found), stacklevel=4)
    return found


def _warned(found: dict[str, Screening]) -> str:
    """The warning, in Python and in a result's ``status``, for the artefacts ``found``."""
    return f"artefacts in the data: {describe_screening(found)}"


def fit_center(
    markers: np.ndarray, method: str = "NM", *, artefacts: str = "refuse", **options: object
) -> CenterResult:
    """Centre of rotation of a segment moving about a fixed point.

    Parameters
    ----------
    markers : (n_frames, n_markers, 3) array [mm]
        The moving segment's markers in the reference segment's frame.
    method : one of ``methods("center")`` (NM, LS, BC, IS, MA, SCoRE, ...).
    artefacts : ``"refuse"``, ``"warn"`` or ``"ignore"`` what :func:`screen` finds.
    """
    return _fit("center", method, (markers,), artefacts, options)


def fit_axis(
    markers: np.ndarray, method: str = "combined", *, artefacts: str = "refuse", **options: object
) -> AxisResult:
    """Dominant axis of rotation of a segment moving about a (nearly) fixed hinge.

    Parameters
    ----------
    markers : (n_frames, n_markers, 3) array [mm]
        The moving segment's markers in the reference segment's frame.
    method : one of ``methods("axis")`` (planar, radial, combined, SARA, ...).
    artefacts : ``"refuse"``, ``"warn"`` or ``"ignore"`` what :func:`screen` finds.
    """
    return _fit("axis", method, (markers,), artefacts, options)


def fit_joint_center(
    proximal: np.ndarray,
    distal: np.ndarray,
    method: str = "gauss-markov",
    *,
    artefacts: str = "refuse",
    **options: object,
) -> JointCenterResult:
    """Ball-joint centre of two segments that both move in the world frame.

    Parameters
    ----------
    proximal, distal : (n_frames, n_markers >= 3, 3) arrays [mm], world frame.
    method : one of ``methods("joint_center")`` (gauss-markov, analytic, SCoRE, ...).
    artefacts : ``"refuse"``, ``"warn"`` or ``"ignore"`` what :func:`screen` finds.
    """
    return _fit("joint_center", method, (proximal, distal), artefacts, options)


def methods(kind: str) -> tuple[str, ...]:
    """Registered estimator names of ``kind`` ("center", "axis" or "joint_center")."""
    return registry.methods(kind)
