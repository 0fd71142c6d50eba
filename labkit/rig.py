"""Rig files (``rigs/*.toml``): which devices sit on which port, the magnets, the limits.

:func:`load_rig` reads and validates a rig file and converts every unit-suffixed key to SI
(``max_speed_rpm = 24000`` -> ``limits.max_speed_rad_s = 2513.3``). Every problem raises
:class:`labkit.errors.RigFileError` as ``file:key: reason`` before any port is opened.
:func:`open_rig` opens the ports (optionally through ``record://`` into a session's
cassettes) and instantiates the drivers; closing an :class:`OpenRig` commands every motor
to zero first. Keys are documented in ``docs/rig-files.md``; unit suffixes, caps, role names
and the table reader live in :mod:`labkit.rig_checks`.
"""

from __future__ import annotations

import math
import tomllib
import urllib.parse
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from labkit.errors import RigFileError
from labkit.rig_checks import (  # noqa: F401 - re-exported: labkit.rig is the public module
    MAX_CONTROL_PERIOD_S,
    MAX_DURATION_S,
    MAX_RAMP_RPM_PER_S,
    MAX_RIG_FILE_BYTES,
    MAX_SPEED_RPM,
    MAX_TACH_TIMEOUT_S,
    ROLE_PATTERN,
    UNIT_SUFFIXES,
    _check_finite,
    _Section,
    check_role,
    read_rig_text,
    split_unit,
)

KINDS = ("balance", "tach", "motor")
SHAPES = ("sphere", "cylinder", "ring", "block", "cube")
SERIAL_KEYS: dict[str, type | tuple[type, ...]] = {
    "baudrate": int, "bytesize": int, "parity": str, "stopbits": (int, float),
    "timeout": (int, float), "write_timeout": (int, float), "xonxoff": bool, "rtscts": bool,
}


# ---- the loaded rig -----------------------------------------------------------------------
@dataclass(frozen=True)
class DeviceConfig:
    """One device of a rig, by role (``rotor_motor``, ``rotor_tach``, ``balance``...)."""

    role: str
    kind: str                      # "balance" | "tach" | "motor"
    protocol: str                  # driver registry name, e.g. "mtsics"
    port: str                      # URL for serial_for_url / labkit.io.open_port
    serial: dict[str, Any] = field(default_factory=dict)
    options: dict[str, Any] = field(default_factory=dict)


@dataclass(frozen=True)
class Body:
    """A magnet (rotator or floator). SI: m, kg, kg m^2, A m^2, rad."""

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
    loops: tuple[LoopConfig, ...] = ()


@dataclass(frozen=True)
class Rig:
    path: Path
    name: str
    description: str
    devices: dict[str, DeviceConfig]
    bodies: dict[str, Body]
    geometry: Geometry
    limits: Limits
    control: ControlSettings
    text: str = ""                        # the file as read (copied into sessions)

    def devices_of(self, kind: str) -> dict[str, DeviceConfig]:
        return {r: d for r, d in self.devices.items() if d.kind == kind}

    def require(self, role: str, kind: str, needed_by: str) -> DeviceConfig:
        """The device ``role`` of ``kind``, or a RigFileError saying who needs it."""
        dev = self.devices.get(role)
        if dev is None or dev.kind != kind:
            raise RigFileError(str(self.path), f"devices.{role}",
                               f"{needed_by} needs a {kind} device called {role!r}")
        return dev


def _check_port_url(sec: _Section, url: str) -> None:
    if not url.strip():
        raise sec.error("port", "empty port URL")
    scheme = urllib.parse.urlsplit(url).scheme
    if scheme == "" and not url.startswith("/") and not url.upper().startswith("COM"):
        raise sec.error("port", f"{url!r} is neither a device path nor a URL (sim://, socket://, ...)")
    if scheme == "sim":
        # an emulated device is checked whole here (emulator, seed, fault names), before any
        # port opens, so a typo is a file:key error and not a failed, "resumable" session
        from labkit.emulators.base import emulator_class
        from labkit.emulators.urls import parse_sim_url
        from labkit.errors import PortURLError

        try:
            emulator_class(parse_sim_url(url).protocol)
        except PortURLError as exc:
            raise sec.error("port", exc.reason) from None
        except KeyError as exc:
            raise sec.error("port", str(exc.args[0])) from None


