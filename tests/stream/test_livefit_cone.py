"""The live Eq. 5.24 fit (``cone-angle`` in LIVE_FITS): torques over I recovered from angles
made by Eq. 5.24 with noise, the same in RPM/deg as in rad/s/rad, a band that covers the truth;
the registry passes the hints' units only to fits that take them (open to more entries); the
pattern table a cone-sweep burst gives the live view inverts the measured semi-axes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from labkit.protocols.cone_sweep import pattern_at_angles
from labkit.stream.frames import semi_axes_at
from labkit.stream.livefit import LIVE_FITS, LiveFit, cone_angle_fit, live_fit

TAU_C, TAU_S = 3.97e4, 4.9e3   # s^-2 (torques over I), the emulated rig's order of magnitude


def eq524(w_rad_s: np.ndarray) -> np.ndarray:
    return np.arctan(TAU_C / (w_rad_s**2 - TAU_S))


def test_the_cone_angle_fit_recovers_the_torques_within_their_errors():
    rng = np.random.default_rng(7)
    w = np.linspace(500.0, 1050.0, 8)
    phi = eq524(w) * (1 + 1e-3 * rng.standard_normal(w.size))
    fit = cone_angle_fit(list(w), list(phi))
    assert fit is not None and fit.n == 8
    (c, sc), (s, ss) = fit.params["tau_C_over_I"], fit.params["tau_S_over_I"]
    assert abs(c - TAU_C) < 4 * sc and abs(s - TAU_S) < 4 * ss
    assert sc < 0.01 * TAU_C
    y, lo, hi = fit.curve(w)
    assert np.all(lo < y) and np.all(y < hi)
    assert np.all(np.abs(y - eq524(w)) < 3 * (hi - lo))


def test_the_hints_units_give_the_same_fit():
    w = np.linspace(500.0, 1050.0, 6)
    rpm, deg = w * 30 / math.pi, np.degrees(eq524(w))
    si = cone_angle_fit(list(w), list(eq524(w)))
    lab = live_fit("cone-angle", list(rpm), list(deg), "RPM", "deg")
    assert si is not None and lab is not None
    for k in ("tau_C_over_I", "tau_S_over_I"):
        assert lab.params[k][0] == pytest.approx(si.params[k][0], rel=1e-6)
    assert lab.curve(np.array([6000.0]))[0][0] == pytest.approx(
        math.degrees(si.curve(np.array([6000.0 * math.pi / 30]))[0][0]), rel=1e-6)


def test_too_few_points_or_unknown_units_give_no_fit():
    w = [500.0, 700.0, 900.0]
    assert cone_angle_fit(w[:2], list(eq524(np.array(w[:2])))) is None
    assert live_fit("cone-angle", w, list(eq524(np.array(w))), "Hz", "rad") is None
    assert live_fit("cone-angle", w, list(eq524(np.array(w))), "rad/s", "grad") is None
    assert live_fit("no-such-fit", w, [1.0, 2.0, 3.0]) is None


def test_a_fit_without_units_is_called_with_the_numbers_alone(monkeypatch):
    seen = []

    def mean_line(x: list[float], y: list[float]) -> LiveFit:
        seen.append((list(x), list(y)))
        m = float(np.mean(y))
        return LiveFit("mean", {"m": (m, 0.0)}, len(y), f"mean {m}", lambda xs: (xs * 0 + m,) * 3)

    monkeypatch.setitem(LIVE_FITS, "mean", mean_line)
    fit = live_fit("mean", [1.0, 2.0], [3.0, 5.0], "RPM", "deg")
    assert seen == [([1.0, 2.0], [3.0, 5.0])] and fit is not None and fit.curve(np.array([9.0]))[0][0] == 4.0


def test_the_pattern_table_gives_the_measured_semi_axes_at_the_measured_angle():
    screen_mm, mm_per_px = 500.0, 2.0
    axes = [40.0, 31.0]
    tilts = [0.5 * math.atan(r * mm_per_px / screen_mm) for r in axes]
    angle = sum(tilts) / 2
    table = pattern_at_angles({"type": "ellipse", "semi_axes_px": axes}, angle, screen_mm, mm_per_px)
    assert table is not None
    back = semi_axes_at(table, math.degrees(angle))
    assert back == pytest.approx(axes, rel=2e-3)   # linear between 41 rows: stated tolerance
    bigger = semi_axes_at(table, 1.2 * math.degrees(angle))
    assert bigger[0] > axes[0] and bigger[1] > axes[1]
    assert semi_axes_at(table, 3 * math.degrees(angle)) is None   # no extrapolation
    trochoid = {"type": "epitrochoid", "semi_axes_px": axes}
    assert pattern_at_angles(trochoid, angle, screen_mm, mm_per_px) is None
