"""labkit.synth: realistic synthetic laser-screen and stroboscope footage with ground truth.

``render_laser(spec)`` / ``render_strobe(spec)`` yield BGR frames; ``write_clip(...)`` writes a video
or photo and its ground-truth JSON beside it. Seeded: the same spec gives the same pixels.
"""

from labkit.synth.laser import LaserSpec, laser_truth, positions_from_angles, render_laser
from labkit.synth.strobe import StrobeSpec, render_strobe, strobe_truth, tilt_from_angles
from labkit.synth.writer import truth_path, write_clip

__all__ = [
    "LaserSpec", "StrobeSpec", "laser_truth", "positions_from_angles", "render_laser", "render_strobe",
    "strobe_truth", "tilt_from_angles", "truth_path", "write_clip",
]
