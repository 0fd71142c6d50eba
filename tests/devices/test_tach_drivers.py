"""Tachometer drivers against their emulators over sim:// on a virtual clock, and the
fault matrix (PROTOCOLS 5.2): each fault either resyncs or ends in a clear DeviceError."""

from __future__ import annotations

import math

import pytest
from sim_driver import open_sim_driver

from labkit.devices.registry import driver_class
from labkit.emulators.plant import reset_plants, shared_plant
from labkit.errors import DeviceDisconnected, DeviceReplyError, DeviceTimeout
from labkit.io.clock import VirtualClock
from labkit.units import RAD_S_PER_RPM


def open_tach(protocol: str, query: str = "", clock: VirtualClock | None = None,
              settings: dict | None = None, **options):
    return open_sim_driver("tachometer", protocol, "t", "rotor_tach", query, clock, settings, **options)


def spin_rotor(rpm: float, t: float = 0.0) -> float:
    """Run the plant's rotor to ``rpm`` (steady state of the first-order lag); returns rad/s."""
    motor = shared_plant("t").motor("rotor")
    motor.max_speed_rad_s = max(motor.max_speed_rad_s, 2 * rpm * RAD_S_PER_RPM)
    duty = rpm * RAD_S_PER_RPM / motor.max_speed_rad_s
    shared_plant("t").set_duty(duty, t)
    return rpm * RAD_S_PER_RPM


# ---- labkit pulse tachometer ---------------------------------------------------------------

@pytest.mark.parametrize("rpm, ppr", [(600.0, 1), (24_000.0, 2), (100_000.0, 1)])
def test_labkit_tach_reads_the_rotor_speed(rpm, ppr):
    tach, clock = open_tach("labkit_tach", ppr=ppr)
    expected = spin_rotor(rpm)
    t0 = clock.now()
    clock.sleep(6.0)  # 15 time constants: settled
    readings = tach.readings_since(t0 + 5.0)
    assert len(readings) == pytest.approx(10, abs=1)       # 10 Hz default rate
    for r in readings:
        assert r.quantity == "angular_speed" and r.unit == "rad/s" and r.stable
        # micros() quantisation (4 us) averaged over a window: well under 1 %
        assert r.value == pytest.approx(expected, rel=0.01)
    assert readings[-1].raw.startswith(b"T,")


def test_labkit_tach_configures_rate_and_identifies():
    tach, clock = open_tach("labkit_tach", rate_hz=50, zto_ms=300)
    assert tach.identify() == {"model": "labkit-tach", "firmware": "1.0", "ppr": 1}
    clock.sleep(0.5)  # the window that was running when RATE arrived ends first
    start = clock.now()
    clock.sleep(1.0)
    assert len(tach.readings_since(start)) == pytest.approx(50, abs=2)


def test_labkit_tach_zero_speed_timeout_flag():
    tach, clock = open_tach("labkit_tach", zto_ms=200)
    spin_rotor(3000.0)
    clock.sleep(3.0)
    shared_plant("t").set_duty(0.0, clock.now())
    clock.sleep(5.0)
    last = tach.latest()
    assert last.value == 0.0 and "zero_speed" in last.flags


def test_labkit_tach_watches_the_floator_spin():
    shared_plant("t").floator_spin_rad_s = 300.0
    tach, clock = open_tach("labkit_tach", "&source=floator")
    spin_rotor(20_000.0)
    clock.sleep(2.0)
    assert tach.wait_reading().value == pytest.approx(300.0, rel=0.01)


def test_wait_reading_returns_a_new_reading():
    tach, clock = open_tach("labkit_tach")
    spin_rotor(1200.0)
    before = clock.now()
    reading = tach.wait_reading(timeout=1.0)
    assert reading.t > before


# ---- labkit tach fault matrix ---------------------------------------------------------------

@pytest.mark.parametrize("faults", ["garbage:0.5", "split:0.7", "mid_frame,dtr_reset:0", "noisy:0.3"])
def test_labkit_tach_faults_never_produce_a_wrong_value(faults):
    query = "&faults=" + faults.split(",")[0]
    if "dtr_reset:0" in faults:
        query += "&dtr_reset=0"
    tach, clock = open_tach("labkit_tach", query)
    expected = spin_rotor(12_000.0)
    clock.sleep(8.0)
    readings = tach.readings_since(4.0)
    assert len(readings) >= 20
    assert all(r.value == pytest.approx(expected, rel=0.01) for r in readings)
    if faults.startswith("noisy"):
        assert any(not r.stable and "noisy" in r.flags for r in readings)


def test_labkit_tach_overload_is_flagged_never_a_number():
    tach, clock = open_tach("labkit_tach", "&faults=overload")
    spin_rotor(12_000.0)
    reading = tach.wait_reading()
    assert reading.overload and math.isnan(reading.value) and "over_range" in reading.flags


