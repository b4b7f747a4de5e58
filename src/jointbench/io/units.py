"""Point units of marker files: their size in mm, and the units a cluster's numbers fit."""

from __future__ import annotations

from pathlib import Path

from jointbench.estimators.validation import MIN_SPAN_MM

__all__ = ["UNIT_TO_MM", "to_mm", "unit_hint"]

#: The point units a file may state (C3D ``POINT:UNITS``, TRC ``Units``), each's size [mm].
UNIT_TO_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "meters": 1000.0, "millimeters": 1.0}

#: The units a cluster's numbers are tried in (:func:`unit_hint`), with their names.
_NAMES = {"mm": "millimetres", "cm": "centimetres", "m": "metres"}


def to_mm(unit: str, path: Path | str) -> float:
    """The size [mm] of the point unit ``unit`` that the file ``path`` states; ``ValueError``
    naming the file and the known units for another."""
    key = unit.strip().lower()
    if key not in UNIT_TO_MM:
        raise ValueError(
            f"{path}: unknown point unit {unit!r}; known: {', '.join(sorted(UNIT_TO_MM))}"
        )
    return UNIT_TO_MM[key]


def unit_hint(span_mm: float, stated: str, largest_mm: float) -> str:
    """In words, the units other than ``stated`` (the file's point unit) in which its numbers
    make a cluster of a body's size, given the size ``span_mm`` [mm] they make in ``stated``:
    ``"millimetres read as centimetres (a cluster 317 mm across)"``, where the cluster is then
    no smaller than a marker (:data:`~jointbench.estimators.validation.MIN_SPAN_MM`) and no
    larger than ``largest_mm``. Where two fit (31.7 m read in metres is a thumb's 31.7 mm or a
    thigh's 317 mm), both are named, smaller unit first: the numbers cannot tell. ``""`` when
    ``stated`` is no unit :data:`UNIT_TO_MM` knows, and a sentence saying so when none fits."""
    stated_mm = UNIT_TO_MM.get(stated.strip().lower())
    if stated_mm is None:
        return ""
    read_as = next(name for unit, name in _NAMES.items() if UNIT_TO_MM[unit] == stated_mm)
    sizes = {
        name: span_mm / stated_mm * UNIT_TO_MM[unit]
        for unit, name in _NAMES.items()
        if UNIT_TO_MM[unit] != stated_mm
    }
    fits = [name for name, size in sizes.items() if MIN_SPAN_MM <= size <= largest_mm]
    if not fits:
        return f"in no unit of {', '.join(_NAMES.values())} are its numbers a body's markers"
    return "its numbers look like " + " or ".join(
        f"{name} read as {read_as} (a cluster {sizes[name]:.3g} mm across)" for name in fits
    )
