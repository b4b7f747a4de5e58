"""Frozen result types returned by every estimator."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "MAX_AXIS_POINT_SD_MM",
    "MAX_AXIS_SD_DEG",
    "MAX_CENTER_SD_MM",
    "MAX_DIRECTION_OFF_DEG",
    "PRECISION_NOT_DETERMINED",
    "REFUSED",
    "AxisResult",
    "CenterResult",
    "JointCenterResult",
    "frozen_rows",
    "method_sd",
    "stated_axis_sd",
    "stated_center_sd",
    "stated_point_sd",
    "stated_sd",
    "states_precision",
    "with_fields",
    "with_warnings",
]


#: The words of every warning that says an answer's stated SD is no statement of its
#: precision, whatever its size (the noise within the eigen-gap it is read from, a pull it
#: leaves out, no marker reading the rotation to first order, markers that keep no distance
#: from any centre, a step from the centre whose scatter it states, a model its data reject,
#: frames that hold far fewer independent ones than it counts): the producers write them and
#: :func:`states_precision` reads them.
PRECISION_NOT_DETERMINED = "precision not determined"

#: An axis whose direction's SD is above this [deg] is "not determined" by the method's cost.
#: Paper B states its accuracy in bands of 5 and 10 degrees (claims B2, B3): an SD above the
#: looser band means the answer cannot be told within it.
MAX_AXIS_SD_DEG = 10.0

#: An axis whose point's SD across the axis, along its least determined direction, is above
#: this [mm] does not place the axis: a line placed for a model (a knee's flexion axis) that
#: far off cannot be told from a failed one, as a centre cannot beyond
#: :data:`MAX_CENTER_SD_MM`. Its direction may still be determined: the warning names the point.
MAX_AXIS_POINT_SD_MM = 10.0

#: No line's direction is further than this [deg] from another's: an SD beyond it states no
#: precision, whatever bound a method's precision is declared not determined above.
MAX_DIRECTION_OFF_DEG = 90.0

#: A centre whose SD along its least determined direction is above this [mm] is "not
#: determined" by the data: paper A's errors on its hardest conditions are of this order, so
#: an answer this uncertain cannot be told from a failed one.
MAX_CENTER_SD_MM = 10.0


#: The diagnostic a checked call sets true where the support verdict did not find that the
#: data support an answer (any of its warnings: too little motion, markers not rigid, a
#: centre not determined along a hinge's axis, markers too nearly collinear for the verdict
#: to test them), false where it found they do; a method's SD then rests on a model the data
#: are not shown to support.
REFUSED = "support_refused"


def states_precision(result) -> bool:
    """Whether the SD the method states of ``result`` can be read as a precision: not where
    the method did not converge (an SD read at an iterate that still moves is no answer's
    precision), nor where a warning in its status says the precision is not determined
    (:data:`PRECISION_NOT_DETERMINED`), nor where the support verdict refused its data
    (:data:`REFUSED`)."""
    return (
        bool(result.converged)
        and PRECISION_NOT_DETERMINED not in result.status
        and not result.diagnostics.get(REFUSED)
    )


def stated_axis_sd(sd_deg: float) -> float | None:
    """``sd_deg``, an axis direction's SD [deg], where it states a precision: at most
    :data:`MAX_AXIS_SD_DEG`, above which the method's cost does not determine the axis
    (:func:`jointbench.estimators.precision.annotate`), and :data:`MAX_DIRECTION_OFF_DEG`;
    ``None`` where it does not (larger, negative, infinite or NaN), so that no output prints it as
    a number."""
    # NaN fails the comparison: it states nothing either; nor does a negative number, no spread.
    return float(sd_deg) if 0.0 <= sd_deg <= min(MAX_AXIS_SD_DEG, MAX_DIRECTION_OFF_DEG) else None


def stated_center_sd(sd_mm: float) -> float | None:
    """``sd_mm``, a centre's SD along its least determined direction [mm], where it states a
    precision: at most :data:`MAX_CENTER_SD_MM`, above which the data do not determine the
    centre; ``None`` where it does not (larger, negative, infinite or NaN), so that no output
    prints it as a number."""
    # NaN fails the comparison: it states nothing either; nor does a negative number, no spread.
    return float(sd_mm) if 0.0 <= sd_mm <= MAX_CENTER_SD_MM else None


def method_sd(result) -> float | None:
    """The SD the method gives of ``result``'s answer, whatever it is worth: an axis
    direction's [deg] (``diagnostics["axis_sd_deg"]``), a centre's or a joint centre's along
    its least determined direction [mm] (``diagnostics["center_sd_mm"]``); ``None`` where the
    method gives none."""
    sd = result.diagnostics.get(_sd_key(result))
    return None if sd is None else float(sd)


def stated_sd(result) -> float | None:
    """The SD of ``result``'s answer that states its precision [deg for an axis, mm for a
    centre or a joint centre] (:func:`method_sd`), or ``None``: where the method gives none,
    where it is above the bound the status declares the answer not determined beyond
    (:func:`stated_axis_sd`, :func:`stated_center_sd`), and where the method did not converge,
    the status says the precision is not determined or the support verdict refused the data
    (:func:`states_precision`). The one rule every output of an SD applies
    (:meth:`jointbench.RecordingFit.stated_sd` prints ``None`` here as "not determined" where
    the method gave an SD)."""
    sd = method_sd(result)
    if sd is None or not states_precision(result):
        return None
    return stated_axis_sd(sd) if isinstance(result, AxisResult) else stated_center_sd(sd)


def stated_point_sd(result) -> float | None:
    """The SD of an axis ``result``'s point across the axis [mm] where it states the point's
    precision: the one the method gives (``diagnostics["axis_point_sd_mm"]``), at most
    :data:`MAX_AXIS_POINT_SD_MM`, above which the status says the point is not determined, and
    only where the answer's SD states a precision at all (:func:`states_precision`: the point's
    is read from the same cost) and the stated noise's share of the curvature it is read from
    is below 1 (``diagnostics["axis_point_noise_share"]``, where given:
    :func:`jointbench.estimators.precision.annotate_point`); ``None`` otherwise, and where the
    method gives none."""
    sd = result.diagnostics.get("axis_point_sd_mm")
    if sd is None or not states_precision(result):
        return None
    if result.diagnostics.get("axis_point_noise_share", 0.0) >= 1.0:
        return None
    # NaN fails the comparison: it states nothing either; nor does a negative number.
    return float(sd) if 0.0 <= sd <= MAX_AXIS_POINT_SD_MM else None


def _sd_key(result) -> str:
    """The diagnostic in which the method states the SD of ``result``'s answer."""
    return "axis_sd_deg" if isinstance(result, AxisResult) else "center_sd_mm"


