"""Periodic orbits of Eq. 5.56 / 5.484 and the co-rotating-frame rigid body, checked by
integration (periodicity, conservation) and against the paper's printed tables."""

import numpy as np
import pytest

from labkit.model import conical_dynamics as cd
from labkit.model.one_dof import cosine_coefficients, one_dof_rhs, periodic_amplitude0
from labkit.model.pfr_force import planar_average_force_ratio
from labkit.model.planar import integrate, periodic_orbit
from labkit.model.stability import criterion_holds

W60 = 60 * np.pi


def test_planar_orbit_is_periodic_and_has_zero_mean_acceleration():
    """Shooting on theta(T/2) alone must give a full period (symmetry argument in planar.py);
    the mean acceleration of Eq. 5.60 is then zero (the paper's -1.29e-6 J_C is noise)."""
    orbit = periodic_orbit(1e4, W60)
    sol = integrate(1e4, W60, orbit.theta0, orbit.rate0, orbit.period)
    assert sol.y[0, -1] == pytest.approx(orbit.theta0, abs=1e-9)
    assert sol.y[1, -1] == pytest.approx(orbit.rate0, rel=1e-9)
    assert sol.y[1, -1] - sol.y[1, 0] == pytest.approx(0.0, abs=1e-8 * 1e4 * orbit.period)


def test_table_5_4_row_1():
    """Printed a1 = -0.2748, a2 = -9.55e-3, a3 = -4.3e-4 (4, 3, 2 significant digits)."""
    a = periodic_orbit(-1e4, W60, theta0=0.0).sine_coefficients(3)
    assert a[0] == pytest.approx(-0.2748, abs=5e-5)
    assert a[1] == pytest.approx(-9.55e-3, abs=5e-5)
    assert a[2] == pytest.approx(-4.3e-4, abs=1e-5)


def test_planar_average_force_tends_to_eq_5_92_at_small_amplitude():
    orbit = periodic_orbit(1e4, 300 * np.pi)
    closed = planar_average_force_ratio(1e4, 300 * np.pi)
    assert orbit.average_force_ratio() == pytest.approx(closed, rel=1e-3)


def test_one_dof_small_amplitude_matches_linear_theory():
    """Eq. 5.491 (sign of the particular solution fixed): a -> J_C / (w^2 - J_S)."""
    j_c, j_s, w = 100.0, 300.0, W60
    a1 = cosine_coefficients(j_c, j_s, w, 1)[0]
    assert a1 == pytest.approx(j_c / (w**2 - j_s), rel=1e-3)


def test_one_dof_orbit_is_periodic():
    from scipy.integrate import solve_ivp
    j_c, j_s, w = 0.2355 * W60**2, 0.0726 * W60**2, W60
    phi0 = periodic_amplitude0(j_c, j_s, w)
    sol = solve_ivp(one_dof_rhs, (0, 2 * np.pi / w), [phi0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                    args=(j_c, j_s, w))
    assert sol.y[0, -1] == pytest.approx(phi0, abs=1e-9)


def test_eq_5_485_setting():
    """The documented setting (I = 1e-7, w = 80 pi, tau_C = 1.488e-3, tau_S = 4.585e-4) gives
    a = 0.248 and b = -2.06e-4 as printed (3 significant digits)."""
    w = 80 * np.pi
    a = cosine_coefficients(1.488e-3 / 1e-7, 4.585e-4 / 1e-7, w, 3)
    assert a[0] == pytest.approx(0.248, abs=5e-4)
    assert a[2] == pytest.approx(-2.06e-4, abs=5e-7)
    assert abs(a[1]) < 1e-12  # only odd harmonics


def test_rotating_frame_rhs_conserves_norm_and_spin():
    body = cd.RotatingFieldBody(0.3, 0.05, 1.3)
    y = np.random.default_rng(1).normal(size=(50, 6))
    dy = cd.rhs(y, body)
    psi, ell = y[:, :3], y[:, 3:]
    assert np.allclose(np.sum(psi * dy[:, :3], axis=1), 0.0, atol=1e-12)
    assert np.allclose(np.sum(dy[:, 3:] * psi + ell * dy[:, :3], axis=1), 0.0, atol=1e-12)


@pytest.mark.parametrize("ratio", [1.4, 1.0, 0.7])
def test_cone_is_a_fixed_point(ratio):
    body = cd.RotatingFieldBody(0.25, 0.06, ratio)
    y = cd.equilibrium(cd.equilibrium_phi(body), body.inertia_ratio)
    assert np.allclose(cd.rhs(y, body), 0.0, atol=1e-14)


@pytest.mark.parametrize("j_c", [0.05, 0.2, 0.35])
@pytest.mark.parametrize("inertia_ratio", [1.0, 1.3, 0.6])
def test_linear_stability_boundary_is_eq_5_46(j_c, inertia_ratio):
    """The co-rotating-frame linearisation is stable exactly where Eq. 5.46 (with I_R) says so."""
    j_min = 1 - np.sqrt(1 - j_c**2)
    for j_s, stable in [(1.05 * j_min, True), (0.95 * j_min, False)]:
        assert bool(criterion_holds(j_c, j_s, 1.0, 1.0)) is stable
        rate = cd.growth_rate(cd.RotatingFieldBody(j_c, j_s, inertia_ratio))
        assert (rate < 1e-7) is stable


def test_time_domain_unstable_cone_leaves_z_and_stable_one_stays():
    body_ok = cd.RotatingFieldBody.from_si(1.1e-3, 0.20 * 1.1e-3, 1e-7, 1e-7, W60)
    body_bad = cd.RotatingFieldBody.from_si(1.1e-3, 0.14 * 1.1e-3, 1e-7, 1e-7, W60)
    for body, bounded in [(body_ok, True), (body_bad, False)]:
        phi = cd.equilibrium_phi(body)
        y0 = cd.paper_initial_state(phi + 1e-3, 0.0, W60, body.inertia_ratio)
        res = cd.run(body, y0, 1.0 * W60, phi, samples=400, rtol=1e-9)
        assert (res.max_deviation < 0.02) is bounded
        assert res.spin_drift < 1e-7
