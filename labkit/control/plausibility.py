"""Does the tachometer agree with what the motor was told? Pure plausibility arithmetic.

A speed loop trusts its tachometer; this module is what it knows besides: the duty it
commanded and the rig's feed-forward ``full_speed`` (the speed at full duty), so
``duty * full_speed`` is the speed the motor should be heading for. A first-order motor
(time constant ``motor_tau_s``, the emulator's d(omega)/dt = (duty*full - omega)/tau) can
only get there with a lag, and it coasts down more slowly than its duty falls. Three
envelopes of the feed-forward speed follow from that (docs/decisions/0017-plausibility-interlocks.md):

* ``expected`` - the first-order lag of the feed-forward speed with ``motor_tau_s``;
* ``low`` - a floor: it rises with twice the motor's time constant and falls at once with
  the duty (a motor is never slower than that floor unless something is wrong);
* ``high`` - a ceiling: it rises at once with the duty and falls with five times the time
  constant (coasting); while the duty is zero it is at least the reading (a rotor still
  coasting from before is no fault).

The verdicts (each a trip reason naming the tachometer, the motor and the numbers):

* **low**: the reading stays below ``low / ratio - slack`` for ``hold_s`` once the duty has
  been on for ``grace_s``: a tachometer that reads zero or lost its mark, or a stalled motor;
* **high**: the reading stays above ``high * ratio + slack`` for ``hold_s / 2`` while the rotor
  is driven (duty > 0) and not coasting down: the feed-forward ``full_speed`` is wrong;
* **stuck**: the reading has not changed (bit for bit) while ``expected`` moved by more than
  ``slack`` (and a fraction ``1 - 1/ratio`` of it): the value does not follow the duty; or
  the same value ``stuck_n`` times over ``stuck_s`` while the rotor is driven;
* **stall**: the duty saturated for ``stall_s`` with the reading below half the speed the
  saturated duty gives;
* **cross-check** (:func:`cross_check`): where the controller measures the speed itself (the
  VESC), the reading must lie in the same band around that speed.

A target the feed-forward cannot reach (:func:`unreachable`) is refused before the rotor
turns: ``full_speed_rpm = 2387`` for 23 873 asks duty 2.5 for 6000 RPM.

No I/O and no clock: :func:`judge` takes the times and values, so the rules are tested in
microseconds (tests/control/test_plausibility.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from labkit.units import rad_s_to_rpm


@dataclass(frozen=True)
class PlausibilitySettings:
    """The band a reading must stay in (rig file ``[control]``, docs/reference/rig-files.md)."""

    full_speed_rad_s: float               # feed-forward: the speed at duty 1
    motor_tau_s: float = 0.4              # the motor's mechanical time constant
    ratio: float = 2.0                    # reading within [low/ratio - slack, high*ratio + slack]
    slack_rad_s: float = 1000.0 * math.pi / 30.0   # 1000 RPM
    hold_s: float = 0.3                   # how long a violation must last to trip
    grace_s: float = 1.5                  # duty on this long before "reads too low" applies
    stuck_s: float = 1.0                  # the same value this long while turning ...
    stuck_n: int = 5                      # ... and at least this many readings: stuck
    stall_s: float = 2.0                  # saturated duty without response this long: stall


@dataclass
class PlausibilityState:
    """What :func:`judge` remembers between control ticks of one loop."""

    t: float | None = None
    duty: float = 0.0                     # the duty held since ``t``
    expected: float = 0.0                 # rad/s
    low: float = 0.0
    high: float = 0.0
    on_since: float | None = None         # duty > 0 continuously since
    low_since: float | None = None        # "reads too low" since
    high_since: float | None = None
    high_first: float = 0.0               # the reading when "too high" began
    same_value: float | None = None       # the last distinct reading ...
    same_reading_t: float | None = None   # ... the time stamp of the reading it came from
    same_since: float | None = None       # ... received first at
    same_count: int = 0
    same_expected: float = 0.0            # ``expected`` when that value first came
    saturated_since: float | None = None
    cross_since: float | None = None      # tachometer and controller disagree since
    motor_speed: float | None = None      # the controller's own last measured speed (VESC)

    def pending_since(self) -> float | None:
        """Start of a violation that has not tripped yet (a point recorded across it must
        wait for the verdict); None when every reading so far is plausible."""
        times = [x for x in (self.low_since, self.high_since, self.cross_since) if x is not None]
        if self.same_since is not None and self.same_count >= 2:
            times.append(self.same_since)
        return min(times, default=None)


def _lag(value: float, target: float, dt: float, tau: float) -> float:
    return target + (value - target) * math.exp(-dt / tau) if tau > 0 else target


def advance(s: PlausibilitySettings, state: PlausibilityState, t: float) -> None:
    """Move the envelopes to ``t`` under the duty held since the last call."""
    if state.t is None:
        state.t = t
        return
    dt = max(0.0, t - state.t)
    state.t = t
    ff = state.duty * s.full_speed_rad_s
    state.expected = _lag(state.expected, ff, dt, s.motor_tau_s)
    state.low = ff if ff <= state.low else _lag(state.low, ff, dt, 2.0 * s.motor_tau_s)
    state.high = ff if ff >= state.high else _lag(state.high, ff, dt, 5.0 * s.motor_tau_s)


def command(state: PlausibilityState, t: float, duty: float, saturated: bool) -> None:
    """Note the duty commanded at ``t`` (held until the next call)."""
    state.duty = duty
    if duty > 0:
        state.on_since = t if state.on_since is None else state.on_since
    else:
        state.on_since = None
    if saturated:
        state.saturated_since = t if state.saturated_since is None else state.saturated_since
    else:
        state.saturated_since = None


def _rpm(x: float) -> str:
    return f"{rad_s_to_rpm(x):.0f} RPM"


def judge(s: PlausibilitySettings, state: PlausibilityState, t: float, measured: float | None,
          reading_t: float | None, names: tuple[str, str], max_duty: float) -> str | None:
    """Check one tick's reading against the duty history; a trip reason, or None.

    ``t`` is the tick's time (after :func:`advance`), ``measured`` the latest reading (rad/s,
    None: none yet) and ``reading_t`` its time stamp (a new time stamp is a new reading),
    ``names`` the tachometer and the motor, ``max_duty`` the duty cap (for the wording).
    """
    tach, motor = names
    if measured is None:
        return None
    duty_text = f"duty {state.duty:.3f} on {motor}"
    # ---- reads too low (zero, lost mark, stalled motor) ------------------------------------
    floor = state.low / s.ratio - s.slack_rad_s
    armed = state.on_since is not None and t - state.on_since >= s.grace_s
    if armed and measured < floor:
        state.low_since = t if state.low_since is None else state.low_since
        if t - state.low_since >= s.hold_s - 1e-9:
            cause = "the tachometer lost its target, or the motor stalls"
            if state.motor_speed is not None:
                cause = (f"motor controller {motor} measures {_rpm(state.motor_speed)}: " +
                         ("the tachometer is wrong" if state.motor_speed > floor else "the motor stalls"))
            if state.saturated_since is not None:
                cause += f" (duty saturated for {t - state.saturated_since:.1f} s)"
            return (f"tachometer {tach} implausible: reads {_rpm(measured)} for {t - state.low_since:.2f} s "
                    f"while {duty_text} predicts at least {_rpm(state.low)} (band: /{s.ratio:g} - "
                    f"{_rpm(s.slack_rad_s)} = {_rpm(max(floor, 0.0))}): {cause}")
    else:
        state.low_since = None
    # ---- reads too high while driven (feed-forward wrong) ----------------------------------
    if state.duty <= 0:  # undriven, the rotor may still coast from before: the ceiling starts there
        state.high = max(state.high, measured)
    ceiling = state.high * s.ratio + s.slack_rad_s
    if state.duty > 0 and measured > ceiling:
        if state.high_since is None or measured < state.high_first - 0.02 * state.high_first:
            state.high_since, state.high_first = t, measured   # first, or coasting down: restart
        elif t - state.high_since >= s.hold_s / 2.0 - 1e-9:  # the sensor is likely right: act fast
            return (f"tachometer {tach} reads {_rpm(measured)}, far above the {_rpm(state.high)} that "
                    f"{duty_text} predicts (x{s.ratio:g} + {_rpm(s.slack_rad_s)} = {_rpm(ceiling)}): "
                    f"is full_speed_rpm in the rig file wrong? (it is {_rpm(s.full_speed_rad_s)}, "
                    "the speed at full duty)")
    else:
        state.high_since = None
    # ---- stuck: the value does not follow the duty -----------------------------------------
    reason = _stuck(s, state, t, measured, reading_t, tach, duty_text)
    if reason:
        return reason
    # ---- stall: saturated duty, no response ------------------------------------------------
    if state.saturated_since is not None and t - state.saturated_since >= s.stall_s - 1e-9:
        full = max_duty * s.full_speed_rad_s
        if measured < full / 2.0:
            return (f"motor {motor} stalled: duty saturated at {max_duty:.3f} for "
                    f"{t - state.saturated_since:.1f} s but tachometer {tach} reads {_rpm(measured)}, "
                    f"below half the {_rpm(full)} that duty gives")
    return None


def _stuck(s: PlausibilitySettings, state: PlausibilityState, t: float, measured: float,
           reading_t: float | None, tach: str, duty_text: str) -> str | None:
    """The stuck rules, on fresh readings only (a new time stamp). Only while the rotor is
    driven and the reading is above zero: a stopped rotor's zeros, and the labkit
    tachometer's repeated last period while it waits for a slow pulse, are both normal."""
    if reading_t is None or reading_t == state.same_reading_t:
        return None
    state.same_reading_t = reading_t
    if state.same_value is None or measured != state.same_value or measured <= 0 or state.duty <= 0:
        state.same_value, state.same_since, state.same_count = measured, t, 1
        state.same_expected = state.expected
        return None
    state.same_count += 1
    assert state.same_since is not None
    moved = abs(state.expected - state.same_expected)
    if moved > max(s.slack_rad_s, (1.0 - 1.0 / s.ratio) * max(state.expected, state.same_expected)):
        return (f"tachometer {tach} stuck: reads {_rpm(measured)} unchanged for {t - state.same_since:.2f} s "
                f"({state.same_count} readings) while {duty_text} moved the expected speed from "
                f"{_rpm(state.same_expected)} to {_rpm(state.expected)}")
    if state.same_count >= s.stuck_n and t - state.same_since >= s.stuck_s - 1e-9:
        return (f"tachometer {tach} stuck: the same value {_rpm(measured)} {state.same_count} times over "
                f"{t - state.same_since:.2f} s while the rotor is driven ({duty_text}); a turning rotor's "
                "reading always wanders")
    return None


