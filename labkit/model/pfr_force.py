"""PFR force on a floator above a rotating dipole (paper Sec. 5.2, Eq. 5.70-5.81, 5.87-5.93).

``M = mu0 m_R m_F / (4 pi)`` (N m^4), ``r`` the axial distance (m),
``inertia`` the floator's moment of inertia (kg m^2), ``omega`` the rotation speed (rad/s),
``tau_s`` the static torque coefficient (N m). Forces in N.
"""

from __future__ import annotations

import numpy as np

from labkit.model.dipole import K_M


def dipole_constant(m_r, m_f):
    """M = mu0 m_R m_F / (4 pi) (Eq. 5.71)."""
    return K_M * np.asarray(m_r, float) * np.asarray(m_f, float)


def cyclic_torque(m_const, r):
    """Cyclic torque coefficient tau_C = M / r^3 (Eq. 5.73)."""
    return m_const / np.asarray(r, float) ** 3


def force_at_cone_angle(phi, r, m_const):
    """(F_x, F_z) = 3M/r^4 (cos phi, sin phi) on the floator in the co-rotating frame (Eq. 5.71)."""
    scale = 3.0 * m_const / np.asarray(r, float) ** 4
    return scale * np.cos(phi), scale * np.sin(phi)


def cone_angle_at_distance(r, m_const, inertia, omega, tau_s=0.0):
    """phi = atan(M / (r^3 (I w^2 - tau_S))) (Eq. 5.74)."""
    with np.errstate(divide="ignore"):
        return np.arctan(m_const / (np.asarray(r, float) ** 3 * (inertia * np.asarray(omega, float) ** 2
                                                               - tau_s)))


def pfr_force(r, m_const, inertia, omega, tau_s=0.0):
    """(F_x, F_z) of a floator on the axis of a rotating dipole, closed form (Eq. 5.77)."""
    r = np.asarray(r, float)
    d = inertia * np.asarray(omega, float) ** 2 - tau_s
    fx = 3.0 / (r * np.sqrt(r**6 / m_const**2 + 1.0 / d**2))
    fz = 3.0 * m_const**2 / (r**7 * np.sqrt(m_const**2 / r**6 + d**2))
    return fx, fz


def distance_for_cone_angle(phi, c_const):
    """r(phi) = (C tan phi)^(-1/3), C = (I w^2 - tau_S) / M (Eq. 5.78)."""
    return (c_const * np.tan(phi)) ** (-1.0 / 3.0)


def pfr_force_power_law(r, m_const, inertia, omega, tau_s=0.0, a=1.0, b=3.0):
    """F_z ~ M^2 a / ((I w^2 - tau_S) r^(4+b)) (Eq. 5.81); (a, b) from Table 5.5 (b -> 3 far away)."""
    return m_const**2 * a / ((inertia * np.asarray(omega, float) ** 2 - tau_s) * np.asarray(r, float)
                             ** (4.0 + b))


def planar_force_ratio(theta, omega, t):
    """F_z / A = cos(theta(t) - w t) for the phi = pi/2 scheme (Eq. 5.89)."""
    return np.cos(np.asarray(theta, float) - np.asarray(omega, float) * np.asarray(t, float))


def planar_average_force_ratio(j_c, omega):
    """Cycle-averaged F_av / A ~ (1/2) atan(J_C / w^2) in the phi = pi/2 scheme (Eq. 5.92/5.93)."""
    return 0.5 * np.arctan(np.asarray(j_c, float) / np.asarray(omega, float) ** 2)
