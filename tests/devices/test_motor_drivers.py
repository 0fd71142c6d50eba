"""Motor drivers against their emulators over sim:// on a virtual clock: safety (never
start on open, zero on close and on exceptions, keep-alive >= 20 Hz) and the fault matrix."""

from __future__ import annotations

import pytest
from sim_driver import open_sim_driver

from labkit.devices.registry import driver_class
from labkit.emulators.plant import shared_plant
from labkit.errors import DeviceDisconnected, DeviceError, DeviceTimeout, SafetyError
from labkit.io.clock import VirtualClock
from labkit.io.ports import open_port
from labkit.units import RAD_S_PER_RPM

MAX_SPEED = 2500.0  # rad/s at duty 1: the plant's default motor


def open_motor(protocol: str, query: str = "", clock: VirtualClock | None = None,
               settings: dict | None = None, **options):
    return open_sim_driver("motor", protocol, "m", "rotor_motor", query, clock, settings, **options)


def rotor_speed(clock) -> float:
    return shared_plant("m").speed(clock.now())


def rotor_duty() -> float:
    return shared_plant("m").motor("rotor").duty


MOTORS = ["pololu_smc", "esc_bridge", "vesc"]


# ---- safety, every protocol ------------------------------------------------------------------

@pytest.mark.parametrize("protocol", MOTORS)
def test_open_identify_and_status_never_start_the_motor(protocol):
    motor, clock = open_motor(protocol)
    motor.identify()
    motor.status()
    clock.sleep(2.0)
    assert rotor_duty() == 0.0 and rotor_speed(clock) == 0.0
    with pytest.raises(SafetyError):
        motor.set_duty(0.5)
    assert rotor_duty() == 0.0


@pytest.mark.parametrize("protocol", MOTORS)
def test_enable_and_set_duty_spin_the_rotor(protocol):
    motor, clock = open_motor(protocol, "&arm_s=0.5" if protocol == "esc_bridge" else "")
    motor.enable()
    motor.set_duty(0.4)
    clock.sleep(5.0)
    # first-order plant: 12.5 time constants after the step, speed = duty x max speed
    assert rotor_speed(clock) == pytest.approx(0.4 * MAX_SPEED, rel=1e-3)
    status = motor.status()
    assert status.duty == pytest.approx(0.4, abs=1e-3) and not status.errors


@pytest.mark.parametrize("protocol", MOTORS)
def test_keepalive_rate_is_at_least_20_hz_on_the_device_side(protocol):
    motor, clock = open_motor(protocol, "&arm_s=0" if protocol == "esc_bridge" else "")
    motor.enable()
    motor.set_duty(0.2)
    start = clock.now()
    clock.sleep(10.0)
    times = [t for t in motor.port.emulator.setpoint_times if t > start]
    rate_hz = (len(times) - 1) / (times[-1] - times[0])
    assert rate_hz >= 20.0 - 1e-6
    gaps = [b - a for a, b in zip(times, times[1:], strict=False)]
    assert max(gaps) <= 0.05 + 1e-9


@pytest.mark.parametrize("protocol", MOTORS)
def test_close_commands_zero(protocol):
    motor, clock = open_motor(protocol, "&arm_s=0" if protocol == "esc_bridge" else "")
    motor.enable()
    motor.set_duty(0.6)
    clock.sleep(3.0)
    motor.close()
    assert rotor_duty() == 0.0
    clock.sleep(5.0)
    assert rotor_speed(clock) < 0.01 * 0.6 * MAX_SPEED


@pytest.mark.parametrize("protocol", MOTORS)
def test_exception_inside_with_block_commands_zero(protocol):
    motor, clock = open_motor(protocol, "&arm_s=0" if protocol == "esc_bridge" else "")
    with pytest.raises(RuntimeError, match="analysis crashed"):
        with motor:
            motor.enable()
            motor.set_duty(0.5)
            clock.sleep(2.0)
            assert rotor_duty() == pytest.approx(0.5, abs=1e-3)
            raise RuntimeError("analysis crashed")
    assert rotor_duty() == 0.0
    with pytest.raises(SafetyError):
        motor.set_duty(0.5)


