"""``labkit emulate RIG``: serve a rig's emulated devices on pseudo-terminals.

Every device whose port is a ``sim://`` URL gets a ``/dev/pts/N`` that any program can open
as a serial port (pyserial, a terminal, the vendor's tool). Devices of one rig share their
plant, so the balance sees the force of the speed the motor emulator reached. Prints one
``role -> /dev/pts/N`` line per device (``--json``: one JSON object), then runs on the real
clock until Ctrl-C or ``--seconds``. A device that unplugs (``faults=disconnect_at:...``)
comes back under a new path, printed as another ``role -> /dev/pts/M`` line.
"""

from __future__ import annotations

import argparse
import json
import signal
import sys
import threading
from typing import Any

from labkit.emulators.sim_port import build_emulator
from labkit.errors import PortURLError
from labkit.io.clock import RealClock
from labkit.io.pty_host import PtyHost


def parse_device_option(text: str) -> tuple[str, str]:
    """``"balance=sim://mtsics?seed=3"`` -> ``("balance", "sim://mtsics?seed=3")``."""
    role, sep, url = text.partition("=")
    if not sep or not role.strip() or not url.startswith("sim://"):
        raise PortURLError(text, "expected --device ROLE=sim://PROTOCOL?...")
    return role.strip(), url


def emulated_devices(rig_path: str | None, extra: list[str]) -> tuple[dict[str, str], list[str]]:
    """``{role: sim:// URL}`` from the rig file and ``--device`` options, and the skipped roles."""
    devices: dict[str, str] = {}
    skipped: list[str] = []
    if rig_path:
        from labkit.rig import load_rig

        rig = load_rig(rig_path)
        for role, device in rig.devices.items():
            if device.kind == "camera":  # frames, not bytes: a program opens sim://camera itself
                skipped.append(f"{role} (a camera: open its URL with labkit.devices.camera.open_camera)")
            elif device.port.startswith("sim://"):
                devices[role] = device.port
            else:
                skipped.append(role)
    for text in extra:
        role, url = parse_device_option(text)
        devices[role] = url
    return devices, skipped


def unplug_on_signal(roles: list[str], hosts: dict[str, PtyHost], announce: Any) -> None:
    """SIGUSR1 pulls the cable of each role in ``roles`` (their pty hangs up for good)."""
    for role in roles:
        if role not in hosts:
            raise PortURLError(role, f"--unplug-on-usr1: no emulated device {role!r} "
                                     f"(have {', '.join(hosts)})")
    if not roles or not hasattr(signal, "SIGUSR1"):
        return

    def pull(signum: int, frame: Any) -> None:
        for role in roles:
            hosts[role].unplug()
            announce(role, hosts[role].path, "unplugged")

    signal.signal(signal.SIGUSR1, pull)


def run(args: argparse.Namespace) -> int:
    devices, skipped = emulated_devices(args.rig, args.device or [])
    for role in skipped:
        reason = "" if " (" in role else " (its port is not sim://)"
        print(f"labkit emulate: {role}: not emulated{reason}", file=sys.stderr)
    if not devices:
        print("labkit emulate: no sim:// devices to emulate (give a rig file or --device ROLE=sim://...)",
              file=sys.stderr)
        return 2
    clock = RealClock()
    lock = threading.Lock()
    hosts: dict[str, PtyHost] = {}

    def announce(role: str, path: str, note: str = "") -> None:
        with lock:
            if args.json:
                print(json.dumps({"role": role, "path": path, "event": note or "open"}), flush=True)
            else:
                print(f"{role} -> {path}{'  (' + note + ')' if note else ''}", flush=True)

    try:
        for role, url in devices.items():
            emulator = build_emulator(url)
            hosts[role] = PtyHost(emulator, clock=clock,
                                  on_reconnect=lambda path, r=role: announce(r, path, "reconnected"))
        if args.json:
            with lock:
                print(json.dumps({role: host.path for role, host in hosts.items()}), flush=True)
        else:
            for role, host in hosts.items():
                announce(role, host.path)
        unplug_on_signal(args.unplug_on_usr1 or [], hosts, announce)
        if sys.stderr.isatty():
            print("Ctrl-C to stop", file=sys.stderr)
        deadline = None if args.seconds is None else clock.now() + args.seconds
        while deadline is None or clock.now() < deadline:
            for role, host in hosts.items():
                if host.error is not None:
                    raise RuntimeError(f"{role}: emulator failed: {host.error!r}") from host.error
            clock.sleep(0.1 if deadline is None else max(0.0, min(0.1, deadline - clock.now())))
    except KeyboardInterrupt:
        pass
    finally:
        for host in hosts.values():
            host.close()
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("emulate", help="serve a rig's emulated devices on /dev/pts/N",
                            description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("rig", nargs="?", help="rig file (its sim:// devices are emulated)")
    parser.add_argument("--device", action="append", metavar="ROLE=sim://...",
                        help="emulate one more device (repeatable), e.g. balance=sim://mtsics?seed=3")
    parser.add_argument("--seconds", type=float, default=None,
                        help="stop after this many seconds (default: run until Ctrl-C)")
    parser.add_argument("--json", action="store_true",
                        help="print {role: path} as one JSON line (reconnects: one object each)")
    parser.add_argument("--unplug-on-usr1", action="append", metavar="ROLE",
                        help="on SIGUSR1 (kill -USR1 PID), unplug ROLE's pty for good, e.g. to see what "
                             "a run does when its motor controller's cable is pulled (repeatable)")
    parser.set_defaults(func=run)


def main(argv: list[str] | None = None) -> int:
    """``python -m labkit.cli.emulate ...``: the same command without loading every other one."""
    parser = argparse.ArgumentParser(prog="labkit")
    register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["emulate", *(sys.argv[1:] if argv is None else argv)])
    try:
        return run(args)
    except PortURLError as exc:
        print(f"labkit emulate: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":  # pragma: no cover - exercised through a subprocess in the tests
    sys.exit(main())
