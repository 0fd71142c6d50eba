"""firmware/labkit_strobe compiled and run on a simulated ATmega328P: the rotor's
once-per-revolution pulse driven on pin 8 (ICP1), the flashes measured on pin 9 (OC1A), both
to the CPU cycle (one Timer1 tick, 62.5 ns). Acceptance of issue 26, part 2:

* a 100-2000 Hz pulse train gives flash-time jitter of at most 2 timer ticks and an apparent
  frequency within 0.1 % of the commanded offset, also with a divider and while the rotor
  ramps by 1 %/s;
* once the pulses stop, the only flash left is the one of the last revolution (at most one
  period + the 150 us scheduling lead after the last pulse) and none follows for 50 ms and
  more; the status line says ``Z``;
* a spurious short pulse mid-revolution is rejected (flag ``N``, flashes unchanged); one
  just before the real pulse costs the lock (flag ``L``), and no flash fires mistimed.

Simulated durations are kept to a second or two per case: simavr runs in real time here.
"""

from __future__ import annotations

import json
import time

import pytest
import serial
from strobe_timing import fit_flashes, flashes_between

from labkit.cli import main

pytestmark = pytest.mark.timeout(120)

JITTER_TICKS = 2.0          # acceptance: flash-time jitter
APPARENT_REL = 1e-3         # acceptance: apparent frequency vs offset
LEAD_CYCLES = 2400          # the sketch's LEAD_TICKS: a flash may follow its edge by T + lead
WIDTH_US = 20
WINDOW_MS = 100             # RATE 10
CYCLES_PER_MS = 16_000      # the sketch's t_ms counts from Timer1's start in setup(), a few
                            # ms after the harness's cycle 0: windows are judged with margin