def test_labkit_tach_wrong_baud_is_a_clear_error_at_open():
    with pytest.raises(DeviceTimeout) as info:
        open_tach("labkit_tach", settings={"baudrate": 9600})
    message = str(info.value)
    assert "rotor_tach" in message and "'open'" in message and "last bytes" in message


def test_labkit_tach_error_reply_names_the_command():
    with pytest.raises(DeviceReplyError) as info:
        open_tach("labkit_tach", "&faults=error_reply:1", ppr=2)
    assert "PPR 2" in str(info.value) and "ERR busy" in str(info.value)


def test_labkit_tach_missing_reply_times_out_naming_the_command():
    with pytest.raises(DeviceTimeout) as info:
        open_tach("labkit_tach", "&faults=drop_reply:1")
    assert "PPR 1" in str(info.value) and "no reply" in str(info.value)


def test_labkit_tach_reset_is_flagged_and_settings_are_sent_again():
    tach, clock = open_tach("labkit_tach", "&faults=reset_at:3", ppr=2)
    expected = spin_rotor(6000.0)
    clock.sleep(8.0)
    readings = tach.readings_since(0.0)
    assert tach.resets == 1
    reset = [r for r in readings if "reset" in r.flags]
    assert len(reset) == 1 and 3.0 < reset[0].t < 4.0
    after = [r for r in readings if r.t > 5.0]
    assert after and all(r.value == pytest.approx(expected, rel=0.01) for r in after)


def test_labkit_tach_unplug_mid_read_is_a_disconnect_naming_the_device():
    tach, clock = open_tach("labkit_tach", "&faults=disconnect_at:2")
    spin_rotor(6000.0)
    clock.sleep(1.5)
    assert tach.latest() is not None
    clock.sleep(1.0)
    with pytest.raises(DeviceDisconnected) as info:
        tach.latest()
    assert "rotor_tach" in str(info.value) and "disconnected" in str(info.value)


def test_labkit_tach_reconnect_then_reopen_resyncs_from_the_boot_banner():
    clock = VirtualClock()
    tach, _ = open_tach("labkit_tach", "&faults=disconnect_at:2,reconnect_after:1", clock=clock, ppr=2)
    expected = spin_rotor(6000.0)
    clock.sleep(2.5)
    with pytest.raises(DeviceDisconnected):
        tach.latest()
    clock.sleep(1.0)                     # plugged back in
    tach.port.close()
    tach.port.open()                     # the same emulator, power-cycled
    again = driver_class("tachometer", "labkit_tach")(tach.port, clock, name="rotor_tach", ppr=2)
    assert again.banner["version"] == "1.0"
    assert again.wait_reading(timeout=2.0).value == pytest.approx(expected, rel=0.01)


# ---- Lutron 16-byte stream ------------------------------------------------------------------

@pytest.mark.parametrize("rpm, resolution", [(1234.5, 0.1), (45_678.0, 1.0)])
def test_lutron_reads_the_rotor_at_display_resolution(rpm, resolution):
    tach, clock = open_tach("lutron16")
    spin_rotor(rpm)
    clock.sleep(8.0)
    readings = tach.readings_since(4.0)
    assert len(readings) == 4                 # ~1 Hz display rate
    for r in readings:
        # display resolution, plus what the first-order lag still lacks after 10 tau
        assert r.value / RAD_S_PER_RPM == pytest.approx(rpm, abs=resolution / 2 + 1e-4 * rpm)


def test_lutron_over_range_above_99999_rpm():
    tach, clock = open_tach("lutron16")
    spin_rotor(120_000.0)
    clock.sleep(8.0)
    last = tach.latest()
    assert last.overload and math.isnan(last.value)


@pytest.mark.parametrize("faults", ["garbage:0.8", "split:0.8", "mid_frame"])
def test_lutron_resyncs_through_garbage_split_frames_and_a_mid_frame_start(faults):
    tach, clock = open_tach("lutron16", f"&faults={faults}&rate_hz=5")
    spin_rotor(3000.0)
    clock.sleep(10.0)
    readings = tach.readings_since(5.0)
    assert len(readings) >= 20
    assert all(r.value / RAD_S_PER_RPM == pytest.approx(3000.0, abs=0.1) for r in readings)


def test_lutron_no_target_hold_keeps_the_last_value():
    tach, clock = open_tach("lutron16", "&no_target=hold&source=floator")
    shared_plant("t").floator_spin_rad_s = 200.0
    clock.sleep(3.0)
    shared_plant("t").floator_present = False     # the floator dropped: beam sees nothing
    clock.sleep(3.0)
    assert tach.latest().value == pytest.approx(200.0, abs=0.1 * RAD_S_PER_RPM)


def test_lutron_refuses_frames_of_a_non_rotation_unit():
    tach, clock = open_tach("lutron16", "&annunciator=01")   # 01 = degC in the Lutron tables
    spin_rotor(3000.0)
    with pytest.raises(DeviceTimeout):
        tach.wait_reading(timeout=3.0)
    assert tach.frames_rejected >= 2


