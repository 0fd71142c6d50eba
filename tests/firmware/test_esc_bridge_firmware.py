"""firmware/labkit_esc_bridge compiled and run on a simulated ATmega328P, driven by labkit's
``esc_bridge`` driver over its pseudo-terminal; the servo pulses on pin 9 are measured in
the simulator (PROTOCOLS 3.3: speed 0..3200 -> 1000..2000 us at 50 Hz, 500 ms command
timeout -> 1000 us)."""

from __future__ import annotations

import pytest

from labkit.devices.registry import driver_class
from labkit.io.clock import RealClock
from labkit.io.ports import open_port

pytestmark = pytest.mark.timeout(120)
WIDTH_TOLERANCE_US = 3.0   # interrupt-timed pulses: a few cycles of latency


def widths_after(sim, t_us: float) -> list[float]:
    return [w for t, w in sim.pwm if t > t_us]


def wait_width(sim, width_us: float, after_us: float, n: int = 3, timeout: float = 5.0) -> float:
    """Simulated time of the first of ``n`` pulses in a row of ``width_us`` after ``after_us``."""
    def found() -> float | None:
        run = [(t, w) for t, w in sim.pwm if t > after_us]
        for i in range(len(run) - n + 1):
            if all(abs(w - width_us) <= WIDTH_TOLERANCE_US for _, w in run[i:i + n]):
                return run[i][0]
        return None

    assert sim.wait_for(lambda: found() is not None, timeout), (
        f"no {n} pulses of {width_us} us; last widths {[w for _, w in sim.pwm[-8:]]}")
    t = found()
    assert t is not None
    return t


def test_driver_sets_pulse_widths_and_close_returns_to_1000_us(simavr):
    sim = simavr("labkit_esc_bridge")
    t0 = wait_width(sim, 1000.0, 0.0)              # zero throttle from the first pulses
    period = [b[0] - a[0] for a, b in zip(sim.pwm, sim.pwm[1:], strict=False)][:5]
    assert period == pytest.approx([20000.0] * len(period), abs=WIDTH_TOLERANCE_US)  # 50 Hz
    clock = RealClock()
    cls = driver_class("motor", "esc_bridge")
    port = open_port(sim.pty, clock=clock, timeout=0, **cls.default_serial)
    motor = cls(port, clock, name="esc bridge on simavr")
    try:
        motor.enable()
        for duty, width in ((0.5, 1500.0), (0.25, 1250.0), (1.0, 2000.0)):
            motor.set_duty(duty)
            t0 = wait_width(sim, width, t0)
            status = motor.status()
            assert status.duty == pytest.approx(duty, abs=1 / 3200) and not status.errors
        clock.sleep(1.0)   # the driver's 20 Hz refresh keeps the bridge's 500 ms timeout away
        assert all(abs(w - 2000.0) <= WIDTH_TOLERANCE_US for w in widths_after(sim, t0))
    finally:
        motor.close()      # commands zero
    wait_width(sim, 1000.0, t0)


def test_command_timeout_cuts_the_pulse_when_commands_stop(simavr):
    sim = simavr("labkit_esc_bridge")
    wait_width(sim, 1000.0, 0.0)
    clock = RealClock()
    port = open_port(sim.pty, clock=clock, timeout=0, baudrate=115200)
    try:
        port.write(bytes.fromhex("83 85 00 32"))   # exit safe start, speed 1600: 1500 us; then silence
        running = wait_width(sim, 1500.0, 0.0, n=1)
        stopped = wait_width(sim, 1000.0, running, n=3)
        # the last command arrived just before the first 1500 us pulse; 500 ms later the
        # bridge drops to 1000 us (one 20 ms period of slack each side)
        assert 500_000 - 20_000 <= stopped - running <= 500_000 + 20_000
        port.write(bytes.fromhex("A1 00"))          # error status: bit 3, command timeout
        reply = b""
        deadline = clock.now() + 2.0
        while len(reply) < 2 and clock.now() < deadline:
            clock.sleep(0.01)
            reply += port.read(2 - len(reply))
        assert int.from_bytes(reply, "little") & (1 << 3)
        assert all(abs(w - 1000.0) <= WIDTH_TOLERANCE_US for w in widths_after(sim, stopped))
    finally:
        port.close()
