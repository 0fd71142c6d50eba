"""The camera as a camera: exposure windows per frame and per row (rolling shutter), the sensor
(linear response, full-well saturation, shot and read noise at high ISO, gamma encoding), the
point-spread function of the lens (core, halo and glow), the light on the scene (lamp gradients,
mains flicker at twice the mains frequency), static reflections, a burnt-in timestamp and the
lossy encoders (JPEG quality, and a per-frame DCT quantisation standing in for a camera's bit
rate before the mp4v encoder, whose own rate OpenCV does not expose).

Everything here works on linear irradiance images in units of the sensor's full well (1.0 is
saturation); :func:`develop` turns them into 8-bit BGR frames. Nothing here knows what is being
filmed: the laser and stroboscope scenes (:mod:`labkit.footage.laser_scene`,
:mod:`labkit.footage.strobe_scene`) hand it irradiance.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np


@dataclass(frozen=True)
class Camera:
    """A camera and its settings.

    ``size`` (width, height) px; ``fps``; ``exposure_s`` per frame (each row's window is this
    long); ``readout_s`` the rolling-shutter readout time from the first to the last row (0: global
    shutter). ``read_noise`` and ``shot_noise`` in full-well units (at high ISO both grow);
    ``gamma`` the encoding exponent (1/2.2 for sRGB-like, 1 for linear). ``psf_core_px``,
    ``psf_halo_px``/``halo_fraction`` and ``psf_glow_px``/``glow_fraction``: Gaussian core plus a
    halo and a wide glow holding those fractions of the light. ``jpeg_quality`` for photos, and
    ``bitrate_quality`` (JPEG-like quality 1-100, None for none) for the per-frame quantisation
    of video frames before mp4v. ``timestamp``: burn the frame time into the picture."""

    size: tuple[int, int] = (640, 480)
    fps: float = 30.0
    exposure_s: float = 1 / 60
    readout_s: float = 0.0
    read_noise: float = 0.004
    shot_noise: float = 0.0
    gamma: float = 1 / 2.2
    psf_core_px: float = 0.8
    psf_halo_px: float = 0.0
    halo_fraction: float = 0.0
    psf_glow_px: float = 0.0
    glow_fraction: float = 0.0
    jpeg_quality: int = 92
    bitrate_quality: int | None = None
    timestamp: bool = False

    @property
    def line_time_s(self) -> float:
        """Delay between the starts of successive rows' exposures."""
        return self.readout_s / max(1, self.size[1] - 1)

    def row_start_s(self, frame: int, rows: np.ndarray | float) -> np.ndarray:
        """Start of the exposure of ``rows`` (may be fractional) in ``frame``: frame ``k`` starts
        at ``k / fps`` on its first row."""
        return frame / self.fps + np.asarray(rows, dtype=float) * self.line_time_s


@dataclass(frozen=True)
class Lighting:
    """Light on the scene (linear full-well units per exposure of ``1 / 60`` s).

    ``level``: uniform part; ``gradient``: the change from one side of the frame to the other
    along ``gradient_deg`` (0 = towards +x); ``lamp``: a soft bright blob of this peak at
    ``lamp_xy`` (fraction of the frame) and radius ``lamp_radius`` (fraction of the width);
    ``flicker``: relative depth of the light's modulation at twice ``mains_hz`` (lamps on AC)."""

    level: float = 0.1
    gradient: float = 0.0
    gradient_deg: float = 0.0
    lamp: float = 0.0
    lamp_xy: tuple[float, float] = (0.8, 0.2)
    lamp_radius: float = 0.25
    flicker: float = 0.0
    mains_hz: float = 50.0


def ambient_image(lighting: Lighting, size: tuple[int, int]) -> np.ndarray:
    """Static pattern of the ambient light (float32, height x width), before flicker."""
    w, h = size
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    ang = math.radians(lighting.gradient_deg)
    along = ((x - w / 2) * math.cos(ang) + (y - h / 2) * math.sin(ang)) / max(w, h)
    img = lighting.level + lighting.gradient * along
    if lighting.lamp > 0:
        lx, ly = lighting.lamp_xy[0] * w, lighting.lamp_xy[1] * h
        r = lighting.lamp_radius * w
        img = img + lighting.lamp * np.exp(-((x - lx) ** 2 + (y - ly) ** 2) / (2 * r * r))
    return np.clip(img, 0.0, None).astype(np.float32)


