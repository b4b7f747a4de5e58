"""How a number, a column name and a margin are written for people: the one home of the
formatting that every table writer, the report's landing page and the README share.

A value is printed the same way wherever it appears:

- a **published** value exactly as the paper printed it (the shortest decimal that reads back as
  the value held, so 0.079 stays 0.079 and 1872.02 stays 1872.02), never rounded;
- one of **ours** to :data:`SIGNIFICANT` significant figures in fixed-point notation, its
  integer digits never rounded away (0.0115, 0.845, 6.83, 556.6 → 557), so a small time and a
  large error stand in one column without an exponent; a value with no more digits than that
  (a grid's 0.5 or 20 mm, a share of 200 trials such as 0.14) exactly as it is, not padded
  with zeros;
- ``True`` / ``False`` as ``yes`` / ``no``; a missing value as ``–``.

A column name becomes a header by its words and unit: ``mean_error_mm`` → ``mean error (mm)``,
``fe_rom_deg`` → ``FE RoM (°)``.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping

__all__ = [
    "MISSING",
    "SIGNIFICANT",
    "format_column",
    "header",
    "is_published_column",
    "margin_words",
    "number",
    "published_number",
    "words",
]

#: Significant figures of a number of ours.
SIGNIFICANT = 3
#: How a missing value is printed.
MISSING = "–"

#: A column name's last word that is a unit, and how the unit is written.
_UNITS = {"mm": "mm", "deg": "°", "s": "s", "seconds": "s", "pct": "%"}
#: Words written in capitals or as the papers write them.
_SPELLED = {
    "rom": "RoM",
    "fe": "FE",
    "aa": "AA",
    "sd": "SD",
    "rms": "RMS",
    "matlab": "MATLAB",
    "ls": "LS",
    "nm": "NM",
    "bc": "BC",
    "ma": "MA",
    "is": "IS",
    "sta": "STA",
    "cor": "CoR",
    "aor": "AoR",
    "score": "SCoRE",
    "sara": "SARA",
    "stoddart": "Stoddart",
    "id": "id",
    "h": "H",
    "m": "M",
}
#: Headers that the words of their column name do not say well.
_HEADERS = {
    "n_frames": "frames used, Nt",
    "aa_ratio": "AA/FE RoM ratio",
    "inside_95": "share inside the 95 % region",
    "binomial_low": "honest band, low",
    "binomial_high": "honest band, high",
    "mean_seconds": "mean time per trial (s)",
    "median_sqrt_trace_cov_mm": "median predicted sqrt(tr Wc) (mm)",
    "not_converged": "trials not converged",
}
#: A column whose name starts with one of these holds the papers' own values.
_PUBLISHED_PREFIXES = ("published", "paper_", "paper:", "paper ")


def words(name: str) -> str:
    """A snake_case name in words, units in brackets: ``ls_worst_share`` → ``LS worst share``,
    ``share_within_0_5_mm`` → ``share within 0.5 (mm)``."""
    text = re.sub(r"(?<=\d)_(?=\d)", ".", name)
    parts = [p for p in text.split("_") if p]
    unit = ""
    if len(parts) > 1 and parts[-1].lower() in _UNITS:
        unit = f" ({_UNITS[parts.pop().lower()]})"
    return " ".join(_SPELLED.get(p.lower(), p) for p in parts) + unit


def header(column: object, headers: Mapping[str, str] | None = None) -> str:
    """The header people read for ``column``: ``headers`` (a table's own), else the shared
    :data:`_HEADERS`, else its :func:`words`; a name with no underscore stays as it is."""
    name = str(column)
    if headers and name in headers:
        return headers[name]
    if name in _HEADERS:
        return _HEADERS[name]
    return words(name) if "_" in name else name


def is_published_column(column: object) -> bool:
    """Whether ``column`` holds the papers' own values (printed exactly as published)."""
    return str(column).lower().startswith(_PUBLISHED_PREFIXES)


def _missing(value: object) -> bool:
    return value is None or (isinstance(value, float) and math.isnan(value))


def number(value: float, significant: int = SIGNIFICANT) -> str:
    """``value`` to ``significant`` figures in fixed-point notation, keeping every integer digit:
    ``number(0.0115)`` → ``0.0115``, ``number(0.019996)`` → ``0.0200``, ``number(556.6)`` →
    ``557``, ``number(0.5)`` → ``0.5``."""
    if _missing(value):
        return MISSING
    if math.isinf(value):
        return "∞" if value > 0 else "−∞"
    if value == 0:
        return "0"
    exact = published_number(value)
    if len(exact.lstrip("-").replace(".", "").strip("0")) <= significant:
        return exact
    decimals = max(0, significant - 1 - math.floor(math.log10(abs(value))))
    text = f"{value:.{decimals}f}"
    # Rounding may carry into a new digit (0.09996 → 0.1000): one decimal fewer then.
    if decimals and len(text.lstrip("-").replace(".", "").lstrip("0")) > significant:
        text = f"{value:.{decimals - 1}f}"
    return text


def published_number(value: float) -> str:
    """A published value as the paper printed it: the shortest decimal that reads back as
    ``value`` (``0.079``, ``1872.02``, ``4.3``), never in exponent notation."""
    if _missing(value) or math.isinf(value):
        return number(value)
    if float(value).is_integer():
        return str(int(value))
    text = repr(float(value))
    if "e" in text:
        digits = len(text.split("e")[0].replace("-", "").replace(".", "").lstrip("0"))
        text = f"{value:.{digits - 1 - math.floor(math.log10(abs(value)))}f}"
    return text


def format_column(values: Iterable[object], *, published: bool = False) -> list[str]:
    """Every cell of one column as people read it (see the module doc): ``published`` for a
    column of the papers' values."""

    def cell(value: object) -> str:
        if isinstance(value, bool):
            return "yes" if value else "no"
        if _missing(value):
            return MISSING
        if isinstance(value, float):
            return published_number(value) if published else number(value)
        return str(value)

    return [cell(v) for v in values]


def margin_words(margin: float, unit: str = "") -> str:
    """How far inside or outside its tolerance a value lies, in words: ``1.7 inside``,
    ``3 trials outside``, ``on the edge``."""
    if _missing(margin):
        return MISSING
    if margin == 0:
        return "on the edge"
    side = "inside" if margin > 0 else "outside"
    return f"{number(abs(margin))}{unit} {side}"
