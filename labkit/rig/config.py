"""Rig files (``rigs/*.toml``) as data: the dataclasses, their validation and units, bundled rigs.

:func:`parse_rig_config` validates rig-file text and converts every unit-suffixed key to SI
(``max_speed_rpm = 24000`` -> ``limits.max_speed_rad_s = 2513.3``, one table:
:data:`labkit.units.UNIT_SUFFIXES`). Every problem raises :class:`labkit.errors.RigFileError`
as ``file:key: reason``. This module imports no device, emulator or port code: checking a
rig against the driver registry and the emulators is :mod:`labkit.rig.against_drivers`,
opening it :mod:`labkit.rig.open`. Keys are documented in ``docs/reference/rig-files.md``; caps, role
names and the table reader live in :mod:`labkit.rig.checks`.
"""

from __future__ import annotations

import math
import tomllib
import urllib.parse
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any, Protocol

from labkit.device_kinds import DEVICE_KINDS, OLD_KIND_WORDS, canonical_kind
from labkit.errors import RigFileError
from labkit.rig.checks import (
    MAX_CONTROL_PERIOD_S,
    MAX_DURATION_S,
    MAX_TACH_TIMEOUT_S,
    MIN_CONTROL_PERIOD_S,
    TableSection,
    check_finite,
    check_rate_options,
    check_role,
    check_toml_shape,
    split_unit,
)
from labkit.rig.plausible import check_plausible

KINDS = DEVICE_KINDS
SHAPES = ("sphere", "cylinder", "ring", "block", "cube")

class DeviceCheck(Protocol):
    """Checks of a device against code outside the config (drivers, emulators); each raises
    ``sec.error(key, reason)``. Implemented by :class:`labkit.rig.against_drivers.DriverCheck`."""

    def protocol(self, sec: TableSection, kind: str, protocol: str) -> None: ...
    def port(self, sec: TableSection, url: str) -> None: ...
    def options(self, sec: TableSection, kind: str, protocol: str, port: str,
                options: dict[str, Any]) -> None: ...


SERIAL_KEYS: dict[str, type | tuple[type, ...]] = {
    "baudrate": int, "bytesize": int, "parity": str, "stopbits": (int, float),
    "timeout": (int, float), "write_timeout": (int, float), "xonxoff": bool, "rtscts": bool,
}


# ---- the loaded rig -----------------------------------------------------------------------
@dataclass(frozen=True)
class DeviceConfig:
    """One device of a rig, by role (``rotor_motor``, ``rotor_tach``, ``balance``...)."""

    role: str
    kind: str                      # "balance" | "tachometer" | "motor" | "camera" | "strobe"
    protocol: str                  # driver registry name, e.g. "mtsics"
    port: str                      # URL for serial_for_url / labkit.io.open_port
    serial: dict[str, Any] = field(default_factory=dict)
    options: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class BodySpec:
    """A magnet (rotator or floator) as a rig file declares it. SI: m, kg, kg m^2, A m^2, rad.

    (Not :class:`labkit.sim.scene.SceneBody`, a body placed in a simulated scene.)
    """

    name: str
    shape: str
    diameter_m: float | None = None
    length_m: float | None = None
    width_m: float | None = None
    mass_kg: float | None = None
    inertia_axial_kg_m2: float | None = None
    inertia_radial_kg_m2: float | None = None
    dipole_moment_a_m2: float | None = None
    tilt_rad: float = 0.0
    grade: str = ""


@dataclass(frozen=True)
class Geometry:
    axis: str = "vertical"
    gap_m: float | None = None            # rotator centre to floator centre
    balance_under: str = "rotator"        # what the balance carries: "rotator" | "floator"
    break_phi_rad: float | None = None    # fixes the Fig. 6.18 break-up cone angle (model plant)


@dataclass(frozen=True)
class Limits:
    """Safety limits. The runner refuses plans beyond them before any motor turns."""

    max_speed_rad_s: float
    max_ramp_rad_s2: float
    max_duty: float = 1.0
    overspeed_margin: float = 0.05        # trip when the tach reads above max_speed*(1+margin)


