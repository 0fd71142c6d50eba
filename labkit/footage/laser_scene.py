"""Laser-trace footage: the spot reflected by the floating magnet onto the screen, filmed.

For every frame the spot's path is sampled densely in time over the frame's exposure (per row
under a rolling shutter: a sample at time t on row y is kept only if t lies in that row's window),
each sample carrying the energy of its time step (a slow spot is brighter), splatted bilinearly,
spread by the lens PSF, and added to the lit screen with its dark hole; the camera then develops
the frame (:mod:`labkit.footage.camera`). A photo is one frame with a long exposure.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import asdict, dataclass, field

import cv2
import numpy as np

from labkit.footage.camera import (
    Camera,
    Lighting,
    ambient_image,
    apply_psf,
    burn_timestamp,
    develop,
    flicker_rows,
    quantise,
)
from labkit.footage.motion import PrecessionNutation, SimulatedCone
from labkit.footage.mount import Mount
from labkit.footage.optics import Screen, ScreenView
from labkit.footage.truth import conic_truth, pattern_truth

SAMPLE_SPACING_PX = 0.25
LASER_BGR = (0.06, 0.22, 1.0)  # red laser through a colour sensor (some crosstalk)
SCREEN_BGR = (0.85, 0.95, 1.0)  # warm white screen under room light


@dataclass(frozen=True)
class StrayReflection:
    """A static stray reflection on the screen (a spot of laser light that does not move with the
    magnet): position in screen mm, radius px and peak level (full-well units)."""

    at_mm: tuple[float, float]
    radius_px: float = 3.0
    level: float = 1.5


@dataclass(frozen=True)
class LaserShot:
    """Everything that makes one laser clip or photo (see the module docstring).

    ``power``: irradiance of the trace line's core, in full-well units, for one pass of the spot
    (> 1 saturates); a long exposure that repeats the path is normalised to the same level.
    ``frames``: clip length (ignored for a photo)."""

    motion: PrecessionNutation | SimulatedCone
    screen: Screen
    view: ScreenView
    camera: Camera
    lighting: Lighting = field(default_factory=Lighting)
    mount: Mount = field(default_factory=Mount)
    frames: int = 60
    photo: bool = False
    power: float = 2.0
    reflection: StrayReflection | None = None
    seed: int = 0

    @property
    def n_frames(self) -> int:
        return 1 if self.photo else self.frames

    @property
    def t_mid_s(self) -> float:
        """Middle of the recording as the analysis reports it: the middle frame's start
        ``(frames - 1) / (2 fps)``, plus half an exposure (when its light was collected)."""
        return (self.n_frames - 1) / (2 * self.camera.fps) + self.camera.exposure_s / 2


def spot_px(shot: LaserShot, t: np.ndarray, with_mount: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Spot positions (N, 2) px at times ``t`` and a mask of those that land on the screen (not in
    the hole, not beyond the screen)."""
    uv = shot.screen.hits_mm(shot.motion.normals(t))
    on = np.isfinite(uv).all(axis=1) & (np.hypot(uv[:, 0], uv[:, 1]) > shot.screen.hole_mm)
    px = shot.view.to_px(np.nan_to_num(uv))
    if with_mount:
        px = px + shot.mount.offset(t)
    return px, on


def _cycle_length_px(shot: LaserShot) -> float:
    t = np.linspace(0.0, 1.0 / shot.motion.cycle_hz, 2049)
    px, _ = spot_px(shot, t, with_mount=False)
    return float(np.sum(np.hypot(*np.diff(px, axis=0).T)))


