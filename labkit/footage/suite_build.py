"""Turn a suite :class:`~labkit.footage.suite.CaseSpec` into a renderer shot: every parameter not
in the spec is drawn from its seed, in ranges set by its difficulty (see docs/explanation/robustness-suite.md,
*Independent footage and the robustness suite*, for the table)."""

from __future__ import annotations

import cmath
import math
from dataclasses import replace

import numpy as np

from labkit.footage.body import Body
from labkit.footage.camera import Camera, Lighting
from labkit.footage.laser_scene import LaserShot, StrayReflection, laser_truth
from labkit.footage.motion import PrecessionNutation, SimulatedCone, loops_ratio
from labkit.footage.mount import Mount
from labkit.footage.optics import Screen, ScreenView
from labkit.footage.sim_swing import SimulatedSwing
from labkit.footage.strobe_scene import Lamp, StrobeShot, Swing
from labkit.footage.suite import CaseSpec

FPS = 30.0
GOLDEN = 0.381966
SCREEN_MM = 500.0


def _camera(case: CaseSpec, rng: np.random.Generator, exposure_s: float, laser: bool) -> Camera:
    w, h = case.size
    d = case.difficulty
    readout = 0.0
    if case.rolling or (laser and d != "easy" and not case.photo and rng.random() < 0.5):
        readout = float(rng.uniform(0.5, 0.9)) / FPS
    if d == "easy":
        return Camera(case.size, FPS, exposure_s, readout, read_noise=0.004, psf_core_px=1.0)
    if d == "medium":
        return Camera(case.size, FPS, exposure_s, readout, read_noise=0.012, shot_noise=0.02,
                      psf_core_px=float(rng.uniform(0.9, 1.6)), psf_halo_px=4.0, halo_fraction=0.15,
                      psf_glow_px=18.0, glow_fraction=0.03, bitrate_quality=85,
                      timestamp=bool(rng.random() < 0.5), jpeg_quality=85)
    return Camera(case.size, FPS, exposure_s, readout, read_noise=0.03, shot_noise=0.04,
                  psf_core_px=float(rng.uniform(1.2, 2.2)), psf_halo_px=float(rng.uniform(5, 8)),
                  halo_fraction=0.3, psf_glow_px=float(rng.uniform(25, 40)), glow_fraction=0.08,
                  bitrate_quality=65, timestamp=True, jpeg_quality=75)


def _lighting(d: str, rng: np.random.Generator, dark: bool) -> Lighting:
    base = 0.03 if dark else 0.0
    if d == "easy":
        return Lighting(level=base)
    strength = 1.0 if d == "medium" else 2.0
    return Lighting(level=base, gradient=0.04 * strength, gradient_deg=float(rng.uniform(0, 360)),
                    lamp=0.05 * strength, lamp_xy=tuple(float(v) for v in rng.uniform(0.1, 0.9, 2)),
                    flicker=0.15 * strength, mains_hz=float(rng.choice([50.0, 60.0])))


def _mount(case: CaseSpec, rng: np.random.Generator, t_ref: float) -> Mount:
    if case.difficulty == "easy" or case.photo:
        return Mount(t_ref=t_ref)
    scale = max(case.size) / 640
    ang = rng.uniform(0, 2 * math.pi)
    if case.difficulty == "medium":
        v = 6.0 * scale
        return Mount((v * math.cos(ang), v * math.sin(ang)), 0.0, 0.2, case.seed, t_ref)
    v = 14.0 * scale
    return Mount((v * math.cos(ang), v * math.sin(ang)), 3.0 * scale, 0.4, case.seed, t_ref)


def _timing(case: CaseSpec, rng: np.random.Generator) -> tuple[float, float]:
    """(pattern cycle frequency, exposure): the arc per frame is ``cycle_hz * exposure``; frame to
    frame the pattern advances by a whole number of cycles plus a near-golden fraction, so the
    arcs of successive frames spread over the whole pattern."""
    if case.photo:
        cycle_hz = float(rng.uniform(20, 45))
        return cycle_hz, float(rng.uniform(0.5, 1.5))
    advance = math.ceil(case.arc_cycles / 0.9) + GOLDEN + float(rng.uniform(-0.04, 0.04))
    cycle_hz = advance * FPS
    return cycle_hz, case.arc_cycles / cycle_hz


