"""Rigid axisymmetric dipole body in a uniform rotating field, in the co-rotating frame.

The body's moment lies on its symmetry axis ``psi``; the field is Eq. 5.21. In the frame
rotating with the field at ``omega`` about z the field is constant, so the equations are
autonomous and the paper's conical motion (Eq. 5.7, cone angle of Eq. 5.35) is a fixed
point. Its linearisation gives the stability verdicts of Table 5.3 (compare Eq. 5.46).

Nondimensional variables: time ``s = omega t``, angular momentum ``ell = L / (I_R omega)``,
torques ``j_c = tau_C / (I_R omega^2)``, ``j_s = tau_S / (I_R omega^2)``, inertia ratio
``a = I_R / I_A``. State ``y = (psi_x, psi_y, psi_z, ell_x, ell_y, ell_z)`` in the rotating
frame, which coincides with the lab frame at t = 0. Euler's equations (Eq. 5.15) for an
axisymmetric body reduce to
``Omega = ell + (a - 1)(ell . psi) psi``, ``psi' = (Omega - e_z) x psi``,
``ell' = psi x (j_c e_y + j_s e_z) - e_z x ell``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from labkit.model.cone import cone_angles_axisymmetric

EZ = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class RotatingFieldBody:
    """Nondimensional parameters: j_c, j_s (torques over I_R w^2) and a = I_R / I_A."""

    j_c: float
    j_s: float
    inertia_ratio: float = 1.0

    @classmethod
    def from_si(cls, tau_c: float, tau_s: float, i_axial: float, i_radial: float,
                omega: float) -> RotatingFieldBody:
        scale = i_radial * omega**2
        return cls(tau_c / scale, tau_s / scale, i_radial / i_axial)


def rhs(y: np.ndarray, body: RotatingFieldBody) -> np.ndarray:
    """d y / d s in the co-rotating frame (see module docstring); vectorised over y[..., 6]."""
    y = np.asarray(y, dtype=float)
    psi, ell = y[..., :3], y[..., 3:]
    spin = np.sum(ell * psi, axis=-1, keepdims=True)
    omega_b = ell + (body.inertia_ratio - 1.0) * spin * psi
    dpsi = np.cross(omega_b - EZ, psi)
    field = np.array([0.0, body.j_c, body.j_s])
    dell = np.cross(psi, np.broadcast_to(field, psi.shape)) - np.cross(np.broadcast_to(EZ, ell.shape), ell)
    return np.concatenate([dpsi, dell], axis=-1)


def equilibrium(phi: float, inertia_ratio: float = 1.0) -> np.ndarray:
    """Fixed point of the conical motion with cone angle ``phi`` (Eq. 5.12, 5.20 at t = 0)."""
    s, c = np.sin(phi), np.cos(phi)
    psi = np.array([0.0, -s, c])
    omega_b = np.array([0.0, s, 1.0 - c])
    ell = omega_b + (1.0 / inertia_ratio - 1.0) * np.dot(omega_b, psi) * psi
    return np.concatenate([psi, ell])


def equilibrium_phi(body: RotatingFieldBody) -> float:
    """Cone angle of ``body`` from Eq. 5.35 (nondimensional: I_R = omega = 1)."""
    return float(cone_angles_axisymmetric(tau_c=body.j_c, tau_s=body.j_s, i_axial=1.0 / body.inertia_ratio,
                                          i_radial=1.0, omega=1.0))


def jacobian(y: np.ndarray, body: RotatingFieldBody, h: float = 1e-6) -> np.ndarray:
    """Central-difference Jacobian of :func:`rhs` at ``y`` (6 x 6)."""
    jac = np.empty((6, 6))
    for i in range(6):
        dy = np.zeros(6)
        dy[i] = h
        jac[:, i] = (rhs(y + dy, body) - rhs(y - dy, body)) / (2 * h)
    return jac


def growth_rate(body: RotatingFieldBody, phi: float | None = None) -> float:
    """Largest real part of the linearised co-rotating-frame dynamics, in units of omega.

    The system is Hamiltonian, so a stable cone has all eigenvalues on the imaginary axis
    (two are zero: |psi| and the spin are conserved); a positive value is the e-folding rate
    of the growing mode per radian of drive (multiply by omega for 1/s).
    """
    if phi is None:
        phi = equilibrium_phi(body)
    eig = np.linalg.eigvals(jacobian(equilibrium(phi, body.inertia_ratio), body))
    return float(np.max(eig.real))


@dataclass(frozen=True)
class TimeDomainResult:
    """Deviation of the dipole axis from the equilibrium cone over a run (rad)."""

    times: np.ndarray
    deviation: np.ndarray
    max_deviation: float
    spin_drift: float


def rhs_unrolled(s: float, y: np.ndarray, j_c: float, j_s: float, a1: float) -> list[float]:
    """Unrolled :func:`rhs` for the integrator (same equations, ~10x fewer numpy calls)."""
    px, py, pz, lx, ly, lz = y
    spin = a1 * (lx * px + ly * py + lz * pz)
    wx, wy, wz = lx + spin * px, ly + spin * py, lz + spin * pz - 1.0
    return [wy * pz - wz * py, wz * px - wx * pz, wx * py - wy * px,
            py * j_s - pz * j_c + ly, -px * j_s - lx, px * j_c]


def run(body: RotatingFieldBody, y0: np.ndarray, s_end: float, phi_eq: float,
        samples: int = 2000, rtol: float = 1e-10) -> TimeDomainResult:
    """Integrate from ``y0`` over ``s_end`` radians of drive (DOP853) and track the axis deviation.

    The deviation is the angle between psi and its equilibrium direction in the co-rotating
    frame; ``spin_drift`` is the change of the conserved ell . psi (an accuracy check).
    """
    s_eval = np.linspace(0.0, s_end, samples)
    sol = solve_ivp(rhs_unrolled, (0.0, s_end), y0, method="DOP853", rtol=rtol, atol=rtol * 1e-2,
                    t_eval=s_eval, args=(body.j_c, body.j_s, body.inertia_ratio - 1.0))
    psi = sol.y[:3].T
    psi_eq = equilibrium(phi_eq, body.inertia_ratio)[:3]
    cosang = np.clip(psi @ psi_eq / np.linalg.norm(psi, axis=1), -1.0, 1.0)
    dev = np.arccos(cosang)
    spin = np.sum(sol.y[:3] * sol.y[3:], axis=0)
    return TimeDomainResult(sol.t, dev, float(np.max(dev)), float(np.max(np.abs(spin - spin[0]))))


def paper_initial_state(phi0: float, bias_y: float, omega: float, inertia_ratio: float) -> np.ndarray:
    """Table 5.3 initial state: psi at cone angle phi0, angular velocity of Eq. 5.12 at t = 0
    (with phi0) plus the bias ``bias_y`` (rad/s) on the lab y axis; nondimensional."""
    s, c = np.sin(phi0), np.cos(phi0)
    psi = np.array([0.0, -s, c])
    omega_b = np.array([0.0, s + bias_y / omega, 1.0 - c])
    ell = omega_b + (1.0 / inertia_ratio - 1.0) * np.dot(omega_b, psi) * psi
    return np.concatenate([psi, ell])
