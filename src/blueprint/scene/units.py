"""Length units: the unit a model file states (its format's record in ``blueprint.scene.formats``
says which: glTF and STEP metres, 3MF its model's ``unit``), and the one a drawing measures the
model in: ``--units`` where given, else the file's, else millimetres, with a warning that says
it was assumed. Drawings print
millimetres (dimensions, the page of a drawing to scale): ``UNITS_MM`` a model unit.
"""

from __future__ import annotations

import logging
from typing import Protocol

from blueprint.errors import InputError

log = logging.getLogger("blueprint")

__all__ = [
    "ASSUMED_UNIT",
    "UNITS_MM",
    "check_units",
    "drawing_unit",
    "named_unit",
    "object_unit",
    "warn_if_assumed",
]

#: Millimetres per model unit, by the unit's name.
UNITS_MM: dict[str, float] = {
    "um": 1e-3,
    "mm": 1.0,
    "cm": 10.0,
    "m": 1000.0,
    "km": 1e6,
    "in": 25.4,
    "ft": 304.8,
}

#: The unit of a model whose file states none (CAD exports to STL and OBJ are most often mm).
ASSUMED_UNIT = "mm"

# The names files state units by: 3MF's (micron ... meter), trimesh's (millimeters, inches),
# and blueprint's own, lower case.
_NAMES: dict[str, str] = {
    **{name: name for name in UNITS_MM},
    "micron": "um",
    "microns": "um",
    "millimeter": "mm",
    "millimeters": "mm",
    "centimeter": "cm",
    "centimeters": "cm",
    "meter": "m",
    "meters": "m",
    "kilometer": "km",
    "kilometers": "km",
    "inch": "in",
    "inches": "in",
    "foot": "ft",
    "feet": "ft",
}


def check_units(units: str) -> str:
    """``units`` where it names a unit of ``UNITS_MM``; else ``InputError``."""
    if units not in UNITS_MM:
        raise InputError(f"unknown units {units!r} (choose {', '.join(UNITS_MM)})")
    return units


def named_unit(stated: str) -> str | None:
    """The unit of ``UNITS_MM`` that a file or an object states as ``stated`` ("inch",
    "meters", any case); None where blueprint knows no unit by that name."""
    return _NAMES.get(str(stated).strip().lower())


def object_unit(stated: str | None) -> tuple[str | None, str]:
    """The length unit of a trimesh object whose ``units`` are ``stated``, and where it comes
    from; None where it has none, or none blueprint knows (drawings then assume one)."""
    if stated is None:
        return None, "the object has no units"
    unit = named_unit(stated)
    return unit, f"its units, {stated}" if unit else f"its units {stated!r} are none blueprint knows"


class Measured(Protocol):
    """What a drawing's unit is read from: a ``Model`` (its unit, why, and its file), named
    by its fields so that the model, which checks its unit against ``UNITS_MM``, imports
    this module and not the other way round."""

    unit: str | None
    unit_reason: str
    source: str | None


def drawing_unit(model: Measured, units: str | None = None) -> str:
    """The unit a drawing measures ``model`` in: ``units`` where given (it states the
    model's unit, whatever the file says), else the model's own (``Model.unit``), else
    ``ASSUMED_UNIT``, which a drawing that measures says with ``warn_if_assumed``.

    Raises
    ------
    InputError
        ``units`` is not a unit of ``UNITS_MM``.
    """
    if units is not None:
        return check_units(units)
    return model.unit or ASSUMED_UNIT


def warn_if_assumed(model: Measured, units: str | None = None) -> None:
    """Warn, naming the file, that a drawing measured ``model`` in ``ASSUMED_UNIT``: where
    neither ``units`` nor the file gave its unit. Called once a drawing is made, so that a
    drawing refused says nothing but why."""
    if units is None and model.unit is None:
        log.warning(
            "%s: %s; assumed %s (set --units)", model.source or "the model", model.unit_reason, ASSUMED_UNIT
        )
