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

    Anti-windup by conditional integration: the integral only grows when the output is
    not saturated in the direction of the error, so a long saturation (a slow ramp, a
    stalled rotor) does not leave a huge integral that overshoots afterwards.
    """
    error = target - measured
    feed_forward = target / gains.full_speed_rad_s if gains.full_speed_rad_s > 0 else 0.0
    unclipped = feed_forward + gains.kp * error + gains.ki * (state.integral + error * dt)
    duty = min(max(unclipped, 0.0), gains.max_duty)
    saturated_high = unclipped > gains.max_duty and error > 0
    saturated_low = unclipped < 0.0 and error < 0
    if not (saturated_high or saturated_low):
        state.integral += error * dt
    if target <= 0.0:
        state.integral = 0.0
        duty = 0.0
    state.duty = duty
    return duty


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
