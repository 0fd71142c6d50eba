"""The one reading shape: a device's measurement (:class:`Reading`) and what its flags mean
(:data:`READING_FLAGS`).

Below every part that handles readings (devices, documents, session, stream: the layer order
in tests/architecture/test_import_rules.py), so a reading's shape is declared once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

#: What each reading flag a driver sets means, and whether the value may be wrong because of
#: it (``True``: the report warns; ``False``: informational). A flag not listed is treated as
#: a warning.
READING_FLAGS: dict[str, tuple[bool, str]] = {
    "device_reset": (True, "the device rebooted mid-run (its banner came again)"),
    "reset": (True, "the device restarted (its sequence counter started over)"),
    "tare_lost": (True, "the device re-tared itself: its zero is no longer the run's zero"),
    "overload": (True, "above the device's range: no value"),
    "underload": (True, "below the device's range: no value"),
    "over_range": (True, "above the tachometer's range: no value"),
    "noisy": (True, "the device marked the value noisy (not stable)"),
    "stability_unknown": (False, "the device does not say whether a value is stable"),
    "zero_speed": (False, "the tachometer sees no rotation (0 RPM)"),
}


@dataclass(frozen=True)
class Reading:
    """One measurement, SI inside (docs/explanation/architecture.md#si-inside).

    ``t`` is the clock time (s) at which the bytes were received; ``quantity`` is e.g.
    ``"force"``, ``"mass"``, ``"angular_speed"``; ``value`` is in ``unit`` (SI: N, kg,
    rad/s); ``raw`` are the bytes of the frame it was parsed from.
    """

    t: float
    quantity: str
    value: float
    unit: str
    stable: bool = True
    overload: bool = False
    raw: bytes = b""
    device: str = ""
    flags: frozenset[str] = field(default_factory=frozenset)

    def as_json(self) -> dict[str, Any]:
        """The probe's JSON object: keys t, value, unit, stable, overload, flags, raw (+ quantity).

        A non-finite value (overload) is ``None`` so the object stays valid JSON. ``flags`` lists
        what the driver noticed besides the value (e.g. ``device_reset``, ``tare_lost``)."""
        return {
            "t": self.t,
            "quantity": self.quantity,
            "value": self.value if math.isfinite(self.value) else None,
            "unit": self.unit,
            "stable": self.stable,
            "overload": self.overload,
            "flags": sorted(self.flags),
            "raw": self.raw.decode("latin-1"),
        }

    @classmethod
    def from_json(cls, obj: dict[str, Any]) -> Reading:
        """The reading :meth:`as_json` wrote (``value`` None reads back as NaN; files written
        before flags and raw were recorded read back with none)."""
        value = obj.get("value")
        return cls(t=float(obj["t"]), quantity=str(obj.get("quantity", "")),
                   value=float("nan") if value is None else float(value), unit=str(obj.get("unit", "")),
                   stable=bool(obj.get("stable", True)), overload=bool(obj.get("overload", False)),
                   raw=str(obj.get("raw", "")).encode("latin-1"), device=str(obj.get("device", "")),
                   flags=frozenset(obj.get("flags") or ()))
