"""The planar (phi = pi/2) motion theta'' = J_C sin(theta - w t) (paper Sec. 5.1.5, Eq. 5.56-5.61).

Periodic orbits are found by shooting: any solution with theta(0) = 0 is odd in t, and one
that also has theta(T/2) = 0 is odd about T/2 and hence T-periodic, so one scalar root on
theta'(0) gives the orbit of Table 5.4 / Table 5.7 exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

RTOL = 1e-12


def planar_rhs(t: float, y: np.ndarray, j_c: float, omega: float) -> list[float]:
    """Eq. 5.56 as a first-order system y = (theta, theta')."""
    return [y[1], j_c * np.sin(y[0] - omega * t)]


def integrate(j_c: float, omega: float, theta0: float, rate0: float, t_end: float,
              t_eval: np.ndarray | None = None):
    """DOP853 solution of Eq. 5.56 (rtol 1e-12, dense in ``t_eval``)."""
    return solve_ivp(planar_rhs, (0.0, t_end), [theta0, rate0], method="DOP853", rtol=RTOL,
                     atol=1e-14, args=(j_c, omega), t_eval=t_eval)


@dataclass(frozen=True)
class PlanarOrbit:
    """T-periodic orbit of Eq. 5.56 around ``theta0`` (0 or pi) with initial rate ``rate0``."""

    j_c: float
    omega: float
    theta0: float
    rate0: float

    @property
    def period(self) -> float:
        return 2.0 * np.pi / self.omega

    def sample(self, n: int = 4096) -> tuple[np.ndarray, np.ndarray]:
        """theta at n equally spaced times over one period (endpoint excluded)."""
        t = np.arange(n) * self.period / n
        sol = integrate(self.j_c, self.omega, self.theta0, self.rate0, self.period, t)
        return t, sol.y[0]

    def sine_coefficients(self, harmonics: int = 3, n: int = 4096) -> np.ndarray:
        """a_i of theta - theta0 = sum a_i sin(i w t) (Eq. 5.57), i = 1..harmonics."""
        t, theta = self.sample(n)
        dev = theta - self.theta0
        return np.array([2.0 * np.mean(dev * np.sin(i * self.omega * t)) for i in range(1, harmonics + 1)])

    def average_force_ratio(self, n: int = 4096) -> float:
        """F_av / A: cycle mean of cos(theta - w t) (Eq. 5.89-5.91); positive = repulsion.

        Eq. 5.89 is used as printed (the minus sign of m_F in Eq. 5.87 is absorbed in it).
        """
        t, theta = self.sample(n)
        return float(np.mean(np.cos(theta - self.omega * t)))

    def amplitude(self, n: int = 4096) -> float:
        """max |theta - theta0| over the period (the |theta| column of Table 5.7)."""
        _, theta = self.sample(n)
        return float(np.max(np.abs(theta - self.theta0)))


def periodic_orbit(j_c: float, omega: float, theta0: float = np.pi,
                   guess: float | None = None) -> PlanarOrbit:
    """Shoot theta'(0) so that theta(T/2) = theta0 (Eq. 5.56; theta0 = 0 or pi).

    The initial bracket is around the linear estimate theta'(0) ~ w * amplitude with the
    amplitude of Eq. 5.58, signed as in Table 5.4.
    """
    half = np.pi / omega
    eff = j_c if theta0 == 0.0 else -j_c  # theta0 = pi flips the sign of the torque
    amp = np.arctan(abs(eff) / omega**2)
    if guess is None:
        guess = np.sign(eff) * omega * amp

    def miss(rate: float) -> float:
        return integrate(j_c, omega, theta0, rate, half).y[0, -1] - theta0

    lo, hi = sorted((0.8 * guess, 1.25 * guess))
    rate = brentq(miss, lo, hi, xtol=1e-13, rtol=1e-14)
    return PlanarOrbit(j_c, omega, theta0, rate)
