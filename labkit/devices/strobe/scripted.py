"""A fixed, scripted strobe session: what strobe cassettes are recorded with.

Running the same script on a ``record://`` port (emulator, the sketch on simavr, or a real
strobe) and later on the ``replay://`` port of its cassette must give the same status lines;
the tests and ``analysis/record_cassettes_strobe.py`` share this one definition.
"""

from __future__ import annotations

from typing import Any, cast

import serial

from labkit.devices.registry import driver_class
from labkit.devices.strobe.labkit_strobe import Strobe
from labkit.devices.strobe.protocol import StrobeStatus
from labkit.io.clock import Clock


def status_record(status: StrobeStatus) -> dict[str, Any]:
    """A status as a JSON-able dict (what the tests compare)."""
    out = status.as_json()
    out.pop("quantity")
    return out


def run_strobe_script(port: serial.SerialBase, clock: Clock, statuses: int = 4,
                      timeout_s: float = 10.0, **options: Any) -> dict[str, Any]:
    """Open the ``labkit_strobe`` driver on ``port``, identify, read ``statuses`` status
    lines, switch to divider 2, read as many again, switch the lamp off (its OK ends the
    session), close. Counting lines, not seconds, keeps a real-clock recording replayable.

    Returns ``{"identify": {...}, "statuses": [status_record, ...]}``.
    """
    cls = cast("type[Strobe]", driver_class("strobe", "labkit_strobe"))
    got: list[StrobeStatus] = []
    with cls(port, clock, name="strobe labkit_strobe", **options) as strobe:
        info = strobe.identify()
        for divider in (1, 2):
            strobe.set_divider(divider)
            start = clock.now()
            while len(strobe.statuses_since(start)) < statuses:
                strobe.wait_status(timeout=timeout_s)
            got += strobe.statuses_since(start)[:statuses]
        strobe.lamp(False)
    return {"identify": info, "statuses": [status_record(s) for s in got]}
