"""Ground truth of a pattern, computed from the motion model (never from an analysis).

A pattern ``z(s) = c + A e^{i s} + B e^{i k s}`` (complex pixels, y down) is written in the layout
of ``labkit analyse laser``'s ``pattern`` object, plus ``symmetry``:

* ellipse (``k = -1``): semi-axes ``|A| +- |B|``, major axis at ``(arg A + arg B) / 2`` (mod pi);
* trochoid (Eq. 6.38 with ``k = (1 + a) / a``): reparametrise ``s -> s + tau`` so both terms share
  one phase; scale ``|A|``, ``b = |B| / |A|``, rotation mod ``2 pi / |k - 1|``; ``loops`` counts
  the main loop and the small ones for an epitrochoid (``= k``) and the arms of a hypotrochoid
  (``= 1 - k``); ``symmetry = round(1 / |a|) = |k - 1|``, the n-fold rotational symmetry.

A conic section drawn by the simulated cone on a tilted screen is not given by coefficients; its
truth comes from :func:`conic_truth`, an algebraic fit to exact (noise-free, dense) curve points,
exact to rounding because the curve is exactly a conic.
"""

from __future__ import annotations

import math

import numpy as np

CIRCLE_BELOW_ELLIPTICITY = 0.02


def _conic_dict(center: complex, major: float, minor: float, rotation_rad: float) -> dict:
    ell = 1 - minor / major if major > 0 else 0.0
    kind = "circle" if ell < CIRCLE_BELOW_ELLIPTICITY else "ellipse"
    return {"type": kind, "center_px": [center.real, center.imag], "semi_axes_px": [major, minor],
            "rotation_deg": math.degrees(rotation_rad % math.pi), "ellipticity": ell, "loops": 1,
            "symmetry": None, "trochoid": None}


def pattern_truth(c: complex, A: complex, B: complex, k: int) -> dict:
    """Truth of ``c + A e^{is} + B e^{iks}`` (see module docstring)."""
    if k == -1:
        major, minor = abs(A) + abs(B), abs(abs(A) - abs(B))
        rot = 0.5 * (np.angle(A) + np.angle(B)) if abs(B) > 0 else 0.0
        return _conic_dict(c, major, minor, float(rot))
    tau = (np.angle(A) - np.angle(B)) / (k - 1)
    sym = 2 * math.pi / abs(k - 1)
    rot = float((np.angle(A) + tau) % sym)
    scale, b = abs(A), abs(B) / abs(A)
    a = 1.0 / (k - 1)
    kind = "epitrochoid" if k >= 2 else "hypotrochoid"
    axes = [scale * (1 + b), scale * abs(1 - b)]
    return {"type": kind, "center_px": [c.real, c.imag], "semi_axes_px": axes,
            "rotation_deg": math.degrees(rot), "ellipticity": None, "loops": k if k >= 2 else 1 - k,
            "symmetry": int(round(1 / abs(a))),
            "trochoid": {"a": a, "b": b, "scale_px": scale, "rotation_deg": math.degrees(rot)}}


def conic_truth(points: np.ndarray) -> dict:
    """Centre, semi-axes and rotation of the conic through exact points (N, 2): the null vector
    of ``[x^2, xy, y^2, x, y, 1]`` (coordinates normalised first), then the conic's centre and the
    eigen-decomposition of its quadratic part."""
    m = points.mean(axis=0)
    s = float(np.abs(points - m).max())
    x, y = ((points - m) / s).T
    design = np.column_stack([x * x, x * y, y * y, x, y, np.ones_like(x)])
    _, _, vt = np.linalg.svd(design, full_matrices=False)
    a, b, c, d, e, f = vt[-1]
    q = np.array([[a, b / 2], [b / 2, c]])
    x0 = np.linalg.solve(q, -0.5 * np.array([d, e]))
    f0 = f + 0.5 * (d * x0[0] + e * x0[1])
    vals, vecs = np.linalg.eigh(q)
    radii = np.sqrt(-f0 / vals)  # both positive for an ellipse
    order = np.argsort(radii)[::-1]
    major, minor = radii[order] * s
    vec = vecs[:, order[0]]
    centre = complex(*(x0 * s + m))
    return _conic_dict(centre, float(major), float(minor), math.atan2(vec[1], vec[0]))


def conic_residual_px(points: np.ndarray, truth: dict) -> float:
    """Largest distance-like deviation of points from a truth ellipse (checks exactness)."""
    cx, cy = truth["center_px"]
    major, minor = truth["semi_axes_px"]
    r = math.radians(truth["rotation_deg"])
    u = (points[:, 0] - cx) * math.cos(r) + (points[:, 1] - cy) * math.sin(r)
    v = -(points[:, 0] - cx) * math.sin(r) + (points[:, 1] - cy) * math.cos(r)
    level = np.sqrt((u / major) ** 2 + (v / minor) ** 2)
    return float(np.abs(level - 1).max() * major)