@dataclass(frozen=True)
class LoopConfig:
    """A speed loop: which motor is steered by which tachometer."""

    name: str
    motor: str
    tach: str


@dataclass(frozen=True)
class ControlSettings:
    """Speed-loop gains and interlock timings (see :mod:`labkit.control`)."""

    period_s: float = 0.05
    full_speed_rad_s: float = 2500.0      # feed-forward: duty = target / full_speed
    kp: float = 2e-4                      # duty per rad/s of error
    ki: float = 4e-4                      # duty per rad of integrated error
    settle_tolerance_rad_s: float = 10.0
    settle_hold_s: float = 1.0
    settle_timeout_s: float = 30.0
    tach_timeout_s: float = 0.5           # tachometer silent this long -> interlock
    status_period_s: float = 0.25         # how often controller error flags are read
    # plausibility of the tachometer against the duty (labkit.control.plausibility, ADR 0017)
    motor_tau_s: float = 0.4              # the motor's mechanical time constant
    plausible_ratio: float = 2.0          # reading within [floor/ratio - slack, ceiling*ratio + slack]
    plausible_slack_rad_s: float = 1000.0 * math.pi / 30.0   # 1000 RPM
    plausible_hold_s: float = 0.3         # a violation this long trips
    spin_up_grace_s: float = 1.5          # duty on this long before "reads too low" applies
    tach_stuck_s: float = 1.0             # the same reading this long while driven: stuck
    stall_s: float = 2.0                  # saturated duty, rotor below half its speed: stall
    loops: tuple[LoopConfig, ...] = ()


@dataclass(frozen=True)
class Rig:
    path: Path
    name: str
    description: str
    devices: dict[str, DeviceConfig]
    bodies: dict[str, BodySpec]
    geometry: Geometry
    limits: Limits
    control: ControlSettings
    text: str = ""                        # the file as read (copied into sessions)

    def devices_of(self, kind: str) -> dict[str, DeviceConfig]:
        kind = canonical_kind(kind)
        return {r: d for r, d in self.devices.items() if d.kind == kind}

    def require(self, role: str, kind: str, needed_by: str) -> DeviceConfig:
        """The device ``role`` of ``kind`` (an old word such as ``tach`` names its kind), or a
        RigFileError saying who needs it."""
        kind = canonical_kind(kind)
        dev = self.devices.get(role)
        if dev is None or dev.kind != kind:
            raise RigFileError(str(self.path), f"devices.{role}",
                               f"{needed_by} needs a {kind} device called {role!r}")
        return dev


def _check_port_url(sec: TableSection, url: str, check_device: DeviceCheck | None) -> None:
    if not url.strip():
        raise sec.error("port", "empty port URL")
    scheme = urllib.parse.urlsplit(url).scheme
    if scheme == "" and not url.startswith("/") and not url.upper().startswith("COM"):
        raise sec.error("port", f"{url!r} is neither a device path nor a URL (sim://, socket://, ...)")
    if check_device is not None:
        check_device.port(sec, url)