def _splat(px: np.ndarray, w: np.ndarray, roi: tuple[int, int, int, int]) -> np.ndarray:
    x0, y0, rw, rh = roi
    x, y = px[:, 0] - x0, px[:, 1] - y0
    ix, iy = np.floor(x).astype(int), np.floor(y).astype(int)
    fx, fy = x - ix, y - iy
    out = np.zeros(rw * rh, dtype=np.float64)
    corners = ((0, 0, (1 - fx) * (1 - fy)), (1, 0, fx * (1 - fy)), (0, 1, (1 - fx) * fy), (1, 1, fx * fy))
    for dx, dy, ww in corners:
        xx, yy = ix + dx, iy + dy
        ok = (xx >= 0) & (xx < rw) & (yy >= 0) & (yy < rh)
        out += np.bincount(yy[ok] * rw + xx[ok], weights=(w * ww)[ok], minlength=rw * rh)
    return out.reshape(rh, rw).astype(np.float32)


def trace_energy(shot: LaserShot, frame: int, cycle_px: float) -> tuple[np.ndarray, tuple[int, ...]]:
    """The laser light collected by each pixel in ``frame`` (after the PSF) in a region of the
    frame: ``(image, (x0, y0, w, h))``."""
    cam = shot.camera
    w, h = cam.size
    t0 = frame / cam.fps
    span = cam.exposure_s + cam.readout_s
    cycles = shot.motion.cycle_hz * span
    n = int(min(2_000_000, math.ceil(cycle_px * cycles / SAMPLE_SPACING_PX) + 64))
    t = t0 + (np.arange(n) + 0.5) * (span / n)
    px, on = spot_px(shot, t)
    start = cam.row_start_s(frame, np.clip(px[:, 1], 0, h - 1))
    on &= (t >= start) & (t <= start + cam.exposure_s)
    px = px[on]
    margin = int(math.ceil(3 * max(cam.psf_core_px, cam.psf_halo_px, cam.psf_glow_px))) + 4
    if len(px) == 0:
        return np.zeros((1, 1), np.float32), (0, 0, 1, 1)
    x0 = max(0, int(px[:, 0].min()) - margin)
    y0 = max(0, int(px[:, 1].min()) - margin)
    x1 = min(w, int(px[:, 0].max()) + margin + 2)
    y1 = min(h, int(px[:, 1].max()) + margin + 2)
    if x1 <= x0 or y1 <= y0:
        return np.zeros((1, 1), np.float32), (0, 0, 1, 1)
    # line density so that one pass has a core peak of ``power``: lambda = P sqrt(2 pi) sigma
    passes = max(1.0, shot.motion.cycle_hz * cam.exposure_s)
    density = shot.power * math.sqrt(2 * math.pi) * max(cam.psf_core_px, 0.5) / passes
    energy = np.full(len(px), density * cycle_px * cycles / n)  # energy of each time step
    roi = (x0, y0, x1 - x0, y1 - y0)
    return apply_psf(_splat(px, energy, roi), cam), roi


def _static_light(shot: LaserShot, frame: int, ambient: np.ndarray) -> np.ndarray:
    """Screen light (room light with gradient, lamp and flicker; ``ambient`` from
    :func:`ambient_image`) with the hole dark, and the static stray reflection, as linear BGR."""
    cam = shot.camera
    w, h = cam.size
    amb = ambient * flicker_rows(shot.lighting, cam, frame)[:, None]
    off = shot.mount.offset(frame / cam.fps + cam.exposure_s / 2)
    out = amb[..., None] * np.array(SCREEN_BGR, np.float32)
    if shot.screen.hole_mm > 0:
        cx, cy = shot.view.hole_px[0] + off[0], shot.view.hole_px[1] + off[1]
        r = shot.screen.hole_mm / shot.view.mm_per_px
        x0, y0 = max(0, int(cx - r) - 2), max(0, int(cy - r) - 2)
        x1, y1 = min(w, int(cx + r) + 3), min(h, int(cy + r) + 3)
        if x1 > x0 and y1 > y0:
            hole = np.zeros((y1 - y0, x1 - x0), np.uint8)
            centre = (int(round((cx - x0) * 16)), int(round((cy - y0) * 16)))
            cv2.circle(hole, centre, int(round(r * 16)), 255, -1, cv2.LINE_AA, 4)
            out[y0:y1, x0:x1] *= (1.0 - hole.astype(np.float32) / 255.0)[..., None]
    if shot.reflection is not None:
        ref = shot.reflection
        p = shot.view.to_px(np.array([ref.at_mm], float))[0] + off
        r = 4 * ref.radius_px
        x0, y0 = max(0, int(p[0] - r)), max(0, int(p[1] - r))
        x1, y1 = min(w, int(p[0] + r) + 2), min(h, int(p[1] + r) + 2)
        if x1 > x0 and y1 > y0:
            y, x = np.ogrid[y0:y1, x0:x1]
            blob = ref.level * np.exp(-((x - p[0]) ** 2 + (y - p[1]) ** 2) / (2 * ref.radius_px ** 2))
            out[y0:y1, x0:x1] += blob.astype(np.float32)[..., None] * np.array(LASER_BGR, np.float32)
    return out


