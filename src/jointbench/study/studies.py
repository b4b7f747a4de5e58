"""The studies: what each simulates, which estimator kind it runs, and how a result is scored."""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
from scipy import special

from jointbench.geometry import angle_between_lines_deg
from jointbench.simulate import Trials

__all__ = ["STUDIES", "GridValues", "StudySpec", "get_study"]

_NAN3 = (np.nan, np.nan, np.nan)
# 95 % quantile of chi-square with 3 degrees of freedom (scipy.stats costs 0.7 s to import).
CHI2_3DOF_95 = float(special.chdtri(3, 0.05))


@dataclass(frozen=True)
class GridValues:
    """The values one grid key allows: numbers of ``type`` (``int`` or ``float``) within bounds,
    or text among ``choices``.

    ``maximum`` and ``choices`` may be functions of the study's protocol, for limits the
    protocol defines (its marker sets, its joints, its recording length), so that a config that
    adds a marker set to the protocol may use it in the grid.
    """

    type: type
    minimum: float | None = None
    exclusive_minimum: bool = False
    maximum: float | Callable[[object], float] | None = None
    choices: tuple[str, ...] | Callable[[object], tuple[str, ...]] | None = None

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

    def accepts(self, value, protocol) -> bool:
        """Whether ``value`` (as YAML gives it) is one of the allowed values."""
        if self.type is str:
            return isinstance(value, str) and value in self._resolve(self.choices, protocol)
        # bool is an int to Python but never a grid value; an integer key takes no 5.0, whose
        # file name and seed would differ from 5's.
        numeric = (int,) if self.type is int else (int, float)
        if isinstance(value, bool) or not isinstance(value, numeric) or not math.isfinite(value):
            return False
        if self.minimum is not None and (
            value <= self.minimum if self.exclusive_minimum else value < self.minimum
        ):
            return False
        maximum = self._resolve(self.maximum, protocol)
        return maximum is None or value <= maximum

    @staticmethod
    def _resolve(limit, protocol):
        return limit(protocol) if callable(limit) else limit


@dataclass(frozen=True)
class StudySpec:
    """One study of the benchmark.

    ``kind`` is the estimator kind it runs; ``grid_keys`` its condition columns, in order;
    ``seed_keys`` the condition keys that define a random trial (the rest select a view of the
    same trial, e.g. the first Nt frames); ``simulator`` the module providing ``simulate`` and
    the protocol class named ``protocol_class``; ``grid_spec`` the values each grid key allows.
    """

    name: str
    kind: str
    grid_keys: tuple[str, ...]
    seed_keys: tuple[str, ...]
    simulator: str
    protocol_class: str
    segments: tuple[str, ...]
    grid_spec: Mapping[str, GridValues] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if tuple(self.grid_spec) != self.grid_keys:
            raise ValueError(
                f"study {self.name!r}: grid_spec keys {tuple(self.grid_spec)} must be the grid "
                f"keys {self.grid_keys}, in order"
            )

    def module(self):
        return importlib.import_module(self.simulator)

    def protocol(self, overrides: Mapping[str, object] | None = None):
        """The study's protocol: documented defaults updated by the config's ``protocol``."""
        return getattr(self.module(), self.protocol_class).from_config(overrides)

    def simulate(self, condition, protocol, rngs) -> Trials:
        return self.module().simulate(condition, protocol, rngs)

    def fit_arguments(self, trials: Trials, trial: int) -> tuple[np.ndarray, ...]:
        """The arrays passed to the estimator for one trial."""
        return tuple(trials.segments[name][trial] for name in self.segments)

    def score(self, result, truth: Mapping[str, list[float]]) -> dict[str, float]:
        """Estimate and error columns of one result (NaN where the estimator failed)."""
        return _SCORERS[self.kind](result, truth)


def _score_center(result, truth) -> dict[str, float]:
    center = _NAN3 if result is None else result.center
    error = float(np.linalg.norm(np.asarray(center) - np.asarray(truth["center"])))
    return {"center_x": center[0], "center_y": center[1], "center_z": center[2], "error_mm": error}


def _score_axis(result, truth) -> dict[str, float]:
    point = _NAN3 if result is None else result.point
    direction = _NAN3 if result is None else result.direction
    error = float(
        angle_between_lines_deg(np.asarray(direction), np.asarray(truth["axis_direction"]))
    )
    return {
        **{f"point_{a}": float(v) for a, v in zip("xyz", point, strict=True)},
        **{f"direction_{a}": float(v) for a, v in zip("xyz", direction, strict=True)},
        "error_deg": error,
    }


