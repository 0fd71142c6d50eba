"""Pattern curves drawn by the reflected laser beam, as complex-valued functions of a parameter t.

Every pattern is ``z(t) = c + A exp(i t) + B exp(i k t)`` with complex ``c, A, B`` and an integer
``k`` (``z = x + i y`` in pixel coordinates, y pointing down):

* ``k = -1`` is an ellipse (the conical motion of Sec. 5.2.3, Fig. 5.19/5.20); ``B = 0`` a circle;
* ``k = n >= 2`` is an epitrochoid, ``k = 1 - n <= -2`` a hypotrochoid with ``n`` loops (the main
  loop and the small ones, Sec. 6.5, Fig. 6.19).

Eq. 6.38, ``x = cos t + b cos((1+a)/a t)``, ``y = sin t + b sin((1+a)/a t)``, is the case
``A = scale``, ``B = scale * b``, ``k = (1+a)/a``; so ``a = 1/(k-1)``: ``a = 1/(n-1)`` for an
epitrochoid with ``n`` loops and ``a = -1/n`` for a hypotrochoid with ``n`` loops (``a = -1/3``,
three arms, is the small plot of Fig. 6.19).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def k_for(kind: str, loops: int) -> int:
    """Frequency ratio k of Eq. 6.38 for a pattern kind and loop count (ellipse: k = -1)."""
    if kind in ("circle", "ellipse"):
        return -1
    if kind == "epitrochoid":
        if loops < 2:
            raise ValueError("an epitrochoid has at least 2 loops")
        return loops
    if kind == "hypotrochoid":
        if loops < 3:
            raise ValueError("a hypotrochoid has at least 3 loops (2 loops is an ellipse)")
        return 1 - loops
    raise ValueError(f"unknown pattern kind {kind!r}")


def a_for_k(k: int) -> float:
    """Parameter a of Eq. 6.38 from the frequency ratio k = (1+a)/a."""
    return 1.0 / (k - 1)


def phasors(t: np.ndarray, k: int | np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``exp(i t)`` and ``exp(i k t)`` for real ``t`` and integer ``k``: the two terms of every
    pattern curve. ``k`` is one integer, or one per row of a 2-D ``t`` (shape (rows, 1)).

    ``exp(i k t)`` is ``exp(i t)`` raised to the integer power k by repeated squaring, and
    ``exp(i t)`` is ``cos t + i sin t``: a complex ``np.exp`` costs about 50 ns per element, a
    complex product about 1 ns, and the fit evaluates these at every point of every candidate in
    every step. The power agrees with ``np.exp(1j * k * t)`` to a few units in the last place
    (|k| <= 8 takes 3 squarings), far below anything the fit resolves."""
    t = np.asarray(t, dtype=float)
    e1 = np.empty(t.shape, complex)
    np.cos(t, out=e1.real)
    np.sin(t, out=e1.imag)
    ks = np.asarray(k)
    if ks.size == 1:
        return e1, _integer_power(e1, int(ks.flat[0]))
    if ks.ndim != 2 or ks.shape != (t.shape[0], 1):
        raise ValueError(f"k must be one integer or one per row (shape ({t.shape[0]}, 1)), got {ks.shape}")
    ek = np.empty(t.shape, complex)
    for value in np.unique(ks):  # a few distinct k among many rows: one power per k
        rows = np.flatnonzero(ks[:, 0] == value)
        ek[rows] = _integer_power(e1[rows], int(value))
    return e1, ek


def _integer_power(e1: np.ndarray, k: int) -> np.ndarray:
    """``e1 ** k`` for unit-modulus ``e1`` by repeated squaring (negative k: the conjugate)."""
    result: np.ndarray | None = None
    power, bits = e1, abs(k)
    while bits:
        if bits & 1:
            result = power if result is None else result * power
        bits >>= 1
        if bits:
            power = power * power
    if result is None:
        return np.ones_like(e1)
    return np.conj(result) if k < 0 else result.copy() if result is e1 else result


def loops_for_k(k: int) -> int:
    """Loop count (main loop plus small loops) of a trochoid with ratio k (Sec. 6.5)."""
    return k if k >= 2 else 1 - k


