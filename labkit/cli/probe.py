"""``labkit probe {balance,tach,motor,camera,strobe}``: a user's first check that a device talks.

Opens the port URL (a device path, ``sim://``, ``replay://``, ``record://`` ...), builds the
protocol's driver, asks the device who it is (where the protocol allows) and prints N
readings, one JSON object per line with keys ``t`` (s since the probe started), ``value``,
``unit``, ``stable``, ``overload``, ``raw``. Motors: status and speed variables only; the
probe never enables or starts a motor, and closing the driver commands zero.
A device fault ends with one line naming device, command and last bytes, exit status 2.
Cameras (no --protocol): one JSON line with the settings the camera accepted (size, fps,
format, exposure), the timestamp kind, and the measured rate and dropped frames of a burst of
--frames frames (:mod:`labkit.devices.camera`).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

import serial

from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.device_kinds import DEVICE_KINDS, OLD_KIND_WORDS, canonical_kind
from labkit.devices.base import Device
from labkit.devices.registry import driver_class, known_drivers
from labkit.errors import DeviceError, LabkitError
from labkit.io.clock import Clock, current_clock

#: the device kinds, and the older words still accepted (``probe tach`` is ``probe tachometer``)
KINDS = (*DEVICE_KINDS, *OLD_KIND_WORDS)

try:  # a pty or serial driver may refuse a setting in tcsetattr (not an OSError)
    from termios import error as TermiosError
except ImportError:  # pragma: no cover - Windows
    class TermiosError(Exception):  # type: ignore[no-redef]
        """Never raised off POSIX."""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "probe", help=COMMAND_SUMMARIES["probe"],
        description=__doc__.split("\n\n")[1] if __doc__ else None,
    )
    p.add_argument("kind", choices=KINDS, help="device kind (tach: the older word for tachometer)")
    p.add_argument("--protocol",
                   help="driver protocol, e.g. mtsics, and_std, line_regex, lutron16, pololu_smc "
                        "(required except for cameras)")
    p.add_argument("--port", required=True, help="port URL: /dev/ttyUSB0, sim://mtsics?seed=1, replay://...")
    p.add_argument("--baud", type=int, help="baud rate (default: the protocol's factory setting)")
    p.add_argument("--bytesize", type=int, choices=(5, 6, 7, 8), help="data bits")
    p.add_argument("--parity", choices=("N", "E", "O"), help="parity: N, E or O")
    p.add_argument("--stopbits", type=float, choices=(1, 1.5, 2), help="stop bits")
    p.add_argument("--samples", type=int, default=5, help="number of readings (default 5)")
    p.add_argument("--frames", type=int, default=30, help="camera: frames in the measured burst (default 30)")
    p.add_argument("--interval", type=float, default=0.0, metavar="S",
                   help="seconds between readings (default: as fast as the device answers)")
    p.add_argument("--timeout", type=float, default=None, metavar="S",
                   help="per-reading timeout (default 3, or the driver's read_timeout_s: "
                        "10 for line_regex preset=bogde_full, which prints every 6 s)")
    p.add_argument("-o", "--option", action="append", default=[], metavar="KEY=VALUE",
                   help="driver option, as in a rig file (e.g. preset=bogde, unit=N); repeatable")
    p.add_argument("--continuous", action="store_true",
                   help="balance: read its continuous output (SIR) on a reader instead of polling")
    p.add_argument("--json", action="store_true",
                   help="only JSON lines on stdout (the identification goes to stderr)")
    p.set_defaults(func=run)


def parse_options(items: list[str]) -> dict[str, str]:
    """``["preset=bogde", "unit=N"]`` -> dict; raises LabkitError naming a bad item."""
    out: dict[str, str] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise LabkitError(f"--option {item!r}: expected KEY=VALUE")
        out[key.strip()] = value.strip()
    return out


def serial_settings(defaults: dict[str, Any], args: argparse.Namespace) -> dict[str, Any]:
    """The driver's factory settings overridden by the command-line flags."""
    settings = dict(defaults)
    for flag, key in (("baud", "baudrate"), ("bytesize", "bytesize"), ("parity", "parity"),
                      ("stopbits", "stopbits")):
        value = getattr(args, flag)
        if value is not None:
            settings[key] = int(value) if key == "stopbits" and float(value).is_integer() else value
    return settings


def json_safe(obj: dict[str, Any]) -> dict[str, Any]:
    """NaN/inf (an overload has no value) become null, so every line is valid JSON."""
    return {k: (None if isinstance(v, float) and not math.isfinite(v) else v) for k, v in obj.items()}


