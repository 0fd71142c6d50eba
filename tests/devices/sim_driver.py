"""Open one driver on its emulator over ``sim://`` (shared by the driver tests)."""

from __future__ import annotations

from labkit.devices.registry import driver_class
from labkit.io.clock import VirtualClock
from labkit.io.ports import open_port


def open_sim_driver(kind: str, protocol: str, plant: str, role: str, query: str = "",
                    clock: VirtualClock | None = None, settings: dict | None = None, **options):
    """``(driver, clock)``: driver ``protocol`` of ``kind`` named ``"<role> (<protocol>)"`` on
    ``sim://<protocol>?plant=<plant><query>``, with the driver's default serial settings."""
    clock = clock or VirtualClock()
    cls = driver_class(kind, protocol)
    port = open_port(f"sim://{protocol}?plant={plant}{query}", clock=clock, timeout=0,
                     **(settings or cls.default_serial))
    return cls(port, clock, name=f"{role} ({protocol})", **options), clock