def _device(file: str, role: str, table: Any, check_device: DeviceCheck | None) -> DeviceConfig:
    check_role(file, f"devices.{role}", role)
    sec = TableSection(file, f"devices.{role}", table)
    kind = canonical_kind(sec.raw("kind", str, required=True))  # "tach" (older files) is "tachometer"
    if kind not in KINDS:
        old = ", ".join(f"{w!r} for {k!r}" for w, k in OLD_KIND_WORDS.items())
        raise sec.error("kind", f"must be one of {', '.join(KINDS)} (also read: {old}), got {kind!r}")
    protocol = sec.raw("protocol", str, required=True)
    if check_device is not None:
        check_device.protocol(sec, kind, protocol)
    port = sec.raw("port", str, required=True)
    _check_port_url(sec, port, check_device)
    serial = dict(sec.raw("serial", dict, default={}))
    ssec = TableSection(file, sec.key("serial"), serial)
    for name, typ in SERIAL_KEYS.items():
        ssec.raw(name, typ)
    ssec.finish()
    if "bytesize" in serial and serial["bytesize"] not in (5, 6, 7, 8):
        raise ssec.error("bytesize", f"must be 5..8, got {serial['bytesize']}")
    if "parity" in serial:
        serial["parity"] = serial["parity"].upper()
        if serial["parity"] not in ("N", "E", "O", "M", "S"):
            raise ssec.error("parity", f"must be N, E, O, M or S, got {serial['parity']!r}")
    if "stopbits" in serial and serial["stopbits"] not in (1, 1.5, 2):
        raise ssec.error("stopbits", f"must be 1, 1.5 or 2, got {serial['stopbits']}")
    if "baudrate" in serial and serial["baudrate"] <= 0:
        raise ssec.error("baudrate", f"must be > 0, got {serial['baudrate']}")
    for name in ("timeout", "write_timeout"):
        if name in serial and not 0 <= serial[name] <= MAX_DURATION_S:
            raise ssec.error(name, f"must be in [0, {MAX_DURATION_S:.0f}] s, got {serial[name]}")
    options = dict(sec.raw("options", dict, default={}))
    check_finite(sec, "options", options)
    check_rate_options(sec, "options", options)
    for name, value in options.items():
        scale = 1.0 if name.endswith("_s") else 1e3 if name.endswith("_ms") else None
        if scale is not None and isinstance(value, int | float) and not isinstance(value, bool) \
                and not 0 <= value <= MAX_DURATION_S * scale:
            raise sec.error(f"options.{name}", f"must be in [0, {MAX_DURATION_S * scale:.0f}], got {value!r}")
    if check_device is not None:
        check_device.options(sec, kind, protocol, port, options)
    sec.finish()
    return DeviceConfig(role, kind, protocol, port, serial, options)


def _body(file: str, name: str, table: Any) -> BodySpec:
    sec = TableSection(file, f"bodies.{name}", table)
    shape = sec.raw("shape", str, required=True)
    if shape not in SHAPES:
        raise sec.error("shape", f"must be one of {', '.join(SHAPES)}, got {shape!r}")
    body = BodySpec(
        name=name, shape=shape,
        diameter_m=sec.quantity("diameter", "m"),
        length_m=sec.quantity("length", "m"),
        width_m=sec.quantity("width", "m"),
        mass_kg=sec.quantity("mass", "kg"),
        inertia_axial_kg_m2=sec.quantity("inertia_axial", "kg m^2"),
        inertia_radial_kg_m2=sec.quantity("inertia_radial", "kg m^2"),
        dipole_moment_a_m2=sec.quantity("dipole_moment", "A m^2"),
        tilt_rad=sec.quantity("tilt", "rad", default=0.0, positive=False) or 0.0,
        grade=sec.raw("grade", str, default=""),
    )
    if abs(body.tilt_rad) >= math.pi / 2:
        raise sec.error("tilt_deg", "must be below 90 degrees")
    sec.finish()
    return body


def parse_body(file: str, name: str, table: Any) -> BodySpec:
    """Validate one ``[bodies.NAME]`` table on its own (``labkit predict`` reads only the
    bodies of a rig file). Raises RigFileError as ``file:bodies.NAME.key: reason``."""
    return _body(file, name, table)


