"""A slow motor controller never stalls a streaming sensor: each stream has its own reader
thread (real clock), so the tachometer keeps its rate while the host waits on the motor."""

import pytest

from labkit.devices.registry import driver_class
from labkit.io.clock import RealClock
from labkit.io.ports import open_port

pytestmark = pytest.mark.timeout(30)


def test_tachometer_keeps_its_rate_while_motor_replies_take_300_ms():
    clock = RealClock()
    smc = driver_class("motor", "pololu_smc")
    motor_port = open_port("sim://pololu_smc?plant=slow&faults=delay:0.3", clock=clock, timeout=0,
                           **smc.default_serial)
    tach_cls = driver_class("tachometer", "labkit_tach")
    tach_port = open_port("sim://labkit_tach?plant=slow&rate_hz=20&boot_s=0.05", clock=clock, timeout=0,
                          **tach_cls.default_serial)
    with tach_cls(tach_port, clock, name="rotor_tach") as tach, \
            smc(motor_port, clock, name="rotor_motor", reply_timeout_s=1.0) as motor:
        tach.wait_reading(timeout=2.0)
        start = clock.now()
        for _ in range(4):
            motor.status()                       # each blocks the host for >= 0.3 s
        waited = clock.now() - start
        times = [r.t for r in tach.readings_since(start)]
    assert waited >= 1.2
    assert len(times) >= 0.7 * 20 * waited       # the 20 Hz stream went on meanwhile
    assert max(b - a for a, b in zip(times, times[1:], strict=False)) < 0.2
