"""PFR force (Eq. 5.70-5.81, 5.92) against Eq. 4.2 and Table 5.5."""

import numpy as np
import pytest

from labkit.model.cone import planar_amplitude
from labkit.model.dipole import dipole_force
from labkit.model.pfr_force import (
    cone_angle_at_distance,
    dipole_constant,
    distance_for_cone_angle,
    force_at_cone_angle,
    pfr_force,
    pfr_force_power_law,
    planar_average_force_ratio,
)


def test_eq_5_71_is_eq_4_2_in_the_co_rotating_configuration():
    m_r, m_f, r, phi = 2.83, 0.8, 0.03, 0.2
    f = dipole_force([m_r, 0, 0], m_f * np.array([np.sin(phi), 0, np.cos(phi)]), [0, 0, r])
    fx, fz = force_at_cone_angle(phi, r, dipole_constant(m_r, m_f))
    assert f == pytest.approx([fx, 0.0, fz], rel=1e-12)


def test_closed_form_eq_5_77_equals_eq_5_71_with_eq_5_74():
    m_const = dipole_constant(2.83, 0.8)
    r = np.linspace(0.01, 0.05, 9)
    phi = cone_angle_at_distance(r, m_const, 1e-7, 589.2, 1e-4)
    fx, fz = pfr_force(r, m_const, 1e-7, 589.2, 1e-4)
    ex, ez = force_at_cone_angle(phi, r, m_const)
    assert np.allclose(fx, ex, rtol=1e-12) and np.allclose(fz, ez, rtol=1e-12)


def test_distance_for_cone_angle_inverts_eq_5_74():
    c_const = 1 / np.tan(0.1)
    assert distance_for_cone_angle(0.1, c_const) == pytest.approx(1.0)


@pytest.mark.parametrize("lo,hi,printed_b", [(0.05, 0.15, 2.97), (0.02, 0.10, 2.99), (0.10, 0.25, 2.91)])
def test_table_5_5_exponents(lo, hi, printed_b):
    """Power-law fit of sin(phi) against r (Eq. 5.79) over Table 5.5's phi ranges: b to 0.02."""
    c_const = 1 / np.tan(0.1)
    phi = np.linspace(lo, hi, 200)
    r = distance_for_cone_angle(phi, c_const)
    slope = np.polyfit(np.log(r), np.log(np.sin(phi)), 1)[0]
    assert -slope == pytest.approx(printed_b, abs=0.02)


def test_power_law_tends_to_exact_far_away():
    m_const = dipole_constant(2.0, 1.0)
    r = 1.0  # phi ~ 2e-7: deep in the b = 3, a = 1 regime
    exact = pfr_force(r, m_const, 1e-7, 1000.0)[1]
    assert pfr_force_power_law(r, m_const, 1e-7, 1000.0) == pytest.approx(exact, rel=1e-9)


def test_eq_5_93_average_force_is_half_the_amplitude():
    half_amplitude = 0.5 * planar_amplitude(1e4, 60 * np.pi)
    assert planar_average_force_ratio(1e4, 60 * np.pi) == pytest.approx(half_amplitude)
