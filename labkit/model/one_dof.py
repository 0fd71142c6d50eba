"""The one-DoF reduction phi'' = -J_S sin phi - J_C cos(w t) cos phi (paper Sec. 5.1.2, Eq. 5.484).

The periodic solution is even in t and has only odd harmonics (phi(t + T/2) = -phi(t)), so
it is fixed by phi'(0) = 0 and phi(T/4) = 0: one scalar root on phi(0).
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq


def one_dof_rhs(t: float, y: np.ndarray, j_c: float, j_s: float, omega: float) -> list[float]:
    """Eq. 5.484 as a first-order system y = (phi, phi')."""
    return [y[1], -j_s * np.sin(y[0]) - j_c * np.cos(omega * t) * np.cos(y[0])]


def periodic_amplitude0(j_c: float, j_s: float, omega: float) -> float:
    """phi(0) of the T-periodic, phase-lag solution of Eq. 5.484 (shooting)."""
    quarter = 0.5 * np.pi / omega

    def miss(phi0: float) -> float:
        sol = solve_ivp(one_dof_rhs, (0.0, quarter), [phi0, 0.0], method="DOP853", rtol=1e-12,
                        atol=1e-14, args=(j_c, j_s, omega))
        return sol.y[0, -1]

    lin = j_c / (omega**2 - j_s)  # linear phase-lag amplitude (Eq. 5.491 with its sign fixed)
    return brentq(miss, 0.5 * lin, min(1.5 * lin, 1.5), xtol=1e-14, rtol=1e-14)


def cosine_coefficients(j_c: float, j_s: float, omega: float, harmonics: int = 3,
                        n: int = 4096) -> np.ndarray:
    """a_i of phi(t) = sum a_i cos(i w t) for the periodic solution (Eq. 5.485), i = 1..harmonics."""
    phi0 = periodic_amplitude0(j_c, j_s, omega)
    period = 2.0 * np.pi / omega
    t = np.arange(n) * period / n
    sol = solve_ivp(one_dof_rhs, (0.0, period), [phi0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14,
                    args=(j_c, j_s, omega), t_eval=t)
    return np.array([2.0 * np.mean(sol.y[0] * np.cos(i * omega * t)) for i in range(1, harmonics + 1)])
