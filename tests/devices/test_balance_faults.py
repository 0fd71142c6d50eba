"""Fault matrix for the balance drivers (PROTOCOLS 5.2/5.3): garbage, partial frames, wrong
baud, timeout, error reply, overload, unstable, reset, unplug mid-read, reconnect. The
driver either resyncs and reads true values or raises a DeviceError naming device,
command and last bytes. Emulators run behind sim:// on a virtual clock or a real pty."""

from __future__ import annotations

import math

import pytest
import serial

from labkit.devices.balance import and_std, mtsics
from labkit.devices.registry import driver_class
from labkit.emulators.balances import MtSicsEmulator
from labkit.emulators.plant import reset_plants, shared_plant
from labkit.emulators.rig_plant import RigPlant
from labkit.errors import DeviceDisconnected, DeviceReplyError, DeviceTimeout
from labkit.io.clock import RealClock, VirtualClock
from labkit.io.ports import open_port
from labkit.io.pty_host import PtyHost

AND_7E1 = {"baudrate": 2400, "bytesize": 7, "parity": "E"}


def mt(query: str = "", clock=None, settings=None, **options):
    clock = clock or VirtualClock()
    port = open_port(f"sim://mtsics?seed=4&plant=flt{query}", clock=clock, timeout=0, **(settings or {}))
    return driver_class("balance", "mtsics")(port, clock, name="bal", **options), clock


def ad(query: str = "", clock=None, **options):
    clock = clock or VirtualClock()
    port = open_port(f"sim://and_std?seed=4&plant=flt{query}", clock=clock, timeout=0, **AND_7E1)
    return driver_class("balance", "and_std")(port, clock, name="bal", **options), clock


def clean(reading, parse) -> None:
    """A reading's raw bytes are one valid frame, and its value is the frame's number."""
    frame = parse(reading.raw)
    assert math.isfinite(reading.value)
    assert frame.value is not None


@pytest.mark.parametrize("faults", ["garbage:0.4", "split:0.7", "garbage:0.3,split:0.5"])
def test_garbage_and_partial_frames_resync_to_true_readings(faults):
    for make, parse in ((mt, mtsics.parse_weight), (ad, and_std.parse_line)):
        reset_plants()
        balance, clock = make(f"&faults={faults}")
        shared_plant("flt").set_duty(0.5, clock.now())
        clock.sleep(4.0)
        readings = [balance.read(timeout=5.0) for _ in range(20)]
        for reading in readings:
            clean(reading, parse)
            assert reading.value * 1e3 == pytest.approx(4.02, abs=0.05) or reading.unit == "N"
        balance.close()


def test_wrong_baud_says_check_baud_rate_and_parity():
    with pytest.raises(DeviceTimeout, match=r"only garbage; check baud rate/parity \(expected 2400 7E1, "
                                            r"port is 9600 8N1\)") as err:
        clock = VirtualClock()
        port = open_port("sim://and_std?plant=flt", clock=clock, timeout=0, baudrate=9600)
        driver_class("balance", "and_std")(port, clock, name="and-balance")
    assert err.value.device == "and-balance" and err.value.command == "C" and err.value.last_bytes
    with pytest.raises(DeviceTimeout, match="check baud rate/parity"):
        mt(settings={"baudrate": 2400})


def test_silent_device_times_out_with_a_clear_message():
    with pytest.raises(DeviceTimeout, match="no reply in 2 s; check the cable") as err:
        mt("&faults=drop_reply:1")
    assert err.value.command == "@"


def test_lost_replies_are_resent():
    balance, clock = mt("&faults=drop_reply:0.4", command_timeout_s=10)
    readings = [balance.read(timeout=5.0) for _ in range(10)]
    assert all(math.isfinite(r.value) for r in readings)


def test_slow_replies_within_the_timeout_are_waited_for():
    balance, clock = mt("&faults=delay:0.3")
    start = clock.now()
    reading = balance.read(timeout=2.0)
    assert clock.now() - start >= 0.3 and math.isfinite(reading.value)


def test_error_replies_raise_naming_command_and_bytes():
    balance, _ = mt()
    balance.port.emulator.faults["error_reply"] = 1.0
    with pytest.raises(DeviceReplyError, match="logical error") as err:
        balance.read()
    assert err.value.command == "SI" and err.value.last_bytes.endswith(b"EL\r\n")
    balance2, _ = ad()
    balance2.port.emulator.faults["error_reply"] = 1.0
    with pytest.raises(DeviceReplyError, match=r"not ready \(EC,E02\)"):
        balance2.read()


