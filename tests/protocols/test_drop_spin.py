"""The spin at the drop from sampled tachometer lines (labkit.protocols.drop_spin)."""

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from labkit.protocols.drop_spin import drop_instant, fresh_samples, line_spacing, spin_at


def ramp(t):
    """A floator spinning up linearly: 300 rad/s at t = 0, +80 rad/s per second."""
    return 300.0 + 80.0 * t


def test_a_linear_spin_up_is_read_at_the_drop_not_at_the_last_line():
    lines = [(t / 10, ramp(t / 10)) for t in range(-20, 1)]     # 10 Hz lines up to t = 0
    t_drop = 0.07                                               # dropped 70 ms after the last line
    assert spin_at(lines, t_drop) == pytest.approx(ramp(t_drop), abs=1e-9)
    assert lines[-1][1] == pytest.approx(ramp(t_drop) - 5.6)   # what the last line alone says


def test_a_constant_spin_stays_constant_and_one_line_is_returned_as_is():
    assert spin_at([(0.1 * k, 500.0) for k in range(8)], 2.0) == pytest.approx(500.0)
    assert spin_at([(1.0, 412.0)], 1.3) == 412.0
    with pytest.raises(ValueError, match="no spin readings"):
        spin_at([], 1.0)


def test_only_the_recent_lines_set_the_trend():
    # an old plateau followed by a spin-up: the line through the last 0.5 s follows the ramp
    lines = [(0.1 * k, 100.0) for k in range(10)] + [(1.0 + 0.1 * k, ramp(0.1 * k)) for k in range(10)]
    assert spin_at(lines, 1.95) == pytest.approx(ramp(0.95), abs=1e-9)


def test_held_display_zero_and_non_finite_lines_are_not_fresh():
    lines = [(0.0, 200.0), (0.1, 208.0), (0.2, 208.0), (0.3, 208.0), (0.4, 0.0), (0.5, math.nan)]
    assert fresh_samples(lines, min_value=6.0) == [(0.0, 200.0), (0.1, 208.0)]


def test_drop_instant_is_the_balance_midpoint_within_the_tachometer_bounds():
    assert line_spacing([0.0, 0.1, 0.2, 0.3]) == pytest.approx(0.1)
    assert drop_instant(10.00, 10.05, 9.99, 0.1) == pytest.approx(10.025)
    # a balance that reports late cannot push the drop past the next tachometer line
    assert drop_instant(10.8, 10.9, 10.0, 0.1) == pytest.approx(10.1)
    # nor before the window of the last line that still saw the floator
    assert drop_instant(9.0, 9.05, 10.0, 0.1) == pytest.approx(9.9)
    assert drop_instant(10.0, None, 9.95, 0.1) == pytest.approx(10.0)


@given(st.floats(-200, 200), st.floats(50, 2000), st.floats(0.02, 0.5), st.floats(0.0, 0.3))
def test_any_linear_trend_is_recovered(slope, start, spacing, ahead):
    lines = [(k * spacing, start + slope * k * spacing) for k in range(12)]
    t_drop = lines[-1][0] + ahead
    assert spin_at(lines, t_drop) == pytest.approx(start + slope * t_drop, rel=1e-9, abs=1e-6)
