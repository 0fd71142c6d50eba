"""The plausibility rules (labkit.control.plausibility) on a first-order motor, no I/O.

The plant here is the emulator's law d(omega)/dt = (duty*full - omega)/tau, stepped exactly;
the tachometer is that speed times a gain (a mis-set feed-forward looks the same), or a fault.
"""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from labkit.control import plausibility as plaus
from labkit.control.loop import duty_cap
from labkit.units import rpm_to_rad_s

FULL = rpm_to_rad_s(23873)
SETTINGS = plaus.PlausibilitySettings(full_speed_rad_s=FULL)
DT = 0.05
NAMES = ("rotor_tach", "rotor_motor")


def drive(duties, reading, tau=0.4, full=FULL, s=SETTINGS, max_duty=1.0, tau_down=None, speed0=0.0):
    """Run the rules over ``duties`` (one per 50 ms tick); ``reading(t, true_speed)`` is what the
    tachometer shows. Returns (trip time or None, reason, the true speed at each tick)."""
    state = plaus.PlausibilityState()
    speed, trace = speed0, []
    for i, duty in enumerate(duties):
        t = i * DT
        plaus.advance(s, state, t)
        measured = reading(t, speed)
        reason = plaus.judge(s, state, t, measured, t, NAMES, max_duty)
        if reason:
            return t, reason, trace
        plaus.command(state, t, duty, duty >= max_duty - 1e-9)
        target = duty * full
        coast = tau_down if tau_down is not None and target < speed else tau
        speed = target + (speed - target) * math.exp(-DT / coast)
        trace.append(speed)
    return None, None, trace


def ramp_then_hold(rpm, seconds, ramp_rpm_s=6000.0):
    """Duties of a loop that ramps its feed-forward to ``rpm`` and holds it."""
    return [min(rpm, ramp_rpm_s * i * DT) / 23873 for i in range(int(seconds / DT))]


def truthful(t, speed):
    return speed


def test_a_truthful_tachometer_on_a_ramp_and_hold_never_trips():
    when, reason, trace = drive(ramp_then_hold(8000, 10), truthful)
    assert when is None, reason
    assert trace[-1] == __import__("pytest").approx(rpm_to_rad_s(8000), rel=1e-3)


def test_zero_reading_while_the_duty_is_high_trips_after_the_hold_time():
    fault_at = 5.0

    def zero_from(t, speed):
        return 0.0 if t >= fault_at else speed

    when, reason, _ = drive(ramp_then_hold(8000, 10), zero_from)
    assert when is not None and fault_at < when <= fault_at + SETTINGS.hold_s + 2 * DT
    assert "rotor_tach" in reason and "rotor_motor" in reason and "reads 0 RPM" in reason


def test_a_value_stuck_while_the_duty_moves_trips_before_the_repetition_rule():
    stuck = {}

    def stuck_from(t, speed):
        if t >= 0.8:
            stuck.setdefault("v", speed)
            return stuck["v"]
        return speed

    when, reason, _ = drive(ramp_then_hold(8000, 10), stuck_from)
    assert when is not None and when < 0.8 + SETTINGS.stuck_s, (when, reason)
    assert "stuck" in reason and "expected speed" in reason


def test_the_same_value_for_a_second_while_driven_is_stuck():
    values = {}

    def frozen_from(t, speed):
        return values.setdefault("v", speed) if t >= 6.0 else speed

    when, reason, _ = drive(ramp_then_hold(8000, 10), frozen_from)
    assert when is not None and 6.0 + SETTINGS.stuck_s - DT <= when <= 6.0 + SETTINGS.stuck_s + 2 * DT
    assert "the same value" in reason


def test_a_stopped_rotor_reading_zero_is_no_fault():
    when, reason, _ = drive([0.0] * 100, lambda t, s: 0.0)
    assert when is None, reason


def test_a_feed_forward_ten_times_too_low_trips_as_such():
    # the rig file says 2387 RPM at full duty; the motor gives 23 873
    typo = plaus.PlausibilitySettings(full_speed_rad_s=FULL / 10)
    duties = [min(1.0, 2000 / 2387 * min(1.0, i * DT / 0.3)) for i in range(200)]
    when, reason, trace = drive(duties, truthful, s=typo)
    assert when is not None and when < 1.5
    assert "full_speed_rpm" in reason and "far above" in reason


