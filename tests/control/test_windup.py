"""Settling near the motor's top speed: the integral gathered during the ramp must not sit
behind the saturation (issue 28's largest plan stopped at 23 053 RPM, the duty pinned at 1.00
for 14 s while the rotor ran 145 RPM fast).

The law against the emulators' model motor (pure, microseconds), then the whole speed loop on
the emulated Fig. 5.25 rig (the SMC and tachometer emulators' bytes) on the virtual clock.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from labkit.control import build_speed_control
from labkit.control.loop import short_of_reach
from labkit.control.pi import PIGains, PIState, SettleDetector, pi_step, ramp_toward
from labkit.emulators.model_plant import Imperfections, ModelMotor
from labkit.io.clock import VirtualClock, use_clock
from labkit.rig import open_rig, parse_rig
from labkit.units import rad_s_to_rpm, rpm_to_rad_s

RIG = Path(__file__).resolve().parents[2] / "rigs" / "emulated-fig525.toml"
#: the emulated rig's [control] and [limits]: full speed 23 873 RPM, ramp 6 000 RPM/s
GAINS = PIGains(full_speed_rad_s=rpm_to_rad_s(23873), kp=2e-4, ki=4e-4)
RAMP = rpm_to_rad_s(6000)
TOLERANCE, HOLD, PERIOD = rpm_to_rad_s(100), 1.0, 0.05


def model_motor() -> ModelMotor:
    """The emulators' motor: 23 873 RPM at full duty unloaded, air drag (23 197 RPM loaded)."""
    imp = Imperfections()
    return ModelMotor(max_speed_rad_s=GAINS.full_speed_rad_s, tau_s=imp.motor_tau_s, drag=imp.motor_drag)


def settle_from_rest(target_rpm: float, seconds: float = 30.0) -> tuple[float | None, float, float]:
    """(settle time or None, final RPM, seconds at full duty after the setpoint arrived) of a
    ramped step from rest, as the speed sweep makes at every point."""
    plant, state, settle = model_motor(), PIState(), SettleDetector(TOLERANCE, HOLD)
    target, setpoint, t, pinned = rpm_to_rad_s(target_rpm), 0.0, 0.0, 0.0
    while t < seconds:
        t += PERIOD
        plant.advance(t)
        setpoint = ramp_toward(setpoint, target, RAMP, PERIOD)
        duty = pi_step(GAINS, state, setpoint, plant.speed_rad_s, PERIOD)
        plant.set_duty(duty, t)
        if setpoint == target:
            pinned += PERIOD if duty >= GAINS.max_duty else 0.0
            if settle.update(t, plant.speed_rad_s - target):
                return t, rad_s_to_rpm(plant.speed_rad_s), pinned
    return None, rad_s_to_rpm(plant.speed_rad_s), pinned


def test_the_model_motor_tops_out_below_the_rigs_full_speed_under_its_load():
    # what the targets near the top can be: the loaded top at full duty
    _, top_rpm, _ = settle_from_rest(30000.0, seconds=20.0)
    assert 23100 < top_rpm < 23300, top_rpm


@pytest.mark.parametrize("target_rpm", [22000.0, 23000.0, 23053.0, 23150.0])
def test_a_ramped_step_near_the_top_speed_settles_without_holding_full_duty(target_rpm):
    # before the integral was bounded by the duty left over the feed-forward: 23 053 RPM took
    # 19.2 s (14 s at full duty), 23 000 RPM 15.8 s; now 5-8 s (3.9 s of it the ramp)
    took, final_rpm, pinned = settle_from_rest(target_rpm)
    assert took is not None and took < 10.0, (took, final_rpm)
    assert pinned < 2.0, pinned
    assert abs(final_rpm - target_rpm) <= 100.0


@given(target=st.floats(0.0, 3000.0), measured=st.floats(0.0, 3000.0),
       integral=st.floats(-1e5, 1e5), dt=st.floats(0.0, 1.0))
def test_the_integral_term_never_asks_for_more_than_the_duty_left_over_the_feed_forward(
        target, measured, integral, dt):
    state = PIState(integral=integral)
    duty = pi_step(GAINS, state, target, measured, dt)
    assert 0.0 <= duty <= GAINS.max_duty
    if target > 0:
        held = target / GAINS.full_speed_rad_s + GAINS.ki * state.integral
        assert -1e-9 <= held <= GAINS.max_duty + 1e-9, (held, state.integral)


def hold_on_the_emulated_rig(target_rpm: float, seconds: float = 20.0):
    """(settled, virtual time, snapshot, why it cannot settle or None) of the speed loop over
    the SMC and tachometer emulators' bytes, from rest to ``target_rpm``."""
    clock = VirtualClock()
    with use_clock(clock):
        opened = open_rig(parse_rig(RIG.read_text(), str(RIG)), clock)
        control = build_speed_control(opened, clock)
        try:
            control.set_targets({"rotor": rpm_to_rad_s(target_rpm)})
            while not control.settled() and control.tripped is None and clock.now() < seconds:
                clock.sleep(PERIOD)
            loop = control.loops["rotor"]
            outcome = control.settled(), clock.now(), loop.snapshot, short_of_reach(loop)
        finally:
            control.stop()
            opened.close()
    assert control.tripped is None, control.tripped
    return outcome


def test_the_emulated_rig_settles_at_the_top_of_issue_28s_plan_on_the_virtual_clock():
    # from rest to 23 053 RPM: step 4 737 of issue 28's plan, which did not settle within 20 s
    settled, settled_at, snapshot, beyond = hold_on_the_emulated_rig(23053.0)
    assert settled and settled_at < 10.0, (settled_at, snapshot)
    assert snapshot.measured_rad_s is not None
    assert abs(rad_s_to_rpm(snapshot.measured_rad_s) - 23053.0) <= 100.0
    assert beyond is None


def test_a_target_beyond_the_loaded_motor_says_where_the_rotor_tops_out():
    # 23 600 RPM is under the rig's 24 000 RPM limit and its 23 873 RPM full speed, but the
    # loaded motor tops out at 23 197 RPM at full duty: no settling, and the reason says so
    settled, _, snapshot, beyond = hold_on_the_emulated_rig(23600.0, seconds=12.0)
    assert not settled and snapshot.duty == GAINS.max_duty
    assert beyond is not None and "cannot reach 23600 RPM" in beyond, beyond
    topped = float(beyond.split("tops out at ")[1].split(" RPM")[0])
    assert 23100 < topped < 23300, beyond