@pytest.mark.parametrize("protocol", MOTORS)
def test_unplug_is_a_disconnect_and_stop_never_raises(protocol):
    motor, clock = open_motor(protocol, "&faults=disconnect_at:1")
    clock.sleep(1.5)
    with pytest.raises(DeviceDisconnected) as info:
        motor.status()
    assert "rotor_motor" in str(info.value) and "disconnected" in str(info.value)
    motor.stop()
    motor.close()


@pytest.mark.parametrize("protocol", MOTORS)
def test_missing_reply_is_a_timeout_naming_device_and_command(protocol):
    motor, clock = open_motor(protocol, "&faults=drop_reply:1")
    with pytest.raises(DeviceTimeout) as info:
        motor.status()
    message = str(info.value)
    # a VESC asks FW_VERSION (the GET_VALUES layout depends on it) before its first GET_VALUES
    assert "rotor_motor" in message and any(
        command in message for command in ("get variable 0", "GET_VALUES", "FW_VERSION"))


@pytest.mark.parametrize("protocol", MOTORS)
def test_garbage_and_split_replies_still_give_true_status(protocol):
    motor, clock = open_motor(protocol, "&faults=garbage:0.1,split:0.5&arm_s=0")
    motor.enable()
    motor.set_duty(0.3)
    clock.sleep(4.0)
    for _ in range(10):
        status = motor.status()
        assert status.duty == pytest.approx(0.3, abs=1e-3)
        assert status.input_voltage_v in (12.0, 24.0)


# ---- Pololu SMC specifics ---------------------------------------------------------------------

def test_smc_reports_safe_start_until_enabled_and_identifies():
    motor, clock = open_motor("pololu_smc")
    assert motor.identify() == {"model": "pololu-smc-g2", "product_id": 0xA1, "firmware": "1.04"}
    assert motor.status().errors == {"safe_start_violation"}
    motor.enable()
    assert motor.status().errors == frozenset()
    assert motor.reset_flags() == "power_or_brownout"


def test_smc_pololu_protocol_with_crc_and_device_number():
    motor, clock = open_motor("pololu_smc", "&crc=1&device_number=7", device_number=7, crc=True)
    motor.enable()
    motor.set_duty(-0.5)
    clock.sleep(4.0)
    assert rotor_speed(clock) == pytest.approx(-0.5 * MAX_SPEED, rel=1e-3)
    assert motor.status().target_duty == pytest.approx(-0.5)


def test_smc_crc_mismatch_is_refused_by_the_controller_and_the_driver_says_so():
    motor, clock = open_motor("pololu_smc", "&crc=1")   # controller expects CRC, driver sends none
    motor.enable()
    motor.set_duty(0.5)
    clock.sleep(1.0)
    assert rotor_duty() == 0.0
    with pytest.raises(DeviceTimeout) as info:
        motor.status()
    assert "get variable 0" in str(info.value)


def test_smc_overload_error_stops_the_motor_and_is_reported():
    motor, clock = open_motor("pololu_smc", "&faults=overload")
    motor.enable()
    motor.set_duty(0.5)
    clock.sleep(2.0)
    status = motor.status()
    assert "over_temperature" in status.errors and status.duty == 0.0
    assert rotor_duty() == 0.0


def test_smc_reset_rearms_safe_start_and_the_driver_does_not_restart_it():
    motor, clock = open_motor("pololu_smc", "&faults=reset_at:2")
    motor.enable()
    motor.set_duty(0.5)
    clock.sleep(5.0)
    status = motor.status()
    assert "safe_start_violation" in status.errors and status.duty == 0.0
    assert rotor_duty() == 0.0
    assert motor.reset_flags() == "watchdog"


