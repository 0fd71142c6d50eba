"""``sim://<protocol>?seed=..&faults=..``: an emulator behind a serial port."""

from labkit.emulators.sim_port import serial_class_for_url

__all__ = ["serial_class_for_url"]
