"""Floator on the axis of a tilted rotating dipole: the steady (co-rotating) state and its force.

A rotator dipole ``m_R`` spins about z at ``omega`` with tilt ``gamma`` (Eq. 5.25:
m_R (sin wt cos g, -cos wt cos g, sin g)). A free floator (mass, isotropic or axisymmetric
inertia, moment ``m_F`` on its symmetry axis) held at height ``r`` (the axial force is
measured as the constraint, as a balance does) settles into a motion that is stationary in
the frame co-rotating with the rotator: a cone of its axis (Eq. 5.7) plus a lateral circle of
radius beta (Sec. 5.2, Fig. 5.13). Solving for that fixed point directly (no time stepping)
gives the cycle-averaged force exactly, split into the parts from the cyclic and static
components of m_R (Eq. 5.84): the repulsive PFR and the static attraction of Eq. 5.85.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from labkit.model.cone import cone_angle_tilted_dipole
from labkit.model.dipole import K_M, dipole_field, dipole_force

EZ = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class FloatorSetup:
    """SI parameters of a rotator / floator pair (Table 5.6 style)."""

    m_rotator: float      # A m^2
    m_floator: float      # A m^2
    mass: float           # kg
    i_radial: float       # kg m^2
    i_axial: float        # kg m^2
    omega: float          # rad/s
    gamma: float          # rad, rotator tilt from the rotation plane
    spin_k: float = -1.0  # spin parameter of Eq. 5.62 (-1: no spin, Eq. 5.12)


@dataclass(frozen=True)
class FloatorState:
    """Co-rotating steady state at height ``r``: cone angle, lateral offset beta (m) and the
    axial force (N) split into the cyclic (repulsive PFR) and static (attractive) parts."""

    r: float
    phi: float
    beta: float
    force_cyclic_z: float
    force_static_z: float
    residual: float
    x: np.ndarray

    @property
    def force_z(self) -> float:
        return self.force_cyclic_z + self.force_static_z


def _moments(setup: FloatorSetup) -> tuple[np.ndarray, np.ndarray]:
    c, s = np.cos(setup.gamma), np.sin(setup.gamma)
    return setup.m_rotator * np.array([0.0, -c, 0.0]), setup.m_rotator * np.array([0.0, 0.0, s])


def _unpack(x: np.ndarray, r: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return x[:3], x[3:6], np.array([x[6] * r, x[7] * r, r])


def _residual(x: np.ndarray, setup: FloatorSetup, r: float) -> np.ndarray:
    psi, ell, pos = _unpack(x, r)
    m_c, m_s = _moments(setup)
    m_r = m_c + m_s
    w = setup.omega
    a1 = setup.i_radial / setup.i_axial - 1.0
    omega_b = ell + a1 * np.dot(ell, psi) * psi
    torque = setup.m_floator * np.cross(psi, dipole_field(m_r, pos)) / (setup.i_radial * w**2)
    force = dipole_force(m_r, setup.m_floator * psi, pos)
    scale = 3 * K_M * setup.m_rotator * setup.m_floator / r**4
    centripetal = setup.mass * w**2 * pos
    # Eq. 5.62: the body's angular velocity is w (e_z + k psi); this also fixes its spin
    return np.concatenate([omega_b - EZ - setup.spin_k * psi, torque - np.cross(EZ, ell),
                           (force[:2] + centripetal[:2]) / scale, [np.dot(psi, psi) - 1.0]])


def _guess(setup: FloatorSetup, r: float) -> np.ndarray:
    tau = K_M * setup.m_rotator * setup.m_floator / r**3
    phi = float(cone_angle_tilted_dipole(tau, setup.gamma, setup.i_radial, setup.omega))
    if setup.spin_k != -1.0:
        phi = -phi
    s, c = np.sin(phi), np.cos(phi)
    psi = np.array([0.0, -s, c])
    omega_b = EZ + setup.spin_k * psi
    ell = omega_b + (setup.i_axial / setup.i_radial - 1.0) * np.dot(omega_b, psi) * psi
    return np.concatenate([psi, ell, [0.0, 0.0]])


def steady_state(setup: FloatorSetup, r: float, x0: np.ndarray | None = None) -> FloatorState:
    """Solve the co-rotating fixed point at height ``r`` (m); ``x0`` continues a previous one."""
    x0 = _guess(setup, r) if x0 is None else x0
    fit = least_squares(_residual, x0, args=(setup, r), method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15)
    psi, _, pos = _unpack(fit.x, r)
    psi = psi / np.linalg.norm(psi)
    m_c, m_s = _moments(setup)
    f_c = dipole_force(m_c, setup.m_floator * psi, pos)
    f_s = dipole_force(m_s, setup.m_floator * psi, pos)
    return FloatorState(r, float(np.arccos(np.clip(psi[2], -1, 1))), float(np.hypot(pos[0], pos[1])),
                        float(f_c[2]), float(f_s[2]), float(np.linalg.norm(fit.fun)), fit.x)


def force_profile(setup: FloatorSetup, radii: np.ndarray) -> list[FloatorState]:
    """Steady states along ``radii`` (continued from the largest distance inwards)."""
    states: dict[float, FloatorState] = {}
    x0 = None
    for r in sorted(radii, reverse=True):
        st = steady_state(setup, float(r), x0)
        x0 = st.x
        states[float(r)] = st
    return [states[float(r)] for r in radii]


def power_law_exponent(r: np.ndarray, force: np.ndarray) -> tuple[float, float]:
    """Fit |F| = k r^-n by least squares in log-log; returns (k, n)."""
    slope, intercept = np.polyfit(np.log(r), np.log(np.abs(force)), 1)
    return float(np.exp(intercept)), float(-slope)


def lab_initial_state(setup: FloatorSetup, state: FloatorState) -> dict[str, np.ndarray]:
    """The steady state as lab-frame initial conditions at t = 0 (rotator phase 0, Eq. 5.25).

    Returns ``position`` (m), ``velocity`` (m/s, the co-rotating circle: omega e_z x position),
    ``dipole_axis`` (unit psi) and ``angular_velocity`` (rad/s, lab frame; Eq. 5.62 with the
    setup's spin k). Point-inverting all of it (position and velocity negated, psi and the
    angular velocity kept) gives the same motion beneath the rotator: a point dipole's field is
    even in the displacement.
    """
    psi, ell, pos = _unpack(state.x, state.r)
    psi = psi / np.linalg.norm(psi)
    a1 = setup.i_radial / setup.i_axial - 1.0
    omega_b = ell + a1 * np.dot(ell, psi) * psi
    return {"position": pos, "velocity": setup.omega * np.cross(EZ, pos), "dipole_axis": psi,
            "angular_velocity": setup.omega * omega_b}
