"""A body point's pattern on the screen from its samples and their known phases (the strobe's
answer to the laser's pattern fit, in the same JSON layout): least squares of Eq. 6.38's curves
with the phase of each sample given. Pure functions."""

from __future__ import annotations

import math

import numpy as np

from labkit.vision.shared.curves import (
    CIRCLE_MAX_ELLIPTICITY,
    MAX_TROCHOID_B,
    a_for_k,
    ellipse_from_coefficients,
    trochoid_beats,
    trochoid_from_coefficients,
)


def phase_pattern(points: np.ndarray, phases: np.ndarray) -> dict:
    """Classify a body point's trajectory with known phase per sample: least squares of
    ``c + A e^{i s psi} + B e^{i s k psi}`` (s = +-1, the sense of rotation) for the ellipse
    (k = -1) and the trochoids of Eq. 6.38 (epitrochoid k = 2..7, hypotrochoid k = -2..-6); the
    ellipse wins unless :func:`labkit.vision.shared.curves.trochoid_beats` it. Same JSON layout as
    the laser pattern."""
    z = points[:, 0] + 1j * points[:, 1]
    fits = []
    for k in [-1, *range(2, 8), *range(-2, -7, -1)]:
        for s in (1, -1):
            m = np.column_stack([np.ones_like(z), np.exp(1j * s * phases), np.exp(1j * s * k * phases)])
            coef, *_ = np.linalg.lstsq(m, z, rcond=None)
            rms = float(np.sqrt(np.mean(np.abs(z - m @ coef) ** 2)))
            if k != -1 and abs(coef[2]) > MAX_TROCHOID_B * abs(coef[1]):
                rms = math.inf
            fits.append((rms, k, s, coef))
    ellipse = min((f for f in fits if f[1] == -1), key=lambda f: f[0])
    best = min(fits, key=lambda f: f[0])
    if best[1] == -1 or not trochoid_beats(best[0], abs(best[3][2]), ellipse[0]):
        best = ellipse
    rms, k, s, (c, a, b) = best
    # s = -1 is the same curve traversed backwards: c + A e^{-it} + B e^{-ikt} = c + A e^{it'} ...
    # with t' = -t, so the coefficients describe the point set unchanged.
    center = [float(c.real), float(c.imag)]
    if k == -1:
        p = ellipse_from_coefficients(c, a, b)
        major, minor = p.semi_axes
        ell = 1 - minor / major if major > 0 else 0.0
        kind = "circle" if ell < CIRCLE_MAX_ELLIPTICITY else "ellipse"
        return {"type": kind, "center_px": center, "semi_axes_px": [major, minor],
                "rotation_deg": math.degrees(p.rotation_rad), "ellipticity": ell, "loops": 1,
                "trochoid": None, "rms_residual_px": rms}
    p = trochoid_from_coefficients(c, a, b, k)
    extent = [p.scale * (1 + p.b), p.scale * abs(1 - p.b)]
    return {"type": p.kind, "center_px": center, "semi_axes_px": extent,
            "rotation_deg": math.degrees(p.rotation_rad), "ellipticity": None, "loops": p.loops,
            "trochoid": {"a": a_for_k(k), "b": p.b, "scale_px": p.scale,
                         "rotation_deg": math.degrees(p.rotation_rad)},
            "rms_residual_px": rms}
