"""A small stroboscope scene renderer for the strobe tests, written independently of
``labkit.synth.strobe`` (no shared code or conventions beyond Eq. 5.97) so that the analysis is
not only tested against the generator it grew up with.

Physics of the scene: the body tilts in the image plane by ``theta(t) = phi sin(2 pi f_rot t + p0)``
about its rest axis, which points at ``rest_deg`` from image +x (any camera roll; 90 = vertical,
0 = horizontal as for a rotor spinning about a horizontal axis, Fig. 5.19). Its centre of mass
moves across the rest axis by ``-delta tan(theta)`` (Eq. 5.97), so the lateral amplitude is
``beta = delta tan(phi)``.

Camera: frame k exposes rows ``r`` during ``[k / fps + r readout / h, ... + exposure]``. Light
comes from lamp flashes at ``t_j = t0 + j / strobe_hz`` (each flash paints the body at its own
rotor phase), or, with ``strobe_hz=None``, from continuous light, sampled densely within the
exposure (the camera is the strobe, Fig. 6.20). Extra light: an ambient ghost of the whole
revolution, a flash shadow of the body on the background, per-frame flicker, sensor noise.
Bodies are drawn by 4x supersampled polygons (cv2.fillPoly, area-averaged).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

SUPER = 4


@dataclass
class Scene:
    size: tuple[int, int] = (320, 240)
    frames: int = 90
    fps: float = 30.0
    exposure_s: float = 1 / 60
    readout_s: float = 0.0  # rolling shutter: first to last row
    rotor_hz: float = 200.0
    strobe_hz: float | None = 199.5  # None: continuous light, the short exposure is the strobe
    phi_rad: float = 0.12
    delta_px: float = 40.0  # Eq. 5.97; the rotation centre lies on the axis towards the end opposite rest_deg
    rest_deg: float = 90.0  # rest axis direction from image +x, counter-clockwise as seen on screen
    length_px: float = 80.0
    width_px: float = 20.0  # equal to length for a cube
    centre_px: tuple[float, float] = (160.0, 120.0)
    dark_body: bool = True
    ghost: float = 0.0  # ambient light fraction: blurred image of the whole revolution
    shadow: float = 0.0  # darkness of the flash shadow (0..1 of the body's contrast)
    shadow_offset_px: tuple[float, float] = (14.0, 6.0)
    flicker: float = 0.0  # relative per-frame brightness swing
    noise: float = 2.0
    phase0_rad: float = 0.4
    seed: int = 0
    jpeg: int | None = None  # JPEG quality applied to each frame (None: none)
    extra: dict = field(default_factory=dict)

    @property
    def beta_px(self) -> float:
        return abs(self.delta_px) * math.tan(self.phi_rad)


def _corners(s: Scene, theta: float) -> np.ndarray:
    a = math.radians(s.rest_deg) + theta  # screen angles: counter-clockwise with y up
    u = np.array([math.cos(a), -math.sin(a)])  # image coords (y down)
    a0 = math.radians(s.rest_deg)
    n0 = np.array([math.sin(a0), math.cos(a0)])  # rest axis normal, image coords
    cm = np.array(s.centre_px) - s.delta_px * math.tan(theta) * n0
    n = np.array([-u[1], u[0]])
    hl, hw = s.length_px / 2, s.width_px / 2
    return np.array([cm + hl * u + hw * n, cm + hl * u - hw * n, cm - hl * u - hw * n, cm - hl * u + hw * n])


def _cover(s: Scene, theta: float, offset=(0.0, 0.0)) -> np.ndarray:
    w, h = s.size
    big = np.zeros((h * SUPER, w * SUPER), np.uint8)
    pts = (_corners(s, theta) + np.array(offset) + 0.5) * SUPER - 0.5
    cv2.fillPoly(big, [np.round(pts * 16).astype(np.int32)], 255, lineType=cv2.LINE_8, shift=4)
    return cv2.resize(big, (w, h), interpolation=cv2.INTER_AREA).astype(np.float32) / 255.0


def _theta(s: Scene, t: float) -> float:
    return s.phi_rad * math.sin(2 * math.pi * s.rotor_hz * t + s.phase0_rad)


def _light_times(s: Scene, t0: float, t1: float) -> list[float]:
    if s.strobe_hz is None:
        n = 9
        return [t0 + (i + 0.5) * (t1 - t0) / n for i in range(n)]
    j0, j1 = math.ceil(t0 * s.strobe_hz - 1e-9), math.floor(t1 * s.strobe_hz - 1e-9)
    return [j / s.strobe_hz for j in range(j0, j1 + 1)]


def render(s: Scene) -> list[np.ndarray]:
    """BGR uint8 frames of the scene."""
    w, h = s.size
    rng = np.random.default_rng(s.seed)
    bg, body = (190.0, 40.0) if s.dark_body else (35.0, 200.0)
    ghost = None
    if s.ghost:
        phases = np.linspace(0, 2 * np.pi, 24, endpoint=False)
        ghost = np.mean([_cover(s, s.phi_rad * math.sin(p)) for p in phases], axis=0)
    bands = 12 if s.readout_s else 1
    edges = np.linspace(0, h, bands + 1).astype(int)
    per_flash = s.exposure_s * (s.strobe_hz or 1.0)
    out = []
    for k in range(s.frames):
        cover = np.zeros((h, w), np.float32)
        shadow = np.zeros((h, w), np.float32)
        light = np.zeros((h, 1), np.float32)
        for b in range(bands):
            r0, r1 = edges[b], edges[b + 1]
            t0 = k / s.fps + s.readout_s * (r0 + r1) / 2 / h
            times = _light_times(s, t0, t0 + s.exposure_s)
            for t in times:
                c = _cover(s, _theta(s, t))
                cover[r0:r1] += c[r0:r1]
                if s.shadow:
                    shadow[r0:r1] += _cover(s, _theta(s, t), s.shadow_offset_px)[r0:r1]
            light[r0:r1] = max(len(times), 1)
            if not times:
                light[r0:r1] = 0.0
        cover /= np.maximum(light, 1)
        shadow /= np.maximum(light, 1)
        flash_frac = light / (per_flash if s.strobe_hz else 9.0)
        gain = 1.0 + s.flicker * math.sin(2 * math.pi * 100.0 * k / s.fps)
        shadow = np.clip(shadow - cover, 0, 1) * s.shadow
        img = bg + (body - bg) * (cover + shadow)
        if ghost is not None:  # ambient light adds the time-average of the whole revolution
            img = (1 - s.ghost) * img + s.ghost * (bg + (body - bg) * ghost)
        img = img * gain * np.clip(flash_frac, 0.6, 1.4) + rng.normal(0, s.noise, (h, w))
        frame = cv2.cvtColor(np.clip(img, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR)
        if s.jpeg:
            frame = cv2.imdecode(cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, s.jpeg])[1],
                                 cv2.IMREAD_COLOR)
        out.append(frame)
    return out


def write(s: Scene, path, fps_in_file: float | None = None) -> str:
    """Write the scene as an MJPG .avi (near-lossless) with ``fps_in_file`` (default the true rate)."""
    frames = render(s)
    w, h = s.size
    vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps_in_file or s.fps, (w, h))
    for f in frames:
        vw.write(f)
    vw.release()
    return str(path)


def tilt_ok(got: float, want: float) -> bool:
    """The acceptance: tilt within 5 % or 0.005 rad."""
    return abs(got - want) <= max(0.05 * abs(want), 0.005)


def lateral_ok(got: float, want: float) -> bool:
    """The acceptance: lateral amplitude within 5 % or 0.5 px."""
    return abs(got - want) <= max(0.05 * abs(want), 0.5)
