"""Synthetic marker data with known ground truth.

Every study's simulator has the signature::

    simulate(condition: Mapping[str, object], protocol: <Study>Protocol,
             rngs: Sequence[numpy.random.Generator]) -> Trials

``condition`` holds one cell of the study's grid (e.g. ``{"marker_set": "M", "rom_deg": 5,
"noise_mm": 1.0}``), ``protocol`` the study's documented, configurable modelling choices, and
``rngs`` one generator per trial (seeded from study, condition and trial). The nominal motion is
a deterministic function of ``condition`` and ``protocol``; the generators draw what varies
between trials.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from jointbench.declared import below, check_fields
from jointbench.simulate.noise import isotropic_noise

__all__ = [
    "KINDS",
    "PROXIMAL_TRUTH",
    "RADII_TRUTH",
    "Diagnostic",
    "GridValues",
    "Study",
    "Trials",
    "isotropic_noise",
    "key_label",
    "value_text",
]

#: Estimator kinds a study can run: each kind's estimators share a signature and a scorer.
KINDS = ("center", "axis", "joint_center")
# What each kind's errors are measured from: kinds sharing one can share a study.
_TRUTH_OF = {"center": "center", "axis": "axis", "joint_center": "center"}
#: The ``truth`` key of a two-segment study's noise-free proximal markers at frame 0
#: ``(n_markers, 3)`` [mm], in the frame of ``truth["center"]``.
PROXIMAL_TRUTH = "proximal_frame0"
#: The ``truth`` key of a one-segment study's true marker radii ``(n_markers,)`` [mm]: each
#: marker's distance from the centre of rotation, which a sphere fit's radii estimate.
RADII_TRUTH = "radii"


@dataclass(frozen=True)
class Trials:
    """Simulated trials of one condition.

    ``segments`` maps a segment name to its markers ``(n_trials, n_frames, n_markers, 3)`` [mm]:
    ``"moving"`` for one-segment studies (markers in the reference segment's frame), or
    ``"proximal"`` and ``"distal"`` (world frame) for two-segment studies. ``truth`` holds the
    JSON-serialisable ground truth shared by all trials (``"center"``, and optionally
    :data:`PROXIMAL_TRUTH` or :data:`RADII_TRUTH`; or ``"axis_point"`` and
    ``"axis_direction"``), ``None`` when read from a blind dataset file, which an estimator
    outside the package is given; ``parameters`` the generator settings for provenance.
    """

    segments: dict[str, np.ndarray]
    truth: dict[str, list[float]] | None
    parameters: dict[str, object] = field(default_factory=dict)

    @property
    def n_trials(self) -> int:
        return next(iter(self.segments.values())).shape[0]


@dataclass(frozen=True)
class GridValues:
    """The values one grid key allows: numbers of ``type`` (``int`` or ``float``) within bounds,
    or text among ``choices``.

    ``maximum`` and ``choices`` may be functions of the study's protocol, for limits the
    protocol defines (its marker sets, its joints, its recording length), so that a config that
    adds a marker set to the protocol may use it in the grid. ``frames``: the value sets how many
    frames a condition's trials have, so a condition too short for every estimator is this
    key's mistake (otherwise the protocol's).

    How the key reads for people: ``label`` names it (``"RoM"``); ``text`` formats one value
    with its unit (``"±{:g}°"``, a :meth:`str.format` template of one value), ``names`` gives
    values a name of their own (``{"mcp": "index MCP"}``). Without them the key reads by its
    unit suffix (``rom_deg`` 20 -> "rom 20°", ``_mm`` likewise) or as "key=value".
    """

    type: type
    minimum: float | None = None
    exclusive_minimum: bool = False
    maximum: float | Callable[[object], float] | None = None
    choices: tuple[str, ...] | Callable[[object], tuple[str, ...]] | None = None
    frames: bool = False
    label: str | None = None
    text: str | None = None
    names: Mapping[object, str] = field(default_factory=dict)

    def allowed(self, protocol) -> str:
        """The allowed values in words, e.g. ``"a number > 0 and <= 180"``."""
        if self.type is str:
            return "one of " + ", ".join(map(str, self._resolve(self.choices, protocol)))
        words = ["an integer" if self.type is int else "a number"]
        if self.minimum is not None:
            words.append(f"{'>' if self.exclusive_minimum else '>='} {self.minimum:g}")
        maximum = self._resolve(self.maximum, protocol)
        if maximum is not None:
            words.append(f"<= {maximum:g}")
        return " ".join(words[:2]) + "".join(f" and {w}" for w in words[2:])

    @property
    def by_protocol(self) -> bool:
        """Whether the study's protocol sets the allowed values (:attr:`maximum` or
        :attr:`choices` a function of it)."""
        return callable(self.maximum) or callable(self.choices)

    def accepts(self, value, protocol) -> bool:
        """Whether ``value`` (as YAML gives it) is one of the allowed values."""
        if self.type is str:
            return isinstance(value, str) and value in self._resolve(self.choices, protocol)
        # bool is an int to Python but never a grid value; an integer key takes no 5.0, whose
        # file name and seed would differ from 5's.
        numeric = (int,) if self.type is int else (int, float)
        if isinstance(value, bool) or not isinstance(value, numeric) or not math.isfinite(value):
            return False
        if self.minimum is not None and below(value, self.minimum, self.exclusive_minimum):
            return False
        maximum = self._resolve(self.maximum, protocol)
        return maximum is None or value <= maximum

    @staticmethod
    def _resolve(limit, protocol):
        return limit(protocol) if callable(limit) else limit


def key_label(key: str, spec: GridValues | None = None) -> str:
    """How grid key ``key`` is named for people: its ``spec.label``, else the key itself with
    its unit suffix dropped and underscores as spaces (``depth_mm`` -> "depth")."""
    if spec is not None and spec.label:
        return spec.label
    return key.removesuffix("_deg").removesuffix("_mm").replace("_", " ")


def value_text(key: str, value: object, spec: GridValues | None = None) -> str:
    """One grid value with its unit, as a row label reads it: by ``spec`` (its ``names``, then
    its ``text``), else by the key's unit suffix (``_deg``: "tilt 10°", ``_mm``: "depth 2 mm"),
    else "key=value"."""
    if spec is not None:
        if value in spec.names:
            return spec.names[value]
        if spec.text:
            return spec.text.format(value)
    if key.endswith("_deg"):
        return f"{key.removesuffix('_deg')} {value:g}°"
    if key.endswith("_mm"):
        return f"{key.removesuffix('_mm')} {value:g} mm"
    return f"{key}={value}"


@dataclass(frozen=True)
class Diagnostic:
    """A per-trial check of one method that needs the ground truth (:attr:`Study.diagnostics`).

    ``diagnose(arguments, results, truth) -> rows`` is given the estimator's arguments for all
    trials of a condition (each segment ``(n_trials, ...)``), its results (``None`` where it
    returned none) and the truth, and returns the extra columns of each trial's row (an empty
    mapping where there was no result). ``columns`` names the columns each of those rows that
    is not empty holds (NaN where a trial has no value): what the study records beside its
    estimates (a claim selects them by name), which the estimate job holds each row to.
    """

    columns: tuple[str, ...]
    diagnose: Callable[..., list[dict[str, object]]]


@dataclass(frozen=True)
class Study:
    """One simulation study of the benchmark, exported by its simulator module as ``STUDY``.

    ``kind`` is the estimator kind it runs (one of :data:`KINDS`); ``grid_keys`` its condition
    columns, in order; ``seed_keys`` the condition keys that define a random trial (the rest
    select a view of the same trial, e.g. the first Nt frames); ``segments`` the names of the
    marker arrays passed to an estimator, in argument order; ``protocol_class`` the dataclass of
    its documented modelling choices (with ``from_config(overrides)``), each field annotated
    with its type and range (:mod:`jointbench.declared`); ``simulate`` the function of the
    signature above; ``grid_spec`` the values each grid key allows, checked before any job runs
    (a study without one has its grid values checked by the schema only), and how each key
    reads for people (:class:`GridValues`).

    ``title`` is the study's name for people in titles and text ("thumb CMC"; the name when
    empty). ``diagnostics`` maps a method to a check that needs the ground truth
    (:class:`Diagnostic`, with the columns it records); the estimate job adds its columns to
    that method's rows.

    ``more_kinds`` gives the trials to estimators of further kinds, each with the segments its
    estimators take, in argument order (names in :attr:`Trials.segments`): a two-segment study
    whose simulator also writes the distal markers in the proximal segment's frame lets the
    one-segment centre methods fit them, e.g. ``{"center": ("distal_in_proximal",)}``. Every
    kind of a study must share its truth (the point or axis its errors are measured from).

    ``frame_count`` (required) gives the frames of a condition's trials under a protocol
    (``frame_count(condition, protocol)``) without simulating them: the config's check of each
    condition's frames counts them so, and simulates nothing, so a size typed a few digits too
    long in a study's config is refused before any job, not laid out in a ``MemoryError`` or
    looped over for hours (a job refuses trials whose frames are not those declared).
    ``recorded_frames`` gives the frames each
    trial's simulation draws under a protocol (``recorded_frames(protocol)``) where it keeps
    fewer of them (paper C's trials are the first ``Nt`` frames of one recording drawn whole):
    what a job holds, which the check bounds.

    ``frame_keys`` gives where the config sets those frames (``frame_keys(condition,
    overrides)``, ``overrides`` the config's ``protocol`` as written): the paths of keys below
    ``studies.<name>`` of the protocol fields the recording's frames are read from, by
    ``frame_count`` or, where a grid key sets a trial's frames, by ``recorded_frames``, each a
    tuple (``[("protocol", "duration_s"), ("protocol", "fps")]``), under the entry that sets
    each where fields can be written under more than one. A frame count refused by
    the config's check names them; a study that does not declare them is refused naming its
    ``protocol`` alone, since only the study knows which fields its ``frame_count`` reads.
    ``frame_values`` gives the values of those fields (``frame_values(condition, protocol)``,
    field -> value, written or default) where the frames are not one of them but read from
    several (``round(duration_s * fps)``): the count alone says neither which field is the
    mistake nor by how much, so the refusal gives each value beside it. A study whose frames
    are one field's value (``n_frames``) need not declare it: the count is that value.
    """

    name: str
    kind: str
    grid_keys: tuple[str, ...]
    seed_keys: tuple[str, ...]
    segments: tuple[str, ...]
    protocol_class: type
    simulate: Callable[[Mapping[str, object], object, Sequence[np.random.Generator]], Trials]
    grid_spec: Mapping[str, GridValues] = field(default_factory=dict)
    title: str = ""
    diagnostics: Mapping[str, Diagnostic] = field(default_factory=dict)
    more_kinds: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    frame_count: Callable[[Mapping[str, object], object], int] | None = None
    recorded_frames: Callable[[object], int] | None = None
    frame_keys: Callable[[Mapping[str, object], Mapping], Sequence[tuple]] | None = None
    frame_values: Callable[[Mapping[str, object], object], Mapping[str, object]] | None = None

    def __post_init__(self) -> None:
        for kind in self.kinds:
            if kind not in KINDS:
                raise ValueError(f"study {self.name!r}: kind {kind!r} is not one of {KINDS}")
        if self.kind in self.more_kinds:
            raise ValueError(f"study {self.name!r}: more_kinds repeats its kind {self.kind!r}")
        scored = {_TRUTH_OF[kind] for kind in self.kinds}
        if len(scored) > 1:
            raise ValueError(
                f"study {self.name!r}: kinds {', '.join(self.kinds)} are scored against different "
                "truths; one study's errors must be comparable"
            )
        stray = set(self.seed_keys) - set(self.grid_keys)
        if stray:
            raise ValueError(f"study {self.name!r}: seed keys {sorted(stray)} are not grid keys")
        if not dataclasses.is_dataclass(self.protocol_class):
            raise ValueError(
                f"study {self.name!r}: protocol_class {self.protocol_class!r} must be a "
                "dataclass, whose annotated fields declare what the config may set"
            )
        loose = [m for m, check in self.diagnostics.items() if not isinstance(check, Diagnostic)]
        if loose:
            raise ValueError(
                f"study {self.name!r}: the diagnostics of {', '.join(loose)} must each be a "
                "Diagnostic, which names the columns it records: write Diagnostic(columns, "
                "diagnose) (jointbench.simulate), columns a tuple of names"
            )
        for method, check in self.diagnostics.items():
            # A string is a sequence of its letters: each would be a column it declares.
            if isinstance(check.columns, str):
                raise ValueError(
                    f"study {self.name!r}: the diagnostic of {method} declares its columns as "
                    f"the string {check.columns!r}; write them as a tuple of names: "
                    f"({check.columns!r},)"
                )
        if self.frame_count is None:
            raise ValueError(
                f"study {self.name!r}: declare its trials' frames, frame_count=, a function of "
                "(condition, protocol) giving the frames of every trial of that condition "
                "(e.g. frame_count=lambda condition, protocol: protocol.n_frames): the config's "
                "check counts each condition's frames from it before any job, without "
                "simulating a trial"
            )
        if self.grid_spec and tuple(self.grid_spec) != self.grid_keys:
            raise ValueError(
                f"study {self.name!r}: grid_spec keys {tuple(self.grid_spec)} must be the grid "
                f"keys {self.grid_keys}, in order"
            )

    def protocol(self, overrides: Mapping[str, object] | None = None) -> object:
        """The study's protocol: documented defaults updated by the config's ``protocol``.

        Every field is then checked against its declaration, whatever ``from_config`` checked
        itself, so a study defined outside the package is held to its declarations too;
        ``DeclarationError`` (a ``ValueError``) names the field.
        """
        protocol = self.protocol_class.from_config(overrides)
        fields = dataclasses.fields(self.protocol_class)
        check_fields(self.protocol_class, {f.name: getattr(protocol, f.name) for f in fields})
        return protocol

    @property
    def kinds(self) -> tuple[str, ...]:
        """Every estimator kind the study runs: :attr:`kind` first, then :attr:`more_kinds`."""
        return (self.kind, *self.more_kinds)

    @property
    def all_segments(self) -> tuple[str, ...]:
        """Every segment some kind's estimators take, each once, in order of first use."""
        return tuple(dict.fromkeys(name for kind in self.kinds for name in self.segments_of(kind)))

    def segments_of(self, kind: str) -> tuple[str, ...]:
        """The segments a ``kind`` estimator takes, in argument order."""
        if kind == self.kind:
            return self.segments
        try:
            return tuple(self.more_kinds[kind])
        except KeyError:
            raise ValueError(
                f"study {self.name!r} runs no {kind} estimators; its kinds: {', '.join(self.kinds)}"
            ) from None

    @property
    def display_name(self) -> str:
        """The study's name for people: its :attr:`title`, else its name."""
        return self.title or self.name

    def key_label(self, key: str) -> str:
        """How grid key ``key`` is named in axis titles and headers (:func:`key_label`)."""
        return key_label(key, self.grid_spec.get(key))

    def condition_label(self, values: Sequence[object], keys: Sequence[str] = ()) -> str:
        """A condition as a row label with units, e.g. ``("M", 5, 0.5)`` -> "M set, ±5°,
        0.5 mm noise"; ``values`` of ``keys`` (the study's grid keys when not given)."""
        keys = tuple(keys) or self.grid_keys
        return ", ".join(
            value_text(k, v, self.grid_spec.get(k)) for k, v in zip(keys, values, strict=True)
        )

    def fit_arguments(
        self, trials: Trials, trial: int, kind: str | None = None
    ) -> tuple[np.ndarray, ...]:
        """The arrays passed to a ``kind`` estimator (default :attr:`kind`) for one trial, in
        :meth:`segments_of` order."""
        return tuple(trials.segments[name][trial] for name in self.segments_of(kind or self.kind))