def test_smc_command_timeout_stops_a_motor_whose_host_went_silent():
    motor, clock = open_motor("pololu_smc", "&command_timeout_ms=200")
    motor.enable()
    motor.set_duty(0.5)
    clock.sleep(3.0)                 # the 20 Hz keep-alive holds it
    assert "command_timeout" not in motor.status().errors
    motor._job.cancel()              # the host process hangs: no more refreshes
    clock.sleep(1.0)
    assert "command_timeout" in motor.status().errors
    assert rotor_duty() == 0.0


# ---- ESC bridge specifics ---------------------------------------------------------------------

def test_esc_bridge_is_one_direction_and_waits_for_the_esc_to_arm():
    motor, clock = open_motor("esc_bridge", "&arm_s=1.0")
    assert motor.identify() == {"model": "esc_bridge"}
    motor.enable()
    with pytest.raises(ValueError):
        motor.set_duty(-0.2)
    motor.set_duty(0.5)
    assert rotor_duty() == 0.0           # ESC not armed yet
    clock.sleep(2.0)
    assert rotor_duty() == pytest.approx(0.5, abs=1e-3)


def test_esc_bridge_refuses_pololu_only_options():
    with pytest.raises(ValueError):
        open_motor("esc_bridge", crc=True)


def test_esc_bridge_wrong_baud_times_out():
    motor, clock = open_motor("esc_bridge", settings={"baudrate": 9600})
    with pytest.raises(DeviceError):
        motor.status()


# ---- VESC specifics ----------------------------------------------------------------------------

def test_vesc_speed_command_in_erpm_with_pole_pairs():
    motor, clock = open_motor("vesc", "&pole_pairs=7", pole_pairs=7)
    assert motor.identify() == {"model": "vesc", "firmware": "6.02", "hardware": "labkit-emu"}
    motor.enable()
    motor.set_speed(1000.0)
    clock.sleep(5.0)
    status = motor.status()
    assert rotor_speed(clock) == pytest.approx(1000.0, rel=1e-3)
    assert status.speed_rad_s == pytest.approx(1000.0, rel=1e-3)


def test_vesc_erpm_limit_caps_the_speed():
    motor, clock = open_motor("vesc", "&pole_pairs=7&max_erpm=70000", pole_pairs=7)
    motor.enable()
    motor.set_speed(20_000 * RAD_S_PER_RPM)      # 140 000 ERPM asked
    clock.sleep(5.0)
    assert motor.status().speed_rad_s == pytest.approx(10_000 * RAD_S_PER_RPM, rel=1e-3)


def test_vesc_comm_timeout_releases_the_motor():
    motor, clock = open_motor("vesc")
    motor.enable()
    motor.set_duty(0.5)
    clock.sleep(2.0)
    motor._job.cancel()               # host hangs
    clock.sleep(1.5)
    assert "comm_timeout" in motor.status().errors
    assert rotor_duty() == 0.0


@pytest.mark.parametrize("faults, name", [("fault_code:5", "over_temp_fet"),
                                         ("overload", "abs_over_current")])
def test_vesc_fault_codes_stop_the_motor_and_are_reported(faults, name):
    motor, clock = open_motor("vesc", f"&faults={faults}")
    motor.enable()
    motor.set_duty(0.5)
    clock.sleep(2.0)
    assert rotor_duty() == 0.0
    assert name in motor.status().errors
    assert motor.status().as_json()["overload"] is True  # current or temperature: an overload


def test_vesc_watchdog_reset_releases_the_motor_and_reports_fault_10():
    motor, clock = open_motor("vesc", "&faults=reset_at:2")
    motor.enable()
    motor.set_duty(0.5)
    clock.sleep(4.0)
    assert rotor_duty() == 0.0
    assert "booting_from_watchdog_reset" in motor.status().errors


