"""Tachometer drivers against their emulators on real pseudo-terminals, real clock (reader
threads), including an unplug seen by real I/O and a replug under a new /dev/pts path."""

from __future__ import annotations

import threading

import pytest

from labkit.devices.registry import driver_class
from labkit.emulators.plant import shared_plant
from labkit.emulators.sim_port import build_emulator
from labkit.errors import DeviceDisconnected, DeviceTimeout
from labkit.io.clock import RealClock
from labkit.io.ports import open_port
from labkit.io.pty_host import PtyHost
from labkit.units import RAD_S_PER_RPM

pytestmark = pytest.mark.timeout(30)


def settled_rotor(clock: RealClock, rpm: float) -> float:
    """Put the pty plant's rotor at a steady ``rpm`` (already settled) and return rad/s."""
    motor = shared_plant("pty").motor("rotor")
    motor.speed_rad_s = rpm * RAD_S_PER_RPM
    motor.duty = rpm * RAD_S_PER_RPM / motor.max_speed_rad_s
    motor.t = clock.now()
    return rpm * RAD_S_PER_RPM


def open_on_pty(host: PtyHost, protocol: str, clock: RealClock, **options):
    cls = driver_class("tachometer", protocol)
    port = open_port(host.path, clock=clock, timeout=0, **cls.default_serial)
    return cls(port, clock, name=f"tach on {host.path}", **options)


def test_labkit_tach_over_a_pty():
    clock = RealClock()
    expected = settled_rotor(clock, 18_000.0)
    emulator = build_emulator("sim://labkit_tach?plant=pty&rate_hz=50&boot_s=0.05")
    with PtyHost(emulator, clock=clock) as host:
        with open_on_pty(host, "labkit_tach", clock, ppr=2) as tach:
            assert tach.identify()["model"] == "labkit-tach"
            first = tach.wait_reading(timeout=2.0)
            clock.sleep(0.3)
            readings = tach.readings_since(first.t)
    assert len(readings) >= 5
    assert all(r.value == pytest.approx(expected, rel=0.01) for r in readings)


def test_lutron_over_a_pty_with_garbage():
    clock = RealClock()
    expected = settled_rotor(clock, 2500.0)
    emulator = build_emulator("sim://lutron16?plant=pty&rate_hz=20&faults=garbage:0.5")
    with PtyHost(emulator, clock=clock) as host:
        with open_on_pty(host, "lutron16", clock) as tach:
            first = tach.wait_reading(timeout=2.0)
            clock.sleep(0.4)
            readings = tach.readings_since(first.t - 1e-9)
    assert len(readings) >= 4
    assert all(r.value == pytest.approx(expected, abs=0.05 * RAD_S_PER_RPM) for r in readings)


def test_monarch_over_a_pty_identifies_and_streams():
    clock = RealClock()
    expected = settled_rotor(clock, 8000.0)
    emulator = build_emulator("sim://monarch_at?plant=pty&faults=split:0.5")
    with PtyHost(emulator, clock=clock) as host:
        with open_on_pty(host, "monarch_at", clock) as tach:
            assert tach.identify() == {"model": "ACT-3X", "firmware": "1.00"}
            first = tach.wait_reading(timeout=3.0)
            second = tach.wait_reading(timeout=3.0)
    assert second.t > first.t
    for r in (first, second):        # the display rate is 2 per second, 0.1 RPM resolution
        assert r.value == pytest.approx(expected, abs=0.06 * RAD_S_PER_RPM + 1e-3 * expected)


def test_unplug_is_detected_by_real_io_and_the_device_comes_back_under_a_new_path():
    clock = RealClock()
    expected = settled_rotor(clock, 9000.0)
    back = threading.Event()
    emulator = build_emulator("sim://labkit_tach?plant=pty&rate_hz=50&boot_s=0.05")
    with PtyHost(emulator, clock=clock, on_reconnect=lambda path: back.set()) as host:
        first_path = host.path
        tach = open_on_pty(host, "labkit_tach", clock)
        tach.wait_reading(timeout=5.0)
        host.unplug(back_after_s=0.3)   # once a reading arrived, not at a fixed time after open
        with pytest.raises(DeviceDisconnected) as info:
            for _ in range(200):
                try:
                    tach.wait_reading(timeout=0.1)
                except DeviceTimeout:   # silence before the reader meets the hung-up pty
                    continue
        assert first_path in str(info.value)
        tach.close()
        assert back.wait(5.0) and host.path != first_path
        with open_on_pty(host, "labkit_tach", clock) as again:
            assert again.wait_reading(timeout=5.0).value == pytest.approx(expected, rel=0.01)
