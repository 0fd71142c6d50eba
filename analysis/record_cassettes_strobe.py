"""Regenerate the strobe cassettes under recordings/cassettes/ (docs/reference/devices-strobe.md).

* ``strobe-labkit_strobe``: the emulator (``sim://labkit_strobe``) on a plant whose rotor
  turns at 300 Hz, on a virtual clock;
* ``strobe-labkit_strobe-simavr``: the sketch ``firmware/labkit_strobe`` itself, compiled
  (firmware/build.py) and run on the simulated ATmega328P (firmware/sim/labkit_simavr.c)
  with a 500 Hz rotor pulse train, over its pseudo-terminal on the real clock.

Each runs :func:`labkit.devices.strobe.scripted.run_strobe_script` through
``record://<port>?cassette=...`` and writes ``<name>.jsonl`` (every byte both ways) and
``<name>.expected.json`` (what the driver read); tests/devices/test_strobe_cassettes.py
replays them. To record a real strobe, run the script on ``record:///dev/ttyUSB0?...``.
Usage: ``python analysis/record_cassettes_strobe.py [name ...]``.
"""

from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from labkit.devices.registry import driver_class
from labkit.devices.strobe.scripted import run_strobe_script
from labkit.emulators.plant import reset_plants, shared_plant
from labkit.io.clock import RealClock, VirtualClock
from labkit.io.ports import open_port

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "recordings" / "cassettes"
OPTIONS = {"offset_hz": 1.5, "width_us": 20, "rate_hz": 5}
SETTINGS = driver_class("strobe", "labkit_strobe").default_serial


def record_emulator(name: str) -> dict:
    reset_plants()
    motor = shared_plant("rec").motor("rotor")
    motor.max_speed_rad_s = max(motor.max_speed_rad_s, 4000.0)
    motor.speed_rad_s = 2 * 3.141592653589793 * 300.0
    motor.duty = motor.speed_rad_s / motor.max_speed_rad_s
    cassette = OUT / f"{name}.jsonl"
    cassette.unlink(missing_ok=True)
    clock = VirtualClock()
    url = f"record://sim://labkit_strobe?plant=rec&seed=1&faults=split:0.3&cassette={cassette}&port={name}"
    return run_strobe_script(open_port(url, clock=clock, timeout=0, **SETTINGS), clock, **OPTIONS)


def record_simavr(name: str) -> dict:
    build = [sys.executable, str(ROOT / "firmware" / "build.py")]
    with tempfile.TemporaryDirectory() as out:
        hex_file = subprocess.run([*build, str(ROOT / "firmware" / "labkit_strobe"), "--out", out],
                                  check=True, capture_output=True, text=True).stdout.split()[-1]
        harness = subprocess.run([*build, "--harness", "--out", out], check=True, capture_output=True,
                                 text=True).stdout.split()[-1]
        sim = subprocess.Popen([harness, hex_file], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        try:
            assert sim.stdout is not None and sim.stdin is not None
            pty = ""
            while not pty:
                words = sim.stdout.readline().split()
                pty = words[1] if words[:1] == ["PTY"] else ""
            stdout = sim.stdout      # drained, or the harness blocks on its EDGE/OC1A lines
            threading.Thread(target=lambda: [None for _ in stdout], daemon=True).start()
            sim.stdin.write("icp 500 ramp 0 low_us 20\n")
            sim.stdin.flush()
            time.sleep(0.5)
            cassette = OUT / f"{name}.jsonl"
            cassette.unlink(missing_ok=True)
            clock = RealClock()
            url = f"record://{pty}?cassette={cassette}&port={name}"
            return run_strobe_script(open_port(url, clock=clock, timeout=0, **SETTINGS), clock, **OPTIONS)
        finally:
            sim.kill()
            sim.wait()


SCENARIOS = {"strobe-labkit_strobe": record_emulator, "strobe-labkit_strobe-simavr": record_simavr}


def main(argv: list[str]) -> int:
    OUT.mkdir(parents=True, exist_ok=True)
    for name in argv or list(SCENARIOS):
        result = SCENARIOS[name](name)
        (OUT / f"{name}.expected.json").write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
        size = (OUT / f"{name}.jsonl").stat().st_size
        print(f"{name}: {len(result['statuses'])} statuses, cassette {size} bytes")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