_FLOAT64 = np.dtype(np.float64)


def _frozen_array(value: np.ndarray | None) -> np.ndarray | None:
    """A read-only float64 copy of ``value``; a read-only view of read-only float64 memory (a
    row of :func:`frozen_rows`) is already that and is kept as it is."""
    if value is None:
        return None
    if (
        type(value) is np.ndarray
        and value.dtype == _FLOAT64  # a dtype, not np.float64: comparing with a type builds one
        and not value.flags.writeable
        and (value.base is None or not value.base.flags.writeable)
    ):
        return value
    array = np.array(value, dtype=float)
    array.setflags(write=False)
    return array


def _frozen_shaped(owner: str, name: str, value: np.ndarray | None, shape: tuple[int, ...]):
    """:func:`_frozen_array` of ``value``, the field ``name`` of a result ``owner`` whose
    documented shape is ``shape``. An answer of another shape is a mistake of the method
    that made it, of which no score or row can be made: a ``TypeError`` (never a trial's
    stated failure) naming both shapes."""
    array = _frozen_array(value)
    if array is not None and array.shape != shape:
        raise TypeError(f"{owner}: {name} of shape {array.shape}, not {shape}")
    return array


def frozen_rows(array: np.ndarray) -> list[np.ndarray]:
    """The rows of a read-only float64 copy of ``array`` ``(n, ...)``: many results' fields
    from one copy instead of one per result."""
    frozen = np.array(array, dtype=float)
    frozen.setflags(write=False)
    return list(frozen)


