"""Stroboscope drivers (device kind ``strobe``); importing the package registers them
(``labkit_strobe``, docs/reference/devices-strobe.md)."""

from labkit.devices.strobe import labkit_strobe  # noqa: F401
