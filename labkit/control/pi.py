"""Pure speed-control arithmetic: feed-forward + PI with anti-windup, and a ramp limiter.

No I/O here, so the law can be tested against a small plant in microseconds. Speeds are
rad/s, duty is 0..max_duty (a PFR rotor only ever turns one way).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class PIGains:
    """``duty = target/full_speed + kp*error + ki*integral(error)``, clipped to [0, max_duty]."""

    full_speed_rad_s: float
    kp: float
    ki: float
    max_duty: float = 1.0


@dataclass
class PIState:
    integral: float = 0.0   # rad (integrated speed error)
    duty: float = 0.0


def pi_step(gains: PIGains, state: PIState, target: float, measured: float, dt: float) -> float:
    """One control period. Returns the new duty and updates ``state`` in place.

    Two anti-windup rules keep the integral to what the motor can deliver:

    * conditional integration: the integral does not grow while the output is saturated in
      the direction of the error (a long saturation, a stalled rotor);
    * the integral term stays within the duty left by the feed-forward,
      ``0 <= target/full_speed + ki*integral <= max_duty`` (:func:`integral_bounds`). What
      the integral gathers while the rotor lags a ramped setpoint would otherwise sit behind
      the saturation: near the top speed the rotor, pinned at full duty, can overshoot the
      target only by the little speed it has left, so that small error unwinds the excess
      slowly (at 23 000 RPM on the emulated Fig. 5.25 rig it held full duty for 14 s and the
      speed did not settle within 20 s).
    """
    error = target - measured
    feed_forward = target / gains.full_speed_rad_s if gains.full_speed_rad_s > 0 else 0.0
    candidate = state.integral + error * dt
    unclipped = feed_forward + gains.kp * error + gains.ki * candidate
    saturated_high = unclipped > gains.max_duty and error > 0
    saturated_low = unclipped < 0.0 and error < 0
    integral = state.integral if (saturated_high or saturated_low) else candidate
    low, high = integral_bounds(gains, feed_forward)
    state.integral = min(max(integral, low), high)
    duty = min(max(feed_forward + gains.kp * error + gains.ki * state.integral, 0.0), gains.max_duty)
    if target <= 0.0:
        state.integral = 0.0
        duty = 0.0
    state.duty = duty
    return duty


def integral_bounds(gains: PIGains, feed_forward: float) -> tuple[float, float]:
    """The integral (rad) whose term ``ki*integral`` keeps ``feed_forward + ki*integral``
    within ``[0, max_duty]``: the duty the motor has left beyond the feed-forward (any of it,
    either way, when ``ki`` is 0)."""
    if gains.ki <= 0:
        return -float("inf"), float("inf")
    return -feed_forward / gains.ki, (gains.max_duty - feed_forward) / gains.ki


def ramp_toward(current: float, target: float, max_rate: float, dt: float) -> float:
    """Move ``current`` toward ``target`` by at most ``max_rate*dt`` (the rig's ramp limit)."""
    step = max_rate * dt
    if target > current:
        return min(target, current + step)
    return max(target, current - step)


@dataclass
class SettleDetector:
    """Settled = within ``tolerance`` of the target continuously for ``hold_s``."""

    tolerance: float
    hold_s: float
    inside_since: float | None = None

    def reset(self) -> None:
        self.inside_since = None

    def update(self, t: float, error: float) -> bool:
        if abs(error) > self.tolerance:
            self.inside_since = None
            return False
        if self.inside_since is None:
            self.inside_since = t
        return t - self.inside_since >= self.hold_s