def test_vesc_wrong_baud_times_out_naming_the_request():
    motor, clock = open_motor("vesc", settings={"baudrate": 9600})
    with pytest.raises(DeviceTimeout) as info:
        motor.status()
    assert "FW_VERSION" in str(info.value)  # asked first: the GET_VALUES layout depends on it
    with pytest.raises(DeviceTimeout) as info:
        motor.identify()
    assert "FW_VERSION" in str(info.value)


def test_smc_commands_split_across_writes_and_junk_between_them():
    """The controller assembles packets byte by byte; a stray data byte is a format error
    that stops the motor until the next exit-safe-start (PROTOCOLS 3.1)."""
    motor, clock = open_motor("pololu_smc")
    port = motor.port
    for byte in bytes.fromhex("83 85 00 32"):     # exit safe start, forward 1600, one byte a time
        port.write(bytes([byte]))
        clock.sleep(0.001)
    assert rotor_duty() == pytest.approx(0.5)
    port.write(b"\x12")                           # junk: a data byte outside any packet
    assert rotor_duty() == 0.0
    assert motor.status().errors == {"serial_error"}
    motor.enable()
    motor.set_duty(0.25)
    assert rotor_duty() == pytest.approx(0.25)


@pytest.mark.parametrize("protocol, timeout_s", [("pololu_smc", 0.1), ("vesc", 0.2)])
def test_slow_replies_within_the_timeout_are_fine_beyond_it_a_timeout(protocol, timeout_s):
    motor, clock = open_motor(protocol, f"&faults=delay:{timeout_s * 0.6}")
    assert motor.status().input_voltage_v in (12.0, 24.0)
    slow, clock = open_motor(protocol, f"&faults=delay:{timeout_s * 1.5}")
    with pytest.raises(DeviceTimeout):
        slow.status()


@pytest.mark.parametrize("protocol, powered_on_errors", [
    ("pololu_smc", {"safe_start_violation"}), ("vesc", set())])
def test_replugged_controller_is_in_its_power_on_state_and_stays_stopped(protocol, powered_on_errors):
    motor, clock = open_motor(protocol, "&faults=disconnect_at:2,reconnect_after:1")
    motor.enable()
    motor.set_duty(0.5)
    clock.sleep(2.5)
    with pytest.raises(DeviceDisconnected):
        motor.status()
    motor.close()                      # quiet on the dead port
    clock.sleep(1.0)                   # plugged back in
    motor.port.open()                  # same emulator, power-cycled
    again = driver_class("motor", protocol)(motor.port, clock, name="rotor_motor")
    status = again.status()
    assert status.errors == powered_on_errors and status.duty == 0.0
    assert rotor_duty() == 0.0


@pytest.mark.parametrize("protocol, query, timeout_s", [("pololu_smc", "&command_timeout_ms=200", 0.2),
                                                        ("vesc", "", 1.0)])
def test_a_controller_timeout_stops_the_motor_even_if_its_port_is_never_used_again(
        protocol, query, timeout_s):
    # only the tachometer is read after the host hangs: the controller's timeout must still
    # act on time (an emulator only runs when its own port is used)
    motor, clock = open_motor(protocol, query)
    tach_port = open_port("sim://labkit_tach?plant=m&rate_hz=20", clock=clock, timeout=0,
                          **driver_class("tachometer", "labkit_tach").default_serial)
    tach = driver_class("tachometer", "labkit_tach")(tach_port, clock, name="rotor_tach")
    motor.enable()
    motor.set_duty(0.5)
    clock.sleep(3.0)
    running = tach.latest().value
    assert running > 0.4 * MAX_SPEED
    hung_at = clock.now()
    motor._job.cancel()               # host hangs: no more commands, nobody reads the motor port
    clock.sleep(3.0)
    assert tach.latest().value < 0.02 * running
    when, duty = shared_plant("m").motor("rotor").duty_changes[-1]
    assert duty == 0.0
    assert hung_at < when <= hung_at + timeout_s
    tach.close()
    tach_port.close()
