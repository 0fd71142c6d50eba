"""The one reading shape: a device's measurement (:class:`Reading`), what its flags mean
(:data:`READING_FLAGS`) and how a stream of readings is written and read back.

Below every part that handles readings (devices, documents, session, stream: the layer order
in tests/architecture/test_import_rules.py), so a reading's shape is declared once.

A stream of one device's readings declares its quantity and unit once, in a descriptor
(``{"type": "descriptor", "quantity": ..., "unit": ...}``, :class:`labkit.documents.StreamDescriptor`)
before its first reading; each reading then carries its values only (:meth:`Reading.values_json`).
:func:`declared` reads such a stream back, and also one written before descriptors existed, where
every line carried its own quantity and unit (docs/reference/session-format.md,
docs/decisions/0033-one-reading-shape.md).
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator
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

    def values_json(self) -> dict[str, Any]:
        """What a reading of a described stream carries: :meth:`as_json` without ``quantity``
        and ``unit`` (its stream's descriptor declares them once)."""
        out = self.as_json()
        del out["quantity"], out["unit"]
        return out

    @classmethod
    def from_json(cls, obj: dict[str, Any], quantity: str = "", unit: str = "") -> Reading:
        """The reading :meth:`as_json` or :meth:`values_json` wrote (``quantity`` and ``unit``:
        its stream's, for a line without them; ``value`` None reads back as NaN; files written
        before flags and raw were recorded read back with none)."""
        value = obj.get("value")
        return cls(t=float(obj["t"]), quantity=str(obj.get("quantity", quantity)),
                   value=float("nan") if value is None else float(value), unit=str(obj.get("unit", unit)),
                   stable=bool(obj.get("stable", True)), overload=bool(obj.get("overload", False)),
                   raw=str(obj.get("raw", "")).encode("latin-1"), device=str(obj.get("device", "")),
                   flags=frozenset(obj.get("flags") or ()))


#: the ``type`` of a stream's descriptor line (reading lines have no ``type``)
DESCRIPTOR_TYPE = "descriptor"


def declared(lines: Iterable[tuple[int, dict[str, Any]]]) -> Iterator[tuple[int, dict[str, Any]]]:
    """``(line number, reading)`` of a readings stream, each reading with the ``quantity`` and
    ``unit`` of the descriptor before it (a line that carries its own, as every line did before
    descriptors, keeps them). Descriptor lines are not yielded; a reading before any descriptor
    and without its own unit is yielded as it is (a reader says what it lacks)."""
    quantity: Any = None
    unit: Any = None
    for number, row in lines:
        if row.get("type") == DESCRIPTOR_TYPE:
            quantity, unit = row.get("quantity"), row.get("unit")
            continue
        if unit is not None and "unit" not in row:
            row = {"t": row.get("t"), "quantity": quantity, "value": row.get("value"), "unit": unit,
                   **{k: v for k, v in row.items() if k not in ("t", "value")}}
        yield number, row
