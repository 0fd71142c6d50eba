"""Conical motion of a dipole body in a rotating field (paper Sec. 5.1, Eq. 5.5-5.35, 5.62-5.68).

The field is ``B = B_C (-sin wt, cos wt, 0) + B_S (0, 0, 1)`` (Eq. 5.21); the body's dipole
draws a cone of half-angle ``phi`` about z in phase opposition with the field (phase lag).
``tau_c = m B_C`` and ``tau_s = m B_S`` are the cyclic and static torque coefficients (N m),
inertias in kg m^2, ``omega`` in rad/s, angles in rad. ``k`` is the spin parameter of
Eq. 5.62 (rho = k omega t); ``k = -1`` is the spin-free motion of Eq. 5.7.

Convention: the rotation matrix is the ZXZ product of Eq. 5.6. The ``R_rho`` printed in Eq. 5.5
has its sines transposed; Eq. 5.6 and 5.7 (used here) are consistent with the standard
rotation ``R_z(rho)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def _rz(angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    z, o = np.zeros_like(c), np.ones_like(c)
    return np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2)


def _rx(angle: np.ndarray) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    z, o = np.zeros_like(c), np.ones_like(c)
    return np.stack([np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)], -2)


def euler_zxz(theta, phi, rho) -> np.ndarray:
    """Rotation matrix R_E = R_theta R_phi R_rho (Eq. 5.6), shape ``(..., 3, 3)``."""
    theta, phi, rho = np.broadcast_arrays(*(np.asarray(a, dtype=float) for a in (theta, phi, rho)))
    return _rz(theta) @ _rx(phi) @ _rz(rho)


def conical_rotation(phi, omega, t, k: float = -1.0) -> np.ndarray:
    """Orientation of the conical motion R_k = R_E(omega t, phi, k omega t) (Eq. 5.7 for k = -1)."""
    wt = np.asarray(omega, dtype=float) * np.asarray(t, dtype=float)
    return euler_zxz(wt, phi, k * wt)


def conical_axis(phi, omega, t) -> np.ndarray:
    """Unit dipole direction psi(t) = (sin wt sin phi, -cos wt sin phi, cos phi) (Eq. 5.20)."""
    wt = np.asarray(omega, dtype=float) * np.asarray(t, dtype=float)
    phi = np.asarray(phi, dtype=float)
    return np.stack(np.broadcast_arrays(np.sin(wt) * np.sin(phi), -np.cos(wt) * np.sin(phi),
                                        np.cos(phi)), -1)


def conical_angular_velocity(phi, omega, t=0.0, k: float = -1.0) -> np.ndarray:
    """Lab-frame angular velocity (rad/s) of the conical motion (Eq. 5.62; Eq. 5.12 for k = -1)."""
    omega = np.asarray(omega, dtype=float)
    wt = omega * np.asarray(t, dtype=float)
    phi = np.asarray(phi, dtype=float)
    return np.stack(np.broadcast_arrays(omega * k * np.sin(wt) * np.sin(phi),
                                        -omega * k * np.cos(wt) * np.sin(phi),
                                        omega * (1.0 + k * np.cos(phi))), -1)


def rotating_field(b_c, b_s, omega, t) -> np.ndarray:
    """Uniform rotating field B_C (-sin wt, cos wt, 0) + B_S (0, 0, 1) in T (Eq. 5.21)."""
    wt = np.asarray(omega, dtype=float) * np.asarray(t, dtype=float)
    b_c = np.asarray(b_c, dtype=float)
    return np.stack(np.broadcast_arrays(-b_c * np.sin(wt), b_c * np.cos(wt), np.asarray(b_s, float)
                                        + 0.0 * wt), -1)


def cone_angle(tau_c, tau_s, inertia, omega):
    """Equilibrium cone angle of an isotropic body: phi = atan(tau_C / (I w^2 - tau_S)) (Eq. 5.24).

    Negative when ``tau_s > I omega^2`` (natural frequency above the drive: no phase lag,
    the PFR force turns attractive).
    """
    with np.errstate(divide="ignore"):
        return np.arctan(np.asarray(tau_c, float) / (np.asarray(inertia, float) * np.asarray(omega, float)
                                                        ** 2 - np.asarray(tau_s, float)))


def cone_angle_tilted_dipole(tau, gamma, inertia, omega):
    """Cone angle under a rotating dipole tilted by ``gamma`` from the xy plane (Eq. 5.30).

    ``tau = mu0 m_R m_F / (4 pi r^3)``; then tau_C = tau cos(gamma), tau_S = 2 tau sin(gamma)
    (Eq. 5.28-5.29).
    """
    with np.errstate(divide="ignore"):
        return np.arctan(tau * np.cos(gamma) / (inertia * np.asarray(omega, float) ** 2
                                                 - 2.0 * tau * np.sin(gamma)))


def static_to_cyclic_ratio(gamma):
    """tau_S / tau_C = 2 tan(gamma) for a tilted rotating dipole on its axis (Eq. 5.29)."""
    return 2.0 * np.tan(gamma)


def cone_equation_residual(phi, tau_c, tau_s, i_axial, i_radial, omega, k: float = -1.0):
    """Magnetic minus inertial torque of the conical motion of an axisymmetric body (N m).

    Zero at equilibrium: tau_C cos phi + tau_S sin phi = w^2 sin phi (-k I_A + (I_R - I_A) cos phi)
    (Eq. 5.64; Eq. 5.35 for k = -1).
    """
    s, c = np.sin(phi), np.cos(phi)
    w2 = np.asarray(omega, float) ** 2
    return tau_c * c + tau_s * s - w2 * s * (-k * i_axial + (i_radial - i_axial) * c)


def cone_angles_axisymmetric(*, tau_c, tau_s, i_axial, i_radial, omega, k: float = -1.0):
    """Equilibrium cone angle(s) of an axisymmetric body, root of Eq. 5.35 (Eq. 5.64 with spin ``k``).

    Keyword-only: :func:`labkit.sim.equilibrium.cone_angle_axisymmetric` (a scalar root for
    the simulator) takes the same quantities in another order, so a positional call here is
    refused rather than silently swapped (docs/decisions/0007-names.md).

    Vectorised Newton iteration started from the isotropic closed form (Eq. 5.24 / 5.68 with
    the inertia the equation has at phi -> 0). Returns NaN where it does not converge.
    """
    tau_c, tau_s, i_axial, i_radial, omega, k = np.broadcast_arrays(
        *(np.asarray(a, dtype=float) for a in (tau_c, tau_s, i_axial, i_radial, omega, k)))
    i_eff = -k * i_axial + i_radial - i_axial
    with np.errstate(divide="ignore"):
        phi = np.arctan(tau_c / (i_eff * omega**2 - tau_s))
    for _ in range(60):
        f = cone_equation_residual(phi, tau_c, tau_s, i_axial, i_radial, omega, k)
        s, c = np.sin(phi), np.cos(phi)
        df = (-tau_c * s + tau_s * c
              - omega**2 * (c * (-k * i_axial + (i_radial - i_axial) * c) - s * s * (i_radial - i_axial)))
        step = f / df
        phi = phi - step
        if np.all(np.abs(step) < 1e-15):
            break
    res = cone_equation_residual(phi, tau_c, tau_s, i_axial, i_radial, omega, k)
    ok = np.abs(res) <= 1e-9 * (np.abs(tau_c) + np.abs(tau_s))
    phi = np.where(ok, phi, np.nan)
    return phi[()] if phi.ndim == 0 else phi


def cone_angle_spin(tau_c, tau_s, inertia, omega, k):
    """Cone angle of a spinning isotropic body: phi = -atan(tau_C / (k I w^2 + tau_S)) (Eq. 5.68)."""
    with np.errstate(divide="ignore"):
        return -np.arctan(tau_c / (k * inertia * np.asarray(omega, float) ** 2 + tau_s))


def spin_velocity(k, omega):
    """Spin velocity a tachometer reads, v_S = (k + 1) omega (rad/s) (Eq. 5.65)."""
    return (np.asarray(k, float) + 1.0) * omega


def spin_ratio(k):
    """Spin ratio q = v_S / omega = k + 1 (Eq. 5.66)."""
    return np.asarray(k, float) + 1.0


def spin_parameter(v_s, omega):
    """k = v_S / omega - 1 from a measured spin velocity (inverse of Eq. 5.65, as in Eq. 6.37)."""
    return np.asarray(v_s, float) / omega - 1.0


def planar_amplitude(j_c, omega):
    """Amplitude of the planar (phi = pi/2) motion, |theta| ~ atan(J_C / w^2) (Eq. 5.58)."""
    return np.arctan(np.abs(j_c) / np.asarray(omega, float) ** 2)


@dataclass(frozen=True)
class ConicalState:
    """Initial state of the equilibrium conical motion at time ``t`` (lab frame, SI).

    ``rotation`` is the body-to-lab rotation (Eq. 5.6), ``dipole_axis`` the unit moment
    direction (Eq. 5.20), ``angular_velocity`` the lab-frame vector (Eq. 5.12/5.62) and
    ``angular_momentum`` = I_T v with I_T = R I R^T (Eq. 5.15).
    """

    phi: float
    rotation: np.ndarray
    dipole_axis: np.ndarray
    angular_velocity: np.ndarray
    angular_momentum: np.ndarray
    body_angular_velocity: np.ndarray


def conical_initial_state(tau_c: float, tau_s: float, i_axial: float, i_radial: float, omega: float,
                          k: float = -1.0, t: float = 0.0, phi: float | None = None) -> ConicalState:
    """Initial conditions of the paper's equilibrium conical motion (Eq. 5.12/5.24/5.35/5.64).

    The cone angle solves Eq. 5.64 (Eq. 5.35 for ``k = -1``; Eq. 5.24 when ``i_axial ==
    i_radial``) unless ``phi`` is given. The body frame has the dipole along its z axis and
    principal inertias (I_R, I_R, I_A). Field convention of Eq. 5.21.
    """
    if phi is None:
        phi = float(cone_angles_axisymmetric(tau_c=tau_c, tau_s=tau_s, i_axial=i_axial, i_radial=i_radial,
                                             omega=omega, k=k))
    rot = conical_rotation(phi, omega, t, k)
    v = conical_angular_velocity(phi, omega, t, k)
    inertia_body = np.diag([i_radial, i_radial, i_axial])
    i_lab = rot @ inertia_body @ rot.T
    return ConicalState(phi=float(phi), rotation=rot, dipole_axis=rot[:, 2].copy(),
                        angular_velocity=v, angular_momentum=i_lab @ v,
                        body_angular_velocity=rot.T @ v)
