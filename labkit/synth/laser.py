"""Render a laser beam reflected from the floating magnet's polar face onto a screen (Sec. 5.2.3,
Fig. 5.19: fuzzy halo, saturated core, dark hole where the beam leaves the screen).

The spot follows a :class:`labkit.vision.shared.curves.Pattern` (circle, ellipse, epitrochoid,
hypotrochoid, Eq. 6.38) at ``cycle_hz``, or any trajectory ``position(t) -> (N, 2) px`` such as one
built from a simulator's tilt angles by :func:`positions_from_angles`. Impairments: exposure smear,
rolling shutter, halo, saturation, sensor noise, background light with a gradient and a lamp, the
hole, slow drift of the pattern centre and per-frame jitter. Pixel (0, 0) is the centre of the
top-left pixel.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field

import cv2
import numpy as np

from labkit.vision.shared.curves import Pattern, a_for_k

Trajectory = Callable[[np.ndarray], np.ndarray]


@dataclass
class LaserSpec:
    """Everything that defines a synthetic laser clip. Lengths in px, times in s."""

    pattern: Pattern = field(default_factory=lambda: Pattern("circle", (320.0, 240.0), 0.0, (80.0, 80.0)))
    size: tuple[int, int] = (640, 480)  # width, height
    fps: float = 30.0
    frames: int = 60
    cycle_hz: float = 7.3  # main-loop frequency of the spot (aliased against fps)
    exposure_s: float = 0.002  # per frame; >= 1/cycle_hz draws the whole pattern
    spot_sigma_px: float = 1.6
    brightness: float = 1.6  # peak of the trace in units of full scale (> 1 saturates)
    halo_sigma_px: float = 0.0
    halo_strength: float = 0.0  # halo peak relative to the peak of a trace line
    noise_sigma: float = 2.0  # grey levels
    background: float = 40.0  # grey level of the screen
    gradient: float = 0.0  # background change across the frame, grey levels
    lamp: float = 0.0  # amplitude of a broad off-pattern light, grey levels
    hole_radius_px: float = 0.0
    drift_px_s: tuple[float, float] = (0.0, 0.0)
    jitter_px: float = 0.0
    rolling_shutter_s: float = 0.0  # readout time top to bottom
    codec: str = "mp4v"
    seed: int = 0
    laser_bgr: tuple[float, float, float] = (0.25, 0.3, 1.0)  # B, G, R response to the laser (red)
    background_bgr: tuple[float, float, float] = (1.0, 1.0, 1.0)  # screen tint: (0.75, 0.9, 1.0) is warm

    def to_dict(self) -> dict:
        d = asdict(self)
        d["pattern"] = asdict(self.pattern)
        return d


def positions_from_angles(times_s: np.ndarray, tilt_x_rad: np.ndarray, tilt_y_rad: np.ndarray,
                          screen_distance_mm: float, mm_per_px: float,
                          center_px: tuple[float, float]) -> Trajectory:
    """A trajectory on the screen from a simulator's tilt angles of the magnet's face normal.

    The reflected beam turns by twice the tilt, so the spot sits ``L tan(2 tilt)`` from the centre
    (L = screen distance). Angles are interpolated linearly (periodic over the run).
    """
    times_s = np.asarray(times_s, float)
    tx, ty = np.asarray(tilt_x_rad, float), np.asarray(tilt_y_rad, float)
    period = times_s[-1] - times_s[0]

    def position(t: np.ndarray) -> np.ndarray:
        tt = times_s[0] + np.mod(np.asarray(t, float) - times_s[0], period)
        ax, ay = np.interp(tt, times_s, tx), np.interp(tt, times_s, ty)
        x = center_px[0] + screen_distance_mm * np.tan(2 * ax) / mm_per_px
        y = center_px[1] + screen_distance_mm * np.tan(2 * ay) / mm_per_px
        return np.column_stack([x, y])

    return position


def pattern_trajectory(pattern: Pattern, cycle_hz: float) -> Trajectory:
    """Spot position at time t for a pattern traversed at ``cycle_hz`` main loops per second."""

    def position(t: np.ndarray) -> np.ndarray:
        return pattern.points(2 * math.pi * cycle_hz * np.asarray(t, float))

    return position


def laser_truth(spec: LaserSpec) -> dict:
    """Ground truth in the layout of ``labkit analyse laser`` (pattern centre at mid recording)."""
    p = spec.pattern
    trochoid = None
    if p.kind in ("circle", "ellipse"):
        major, minor = max(p.semi_axes), min(p.semi_axes)
        axes, rot, loops = [major, minor], math.degrees(p.rotation_rad) % 180, 1
        if p.semi_axes[1] > p.semi_axes[0]:
            rot = (rot + 90) % 180
        ellipticity = 1 - minor / major
    else:
        axes, ellipticity, loops = [p.scale * (1 + p.b), p.scale * abs(1 - p.b)], None, p.loops
        rot = math.degrees(p.rotation_rad) % (360 / abs(p.k - 1))
        trochoid = {"a": a_for_k(p.k), "b": p.b, "scale_px": p.scale, "rotation_deg": rot}
    return {
        "kind": "laser",
        "spec": spec.to_dict(),
        "frames": spec.frames, "fps": spec.fps, "size": list(spec.size),
        "pattern": {"type": p.kind, "center_px": list(p.center), "semi_axes_px": axes,
                    "rotation_deg": rot, "ellipticity": ellipticity, "loops": loops,
                    "trochoid": trochoid},
    }


class NoiseBank:
    """Gaussian sensor noise, independent per pixel: a few seeded noise fields larger than the
    frame, cropped at a random offset per frame (drawing ~3 M normals per 720p frame would cost
    more than everything else in the renderer)."""

    MARGIN = 24

    def __init__(self, size: tuple[int, int], sigma: float, rng: np.random.Generator, fields: int = 3):
        w, h = size
        self.rng, self.sigma, self.size = rng, sigma, size
        self.fields = [rng.standard_normal((h + self.MARGIN, w + self.MARGIN, 3), dtype=np.float32) * sigma
                       for _ in range(fields if sigma else 0)]

    def add_to(self, img: np.ndarray) -> None:
        if not self.fields:
            return
        w, h = self.size
        f = self.fields[int(self.rng.integers(len(self.fields)))]
        dx, dy = (int(v) for v in self.rng.integers(0, self.MARGIN, 2))
        cv2.add(img, f[dy:dy + h, dx:dx + w], dst=img)


def _background(spec: LaserSpec, rng: np.random.Generator) -> np.ndarray:
    w, h = spec.size
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    bg = spec.background + spec.gradient * ((x / w - 0.5) * 0.8 + (y / h - 0.5) * 0.6)
    if spec.lamp:
        lx, ly = rng.uniform(0.05, 0.3) * w, rng.uniform(0.05, 0.95) * h
        bg += spec.lamp * np.exp(-((x - lx) ** 2 + (y - ly) ** 2) / (2 * (0.12 * w) ** 2))
    return bg


def _hole_mask(spec: LaserSpec) -> np.ndarray | None:
    if spec.hole_radius_px <= 0:
        return None
    w, h = spec.size
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    cx, cy = spec.pattern.center
    r = np.hypot(x - cx, y - cy)
    return np.clip(r - spec.hole_radius_px, 0, 1).astype(np.float32)  # 0 inside, soft 1 px edge


def _splat(img: np.ndarray, pts: np.ndarray, weight: float) -> None:
    h, w = img.shape
    x, y = pts[:, 0], pts[:, 1]
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = x - x0, y - y0
    for dx, dy, ww in ((0, 0, (1 - fx) * (1 - fy)), (1, 0, fx * (1 - fy)), (0, 1, (1 - fx) * fy),
                       (1, 1, fx * fy)):
        xi, yi = x0 + dx, y0 + dy
        ok = (xi >= 0) & (xi < w) & (yi >= 0) & (yi < h)
        np.add.at(img, (yi[ok], xi[ok]), ww[ok] * weight)


def _exposure_samples(spec: LaserSpec, position: Trajectory, t0: float) -> np.ndarray:
    """Spot positions seen in frame starting at t0: uniform in time across the exposure, and with
    a rolling shutter only those whose row was exposing at that time."""
    h = spec.size[1]
    span = spec.exposure_s + spec.rolling_shutter_s
    probe = position(t0 + np.linspace(0, span, 64))
    length = float(np.sum(np.hypot(*np.diff(probe, axis=0).T)))
    n = int(min(20000, max(1, math.ceil(length / 0.3))))
    ts = t0 + (np.arange(n) + 0.5) * span / n
    pts = position(ts)
    if spec.rolling_shutter_s > 0:
        row_start = t0 + np.clip(pts[:, 1], 0, h - 1) / h * spec.rolling_shutter_s
        keep = (ts >= row_start) & (ts <= row_start + spec.exposure_s)
        pts = pts[keep]
    return pts


def render_laser(spec: LaserSpec, position: Trajectory | None = None) -> Iterator[np.ndarray]:
    """Yield ``spec.frames`` BGR uint8 frames of the laser screen."""
    rng = np.random.default_rng(spec.seed)
    position = position or pattern_trajectory(spec.pattern, spec.cycle_hz)
    w, h = spec.size
    hole = _hole_mask(spec)
    bg = _background(spec, rng)
    if hole is not None:
        bg = bg * hole + 8.0 * (1 - hole)
    base = cv2.merge([bg * np.float32(k) for k in spec.background_bgr])
    colour = np.array(spec.laser_bgr, np.float32)
    sig, hsig = spec.spot_sigma_px, spec.halo_sigma_px
    t_mid = (spec.frames - 1) / (2 * spec.fps)
    margin = int(4 * max(sig, hsig) + 3)
    noise = NoiseBank(spec.size, spec.noise_sigma, rng)
    for i in range(spec.frames):
        t0 = i / spec.fps
        pts = _exposure_samples(spec, position, t0)
        shift = np.array(spec.drift_px_s) * (t0 + spec.exposure_s / 2 - t_mid)
        if spec.jitter_px:
            shift = shift + rng.normal(0, spec.jitter_px, 2)
        pts = pts + shift
        img = base.copy()
        if len(pts):
            x0 = max(0, int(pts[:, 0].min()) - margin)
            x1 = min(w, int(pts[:, 0].max()) + margin + 2)
            y0 = max(0, int(pts[:, 1].min()) - margin)
            y1 = min(h, int(pts[:, 1].max()) + margin + 2)
            if x1 > x0 and y1 > y0:
                length = float(np.sum(np.hypot(*np.diff(pts, axis=0).T))) if len(pts) > 1 else 0.0
                peak = spec.brightness * 255.0
                total = peak * max(2 * math.pi * sig * sig, math.sqrt(2 * math.pi) * sig * length)
                roi = np.zeros((y1 - y0, x1 - x0), np.float32)
                _splat(roi, pts - [x0, y0], total / len(pts))
                light = cv2.GaussianBlur(roi, (0, 0), sig)
                if spec.halo_strength > 0 and hsig > 0:
                    light += cv2.GaussianBlur(roi, (0, 0), hsig) * (spec.halo_strength * hsig / sig)
                if hole is not None:
                    light *= hole[y0:y1, x0:x1]
                img[y0:y1, x0:x1] += light[:, :, None] * colour
        noise.add_to(img)
        yield cv2.convertScaleAbs(cv2.max(img, 0.0), alpha=1.0, beta=0.5)
