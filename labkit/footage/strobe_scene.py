"""Stroboscope footage: the floating body, lit by a strobe lamp that flashes on its own clock,
filmed by an ordinary camera.

Motion (Eq. 5.97): the rotor turns at ``rotor_hz``; with ``psi = 2 pi rotor_hz t + psi0`` the body
axis tilts by ``theta = phi sin(psi)`` from its rest axis (in the image plane) and the centre of
mass moves across the rest axis by ``-delta tan(theta)`` (``delta``: the offset of the rotation
centre from the centre of mass along the axis). The rest axis points at ``rest_deg`` in the world
(0 = vertical, 90 = horizontal as for a rotor spinning about a horizontal axis, Fig. 5.19); the
camera's roll adds to it in the image.

Light: the lamp flashes at ``t_j = t0 + j / strobe_hz`` (each flash ``flash_s`` long), whatever
the camera's frame rate. A row of frame k records the flashes inside its exposure window (per row
under a rolling shutter), so a frame holds 1-6 images of the body at nearly the same apparent
phase: flash to flash the rotor turns ``rotor_hz / strobe_hz`` revolutions, and the apparent
motion runs in real time at ``f_rot - m f_strobe`` (``m`` the harmonic, the nearest integer to
``rotor_hz / strobe_hz``). Room light during the whole exposure adds a ghost of the revolution.
Without a lamp (``strobe_hz = None``) the camera's short exposure is the strobe (Fig. 6.20).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from labkit.footage.body import Body, coverage, outline
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
from labkit.footage.mount import Mount
from labkit.footage.sim_swing import SimulatedSwing

GHOST_SAMPLES = 12
FLASH_SUBSAMPLES = 3
SHUTTER_SUBSAMPLES = 8


@dataclass(frozen=True)
class Swing:
    """Eq. 5.97 motion: tilt amplitude ``phi_rad``, RC offset ``delta_px`` (signed, along the
    axis), rotor frequency and phase at t = 0."""

    phi_rad: float = 0.12
    delta_px: float = 60.0
    rotor_hz: float = 200.0
    psi0_rad: float = 0.0

    def psi(self, t: np.ndarray | float) -> np.ndarray:
        return 2 * math.pi * self.rotor_hz * np.asarray(t, dtype=float) + self.psi0_rad

    def tilt(self, t: np.ndarray | float) -> np.ndarray:
        return self.phi_rad * np.sin(self.psi(t))

    def lateral_px(self, t: np.ndarray | float) -> np.ndarray:
        return -self.delta_px * np.tan(self.tilt(t))


@dataclass(frozen=True)
class Lamp:
    """Strobe lamp: ``hz`` (None: no lamp, the camera's exposure is the strobe), first flash at
    ``t0_s``, each ``flash_s`` long; ``shadow_px`` offset and ``shadow_depth`` of the body's
    shadow on the background (the lamp is beside the camera)."""

    hz: float | None = 200.0
    t0_s: float = 0.0
    flash_s: float = 20e-6
    shadow_px: tuple[float, float] = (0.0, 0.0)
    shadow_depth: float = 0.0


@dataclass(frozen=True)
class StrobeShot:
    """Everything that makes one stroboscope clip. ``backlit``: a dark body against a lit
    background (else a bright body on a dark one); ``ambient``: room light during the exposure
    relative to the lamp (the ghost of the revolution)."""

    body: Body
    swing: Swing | SimulatedSwing  # kinematic (Eq. 5.97) or integrated by labkit.sim
    lamp: Lamp
    camera: Camera
    centre_px: tuple[float, float]
    rest_deg: float = 0.0
    roll_deg: float = 0.0
    lighting: Lighting = field(default_factory=lambda: Lighting(level=0.0))
    ambient: float = 0.0
    mount: Mount = field(default_factory=Mount)
    backlit: bool = True
    frames: int = 60
    seed: int = 0

    @property
    def axis_image_deg(self) -> float:
        return self.rest_deg + self.roll_deg


def pose(shot: StrobeShot, t: float) -> tuple[tuple[float, float], float]:
    """Centre of mass (px) and axis direction (deg from image-up towards +x) at time ``t``."""
    rest = math.radians(shot.axis_image_deg)
    across = np.array([math.cos(rest), math.sin(rest)])
    off = shot.mount.offset(t)
    c = np.asarray(shot.centre_px) + off + across * float(shot.swing.lateral_px(t))
    return (float(c[0]), float(c[1])), shot.axis_image_deg + math.degrees(float(shot.swing.tilt(t)))


def _silhouette(shot: StrobeShot, t: float, roi: tuple[int, int, int, int]) -> np.ndarray:
    centre, axis = pose(shot, t)
    return coverage(outline(centre, axis, shot.body.length_px, shot.body.apparent_width(t)), roi)


def light_times(shot: StrobeShot, frame: int) -> tuple[np.ndarray, np.ndarray]:
    """Times (s) at which light reaches the sensor during ``frame`` (all rows), and each one's
    weight (energy in units of a full exposure's worth of light)."""
    cam = shot.camera
    t_start, t_end = frame / cam.fps, frame / cam.fps + cam.exposure_s + cam.readout_s
    lamp = shot.lamp
    if lamp.hz is None:
        n = SHUTTER_SUBSAMPLES * max(1, int(math.ceil((t_end - t_start) / cam.exposure_s)))
        t = t_start + (np.arange(n) + 0.5) * (t_end - t_start) / n
        return t, np.full(n, (t_end - t_start) / n / cam.exposure_s)
    j0 = math.ceil((t_start - lamp.t0_s) * lamp.hz)
    j1 = math.floor((t_end - lamp.t0_s) * lamp.hz)
    flashes = lamp.t0_s + np.arange(j0, j1 + 1) / lamp.hz
    per_exposure = max(1e-9, cam.exposure_s * lamp.hz)
    sub = (np.arange(FLASH_SUBSAMPLES) + 0.5) / FLASH_SUBSAMPLES * lamp.flash_s
    t = (flashes[:, None] + sub[None, :]).ravel()
    return t, np.full(len(t), 1.0 / (per_exposure * FLASH_SUBSAMPLES))


def _roi(shot: StrobeShot) -> tuple[int, int, int, int]:
    w, h = shot.camera.size
    reach = shot.body.radius_px + abs(shot.swing.delta_px * math.tan(shot.swing.phi_rad))
    reach += math.hypot(*shot.lamp.shadow_px) + 3 * shot.mount.wander_px + 4 * shot.mount.shake_px + 6
    reach += 4 * max(shot.camera.psf_core_px, shot.camera.psf_halo_px if shot.camera.halo_fraction else 0.0)
    t_all = np.array([0.0, shot.frames / shot.camera.fps])
    offs = shot.mount.offset(t_all)
    cx0, cy0 = shot.centre_px[0] + offs[:, 0].min(), shot.centre_px[1] + offs[:, 1].min()
    cx1, cy1 = shot.centre_px[0] + offs[:, 0].max(), shot.centre_px[1] + offs[:, 1].max()
    x0, y0 = max(0, int(cx0 - reach)), max(0, int(cy0 - reach))
    x1, y1 = min(w, int(cx1 + reach) + 2), min(h, int(cy1 + reach) + 2)
    return x0, y0, x1 - x0, y1 - y0


def _ghost(shot: StrobeShot, roi: tuple[int, int, int, int], t_mid: float) -> np.ndarray:
    period = 1.0 / shot.swing.rotor_hz if shot.swing.rotor_hz else 0.0
    ts = t_mid + (np.arange(GHOST_SAMPLES) + 0.5) / GHOST_SAMPLES * period
    return sum(_silhouette(shot, float(t), roi) for t in ts) / GHOST_SAMPLES


def render_strobe(shot: StrobeShot) -> Iterator[np.ndarray]:
    """The clip's frames as 8-bit BGR images, in order."""
    cam = shot.camera
    w, h = cam.size
    rng = np.random.default_rng(shot.seed)
    bg_level, body_level = (0.55, 0.04) if shot.backlit else (0.03, 0.6)
    lighting = shot.lighting
    base = ambient_image(lighting, cam.size) if lighting.level or lighting.gradient or lighting.lamp else None
    roi = _roi(shot)
    x0, y0, rw, rh = roi
    rows = np.arange(h, dtype=float)
    sx, sy = shot.lamp.shadow_px
    lens = replace(cam, glow_fraction=0.0)  # core and halo (the wide glow matters for bright spots only)
    for k in range(shot.frames):
        starts = cam.row_start_s(k, rows)
        flash = np.zeros(h, np.float32)  # lamp light per row
        body_energy = np.zeros((rh, rw), np.float32)  # change by the body and its shadow, in the roi
        t, weight = light_times(shot, k)
        for tj, wj in zip(t, weight, strict=True):
            seen = ((tj >= starts) & (tj <= starts + cam.exposure_s)).astype(np.float32) * wj
            if not seen.any():
                continue
            flash += seen
            if not seen[y0:y0 + rh].any():
                continue
            mask = _silhouette(shot, float(tj), roi)
            lit_bg = 1.0 - mask
            if shot.lamp.shadow_depth > 0:
                shadow = _silhouette(shot, float(tj), (x0 - int(round(sx)), y0 - int(round(sy)), rw, rh))
                lit_bg *= 1.0 - shot.lamp.shadow_depth * shadow
            part = bg_level * lit_bg + body_level * mask
            body_energy += seen[y0:y0 + rh, None] * (part - bg_level)
        if shot.lamp.hz is None:  # room light: each row's mean over its own window, whatever the sampling
            body_energy /= np.maximum(flash[y0:y0 + rh, None], 1e-9)
            flash[:] = 1.0
        image = np.repeat(bg_level * flash[:, None], w, axis=1)
        # lens blur of the body's edges (core and halo; the wide glow matters for bright spots only)
        image[y0:y0 + rh, x0:x0 + rw] += apply_psf(body_energy, lens)
        if shot.ambient > 0:
            # the room light's image of the revolution passes through the same lens as the flashes'
            ghost = apply_psf(_ghost(shot, roi, k / cam.fps + cam.exposure_s / 2), lens)
            amb = np.full((h, w), shot.ambient * bg_level, np.float32)
            amb[y0:y0 + rh, x0:x0 + rw] += shot.ambient * (body_level - bg_level) * ghost
            image += amb * flicker_rows(lighting, cam, k)[:, None]
        if base is not None:
            image += base * flicker_rows(lighting, cam, k)[:, None]
        linear = np.repeat(image[..., None], 3, axis=2)
        frame = develop(linear, cam, rng)
        if cam.timestamp:
            burn_timestamp(frame, k / cam.fps, k)
        yield quantise(frame, cam.bitrate_quality)


def harmonic(shot: StrobeShot) -> int:
    """The strobe harmonic m: the nearest integer to rotor_hz / strobe_hz (or / fps without a lamp)."""
    f = shot.lamp.hz or shot.camera.fps
    return max(1, int(round(shot.swing.rotor_hz / f)))


def strobe_truth(shot: StrobeShot) -> dict:
    """Ground truth from the motion model: phi, the lateral amplitude ``|delta| tan(phi)`` across
    the rest axis, delta, the apparent frequency ``f_rot - m f_strobe`` (signed, in real time),
    flashes per exposure, orientation, and per frame the mean phase, tilt and centre of mass of
    the light that made it (middle row)."""
    cam, sw = shot.camera, shot.swing
    f_strobe = shot.lamp.hz or cam.fps
    m = harmonic(shot)
    per_frame = []
    mid_row = (cam.size[1] - 1) / 2
    for k in range(shot.frames):
        t, weight = light_times(shot, k)
        start = float(cam.row_start_s(k, mid_row))
        keep = (t >= start) & (t <= start + cam.exposure_s)
        tk = t[keep] if keep.any() else np.array([start + cam.exposure_s / 2])
        psi = sw.psi(tk)
        phase = float(np.angle(np.mean(np.exp(1j * psi))) % (2 * math.pi))
        centres = np.array([pose(shot, float(x))[0] for x in tk])
        per_frame.append({"t_s": float(tk.mean()), "phase_rad": phase, "flashes": int(keep.sum() // (
            1 if shot.lamp.hz is None else FLASH_SUBSAMPLES)), "tilt_rad": float(np.mean(sw.tilt(tk))),
            "centre_px": centres.mean(axis=0).tolist()})
    return {
        "kind": "strobe", "frames": shot.frames, "fps": cam.fps, "size": list(cam.size),
        "exposure_s": cam.exposure_s, "readout_s": cam.readout_s,
        "tilt_amplitude_rad": sw.phi_rad, "lateral_amplitude_px": abs(sw.delta_px) * math.tan(sw.phi_rad),
        "rc_offset_px": abs(sw.delta_px), "rotor_hz": sw.rotor_hz, "strobe_hz": shot.lamp.hz,
        "harmonic": m, "apparent_hz": sw.rotor_hz - m * f_strobe,
        "flashes_per_exposure": None if shot.lamp.hz is None else cam.exposure_s * shot.lamp.hz,
        "camera_is_strobe": shot.lamp.hz is None, "body": shot.body.shape,
        "rest_deg": shot.rest_deg, "roll_deg": shot.roll_deg, "axis_image_deg": shot.axis_image_deg,
        "analysis_inputs": {"rotor_hz": sw.rotor_hz, **({"strobe_hz": shot.lamp.hz} if shot.lamp.hz else {})},
        "per_frame": per_frame, "spec": asdict(shot),
    }
