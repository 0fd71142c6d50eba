"""A strobe-lit cylinder, rendered with its own geometry for checking the strobe analysis on footage
that neither ``labkit.footage`` nor ``labkit.synth`` drew (issue 26, item 5;
docs/explanation/strobe-speed.md).

The body is a cylinder of length ``length_px`` and diameter ``diameter_px`` whose axis leans
``lean_deg`` out of the image plane, so its end faces show as ellipses: the silhouette is the
convex hull of the two end ellipses (a rectangle closed by two half-ellipses), drawn with
``cv2.fillPoly`` at 4x supersampling inside a box around the body only (a 1080p clip costs what
its body costs). Motion is Eq. 5.97 of the paper: the axis tilts in the image plane by
``theta(t) = phi sin(2 pi f_rot t + psi0)`` and the centre of mass moves across the rest axis by
``-delta tan(theta)``, so the lateral amplitude is ``beta = delta tan(phi)``.

Light is added in linear units: every lamp flash inside a frame's exposure (global shutter)
paints the body at its own rotor phase; room light, ``room_light`` times one exposure's flash
light, adds the body averaged over a whole revolution (the ghost). The image goes through a
Gaussian lens blur, is encoded with a pure power law (``1 / gamma``), gets sensor noise in grey
levels and is written as MJPEG (``.avi``) or MPEG-4 part 2 (``.mp4``), streamed frame by frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

SUPERSAMPLE = 4
GHOST_PHASES = 48  # rotor phases averaged for the room light's ghost
CAP_POINTS = 24  # points on each half-ellipse of the outline


@dataclass(frozen=True)
class CylinderClip:
    """One clip: geometry (px), motion (Eq. 5.97), lamp, camera and light."""

    size: tuple[int, int] = (640, 480)
    frames: int = 120
    fps: float = 30.0
    exposure_s: float = 1 / 60
    rotor_hz: float = 200.0
    strobe_hz: float = 199.5
    phi_rad: float = 0.12
    delta_px: float = 80.0
    psi0_rad: float = 1.1
    length_px: float = 190.0
    diameter_px: float = 88.0
    lean_deg: float = 12.0  # axis out of the image plane: end faces seen as ellipses
    rest_deg: float = 90.0  # rest axis from image +x, counter-clockwise on screen
    centre_px: tuple[float, float] | None = None  # default: the frame's centre
    background: float = 0.75  # linear reflectances
    body: float = 0.06
    room_light: float = 0.0  # room light over one exposure's flash light
    blur_px: float = 1.2
    gamma: float = 2.2
    noise: float = 1.5  # grey levels, after encoding
    seed: int = 0

    @property
    def beta_px(self) -> float:
        """The lateral amplitude, Eq. 5.97."""
        return abs(self.delta_px) * math.tan(self.phi_rad)

    @property
    def duration_s(self) -> float:
        return self.frames / self.fps

    def truth(self) -> dict:
        return {"tilt_amplitude_rad": self.phi_rad, "lateral_amplitude_px": self.beta_px,
                "rc_offset_px": abs(self.delta_px), "rotor_hz": self.rotor_hz, "strobe_hz": self.strobe_hz,
                "body_extent_px": list(self.extent_px())}

    def extent_px(self) -> tuple[float, float]:
        """Silhouette length along the axis and width across it."""
        lean = math.radians(self.lean_deg)
        return self.length_px * math.cos(lean) + self.diameter_px * math.sin(lean), self.diameter_px


def outline(clip: CylinderClip, theta: float) -> np.ndarray:
    """The silhouette's polygon (N, 2) in image pixels at tilt ``theta`` (rad)."""
    w, h = clip.size
    cx, cy = clip.centre_px or (w / 2, h / 2)
    rest = math.radians(clip.rest_deg)
    normal0 = np.array([math.sin(rest), math.cos(rest)])  # across the rest axis, image coordinates
    centre = np.array([cx, cy]) - clip.delta_px * math.tan(theta) * normal0
    angle = rest + theta
    along = np.array([math.cos(angle), -math.sin(angle)])
    across = np.array([-along[1], along[0]])
    lean = math.radians(clip.lean_deg)
    half_len = 0.5 * clip.length_px * math.cos(lean)
    r_across, r_along = 0.5 * clip.diameter_px, 0.5 * clip.diameter_px * math.sin(lean)
    t = np.linspace(-math.pi / 2, math.pi / 2, CAP_POINTS)
    ends = []
    for sign in (1.0, -1.0):  # the outer half of each end ellipse
        a = sign * (half_len + r_along * np.cos(t))
        b = sign * r_across * np.sin(t)
        ends.append(centre + a[:, None] * along + b[:, None] * across)
    return np.vstack(ends)


