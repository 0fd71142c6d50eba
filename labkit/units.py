"""Unit constants used across labkit (SI inside; these convert at the edges).

One definition each, so a rig file, a driver, an emulator and a plot agree to the last bit.
"""

from __future__ import annotations

import math

#: rad/s per mechanical revolution per minute
RAD_S_PER_RPM = 2.0 * math.pi / 60.0
#: m/s^2, standard gravity (grams-force -> newtons)
G0 = 9.80665


def rpm_to_rad_s(rpm: float) -> float:
    """Mechanical RPM -> rad/s."""
    return rpm * RAD_S_PER_RPM


def rad_s_to_rpm(rad_s: float) -> float:
    """rad/s -> mechanical RPM."""
    return rad_s / RAD_S_PER_RPM
