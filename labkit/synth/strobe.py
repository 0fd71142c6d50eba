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


BODY_POINT_OFFSETS = {"tip": 0.5, "bottom": -0.5, "centroid": 0.0}  # along the axis, in body lengths


def body_point_positions(spec: StrobeSpec, point: str, phases_rad: np.ndarray) -> np.ndarray:
    """True image positions (N, 2) of a body point at rotor phases ``psi`` (Eq. 5.97): tilt
    ``theta = phi sin(psi)``, centre of mass ``x_cm = x_c - delta tan(theta)`` at the fixed height
    of ``center_px``, and the point ``s`` px up the body axis (``s = +L/2`` tip, ``-L/2`` bottom,
    0 centroid): ``(x_cm + s sin(theta), y_c - s cos(theta))`` (image y points down)."""
    s = BODY_POINT_OFFSETS[point] * spec.body_length_px
    theta = spec.tilt_amplitude_rad * np.sin(np.asarray(phases_rad, float))
    x = spec.center_px[0] - spec.rc_offset_px * np.tan(theta) + s * np.sin(theta)
    y = spec.center_px[1] - s * np.cos(theta)
    return np.column_stack([x, y])


def first_harmonic_ellipse(points: np.ndarray, phases_rad: np.ndarray) -> dict:
    """Least-squares ellipse ``c + A e^{i psi} + B e^{-i psi}`` of points with known phases,
    as centre, semi-axes ``|A| +- |B|`` (major first) and the major axis's angle in [0, 180) deg.
    Solved here with numpy alone so that it serves as an independent truth for the analysis."""
    z = points[:, 0] + 1j * points[:, 1]
    psi = np.asarray(phases_rad, float)
    m = np.column_stack([np.ones_like(z), np.exp(1j * psi), np.exp(-1j * psi)])
    (c, a, b), *_ = np.linalg.lstsq(m, z, rcond=None)
    rotation = math.degrees(0.5 * (np.angle(a) + np.angle(b))) % 180.0 if abs(b) > 0 else 0.0
    return {"center_px": [float(c.real), float(c.imag)],
            "semi_axes_px": [float(abs(a) + abs(b)), float(abs(abs(a) - abs(b)))],
            "rotation_deg": float(rotation),
            "rms_residual_px": float(np.sqrt(np.mean(np.abs(z - m @ np.array([c, a, b])) ** 2)))}


def point_truth(spec: StrobeSpec, phases_rad: np.ndarray) -> dict:
    """Truth of the body-point trajectories (tip, bottom, centroid) at the flash phases: the true
    positions per frame, their half ranges in x and y (``extent_px``; the tip swings on a flat
    arc, so its y half range is the sag ``L/2 (1 - cos phi) / 2``) and their first-harmonic
    ellipse (what ``point_pattern`` fits; its minor axis is ~0 for a flat arc). The positions
    are those at the nominal phase of each frame, i.e. at mid exposure and, with a rolling
    shutter, at the middle row; blur and shutter shear are impairments the analysis must absorb."""
    out = {}
    for point in BODY_POINT_OFFSETS:
        pts = body_point_positions(spec, point, phases_rad)
        extent = 0.5 * (pts.max(axis=0) - pts.min(axis=0))
        out[point] = {"positions_px": pts.round(4).tolist(), "extent_px": extent.tolist(),
                      **first_harmonic_ellipse(pts, phases_rad)}
    return out


def strobe_truth(spec: StrobeSpec) -> dict:
    """Ground truth in the layout of ``labkit analyse strobe``, plus ``point_truth`` (see
    :func:`point_truth`) for the sinusoidal tilt of the spec."""
    beta = abs(spec.rc_offset_px) * math.tan(spec.tilt_amplitude_rad)
    phases = [(spec.phase0_rad + 2 * math.pi * spec.rotor_hz * k / spec.strobe_hz) % (2 * math.pi)
              for k in range(spec.frames)]
    return {"kind": "strobe", "spec": spec.to_dict(), "frames": spec.frames,
            "apparent_hz": abs(spec.apparent_hz), "tilt_amplitude_rad": spec.tilt_amplitude_rad,
            "lateral_amplitude_px": beta, "rc_offset_px": abs(spec.rc_offset_px),
            "phase_per_frame": phases, "point_truth": point_truth(spec, np.array(phases))}


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


def body_coverage(spec: StrobeSpec, psi: float, theta: float | None = None,
                  rows: tuple[int, int] | None = None) -> np.ndarray:
    """Fraction of each pixel covered by the body at rotor phase psi (or tilt ``theta``), pixel
    centres at integer coordinates; shape (h, w), or (r1 - r0, w) for ``rows=(r0, r1)``. Each
    pixel's coverage is the product of linear ramps across the body's length and width edges, so
    the drawn body has the spec's length and width (an anti-aliased ``cv2.fillPoly`` adds ~0.7 px
    all round, which biased the measured tip by as much)."""
    if theta is None:
        theta = spec.tilt_amplitude_rad * math.sin(psi)
    w, h = spec.size
    r0, r1 = rows if rows is not None else (0, h)
    cover = np.zeros((r1 - r0, w), np.float32)
    corners = body_polygon(spec, psi, theta)
    x0, y0 = np.maximum(np.floor(corners.min(axis=0)).astype(int) - 1, (0, r0))
    x1, y1 = np.minimum(np.ceil(corners.max(axis=0)).astype(int) + 2, (w, r1))
    if x0 >= x1 or y0 >= y1:
        return cover
    cx, cy = corners.mean(axis=0)
    dx = np.arange(x0, x1, dtype=np.float32)[None, :] - np.float32(cx)
    dy = np.arange(y0, y1, dtype=np.float32)[:, None] - np.float32(cy)
    along = np.abs(dx * math.sin(theta) - dy * math.cos(theta))
    across = np.abs(dx * math.cos(theta) + dy * math.sin(theta))
    cover[y0 - r0:y1 - r0, x0:x1] = (np.clip(spec.body_length_px / 2 + 0.5 - along, 0, 1)
                                     * np.clip(spec.body_width_px / 2 + 0.5 - across, 0, 1))
    return cover


def _draw(spec: StrobeSpec, psi: float, tilt_of_time: Callable[[float], float] | None,
          rows: tuple[int, int]) -> np.ndarray:
    theta = None
    if tilt_of_time is not None:  # rotor phase -> time since the first flash
        theta = tilt_of_time((psi - spec.phase0_rad) / (2 * math.pi * spec.rotor_hz))
    return body_coverage(spec, psi, theta, rows)


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
            acc = np.zeros((r1 - r0, w), np.float32)
            for j in range(blur_n):
                off = spec.blur_rad * ((j + 0.5) / blur_n - 0.5)
                acc += _draw(spec, psi_row + off, tilt_of_time, (r0, r1))
            cover[r0:r1] = acc / blur_n
        img = bg * (1 - cover) + body_level * cover
        img = cv2.merge([img, img, img])
        noise.add_to(img)
        yield cv2.convertScaleAbs(cv2.max(img, 0.0), alpha=1.0, beta=0.5)