def _control(file: str, table: Any, devices: dict[str, DeviceConfig]) -> ControlSettings:
    sec = TableSection(file, "control", table)
    d = ControlSettings()
    loops_raw = sec.raw("loops", list, default=None)
    values = dict(
        period_s=sec.quantity("period", "s", default=d.period_s,
                              cap=(MAX_CONTROL_PERIOD_S, f"{MAX_CONTROL_PERIOD_S:g} s")),
        full_speed_rad_s=sec.quantity("full_speed", "rad/s", default=d.full_speed_rad_s),
        settle_tolerance_rad_s=sec.quantity("settle_tolerance", "rad/s", default=d.settle_tolerance_rad_s),
        settle_hold_s=sec.quantity("settle_hold", "s", default=d.settle_hold_s, allow_zero=True),
        settle_timeout_s=sec.quantity("settle_timeout", "s", default=d.settle_timeout_s),
        tach_timeout_s=sec.quantity("tach_timeout", "s", default=d.tach_timeout_s,
                                    cap=(MAX_TACH_TIMEOUT_S, f"{MAX_TACH_TIMEOUT_S:g} s")),
        status_period_s=sec.quantity("status_period", "s", default=d.status_period_s),
        **_plausibility(sec, d),
    )
    for base in ("period", "status_period"):  # a loop every nanosecond is a run that never ends
        if values[base + "_s"] < MIN_CONTROL_PERIOD_S:
            key = next(k for k in sec.table if (s := split_unit(k)) and s[0] == base)
            raise sec.error(key, f"{sec.table[key]!r} is below the floor of "
                                 f"{MIN_CONTROL_PERIOD_S * 1e3:g} ms (no serial device answers faster)")
    for gain in ("kp", "ki"):
        v = sec.raw(gain, (int, float), default=getattr(d, gain))
        if v < 0:
            raise sec.error(gain, f"must be >= 0, got {v}")
        values[gain] = float(v)
    sec.finish()
    loops: list[LoopConfig] = []
    if loops_raw is None:
        for role, dev in devices.items():
            if dev.kind == "motor" and role.endswith("_motor"):
                tach = role[: -len("_motor")] + "_tach"
                if tach in devices and devices[tach].kind == "tachometer":
                    loops.append(LoopConfig(role[: -len("_motor")], role, tach))
    else:
        for i, item in enumerate(loops_raw):
            lsec = TableSection(file, f"control.loops[{i}]", item)
            motor = lsec.raw("motor", str, required=True)
            tach = lsec.raw("tach", str, required=True)
            name = lsec.raw("name", str, default=motor.removesuffix("_motor"))
            check_role(file, lsec.key("name"), name)
            lsec.finish()
            for key, role, kind in (("motor", motor, "motor"), ("tach", tach, "tachometer")):
                if role not in devices or devices[role].kind != kind:
                    raise lsec.error(key, f"{role!r} is not a {kind} device of this rig")
            loops.append(LoopConfig(name, motor, tach))
    return ControlSettings(loops=tuple(loops), **values)


def _plausibility(sec: TableSection, d: ControlSettings) -> dict[str, float]:
    """The ``[control]`` keys of the plausibility interlocks (docs/reference/rig-files.md)."""
    cap = (MAX_TACH_TIMEOUT_S, f"{MAX_TACH_TIMEOUT_S:g} s")
    values = {
        "motor_tau_s": sec.quantity("motor_tau", "s", default=d.motor_tau_s, cap=cap),
        "plausible_slack_rad_s": sec.quantity("plausible_slack", "rad/s", default=d.plausible_slack_rad_s),
        "plausible_hold_s": sec.quantity("plausible_hold", "s", default=d.plausible_hold_s, cap=cap),
        "spin_up_grace_s": sec.quantity("spin_up_grace", "s", default=d.spin_up_grace_s, cap=cap),
        "tach_stuck_s": sec.quantity("tach_stuck", "s", default=d.tach_stuck_s, cap=cap),
        "stall_s": sec.quantity("stall", "s", default=d.stall_s, cap=cap),
    }
    ratio = sec.raw("plausible_ratio", (int, float), default=d.plausible_ratio)
    if not 1.0 < ratio <= 10.0:
        raise sec.error("plausible_ratio", f"must be in (1, 10], got {ratio}")
    values["plausible_ratio"] = float(ratio)
    return values


