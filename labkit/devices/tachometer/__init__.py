"""Tachometer drivers; importing the package registers them (``lutron16``, ``labkit_tach``)."""

from labkit.devices.tachometer import labkit_tach, lutron16  # noqa: F401
