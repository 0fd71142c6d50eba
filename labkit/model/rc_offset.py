"""Offset of the rotation centre (RC) from the centre of mass (paper Sec. 5.2.3, Eq. 5.97-5.102).

A body in a rotating force F and torque T oscillates laterally by beta and angularly by phi;
the apparent pivot sits delta from the CM along z.
"""

from __future__ import annotations

import numpy as np


def offset_from_amplitudes(beta, phi):
    """delta = beta / tan(phi) (Eq. 5.97)."""
    return np.asarray(beta, float) / np.tan(phi)


def lateral_amplitude(force, mass, omega):
    """beta = F / (m w^2) for a driven motion without stiffness (Eq. 5.98/5.99)."""
    return force / (mass * np.asarray(omega, float) ** 2)


def angular_amplitude(torque, inertia, omega):
    """phi = T / (I w^2) for a driven motion without stiffness (Eq. 5.99)."""
    return torque / (inertia * np.asarray(omega, float) ** 2)


def offset_from_loads(force, torque, inertia, mass):
    """delta ~ (F / T) (I / m), small angles (Eq. 5.100)."""
    return force / torque * inertia / mass


def force_torque_ratio(pole_distance, k):
    """F / T = (2 / h) (k + 1) / (k - 1), k = F_1 / F_2 the lateral pole forces (Eq. 5.101)."""
    return 2.0 / pole_distance * (k + 1.0) / (k - 1.0)


def shape_length(inertia, pole_distance, mass):
    """W = 2 I / (h m) (Eq. 5.102): h/6 for a thin rod, h/3 for a cube, 7h/24 for a cylinder d = h."""
    return 2.0 * inertia / (pole_distance * mass)


def offset_pole_model(k, inertia, pole_distance, mass):
    """delta ~ (k + 1)/(k - 1) W (Eq. 5.102); |delta| < W for antiparallel pole forces (k < 0)."""
    return (k + 1.0) / (k - 1.0) * shape_length(inertia, pole_distance, mass)