_COVARIANCE_ENTRIES = {
    "cov_xx": (0, 0),
    "cov_xy": (0, 1),
    "cov_xz": (0, 2),
    "cov_yy": (1, 1),
    "cov_yz": (1, 2),
    "cov_zz": (2, 2),
}


def _covariance_entries(covariance) -> dict[str, float]:
    """The six distinct entries of a predicted 3×3 covariance [mm²] (NaN when there is none)."""
    return {
        name: (np.nan if covariance is None else float(covariance[index]))
        for name, index in _COVARIANCE_ENTRIES.items()
    }


def covariance_from_entries(frame) -> np.ndarray:
    """``(n, 3, 3)`` covariances rebuilt from the ``cov_*`` columns of a results table."""
    out = np.empty((len(frame), 3, 3))
    for name, (i, j) in _COVARIANCE_ENTRIES.items():
        out[:, i, j] = out[:, j, i] = frame[name].to_numpy(float)
    return out


def _score_joint_center(result, truth) -> dict[str, float]:
    """Centre error, predicted uncertainty and its honesty against the TRUE centre.

    ``mahalanobis_sq`` is ``e`` of paper C eq. 16, ``validation_index`` is ``v = sqrt(e / 3)``;
    ``cov_*`` are the predicted covariance's entries, so other references can be used later.
    """
    scores = _score_center(result, truth)
    covariance = None if result is None else result.covariance
    entries = _covariance_entries(covariance)
    if covariance is None:
        return {
            **scores,
            "sqrt_trace_cov_mm": np.nan,
            "mahalanobis_sq": np.nan,
            "validation_index": np.nan,
            **entries,
        }
    offset = np.asarray(result.center) - np.asarray(truth["center"])
    try:
        mahalanobis_sq = float(offset @ np.linalg.solve(covariance, offset))
    except np.linalg.LinAlgError:
        mahalanobis_sq = np.nan
    return {
        **scores,
        "sqrt_trace_cov_mm": float(np.sqrt(np.trace(covariance))),
        "mahalanobis_sq": mahalanobis_sq,
        "validation_index": float(np.sqrt(mahalanobis_sq / 3.0)),
        **entries,
    }


_SCORERS: dict[str, Callable] = {
    "center": _score_center,
    "axis": _score_axis,
    "joint_center": _score_joint_center,
}

STUDIES: dict[str, StudySpec] = {
    spec.name: spec
    for spec in (
        StudySpec(
            name="cmc",
            kind="center",
            grid_keys=("marker_set", "rom_deg", "noise_mm"),
            seed_keys=("marker_set", "rom_deg", "noise_mm"),
            simulator="jointbench.simulate.cmc",
            protocol_class="CmcProtocol",
            segments=("moving",),
            grid_spec={
                "marker_set": GridValues(str, choices=lambda protocol: tuple(protocol.directions)),
                # A circumduction tilt: 0° does not move, beyond 180° it repeats.
                "rom_deg": GridValues(float, minimum=0, exclusive_minimum=True, maximum=180),
                "noise_mm": GridValues(float, minimum=0),
            },
        ),
        StudySpec(
            name="hinge",
            kind="axis",
            grid_keys=("protocol", "fe_rom_deg", "aa_ratio"),
            seed_keys=("protocol", "fe_rom_deg", "aa_ratio"),
            simulator="jointbench.simulate.hinge_study",
            protocol_class="HingeStudyProtocol",
            segments=("moving",),
            grid_spec={
                "protocol": GridValues(str, choices=lambda protocol: tuple(protocol.joints)),
                "fe_rom_deg": GridValues(float, minimum=0, exclusive_minimum=True, maximum=180),
                "aa_ratio": GridValues(float, minimum=0),
            },
        ),
        StudySpec(
            name="hip",
            kind="joint_center",
            grid_keys=("n_frames",),
            # Paper C §8 analyses the first Nt frames of one recording: Nt selects a view.
            seed_keys=(),
            simulator="jointbench.simulate.hip",
            protocol_class="HipProtocol",
            segments=("proximal", "distal"),
            # Nt frames of a recording of the protocol's n_frames.
            grid_spec={
                "n_frames": GridValues(int, minimum=1, maximum=lambda protocol: protocol.n_frames)
            },
        ),
    )
}


def get_study(name: str) -> StudySpec:
    """The study called ``name``; ``ValueError`` listing the known studies otherwise."""
    try:
        return STUDIES[name]
    except KeyError:
        raise ValueError(f"unknown study {name!r}; known: {', '.join(STUDIES)}") from None
