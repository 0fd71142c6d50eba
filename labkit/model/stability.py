"""Heuristic stability criterion of the conical motion about z (paper Sec. 5.1.1, Eq. 5.36-5.46).

For an isotropic body (or an axisymmetric one using its radial inertia I_R), the cone axis
stays on z when tau_S > I w^2 - sqrt((I w^2)^2 - tau_C^2) (Eq. 5.46). ``J_C = tau_C / I`` and
``J_S = tau_S / I`` (1/s^2).
"""

from __future__ import annotations

import numpy as np


def min_static_torque(tau_c, inertia, omega):
    """Smallest static torque coefficient (N m) keeping the cone on z (Eq. 5.46, minus root).

    NaN when tau_C > I w^2 (the criterion has no real root).
    """
    iw2 = np.asarray(inertia, float) * np.asarray(omega, float) ** 2
    with np.errstate(invalid="ignore"):
        return iw2 - np.sqrt(iw2**2 - np.asarray(tau_c, float) ** 2)


def min_static_ratio(tau_c, inertia, omega):
    """Minimum tau_S / tau_C of Eq. 5.46 (the "Min tau_S/tau_C" column of Table 5.3)."""
    return min_static_torque(tau_c, inertia, omega) / tau_c


def criterion_holds(tau_c, tau_s, inertia, omega):
    """True where J_C^2 + J_S^2 - 2 w^2 J_S < 0 (Eq. 5.44), i.e. the heuristic predicts stability."""
    j_c = np.asarray(tau_c, float) / inertia
    j_s = np.asarray(tau_s, float) / inertia
    return j_c**2 + j_s**2 - 2.0 * np.asarray(omega, float) ** 2 * j_s < 0


def equilibrium_function(phi, j_c, j_s, omega):
    """F(phi) = sin phi (w^2 - J_S) - cos phi J_C (Eq. 5.36); zero at the cone angle."""
    return np.sin(phi) * (np.asarray(omega, float) ** 2 - j_s) - np.cos(phi) * j_c


def stability_term(phi, j_c, j_s, omega):
    """C(phi) = w^2 - F'(phi) of Fig. 5.2 (Eq. 5.39/5.41); positive everywhere when stable."""
    w2 = np.asarray(omega, float) ** 2
    return w2 - (np.cos(phi) * (w2 - j_s) + np.sin(phi) * j_c)