def _box(clip: CylinderClip) -> tuple[int, int, int, int]:
    """A box (x0, y0, x1, y1) that holds the body at every tilt, with room for the blur."""
    pts = np.vstack([outline(clip, s * clip.phi_rad) for s in np.linspace(-1, 1, 9)])
    pad = int(4 * clip.blur_px) + 6
    w, h = clip.size
    x0, y0 = (max(0, int(v) - pad) for v in pts.min(axis=0))
    x1, y1 = (min(lim, int(v) + pad + 1) for v, lim in zip(pts.max(axis=0), (w, h), strict=True))
    return x0, y0, x1, y1


def coverage(clip: CylinderClip, theta: float, box: tuple[int, int, int, int]) -> np.ndarray:
    """Fraction of each pixel of ``box`` the body covers at tilt ``theta`` (area-averaged)."""
    x0, y0, x1, y1 = box
    big = np.zeros(((y1 - y0) * SUPERSAMPLE, (x1 - x0) * SUPERSAMPLE), np.uint8)
    pts = (outline(clip, theta) - np.array([x0, y0]) + 0.5) * SUPERSAMPLE - 0.5
    cv2.fillPoly(big, [np.round(pts * 16).astype(np.int32)], 255, lineType=cv2.LINE_8, shift=4)
    return cv2.resize(big, (x1 - x0, y1 - y0), interpolation=cv2.INTER_AREA).astype(np.float32) / 255.0


def _tilt(clip: CylinderClip, t: float) -> float:
    return clip.phi_rad * math.sin(2 * math.pi * clip.rotor_hz * t + clip.psi0_rad)


def frames(clip: CylinderClip):
    """Yield the clip's BGR uint8 frames one at a time."""
    w, h = clip.size
    box = _box(clip)
    x0, y0, x1, y1 = box
    rng = np.random.default_rng(clip.seed)
    ghost = np.mean([coverage(clip, clip.phi_rad * math.sin(p), box)
                     for p in np.linspace(0, 2 * math.pi, GHOST_PHASES, endpoint=False)], axis=0)
    per_exposure = clip.exposure_s * clip.strobe_hz
    contrast = clip.body - clip.background
    for k in range(clip.frames):
        t0 = k / clip.fps
        j0, j1 = math.ceil(t0 * clip.strobe_hz), math.floor((t0 + clip.exposure_s) * clip.strobe_hz)
        flashes = [j / clip.strobe_hz for j in range(j0, j1 + 1)]
        cover = np.zeros((y1 - y0, x1 - x0), np.float32)
        for t in flashes:
            cover += coverage(clip, _tilt(clip, t), box)
        flash_light = len(flashes) / per_exposure  # 3 or 4 flashes: the frame's brightness moves
        lin: np.ndarray = np.full((h, w), clip.background * (flash_light + clip.room_light), np.float32)
        lin[y0:y1, x0:x1] += contrast * (cover / per_exposure + clip.room_light * ghost)
        if clip.blur_px > 0:
            lin = cv2.GaussianBlur(lin, (0, 0), clip.blur_px)
        scale = 1.0 / (1.15 * (1.0 + clip.room_light))  # a little headroom, exposure set for the light
        grey = 255.0 * np.clip(lin * scale, 0, 1) ** (1 / clip.gamma) + rng.normal(0, clip.noise, (h, w))
        yield cv2.cvtColor(np.clip(grey + 0.5, 0, 255).astype(np.uint8), cv2.COLOR_GRAY2BGR)


def write_clip(clip: CylinderClip, path: str | Path) -> str:
    """Write the clip (``.avi``: MJPEG; ``.mp4``: mp4v) and return its path."""
    path = Path(path)
    fourcc = "MJPG" if path.suffix.lower() == ".avi" else "mp4v"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*fourcc), clip.fps, clip.size)
    if not writer.isOpened():
        raise OSError(f"{path}: OpenCV cannot write {fourcc}")
    try:
        for frame in frames(clip):
            writer.write(frame)
    finally:
        writer.release()
    return str(path)


def sized(name: str, size: tuple[int, int] = (640, 480), room_light: float = 0.0, **extra) -> CylinderClip:
    """A clip with a ``small``, ``medium`` or ``large`` body for the frame (large: about 200x90 px
    at 640x480; lengths scale with the frame's height), tilt 0.12 rad, lateral amplitude about
    a twentieth of the body's length (10 px for the large body at 640x480)."""
    length = {"small": 0.12, "medium": 0.24, "large": 0.40}[name] * size[1]
    phi = 0.12
    return CylinderClip(size=size, length_px=length, diameter_px=length * 88 / 190, phi_rad=phi,
                        delta_px=0.052 * length / math.tan(phi), room_light=room_light,
                        blur_px=1.2 * max(1.0, 0.8 * size[1] / 480), **extra)
