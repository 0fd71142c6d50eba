"""Stroboscope drivers (device kind ``strobe``); importing the package registers them
(``labkit_strobe``, docs/devices-strobe.md)."""

from labkit.devices.strobe import labkit_strobe  # noqa: F401