def _device(file: str, role: str, table: Any, check_protocols: bool) -> DeviceConfig:
    check_role(file, f"devices.{role}", role)
    sec = _Section(file, f"devices.{role}", table)
    kind = sec.raw("kind", str, required=True)
    if kind not in KINDS:
        raise sec.error("kind", f"must be one of {', '.join(KINDS)}, got {kind!r}")
    protocol = sec.raw("protocol", str, required=True)
    if check_protocols:
        from labkit.devices.base import driver_class

        try:
            driver_class(kind, protocol)
        except KeyError as exc:
            raise sec.error("protocol", str(exc.args[0])) from None
    port = sec.raw("port", str, required=True)
    _check_port_url(sec, port)
    serial = dict(sec.raw("serial", dict, default={}))
    ssec = _Section(file, sec.key("serial"), serial)
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
    _check_finite(sec, "options", options)
    for name, value in options.items():
        scale = 1.0 if name.endswith("_s") else 1e3 if name.endswith("_ms") else None
        if scale is not None and isinstance(value, int | float) and not isinstance(value, bool) \
                and not 0 <= value <= MAX_DURATION_S * scale:
            raise sec.error(f"options.{name}", f"must be in [0, {MAX_DURATION_S * scale:.0f}], got {value!r}")
    if check_protocols:
        from labkit.devices.base import driver_class, unknown_options, unknown_options_message

        cls = driver_class(kind, protocol)
        unknown = unknown_options(cls, options)
        if unknown:
            raise sec.error(f"options.{unknown[0]}", unknown_options_message(cls, unknown))
        watchdog = getattr(cls, "watchdog_problem", None)  # motors: the controller's own timeout
        if watchdog is not None:
            problem = watchdog(options, required=not port.startswith(("sim://", "replay://")))
            if problem is not None:
                raise sec.error(*problem)
    sec.finish()
    return DeviceConfig(role, kind, protocol, port, serial, options)


def _body(file: str, name: str, table: Any) -> Body:
    sec = _Section(file, f"bodies.{name}", table)
    shape = sec.raw("shape", str, required=True)
    if shape not in SHAPES:
        raise sec.error("shape", f"must be one of {', '.join(SHAPES)}, got {shape!r}")
    body = Body(
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


def parse_body(file: str, name: str, table: Any) -> Body:
    """Validate one ``[bodies.NAME]`` table on its own (``labkit predict`` reads only the
    bodies of a rig file). Raises RigFileError as ``file:bodies.NAME.key: reason``."""
    return _body(file, name, table)


def _control(file: str, table: Any, devices: dict[str, DeviceConfig]) -> ControlSettings:
    sec = _Section(file, "control", table)
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
    )
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
                if tach in devices and devices[tach].kind == "tach":
                    loops.append(LoopConfig(role[: -len("_motor")], role, tach))
    else:
        for i, item in enumerate(loops_raw):
            lsec = _Section(file, f"control.loops[{i}]", item)
            motor = lsec.raw("motor", str, required=True)
            tach = lsec.raw("tach", str, required=True)
            name = lsec.raw("name", str, default=motor.removesuffix("_motor"))
            check_role(file, lsec.key("name"), name)
            lsec.finish()
            for key, role, kind in (("motor", motor, "motor"), ("tach", tach, "tach")):
                if role not in devices or devices[role].kind != kind:
                    raise lsec.error(key, f"{role!r} is not a {kind} device of this rig")
            loops.append(LoopConfig(name, motor, tach))
    return ControlSettings(loops=tuple(loops), **values)


def parse_rig(text: str, file: str = "<rig>", check_protocols: bool = True) -> Rig:
    """Validate rig-file text and build a :class:`Rig` (SI inside). Raises RigFileError."""
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise RigFileError(file, "(syntax)", str(exc)) from None
    except RecursionError:
        raise RigFileError(file, "(syntax)", "nested too deeply") from None
    top = _Section(file, "", data)
    rig_sec = _Section(file, "rig", top.raw("rig", dict, required=True))
    name = rig_sec.raw("name", str, required=True)
    description = rig_sec.raw("description", str, default="")
    rig_sec.finish()

    dev_tables = top.raw("devices", dict, required=True)
    if not dev_tables:
        raise RigFileError(file, "devices", "no devices")
    devices = {role: _device(file, role, t, check_protocols) for role, t in dev_tables.items()}

    bodies = {n: _body(file, n, t) for n, t in top.raw("bodies", dict, default={}).items()}
    for n in bodies:
        if n not in ("rotator", "floator"):
            raise RigFileError(file, f"bodies.{n}", "unknown body (use rotator or floator)")

    gsec = _Section(file, "geometry", top.raw("geometry", dict, default={}))
    axis = gsec.raw("axis", str, default="vertical")
    if axis not in ("vertical", "horizontal"):
        raise gsec.error("axis", f"must be vertical or horizontal, got {axis!r}")
    under = gsec.raw("balance_under", str, default="rotator")
    if under not in ("rotator", "floator"):
        raise gsec.error("balance_under", f"must be rotator or floator, got {under!r}")
    geometry = Geometry(axis=axis, gap_m=gsec.quantity("gap", "m"), balance_under=under)
    gsec.finish()

    lsec = _Section(file, "limits", top.raw("limits", dict, required=True))
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
    return Rig(Path(file), name, description, devices, bodies, geometry, limits, control, text)


