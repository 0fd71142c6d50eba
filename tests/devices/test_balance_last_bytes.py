"""``last_bytes`` of the line-based balance drivers is the tail their LineLink received
(one LinkTailMixin for MT-SICS, A&D and the HX711 sketches), so DeviceErrors raised from
any layer quote the same bytes."""

from __future__ import annotations

import pytest

from labkit.devices.registry import driver_class
from labkit.io.clock import VirtualClock
from labkit.io.ports import open_port

BALANCES = {
    "mtsics": ("sim://mtsics?seed=2&plant=tail", {}, {}),
    "and_std": ("sim://and_std?seed=2&plant=tail", {"baudrate": 2400, "bytesize": 7, "parity": "E"}, {}),
    "line_regex": ("sim://hx711?seed=2&plant=tail&startup_s=0.2", {"baudrate": 57600}, {}),
}


@pytest.mark.parametrize("protocol", sorted(BALANCES))
def test_last_bytes_is_the_tail_of_the_reading_line(protocol):
    url, serial_settings, options = BALANCES[protocol]
    clock = VirtualClock()
    port = open_port(url, clock=clock, timeout=0, **serial_settings)
    balance = driver_class("balance", protocol)(port, clock, name="bal", **options)
    try:
        reading = balance.read(timeout=5.0)
        assert reading.raw and reading.raw in balance.last_bytes  # the line just read is in the tail
        assert balance.last_bytes == balance.link.last_bytes
        balance.last_bytes = b"ignored"  # the base class assigns it; the link keeps the tail
        assert balance.last_bytes == balance.link.last_bytes
    finally:
        balance.close()
