"""``labkit emulate RIG``: serve a rig's emulated devices on pseudo-terminals.

Every device whose port is a ``sim://`` URL gets a ``/dev/pts/N`` that any program can open
as a serial port (pyserial, a terminal, the vendor's tool). Devices of one rig share their
plant, so the balance sees the force of the speed the motor emulator reached. Prints one
``role -> /dev/pts/N`` line per device (``--json``: one JSON object), then runs on the real
clock until Ctrl-C or ``--seconds``. A device that unplugs (``faults=disconnect_at:...``)
comes back under a new path, printed as another ``role -> /dev/pts/M`` line.

Faults can start from outside, mid-run: ``--unplug-on-usr1 ROLE`` pulls a cable on SIGUSR1,
``--fault-on-usr2 ROLE:NAME`` starts a time-triggered fault (``zero``, ``stuck``, ``repeat``,
``stop`` of a tachometer, ``stall`` of a motor, ...) on SIGUSR2. ``--truth FILE`` writes the
true speed and duty of every emulated motor as JSON lines (clock: ``time.monotonic``), so a
test can tell what the rotor did whatever its tachometer said.
"""

from __future__ import annotations

import argparse
import json
import math
import signal
import sys
import threading
from typing import Any

from labkit.cli.summaries import COMMAND_SUMMARIES
from labkit.emulators.base import TIMED_FAULTS
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


def parse_fault_option(text: str) -> tuple[str, str]:
    """``"rotor_tach:zero"`` -> ``("rotor_tach", "zero")``; PortURLError for anything else."""
    role, sep, name = text.partition(":")
    if not sep or not role.strip() or name.strip() not in TIMED_FAULTS:
        raise PortURLError(text, f"expected --fault-on-usr2 ROLE:NAME, NAME one of {', '.join(TIMED_FAULTS)}")
    return role.strip(), name.strip()


def fault_on_signal(faults: list[str], hosts: dict[str, PtyHost], clock: Any, announce: Any) -> None:
    """SIGUSR2 starts each ``ROLE:NAME`` fault now (its ``NAME_at`` becomes the time since open)."""
    wanted = [parse_fault_option(text) for text in faults]
    for role, _ in wanted:
        if role not in hosts:
            raise PortURLError(role, f"--fault-on-usr2: no emulated device {role!r} "
                                     f"(have {', '.join(hosts)})")
    if not wanted or not hasattr(signal, "SIGUSR2"):
        return

    def start(signum: int, frame: Any) -> None:
        for role, name in wanted:
            emulator: Any = hosts[role].emulator  # an Emulator (PtyHost types it as a protocol)
            emulator.start_fault(name, clock.now())
            announce(role, hosts[role].path, f"fault {name}")

    signal.signal(signal.SIGUSR2, start)


class TruthLog:
    """Every emulated motor's true speed and duty, as JSON lines (``--truth FILE``)."""

    def __init__(self, path: str, hosts: dict[str, PtyHost]) -> None:
        self.file = open(path, "a", encoding="utf-8")  # noqa: SIM115 - closed by close()
        self.plants = {id(h.emulator.plant): h.emulator.plant for h in hosts.values()
                       if hasattr(h.emulator, "plant")}

    def sample(self, t: float) -> None:
        for plant in self.plants.values():
            with plant._lock:
                names = list(plant.motors)
            for name in names:
                speed = plant.speed(t, name)
                motor = plant.motor(name)
                rpm = speed * 60.0 / (2.0 * math.pi)
                line = {"t": t, "motor": name, "rpm": rpm, "duty": motor.duty,
                        "stalled": motor.drive_duty != motor.duty}
                self.file.write(json.dumps(line) + "\n")
        self.file.flush()

    def close(self) -> None:
        self.file.close()


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
    truth: TruthLog | None = None

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
        fault_on_signal(args.fault_on_usr2 or [], hosts, clock, announce)
        truth = TruthLog(args.truth, hosts) if args.truth else None
        if sys.stderr.isatty():
            print("Ctrl-C to stop", file=sys.stderr)
        deadline = None if args.seconds is None else clock.now() + args.seconds
        step = 0.02 if truth is not None else 0.1
        while deadline is None or clock.now() < deadline:
            for role, host in hosts.items():
                if host.error is not None:
                    raise RuntimeError(f"{role}: emulator failed: {host.error!r}") from host.error
            if truth is not None:
                truth.sample(clock.now())
            clock.sleep(step if deadline is None else max(0.0, min(step, deadline - clock.now())))
    except KeyboardInterrupt:
        pass
    finally:
        if truth is not None:
            truth.close()
        for host in hosts.values():
            host.close()
    return 0


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser("emulate", help=COMMAND_SUMMARIES["emulate"],
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
    parser.add_argument("--fault-on-usr2", action="append", metavar="ROLE:NAME",
                        help="on SIGUSR2 (kill -USR2 PID), start fault NAME of ROLE now, e.g. "
                             "rotor_tach:zero, rotor_tach:stuck, rotor_motor:stall "
                             f"(repeatable; NAME: {', '.join(TIMED_FAULTS)})")
    parser.add_argument("--truth", metavar="FILE",
                        help="append every emulated motor's true speed and duty to FILE as JSON lines "
                             "every 20 ms (t is time.monotonic)")
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