def load_rig(path: str | Path, check_protocols: bool = True) -> Rig:
    """Read and validate a rig file. ``path`` may also name a bundled rig (``emulated-fig525``)."""
    p = Path(path)
    if not p.exists():
        bundled = bundled_rig_path(str(path))
        if bundled is None:
            raise RigFileError(str(path), "(file)", "no such rig file")
        p = bundled
    return parse_rig(read_rig_text(p), str(p), check_protocols)


def bundled_rig_names() -> list[str]:
    folder = resources.files("labkit") / "data" / "rigs"
    return sorted(f.name[:-5] for f in folder.iterdir() if f.name.endswith(".toml"))


def bundled_rig_path(name: str) -> Path | None:
    """Path of a rig shipped inside the package (works after a plain ``pip install``)."""
    stem = Path(name).name.removesuffix(".toml")
    candidate = resources.files("labkit") / "data" / "rigs" / f"{stem}.toml"
    return Path(str(candidate)) if candidate.is_file() else None


# ---- opening a rig ------------------------------------------------------------------------
PortOpener = Callable[..., Any]


def _record_url(inner: str, cassette: Path, role: str) -> str:
    check_role("<rig>", f"devices.{role}", role)  # a Rig built in Python skips load_rig's check
    query = urllib.parse.urlencode({"cassette": str(cassette), "port": role})
    return f"record://{inner}?{query}" if "?" not in inner else f"record://{inner}&{query}"


class OpenRig:
    """A rig with open ports and live drivers, by role. ``close()`` zeroes motors first.

    ``devices[role]`` is the driver for balances and tachometers and a rig-aware
    :class:`labkit.control.handle.RigMotor` for motors (speeds within the rig's limits and
    interlocks); ``devices[role].raw_driver`` (or ``drivers[role]``) is the bare motor driver.
    """

    def __init__(self, rig: Rig, clock: Any) -> None:
        self.rig = rig
        self.clock = clock
        self.drivers: dict[str, Any] = {}
        self.port_urls: dict[str, str] = {}
        self.stop_failures: dict[str, str] = {}
        self._handles: dict[str, Any] = {}

    @property
    def devices(self) -> dict[str, Any]:
        from labkit.control.handle import RigMotor

        out = {}
        for role, driver in self.drivers.items():
            if self.rig.devices[role].kind == "motor":
                out[role] = self._handles.setdefault(role, RigMotor(self, role))
            else:
                out[role] = driver
        return out

    def motors(self) -> dict[str, Any]:
        """The motor drivers themselves (raw), by role."""
        return {r: d for r, d in self.drivers.items() if self.rig.devices[r].kind == "motor"}

    def stop_motors(self) -> list[str]:
        """Command every motor to zero; never raises. Returns the roles whose STOP was not
        delivered (their reason is in ``stop_failures``)."""
        failed = []
        for role, motor in self.motors().items():
            try:
                motor.stop()
                problem = getattr(motor, "stop_error", None)
            except Exception as exc:  # noqa: BLE001 - keep stopping the others
                problem = str(exc)
            if problem:
                self.stop_failures[role] = problem
                failed.append(role)
        return failed

    def close(self) -> None:
        for handle in self._handles.values():
            if handle._control is not None:
                handle._control.stop("rig closed")
        self.stop_motors()
        for role in sorted(self.drivers, key=lambda r: self.rig.devices[r].kind != "motor"):
            try:
                self.drivers[role].close()
            except Exception:  # noqa: BLE001 - closing must reach every device
                pass
        self.drivers.clear()

    def __enter__(self) -> OpenRig:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def open_rig(rig: Rig, clock: Any, record_to: str | Path | None = None,
             port_override: Callable[[DeviceConfig], str] | None = None) -> OpenRig:
    """Open every port of ``rig`` and instantiate its drivers.

    ``record_to``: a cassette folder; each port is wrapped as
    ``record://<url>?cassette=<folder>/<role>.jsonl&port=<role>``. ``port_override(dev)``
    may replace a device's URL (``labkit replay`` points ports at ``replay://`` cassettes).
    If anything fails, everything already opened is closed (motors zeroed) and the error
    is re-raised.
    """
    from labkit.devices.base import driver_class
    from labkit.io.ports import open_port

    opened = OpenRig(rig, clock)
    try:
        for role, dev in rig.devices.items():
            url = port_override(dev) if port_override else dev.port
            if record_to is not None:
                url = _record_url(url, Path(record_to) / f"{role}.jsonl", role)
            cls = driver_class(dev.kind, dev.protocol)
            settings = {**getattr(cls, "default_serial", {}), **dev.serial}
            port = open_port(url, clock=clock, **settings)
            opened.port_urls[role] = url
            opened.drivers[role] = cls(port, clock, name=role, **dev.options)
    except BaseException:
        opened.close()
        raise
    return opened