def test_lutron_rpm_code_option_selects_the_annunciator():
    tach, clock = open_tach("lutron16", "&annunciator=53", rpm_code="53")
    spin_rotor(3000.0)
    clock.sleep(6.0)
    assert tach.wait_reading(timeout=3.0).value / RAD_S_PER_RPM == pytest.approx(3000.0, abs=0.1)


def test_lutron_wrong_baud_gives_no_reading_and_names_the_last_bytes():
    tach, clock = open_tach("lutron16", settings={"baudrate": 19200})
    spin_rotor(3000.0)
    with pytest.raises(DeviceTimeout) as info:
        tach.wait_reading(timeout=3.0)
    assert "no reading in 3.0 s" in str(info.value) and "last bytes" in str(info.value)


def test_lutron_unplug_mid_read():
    tach, clock = open_tach("lutron16", "&faults=disconnect_at:2.5")
    clock.sleep(2.2)
    with pytest.raises(DeviceDisconnected):
        tach.wait_reading(timeout=3.0)


# ---- the emulated sensor: period method with micros() quantisation ------------------------

def test_micros_quantisation_scatter_is_bounded_by_one_tick_per_window():
    # 100 000 RPM at 1 PPR: 600 us period; at 200 lines/s a window holds ~8.3 periods and
    # its summed time is quantised to the 4 us tick, so each reading is off by at most
    # 4 us / (pulses x 600 us) plus the float rounding of the printed period.
    tach, clock = open_tach("labkit_tach", "&tick_us=4", rate_hz=200)
    expected = spin_rotor(100_000.0)
    t0 = clock.now()
    clock.sleep(6.0)
    readings = [r for r in tach.readings_since(t0 + 5.0)]
    errors = []
    for r in readings:
        pulses = int(r.raw.split(b",")[5])
        bound = 4.0 / (pulses * 600.0) + 2e-4
        errors.append(abs(r.value / expected - 1.0))
        assert errors[-1] <= bound
    assert max(errors) > 1e-4          # the quantisation is really there


def test_coarser_ticks_give_a_larger_scatter():
    spreads = []
    for tick in ("4", "64"):
        reset_plants()
        tach, clock = open_tach("labkit_tach", f"&tick_us={tick}", rate_hz=200)
        spin_rotor(60_000.0)
        t0 = clock.now()
        clock.sleep(6.0)
        values = [r.value for r in tach.readings_since(t0 + 5.0)]
        spreads.append(max(values) - min(values))
    assert spreads[1] > 4 * spreads[0]


def test_labkit_tach_slow_replies():
    tach, clock = open_tach("labkit_tach", "&faults=delay:0.3")       # under the 0.5 s timeout
    assert tach.identify()["model"] == "labkit-tach"
    with pytest.raises(DeviceTimeout):
        open_tach("labkit_tach", "&faults=delay:2.0")   # later than all three attempts


# ---- Monarch "@" protocol -------------------------------------------------------------------

def test_monarch_streams_the_display_value_and_identifies():
    tach, clock = open_tach("monarch_at")
    expected = spin_rotor(8000.0)
    assert tach.identify() == {"model": "ACT-3X", "firmware": "1.00"}
    clock.sleep(6.0)
    readings = tach.readings_since(clock.now() - 2.0)
    assert len(readings) == pytest.approx(4, abs=1)          # the display rate, 2 per second
    assert all(r.value == pytest.approx(expected, abs=0.06 * RAD_S_PER_RPM + 1e-3 * expected)
               for r in readings)


def test_monarch_error_reply_names_the_command():
    tach, clock = open_tach("monarch_at", "&faults=error_reply:1")
    with pytest.raises(DeviceReplyError) as info:
        tach.identify()
    assert "@PI" in str(info.value)


def test_monarch_split_lines_and_unplug():
    # (no garbage case: the Monarch value lines carry no framing or checksum, so a junk
    # byte that happens to be a digit next to a number cannot be told from the number)
    tach, clock = open_tach("monarch_at", "&faults=split:0.7,disconnect_at:8")
    expected = spin_rotor(3000.0)
    clock.sleep(7.0)
    readings = tach.readings_since(4.0)
    assert len(readings) >= 3
    assert all(r.value == pytest.approx(expected, abs=0.06 * RAD_S_PER_RPM + 1e-3 * expected)
               for r in readings)
    clock.sleep(1.5)
    with pytest.raises(DeviceDisconnected):
        tach.latest()


def test_command_to_an_unplugged_tach_names_the_command():
    tach, clock = open_tach("labkit_tach", "&faults=disconnect_at:1")
    clock.sleep(1.5)
    with pytest.raises(DeviceDisconnected) as info:
        tach.identify()
    assert "command 'ID?'" in str(info.value) and "disconnected" in str(info.value)