def _kinematic(case: CaseSpec, rng: np.random.Generator, radius_px: float, cycle_hz: float):
    """Motion and mm per pixel for a pattern whose outer radius is ``radius_px``."""
    amp = float(rng.uniform(0.08, 0.3))  # tangent of the beam's deflection (tilt 2-8 deg)
    rot = cmath.exp(1j * rng.uniform(0, 2 * math.pi))
    if case.family in ("circle", "ellipse"):
        ell = 0.0 if case.family == "circle" else float(rng.uniform(0.12, 0.6))
        major, minor = 1.0, 1.0 - ell
        a, b, k, outer = rot * (major + minor) / 2, rot * (major - minor) / 2, -1, major
    else:
        k = loops_ratio(case.family, case.loops)
        a, b, outer = rot, rot * case.b * cmath.exp(1j * rng.uniform(0, 2 * math.pi)), 1 + case.b
    scale = amp / outer
    mm_per_px = amp * SCREEN_MM / radius_px
    c = complex(*rng.uniform(-0.02, 0.02, 2)) * amp
    a, b = scale * a, scale * b
    motion = PrecessionNutation((c.real, c.imag), (a.real, a.imag), (b.real, b.imag), k, cycle_hz,
                                float(rng.uniform(0, 2 * math.pi)))
    return motion, Screen(SCREEN_MM, 0.0, hole_mm=float(rng.uniform(2, 5))), mm_per_px


def build_laser(case: CaseSpec) -> LaserShot:
    rng = np.random.default_rng(case.seed)
    w, h = case.size
    cycle_hz, exposure = _timing(case, rng)
    radius = float(rng.uniform(0.25, 0.4)) * min(w, h)
    centre = (w / 2 + float(rng.uniform(-0.08, 0.08)) * w, h / 2 + float(rng.uniform(-0.08, 0.08)) * h)
    if case.source == "sim":
        tilt = 0.0 if case.family == "circle" else float(rng.uniform(12, 25))
        motion = SimulatedCone(cycle_hz=cycle_hz, phase_cycles=float(rng.uniform(0, 1)))
        screen = Screen(60.0, tilt, hole_mm=1.0)
        probe = ScreenView((0.0, 0.0), 1.0, 0.0)
    else:
        motion, screen, mm = _kinematic(case, rng, radius, cycle_hz)
        probe = ScreenView((0.0, 0.0), mm, 0.0)
    frames = 1 if case.photo else (45 if max(case.size) > 1300 else 60)
    cam = _camera(case, rng, exposure, laser=True)
    power = {"easy": 1.2, "medium": 2.0, "hard": float(rng.uniform(3, 6))}[case.difficulty]
    shot = LaserShot(motion, screen, probe, cam, _lighting(case.difficulty, rng, dark=True), Mount(),
                     frames=frames, photo=case.photo, power=power, seed=case.seed)
    # place and scale: the truth with the hole at (0, 0) and this scale gives where the pattern is
    p = laser_truth(shot)["pattern"]
    roll = float(rng.uniform(-20, 20)) if case.difficulty != "easy" else 0.0
    zoom = p["semi_axes_px"][0] / radius
    centre_vec = complex(*p["center_px"]) / zoom * cmath.exp(1j * math.radians(roll))
    hole = (centre[0] - centre_vec.real, centre[1] - centre_vec.imag)
    view = ScreenView(hole, probe.mm_per_px * zoom, roll)
    reflection = None
    if case.difficulty == "hard":
        side = cmath.exp(1j * rng.uniform(0, 2 * math.pi)) * radius * 1.25 * view.mm_per_px
        at = complex(*p["center_px"]) / zoom * view.mm_per_px + side
        reflection = StrayReflection((at.real, at.imag), float(rng.uniform(2, 4)), float(rng.uniform(1, 3)))
    shot = replace(shot, view=view, reflection=reflection)
    return replace(shot, mount=_mount(case, rng, shot.t_mid_s))


