"""Regenerate the tachometer and motor cassettes under recordings/cassettes/.

Each scenario runs a scripted driver session (labkit.devices.{tachometer,motor}.scripted)
through ``record://sim://<protocol>?...`` on a virtual clock and writes

* ``recordings/cassettes/<name>.jsonl``          every byte both ways (labkit cassette)
* ``recordings/cassettes/<name>.expected.json``  what the driver read while recording

The tests replay each cassette through ``replay://`` and must read the same thing.
To record a real device instead, run the same script on ``record:///dev/ttyUSB0?cassette=...``
(see docs/reference/devices-tach-motor.md). Usage: ``python analysis/record_cassettes_tach_motor.py``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from labkit.devices.motor.scripted import run_motor_script
from labkit.devices.registry import driver_class
from labkit.devices.tachometer.scripted import run_tach_script
from labkit.emulators.plant import reset_plants, shared_plant
from labkit.io.clock import VirtualClock
from labkit.io.ports import open_port
from labkit.units import RAD_S_PER_RPM

OUT = Path(__file__).resolve().parent.parent / "recordings" / "cassettes"

#: name -> (kind, protocol, sim query, driver options, rotor rpm set on the plant first)
SCENARIOS: dict[str, tuple[str, str, str, dict, float]] = {
    "tach-labkit_tach": ("tachometer", "labkit_tach", "seed=1&rate_hz=10&faults=garbage:0.2",
                         {"ppr": 2}, 24_000.0),
    "tach-lutron16": ("tachometer", "lutron16", "seed=1&rate_hz=5&faults=mid_frame", {}, 12_345.6),
    "tach-monarch_at": ("tachometer", "monarch_at", "seed=1&faults=split:0.5", {}, 4_321.0),
    "motor-pololu_smc": ("motor", "pololu_smc", "seed=1&crc=1&device_number=13",
                         {"crc": True, "device_number": 13}, 0.0),
    "motor-esc_bridge": ("motor", "esc_bridge", "seed=1&arm_s=0", {}, 0.0),
    "motor-vesc": ("motor", "vesc", "seed=1&pole_pairs=7", {"pole_pairs": 7}, 0.0),
}


def spin(rpm: float) -> None:
    motor = shared_plant("rec").motor("rotor")
    motor.max_speed_rad_s = max(motor.max_speed_rad_s, 2 * rpm * RAD_S_PER_RPM)
    motor.speed_rad_s = rpm * RAD_S_PER_RPM
    motor.duty = motor.speed_rad_s / motor.max_speed_rad_s


def run_script(kind: str, protocol: str, port, clock, options: dict) -> dict:
    if kind == "tachometer":
        return run_tach_script(port, clock, protocol, duration_s=2.0, **options)
    return run_motor_script(port, clock, protocol, duty=0.3, run_s=1.0, **options)


def record(name: str, out: Path = OUT) -> dict:
    kind, protocol, query, options, rpm = SCENARIOS[name]
    reset_plants()
    spin(rpm)
    cassette = out / f"{name}.jsonl"
    cassette.unlink(missing_ok=True)
    clock = VirtualClock()
    settings = driver_class(kind, protocol).default_serial
    url = f"record://sim://{protocol}?plant=rec&{query}&cassette={cassette}&port={name}"
    port = open_port(url, clock=clock, timeout=0, **settings)
    result = run_script(kind, protocol, port, clock, options)
    (out / f"{name}.expected.json").write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    return result


def main(argv: list[str]) -> int:
    OUT.mkdir(parents=True, exist_ok=True)
    for name in argv or list(SCENARIOS):
        result = record(name)
        count = len(result.get("readings", result.get("statuses", [])))
        size = (OUT / f"{name}.jsonl").stat().st_size
        print(f"{name}: {count} readings/statuses, cassette {size} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
