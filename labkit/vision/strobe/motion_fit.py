"""Fit of Eq. 5.97 to per-frame tilt and lateral position with known phase, with standard errors
(docs/explanation/strobe-analysis.md, *Fit and uncertainties*).

Model: ``theta_k = phi sin(psi_k - psi_0)`` and ``p_k = p_0 - delta tan(theta_k)`` (p across the
rest axis), so the lateral amplitude is ``beta = delta tan(phi)`` (Eq. 5.97). Both are fitted by
linear least squares on ``[1, sin psi, cos psi]``. The phase reference ``psi_0`` is that of the
lateral motion (when it stands clear of its noise), and phi is the tilt component in phase with it:
a rolling shutter shears the body in proportion to its lateral velocity, which adds tilt in
quadrature. The first sine harmonic of ``tan(phi sin psi)`` is ``T1(phi)`` (slightly below
``tan phi``), so ``delta = A_p / T1(phi)`` and ``beta = delta tan(phi)`` from the lateral first
harmonic ``A_p``. Both amplitudes are divided by the exposure's sinc factor when it is known.

Standard errors: ``Cov = s^2 (A^T A)^-1`` with ``s^2 = RSS / (N - 3)`` of each fit; phi's is the
variance of the in-phase projection, beta's that of the lateral amplitude times ``tan(phi)/T1``,
delta's from both by first-order propagation (tilt and lateral errors taken as independent). They
count scatter only: a systematic error common to all frames (a wrong phase model, a biased body
measurement) is not in them; the quality verdict looks at those separately.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

_PSI = np.linspace(0.0, 2 * math.pi, 512, endpoint=False)


def t1(phi: float) -> float:
    """First Fourier sine coefficient of ``tan(phi sin psi)``; ``~ phi + phi^3/4`` for small phi."""
    return float(np.mean(np.tan(phi * np.sin(_PSI)) * 2 * np.sin(_PSI)))


@dataclass
class SineFit:
    coef: np.ndarray  # offset, sin, cos
    cov: np.ndarray  # 3x3
    rms: float
    explained: float  # fraction of the variance explained

    @property
    def amplitude(self) -> float:
        return float(math.hypot(self.coef[1], self.coef[2]))

    def amplitude_se(self) -> float:
        a = self.amplitude
        if a <= 0:
            return float(math.sqrt(max(self.cov[1, 1], 0.0)))
        g = np.array([self.coef[1], self.coef[2]]) / a
        return float(math.sqrt(max(g @ self.cov[1:, 1:] @ g, 0.0)))

    def at(self, psi: np.ndarray) -> np.ndarray:
        """The fitted sinusoid at phases ``psi``."""
        return self.coef[0] + self.coef[1] * np.sin(psi) + self.coef[2] * np.cos(psi)

    def projection(self, unit: np.ndarray) -> tuple[float, float]:
        """Component of (sin, cos) coefficients along ``unit`` and its standard error."""
        return float(self.coef[1:] @ unit), float(math.sqrt(max(unit @ self.cov[1:, 1:] @ unit, 0.0)))


def sine_fit(psi: np.ndarray, y: np.ndarray) -> SineFit:
    design = np.column_stack([np.ones_like(psi), np.sin(psi), np.cos(psi)])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    resid = y - design @ coef
    dof = max(1, len(y) - 3)
    s2 = float(resid @ resid) / dof
    cov = s2 * np.linalg.pinv(design.T @ design)
    var = float(np.var(y))
    explained = 1 - float(np.mean(resid ** 2)) / var if var > 0 else 0.0
    return SineFit(coef, cov, float(np.sqrt(np.mean(resid ** 2))), explained)


@dataclass
class MotionFit:
    phi: float
    phi_se: float
    beta: float
    beta_se: float
    delta: float | None
    delta_se: float | None
    quadrature: float
    phase_offset: float  # psi_0: tilt = phi sin(psi + offset)
    towards_top: bool | None
    tilt: SineFit
    lateral: SineFit


def fit_motion(psi: np.ndarray, tilt: np.ndarray, lateral: np.ndarray, blur_factor: float = 1.0) -> MotionFit:
    """Eq. 5.97 from tilt (rad) and lateral position (px) at phases psi; see the module doc."""
    ft, fx = sine_fit(psi, tilt), sine_fit(psi, lateral)
    a_x = fx.amplitude
    if a_x > 3 * fx.amplitude_se() + 1e-9:
        e = np.array([fx.coef[1], fx.coef[2]]) / a_x
        in_phase, phi_se = ft.projection(e)
        quad, _ = ft.projection(np.array([-e[1], e[0]]))
        phi = abs(in_phase)
        offset = math.atan2(fx.coef[2], fx.coef[1]) + (math.pi if in_phase < 0 else 0.0)
        # p = p0 - delta tan(theta): p in antiphase with the tilt means the centre is towards the top
        towards_top = in_phase < 0
    else:
        phi, phi_se, quad = ft.amplitude, ft.amplitude_se(), 0.0
        offset, towards_top = math.atan2(ft.coef[2], ft.coef[1]), None
    phi, phi_se = phi / blur_factor, phi_se / blur_factor
    a_x, a_x_se = a_x / blur_factor, fx.amplitude_se() / blur_factor
    if phi > 0:
        t1_phi = t1(phi)
        delta = a_x / t1_phi
        beta = delta * math.tan(phi)
        beta_se = a_x_se * math.tan(phi) / t1_phi
        dt1 = (t1(phi * 1.001) - t1_phi) / (phi * 0.001)
        rel = math.hypot(a_x_se / a_x if a_x > 0 else 0.0, dt1 / t1_phi * phi_se)
        delta_se = abs(delta) * rel
    else:
        beta, beta_se, delta, delta_se = a_x, a_x_se, None, None
    return MotionFit(phi, phi_se, beta, beta_se, delta, delta_se, quad, offset, towards_top, ft, fx)
