"""Regenerate the balance cassettes under recordings/cassettes/ (one per balance driver).

Each session runs a driver against its emulator through ``record://sim://...`` on a
virtual clock (so the cassette is small and the same every time): identify, a motor
spin-up seen as unstable readings, a stable reading, tare, zero. The readings the driver
produced while recording are stored next to the cassette (``*.readings.json``); the
replay tests must reproduce them exactly from the cassette alone.

    python analysis/record_cassettes_balance.py [--out recordings/cassettes]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from labkit.devices.registry import driver_class
from labkit.emulators.plant import reset_plants, shared_plant
from labkit.io.clock import VirtualClock
from labkit.io.ports import open_port
from labkit.readings import Reading

#: name -> (driver protocol, emulator URL, serial settings, driver options)
SESSIONS: dict[str, tuple[str, str, dict[str, Any], dict[str, Any]]] = {
    "mtsics": ("mtsics", "sim://mtsics?seed=3&plant=model-fig525.rec-mtsics",
               {"baudrate": 9600, "bytesize": 8, "parity": "N", "stopbits": 1}, {}),
    "and_std": ("and_std", "sim://and_std?seed=3&plant=model-fig525.rec-and&unit=N",
                {"baudrate": 2400, "bytesize": 7, "parity": "E", "stopbits": 1}, {}),
    "hx711_adc": ("line_regex", "sim://hx711?seed=3&plant=model-fig525.rec-hx711&preset=hx711_adc&startup_s=0.3",
                  {"baudrate": 57600, "bytesize": 8, "parity": "N", "stopbits": 1},
                  {"preset": "hx711_adc", "stable_std": 0.02}),
}


def reading_record(reading: Reading) -> dict[str, Any]:
    """What a replay must reproduce (times differ between record and strict replay)."""
    out = reading.as_json()
    del out["t"]
    out["value"] = None if out["value"] != out["value"] else out["value"]  # NaN -> null
    out["flags"] = sorted(reading.flags)
    return out


def session(device, clock: VirtualClock, plant_name: str) -> list[dict[str, Any]]:
    """The scripted session; returns the readings. ``plant_name`` None when replaying."""
    readings: list[Reading] = [device.read()]
    if plant_name:
        shared_plant(plant_name).set_duty(0.4, clock.now())
    clock.sleep(0.3)
    readings += [device.read() for _ in range(3)]
    clock.sleep(2.5)
    readings.append(device.read_stable())
    result = device.tare()
    if isinstance(result, Reading):
        readings.append(result)
    readings.append(device.read())
    if plant_name:
        shared_plant(plant_name).set_duty(0.0, clock.now())
    clock.sleep(2.5)
    device.zero()
    readings.append(device.read())
    return [reading_record(r) for r in readings]


def run_session(name: str, url: str, protocol: str, settings: dict[str, Any],
                options: dict[str, Any], plant_name: str | None) -> tuple[dict, list]:
    clock = VirtualClock()
    port = open_port(url, clock=clock, timeout=0, **settings)
    device = driver_class("balance", protocol)(port, clock, name=f"balance {name}", **options)
    try:
        info = device.identify()
        readings = session(device, clock, plant_name or "")
    finally:
        device.close()
    return info, readings


def record(name: str, out: Path) -> Path:
    protocol, sim_url, settings, options = SESSIONS[name]
    cassette = out / f"balance-{name}.jsonl"
    cassette.unlink(missing_ok=True)
    url = f"record://{sim_url}&cassette={cassette}&port=balance"
    plant_name = sim_url.split("plant=")[1].split("&")[0]
    reset_plants()
    info, readings = run_session(name, url, protocol, settings, options, plant_name)
    expected = {"protocol": protocol, "options": options, "serial": settings,
                "identify": info, "readings": readings}
    (out / f"balance-{name}.readings.json").write_text(json.dumps(expected, indent=1) + "\n")
    return cassette


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    default = Path(__file__).resolve().parents[1] / "recordings" / "cassettes"
    parser.add_argument("--out", default=str(default))
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    for name in SESSIONS:
        path = record(name, out)
        print(f"{path}: {path.stat().st_size} bytes")


if __name__ == "__main__":
    main()
