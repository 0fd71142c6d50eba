"""Render stroboscopic side-view footage of a floating magnet (Fig. 6.14, 6.20).

The body (a rectangle, axis vertical at rest) tilts in the image plane by ``theta = phi sin(psi)``
while its centre of mass moves laterally so that the body axis always passes through a rotation
centre a distance ``delta`` above the centre of mass: ``x_cm = x_c - delta tan(theta)``, whose
amplitude is ``beta = delta tan(phi)`` (Eq. 5.97). The strobe samples the rotor phase
``psi_k = 2 pi rotor_hz k / strobe_hz`` (one flash per frame); the apparent motion repeats at the
alias of ``rotor_hz`` against ``strobe_hz``. Impairments: rolling shutter (the phase advances down
the rows), motion blur (phase span of the exposure), noise, background gradient, compression.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass

import cv2
import numpy as np

from labkit.synth.laser import NoiseBank


@dataclass
class StrobeSpec:
    """A synthetic stroboscope clip. Lengths in px, angles in rad, frequencies in Hz."""

    size: tuple[int, int] = (320, 240)
    frames: int = 48
    rotor_hz: float = 240.0
    strobe_hz: float = 15.15  # one flash per frame; the clip's frame rate
    tilt_amplitude_rad: float = 0.25
    rc_offset_px: float = 60.0  # rotation centre above the centre of mass (Eq. 5.97)
    center_px: tuple[float, float] = (160.0, 130.0)  # centre of mass at zero tilt
    body_length_px: float = 70.0
    body_width_px: float = 24.0
    dark_body: bool = True
    phase0_rad: float = 0.3
    rolling_shutter_rad: float = 0.0  # rotor phase advance from the top row to the bottom row
    blur_rad: float = 0.0  # rotor phase span of one exposure
    noise_sigma: float = 3.0
    gradient: float = 0.0
    codec: str = "mp4v"
    seed: int = 0

    def to_dict(self) -> dict:
        return asdict(self)

    @property
    def apparent_hz(self) -> float:
        """Alias of the rotor frequency against the strobe, folded into [-f_s/2, f_s/2)."""
        ratio = self.rotor_hz / self.strobe_hz
        return (ratio - round(ratio)) * self.strobe_hz


def strobe_truth(spec: StrobeSpec) -> dict:
    """Ground truth in the layout of ``labkit analyse strobe``."""
    beta = abs(spec.rc_offset_px) * math.tan(spec.tilt_amplitude_rad)
    phases = [(spec.phase0_rad + 2 * math.pi * spec.rotor_hz * k / spec.strobe_hz) % (2 * math.pi)
              for k in range(spec.frames)]
    return {"kind": "strobe", "spec": spec.to_dict(), "frames": spec.frames,
            "apparent_hz": abs(spec.apparent_hz), "tilt_amplitude_rad": spec.tilt_amplitude_rad,
            "lateral_amplitude_px": beta, "rc_offset_px": abs(spec.rc_offset_px),
            "phase_per_frame": phases}


def tilt_from_angles(times_s: np.ndarray, tilt_rad: np.ndarray) -> Callable[[float], float]:
    """A tilt track from a simulator run (angle in the image plane over time), linearly
    interpolated and repeated with the run's period, for ``render_strobe(spec, tilt_of_time=...)``."""
    t = np.asarray(times_s, float)
    a = np.asarray(tilt_rad, float)
    period = t[-1] - t[0]

    def tilt(time_s: float) -> float:
        return float(np.interp(t[0] + (time_s - t[0]) % period, t, a))

    return tilt


def body_polygon(spec: StrobeSpec, psi: float, theta: float | None = None) -> np.ndarray:
    """Corners (4, 2) of the body at rotor phase psi, or at tilt ``theta`` if given (image
    coordinates, y down)."""
    if theta is None:
        theta = spec.tilt_amplitude_rad * math.sin(psi)
    cx = spec.center_px[0] - spec.rc_offset_px * math.tan(theta)
    cy = spec.center_px[1]
    u = np.array([math.sin(theta), -math.cos(theta)])  # along the axis, up
    n = np.array([math.cos(theta), math.sin(theta)])
    hl, hw = spec.body_length_px / 2, spec.body_width_px / 2
    c = np.array([cx, cy])
    return np.array([c + hl * u + hw * n, c + hl * u - hw * n, c - hl * u - hw * n, c - hl * u + hw * n])


def _draw(spec: StrobeSpec, psi: float, tilt_of_time: Callable[[float], float] | None) -> np.ndarray:
    w, h = spec.size
    img = np.zeros((h, w), np.uint8)
    theta = None
    if tilt_of_time is not None:  # rotor phase -> time since the first flash
        theta = tilt_of_time((psi - spec.phase0_rad) / (2 * math.pi * spec.rotor_hz))
    pts = np.round(body_polygon(spec, psi, theta) * 16).astype(np.int32)
    cv2.fillPoly(img, [pts], 255, lineType=cv2.LINE_AA, shift=4)
    return img.astype(np.float32) / 255.0


def render_strobe(spec: StrobeSpec, tilt_of_time: Callable[[float], float] | None = None
                  ) -> Iterator[np.ndarray]:
    """Yield ``spec.frames`` BGR uint8 frames. ``tilt_of_time(t_s)`` (e.g. from a simulator via
    :func:`tilt_from_angles`) replaces the sinusoidal tilt ``phi sin(psi)``; frame k is flashed at
    ``t = k / strobe_hz`` and rows or blur samples at the matching rotor phase."""
    w, h = spec.size
    noise = NoiseBank(spec.size, spec.noise_sigma, np.random.default_rng(spec.seed))
    y, x = np.mgrid[0:h, 0:w].astype(np.float32)
    bg_level, body_level = (200.0, 35.0) if spec.dark_body else (30.0, 210.0)
    bg = bg_level + spec.gradient * (x / w - 0.5 + 0.5 * (y / h - 0.5))
    bands = 24 if spec.rolling_shutter_rad else 1
    blur_n = 7 if spec.blur_rad else 1
    for k in range(spec.frames):
        psi0 = spec.phase0_rad + 2 * math.pi * spec.rotor_hz * k / spec.strobe_hz
        cover = np.zeros((h, w), np.float32)
        edges = np.linspace(0, h, bands + 1).astype(int)
        for bi in range(bands):
            r0, r1 = edges[bi], edges[bi + 1]
            psi_row = psi0 + spec.rolling_shutter_rad * ((r0 + r1) / 2 / h - 0.5)
            acc = np.zeros((h, w), np.float32)
            for j in range(blur_n):
                off = spec.blur_rad * ((j + 0.5) / blur_n - 0.5)
                acc += _draw(spec, psi_row + off, tilt_of_time)
            cover[r0:r1] = acc[r0:r1] / blur_n
        img = bg * (1 - cover) + body_level * cover
        img = cv2.merge([img, img, img])
        noise.add_to(img)
        yield cv2.convertScaleAbs(cv2.max(img, 0.0), alpha=1.0, beta=0.5)