def build_strobe(case: CaseSpec) -> StrobeShot:
    rng = np.random.default_rng(case.seed)
    w, h = case.size
    d = case.difficulty
    unit = min(w, h) / 480
    length = float(rng.uniform(50, 80)) * unit
    if case.body == "cylinder":
        body = Body("cylinder", length, length * float(rng.uniform(0.35, 0.6)))
    else:  # a square plate magnet, thin along its dipole axis (Fig. 6.20)
        body = Body("cuboid", length * 0.35, length, spin_hz=float(rng.uniform(0.3, 3.0)))
    f_app = case.apparent_cpf * FPS
    if case.flashes == 0:  # the camera is the strobe: a short exposure, room light
        f_strobe, lamp = FPS, Lamp(None)
        exposure = float(rng.uniform(1 / 10000, 1 / 4000))
    elif d == "easy":  # lamp triggered by the camera: one flash per frame
        f_strobe = FPS
        lamp = Lamp(FPS, 0.2 / FPS, 20e-6)
        exposure = 0.5 / FPS
    else:
        f_strobe = float(rng.uniform(150, 250))
        exposure = min(0.95 / FPS, case.flashes / f_strobe)
        shadow = tuple(float(v) * unit for v in rng.uniform(-8, 8, 2)) if d == "hard" else (0.0, 0.0)
        lamp = Lamp(f_strobe, float(rng.uniform(0.1, 0.9)) / f_strobe, float(rng.uniform(10e-6, 40e-6)),
                    shadow, 0.35 if d == "hard" else 0.0)
    # a camera-strobe (or, for simulated motion, an easy 30 Hz lamp) films a fast rotor
    fast = 8 if case.source == "kinematic" else 7
    harmonic = case.harmonic * (fast if lamp.hz is None or (case.source == "sim" and d == "easy") else 1)
    rotor = harmonic * f_strobe + f_app
    if case.source == "sim":
        body, swing = _simulated_body(case, rng, length, rotor)
    else:  # the draws keep their order: the cached footage of these cases stays valid
        phi = float(rng.uniform(0.06, 0.22))
        delta = float(rng.uniform(0.4, 1.3)) * length * float(rng.choice([-1.0, 1.0]))
    cam = _camera(case, rng, exposure, laser=False)
    if case.rolling:
        cam = replace(cam, readout_s=float(rng.uniform(0.5, 0.9)) / FPS)
    roll = 0.0 if d == "easy" else float(rng.uniform(-12, 12))
    centre = (w / 2 + float(rng.uniform(-0.1, 0.1)) * w, h / 2 + float(rng.uniform(-0.1, 0.1)) * h)
    ambient = {"easy": 0.0, "medium": 0.1, "hard": 0.3}[d] if lamp.hz is not None else 0.0
    frames = 48 if max(case.size) > 1300 else 60
    if case.source != "sim":
        swing = Swing(phi, delta, rotor, float(rng.uniform(0, 2 * math.pi)))
    shot = StrobeShot(body, swing, lamp, cam, centre,
                      case.rest_deg, roll, _lighting(d, rng, dark=False), ambient, Mount(),
                      backlit=bool(d != "hard" or rng.random() < 0.5), frames=frames, seed=case.seed)
    mount = Mount() if d != "hard" else Mount((0.0, 0.0), 1.5 * unit, 0.2, case.seed, 0.0)
    return replace(shot, mount=mount)


def _simulated_body(case: CaseSpec, rng: np.random.Generator, length_px: float,
                    rotor_hz: float) -> tuple[Body, SimulatedSwing]:
    """A floator magnet bound beneath a 6x3 mm rotator, its motion integrated by labkit.sim; the
    image scale makes its length along the dipole ``length_px``."""
    if case.body == "cylinder":
        diameter, height = float(rng.uniform(6, 10)), float(rng.uniform(5, 9))
        spec, body = f"cylinder:{diameter:.2f}x{height:.2f}mm", ("cylinder", height, diameter)
    else:  # a square plate, thin along its dipole (Fig. 6.20)
        side = float(rng.uniform(8, 12))
        spec, body = f"block:{side:.2f}x{side:.2f}x{0.35 * side:.2f}mm", ("cuboid", 0.35 * side, side)
    mm_per_px = body[1] / length_px if case.body == "cylinder" else body[2] / length_px
    swing = SimulatedSwing("cylinder:6x3mm", spec, float(rng.uniform(6, 12)), rotor_hz, mm_per_px,
                           float(rng.uniform(0, 2 * math.pi)))
    spin = {"spin_hz": float(rng.uniform(0.3, 3.0))} if case.body == "cuboid" else {}
    return Body(body[0], body[1] / mm_per_px, body[2] / mm_per_px, **spin), swing


def build_shot(case: CaseSpec) -> LaserShot | StrobeShot:
    return build_strobe(case) if case.family == "strobe" else build_laser(case)