@dataclass(frozen=True)
class _Result:
    converged: bool
    iterations: int
    status: str
    method: str
    cost: float = float("nan")
    diagnostics: dict = field(default_factory=dict)


@dataclass(frozen=True, kw_only=True)
class CenterResult(_Result):
    """Centre of rotation of one segment's markers in the reference frame.

    ``center`` is ``(3,)`` [mm]; ``radii`` is ``(n_markers,)`` [mm] where the method defines
    them (sphere fits), else ``None``.
    """

    center: np.ndarray
    radii: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "center", _frozen_shaped("CenterResult", "center", self.center, (3,))
        )
        object.__setattr__(self, "radii", _frozen_array(self.radii))


@dataclass(frozen=True, kw_only=True)
class AxisResult(_Result):
    """Axis of rotation: a ``point`` ``(3,)`` [mm] on it and a unit ``direction`` ``(3,)``.

    ``radii`` ``(n_markers,)`` [mm] are the markers' mean distances from the axis.
    """

    point: np.ndarray
    direction: np.ndarray
    radii: np.ndarray | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "point", _frozen_shaped("AxisResult", "point", self.point, (3,)))
        direction = _frozen_shaped("AxisResult", "direction", self.direction, (3,))
        object.__setattr__(self, "direction", direction)
        object.__setattr__(self, "radii", _frozen_array(self.radii))


@dataclass(frozen=True, kw_only=True)
class JointCenterResult(_Result):
    """Joint centre of two segments, in the body-fixed frame shared at frame 0.

    ``center`` is ``(3,)`` [mm]; ``covariance`` ``(3, 3)`` [mm^2] where the method predicts one.
    """

    center: np.ndarray
    covariance: np.ndarray | None = None

    def __post_init__(self) -> None:
        center = _frozen_shaped("JointCenterResult", "center", self.center, (3,))
        object.__setattr__(self, "center", center)
        covariance = _frozen_shaped("JointCenterResult", "covariance", self.covariance, (3, 3))
        object.__setattr__(self, "covariance", covariance)


def with_fields(result, **changes):
    """``result`` (a frozen result dataclass) with ``changes`` to fields that hold no array.

    As ``dataclasses.replace`` gives it, without running the constructor again: that would
    re-validate the arrays ``result`` already holds, read-only, which costs more than many a
    check (the constructor only freezes arrays, so nothing it does is skipped for these
    fields)."""
    if not changes.keys() <= result.__dataclass_fields__.keys():
        unknown = sorted(changes.keys() - result.__dataclass_fields__.keys())
        raise ValueError(f"{type(result).__name__} has no field {unknown[0]!r}")
    return _replaced(result, changes)


def _replaced(result, changes: dict):
    """:func:`with_fields` of ``changes`` that are known to name fields holding no array."""
    copy = object.__new__(type(result))
    copy.__dict__.update(result.__dict__, **changes)
    return copy


def with_warnings(result, warnings: tuple[str, ...], diagnostics: dict):
    """``result`` with ``warnings`` appended to its ``status``, each as ``"warning: ..."`` (in
    place of ``"ok"``, after any other status) and once (two tests of one model that find the
    same fault say it in the same words), and ``diagnostics`` added to its diagnostics;
    ``converged`` is left as the method set it."""
    status = result.status
    if warnings:  # a call that adds numbers only pays nothing for the words' checks
        # Bounded by the separators on both sides: a warning that begins another is not that one.
        said = f"; {status}; warning: "
        fresh = [w for w in dict.fromkeys(warnings) if f"; warning: {w}; warning: " not in said]
        if fresh:
            words = "warning: " + "; warning: ".join(fresh)
            status = words if status == "ok" else f"{status}; {words}"
    # Fields every result has: with_fields's check of the names is not needed.
    merged = {**result.diagnostics, **diagnostics}
    return _replaced(result, {"status": status, "diagnostics": merged})
