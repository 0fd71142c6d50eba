"""Point-dipole field, force and torque (paper Sec. 4, Eq. 4.1-4.5), vectorised over leading axes.

Every function takes vectors as arrays of shape ``(..., 3)`` in SI units (A m^2, m) and
broadcasts over the leading axes, so a whole trajectory is evaluated in one call.
The displacement ``r`` always points from the source dipole ``a`` to the dipole ``b`` that
receives the field, force or torque (the paper's convention below Eq. 4.3).
"""

from __future__ import annotations

import numpy as np

MU0 = 4e-7 * np.pi  # T m / A, the paper's value of the vacuum permeability (below Eq. 4.3)
K_M = MU0 / (4.0 * np.pi)  # mu0 / 4 pi


def _norm_and_unit(r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r = np.asarray(r, dtype=float)
    dist = np.linalg.norm(r, axis=-1, keepdims=True)
    return dist, r / dist


def dipole_field(m: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Field B (T) of a point dipole ``m`` at displacement ``r`` from it (Eq. 4.1)."""
    m = np.asarray(m, dtype=float)
    dist, rhat = _norm_and_unit(r)
    m_dot_r = np.sum(m * rhat, axis=-1, keepdims=True)
    return K_M / dist**3 * (3.0 * m_dot_r * rhat - m)


def dipole_force(m_a: np.ndarray, m_b: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Force (N) on dipole ``m_b`` from dipole ``m_a``; ``r`` goes from a to b (Eq. 4.2).

    Written in the paper's form with moment magnitudes and unit vectors; zero moments give
    zero force.
    """
    m_a = np.asarray(m_a, dtype=float)
    m_b = np.asarray(m_b, dtype=float)
    dist, rhat = _norm_and_unit(r)
    ab = np.sum(m_a * m_b, axis=-1, keepdims=True)
    ra = np.sum(rhat * m_a, axis=-1, keepdims=True)
    rb = np.sum(rhat * m_b, axis=-1, keepdims=True)
    # 3 mu0/(4 pi r^4) [r (ma.mb) + ma (r.mb) + mb (r.ma) - 5 r (r.ma)(r.mb)], magnitudes folded in
    return 3.0 * K_M / dist**4 * (rhat * ab + m_a * rb + m_b * ra - 5.0 * rhat * ra * rb)


def dipole_torque(m_a: np.ndarray, m_b: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Torque (N m) on dipole ``m_b`` from dipole ``m_a``; ``r`` goes from a to b (Eq. 4.3).

    This is the torque about ``m_b``'s own centre; it equals ``m_b x B_a(r)`` (Eq. 4.4).
    """
    m_a = np.asarray(m_a, dtype=float)
    m_b = np.asarray(m_b, dtype=float)
    dist, rhat = _norm_and_unit(r)
    ra = np.sum(rhat * m_a, axis=-1, keepdims=True)
    return K_M / dist**3 * (3.0 * ra * np.cross(m_b, rhat) + np.cross(m_a, m_b))


def torque_in_field(m: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Torque (N m) on moment ``m`` in field ``b``: tau = m x B (Eq. 4.4)."""
    return np.cross(np.asarray(m, dtype=float), np.asarray(b, dtype=float))


def torque_magnitude(m: float, b: float, angle: float) -> float:
    """Scalar torque m B sin(phi), phi the angle between m and B (Eq. 4.5)."""
    return m * b * np.sin(angle)


def potential_energy(m_a: np.ndarray, m_b: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Interaction energy (J) U = -m_b . B_a(r); the force of Eq. 4.2 is -grad_r U."""
    return -np.sum(np.asarray(m_b, dtype=float) * dipole_field(m_a, r), axis=-1)