def flicker_rows(lighting: Lighting, camera: Camera, frame: int) -> np.ndarray:
    """Per-row factor of the ambient light: the mean of ``1 + depth cos(2 pi 2 f_mains t)`` over
    each row's exposure window (rows see different phases under a rolling shutter)."""
    rows = np.arange(camera.size[1], dtype=float)
    t0 = camera.row_start_s(frame, rows)
    if lighting.flicker <= 0:
        return np.ones_like(t0, dtype=np.float32)
    w = 2 * math.pi * 2 * lighting.mains_hz
    e = camera.exposure_s
    mean_cos = (np.sin(w * (t0 + e)) - np.sin(w * t0)) / (w * e)
    return (1 + lighting.flicker * mean_cos).astype(np.float32)


def gaussian(image: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian blur; wide kernels run on a reduced copy (the glow is smooth)."""
    if sigma <= 0.05:
        return image
    if sigma < 6:
        return cv2.GaussianBlur(image, (0, 0), sigma)
    f = max(2, int(sigma // 3))
    h, w = image.shape[:2]
    small = cv2.resize(image, (max(1, w // f), max(1, h // f)), interpolation=cv2.INTER_AREA)
    small = cv2.GaussianBlur(small, (0, 0), sigma / f)
    return cv2.resize(small, (w, h), interpolation=cv2.INTER_LINEAR)


def apply_psf(energy: np.ndarray, camera: Camera) -> np.ndarray:
    """Spread point energy by the lens: core, halo and glow (each normalised, so light is kept)."""
    core = 1.0 - camera.halo_fraction - camera.glow_fraction
    out = core * gaussian(energy, camera.psf_core_px)
    if camera.halo_fraction > 0:
        out += camera.halo_fraction * gaussian(energy, camera.psf_halo_px)
    if camera.glow_fraction > 0:
        out += camera.glow_fraction * gaussian(energy, camera.psf_glow_px)
    return out


def _gamma_table(gamma: float, levels: int = 4096) -> np.ndarray:
    x = np.linspace(0.0, 1.0, levels)
    return np.clip(x ** gamma * 255.0 + 0.5, 0, 255).astype(np.uint8)


def develop(linear_bgr: np.ndarray, camera: Camera, rng: np.random.Generator) -> np.ndarray:
    """Sensor and pipeline: shot + read noise on the linear signal, clip at full well (saturation),
    gamma encode, quantise to 8 bits. ``linear_bgr`` is float32 (h, w, 3) in full-well units and
    is overwritten."""
    sig = np.maximum(linear_bgr, 0.0, out=linear_bgr)
    sigma = sig * np.float32(camera.shot_noise ** 2)
    sigma += np.float32(camera.read_noise ** 2)
    np.sqrt(sigma, out=sigma)
    sigma *= rng.standard_normal(sig.shape, dtype=np.float32)
    sig += sigma
    np.clip(sig, 0.0, 1.0, out=sig)
    sig *= 4095.0
    return _gamma_table(camera.gamma)[sig.astype(np.uint16)]


def burn_timestamp(frame: np.ndarray, t_s: float, index: int) -> None:
    """Write the camera's date-time and frame number into the picture's bottom-left corner."""
    h, w = frame.shape[:2]
    scale = max(0.35, w / 1600)
    ms = int(round(t_s * 1000))
    text = f"2026-11-24 10:{ms // 60000 % 60:02d}:{ms // 1000 % 60:02d}.{ms % 1000:03d}  #{index:05d}"
    org = (int(0.02 * w), int(h - 0.03 * h))
    thick = max(1, int(round(2 * scale)))
    cv2.putText(frame, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, (0, 0, 0), thick + 2, cv2.LINE_AA)
    cv2.putText(frame, text, org, cv2.FONT_HERSHEY_SIMPLEX, scale, (235, 235, 235), thick, cv2.LINE_AA)


def quantise(frame: np.ndarray, quality: int | None) -> np.ndarray:
    """A camera's lossy encoding at a given quality (JPEG round trip: 8x8 DCT quantisation and
    4:2:0 chroma); None returns the frame unchanged."""
    if quality is None:
        return frame
    ok, buf = cv2.imencode(".jpg", frame, [cv2.IMWRITE_JPEG_QUALITY, int(quality)])
    if not ok:  # pragma: no cover - OpenCV always encodes a valid uint8 image
        raise RuntimeError("JPEG encoding failed")
    return cv2.imdecode(buf, cv2.IMREAD_COLOR)
