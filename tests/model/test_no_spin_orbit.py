"""The no-net-spin periodic orbit (Fig. 5.6): on the axis it is Eq. 5.7's cone, whose spin is
Eq. 5.12's cos(phi) - 1; off the axis the whole attitude returns after one drive period."""

import math

import numpy as np
import pytest

from labkit.model import conical_dynamics as cd
from labkit.model import tilted_cone as tc
from labkit.model.no_spin_orbit import no_spin_orbit, period_map, tilt_angles


def test_on_axis_the_no_net_spin_orbit_is_eq_5_7_with_the_spin_of_eq_5_12():
    body = cd.RotatingFieldBody.from_si(1e-3, 0.3e-3, 0.998e-7, 0.998e-7, 60 * math.pi)  # stable cone
    phi = cd.equilibrium_phi(body)
    guess = cd.equilibrium(phi * 1.02, body.inertia_ratio)
    orbit, spin = no_spin_orbit(body, guess, 0.0)
    assert spin == pytest.approx(math.cos(phi) - 1.0, abs=1e-8)
    assert orbit.residual < 1e-9 and orbit.r_x < 1e-6
    lam, r_x = tilt_angles(body, orbit.y0)
    assert lam == pytest.approx(0.0, abs=1e-7) and r_x == pytest.approx(phi, abs=1e-7)


def test_tilted_orbit_returns_whole_attitude_and_differs_from_the_spin_free_one():
    body = cd.RotatingFieldBody.from_si(1e-3, 0.06e-3, 0.998e-7, 0.998e-7, 60 * math.pi)   # Fig. 5.6 row 8
    free, free_spin = tc.spin_free_orbit(body, tc.tilted_guess(body, 1.14, 0.2), -0.028)
    orbit, spin = no_spin_orbit(body, free.y0, free_spin)
    end, twist = period_map(body, orbit.y0)
    assert np.linalg.norm(end - orbit.y0) < 1e-9 and abs(twist) < 1e-9
    _, free_twist = period_map(body, free.y0)
    assert abs(free_twist) > 1e-3                       # the spin-free orbit turns about its axis
    assert spin != pytest.approx(free_spin, abs=1e-3)
    assert tilt_angles(body, orbit.y0) == pytest.approx((1.1369, 0.119), rel=0.01)   # paper's lambda, R_X


def test_row_3_path_encloses_the_pole_and_the_signed_angle_gives_the_papers_lambda_and_r_x():
    """Fig. 5.6 row 3 (ratio 0.140): lambda 0.2666 < R_X 0.275, so the dipole's path goes round
    the pole; the zenith angle folds at 0 there (its range is [R_X - lambda, R_X + lambda]), the
    signed tilt-plane angle does not."""
    body = cd.RotatingFieldBody.from_si(1e-3, 0.14e-3, 0.998e-7, 0.998e-7, 60 * math.pi)
    orbit, _ = no_spin_orbit(body, tc.tilted_guess(body, 0.27, 0.28), -0.039)
    end, twist = period_map(body, orbit.y0)
    assert np.linalg.norm(end - orbit.y0) < 1e-9 and abs(twist) < 1e-9
    lam, r_x = tilt_angles(body, orbit.y0)
    assert lam < r_x
    assert lam == pytest.approx(0.2666, rel=0.025) and r_x == pytest.approx(0.275, rel=0.01)
    assert orbit.r_x == pytest.approx(lam, rel=1e-3)     # zenith half-range = lambda: the fold
    assert tilt_angles(body, orbit.y0, 16384) == pytest.approx((lam, r_x), abs=1e-5)
