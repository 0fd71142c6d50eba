"""The streaming-only Lutron tachometer when its stream stops (meter switched off, cable
pulled at the meter end, the host's port still open): a read fails after its timeout with a
DeviceTimeout naming device, what it waited for and the last bytes seen; it never hangs and
never hands back the last (stale) reading. Over ``sim://`` on a virtual clock (``stop_at``
fault) and over a real pseudo-terminal on the real clock."""

from __future__ import annotations

import pytest

from labkit.devices.registry import driver_class
from labkit.devices.tachometer.lutron16 import parse_lutron16
from labkit.emulators.plant import shared_plant
from labkit.emulators.sim_port import build_emulator
from labkit.errors import DeviceTimeout
from labkit.io.clock import RealClock, VirtualClock
from labkit.io.ports import open_port
from labkit.io.pty_host import PtyHost
from labkit.units import RAD_S_PER_RPM

RPM = 3000.0


def spin(plant: str, clock) -> None:
    """The plant's rotor steady at 3000 RPM from now."""
    motor = shared_plant(plant).motor("rotor")
    motor.advance(clock.now())
    motor.speed_rad_s = RPM * RAD_S_PER_RPM
    motor.duty = motor.speed_rad_s / motor.max_speed_rad_s


def open_lutron(query: str, clock, settings: dict | None = None, **options):
    cls = driver_class("tachometer", "lutron16")
    port = open_port(f"sim://lutron16?plant=lut&rate_hz=5{query}", clock=clock, timeout=0,
                     **(settings or cls.default_serial))
    return cls(port, clock, name="rotor tach", **options)


def test_stopped_stream_times_out_naming_device_wait_and_last_frame():
    clock = VirtualClock()
    tach = open_lutron("&faults=stop_at:3", clock)
    spin("lut", clock)
    clock.sleep(2.5)
    assert tach.wait_reading(timeout=1.0).value == pytest.approx(RPM * RAD_S_PER_RPM, rel=1e-4)
    clock.sleep(1.0)                                    # the meter went quiet at 3 s
    start = clock.now()
    with pytest.raises(DeviceTimeout) as err:
        tach.wait_reading(timeout=1.5)
    assert clock.now() - start == pytest.approx(1.5, abs=0.02)   # its timeout, no hang
    exc = err.value
    assert exc.device == "rotor tach" and exc.command == "stream"
    assert "waiting for a 16-byte frame of display 1" in str(exc)
    assert "the meter sent nothing" in str(exc) and "last reading" in str(exc)
    # the last bytes are the last frame the meter sent: 3000.0 RPM
    assert parse_lutron16(exc.last_bytes[-16:]).value == pytest.approx(RPM)
    # latest() still holds the old value (that is what it is for); a read never returns it
    stale = tach.latest()
    assert stale is not None and stale.t < 3.0
    with pytest.raises(DeviceTimeout):
        tach.wait_reading(timeout=0.5)


def test_silent_from_open_says_so():
    clock = VirtualClock()
    tach = open_lutron("&faults=stop_at:0", clock)
    with pytest.raises(DeviceTimeout, match="sent nothing.*no reading since open") as err:
        tach.wait_reading(timeout=2.0)
    assert err.value.last_bytes == b""


def test_timeout_message_tells_silence_from_garbage_and_refused_frames():
    clock = VirtualClock()
    wrong_baud = open_lutron("", clock, settings={"baudrate": 19200})  # bytes, but no frames
    with pytest.raises(DeviceTimeout, match="check baud rate"):
        wrong_baud.wait_reading(timeout=2.0)
    other_unit = open_lutron("&annunciator=01", clock)  # 01 = degC: frames, all refused
    with pytest.raises(DeviceTimeout, match="frames this driver refuses"):
        other_unit.wait_reading(timeout=2.0)


@pytest.mark.timeout(30)
def test_stopped_stream_over_a_real_pty_times_out():
    clock = RealClock()
    spin("pty-lut", clock)
    emulator = build_emulator("sim://lutron16?plant=pty-lut&rate_hz=20")
    with PtyHost(emulator, clock=clock) as host:
        cls = driver_class("tachometer", "lutron16")
        port = open_port(host.path, clock=clock, timeout=0, **cls.default_serial)
        with cls(port, clock, name="pty tach") as tach:
            first = tach.wait_reading(timeout=5.0)
            assert first.value == pytest.approx(RPM * RAD_S_PER_RPM, rel=1e-3)
            # the meter is switched off once its first reading arrived (event-driven: a fault at
            # a fixed time after open may fall before the test is ready on a loaded machine)
            emulator.faults["stop_at"] = emulator.since_open(clock.now())
            with pytest.raises(DeviceTimeout, match="the meter sent nothing") as err:
                for _ in range(3):  # a frame already on its way may still arrive, then nothing
                    tach.wait_reading(timeout=0.5)
    assert err.value.device == "pty tach" and err.value.last_bytes.endswith(b"\r")
