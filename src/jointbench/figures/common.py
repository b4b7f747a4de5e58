"""Shared figure helpers: matplotlib on first use, one colour and marker per method across every
figure and study (each method's own, from its registration), the studies' names for people, and
saving figures reproducibly."""

from __future__ import annotations

import functools
import zlib
from collections.abc import Iterable, Mapping
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from jointbench.configuration.studies import get_study, study_names
from jointbench.estimators import registry
from jointbench.resultfiles.tables import output_paths

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "DISPLAY_SPAN",
    "display_limits",
    "equal_3d_limits",
    "few_3d_ticks",
    "group_label",
    "legend_below",
    "median_trial",
    "method_style",
    "method_styles",
    "pyplot",
    "save_figure",
    "study_title",
]

# Colours for methods that registered none (a newcomer's), none of them a built-in's; a
# method's own colour and marker are those it registered with (`register(..., color=...)`).
_SPARE_COLORS = (
    "#999933",
    "#882255",
    "#44aa99",
    "#332288",
    "#ddcc77",
    "#117733",
    "#aa4499",
    "#88ccee",
    "#525252",
    "#f46d43",
)


def study_title(study: str) -> str:
    """A study's name for people, its ``Study.title`` ("thumb CMC" for ``cmc``); a study
    without one, or not registered, keeps its name."""
    if study not in study_names():
        return study
    return get_study(study).display_name


@functools.cache
def pyplot() -> ModuleType:
    """``matplotlib.pyplot`` on the Agg backend (files, no window), imported on first use.

    The figure modules also compute their papers' tables and measurements, which the table
    jobs, the published-value check and the report's captions run without drawing; they do
    not pay for importing matplotlib (about a second of CPU).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot

    return matplotlib.pyplot


def method_style(method: str, index: int = 0) -> dict[str, object]:
    """Matplotlib colour and marker of a method: those it registered with, or for a method
    without a colour a spare one chosen by its name (so the same in every figure) and marker
    "X". ``index`` is unused; it is kept for callers that pass a method's position."""
    own = registry.styles().get(method, {})
    spare = _SPARE_COLORS[zlib.crc32(method.encode()) % len(_SPARE_COLORS)]
    return {"color": own.get("color", spare), "marker": own.get("marker", "X")}


def method_styles(methods: Iterable[str]) -> dict[str, dict[str, object]]:
    """:func:`method_style` of each of ``methods``, where a method without a colour of its
    own would share one with another method of the figure it takes the next spare colour free
    (methods in name order), so every method of one figure has a colour of its own."""
    methods = list(dict.fromkeys(methods))
    styles = {m: method_style(m) for m in methods}
    own = {m for m in methods if "color" in registry.styles().get(m, {})}
    taken = {styles[m]["color"] for m in own}
    for method in sorted(m for m in methods if m not in own):
        start = _SPARE_COLORS.index(styles[method]["color"])
        for step in range(len(_SPARE_COLORS)):
            color = _SPARE_COLORS[(start + step) % len(_SPARE_COLORS)]
            if color not in taken:
                styles[method] = {**styles[method], "color": color}
                break
        taken.add(styles[method]["color"])
    return styles


#: A figure's scale of errors spans at most this factor either side of the median of its
#: positive values: a value beyond it (an estimator far off, up to inf) is drawn at the scale's
#: end and marked, so that it neither flattens every other value nor makes a log axis span
#: hundreds of decades (matplotlib's log ticks overflow near 1e300).
DISPLAY_SPAN = 1e6


def display_limits(values) -> tuple[float, float]:
    """``(low, high)`` of a log scale for ``values`` (any shape; NaN and values <= 0 left
    out): the smallest and largest positive finite values within :data:`DISPLAY_SPAN` either
    side of their median, at least a decade apart."""
    values = np.asarray(values, dtype=float)
    positive = values[np.isfinite(values) & (values > 0)]
    if not positive.size:
        return 1e-3, 1e-2
    centre = float(np.median(positive))
    shown = positive[(positive >= centre / DISPLAY_SPAN) & (positive <= centre * DISPLAY_SPAN)]
    low = float(shown.min())
    return low, max(float(shown.max()), low * 10)


def equal_3d_limits(ax, points: np.ndarray, margin: float = 0.08) -> None:
    """Same scale on x, y and z of a 3-D axes spanning ``points`` ``(n, 3)``, so distances
    and angles in the plot are true ones (matplotlib otherwise stretches each axis to fill)."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    low, high = np.nanmin(points, axis=0), np.nanmax(points, axis=0)
    centre, half = (low + high) / 2, (high - low).max() / 2 * (1 + margin)
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_zlim(centre[2] - half, centre[2] + half)
    ax.set_box_aspect((1, 1, 1))


def few_3d_ticks(ax, n: int = 4) -> None:
    """At most about ``n`` ticks on each axis of a 3-D axes, so tick labels large enough to
    read when the figure is shown small do not run into each other."""
    from matplotlib.ticker import MaxNLocator

    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_major_locator(MaxNLocator(n))


def legend_below(fig, handles, names) -> None:
    """One legend for the whole figure, in a row under its panels, off every curve; the
    caller's layout leaves room for it at the bottom."""
    fig.legend(
        handles,
        names,
        loc="lower center",
        ncol=len(handles),
        fontsize=9,
        frameon=False,
        bbox_to_anchor=(0.5, 0),
    )


def group_label(ax, x: float, text: str) -> None:
    """Name a group of conditions (e.g. "noise SD 1.0 mm") just above the axes, centred on
    ``x`` in data coordinates, where it cannot cover data."""
    ax.text(
        x,
        1.01,
        text,
        transform=ax.get_xaxis_transform(),
        ha="center",
        va="bottom",
        fontsize=9,
    )


def median_trial(errors: pd.Series) -> int:
    """The trial (index of ``errors``) with the median error; for an even count the lower of
    the two middle ones, so it is a real trial. Equal errors are ordered by trial number.
    NaN errors are left out."""
    finite = errors.dropna()
    if finite.empty:
        raise ValueError("no trial with a finite error to choose from")
    ordered = sorted(zip(finite.to_numpy(), finite.index, strict=True))
    return int(ordered[(len(ordered) - 1) // 2][1])


#: Resolution of the PNG files [dots per inch].
SAVE_DPI = 150
# Margin around the figure's drawn content [inches], matplotlib's default for a tight bounding box.
_PAD_INCHES = 0.1


def save_figure(fig: Figure, outputs: Mapping[str, str] | object) -> None:
    """Save to every path given (``png`` and ``pdf`` keys or attributes), cropped to what is
    drawn, and close the figure.

    The layout and the crop box are computed once, on the PNG's resolution and without
    drawing, and every format is saved with them: a ``bbox_inches="tight"`` save lays the
    figure out and draws it an extra time per format.
    """
    fig.set_dpi(SAVE_DPI)
    engine = fig.get_layout_engine()
    if engine is not None:
        engine.execute(fig)
    crop = fig.get_tightbbox(fig.canvas.get_renderer()).padded(_PAD_INCHES)
    # No engine at all (not "none", a placeholder): a figure with one is laid out again, and
    # drawn once more, before each save.
    fig.set_layout_engine(None)
    for path in output_paths(outputs, ("png", "pdf")):
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=SAVE_DPI, bbox_inches=crop, metadata=_stable_metadata(path))
    pyplot().close(fig)


def _stable_metadata(path: str) -> dict[str, object]:
    # Dated metadata would make identical results differ byte for byte between runs.
    if str(path).endswith(".pdf"):
        return {"CreationDate": None, "Producer": "jointbench"}
    return {"Software": "jointbench"}
