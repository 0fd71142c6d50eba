"""Point-dipole physics (Eq. 4.1-4.4) against textbook limits, -grad U, and the paper's Eq. 5.26/5.71."""

import numpy as np
import pytest

from labkit.model.dipole import (
    K_M,
    dipole_field,
    dipole_force,
    dipole_torque,
    potential_energy,
    torque_in_field,
)

RNG = np.random.default_rng(4)


def random_config(n=20):
    return RNG.normal(size=(n, 3)), RNG.normal(size=(n, 3)), RNG.normal(size=(n, 3)) * 0.02 + 0.05


def test_field_on_axis_and_equator():
    m = np.array([0.0, 0.0, 2.0])
    r = 0.01
    assert np.allclose(dipole_field(m, [0, 0, r]), [0, 0, 2 * K_M * 2.0 / r**3])
    assert np.allclose(dipole_field(m, [r, 0, 0]), [0, 0, -K_M * 2.0 / r**3])


def test_force_is_minus_gradient_of_energy():
    m_a, m_b, r = random_config()
    h = 1e-7
    grad = np.empty_like(r)
    for i in range(3):
        dr = np.zeros(3)
        dr[i] = h
        grad[:, i] = (potential_energy(m_a, m_b, r + dr) - potential_energy(m_a, m_b, r - dr)) / (2 * h)
    assert np.allclose(dipole_force(m_a, m_b, r), -grad, rtol=1e-6, atol=0)


def test_torque_equals_moment_cross_field():
    m_a, m_b, r = random_config()
    assert np.allclose(dipole_torque(m_a, m_b, r), torque_in_field(m_b, dipole_field(m_a, r)), rtol=1e-12)


def test_newton_third_law_and_total_angular_momentum():
    m_a, m_b, r = random_config()
    f_ab = dipole_force(m_a, m_b, r)
    assert np.allclose(f_ab, -dipole_force(m_b, m_a, -r), rtol=1e-12)
    total = dipole_torque(m_a, m_b, r) + dipole_torque(m_b, m_a, -r) + np.cross(r, f_ab)
    assert np.allclose(total, 0.0, atol=1e-12 * np.abs(f_ab).max() * 0.05)


def test_coaxial_dipoles_attract_with_textbook_force():
    r = 0.02
    f = dipole_force([0, 0, 1.0], [0, 0, 3.0], [0, 0, r])
    assert f[2] == pytest.approx(-6 * K_M * 3.0 / r**4, rel=1e-12)  # -3 mu0 m1 m2 / (2 pi r^4)


@pytest.mark.parametrize("gamma,phi,wt", [(0.1, 0.2, 0.3), (0.0, 0.5, 1.1), (-0.2, 0.05, 2.0)])
def test_rotator_floator_torque_matches_eq_5_26(gamma, phi, wt):
    s, c = np.sin(wt), np.cos(wt)
    m_r = 2.0 * np.array([s * np.cos(gamma), -c * np.cos(gamma), np.sin(gamma)])
    m_f = 0.8 * np.array([s * np.sin(phi), -c * np.sin(phi), np.cos(phi)])
    r = 0.03
    tau = dipole_torque(m_r, m_f, [0, 0, r])
    expected = K_M * 2.0 * 0.8 / r**3 * (np.cos(gamma) * np.cos(phi) + 2 * np.sin(gamma) * np.sin(phi)) \
        * np.array([-c, -s, 0.0])
    assert np.allclose(tau, expected, rtol=1e-12, atol=1e-18)


def test_broadcasts_over_trajectories():
    m_a, m_b, r = random_config(7)
    assert dipole_force(m_a[0], m_b, r).shape == (7, 3)
    assert dipole_field(m_a, r).shape == (7, 3)