def one_sample(device: Device, timeout: float | None) -> dict[str, Any]:
    """One reading from any device class, as the probe prints it (``timeout`` None: the
    driver's ``read_timeout_s`` if it has one, else 3 s)."""
    if timeout is None:
        timeout = float(getattr(device, "read_timeout_s", 3.0))
    kind = canonical_kind(device.kind)  # a plugin driver may still say "tach"
    if kind == "balance":
        return device.read(timeout=timeout).as_json()  # type: ignore[attr-defined]
    if kind == "tachometer":
        return device.wait_reading(timeout=timeout).as_json()  # type: ignore[attr-defined]
    if kind == "strobe":  # one status line: rotor and strobe frequency, phase, flags
        return device.wait_status(timeout=timeout).as_json()  # type: ignore[attr-defined]
    return device.status().as_json()  # type: ignore[attr-defined]


def open_device(kind: str, protocol: str, url: str, settings: dict[str, Any],
                options: dict[str, str], clock: Clock) -> Device:
    """Open ``url`` and build the driver; turns every expected failure into a LabkitError."""
    from labkit.io.ports import open_port

    if url.lower().startswith("sim://"):
        import labkit.emulators  # noqa: F401 - registers the sim:// URL handler

    try:
        cls = driver_class(kind, protocol)
    except KeyError as exc:
        raise LabkitError(str(exc.args[0])) from None
    name = f"{kind} {protocol} at {url}"
    try:
        port = open_port(url, clock=clock, timeout=0, **settings)
    except (serial.SerialException, OSError, ValueError, TermiosError) as exc:
        raise DeviceError(name, "open", b"", f"cannot open port: {exc}") from None
    try:
        return cls(port, clock, name=name, **options)
    except ValueError as exc:  # a bad option value
        port.close()
        raise LabkitError(f"{name}: {exc}") from None
    except BaseException:
        port.close()
        raise


def probe(args: argparse.Namespace, out=None, err=None, clock: Clock | None = None) -> int:
    out = out or sys.stdout
    err = err or sys.stderr
    clock = clock or current_clock()
    if args.samples < 0:
        raise LabkitError("--samples must be >= 0")
    args.kind = canonical_kind(args.kind)
    if args.kind == "camera":
        from labkit.cli.probe_camera import probe_camera

        return probe_camera(args.port, args.frames, out, clock)
    if not args.protocol:
        raise LabkitError(f"probe {args.kind} needs --protocol (known: "
                          f"{', '.join(known_drivers().get(args.kind, []))})")
    try:
        cls = driver_class(args.kind, args.protocol)
    except KeyError:
        known = ", ".join(known_drivers().get(args.kind, []))
        raise LabkitError(f"no {args.kind} driver {args.protocol!r}; known: {known}") from None
    options = parse_options(args.option)
    defaults = getattr(cls, "serial_defaults", None)  # drivers whose settings depend on options
    settings = serial_settings(defaults(options) if defaults else dict(cls.default_serial), args)
    device = open_device(args.kind, args.protocol, args.port, settings, options, clock)
    start = clock.now()
    try:
        info = device.identify()
        header = {"device": device.name, "settings": settings, **info}
        if args.json:
            print(json.dumps(header), file=err)
        else:
            print("# " + json.dumps(header), file=out)
        if args.kind == "motor":
            print("# " + watchdog_note(cls, options), file=err if args.json else out)
        if getattr(args, "continuous", False):
            if not hasattr(device, "start_continuous"):
                raise LabkitError(f"{device.name}: --continuous is for balances with continuous output")
            device.start_continuous()  # type: ignore[attr-defined]
        for i in range(args.samples):
            if i and args.interval > 0:
                clock.sleep(args.interval)
            sample = json_safe(one_sample(device, args.timeout))
            sample["t"] = round(sample["t"] - start, 6)
            print(json.dumps(sample), file=out, flush=True)
    except TermiosError as exc:
        raise DeviceError(device.name, "configure port", b"", f"the port refused the serial settings "
                          f"{settings}: {exc}") from None
    finally:
        device.close()
    return 0


def watchdog_note(cls: Any, options: dict[str, Any]) -> str:
    """What the motor controller's own command timeout is and how to switch it on
    (docs/explanation/safety.md)."""
    builtin = getattr(cls, "builtin_watchdog_ms", None)
    option = getattr(cls, "watchdog_option", None)
    advice = getattr(cls, "watchdog_advice", "")
    if builtin is not None:
        return f"watchdog: built in, the motor stops {builtin:.0f} ms after the last command ({advice})"
    if option is None:
        return "watchdog: this controller has none labkit knows of; see docs/explanation/safety.md"
    if option in options:
        return (f"watchdog: declared {option} = {options[option]} ms; labkit cannot read it back over "
                f"serial, so make sure it is set: {advice}")
    return (f"watchdog: to enable it, {advice}; then add options = {{ {option} = 500 }} to the "
            "rig file (required for real hardware, docs/explanation/safety.md)")


def run(args: argparse.Namespace) -> int:
    return probe(args)
