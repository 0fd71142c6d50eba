"""Tilted conical orbits (paper Fig. 5.4, 5.6, Table 5.1): below the static field of Eq. 5.46
the cone axis settles at an angle lambda from z. Found by shooting for the drive-periodic
orbit of the rigid isotropic/axisymmetric body of :mod:`labkit.model.conical_dynamics`.

In the co-rotating frame the orbit is periodic with the drive period (2 pi in ``s = w t``).
The spin ``ell . psi`` is conserved, so orbits form a family labelled by it; we fix it to the
spin of the paper's own initial conditions, ``cos(R) - 1`` with ``R`` the cone half-angle
(Eq. 5.12 about the tilted axis; Fig. 5.4: v_z = -4.891 rad/s = w (cos R - 1), R = 0.228).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

from labkit.model.conical_dynamics import RotatingFieldBody, equilibrium, rhs_unrolled


@dataclass(frozen=True)
class TiltedOrbit:
    """A drive-periodic orbit: initial state ``y0`` (nondimensional), mean zenith angle ``lam``,
    semi-axes of the zenith/azimuth oscillation and the periodicity residual."""

    y0: np.ndarray
    lam: float
    r_x: float
    r_y: float
    residual: float


def one_drive_period(body: RotatingFieldBody, y0: np.ndarray, n: int = 0):
    """The flow of :func:`labkit.model.conical_dynamics.rhs_unrolled` over one drive period
    from ``y0`` (``n`` samples, or only the end state)."""
    t_eval = None if n == 0 else np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    return solve_ivp(rhs_unrolled, (0.0, 2 * np.pi), y0, method="DOP853", rtol=1e-11, atol=1e-13,
                     t_eval=t_eval, args=(body.j_c, body.j_s, body.inertia_ratio - 1.0))


def state_from_coords(x: np.ndarray, spin: float) -> np.ndarray:
    """The state (psi, ell) from (zenith, azimuth, l1, l2) and the spin along psi."""
    zen, az, l1, l2 = x
    psi = np.array([np.sin(zen) * np.cos(az), np.sin(zen) * np.sin(az), np.cos(zen)])
    e1 = np.array([np.cos(zen) * np.cos(az), np.cos(zen) * np.sin(az), -np.sin(zen)])
    e2 = np.cross(psi, e1)
    return np.concatenate([psi, spin * psi + l1 * e1 + l2 * e2])


def coords_from_state(y: np.ndarray) -> np.ndarray:
    """(zenith, azimuth, l1, l2) of a state (psi, ell): :func:`state_from_coords` inverted."""
    psi, ell = y[:3] / np.linalg.norm(y[:3]), y[3:]
    zen = np.arccos(np.clip(psi[2], -1, 1))
    az = np.arctan2(psi[1], psi[0])
    e1 = np.array([np.cos(zen) * np.cos(az), np.cos(zen) * np.sin(az), -np.sin(zen)])
    e2 = np.cross(psi, e1)
    return np.array([zen, az, ell @ e1, ell @ e2])


def describe(body: RotatingFieldBody, y0: np.ndarray) -> TiltedOrbit:
    """lambda = cycle mean of the dipole's zenith angle (the a_0 of Table 5.1)."""
    sol = one_drive_period(body, y0, 2048)
    psi = sol.y[:3]
    zen = np.arccos(np.clip(psi[2] / np.linalg.norm(psi, axis=0), -1, 1))
    lam = float(np.mean(zen))
    r_x = 0.5 * float(zen.max() - zen.min())
    end = one_drive_period(body, y0).y[:, -1]
    # azimuthal half-width of the dipole path about the tilted axis, seen in the lab frame
    s = sol.t
    lab = np.stack([np.cos(s) * psi[0] - np.sin(s) * psi[1], np.sin(s) * psi[0] + np.cos(s) * psi[1], psi[2]])
    axis = lab.mean(axis=1)
    axis /= np.linalg.norm(axis)
    e_perp = np.cross(axis, [0.0, 0.0, 1.0]) if abs(axis[2]) < 1 - 1e-12 else np.array([1.0, 0, 0])
    e_perp /= np.linalg.norm(e_perp)
    r_y = float(np.max(np.abs(np.arcsin(np.clip(e_perp @ lab, -1, 1)))))
    return TiltedOrbit(y0, lam, r_x, r_y, float(np.linalg.norm(end - y0)))


def shoot(body: RotatingFieldBody, spin: float, y_guess: np.ndarray) -> TiltedOrbit:
    """Least-squares shooting for ``y0`` with ``flow_2pi(y0) = y0`` at fixed spin."""
    def residual(x: np.ndarray) -> np.ndarray:
        y0 = state_from_coords(x, spin)
        return one_drive_period(body, y0).y[:, -1] - y0

    fit = least_squares(residual, coords_from_state(y_guess), method="lm", xtol=1e-14, ftol=1e-14, gtol=1e-14)
    return describe(body, state_from_coords(fit.x, spin))


def tilted_guess(body: RotatingFieldBody, lam: float, half_angle: float) -> np.ndarray:
    """Starting state: the on-axis cone of half-angle ``half_angle`` tilted by ``lam`` about x."""
    y = equilibrium(half_angle, body.inertia_ratio)
    c, s = np.cos(lam), np.sin(lam)
    rot = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    return np.concatenate([rot @ y[:3], rot @ y[3:]])


def self_consistent_spin(body: RotatingFieldBody, y0: np.ndarray) -> float:
    """Spin of a spin-free (k = -1) cone about the orbit's own mean axis: <cos(phi')> - 1, with
    phi' the angle between the dipole and that axis (Eq. 5.12 applied about the tilted axis)."""
    sol = one_drive_period(body, y0, 1024)
    s = sol.t
    psi = sol.y[:3] / np.linalg.norm(sol.y[:3], axis=0)
    lab = np.stack([np.cos(s) * psi[0] - np.sin(s) * psi[1], np.sin(s) * psi[0] + np.cos(s) * psi[1], psi[2]])
    axis = lab.mean(axis=1)
    axis /= np.linalg.norm(axis)
    return float(np.mean(axis @ lab) - 1.0)


def spin_free_orbit(body: RotatingFieldBody, y_guess: np.ndarray, spin: float = 0.0,
                    iterations: int = 6) -> tuple[TiltedOrbit, float]:
    """Tilted orbit whose conserved spin equals :func:`self_consistent_spin` (fixed-point iteration)."""
    orbit = shoot(body, spin, y_guess)
    for _ in range(iterations):
        new = self_consistent_spin(body, orbit.y0)
        if abs(new - spin) < 1e-7:
            break
        spin = new
        orbit = shoot(body, spin, orbit.y0)
    return orbit, spin
