"""Whether the numbers a generated text gives are in the tables it cites.

A README block or a recorded reason may only repeat numbers of the results: a number in the
text must be printed somewhere in a cited table, as :mod:`jointbench.resultfiles.formatting`
prints it (:func:`~jointbench.resultfiles.formatting.number` or
:func:`~jointbench.resultfiles.formatting.published_number`), or rounded to the decimals the
text shows, or inside a text cell or a column's header. A number typed by hand, or one left over
from an older run, is then found in none of them.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable

import pandas as pd

from jointbench.resultfiles.formatting import header, number, published_number

__all__ = ["NUMBER", "numbers_in", "shown_numbers", "unfound_numbers"]

#: A number standing alone: not part of a name ("frame-0", "T1") nor an equation's ("eq. 2").
NUMBER = re.compile(r"(?<![\w.])(?<![A-Za-z]-)(?<!eq\. )[-+−]?\d+(?:\.\d+)?")
#: The most decimals a number rounded from a table may show.
_MOST_DECIMALS = 6


def numbers_in(text: object) -> set[str]:
    """Every number standing alone in ``text``, without its sign (``"−3.5 mm, 20"`` →
    ``{"3.5", "20"}``)."""
    return {n.lstrip("+-−") for n in NUMBER.findall(str(text))}


def _printed(value: float) -> set[str]:
    """The ways a numeric cell may be printed: by the shared formatting, as an integer when it
    is one, and rounded to 1 … :data:`_MOST_DECIMALS` decimals."""
    magnitude = abs(float(value))
    shown = {number(magnitude), published_number(magnitude)}
    if magnitude.is_integer():
        shown.add(str(int(magnitude)))
    shown.update(f"{magnitude:.{d}f}" for d in range(1, _MOST_DECIMALS + 1))
    return shown


def shown_numbers(tables: Iterable[pd.DataFrame]) -> set[str]:
    """Every number the ``tables`` print: each numeric cell as :func:`_printed` allows, the
    numbers inside text cells, and those in column headers."""
    shown: set[str] = set()
    for table in tables:
        for column in table.columns:
            shown |= numbers_in(header(column))
        for value in table.to_numpy().ravel():
            if isinstance(value, bool) or value is None:
                continue
            if isinstance(value, int | float) or pd.api.types.is_number(value):
                if math.isfinite(float(value)):
                    shown |= _printed(value)
            else:
                shown |= numbers_in(value)
    return shown


def unfound_numbers(text: str, tables: Iterable[pd.DataFrame]) -> list[str]:
    """The numbers of ``text`` that none of ``tables`` prints (:func:`shown_numbers`), sorted;
    empty when every one is found."""
    return sorted(numbers_in(text) - shown_numbers(tables))
