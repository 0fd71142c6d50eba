"""Sensor and motor faults injected at the emulator (sim:// faults=...), virtual clock.

The shipped emulated Fig. 5.25 rig with its limit lowered to 12 000 RPM holds 8 000 RPM; at
6 s the fault starts. Each must trip the interlock within the stated time with a reason that
names the device and the numbers, with the true rotor (the plant, not the tachometer) never
above the limit. The same faults with `labkit emulate` in its own process:
tests/safety/test_sensor_faults_pty.py.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from labkit.control import build_speed_control
from labkit.emulators.plant import use_emulation
from labkit.emulators.sim_port import build_emulator
from labkit.errors import RigFileError
from labkit.io.clock import VirtualClock, use_clock
from labkit.rig import open_rig, parse_rig
from labkit.units import rad_s_to_rpm, rpm_to_rad_s

RIG = (Path(__file__).resolve().parents[2] / "rigs" / "emulated-fig525.toml").read_text() \
    .replace("max_speed_rpm = 24000", "max_speed_rpm = 12000")
LIMIT_RPM = 12000.0
FAULT_AT = 6.0


def run(tach_faults="", motor_faults="", full_speed_rpm=None, target_rpm=8000.0, seconds=15.0,
        limit_rpm=None):
    """(trip time, reason, peak true RPM, plant) of a hold at ``target_rpm`` with the faults."""
    from labkit.emulators.plant import shared_plant

    text = RIG if limit_rpm is None else RIG.replace("max_speed_rpm = 12000", f"max_speed_rpm = {limit_rpm}")
    if tach_faults:
        text = text.replace("role=rotor_tach", f"role=rotor_tach&faults={tach_faults}")
    if motor_faults:
        text = text.replace("role=rotor_motor", f"role=rotor_motor&faults={motor_faults}")
    if full_speed_rpm:
        text = text.replace("full_speed_rpm = 23873", f"full_speed_rpm = {full_speed_rpm}")
    clock = VirtualClock()
    with use_clock(clock):
        opened = open_rig(parse_rig(text, "test.toml"), clock)
        control = build_speed_control(opened, clock)
        plant = shared_plant("model-fig525")
        try:
            control.set_targets({"rotor": rpm_to_rad_s(target_rpm)})
            peak = 0.0
            while control.tripped is None and clock.now() < seconds:
                clock.sleep(0.01)
                peak = max(peak, rad_s_to_rpm(plant.speed(clock.now())))
        finally:
            control.stop()
            opened.close()
    return control.tripped_at, control.tripped, peak, plant


@pytest.mark.parametrize("fault, within_s, words", [
    ("zero_at", 1.0, ["rotor_tach implausible: reads 0 RPM", "rotor_motor", "predicts at least"]),
    ("stuck_at", 1.5, ["rotor_tach stuck: the same value", "times over"]),
    ("repeat_at", 1.0, ["rotor_tach silent"]),  # the same sequence number: no new reading
    ("stop_at", 1.0, ["rotor_tach silent"]),
])
def test_a_lying_tachometer_trips_within_its_time_and_the_rotor_stays_under_the_limit(fault, within_s, words):
    tripped_at, reason, peak, _ = run(tach_faults=f"{fault}:{FAULT_AT}")
    assert tripped_at is not None, f"{fault}: no trip"
    assert FAULT_AT < tripped_at <= FAULT_AT + within_s, (tripped_at, reason)
    assert peak <= LIMIT_RPM, f"{fault}: true rotor at {peak:.0f} RPM"
    for word in words:
        assert word in reason, reason


def test_a_tachometer_stuck_during_the_ramp_trips_on_the_duty_it_does_not_follow():
    tripped_at, reason, peak, _ = run(tach_faults="stuck_at:1.0")
    assert tripped_at is not None and tripped_at <= 1.0 + 1.0, (tripped_at, reason)
    assert "stuck" in reason and "moved the expected speed" in reason
    assert peak <= LIMIT_RPM


def test_a_stalled_motor_trips_within_3_s_of_the_duty_saturating():
    tripped_at, reason, peak, plant = run(motor_faults=f"stall_at:{FAULT_AT}")
    motor = plant.motor("rotor")
    saturated = [t for t, duty in motor.duty_changes if t >= FAULT_AT and duty >= 0.5]
    assert saturated, "the loop never raised its duty into the stall"
    assert tripped_at is not None and tripped_at - saturated[0] <= 3.0, (saturated[0], tripped_at, reason)
    assert "rotor_motor" in reason and "saturated" in reason
    assert peak <= LIMIT_RPM


def test_the_duty_cap_holds_the_rotor_under_the_limit_with_a_tachometer_that_reads_zero():
    # zero from the start: nothing to compare with during the spin-up grace, only the cap
    tripped_at, reason, peak, plant = run(tach_faults="zero_at:0")
    assert tripped_at is not None and "reads 0 RPM" in reason
    smc_step = 1 / 3200  # the SMC's speed resolution: the cap's duty is rounded to it
    assert max(d for _, d in plant.motor("rotor").duty_changes) <= LIMIT_RPM / 23873 + smc_step
    assert peak <= LIMIT_RPM


def test_a_feed_forward_typo_the_rig_check_admits_still_trips_at_run_time():
    # 2387 for 23 873 under a 2 500 RPM limit (so labkit.rig.plausible lets it through): 2000 RPM
    # asks duty 0.84 and the rotor heads for 20 000 RPM; the loop stops it within half a second
    tripped_at, reason, peak, _ = run(full_speed_rpm=2387, target_rpm=2000, limit_rpm=2500)
    assert tripped_at is not None and tripped_at < 1.5, (tripped_at, reason)
    assert ("full_speed_rpm" in reason and "far above" in reason) or "over-speed" in reason, reason
    assert peak < 2 * 2500, peak


def test_a_feed_forward_typo_is_refused_before_anything_opens():
    # 2387 for 23 873 under the 12 000 RPM limit: the rig file itself is refused (issue 27)
    refused = r"control\.full_speed_rpm: 2387 RPM is below limits\.max_speed_rpm"
    with pytest.raises(RigFileError, match=refused):
        run(full_speed_rpm=2387, target_rpm=6000)


@pytest.mark.parametrize("lag_s", [0.3, 1.0])
def test_a_lagging_tachometer_does_not_trip_and_the_cap_holds_the_overshoot(lag_s):
    # a lag makes the loop overshoot (8 878 RPM without one); no rule can call it a fault
    # within the band, the duty cap keeps the rotor under the limit
    tripped_at, reason, peak, _ = run(tach_faults=f"lag_s:{lag_s}", seconds=12.0)
    assert tripped_at is None, reason
    assert 9000 < peak <= LIMIT_RPM, peak


def _lines(url, seconds, clock_step=0.05):
    """The labkit-tach lines an emulator sends over ``seconds`` with the rotor at 6 000 RPM."""
    emulator = build_emulator(url)
    emulator.plant.set_duty(0.26, 0.0)
    emulator.open(0.0)
    out = b""
    t = 0.0
    while t < seconds:
        t += clock_step
        out += emulator.emit(t)
    return [line for line in out.decode().splitlines() if line.startswith("T,")]


def test_labkit_tach_fault_bytes():
    base = "sim://labkit_tach?seed=2&plant=fig525.faultbytes&rate_hz=20"
    zero = [line.split(",") for line in _lines(base + "&faults=zero_at:3", 4.0)]
    after = [f for f in zero if int(f[2]) >= 3000]
    assert after and all(f[3] == "0.0" and f[6] == "Z" for f in after)
    stuck = [line.split(",") for line in _lines(base + "&faults=stuck_at:3", 4.0)]
    late = stuck[-10:]
    assert len({tuple(f[3:]) for f in late}) == 1 and len({f[1] for f in late}) == 10  # seq advances
    repeat = _lines(base + "&faults=repeat_at:3", 4.0)
    assert len(set(repeat[-10:])) == 1


def test_start_fault_on_a_signal_sets_the_time_since_open():
    emulator = build_emulator("sim://labkit_tach?plant=fig525.signal")
    emulator.open(10.0)
    emulator.start_fault("zero", 12.5)
    assert emulator.faults["zero_at"] == pytest.approx(2.5)
    with pytest.raises(ValueError, match="cannot be started on a signal"):
        emulator.start_fault("garbage", 12.5)


def _vesc_rig(driver_pole_pairs: int, tach_faults: str = "") -> str:
    """The rig with a VESC (7 pole pairs in the emulator) in place of the SMC."""
    start, end = RIG.index("[devices.rotor_motor]"), RIG.index("[devices.rotor_tach]")
    vesc = ('[devices.rotor_motor]\nkind = "motor"\nprotocol = "vesc"\n'
            'port = "sim://vesc?seed=1&plant=model-fig525&role=rotor_motor&pole_pairs=7&timeout_ms=1000"\n'
            f'options = {{ pole_pairs = {driver_pole_pairs}, timeout_ms = 1000 }}\n\n')
    text = RIG[:start] + vesc + RIG[end:]
    return text.replace("role=rotor_tach", f"role=rotor_tach&faults={tach_faults}") if tach_faults else text


def _hold(text: str, seconds: float = 10.0):
    clock = VirtualClock()
    with use_emulation(), use_clock(clock):
        opened = open_rig(parse_rig(text, "test.toml"), clock)
        control = build_speed_control(opened, clock)
        try:
            control.set_targets({"rotor": rpm_to_rad_s(8000)})
            while control.tripped is None and clock.now() < seconds:
                clock.sleep(0.01)
        finally:
            control.stop()
            opened.close()
    return control.tripped_at, control.tripped


def test_the_tachometer_is_cross_checked_against_the_vesc_s_own_speed():
    assert _hold(_vesc_rig(7)) == (None, None)  # agree: no trip
    tripped_at, reason = _hold(_vesc_rig(1))      # wrong pole pairs: the VESC says 7x
    assert tripped_at is not None and "motor controller rotor_motor measures" in reason
    assert "check pole_pairs" in reason
    tripped_at, reason = _hold(_vesc_rig(7, tach_faults=f"zero_at:{FAULT_AT}"))
    assert "reads 0 RPM" in reason and "the tachometer is wrong" in reason


def test_a_plan_the_feed_forward_cannot_reach_is_refused_by_the_dry_run(tmp_path, capsys):
    from labkit.cli import main

    rig = tmp_path / "typo.toml"
    rig.write_text(RIG.replace("full_speed_rpm = 23873", "full_speed_rpm = 2387"))
    code = main(["run", str(rig), "speed-sweep", "--set", "speeds_rpm=6000", "--dry-run"])
    err = capsys.readouterr().err
    assert code == 2 and f"{rig}:control.full_speed_rpm: 2387 RPM is below" in err


def _sweep(tach_faults: str, zero: str = "each"):
    """A speed-sweep run (8 000 RPM, 2 s record, rest readings) in-process on the virtual clock."""
    from labkit.protocols import ListSink, Runner
    from labkit.protocols.params import resolve_params
    from labkit.protocols.speed_sweep import SpeedSweep

    text = RIG.replace("role=rotor_tach", f"role=rotor_tach&faults={tach_faults}") if tach_faults else RIG
    proto, clock, sink = SpeedSweep(), VirtualClock(), ListSink()
    params = resolve_params(proto.defaults, {"speeds_rpm": [8000.0], "record_s": 2.0, "zero": zero})
    with use_emulation(), use_clock(clock):  # a fresh plant: each run starts from rest at t = 0
        return Runner(proto, parse_rig(text, "test.toml"), params, clock=clock, sinks=[sink]).run(), sink


@pytest.mark.parametrize("zero", ["each", "start"])
@pytest.mark.parametrize("before_end_s", [0.05, 0.15, 0.25])
def test_a_fault_in_the_last_moments_of_a_recording_gives_no_point(before_end_s, zero):
    # the clean run's recording ends at a fixed virtual time; a zero reading that starts just
    # before it has not tripped when the recording ends: the step waits for the verdict (with
    # zero=start nothing comes after the recording in the step to give it time)
    clean, sink = _sweep("", zero)
    assert clean.status == "completed" and len(clean.results["points"]) == 1
    settled_t = sink.of_type("settled")[0]["t"]  # the 2 s recording follows
    end = max(e["t"] for e in sink.of_type("reading")
              if e["device"] == "balance" and settled_t <= e["t"] <= settled_t + 2.5)
    outcome, sink = _sweep(f"zero_at:{end - before_end_s}", zero)
    assert outcome.status == "failed" and outcome.results["points"] == []
    assert "reads 0 RPM" in outcome.reason and sink.of_type("point") == []


def test_fault_on_usr2_option_names_a_role_and_a_timed_fault():
    from labkit.cli.emulate import parse_fault_option
    from labkit.errors import PortURLError

    assert parse_fault_option("rotor_tach:zero") == ("rotor_tach", "zero")
    assert parse_fault_option("rotor_motor:stall") == ("rotor_motor", "stall")
    for bad in ("rotor_tach", "rotor_tach:garbage", ":zero"):
        with pytest.raises(PortURLError, match="ROLE:NAME"):
            parse_fault_option(bad)