class Sketch:
    """The strobe's serial port: commands answered ``OK``, status lines kept."""

    def __init__(self, pty: str) -> None:
        self.port = serial.Serial(pty, 115200, timeout=0.05)
        self.buffer = b""
        self.status: list[list[str]] = []

    def _pump(self) -> list[bytes]:
        self.buffer += self.port.read(4096)
        *lines, self.buffer = self.buffer.split(b"\n")
        out = []
        for line in lines:
            if line.startswith(b"S,"):
                self.status.append(line.decode().split(","))
            else:
                out.append(line)
        return out

    def command(self, text: str, timeout: float = 5.0) -> None:
        self.port.write(text.encode() + b"\n")
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for line in self._pump():
                if line == b"OK":
                    return
                assert not line.startswith(b"ERR"), (text, line)
        raise AssertionError(f"no OK to {text!r}")

    def status_between(self, from_cycle: int, to_cycle: int, timeout: float = 10.0,
                       overlapping: bool = False) -> list[list[str]]:
        """The status lines whose window (1/RATE s before their t_ms) lies in (or, with
        ``overlapping``, overlaps) the given stretch of simulated time, waiting for the
        sketch to have printed past its end."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self._pump()
            if self.status and int(self.status[-1][2]) * CYCLES_PER_MS > to_cycle:
                break
        def window(line: list[str]) -> tuple[int, int]:
            end = int(line[2]) * CYCLES_PER_MS
            return end - WINDOW_MS * CYCLES_PER_MS, end

        if overlapping:
            return [s for s in self.status if from_cycle <= window(s)[1] and window(s)[0] <= to_cycle]
        return [s for s in self.status if from_cycle <= window(s)[0] and window(s)[1] <= to_cycle]

    def close(self) -> None:
        self.port.close()


@pytest.fixture
def strobe(simavr):
    sim = simavr("labkit_strobe")
    sketch = Sketch(sim.pty)
    sketch.command(f"RATE {1000 // WINDOW_MS}")
    sketch.command(f"WIDTH {WIDTH_US}")
    yield sim, sketch
    sketch.close()


def measure(sim, seconds: float, settle: float = 0.1):
    """Run ``settle`` s (lock, new settings), then ``seconds``; the fit of that stretch."""
    sim.run_for(settle)
    start = sim.now_cycles()
    sim.run_for(seconds)
    end = sim.now_cycles()
    flashes = flashes_between(sim.oc1a, start, end)
    edges = [e for e in sim.edges if start - 400_000 <= e <= end + 400_000]
    return fit_flashes(edges, flashes), flashes


@pytest.mark.parametrize("rotor_hz, offset_hz", [(100.0, 0.5), (500.0, 2.0), (1000.0, 2.0), (2000.0, 5.0)])
def test_flashes_are_locked_to_the_pulse_train(strobe, rotor_hz, offset_hz):
    sim, sketch = strobe
    sketch.command(f"OFFSET {offset_hz}")
    sim.rotor(rotor_hz)
    fit, flashes = measure(sim, 1.0 if rotor_hz < 200 else 0.5, settle=0.15)
    assert fit.n >= 0.9 * rotor_hz * (1.0 if rotor_hz < 200 else 0.5), fit
    assert fit.jitter_ticks <= JITTER_TICKS, fit
    assert fit.apparent_hz == pytest.approx(offset_hz, rel=APPARENT_REL), fit
    widths = [fall - rise for rise, fall in sim.oc1a if rise in set(flashes)]
    assert set(widths) <= {WIDTH_US * 16, WIDTH_US * 16 + 1}, sorted(set(widths))[:10]
    # the status lines: rotor and strobe frequency, f_rot - f_strobe = the offset
    lines = sketch.status_between(flashes[0] + 1_600_000, flashes[-1])
    assert len(lines) >= 2, sketch.status[-4:]
    for line in lines:
        f_rot, f_strobe, flags = float(line[3]), float(line[4]), line[6]
        # S (a flash's end set late in software) can come from a host command's UART interrupt
        # landing on a flash end, when the command reaches the simulated chip depends on the host's
        # load (seen once in a parallel run); every measured flash's width is checked above
        assert flags == "0" or set(flags) == {"S"}, line
        assert f_rot == pytest.approx(rotor_hz, rel=1e-5), line
        assert f_rot - f_strobe == pytest.approx(offset_hz, rel=APPARENT_REL, abs=2e-4), line


def test_divider_and_negative_offset(strobe):
    sim, sketch = strobe
    sketch.command("DIV 3")
    sketch.command("OFFSET -1.5")
    sim.rotor(900.0)
    fit, flashes = measure(sim, 0.6, settle=0.15)
    assert fit.jitter_ticks <= JITTER_TICKS, fit
    assert fit.apparent_hz == pytest.approx(-1.5, rel=APPARENT_REL), fit
    strobe_hz = (len(flashes) - 1) / ((flashes[-1] - flashes[0]) / 16e6)
    assert strobe_hz == pytest.approx((900.0 + 1.5) / 3, rel=1e-3)


def test_apparent_frequency_holds_while_the_rotor_ramps(strobe):
    sim, sketch = strobe
    sketch.command("OFFSET 2")
    sim.rotor(600.0, ramp_per_s=0.01)            # +1 %/s
    fit, _ = measure(sim, 1.5, settle=0.15)
    assert fit.apparent_hz == pytest.approx(2.0, rel=APPARENT_REL), fit
    assert fit.jitter_ticks <= JITTER_TICKS, fit
    sim.rotor(1500.0, ramp_per_s=-0.01)          # -1 %/s
    fit, _ = measure(sim, 1.0, settle=0.15)
    assert fit.apparent_hz == pytest.approx(2.0, rel=APPARENT_REL), fit


@pytest.mark.parametrize("rotor_hz", [100.0, 2000.0])
def test_no_flash_after_the_pulses_stop(strobe, rotor_hz):
    sim, sketch = strobe
    sketch.command("OFFSET 3")
    sim.rotor(rotor_hz)
    sim.run_for(0.2)
    sim.rotor(0.0)
    sim.run_for(0.3)
    last_edge = sim.edges[-1]
    period = sim.edges[-1] - sim.edges[-2]
    late = [rise for rise, _ in sim.oc1a if rise > last_edge]
    assert len(late) <= 1, (late, last_edge)           # the last revolution's own flash
    assert all(rise <= last_edge + period + LEAD_CYCLES for rise in late), (late, last_edge, period)
    quiet_from = last_edge + period + LEAD_CYCLES
    assert sim.now_cycles() >= quiet_from + 50e-3 * 16e6
    assert not [rise for rise, _ in sim.oc1a if rise > quiet_from]
    after = sketch.status_between(quiet_from + 8 * period + 160_000, sim.now_cycles())
    assert after, sketch.status[-4:]
    assert all("Z" in s[6] and float(s[3]) == 0.0 and float(s[4]) == 0.0 for s in after), after


def test_a_noise_pulse_mid_revolution_is_rejected(strobe):
    sim, sketch = strobe
    sketch.command("OFFSET 2")
    sim.rotor(500.0)
    sim.run_for(0.15)
    start = sim.now_cycles()
    sim.glitch(0.5, 8)                             # 0.5 us spurious pulse half a turn late
    sim.run_for(0.3)
    end = sim.now_cycles()
    assert len(sim.glitches) == 1 and start < sim.glitches[0] < end
    flashes = flashes_between(sim.oc1a, start, end)
    fit = fit_flashes(sim.edges, flashes)
    assert fit.jitter_ticks <= JITTER_TICKS, fit
    assert len(flashes) == pytest.approx((flashes[-1] - flashes[0]) / 16e6 * (500 - 2) + 1, abs=1)
    flags = "".join(s[6] for s in sketch.status_between(start, end, overlapping=True))
    assert "N" in flags and "L" not in flags, (sim.glitches[0] / CYCLES_PER_MS, sketch.status)


def test_a_noise_pulse_just_before_the_edge_costs_the_lock_not_a_mistimed_flash(strobe):
    sim, sketch = strobe
    sketch.command("OFFSET 2")
    sim.rotor(500.0)
    sim.run_for(0.15)
    start = sim.now_cycles()
    sim.glitch(0.9, 8)
    sim.run_for(0.3)
    end = sim.now_cycles()
    glitch = sim.glitches[0]
    flashes = flashes_between(sim.oc1a, start, end)
    fit = fit_flashes([e for e in sim.edges], flashes)   # true edges only: every flash on time
    assert fit.jitter_ticks <= JITTER_TICKS, fit
    period = 16e6 / 500
    dark = [f for f in flashes if glitch < f < glitch + 4 * period]
    assert not dark, "flashes while the lock was being regained"
    assert [f for f in flashes if f > glitch + 10 * period], "the lock came back"
    flags = "".join(s[6] for s in sketch.status_between(start, end, overlapping=True))
    assert "L" in flags, (glitch / CYCLES_PER_MS, sketch.status)


def test_lamp_off_and_commands(strobe):
    sim, sketch = strobe
    sim.rotor(400.0)
    sim.run_for(0.1)
    sketch.command("OFF")
    off_at = sim.run_for(0.2)
    assert not flashes_between(sim.oc1a, off_at + 16_000, sim.now_cycles())
    lines = sketch.status_between(off_at + 200_000, sim.now_cycles())
    assert lines and all("X" in s[6] for s in lines), lines
    sketch.command("ON")
    on_at = sim.run_for(0.2)
    assert len(flashes_between(sim.oc1a, on_at + 200_000, sim.now_cycles())) > 50
    sketch.port.write(b"ID?\nWIDTH 0\nDIV 101\nOFFSET x\nFOO 1\n")
    replies = []
    deadline = time.monotonic() + 5
    while len(replies) < 5 and time.monotonic() < deadline:
        replies += sketch._pump()
    assert replies[:5] == [b"ID labkit-strobe 1.0", b"ERR bad value", b"ERR bad value", b"ERR bad value",
                           b"ERR unknown command"], replies


def test_labkit_probe_strobe_reads_the_sketch(simavr, capsys):
    """labkit's own driver (``labkit probe strobe``) on the sketch's pseudo-terminal: the
    settings it sends are taken, and the status lines give the rotor and the offset."""
    sim = simavr("labkit_strobe")
    sim.rotor(800.0)
    code = main(["probe", "strobe", "--protocol", "labkit_strobe", "--port", sim.pty, "--samples", "4",
                 "--json", "-o", "offset_hz=1.25", "-o", "rate_hz=10", "-o", "divider=2"])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert '"model": "labkit-strobe"' in err
    last = [json.loads(line) for line in out.splitlines()][-2:]
    for status in last:
        assert status["stable"] and status["flags"] == [], status
        assert status["rotor_hz"] == pytest.approx(800.0, rel=1e-5), status
        assert status["apparent_hz"] == pytest.approx(1.25, abs=5e-4), status
        assert status["strobe_hz"] == pytest.approx((800.0 - 1.25) / 2, rel=1e-5), status


@pytest.mark.parametrize("width_us", [2, 5])
def test_short_flashes_at_2_khz_are_ended_by_the_hardware(strobe, width_us):
    """The end compare is set by an interrupt that waits just before the flash:
    5 us (1.8 deg at 1 kHz) comes out exact but for the odd one, 2 us mostly; a flash held up
    by another interrupt (the UART's) is flagged ``S`` (stretched), never silently."""
    sim, sketch = strobe
    sketch.command(f"WIDTH {width_us}")
    sketch.command("OFFSET 3")
    sim.rotor(2000.0)
    sim.run_for(0.1)
    start = sim.now_cycles()
    sim.run_for(0.4)
    end = sim.now_cycles()
    widths = [fall - rise for rise, fall in sim.oc1a if start <= rise < end]
    exact = [w for w in widths if abs(w - 16 * width_us) <= 1]
    assert len(widths) > 700
    assert len(exact) >= (0.99 if width_us >= 5 else 0.9) * len(widths), sorted(set(widths))
    if len(exact) < len(widths):
        flags = "".join(s[6] for s in sketch.status_between(start, end, overlapping=True))
        assert "S" in flags, sketch.status[-5:]
