"""Where the camera points: a tripod on a bench that drifts, wanders and shakes.

The image of everything fixed in the room (the screen, the rig) moves by ``offset(t)`` px:
a linear drift, a slow wander (a sum of a few low-frequency sinusoids of seeded phases) and a
fast shake (small, a few Hz). The drift is zero at ``t_ref`` so that the scene's nominal centre
is where it is at that moment (the middle of the clip).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Mount:
    """``drift_px_s`` (vx, vy); ``wander_px`` amplitude of the slow wander (0.1-0.6 Hz);
    ``shake_px`` amplitude of the shake (5-13 Hz); ``seed`` for their phases; ``t_ref`` the time
    at which the drift term is zero."""

    drift_px_s: tuple[float, float] = (0.0, 0.0)
    wander_px: float = 0.0
    shake_px: float = 0.0
    seed: int = 0
    t_ref: float = 0.0

    def _terms(self) -> list[tuple[float, float, float, float]]:
        rng = np.random.default_rng(self.seed + 7919)
        terms = []
        for amp, (lo, hi) in ((self.wander_px, (0.1, 0.6)), (self.shake_px, (5.0, 13.0))):
            if amp <= 0:
                continue
            for _ in range(3):
                f = float(rng.uniform(lo, hi))
                terms.append((amp / math.sqrt(3), f, float(rng.uniform(0, 2 * math.pi)),
                              float(rng.uniform(0, 2 * math.pi))))
        return terms

    def offset(self, t: np.ndarray | float) -> np.ndarray:
        """Image offset (..., 2) px of the fixed scene at times ``t`` (s)."""
        t = np.asarray(t, dtype=float)
        dx = self.drift_px_s[0] * (t - self.t_ref)
        dy = self.drift_px_s[1] * (t - self.t_ref)
        for amp, f, px, py in self._terms():
            dx = dx + amp * (np.sin(2 * math.pi * f * t + px) - math.sin(2 * math.pi * f * self.t_ref + px))
            dy = dy + amp * (np.sin(2 * math.pi * f * t + py) - math.sin(2 * math.pi * f * self.t_ref + py))
        return np.stack([dx, dy], axis=-1)

    @property
    def moves(self) -> bool:
        return any(self.drift_px_s) or self.wander_px > 0 or self.shake_px > 0
