"""Laser optics: the beam through the screen's hole, reflected by the polar face, onto the screen,
and the screen seen by the camera.

The laser sits behind the screen; its beam passes through the hole in the screen (at distance
``L`` along +z from the magnet) travelling along -z, is reflected by the polar face (mirror law,
``r = d - 2 (d . n) n``) and lands on the screen where the ray ``s r`` meets the screen's plane.
The screen may be tilted by ``tilt_deg`` about its x axis (its normal leaning towards +y); then a
circular cone of reflected rays draws an exact ellipse (a conic section). The camera looks at the
screen square on: screen millimetres map to pixels by a similarity (scale ``1 / mm_per_px``,
rotation ``roll_deg``, the hole at ``hole_px``), which keeps circles, ellipses and trochoids what
they are. See docs/explanation/robustness-suite.md, *Independent footage and the robustness suite*.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

INCOMING = np.array([0.0, 0.0, -1.0])


def reflect(d: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Mirror law for unit directions: ``r = d - 2 (d . n) n`` for each normal (N, 3)."""
    dn = normals @ d
    return d[None, :] - 2 * dn[:, None] * normals


@dataclass(frozen=True)
class Screen:
    """``distance_mm`` from the magnet, ``tilt_deg`` of the screen plane about its x axis,
    ``hole_mm`` radius of the hole the beam passes through."""

    distance_mm: float = 500.0
    tilt_deg: float = 0.0
    hole_mm: float = 0.0

    def axes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        e = math.radians(self.tilt_deg)
        normal = np.array([0.0, math.sin(e), math.cos(e)])
        return np.array([1.0, 0.0, 0.0]), np.array([0.0, math.cos(e), -math.sin(e)]), normal

    def hits_mm(self, normals: np.ndarray) -> np.ndarray:
        """Screen coordinates (N, 2) mm of the spot for polar-face normals (N, 3); NaN where the
        reflected beam does not reach the screen."""
        r = reflect(INCOMING, normals)
        e1, e2, ns = self.axes()
        p0 = np.array([0.0, 0.0, self.distance_mm])
        denom = r @ ns
        with np.errstate(divide="ignore", invalid="ignore"):
            s = np.where(denom > 1e-9, (p0 @ ns) / denom, np.nan)
        p = s[:, None] * r - p0
        return np.column_stack([p @ e1, p @ e2])


@dataclass(frozen=True)
class ScreenView:
    """The camera's view of the screen: pixel position of the hole, millimetres per pixel, and
    the camera's roll (the screen's x axis is at ``roll_deg`` in the image, towards +y)."""

    hole_px: tuple[float, float]
    mm_per_px: float
    roll_deg: float = 0.0

    def to_px(self, uv_mm: np.ndarray) -> np.ndarray:
        r = math.radians(self.roll_deg)
        c, s = math.cos(r), math.sin(r)
        u, v = uv_mm[:, 0] / self.mm_per_px, uv_mm[:, 1] / self.mm_per_px
        return np.column_stack([self.hole_px[0] + c * u - s * v, self.hole_px[1] + s * u + c * v])

    def complex_px(self, z_mm: complex) -> complex:
        """A screen vector (complex mm) as an image vector (complex px), without the offset."""
        return z_mm * complex(math.cos(math.radians(self.roll_deg)), math.sin(math.radians(self.roll_deg))) \
            / self.mm_per_px
