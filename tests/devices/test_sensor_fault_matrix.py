"""The fault matrix of issue 2 across every balance and tachometer driver, one table.

Each sensor driver reads its own emulator over ``sim://`` on a virtual clock, with the rotor
of the shared plant held at 9000 RPM (the balances weigh the Fig. 5.25 force of that speed,
the tachometers see it). Per case the driver either resyncs to true readings or raises a
clear DeviceError naming the device; a dead port is found by real I/O.
"""

from __future__ import annotations

import math

import pytest
import serial

from labkit.devices.registry import driver_class
from labkit.emulators.plant import shared_plant
from labkit.emulators.rig_plant import fig525_force_n
from labkit.errors import DeviceDisconnected, DeviceError
from labkit.io.clock import VirtualClock
from labkit.io.ports import open_port
from labkit.units import G0, RAD_S_PER_RPM

RPM = 9000.0
# name -> (kind, driver protocol, emulator, extra query, driver options)
SENSORS = {
    "mtsics": ("balance", "mtsics", "mtsics", "", {}),
    "and_std": ("balance", "and_std", "and_std", "", {}),
    "hx711": ("balance", "line_regex", "hx711", "&startup_s=0.2", {"preset": "hx711_adc"}),
    "labkit_tach": ("tachometer", "labkit_tach", "labkit_tach", "", {}),
    "lutron16": ("tachometer", "lutron16", "lutron16", "&rate_hz=5", {}),
    "monarch_at": ("tachometer", "monarch_at", "monarch_at", "", {}),
}


def spin_rotor(clock: VirtualClock) -> None:
    """Hold the plant's rotor at 9000 RPM from now (after power-on: a balance zeroes then)."""
    motor = shared_plant("fm").motor("rotor")
    motor.advance(clock.now())
    motor.speed_rad_s = RPM * RAD_S_PER_RPM
    motor.duty = motor.speed_rad_s / motor.max_speed_rad_s


def open_sensor(name: str, faults: str, clock: VirtualClock):
    kind, protocol, emulator, query, options = SENSORS[name]
    cls = driver_class(kind, protocol)
    settings = cls.default_serial    # hx711_adc sketch: 57600 8N1, the line_regex default
    url = f"sim://{emulator}?seed=5&plant=fm&noise_g=0{query}" + (f"&faults={faults}" if faults else "")
    port = open_port(url, clock=clock, timeout=0, **settings)
    device = cls(port, clock, name=f"{name} sensor", **options)
    spin_rotor(clock)
    return device


def read(device, timeout: float = 3.0):
    """One new reading through the driver's public interface."""
    return device.read(timeout=timeout) if hasattr(device, "read_stable") else device.wait_reading(timeout)


def truth(name: str) -> float:
    """What the device should report at 9000 RPM, in the reading's SI unit."""
    if SENSORS[name][0] == "tachometer":
        return RPM * RAD_S_PER_RPM
    return fig525_force_n(RPM * RAD_S_PER_RPM)


def as_si(name: str, reading) -> float:
    if reading.quantity == "mass":
        return reading.value * G0     # kg on the pan -> N
    return reading.value


def tolerance(name: str) -> float:
    return 0.02 * truth(name) if SENSORS[name][0] == "tachometer" else 0.02e-3 * G0 + 0.01 * truth(name)


@pytest.mark.parametrize("name", sorted(SENSORS))
def test_garbage_and_partial_frames_never_become_a_wrong_value(name):
    clock = VirtualClock()
    device = open_sensor(name, "garbage:0.3,split:0.5", clock)
    clock.sleep(1.0)
    values = [as_si(name, read(device)) for _ in range(8)]
    assert all(v == pytest.approx(truth(name), abs=tolerance(name)) for v in values), values


@pytest.mark.parametrize("name", sorted(SENSORS))
def test_wrong_baud_gives_no_reading_but_a_clear_error(name):
    clock = VirtualClock()
    with pytest.raises(DeviceError) as info:
        device = open_sensor(name, "wrong_baud", clock)
        for _ in range(3):
            reading = read(device, timeout=2.0)
            # a garbled line must never pass as a plausible value
            assert not math.isfinite(reading.value) or reading.value != pytest.approx(truth(name), rel=0.2)
    assert f"{name} sensor" in str(info.value)


@pytest.mark.parametrize("name", sorted(SENSORS))
def test_unplug_mid_read_is_a_disconnect_found_by_real_io(name):
    clock = VirtualClock()
    device = open_sensor(name, "disconnect_at:2", clock)
    clock.sleep(0.5)
    assert as_si(name, read(device)) == pytest.approx(truth(name), abs=tolerance(name))
    clock.sleep(2.5)
    assert device.port.is_open           # pyserial still believes it is open ...
    with pytest.raises(DeviceDisconnected) as info:
        for _ in range(5):              # ... the next real read says otherwise
            read(device, timeout=1.0)
    assert f"{name} sensor" in str(info.value)


@pytest.mark.parametrize("name", sorted(SENSORS))
def test_reconnect_then_reopen_reads_true_values_again(name):
    clock = VirtualClock()
    device = open_sensor(name, "disconnect_at:2,reconnect_after:1", clock)
    clock.sleep(2.5)
    with pytest.raises(DeviceDisconnected):
        for _ in range(5):
            read(device, timeout=1.0)
    port = device.port
    port.close()
    with pytest.raises(serial.SerialException):
        port.open()                      # still unplugged
    clock.sleep(1.0)
    port.open()                          # plugged back in: the device has power-cycled
    kind, protocol, _, _, options = SENSORS[name]
    again = driver_class(kind, protocol)(port, clock, name=f"{name} sensor", **options)
    clock.sleep(0.5)
    # a balance zeroes at power-on with the force on it (as real ones do); a tachometer
    # simply sees the rotor again
    expected = truth(name) if kind == "tachometer" else 0.0
    assert as_si(name, read(again)) == pytest.approx(expected, abs=tolerance(name))