def test_coasting_down_after_a_step_down_is_not_too_high():
    duties = [0.5] * 100 + [0.0] * 20 + [0.1] * 200   # 12 000 RPM, duty off, then 2 400 RPM
    when, reason, _ = drive(duties, truthful, tau_down=4.0)  # a rotor that coasts ten times slower
    assert when is None, reason


def test_a_rotor_still_coasting_when_the_loop_starts_is_not_too_high():
    # a new run ramps its setpoint from zero while the rotor still turns at 8 000 RPM
    duties = [0.0] * 10 + [min(0.25, 0.01 * i) for i in range(200)]
    when, reason, _ = drive(duties, truthful, speed0=rpm_to_rad_s(8000), tau_down=3.0)
    assert when is None, reason


def test_a_stalled_motor_at_saturated_duty_trips():
    # jammed from the start: the speed never rises, the loop saturates its duty
    duties = [0.2] * 10 + [1.0] * 200
    s = plaus.PlausibilitySettings(full_speed_rad_s=FULL, slack_rad_s=rpm_to_rad_s(30000))  # band off
    when, reason, _ = drive(duties, lambda t, speed: rpm_to_rad_s(50.0 + 10 * math.sin(t)), s=s)
    assert when is not None and 0.5 + s.stall_s - DT <= when <= 0.5 + s.stall_s + 2 * DT
    assert "rotor_motor stalled" in reason and "saturated" in reason


@settings(max_examples=60, deadline=None)
@given(tau=st.floats(0.05, 0.4), gain=st.floats(0.6, 1.5), rpm=st.floats(1500, 20000),
       hold=st.floats(1.0, 6.0), jitter=st.floats(1e-5, 5e-4))
def test_no_false_trip_for_a_motor_no_slower_than_its_time_constant(tau, gain, rpm, hold, jitter):
    # any motor with tau <= motor_tau_s and a feed-forward off by -40 % .. +50 %, a noisy
    # tachometer, a ramp, a hold, a stop: never a trip. (Without any jitter a perfectly steady
    # reading is "the same value" for a second: the stuck rule; a real tachometer always wanders.)
    import random

    rng = random.Random(round(rpm))
    duties = ramp_then_hold(rpm, hold + rpm / 6000) + [0.0] * 60

    def reading(t, speed):
        return speed * gain * (1 + rng.gauss(0, jitter)) if speed > 1 else 0.0

    when, reason, _ = drive(duties, reading, tau=tau)
    assert when is None, reason


def test_cross_check_against_the_controllers_own_speed():
    state = plaus.PlausibilityState()
    agree = [plaus.cross_check(SETTINGS, state, t * 0.25, rpm_to_rad_s(8000), rpm_to_rad_s(8100), NAMES)
             for t in range(4)]
    assert agree == [None] * 4
    reasons = [plaus.cross_check(SETTINGS, state, 1 + t * 0.25, 0.0, rpm_to_rad_s(8000), NAMES)
               for t in range(3)]
    assert reasons[:2] == [None, None] and reasons[2] is not None  # 0.5 s >= the 0.3 s hold
    assert "controller rotor_motor measures 8000 RPM" in reasons[2]
    assert plaus.cross_check(SETTINGS, state, 2, 0.0, None, NAMES) is None  # SMC: no speed of its own


def test_duty_cap_keeps_the_feed_forward_speed_under_the_limit():
    assert duty_cap(1.0, rpm_to_rad_s(12000), FULL) * 23873 == __import__("pytest").approx(12000)
    assert duty_cap(0.8, rpm_to_rad_s(24000), FULL) == 0.8
    assert duty_cap(1.0, rpm_to_rad_s(24000), FULL) == 1.0


def test_a_target_the_feed_forward_cannot_reach_is_named():
    typo = plaus.PlausibilitySettings(full_speed_rad_s=rpm_to_rad_s(2387))
    problem = plaus.unreachable(typo, rpm_to_rad_s(6000), 1.0)
    assert problem is not None and "needs duty 2.51" in problem and "full_speed_rpm" in problem
    assert plaus.unreachable(SETTINGS, rpm_to_rad_s(24000), 1.0) is None
