"""The no-net-spin drive-periodic orbit of the tilted cone (paper Fig. 5.6, Eq. 5.7).

:mod:`labkit.model.tilted_cone` finds orbits that return in the co-rotating frame after one
drive period T: the dipole axis and the angular momentum come back, but the body may have
turned about its own axis (the orbits form a family labelled by the conserved spin). The
paper's conical motion (Eq. 5.7, ``R = R_z(wt) R_x(phi) R_z(-wt)``) is the member on which
the whole orientation comes back as well: after T the body has no net rotation about its
dipole axis. Here the spin is a shooting unknown and the extra condition is that the body's
attitude ``Q`` in the co-rotating frame (``Q' = [Omega - e_z]_x Q``; the lab attitude is
``R_z(s) Q`` and ``R_z(2 pi) = 1``) returns to itself: ``Q(2 pi) = Q(0)``.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

from labkit.model.conical_dynamics import RotatingFieldBody, rhs_unrolled
from labkit.model.tilted_cone import TiltedOrbit, coords_from_state, describe, state_from_coords


def _rhs_attitude(s: float, y: np.ndarray, j_c: float, j_s: float, a1: float) -> np.ndarray:
    """:func:`labkit.model.conical_dynamics.rhs_unrolled` plus the attitude ``Q`` (row-major)."""
    px, py, pz, lx, ly, lz = y[:6]
    spin = a1 * (lx * px + ly * py + lz * pz)
    wx, wy, wz = lx + spin * px, ly + spin * py, lz + spin * pz - 1.0
    q = y[6:].reshape(3, 3)
    skew = np.array([[0.0, -wz, wy], [wz, 0.0, -wx], [-wy, wx, 0.0]])
    return np.concatenate([rhs_unrolled(s, y[:6], j_c, j_s, a1), (skew @ q).ravel()])


def period_map(body: RotatingFieldBody, y0: np.ndarray) -> tuple[np.ndarray, float]:
    """State after one drive period and the body's net rotation (rad) about its dipole axis."""
    start = np.concatenate([y0, np.eye(3).ravel()])
    sol = solve_ivp(_rhs_attitude, (0.0, 2 * np.pi), start, method="DOP853", rtol=1e-11, atol=1e-13,
                    args=(body.j_c, body.j_s, body.inertia_ratio - 1.0))
    end = sol.y[:, -1]
    q = end[6:].reshape(3, 3)
    psi = y0[:3] / np.linalg.norm(y0[:3])
    vee = 0.5 * np.array([q[2, 1] - q[1, 2], q[0, 2] - q[2, 0], q[1, 0] - q[0, 1]])
    twist = float(np.arctan2(psi @ vee, 0.5 * (np.trace(q) - 1.0)))
    return end[:6], twist


def no_spin_orbit(body: RotatingFieldBody, y_guess: np.ndarray, spin: float) -> tuple[TiltedOrbit, float]:
    """The drive-periodic orbit with no net rotation about the dipole axis: shooting for the
    state and the conserved spin together; returns the orbit and its spin (units of w)."""
    def residual(x: np.ndarray) -> np.ndarray:
        y0 = state_from_coords(x[:4], x[4])
        end, twist = period_map(body, y0)
        return np.concatenate([end - y0, [twist]])

    x0 = np.concatenate([coords_from_state(y_guess), [spin]])
    fit = least_squares(residual, x0, method="lm", xtol=1e-14, ftol=1e-14, gtol=1e-14)
    return describe(body, state_from_coords(fit.x[:4], fit.x[4])), float(fit.x[4])


def tilt_angles(body: RotatingFieldBody, y0: np.ndarray, samples: int = 2048) -> tuple[float, float]:
    """Fig. 5.6's lambda and R_X: centre and half-range of the dipole's *signed* angle from z
    in the tilt plane (the plane of z and the orbit's mean axis; Fig. 5.4: "rotation lambda
    aligned with axis-x", i.e. the rotation about the horizontal axis normal to that plane).

    The zenith angle is not signed: once the path comes within R_X of the pole (lambda < R_X,
    Fig. 5.6 row 3: 0.2666 < 0.275) its range folds at 0 and its centre and half-range swap
    lambda and R_X. Elsewhere both definitions agree.
    """
    from labkit.model.tilted_cone import one_drive_period
    sol = one_drive_period(body, y0, samples)
    s = sol.t
    psi = sol.y[:3] / np.linalg.norm(sol.y[:3], axis=0)
    lab = np.stack([np.cos(s) * psi[0] - np.sin(s) * psi[1], np.sin(s) * psi[0] + np.cos(s) * psi[1], psi[2]])
    axis = lab.mean(axis=1)
    azimuth = np.arctan2(axis[1], axis[0])
    signed = np.arctan2(np.cos(azimuth) * lab[0] + np.sin(azimuth) * lab[1], lab[2])
    return 0.5 * float(signed.max() + signed.min()), 0.5 * float(signed.max() - signed.min())
