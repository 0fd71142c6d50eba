"""MBS laws (Eq. 5.85, 6.13, 6.20-6.22, 6.30, 6.18, 5.69/6.37) against numeric derivatives and the
paper's printed numbers."""

import numpy as np
import pytest

from labkit.model.cone import cone_angle_spin
from labkit.model.mbs import (
    bipolar_tilt,
    equilibrium_distance,
    loaded_equilibrium,
    max_outward_load,
    mbs_force,
    scaled_speed,
    spin_equilibrium_constant,
    spin_for_speed,
    stiffness,
    stiffness_limit_distance,
)

EQ621 = (3950.0, 7.0, 89.5, 4.0)  # cm, N


def test_stiffness_is_minus_derivative_and_prints_eq_6_22():
    r = np.linspace(2.0, 5.0, 7)
    h = 1e-6
    numeric = -(mbs_force(r + h, *EQ621) - mbs_force(r - h, *EQ621)) / (2 * h)
    assert np.allclose(stiffness(r, *EQ621), numeric, rtol=1e-6)
    assert np.allclose(stiffness(r, *EQ621), 27650 * r**-8 - 358 * r**-5)


def test_numbers_below_eq_6_22():
    """S > 0 for r < 4.26 cm; load 0.117 N; equilibrium 3.53 cm (printed to 3 digits)."""
    assert stiffness_limit_distance(*EQ621) == pytest.approx(4.26, abs=5e-3)
    assert max_outward_load(*EQ621) == pytest.approx(0.117, abs=5e-4)
    assert loaded_equilibrium(0.0, *EQ621) == pytest.approx(3.53, abs=5e-3)
    assert stiffness(loaded_equilibrium(0.0, *EQ621), *EQ621) * 100 == pytest.approx(48.7, abs=0.05)


def test_loaded_equilibrium_balances_and_fails_beyond_the_load():
    f = 0.05
    r = loaded_equilibrium(f, *EQ621)
    assert mbs_force(r, *EQ621) + f == pytest.approx(0.0, abs=1e-12)
    assert stiffness(r, *EQ621) > 0
    assert np.isnan(loaded_equilibrium(0.12, *EQ621))


def test_equilibrium_distance_eq_6_13_zeroes_the_force_and_scales_as_inverse_sqrt_speed():
    a, b, c, d = 2e5, 7.5, 3.0, 3.5
    r1 = equilibrium_distance(500.0, a, b, c, d)
    assert mbs_force(r1, a / 500.0**2, b, c, d) == pytest.approx(0.0, abs=1e-9 * c * r1**-d)
    assert equilibrium_distance(2000.0, a, b, c, d) / r1 == pytest.approx(0.5)  # (b - d) = 4


def test_bipolar_tilt_is_the_smaller_root_of_eq_6_30_and_solves_eq_6_29():
    inertia, w, tau_m = 1e-7, 857.0, 0.02
    sigma = bipolar_tilt(inertia, w, tau_m)
    s = np.sin(sigma)
    big_a = w**2 * inertia / tau_m
    assert 3 * s**2 - 2 * big_a * s + 1 == pytest.approx(0.0, abs=1e-12)
    assert 1 - s**2 - (2 * inertia * w**2 - 4 * tau_m * s) / tau_m * s == pytest.approx(0.0, abs=1e-12)
    assert s < big_a / 3


def test_frequency_scaling_eq_6_18():
    assert scaled_speed(1000.0, 1.0, 8.0) == pytest.approx(500.0)


def test_eq_5_69_round_trips_through_eq_5_68():
    tau_c, tau_s, inertia, w, k = 1e-3, 1e-4, 1e-7, 900.0, -0.6
    phi = cone_angle_spin(tau_c, tau_s, inertia, w, k)
    c_const = spin_equilibrium_constant(tau_c, tau_s, inertia, phi)
    v_s = spin_for_speed(w, c_const, omega_c=np.inf)
    assert v_s / w - 1 == pytest.approx(k)
