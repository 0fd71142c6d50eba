"""Units used across labkit (SI inside; these convert at the edges): the one place a value
changes unit (a reading's force, speeds in RPM, table columns).

Balances' display units become SI here too (:func:`to_si`: a mass in kg, a force in N).
One definition each, so a rig file, a data table, a driver, an emulator and a plot agree to
the last bit. :data:`UNIT_SUFFIXES` is the one table of unit suffixes in names: rig-file keys
(``max_speed_rpm``, via :mod:`labkit.rig.checks`) and the columns of fit tables (``speed_rpm``,
``force_gf``, via :func:`column_to_si`) are read with it. ``_g`` is grams of *mass* and
``_gf`` grams-*force* (docs/reference/rig-files.md, docs/reference/fitting.md).
"""

from __future__ import annotations

import math

#: rad/s per mechanical revolution per minute
RAD_S_PER_RPM = 2.0 * math.pi / 60.0
#: m/s^2, standard gravity (grams-force -> newtons)
G0 = 9.80665

#: name suffix -> (SI unit, factor to SI). The longest matching suffix wins.
UNIT_SUFFIXES: dict[str, tuple[str, float]] = {
    "rpm_per_s": ("rad/s^2", RAD_S_PER_RPM),
    "rad_s2": ("rad/s^2", 1.0),
    "rpm": ("rad/s", RAD_S_PER_RPM),
    "hz": ("rad/s", 2.0 * math.pi),       # revolutions per second
    "rad_s": ("rad/s", 1.0),
    "kg_m2": ("kg m^2", 1.0),
    "g_mm2": ("kg m^2", 1e-9),
    "a_m2": ("A m^2", 1.0),
    "kg": ("kg", 1.0),
    "g": ("kg", 1e-3),                    # grams of mass
    "mm": ("m", 1e-3),
    "m": ("m", 1.0),
    "deg": ("rad", math.pi / 180.0),
    "rad": ("rad", 1.0),
    "ms": ("s", 1e-3),
    "s": ("s", 1.0),
    "gf": ("N", 1e-3 * G0),               # grams-force (what a balance shows)
    "n": ("N", 1.0),
}
#: SI unit -> the suffix a converted name gets
SI_SUFFIXES: dict[str, str] = {
    "rad/s^2": "rad_s2", "rad/s": "rad_s", "kg m^2": "kg_m2", "A m^2": "a_m2", "kg": "kg",
    "m": "m", "rad": "rad", "s": "s", "N": "n",
}
#: In data tables (fit inputs, session results) a ``_g`` column has always held a balance
#: reading, i.e. grams-force; it is read as ``_gf``. New tables write ``_gf``.
TABLE_SUFFIX_ALIASES: dict[str, str] = {"g": "gf"}


def split_suffix(name: str) -> tuple[str, str] | None:
    """``"mass_g"`` -> ``("mass", "g")``: the longest unit suffix of ``name`` (any case), or None."""
    lowered = name.lower()
    for suffix in sorted(UNIT_SUFFIXES, key=len, reverse=True):
        if lowered.endswith("_" + suffix):
            return name[: -len(suffix) - 1], suffix
    return None


def column_to_si(name: str) -> tuple[str, float]:
    """A data-table column name -> (its SI name, factor): ``speed_rpm`` -> (``speed_rad_s``,
    0.1047...), ``force_gf`` and the older ``force_g`` -> (``force_n``, 9.80665e-3).
    A name without a unit suffix is returned unchanged with factor 1."""
    split = split_suffix(name)
    if split is None:
        return name, 1.0
    base, suffix = split
    suffix = TABLE_SUFFIX_ALIASES.get(suffix, suffix)
    unit, factor = UNIT_SUFFIXES[suffix]
    return f"{base}_{SI_SUFFIXES[unit]}", factor


def rpm_to_rad_s(rpm: float) -> float:
    """Mechanical RPM -> rad/s."""
    return rpm * RAD_S_PER_RPM


def rad_s_to_rpm(rad_s: float) -> float:
    """rad/s -> mechanical RPM."""
    return rad_s / RAD_S_PER_RPM


def n_to_gf(newtons: float) -> float:
    """N -> grams-force (what a balance shows; Fig. 5.25's axis): ``n / G0 * 1e3``."""
    return newtons / G0 * 1e3


def gf_to_n(grams: float) -> float:
    """Grams-force (or a mass in grams weighed under standard gravity) -> N."""
    return grams * 1e-3 * G0


def force_n(value: float, unit: str) -> float:
    """A balance's value in its SI ``unit`` as a force (N): ``N`` as it is, ``kg`` a mass under
    standard gravity. ValueError for any other unit (the caller names the device)."""
    if unit == "N":
        return float(value)
    if unit == "kg":
        return float(value) * G0
    raise ValueError(f"cannot use a value in {unit!r} as a force (N or kg)")


def force_gf(value: float, unit: str) -> float:
    """A balance's value in its SI ``unit`` in grams-force: ``kg`` x 1000 (the mass in grams),
    ``N`` via :func:`n_to_gf`. ValueError for any other unit."""
    if unit == "kg":
        return float(value) * 1000.0
    return n_to_gf(force_n(value, unit))


# ---- a balance's display unit -> SI (docs/reference/devices-balance.md) -----------------------
# A balance shows either a mass (g, kg, oz, ...) or, on force-capable models (A&D ``N``, the
# labkit HX711 sketch), a force. labkit keeps what the device measured: a force unit becomes
# ``quantity="force"`` in N; a mass unit becomes ``quantity="mass"`` in kg. The conversion of a
# mass reading to the PFR force (Fig. 5.25: grams-force) is :func:`force_n` / :func:`force_gf`.

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
