"""The PI law against the emulators' first-order motor plant (pure, no I/O)."""

import pytest

from labkit.control.pi import PIGains, PIState, SettleDetector, pi_step, ramp_toward
from labkit.emulators.rig_plant import MotorPlant


def run_loop(plant: MotorPlant, gains: PIGains, target: float, seconds: float, dt: float = 0.05,
             ramp: float = 1e9) -> tuple[PIState, list[float]]:
    state, speeds, setpoint, t = PIState(), [], 0.0, 0.0
    while t < seconds:
        t += dt
        plant.advance(t)
        setpoint = ramp_toward(setpoint, target, ramp, dt)
        plant.set_duty(pi_step(gains, state, setpoint, plant.speed_rad_s, dt), t)
        speeds.append(plant.speed_rad_s)
    return state, speeds


def test_pi_removes_the_load_offset_that_feed_forward_alone_leaves():
    # a loaded motor: feed-forward alone would settle 150 rad/s low
    plant = MotorPlant(max_speed_rad_s=2500, tau_s=0.4, load_rad_s=150)
    gains = PIGains(full_speed_rad_s=2500, kp=2e-4, ki=4e-4)
    _, speeds = run_loop(plant, gains, target=1000.0, seconds=20)
    assert speeds[-1] == pytest.approx(1000.0, abs=2.0)


def test_anti_windup_limits_overshoot_after_saturation():
    # the target is unreachable for a while (max duty 0.5 -> 1250 rad/s), then lowered
    plant = MotorPlant(max_speed_rad_s=2500, tau_s=0.4)
    gains = PIGains(full_speed_rad_s=2500, kp=2e-4, ki=4e-4, max_duty=0.5)
    state, _ = run_loop(plant, gains, target=2000.0, seconds=30)
    assert state.duty == 0.5
    # the integral did not keep growing during 30 s of saturation
    assert state.integral < 800 * 2.0
    state2, speeds = PIState(integral=state.integral), []
    t = 30.0
    for _ in range(400):
        t += 0.05
        plant.advance(t)
        plant.set_duty(pi_step(gains, state2, 1000.0, plant.speed_rad_s, 0.05), t)
        speeds.append(plant.speed_rad_s)
    assert max(speeds[40:]) < 1100.0


def test_ramp_limit_bounds_the_setpoint_rate():
    values, sp = [], 0.0
    for _ in range(10):
        sp = ramp_toward(sp, 1000.0, max_rate=600.0, dt=0.1)
        values.append(sp)
    steps = [b - a for a, b in zip([0.0] + values, values, strict=False)]
    assert max(steps) == pytest.approx(60.0)
    assert ramp_toward(500.0, 0.0, 600.0, 0.1) == pytest.approx(440.0)


def test_zero_target_means_zero_duty():
    state = PIState(integral=123.0)
    assert pi_step(PIGains(2500, 2e-4, 4e-4), state, 0.0, 800.0, 0.05) == 0.0
    assert state.integral == 0.0


def test_settle_needs_the_hold_time_inside_tolerance():
    s = SettleDetector(tolerance=10.0, hold_s=1.0)
    assert not s.update(0.0, 5.0)
    assert not s.update(0.5, -5.0)
    assert not s.update(0.9, 20.0)   # left the band: starts over
    assert not s.update(1.0, 0.0)
    assert s.update(2.0, 1.0)
