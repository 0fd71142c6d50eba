"""Small pure helpers for rotations (3x3 matrices, body -> lab).

The paper's Euler convention is ZXZ: ``R_E = R_theta R_phi R_rho`` (Eq. 5.6). Eq. 5.5 prints
``R_rho`` as the transpose of a z rotation, but the product printed in Eq. 5.6 and the conical
motion of Eq. 5.7 (``theta = wt``, ``rho = -wt``) both need ``R_rho = rot_z(rho)``; we follow
Eq. 5.6-5.7.
"""

from __future__ import annotations

import math

import numpy as np


def rot_x(angle: float) -> np.ndarray:
    """Rotation about x by ``angle`` (rad): the paper's ``R_phi`` (Eq. 5.5)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_z(angle: float) -> np.ndarray:
    """Rotation about z by ``angle`` (rad): the paper's ``R_theta`` (Eq. 5.5)."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def euler_zxz(theta: float, phi: float, rho: float) -> np.ndarray:
    """The paper's ``R_E = R_theta R_phi R_rho`` (Eq. 5.6) with ``R_rho = rot_z(rho)``."""
    return rot_z(theta) @ rot_x(phi) @ rot_z(rho)


def axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rodrigues' rotation by ``angle`` (rad) about ``axis`` (any non-zero length)."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + math.sin(angle) * k + (1.0 - math.cos(angle)) * (k @ k)


def orthonormality_residual(r: np.ndarray, chunk: int = 65536) -> float:
    """Frobenius norm of ``R^T R - I`` (largest over leading axes): zero for a rotation. Taken
    ``chunk`` matrices at a time, so a long run's check needs no second copy of its samples."""
    flat = np.asarray(r, dtype=float).reshape(-1, 3, 3)
    worst = 0.0
    for start in range(0, len(flat), chunk):
        res = np.einsum("nji,njk->nik", flat[start:start + chunk], flat[start:start + chunk]) - np.eye(3)
        worst = max(worst, float(np.max(np.sqrt(np.sum(res * res, axis=(-2, -1))))))
    return worst


def zenith_angle(vectors: np.ndarray) -> np.ndarray:
    """Angle (rad) between each vector (..., 3) and the lab z axis."""
    v = np.asarray(vectors, dtype=float)
    n = np.linalg.norm(v, axis=-1)
    return np.arccos(np.clip(v[..., 2] / n, -1.0, 1.0))