@dataclass(frozen=True)
class Pattern:
    """A pattern in canonical form: ``c + s R(rot) [cos t + b cos k t, sin t + b sin k t]``
    for trochoids (Eq. 6.38), or centre, semi-axes and rotation for an ellipse."""

    kind: str  # circle | ellipse | epitrochoid | hypotrochoid
    center: tuple[float, float]
    rotation_rad: float = 0.0
    semi_axes: tuple[float, float] = (0.0, 0.0)  # ellipse: major, minor (px)
    scale: float = 0.0  # trochoid: radius of the main circle (px)
    b: float = 0.0  # trochoid: relative radius of the second term
    loops: int = 1

    @property
    def k(self) -> int:
        return k_for(self.kind, self.loops)

    def coefficients(self) -> tuple[complex, complex, complex, int]:
        """Complex ``(c, A, B, k)`` with ``z(t) = c + A e^{it} + B e^{ikt}``."""
        c = complex(*self.center)
        rot = complex(math.cos(self.rotation_rad), math.sin(self.rotation_rad))
        if self.kind in ("circle", "ellipse"):
            major, minor = self.semi_axes
            # x' = M cos t, y' = m sin t  ->  (M+m)/2 e^{it} + (M-m)/2 e^{-it}
            return c, rot * (major + minor) / 2, rot * (major - minor) / 2, -1
        return c, rot * self.scale, rot * self.scale * self.b, self.k

    def points(self, t: np.ndarray) -> np.ndarray:
        """Curve points (N, 2) at parameters ``t``."""
        c, a_coef, b_coef, k = self.coefficients()
        z = c + a_coef * np.exp(1j * t) + b_coef * np.exp(1j * k * t)
        return np.column_stack([z.real, z.imag])


def ellipse_from_coefficients(c: complex, a_coef: complex, b_coef: complex) -> Pattern:
    """Canonical ellipse (major first, rotation of the major axis in [0, 180) deg) from
    ``c + A e^{it} + B e^{-it}``: semi-axes are ``|A| +- |B|``, the major axis lies at
    ``(arg A + arg B) / 2``."""
    major = abs(a_coef) + abs(b_coef)
    minor = abs(abs(a_coef) - abs(b_coef))
    rot = 0.5 * (np.angle(a_coef) + np.angle(b_coef)) if abs(b_coef) > 0 else 0.0
    rot = float(rot % math.pi)
    kind = "ellipse"
    return Pattern(kind, (c.real, c.imag), rot, (float(major), float(minor)), loops=1)


def trochoid_from_coefficients(c: complex, a_coef: complex, b_coef: complex, k: int) -> Pattern:
    """Canonical trochoid from ``c + A e^{it} + B e^{ikt}``: reparametrise ``t -> t + tau`` so
    that both terms share one phase, which is then the rotation. The rotation is defined modulo
    the curve's symmetry ``2 pi / |k - 1|``; the value returned lies in ``[0, 2 pi / |k-1|)``."""
    # want arg(A) + tau == arg(B) + k tau  (mod 2 pi)  ->  tau = (arg A - arg B) / (k - 1)
    tau = (np.angle(a_coef) - np.angle(b_coef)) / (k - 1)
    rot = float(np.angle(a_coef) + tau)
    sym = 2 * math.pi / abs(k - 1)
    rot = rot % sym
    kind = "epitrochoid" if k >= 2 else "hypotrochoid"
    scale = abs(a_coef)
    return Pattern(kind, (c.real, c.imag), rot, scale=float(scale), b=float(abs(b_coef) / scale),
                   loops=loops_for_k(k))


def rotation_error_deg(a_rad: float, b_rad: float, period_rad: float) -> float:
    """Smallest difference between two angles defined modulo ``period_rad``, in degrees."""
    d = (a_rad - b_rad) % period_rad
    return math.degrees(min(d, period_rad - d))


# How a pattern is told, the same for the laser's fit (labkit.vision.laser.pattern_fit) and the
# strobe's point pattern (labkit.vision.strobe.analyse):
CIRCLE_MAX_ELLIPTICITY = 0.02  # below this an ellipse is reported as a circle
SIMPLER_TOLERANCE = 1.12  # a simpler pattern wins unless a trochoid's residual is this much lower
MIN_GAIN_PX = 0.1  # ... and at least this much lower in absolute terms
MIN_SECOND_TERM_PX = 1.0  # ... and its second term (b * scale) is visible
MAX_TROCHOID_B = 1.05  # larger b means the fast term dominates: not a trochoid of Eq. 6.38


def trochoid_beats(trochoid_rms: float, second_term_px: float, simpler_rms: float) -> bool:
    """A trochoid replaces a simpler pattern only if it lowers the residual by the factor
    ``SIMPLER_TOLERANCE`` and by ``MIN_GAIN_PX``, and its second term (``|B| = b * scale``) is at
    least ``MIN_SECOND_TERM_PX``: otherwise it is a circle with invisible wiggles fitted to noise."""
    return (trochoid_rms * SIMPLER_TOLERANCE < simpler_rms and simpler_rms - trochoid_rms > MIN_GAIN_PX
            and second_term_px >= MIN_SECOND_TERM_PX)
