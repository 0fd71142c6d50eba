"""Closed-loop speed control with interlocks (see loop.py; pure arithmetic in pi.py)."""

from labkit.control.loop import LoopSnapshot, SpeedControl, SpeedLoop, build_speed_control
from labkit.control.pi import PIGains, PIState, SettleDetector, pi_step, ramp_toward

__all__ = [
    "LoopSnapshot", "PIGains", "PIState", "SettleDetector", "SpeedControl", "SpeedLoop",
    "build_speed_control", "pi_step", "ramp_toward",
]
