"""Rig files (``rigs/*.toml``): which devices sit on which port, the magnets, the limits.

* :mod:`labkit.rig.config` - the dataclasses, validation and units (imports no device);
* :mod:`labkit.rig.against_drivers` - :func:`parse_rig` / :func:`load_rig`: the config checked
  against the driver registry and the emulators;
* :mod:`labkit.rig.open` - :func:`open_rig` and the typed :class:`OpenRig`;
* caps, role names and the table reader: :mod:`labkit.rig.checks`; the unit-suffix table:
  :data:`labkit.units.UNIT_SUFFIXES`.

Keys are documented in docs/reference/rig-files.md. The names of ``against_drivers`` and ``open`` load
on first use, so ``import labkit.rig.config`` (predict, report) pulls in no device code.
"""


from labkit.lazy import lazy_attributes
from labkit.rig.checks import (
    MAX_CONTROL_PERIOD_S,
    MAX_DURATION_S,
    MAX_RAMP_RPM_PER_S,
    MAX_RIG_FILE_BYTES,
    MAX_SPEED_RPM,
    MAX_TACH_TIMEOUT_S,
    ROLE_PATTERN,
    UNIT_SUFFIXES,
    check_role,
    read_rig_text,
    split_unit,
)
from labkit.rig.config import (
    KINDS,
    SERIAL_KEYS,
    SHAPES,
    BodySpec,
    ControlSettings,
    DeviceCheck,
    DeviceConfig,
    Geometry,
    Limits,
    LoopConfig,
    Rig,
    bundled_rig_names,
    bundled_rig_path,
    find_rig_file,
    parse_body,
    parse_rig_config,
)

_LAZY = {**{name: "labkit.rig.against_drivers" for name in ("DriverCheck", "load_rig", "parse_rig")},
         **{name: "labkit.rig.open" for name in ("OpenRig", "PortOpener", "open_rig")}}


__getattr__ = lazy_attributes(__name__, _LAZY)


#: the old name of :class:`BodySpec` (ADR docs/decisions/0007-names.md); kept for scripts
Body = BodySpec

__all__ = [
    "KINDS", "MAX_CONTROL_PERIOD_S", "MAX_DURATION_S", "MAX_RAMP_RPM_PER_S", "MAX_RIG_FILE_BYTES",
    "MAX_SPEED_RPM", "MAX_TACH_TIMEOUT_S", "ROLE_PATTERN", "SERIAL_KEYS", "SHAPES", "UNIT_SUFFIXES",
    "Body", "BodySpec", "ControlSettings", "DeviceCheck", "DeviceConfig", "DriverCheck", "Geometry",
    "Limits", "LoopConfig", "OpenRig", "PortOpener", "Rig", "bundled_rig_names", "bundled_rig_path",
    "check_role", "find_rig_file", "load_rig", "open_rig", "parse_body", "parse_rig", "parse_rig_config",
    "read_rig_text", "split_unit",
]
