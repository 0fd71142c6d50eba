"""Magnetic bound state: force law, equilibrium, stiffness, scaling (paper Sec. 5.2.1, 6.0, 6.2, 6.5).

Units are whatever the coefficients are in (the paper's Eq. 6.21 uses cm and N); functions
are pure power-law algebra. Repulsion ``a r^-b`` (PFR), attraction ``c r^-d``.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq


def mbs_force(r, a, b, c, d):
    """Axial force F_z(r) = a r^-b - c r^-d, repulsive PFR minus static attraction (Eq. 5.85)."""
    r = np.asarray(r, float)
    return a * r ** (-b) - c * r ** (-d)


def equilibrium_distance(omega, a, b, c, d):
    """Weightless equilibrium r = (a / (c w^2))^(1/(b-d)) with PFR scaling as w^-2 (Eq. 6.13)."""
    return (a / (c * np.asarray(omega, float) ** 2)) ** (1.0 / (b - d))


def stiffness(r, a, b, c, d):
    """S(r) = -d(F_R + F_A)/dr for F_R = a r^-b, F_A = -c r^-d (Eq. 6.20; Eq. 6.22 for Eq. 6.21)."""
    r = np.asarray(r, float)
    return a * b * r ** (-b - 1.0) - c * d * r ** (-d - 1.0)


def stiffness_limit_distance(a, b, c, d):
    """Largest distance with positive stiffness, S(r) = 0 (below Eq. 6.22)."""
    return (a * b / (c * d)) ** (1.0 / (b - d))


def max_outward_load(a, b, c, d):
    """Largest external force pulling the floator away the bound state carries (below Eq. 6.22).

    Equals the net attraction c r^-d - a r^-b at :func:`stiffness_limit_distance`.
    """
    r = stiffness_limit_distance(a, b, c, d)
    return -float(mbs_force(r, a, b, c, d))


def loaded_equilibrium(f_ext, a, b, c, d):
    """Stable equilibrium distance with a constant external force ``f_ext`` (Eq. 6.19).

    ``f_ext`` > 0 pushes the floator away from the rotator (beneath it), < 0 towards it.
    Solves F_R + F_A + f_ext = 0 on the stable branch r < r_limit; NaN when none exists.
    """
    r_lim = stiffness_limit_distance(a, b, c, d)

    def net(r: float) -> float:
        return float(mbs_force(r, a, b, c, d)) + f_ext

    if net(r_lim) > 0:
        return float("nan")
    lo = r_lim
    while net(lo) <= 0:
        lo *= 0.5
    return brentq(net, lo, r_lim, xtol=1e-14, rtol=1e-14)


def bipolar_tilt(inertia_f, omega, tau_m):
    """sin(sigma) of the bipolar bound state, minus root of 3 s^2 - 2 A s + 1 = 0 (Eq. 6.30).

    ``A = w^2 I_F / tau_M`` with ``tau_M = mu0 m_R m_F / (4 pi r^3)``. Returns sigma (rad);
    NaN when A^2 < 3.
    """
    big_a = np.asarray(omega, float) ** 2 * inertia_f / tau_m
    with np.errstate(invalid="ignore"):
        return np.arcsin((big_a - np.sqrt(big_a**2 - 3.0)) / 3.0)


def scaled_speed(omega_ref, mass_ref, mass):
    """Stability speed of a geometrically similar floator, w ~ m^(-1/3) (Eq. 6.18)."""
    return omega_ref * (np.asarray(mass, float) / mass_ref) ** (-1.0 / 3.0)


def spin_equilibrium_constant(tau_c, tau_s, inertia, phi):
    """C = (tau_C cos phi + tau_S sin phi) / (I sin phi) = -k w^2 (Eq. 5.69)."""
    return (tau_c * np.cos(phi) + tau_s * np.sin(phi)) / (inertia * np.sin(phi))


def spin_for_speed(omega, c_const, omega_c=3000.0):
    """Spin velocity v_S (rad/s) keeping the PFR constant, -k w^2 = C (1 - w/w_c) (Eq. 6.37).

    ``omega_c = inf`` gives the plain Eq. 5.69. k = v_S / w - 1.
    """
    omega = np.asarray(omega, float)
    k = -c_const * (1.0 - omega / omega_c) / omega**2
    return (k + 1.0) * omega
