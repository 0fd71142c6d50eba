"""An independent camera-model renderer of test footage (laser traces and stroboscope clips) with
exact ground truth, for the robustness suite (docs/explanation/robustness-suite.md, *Independent footage and
the robustness suite*). It shares no code with :mod:`labkit.synth` and never imports
:mod:`labkit.vision`: the geometry comes from the motion (:mod:`labkit.sim`, or a kinematic
precession + nutation model and Eq. 5.97's swing), the mirror law and a camera model.
"""

from labkit.footage.body import Body
from labkit.footage.camera import Camera, Lighting
from labkit.footage.laser_scene import LaserShot, StrayReflection, laser_truth, render_laser, spot_px
from labkit.footage.motion import PrecessionNutation, SimulatedCone, loops_ratio, normal_from_beam_tangent
from labkit.footage.mount import Mount
from labkit.footage.optics import Screen, ScreenView, reflect
from labkit.footage.output import truth_path, write_footage
from labkit.footage.sim_swing import SimulatedSwing
from labkit.footage.strobe_scene import Lamp, StrobeShot, Swing, render_strobe, strobe_truth
from labkit.footage.truth import conic_truth, pattern_truth

__all__ = [
    "Camera", "Lighting", "LaserShot", "StrayReflection", "laser_truth", "render_laser", "spot_px",
    "PrecessionNutation", "SimulatedCone", "loops_ratio", "normal_from_beam_tangent", "Mount",
    "Screen", "ScreenView", "reflect", "truth_path", "write_footage", "conic_truth", "pattern_truth",
    "Body", "Lamp", "StrobeShot", "Swing", "SimulatedSwing", "render_strobe", "strobe_truth",
]
