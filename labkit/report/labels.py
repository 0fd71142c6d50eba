"""Axis labels with quantity and unit from column names (``force_g`` -> ``force [g]``)."""

from __future__ import annotations

import re

#: column name -> label (quantity [unit]) for the columns labkit writes
KNOWN = {
    "speed_rpm": "rotor speed [RPM]",
    "force_g": "force [g]",
    "force_n": "force [N]",
    "force_mn": "force [mN]",
    "rotor_rad_s": "rotor speed ω [rad/s]",
    "spin_rad_s": "floator spin v [rad/s]",
    "cone_angle_rad": "cone angle φ [rad]",
    "cone_angle_deg": "cone angle φ [°]",
    "distance_m": "distance r [m]",
    "distance_mm": "distance r [mm]",
    "omega_rad_s": "field speed ω [rad/s]",
}

#: trailing unit of a column name -> unit as printed
UNITS = {"rpm": "RPM", "g": "g", "n": "N", "mn": "mN", "m": "m", "mm": "mm", "rad": "rad", "deg": "°",
         "rad_s": "rad/s", "s": "s", "hz": "Hz", "kg": "kg", "px": "px", "pct": "%"}


def axis_label(column: str) -> str:
    """``quantity [unit]`` for a column name; the name itself when no unit is recognised."""
    if column in KNOWN:
        return KNOWN[column]
    for suffix in sorted(UNITS, key=len, reverse=True):
        if column.endswith("_" + suffix):
            quantity = column[: -len(suffix) - 1].replace("_", " ")
            return f"{quantity} [{UNITS[suffix]}]"
    return column.replace("_", " ")


def residual_label(space: str) -> str:
    """A residual space such as ``ln(force_g)`` with its column written as a label:
    ``ln(force [g])``; a plain column gives ``spin v [rad/s]``."""
    return re.sub(r"[A-Za-z][A-Za-z0-9_]*_[A-Za-z0-9_]+", lambda m: axis_label(m.group(0)), space)
