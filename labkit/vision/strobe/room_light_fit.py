"""The room light's share and the lens's blur mix of a stroboscope clip, from normal equations
accumulated frame by frame (docs/explanation/strobe-analysis.md, *Room light*;
docs/explanation/strobe-speed.md; ADR 0016).

The model of :mod:`labkit.vision.strobe.room_light` is ``d = (1 - a) B p + a h`` per pixel, with the
row's share ``a = alpha w``. While no share is clipped, ``(1 - a)^2 = 1 - 2 alpha w + alpha^2 w^2``,
so the least-squares normal equations for the blur mix ``p`` are a quadratic in ``alpha`` whose
three coefficient matrices (``B^T B``, ``B^T W B``, ``B^T W^2 B``) and right-hand sides are sums
over pixels; so are the two numbers the ``alpha`` step needs (``x.x`` and ``x.(d - B p)`` with
``x = w (h - B p)``, expanded). :class:`NormalSums` adds each frame's pixels to those sums and
forgets them: memory is the sums (3 x 24 x 24 numbers), not every pixel of every frame, and one
pass over the pixels serves every alternation. Everything is float64: the columns are nearly
collinear and sums formed in float32 changed with the BLAS kernel.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

MAX_AMBIENT = 0.9  # a row's room-light share is clipped here (1 would leave no flash light to measure)
ALPHA_TOL = 1e-5  # the lens-blur / room-light alternation stops when the share moves by less
MAX_ALTERNATIONS = 200  # ... or after this many (it converges linearly, ~25 on the suite's clips)
# pixels per block of the sums: 24 x 24 x 360 multiply-adds stay under OpenBLAS's threshold for
# threads (65536 x 4), whose idle spinning between calls doubled the analysis's CPU time on a busy
# machine; a block's products are still BLAS, one thread
BLOCK_ROWS = 360


@dataclass
class NormalSums:
    """Sums over pixels of the room-light model's normal equations (module docstring)."""

    columns: int
    gram: list[np.ndarray] = field(default_factory=list)  # B^T B, B^T W B, B^T W^2 B
    rhs: list[np.ndarray] = field(default_factory=list)  # B^T d, B^T W (d + h), B^T W^2 h
    whd: float = 0.0  # sum of w h d
    wh2: float = 0.0  # sum of (w h)^2
    w_max: float = 0.0
    pixels: int = 0

    def __post_init__(self) -> None:
        if not self.gram:
            self.gram = [np.zeros((self.columns, self.columns)) for _ in range(3)]
            self.rhs = [np.zeros(self.columns) for _ in range(3)]

    def add(self, d: np.ndarray, h: np.ndarray, weight: np.ndarray, blurred: np.ndarray) -> None:
        """Add pixels: darkening ``d``, ghost ``h``, row weight ``weight`` (flat), columns ``blurred``."""
        d, h, w, b = (np.asarray(v, np.float64) for v in (d, h, weight, blurred))
        if not len(d):
            return
        bw = b * w[:, None]
        wh = w * h
        dh = d + h
        g, r = self.gram, self.rhs
        for s in range(0, len(d), BLOCK_ROWS):
            e = s + BLOCK_ROWS
            bs, bws = b[s:e], bw[s:e]
            g[0] += bs.T @ bs
            g[1] += bws.T @ bs
            g[2] += bws.T @ bws
            r[0] += bs.T @ d[s:e]
            r[1] += bws.T @ dh[s:e]
            r[2] += bws.T @ wh[s:e]
        self.whd += float(np.sum(wh * d))
        self.wh2 += float(np.sum(wh * wh))
        self.w_max = max(self.w_max, float(w.max()))
        self.pixels += len(d)

    def normal_equations(self, alpha: float) -> tuple[np.ndarray, np.ndarray]:
        """The equations for the blur mix at share ``alpha``; the share is kept within
        [0, MAX_AMBIENT / w_max] (no room light below 0; no row's share above MAX_AMBIENT)."""
        a = min(max(alpha, 0.0), MAX_AMBIENT / self.w_max) if self.w_max > 0 else 0.0
        g, r = self.gram, self.rhs
        return g[0] - 2 * a * g[1] + a * a * g[2], r[0] - a * r[1] + a * a * r[2]

    def solve(self) -> tuple[float, np.ndarray]:
        """``alpha`` and the blur mix ``p`` by alternating least squares until ``alpha`` moves by
        less than ``ALPHA_TOL`` (at most ``MAX_ALTERNATIONS``)."""
        alpha, p = 0.0, np.zeros(self.columns)
        if self.pixels == 0:
            return alpha, p
        eye = np.eye(self.columns)
        for _ in range(MAX_ALTERNATIONS):
            normal, right = self.normal_equations(alpha)
            p = np.linalg.solve(normal + 1e-9 * np.trace(normal) * eye, right)
            xx = self.wh2 - 2 * float(p @ self.rhs[2]) + float(p @ self.gram[2] @ p)
            xd = self.whd - float(p @ self.rhs[1]) + float(p @ self.gram[1] @ p)
            alpha, before = (xd / xx if xx > 0 else 0.0), alpha
            if abs(alpha - before) < ALPHA_TOL:
                break
        return alpha, p


def fit_room_light(d: np.ndarray, h: np.ndarray, weight: np.ndarray, blurred: np.ndarray
                   ) -> tuple[float, np.ndarray]:
    """``alpha`` of ``d = (1 - a) B p + a h`` with ``a = alpha * weight`` (pixels flattened;
    ``blurred`` the columns ``B``, ``p`` the lens's mix) for pixels given at once; returns both."""
    sums = NormalSums(np.shape(blurred)[1])
    sums.add(d, h, weight, blurred)
    return sums.solve()
