"""Motor-controller drivers; importing the package registers them
(``pololu_smc``, ``esc_bridge``, ``vesc``)."""

from labkit.devices.motor import esc_bridge, pololu_smc, vesc  # noqa: F401