def parse_rig_config(text: str, file: str = "<rig>", check_device: DeviceCheck | None = None) -> Rig:
    """Validate rig-file text and build a :class:`Rig` (SI inside). Raises RigFileError.

    ``check_device`` (:class:`labkit.rig.against_drivers.DriverCheck`) also checks each device
    against the driver registry and the emulators, at the point of the file it belongs to.
    """
    data = load_toml(text, file)
    top = TableSection(file, "", data)
    rig_sec = TableSection(file, "rig", top.raw("rig", dict, required=True))
    name = rig_sec.raw("name", str, required=True)
    description = rig_sec.raw("description", str, default="")
    rig_sec.finish()

    dev_tables = top.raw("devices", dict, required=True)
    if not dev_tables:
        raise RigFileError(file, "devices", "no devices")
    devices = {role: _device(file, role, t, check_device) for role, t in dev_tables.items()}

    bodies = {n: _body(file, n, t) for n, t in top.raw("bodies", dict, default={}).items()}
    for n in bodies:
        if n not in ("rotator", "floator"):
            raise RigFileError(file, f"bodies.{n}", "unknown body (use rotator or floator)")

    gsec = TableSection(file, "geometry", top.raw("geometry", dict, default={}))
    axis = gsec.raw("axis", str, default="vertical")
    if axis not in ("vertical", "horizontal"):
        raise gsec.error("axis", f"must be vertical or horizontal, got {axis!r}")
    under = gsec.raw("balance_under", str, default="rotator")
    if under not in ("rotator", "floator"):
        raise gsec.error("balance_under", f"must be rotator or floator, got {under!r}")
    break_phi = gsec.quantity("break_phi", "rad")
    if break_phi is not None and break_phi >= math.pi / 2:
        key = next(k for k in gsec.table if k.startswith("break_phi_"))
        raise gsec.error(key, "must be below 90 degrees")
    geometry = Geometry(axis=axis, gap_m=gsec.quantity("gap", "m"), balance_under=under,
                        break_phi_rad=break_phi)
    gsec.finish()

    lsec = TableSection(file, "limits", top.raw("limits", dict, required=True))
    max_duty = lsec.raw("max_duty", (int, float), default=1.0)
    if not 0 < max_duty <= 1:
        raise lsec.error("max_duty", f"must be in (0, 1], got {max_duty}")
    margin = lsec.raw("overspeed_margin", (int, float), default=0.05)
    if not 0 <= margin <= 1:
        raise lsec.error("overspeed_margin", f"must be in [0, 1], got {margin}")
    limits = Limits(
        max_speed_rad_s=lsec.quantity("max_speed", "rad/s", required=True),  # type: ignore[arg-type]
        max_ramp_rad_s2=lsec.quantity("max_ramp", "rad/s^2", required=True),  # type: ignore[arg-type]
        max_duty=float(max_duty), overspeed_margin=float(margin),
    )
    lsec.finish()

    control = _control(file, top.raw("control", dict, default={}), devices)
    top.finish()
    rig = Rig(Path(file), name, description, devices, bodies, geometry, limits, control, text)
    check_plausible(rig, data)
    return rig


def load_toml(text: str, file: str) -> dict[str, Any]:
    """Rig-file text -> tables; a syntax error is a RigFileError at key ``(syntax)``."""
    check_toml_shape(text, file)
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RigFileError(file, "(syntax)", str(exc)) from None
    except RecursionError:
        raise RigFileError(file, "(syntax)", "nested too deeply") from None


def find_rig_file(path: str | Path) -> Path:
    """``path``, or the bundled rig it names (``emulated-fig525``); RigFileError if neither."""
    p = Path(path)
    if not p.exists():
        bundled = bundled_rig_path(str(path))
        if bundled is None:
            raise RigFileError(str(path), "(file)", "no such rig file")
        p = bundled
    return p


def bundled_rig_names() -> list[str]:
    folder = resources.files("labkit") / "data" / "rigs"
    return sorted(f.name[:-5] for f in folder.iterdir() if f.name.endswith(".toml"))


def bundled_rig_path(name: str) -> Path | None:
    """Path of a rig shipped inside the package (works after a plain ``pip install``)."""
    stem = Path(name).name.removesuffix(".toml")
    candidate = resources.files("labkit") / "data" / "rigs" / f"{stem}.toml"
    return Path(str(candidate)) if candidate.is_file() else None
