"""A fixed, scripted tachometer session: what cassettes of tachometers are recorded with.

Running the same script on a ``record://`` port (emulator or real device) and later on the
``replay://`` port of its cassette must give the same readings; the tests and
``analysis/record_cassettes_tach_motor.py`` share this one definition.
"""

from __future__ import annotations

from typing import Any, cast

import serial

from labkit.devices.base import Tachometer
from labkit.devices.registry import driver_class
from labkit.io.clock import Clock
from labkit.readings import Reading


def reading_record(reading: Reading) -> dict[str, Any]:
    """A reading as a JSON-able dict (all fields, raw bytes as latin-1 text)."""
    return {"t": reading.t, "value": reading.value, "unit": reading.unit, "stable": reading.stable,
            "overload": reading.overload, "flags": sorted(reading.flags),
            "raw": reading.raw.decode("latin-1")}


def run_tach_script(port: serial.SerialBase, clock: Clock, protocol: str,
                    duration_s: float = 2.0, **options: Any) -> dict[str, Any]:
    """Open the ``protocol`` driver on ``port``, identify, read for ``duration_s``, close.

    Returns ``{"identify": {...}, "readings": [reading_record, ...]}``.
    """
    cls = cast("type[Tachometer]", driver_class("tachometer", protocol))
    with cls(port, clock, name=f"tach {protocol}", **options) as tach:
        info = tach.identify()
        start = clock.now()
        clock.sleep(duration_s)
        readings = tach.readings_since(start - 1e9)
    return {"identify": info, "readings": [reading_record(r) for r in readings]}
