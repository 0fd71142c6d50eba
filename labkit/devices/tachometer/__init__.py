"""Tachometer drivers; importing the package registers them
(``lutron16``, ``labkit_tach``, ``monarch_at``)."""

from labkit.devices.tachometer import labkit_tach, lutron16, monarch  # noqa: F401
