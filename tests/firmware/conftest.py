"""Firmware in the loop: labkit's sketches compiled with avr-gcc against the Arduino AVR core
(firmware/build.py) and run on a simulated ATmega328P (simavr, firmware/sim/labkit_simavr.c)
with the UART on a pseudo-terminal. Without the toolchain the tests skip and say why;
firmware/ci/install-toolchain.sh (run by .ci/run) installs it."""

from __future__ import annotations

import shutil
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
BUILD = ROOT / "firmware" / "build.py"
CORE = Path("/usr/share/arduino/hardware/arduino/avr/cores/arduino/Arduino.h")
SIMAVR_HEADER = Path("/usr/include/simavr/parts/uart_pty.h")


def missing_toolchain() -> str | None:
    """Why the firmware tests cannot run here, or None."""
    for tool in ("avr-gcc", "avr-g++", "avr-objcopy", "gcc"):
        if shutil.which(tool) is None:
            return f"{tool} not installed (run firmware/ci/install-toolchain.sh)"
    if not CORE.is_file():
        return "Arduino AVR core not installed (arduino-core-avr; firmware/ci/install-toolchain.sh)"
    if not SIMAVR_HEADER.is_file():
        return "simavr headers not installed (libsimavr-dev; firmware/ci/install-toolchain.sh)"
    return None


def build(args: list[str], out: Path) -> Path:
    done = subprocess.run([sys.executable, str(BUILD), *args, "--out", str(out)],
                          capture_output=True, text=True, timeout=300, check=False)
    if done.returncode != 0:
        pytest.fail(f"firmware build {args} failed: {done.stderr.strip()}")
    return Path(done.stdout.strip().splitlines()[-1])


@pytest.fixture(scope="session")
def firmware(tmp_path_factory) -> dict[str, Path]:
    """The sketches' .hex and the harness, built once per session from the checkout."""
    reason = missing_toolchain()
    if reason:
        pytest.skip(reason)
    out = tmp_path_factory.mktemp("firmware")
    return {
        "labkit_tach": build([str(ROOT / "firmware" / "labkit_tach")], out),
        "labkit_esc_bridge": build([str(ROOT / "firmware" / "labkit_esc_bridge")], out),
        "labkit_strobe": build([str(ROOT / "firmware" / "labkit_strobe")], out),
        "harness": build(["--harness"], out),
    }


class SimAvr:
    """A running harness: ``pty`` is the sketch's serial port; pulse widths measured on pin
    9 arrive in ``pwm`` as (simulated time in us, high time in us) and, cycle-exact, in
    ``oc1a`` as (rising cycle, falling cycle); the falling edges driven on pin 8 (ICP1) in
    ``edges`` (cycles), spurious ones in ``glitches``."""

    def __init__(self, harness: Path, hex_file: Path) -> None:
        self.proc = subprocess.Popen([str(harness), str(hex_file)], stdin=subprocess.PIPE,
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                     bufsize=1)
        self.pwm: list[tuple[float, float]] = []
        self.acks: list[str] = []
        self.oc1a: list[tuple[int, int]] = []
        self.edges: list[int] = []
        self.glitches: list[int] = []
        self.cycle = 0
        self.pty = ""
        self._changed = threading.Condition()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        if not self.wait_for(lambda: bool(self.pty), 10.0):
            self.close()
            raise RuntimeError("the simavr harness printed no PTY line")

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            words = line.split()
            with self._changed:
                if words[:1] == ["PWM"] and len(words) == 3:
                    self.pwm.append((float(words[1]), float(words[2])))
                elif words[:1] == ["EDGE"] and len(words) == 2:
                    self.edges.append(int(words[1]))
                elif words[:1] == ["OC1A"] and len(words) == 3:
                    self.oc1a.append((int(words[1]), int(words[2])))
                elif words[:1] == ["CYCLE"] and len(words) == 2:
                    self.cycle = int(words[1])
                elif words[:1] == ["GLITCH"] and len(words) == 2:
                    self.glitches.append(int(words[1]))
                elif words[:1] == ["PTY"]:
                    self.pty = words[1]
                elif words[:1] == ["OK"]:
                    self.acks.append(line.strip())
                self._changed.notify_all()
        with self._changed:
            self._changed.notify_all()

    def wait_for(self, condition: Callable[[], bool], timeout: float) -> bool:
        """Wait (event-driven) until ``condition()`` holds or the harness ends."""
        with self._changed:
            return self._changed.wait_for(lambda: condition() or self.proc.poll() is not None,
                                          timeout) and condition()

    def pulses(self, rpm: float, ppr: int = 1, jitter: float = 0.0, miss: int = 0) -> None:
        """Drive pin 2 with this pulse train from now on (acknowledged by the harness)."""
        assert self.proc.stdin is not None
        count = len(self.acks)
        self.proc.stdin.write(f"rpm {rpm} ppr {ppr} jitter {jitter} miss {miss}\n")
        self.proc.stdin.flush()
        assert self.wait_for(lambda: len(self.acks) > count, 5.0), "harness did not take the pulse train"

    def _send(self, line: str) -> None:
        assert self.proc.stdin is not None
        count = len(self.acks)
        self.proc.stdin.write(line + "\n")
        self.proc.stdin.flush()
        assert self.wait_for(lambda: len(self.acks) > count, 5.0), f"harness did not take {line!r}"

    def rotor(self, hz: float, ramp_per_s: float = 0.0, low_us: float = 20.0) -> None:
        """Drive pin 8 (ICP1) with a once-per-revolution pulse at ``hz`` from now on, the
        frequency changing by ``ramp_per_s`` (relative) per second; 0 Hz stops it."""
        self._send(f"icp {hz} ramp {ramp_per_s} low_us {low_us}")

    def glitch(self, fraction: float, low_cycles: int) -> None:
        """One spurious pulse ``fraction`` of a period after the next rotor edge."""
        self._send(f"glitch {fraction} {low_cycles}")

    def now_cycles(self) -> int:
        """The simulated clock (cycles) as the harness last reported it (every 10 ms)."""
        return self.cycle

    def run_for(self, seconds: float, timeout: float = 30.0) -> int:
        """Wait until the simulation has run ``seconds`` past now (by its own reports, so a
        slow host only takes longer); returns the cycle it started from."""
        start = self.now_cycles()
        end = start + int(seconds * 16e6)
        assert self.wait_for(lambda: self.now_cycles() >= end, timeout), (
            f"simulation did not reach {seconds} s past cycle {start} in {timeout} s")
        return start

    def close(self) -> None:
        if self.proc.poll() is None:
            try:
                assert self.proc.stdin is not None
                self.proc.stdin.write("quit\n")
                self.proc.stdin.flush()
                self.proc.wait(timeout=5)
            except (OSError, subprocess.TimeoutExpired):
                self.proc.kill()
                self.proc.wait(timeout=5)
        self._reader.join(timeout=5)


@pytest.fixture
def simavr(firmware) -> Iterator[Callable[[str], SimAvr]]:
    """``simavr("labkit_tach")`` starts that sketch; every harness is ended after the test."""
    running: list[SimAvr] = []

    def start(sketch: str) -> SimAvr:
        sim = SimAvr(firmware["harness"], firmware[sketch])
        running.append(sim)
        return sim

    yield start
    for sim in running:
        sim.close()
