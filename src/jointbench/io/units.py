"""Point units of marker files: their size in mm, and the units a cluster's numbers fit."""

from __future__ import annotations

from pathlib import Path

from jointbench.estimators.validation import MIN_SPAN_MM

__all__ = [
    "UNIT_READ",
    "UNIT_TO_MM",
    "fitting_units",
    "the_files_unit",
    "to_mm",
    "unit_hint",
    "unit_read_in",
    "unit_size",
]

#: The point units a file may state (C3D ``POINT:UNITS``, TRC ``Units``) by symbol, each's
#: size [mm]; spelled out (:func:`unit_size`) they are read as these.
UNIT_TO_MM = {"mm": 1.0, "cm": 10.0, "m": 1000.0}

#: The unit a file's coordinates are read in where it states none (a C3D without
#: ``POINT:UNITS``; a CSV, whose format states no unit and is in mm).
UNIT_READ = "mm"

# The symbol each unit's name, in either spelling and either number, is read as.
_SPELLED = {
    f"{prefix}{stem}{plural}": f"{symbol}m"
    for prefix, symbol in (("milli", "m"), ("centi", "c"), ("", ""))
    for stem in ("metre", "meter")
    for plural in ("", "s")
}

#: The units a cluster's numbers are tried in (:func:`fitting_units`), with their names.
_NAMES = {"mm": "millimetres", "cm": "centimetres", "m": "metres"}


def to_mm(unit: str, path: Path | str) -> float:
    """The size [mm] of the point unit ``unit`` that the file ``path`` states; ``ValueError``
    naming the file and the known units for another."""
    size = unit_size(unit)
    if size is None:
        raise ValueError(
            f"{path}: unknown point unit {unit!r}; known: {', '.join(sorted(UNIT_TO_MM))} "
            "(or spelled out: millimetres, centimeters, metre, ...)"
        )
    return size


def unit_size(unit: str) -> float | None:
    """The size [mm] of the point unit ``unit``, by symbol (:data:`UNIT_TO_MM`) or spelled out
    in any case, British or American, singular or plural; ``None`` for another."""
    key = unit.strip().lower()
    return UNIT_TO_MM.get(_SPELLED.get(key, key))


def fitting_units(span_mm: float, stated: str, largest_mm: float) -> dict[str, float] | None:
    """The units other than ``stated`` (the file's point unit) in which its numbers make a
    cluster of a body's size, each's name with that size [mm], given the size ``span_mm`` [mm]
    they make in ``stated``: no smaller than a marker
    (:data:`~jointbench.estimators.validation.MIN_SPAN_MM`) and no larger than ``largest_mm``,
    smaller unit first. Empty when none fits, ``None`` when ``stated`` is no unit
    :data:`UNIT_TO_MM` knows."""
    stated_mm = unit_size(stated)
    if stated_mm is None:
        return None
    sizes = {
        name: span_mm / stated_mm * UNIT_TO_MM[unit]
        for unit, name in _NAMES.items()
        if UNIT_TO_MM[unit] != stated_mm
    }
    return {name: size for name, size in sizes.items() if MIN_SPAN_MM <= size <= largest_mm}


def unit_hint(span_mm: float, stated: str, largest_mm: float) -> str:
    """In words, the units that fit (:func:`fitting_units`):
    ``"millimetres read as centimetres (a cluster 317 mm across)"``. Where two fit (31.7 m
    read in metres is a thumb's 31.7 mm or a thigh's 317 mm), both are named, smaller unit
    first: the numbers cannot tell. ``""`` when ``stated`` is no unit :data:`UNIT_TO_MM`
    knows, and a sentence saying so when none fits."""
    fits = fitting_units(span_mm, stated, largest_mm)
    if fits is None:
        return ""
    if not fits:
        return f"in no unit of {', '.join(_NAMES.values())} are its numbers a body's markers"
    stated_mm = unit_size(stated)
    read_as = next(name for unit, name in _NAMES.items() if UNIT_TO_MM[unit] == stated_mm)
    return "its numbers look like " + " or ".join(
        f"{name} read as {read_as} (a cluster {size:.3g} mm across)" for name, size in fits.items()
    )


def unit_read_in(stated: str) -> str:
    """For messages, in words, the unit a file's coordinates were read in, given the unit it
    ``stated`` (``""`` where it states none): ``"the unit the file states ('cm', read as
    mm)"``, or ``"the unit the file is read in (it states no unit; read as mm)"``; a file that
    states nothing is not said to state mm."""
    if not stated:
        return f"the unit the file is read in (it states no unit; read as {UNIT_READ})"
    return f"the unit the file states ({stated!r}, read as mm)"


def the_files_unit(stated: str) -> str:
    """For messages, the unit of a file that ``stated`` it (``""`` where it states none), as
    a name: ``"the file's 'cm'"``, or ``"mm, which the file is read in (it states no unit)"``."""
    if not stated:
        return f"{UNIT_READ}, which the file is read in (it states no unit)"
    return f"the file's {stated!r}"