def test_unknown_command_gives_es_and_identify_skips_what_the_model_lacks():
    balance, _ = mt()
    with pytest.raises(DeviceReplyError, match="syntax error"):
        balance.command("XYZ", "XYZ", 1.0)  # what a model without the command answers


def test_overload_is_flagged_and_never_a_value():
    for make in (mt, ad):
        balance, clock = make("&capacity_g=2")  # 4 g of PFR force on a 2 g balance
        shared_plant("flt").set_duty(0.5, clock.now())
        clock.sleep(4.0)
        reading = balance.read()
        assert reading.overload and not reading.stable and math.isnan(reading.value)
        assert b"+" in reading.raw or reading.raw.startswith(b"OL")
        reset_plants()


def test_mtsics_zero_out_of_range_and_underload():
    balance, clock = mt("&faults=underload:1")
    reading = balance.read()
    assert reading.overload and "underload" in reading.flags
    with pytest.raises(DeviceReplyError, match="underload"):
        balance.zero()


def test_unstable_force_makes_stable_commands_wait_then_fail():
    # vibration: noise well above the stability band, so the balance never settles
    balance, clock = mt("&stability_timeout_s=1&noise_g=0.2")
    assert not balance.read().stable
    start = clock.now()
    with pytest.raises(DeviceReplyError, match=r"no stable value") as err:
        balance.read_stable(timeout=10)
    assert clock.now() - start >= 1.0 and err.value.last_bytes.endswith(b"S I\r\n")
    balance2, _ = ad("&stability_timeout_s=1&noise_g=0.2")
    with pytest.raises(DeviceReplyError, match=r"EC,E11"):
        balance2.zero(timeout=10)


def test_and_double_ack_zero_and_no_ack_mode():
    balance, clock = ad()
    balance.zero()  # receipt ACK + completion ACK
    quiet, clock2 = ad("&ack=0", ack=False, settle_s=1.0)
    start = clock2.now()
    quiet.zero()
    assert clock2.now() - start >= 1.0
    assert math.isfinite(quiet.read().value)


def test_device_reset_is_flagged_and_tare_is_gone():
    balance, clock = mt("&faults=reset_at:5")
    shared_plant("flt").set_duty(0.5, clock.now())
    clock.sleep(3.0)
    balance.tare()
    assert abs(balance.read().value) < 2e-5
    clock.sleep(3.0)  # the balance resets at 5 s: junk + I4 line, power-on zero
    after = balance.read(timeout=3.0)
    assert "device_reset" in after.flags
    assert balance.resets_seen == 1
    assert balance.tare_value().value == 0.0


def test_unplug_mid_read_names_device_command_and_last_bytes():
    balance, clock = mt("&faults=disconnect_at:1.0")
    while clock.now() < 0.9:
        balance.read()
    with pytest.raises(DeviceDisconnected, match="port disconnected") as err:
        for _ in range(100):
            balance.read()
    assert err.value.device == "bal" and err.value.command == "SI"
    assert err.value.last_bytes.endswith(b" g\r\n")


def test_reconnect_gives_a_fresh_device_on_reopen():
    balance, clock = mt("&faults=disconnect_at:1.0,reconnect_after:2.0")
    clock.sleep(1.5)
    with pytest.raises(DeviceDisconnected):
        balance.read()
    port = balance.port
    port.close()
    with pytest.raises(serial.SerialException):
        port.open()  # still unplugged
    clock.sleep(2.0)
    port.open()
    again = driver_class("balance", "mtsics")(port, clock, name="bal")
    assert again.identify()["serial"] == "B207696838"
    assert math.isfinite(again.read().value)


def test_unplugged_pty_is_detected_by_real_io_and_replugs_under_a_new_path():
    clock = RealClock()
    emulator = MtSicsEmulator(plant=RigPlant(), seed=1,
                              faults={"disconnect_at": 0.4, "reconnect_after": 0.3})
    paths: list[str] = []
    with PtyHost(emulator, clock=clock, on_reconnect=paths.append) as host:
        first = host.path
        port = open_port(first, baudrate=9600, timeout=0)
        balance = driver_class("balance", "mtsics")(port, clock, name="pty-bal")
        with pytest.raises(DeviceDisconnected) as err:
            for _ in range(200):
                balance.read(timeout=1.0)
        assert port.is_open  # pyserial still believes it is open: only real I/O can tell
        assert err.value.device == "pty-bal"
        balance.close()
        deadline = clock.now() + 3.0
        while not paths and clock.now() < deadline:
            clock.sleep(0.02)
        assert paths and paths[0] != first
        port2 = open_port(paths[0], baudrate=9600, timeout=0)
        with driver_class("balance", "mtsics")(port2, clock, name="pty-bal") as again:
            assert math.isfinite(again.read().value)
