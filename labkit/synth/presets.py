"""Footage difficulty presets and the seeded synthetic test set used by tests and benchmarks.

``easy``: clean screen, thin spot. ``medium``: halo, noise, background gradient, the hole, exposure
smear. ``hard``: strong saturating halo, heavy noise, a lamp, drift of the centre, jitter, rolling
shutter, compression.
"""

from __future__ import annotations

import math
from dataclasses import replace

from labkit.synth.laser import LaserSpec
from labkit.synth.strobe import StrobeSpec
from labkit.vision.shared.curves import Pattern

LEVELS = ("easy", "medium", "hard")


def laser_preset(level: str, size: tuple[int, int] = (640, 480), seed: int = 0) -> LaserSpec:
    """Impairments for a difficulty level (the pattern is set separately)."""
    scale = max(size) / 640
    base = LaserSpec(size=size, seed=seed, spot_sigma_px=1.4 * scale)
    if level == "easy":
        return replace(base, noise_sigma=1.5, background=30.0, exposure_s=0.004)
    if level == "medium":
        return replace(base, noise_sigma=4.0, background=45.0, gradient=40.0, halo_sigma_px=6 * scale,
                       halo_strength=0.15, hole_radius_px=7 * scale, exposure_s=0.01, brightness=1.5)
    if level == "hard":
        return replace(base, noise_sigma=8.0, background=55.0, gradient=70.0, lamp=50.0,
                       halo_sigma_px=9 * scale, halo_strength=0.3, hole_radius_px=9 * scale,
                       exposure_s=0.02, brightness=2.5, drift_px_s=(3.0 * scale, -2.0 * scale),
                       jitter_px=0.3, rolling_shutter_s=0.01)
    raise ValueError(f"unknown level {level!r}; choose one of {', '.join(LEVELS)}")


def laser_pattern(kind: str, size: tuple[int, int], ellipticity: float = 0.0, loops: int = 3, b: float = 0.5,
                  rotation_deg: float = 20.0, offset: tuple[float, float] = (0.0, 0.0)) -> Pattern:
    """A pattern that fills about 60 % of the frame height, centred (plus ``offset``)."""
    w, h = size
    center = (w / 2 + offset[0] + 0.37, h / 2 + offset[1] - 0.21)  # off the pixel grid on purpose
    rot = math.radians(rotation_deg)
    if kind in ("circle", "ellipse"):
        major = 0.3 * h
        return Pattern(kind, center, rot, (major, major * (1 - ellipticity)))
    scale = 0.3 * h / (1 + b)
    return Pattern(kind, center, rot, scale=scale, b=b, loops=loops)


def laser_test_set(small: bool = True) -> list[tuple[str, LaserSpec]]:
    """The seeded acceptance set: circles, ellipses (ellipticity 0.05-0.9, any rotation), epi- and
    hypotrochoids with 2-7 loops, over easy/medium/hard footage from 320x240 to 1280x720."""
    cases = [
        ("circle", "easy", (320, 240), dict()),
        ("ellipse", "medium", (320, 240), dict(ellipticity=0.05, rotation_deg=120)),
        ("ellipse", "hard", (640, 480), dict(ellipticity=0.4, rotation_deg=63)),
        ("ellipse", "medium", (640, 480), dict(ellipticity=0.9, rotation_deg=155)),
        ("epitrochoid", "easy", (640, 480), dict(loops=2, b=0.3, rotation_deg=10)),
        ("epitrochoid", "medium", (640, 480), dict(loops=4, b=0.25, rotation_deg=50)),
        ("epitrochoid", "hard", (640, 480), dict(loops=7, b=0.16, rotation_deg=5)),
        ("hypotrochoid", "medium", (640, 480), dict(loops=3, b=0.82, rotation_deg=30)),
        ("hypotrochoid", "hard", (640, 480), dict(loops=5, b=0.5, rotation_deg=12)),
        ("hypotrochoid", "easy", (320, 240), dict(loops=6, b=0.3, rotation_deg=40)),
        ("ellipse", "hard", (1280, 720), dict(ellipticity=0.3, rotation_deg=35)),
    ]
    out = []
    for i, (kind, level, size, kw) in enumerate(cases):
        spec = laser_preset(level, size, seed=100 + i)
        pattern = laser_pattern(kind, size, **kw)
        frames = 45 if small else 150
        spec = replace(spec, pattern=pattern, frames=frames, cycle_hz=7.3 + 0.37 * i)
        name = f"{i:02d}-{kind}-{level}-{size[0]}x{size[1]}"
        out.append((name, spec))
    return out


def strobe_preset(level: str, seed: int = 0) -> StrobeSpec:
    """Stroboscope footage for a difficulty level."""
    base = StrobeSpec(seed=seed)
    if level == "easy":
        return replace(base, noise_sigma=2.0)
    if level == "medium":
        return replace(base, noise_sigma=5.0, gradient=40.0, blur_rad=0.3)
    if level == "hard":
        return replace(base, noise_sigma=9.0, gradient=60.0, blur_rad=0.5, rolling_shutter_rad=0.4,
                       dark_body=False)
    raise ValueError(f"unknown level {level!r}; choose one of {', '.join(LEVELS)}")
