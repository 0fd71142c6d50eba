"""What a protocol declares about its parameters and its row, as its run's start document
carries it (ADR 0021): :func:`param_specs` gives every parameter with the unit of its suffix,
its default and its bounds (the protocol's ``bounds`` within the caps of the suffix,
:mod:`labkit.protocols.params`), and :func:`declaration_of` the start document's
``param_specs``, ``row`` and ``hints`` (types: :mod:`labkit.hints`).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

from labkit.hints import Column
from labkit.units import RAD_S_PER_RPM

#: parameter-name suffix -> the unit it is given in (``--set speeds_rpm=...``)
PARAM_UNITS: dict[str, str] = {"rad_s": "rad/s", "rpm": "RPM", "pct": "%", "s": "s", "g": "g",
                               "mm": "mm", "hz": "Hz", "n": "N"}


@dataclass(frozen=True)
class Param:
    """One parameter: its default, the unit of its suffix and its bounds (None: no bound)."""

    name: str
    default: Any
    unit: str = ""
    low: float | None = None
    high: float | None = None


#: the key the runner adds to every row
STEP_COLUMN = Column("step", "", "index of the step in the plan (added by the runner)")


def unit_of(name: str) -> str:
    """The unit of a parameter from its suffix (``record_s`` -> ``s``), "" for none."""
    for suffix in sorted(PARAM_UNITS, key=len, reverse=True):
        if name.endswith("_" + suffix):
            return PARAM_UNITS[suffix]
    return ""


def suffix_caps(name: str) -> tuple[float | None, float | None]:
    """The bounds every parameter with this suffix obeys (:mod:`labkit.protocols.params`)."""
    from labkit.rig import MAX_DURATION_S, MAX_SPEED_RPM

    if name.endswith("_rad_s"):
        cap = MAX_SPEED_RPM * RAD_S_PER_RPM
        return -cap, cap
    if name.endswith("_rpm"):
        return -MAX_SPEED_RPM, MAX_SPEED_RPM
    if name.endswith("_s"):
        return 0.0, MAX_DURATION_S
    return None, None


def param_specs(defaults: dict[str, Any], bounds: dict[str, tuple[float | None, float | None]]
                ) -> tuple[Param, ...]:
    """Every parameter with its unit and bounds: the declared ``bounds`` within the caps of
    its suffix (a declared bound never widens a cap)."""
    out = []
    for name, default in defaults.items():
        low, high = suffix_caps(name)
        d_low, d_high = bounds.get(name, (None, None))
        low = d_low if low is None else (low if d_low is None else max(low, d_low))
        high = d_high if high is None else (high if d_high is None else min(high, d_high))
        out.append(Param(name, default, unit_of(name), low, high))
    return tuple(out)


def declaration_of(protocol: Any) -> dict[str, Any]:
    """The start document's ``param_specs``, ``row`` and ``hints`` for a protocol object (a
    protocol that declares no hints gets None, the legacy table's for old names)."""
    hints = getattr(protocol, "hints", None)
    row = tuple(getattr(protocol, "row", ()))
    if row and STEP_COLUMN.name not in {c.name for c in row}:
        row = (STEP_COLUMN, *row)
    params = param_specs(protocol.defaults, getattr(protocol, "bounds", {}))
    return {"param_specs": [asdict(p) for p in params],
            "row": [asdict(c) for c in row], "hints": hints.to_json() if hints is not None else None}
