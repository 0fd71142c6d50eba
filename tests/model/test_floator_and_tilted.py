"""Co-rotating steady state of a floator over a tilted rotating dipole (Eq. 5.85 setting) and the
tilted conical orbits of Fig. 5.6, checked in the lab frame by independent means."""

import numpy as np
import pytest

from labkit.model import conical_dynamics as cd
from labkit.model import tilted_cone as tc
from labkit.model.dipole import dipole_force, dipole_torque
from labkit.model.floator_equilibrium import FloatorSetup, power_law_exponent, steady_state

SETUP = FloatorSetup(4.52, 0.8, 6.67e-3, 1e-7, 1e-7, 1129.0, 0.151)  # Table 5.6 row 5


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def test_steady_state_obeys_newton_and_euler_in_the_lab_frame():
    """Rebuild the lab trajectory (rotate the co-rotating state by w t) and check m a = F_xy and
    dL/dt = tau by finite differences, with forces from Eq. 4.2/4.3 directly."""
    r = 0.0238
    st = steady_state(SETUP, r)
    psi_c, ell_c = st.x[:3] / np.linalg.norm(st.x[:3]), st.x[3:6]
    pos_c = np.array([st.x[6] * r, st.x[7] * r, r])
    w, h = SETUP.omega, 1e-6
    m_r0 = SETUP.m_rotator * np.array([0.0, -np.cos(SETUP.gamma), np.sin(SETUP.gamma)])

    def lab(t):
        rot = _rz(w * t)
        return rot @ pos_c, rot @ psi_c, rot @ ell_c * SETUP.i_radial * w, rot @ m_r0

    t0 = 0.37e-3
    pos, psi, _, m_r = lab(t0)
    acc = (lab(t0 + h)[0] - 2 * pos + lab(t0 - h)[0]) / h**2
    force = dipole_force(m_r, SETUP.m_floator * psi, pos)
    assert np.allclose(SETUP.mass * acc[:2], force[:2], rtol=1e-4)
    dl = (lab(t0 + h)[2] - lab(t0 - h)[2]) / (2 * h)
    assert np.allclose(dl, dipole_torque(m_r, SETUP.m_floator * psi, pos), rtol=1e-5, atol=1e-9)
    # no spin: psi . Omega = cos(phi) - 1 (Eq. 5.12)
    assert np.dot(psi_c, ell_c) == pytest.approx(np.cos(st.phi) - 1.0, abs=1e-9)


def test_steady_state_near_table_5_6_row_5():
    """Point-dipole cone angle 0.213 and beta 0.362 mm printed (FEM-coupled sim): within 10 %."""
    st = steady_state(SETUP, 0.0238)
    assert st.phi == pytest.approx(0.213, rel=0.05)
    assert st.beta == pytest.approx(0.362e-3, rel=0.1)
    assert st.force_cyclic_z > 0 > st.force_static_z


def test_power_law_exponent_recovers_a_known_law():
    r = np.geomspace(0.01, 0.05, 9)
    k, n = power_law_exponent(r, -3.0 * r**-4.2)
    assert n == pytest.approx(4.2) and k == pytest.approx(3.0)


def test_tilted_orbit_is_periodic_with_the_fig_5_4_semi_axis():
    """Fig. 5.4 / Fig. 5.6 row 7 (tau_S/tau_C = 0.0944): R_X = 0.186 rad printed (3 digits)."""
    body = cd.RotatingFieldBody.from_si(1e-3, 0.0944e-3, 0.998e-7, 0.998e-7, 60 * np.pi)
    orbit = tc.shoot(body, -0.028, tc.tilted_guess(body, 0.85, 0.2))
    assert orbit.residual < 1e-9
    assert orbit.r_x == pytest.approx(0.186, abs=1e-3)
    assert 0.8 < orbit.lam < 0.95
