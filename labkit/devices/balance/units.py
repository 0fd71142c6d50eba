"""Balance display units -> SI (pure functions, no I/O).

A balance shows either a mass (g, kg, oz, ...) or, on force-capable models (A&D ``N``,
the labkit HX711 sketch), a force. labkit keeps what the device measured: a force unit
becomes ``quantity="force"`` in N; a mass unit becomes ``quantity="mass"`` in kg. The
conversion of a mass reading to the PFR force (Fig. 5.25: grams-force) is left to the
analysis, which knows local gravity.
"""

from __future__ import annotations

#: kilograms per unit, for the mass units balances display (A&D and MT-SICS unit names)
KG_PER_UNIT: dict[str, float] = {
    "kg": 1.0,
    "g": 1e-3,
    "mg": 1e-6,
    "ug": 1e-9,
    "ct": 2e-4,               # metric carat
    "lb": 0.45359237,
    "oz": 0.028349523125,
    "ozt": 0.0311034768,      # troy ounce
    "dwt": 0.00155517384,     # pennyweight
    "GN": 6.479891e-5,        # grain
    "mom": 3.75e-3,           # momme
    "t": 1000.0,              # metric tonne
}

#: newtons per unit, for force units
N_PER_UNIT: dict[str, float] = {"N": 1.0, "mN": 1e-3, "kN": 1e3}


class UnitError(ValueError):
    """The balance shows a unit that is neither a mass nor a force (pieces, percent...)."""


def to_si(value: float, unit: str) -> tuple[str, float, str]:
    """Convert a displayed value to SI: returns ``(quantity, value_si, si_unit)``.

    ``to_si(12.34, "g") == ("mass", 0.01234, "kg")``; ``to_si(0.5, "N") == ("force", 0.5, "N")``.
    Raises :class:`UnitError` for counting/percent units (``PC``, ``%``, ``DS``...).
    """
    unit = unit.strip()
    if unit in N_PER_UNIT:
        return "force", value * N_PER_UNIT[unit], "N"
    if unit in KG_PER_UNIT:
        return "mass", value * KG_PER_UNIT[unit], "kg"
    raise UnitError(
        f"unit {unit!r} is neither a mass nor a force; set the balance to g, kg or N"
    )