def cross_check(s: PlausibilitySettings, state: PlausibilityState, t: float, measured: float,
                motor_speed: float | None, names: tuple[str, str]) -> str | None:
    """The tachometer against the speed the motor controller measures itself (VESC: ERPM /
    pole pairs); None when the controller reports none (Pololu SMC, ESC bridge: their
    "speed" is the command). Same band and hold time as :func:`judge`."""
    if motor_speed is None or not math.isfinite(motor_speed):
        state.cross_since = state.motor_speed = None
        return None
    motor_speed = state.motor_speed = abs(motor_speed)
    low, high = motor_speed / s.ratio - s.slack_rad_s, motor_speed * s.ratio + s.slack_rad_s
    if low <= measured <= high:
        state.cross_since = None
        return None
    state.cross_since = t if state.cross_since is None else state.cross_since
    if t - state.cross_since < s.hold_s - 1e-9:
        return None
    tach, motor = names
    return (f"tachometer {tach} reads {_rpm(measured)} but motor controller {motor} measures "
            f"{_rpm(motor_speed)} for {t - state.cross_since:.2f} s (band /{s.ratio:g} - "
            f"{_rpm(s.slack_rad_s)} .. x{s.ratio:g} + {_rpm(s.slack_rad_s)}): one of them is wrong "
            "(VESC: check pole_pairs)")


def unreachable(s: PlausibilitySettings, target: float, max_duty: float) -> str | None:
    """Why ``target`` (rad/s) is beyond 1.5 times the speed the capped duty gives by the
    feed-forward (a typo in ``full_speed_rpm``), or None."""
    reach = max_duty * s.full_speed_rad_s
    if target <= 1.5 * reach:
        return None
    return (f"target {_rpm(target)} needs duty {target / s.full_speed_rad_s:.2f} by the feed-forward, "
            f"but the duty is capped at {max_duty:.3f} ({_rpm(reach)}): is full_speed_rpm in the rig file "
            f"wrong? (it is {_rpm(s.full_speed_rad_s)}, the speed at full duty)")