def render_laser(shot: LaserShot) -> Iterator[np.ndarray]:
    """The clip's frames (or the photo) as 8-bit BGR images, in order."""
    rng = np.random.default_rng(shot.seed)
    cycle_px = _cycle_length_px(shot)
    colour = np.array(LASER_BGR, np.float32)
    ambient = ambient_image(shot.lighting, shot.camera.size)
    for k in range(shot.n_frames):
        linear = _static_light(shot, k, ambient)
        energy, (x0, y0, rw, rh) = trace_energy(shot, k, cycle_px)
        linear[y0:y0 + rh, x0:x0 + rw] += energy[..., None] * colour
        frame = develop(linear, shot.camera, rng)
        if shot.camera.timestamp:
            burn_timestamp(frame, k / shot.camera.fps, k)
        yield frame if shot.photo else quantise(frame, shot.camera.bitrate_quality)


def laser_truth(shot: LaserShot) -> dict:
    """Ground truth from the motion model: the pattern (centre at the middle of the recording),
    the tilt amplitudes, the arc per frame and the camera's path."""
    m, L = shot.motion, shot.screen.distance_mm
    off = shot.mount.offset(shot.t_mid_s)
    if isinstance(m, PrecessionNutation):
        if shot.screen.tilt_deg != 0:
            raise ValueError("a kinematic trochoid is exact only on a perpendicular screen (tilt_deg = 0)")
        hole = complex(*shot.view.hole_px) + complex(*off)
        c = hole + shot.view.complex_px(L * complex(*m.c))
        pattern = pattern_truth(c, shot.view.complex_px(L * complex(*m.A)),
                                shot.view.complex_px(L * complex(*m.B)), m.k)
    else:
        t = np.linspace(0, 1 / m.cycle_hz, 4096, endpoint=False)
        px, _ = spot_px(shot, t, with_mount=False)
        pattern = conic_truth(px + off)
    t_cycle = np.linspace(0, 1 / m.cycle_hz, 4096, endpoint=False)
    tilt = m.tilt_rad(t_cycle)
    cam = shot.camera
    frame_mid = np.arange(shot.n_frames) / cam.fps + cam.exposure_s / 2
    return {
        "kind": "laser", "photo": shot.photo, "frames": shot.n_frames, "fps": cam.fps,
        "size": list(cam.size), "exposure_s": cam.exposure_s, "readout_s": cam.readout_s,
        "pattern": pattern, "t_mid_s": shot.t_mid_s,
        "arc_cycles_per_frame": m.cycle_hz * cam.exposure_s,
        "screen_distance_mm": L, "mm_per_px": shot.view.mm_per_px,
        "tilt_rad": {"max": float(tilt.max()), "min": float(tilt.min())},
        "camera_moves": shot.mount.moves,
        "camera_offset_px": shot.mount.offset(frame_mid).tolist(),
        "spec": asdict(shot),
    }
