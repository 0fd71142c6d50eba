"""The device kinds as typed protocols: what a protocol step may ask of a balance, a
tachometer and a camera, checked statically (mypy) and, by method name, at run time.

The abstract classes of :mod:`labkit.devices.base` (``Balance``, ``Tachometer``) satisfy them;
so does a plugin driver (``labkit.drivers`` entry point) that subclasses only ``Device`` but
has the methods. :class:`labkit.protocols.runner.RunContext` hands devices out through them
(``ctx.balance(role)``, ``ctx.tachometer(role)``, ``ctx.camera(role)``).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

from labkit.readings import Reading


@runtime_checkable
class BalanceKind(Protocol):
    """A balance or load cell (kind ``balance``)."""

    name: str

    def read(self, timeout: float = 2.0) -> Reading: ...

    def read_stable(self, timeout: float = 20.0) -> Reading: ...

    def zero(self, timeout: float = 20.0) -> None: ...


@runtime_checkable
class TachometerKind(Protocol):
    """A streaming tachometer (kind ``tach``)."""

    name: str

    def latest(self) -> Reading | None: ...

    def readings_since(self, t: float) -> list[Reading]: ...


@runtime_checkable
class CameraKind(Protocol):
    """A camera (kind ``camera``): bursts of frames at its settings."""

    name: str
    settings: Any

    def burst(self, n: int, step: Any = None) -> list[Any]: ...


@runtime_checkable
class StrobeKind(Protocol):
    """A stroboscope locked to the rotor (kind ``strobe``, docs/reference/devices-strobe.md)."""

    name: str

    def set_offset(self, offset_hz: float) -> None: ...

    def set_divider(self, divider: int) -> None: ...

    def lamp(self, on: bool) -> None: ...

    def statuses_since(self, t: float) -> list[Any]: ...
