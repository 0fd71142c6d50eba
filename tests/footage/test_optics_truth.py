"""The independent renderer's geometry: mirror law, screen hits, truth of the patterns drawn."""

from __future__ import annotations

import cmath
import json
import math

import cv2
import numpy as np
import pytest

from labkit.footage import (
    Camera,
    LaserShot,
    Mount,
    PrecessionNutation,
    Screen,
    ScreenView,
    SimulatedCone,
    conic_truth,
    laser_truth,
    loops_ratio,
    reflect,
    render_laser,
    spot_px,
    truth_path,
    write_footage,
)
from labkit.footage.truth import conic_residual_px


@pytest.mark.parametrize("tilt", [0.01, 0.1, 0.3])
@pytest.mark.parametrize("azimuth", [0.0, 1.0, -2.5])
def test_spot_lands_where_the_mirror_law_says(tilt, azimuth):
    # a polar face tilted by `tilt` towards `azimuth` turns the returning beam by 2 tilt:
    # the spot sits L tan(2 tilt) from the hole, in the tilt's direction
    n = np.array([[math.sin(tilt) * math.cos(azimuth), math.sin(tilt) * math.sin(azimuth), math.cos(tilt)]])
    L = 400.0
    uv = Screen(L).hits_mm(n)[0]
    assert math.hypot(*uv) == pytest.approx(L * math.tan(2 * tilt), rel=1e-12)
    assert math.atan2(uv[1], uv[0]) == pytest.approx(azimuth, abs=1e-12)


def test_reflection_keeps_length_and_angle():
    rng = np.random.default_rng(3)
    n = rng.normal(size=(50, 3))
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    d = np.array([0.0, 0.0, -1.0])
    r = reflect(d, n)
    assert np.allclose(np.linalg.norm(r, axis=1), 1.0)
    assert np.allclose(np.einsum("ij,ij->i", r, n), -(n @ d))  # angle of incidence = angle of reflection


def test_face_normal_returns_beam_through_the_hole():
    shot = LaserShot(PrecessionNutation((0, 0), (0, 0), (0, 0), -1, 5.0), Screen(300.0, 0.0, 3.0),
                     ScreenView((100.0, 80.0), 0.5), Camera((200, 160)))
    px, on = spot_px(shot, np.array([0.0, 0.1]))
    assert np.allclose(px, [[100.0, 80.0], [100.0, 80.0]])
    assert not on.any()  # the returning beam goes back through the hole: no spot on the screen


@pytest.mark.parametrize("kind,loops,b", [("epitrochoid", 2, 0.6), ("epitrochoid", 7, 0.2),
                                          ("hypotrochoid", 3, 0.82), ("hypotrochoid", 7, 0.5)])
def test_trochoid_spot_path_is_the_truth_curve(kind, loops, b):
    k = loops_ratio(kind, loops)
    A, B = 0.2 * cmath.exp(0.7j), 0.2 * b * cmath.exp(-1.9j)
    motion = PrecessionNutation((0.01, -0.02), (A.real, A.imag), (B.real, B.imag), k, 3.0, 0.4)
    shot = LaserShot(motion, Screen(500.0), ScreenView((320.0, 240.0), 0.6, 17.0), Camera((640, 480)))
    truth = laser_truth(shot)["pattern"]
    assert truth["type"] == kind and truth["loops"] == loops
    assert truth["symmetry"] == round(1 / abs(truth["trochoid"]["a"]))
    assert truth["trochoid"]["b"] == pytest.approx(b, rel=1e-12)
    # the canonical form c + s R(rot) [cos t + b cos kt, sin t + b sin kt] passes through every spot
    t = np.linspace(0, 1 / 3.0, 500, endpoint=False)
    spots, _ = spot_px(shot, t)
    tr = truth["trochoid"]
    s = np.linspace(0, 2 * np.pi, 200_001)
    turn = tr["scale_px"] * cmath.exp(1j * math.radians(tr["rotation_deg"]))
    curve = complex(*truth["center_px"]) + turn * (np.exp(1j * s) + tr["b"] * np.exp(1j * k * s))
    z = spots[:, 0] + 1j * spots[:, 1]
    dist = np.concatenate([np.abs(part[:, None] - curve[None, :]).min(axis=1) for part in np.split(z, 25)])
    assert dist.max() < 0.02  # px; the curve is sampled every < 0.02 px of arc


def test_simulated_cone_draws_circle_of_radius_L_tan_2phi():
    motion = SimulatedCone(cycle_hz=10.0)
    t = np.linspace(0, 0.1, 400, endpoint=False)
    phi = float(np.mean(motion.tilt_rad(t)))
    assert np.ptp(motion.tilt_rad(t)) < 1e-4  # exact conical motion (Eq. 5.7/5.24)
    assert phi == pytest.approx(0.535984, abs=2e-5)  # closed form printed by `labkit simulate conical_5_1`
    shot = LaserShot(motion, Screen(50.0), ScreenView((0.0, 0.0), 0.25), Camera((640, 480)))
    truth = laser_truth(shot)["pattern"]
    assert truth["type"] == "circle"
    assert truth["semi_axes_px"][0] == pytest.approx(50.0 * math.tan(2 * phi) / 0.25, rel=1e-4)


def test_tilted_screen_gives_exact_ellipse():
    motion = SimulatedCone(cycle_hz=10.0)
    shot = LaserShot(motion, Screen(50.0, 20.0), ScreenView((0.0, 0.0), 0.5), Camera((640, 480)))
    truth = laser_truth(shot)["pattern"]
    assert truth["type"] == "ellipse" and truth["ellipticity"] > 0.2
    spots, _ = spot_px(shot, np.linspace(0.013, 0.113, 777))  # other samples than the truth's
    assert conic_residual_px(spots, truth) < 0.01


def test_conic_truth_recovers_a_known_ellipse():
    s = np.linspace(0, 2 * np.pi, 300)
    rot = math.radians(33.0)
    x, y = 140 * np.cos(s), 60 * np.sin(s)
    c, s_ = math.cos(rot), math.sin(rot)
    pts = np.column_stack([50 + x * c - y * s_, -20 + x * s_ + y * c])
    t = conic_truth(pts)
    assert t["center_px"] == pytest.approx([50, -20], abs=1e-8)
    assert t["semi_axes_px"] == pytest.approx([140, 60], rel=1e-9)
    assert t["rotation_deg"] == pytest.approx(33.0, abs=1e-7)


def test_truth_json_beside_footage_matches_motion_and_mount(tmp_path):
    k = loops_ratio("epitrochoid", 4)
    motion = PrecessionNutation((0.0, 0.0), (0.15, 0.0), (0.05, 0.0), k, 41.0)
    cam = Camera((320, 240), exposure_s=0.01)
    shot = LaserShot(motion, Screen(500.0), ScreenView((160.0, 120.0), 4.0), cam, frames=6,
                     mount=Mount((20.0, -10.0), t_ref=0.0))
    blank = [np.zeros((240, 320, 3), np.uint8)] * 6
    path = write_footage(tmp_path / "clip.mp4", blank, 30.0, laser_truth(shot))
    truth = json.loads(truth_path(path).read_text())
    # the centre at the middle of the recording has moved with the camera since t_ref = 0
    t_mid = 5 / 60 + 0.005
    assert truth["t_mid_s"] == pytest.approx(t_mid)
    assert truth["pattern"]["center_px"] == pytest.approx([160 + 20 * t_mid, 120 - 10 * t_mid], abs=1e-9)
    assert truth["camera_moves"] is True
    assert truth["arc_cycles_per_frame"] == pytest.approx(0.41)
    # scale: 0.15 of L = 500 mm at 4 mm/px
    assert truth["pattern"]["trochoid"]["scale_px"] == pytest.approx(0.15 * 500 / 4)
    assert truth["tilt_rad"]["max"] == pytest.approx(0.5 * math.atan(0.2), rel=1e-5)


def test_long_exposure_photo_draws_the_truth_circle(tmp_path):
    cam = Camera((320, 240), exposure_s=0.5, psf_core_px=1.0)
    shot = LaserShot(SimulatedCone(cycle_hz=23.0), Screen(30.0), ScreenView((160.0, 120.0), 0.6), cam,
                     photo=True, power=1.0)
    truth = laser_truth(shot)
    path = write_footage(tmp_path / "cone.jpg", render_laser(shot), cam.fps, truth)
    image = cv2.imread(str(path))
    assert image.shape == (240, 320, 3)
    red = image[:, :, 2].astype(float)
    ys, xs = np.nonzero(red > 0.8 * red.max())
    r = np.hypot(xs - truth["pattern"]["center_px"][0], ys - truth["pattern"]["center_px"][1])
    assert len(r) > 200
    assert np.abs(r - truth["pattern"]["semi_axes_px"][0]).max() < 1.5  # the lit ring is the truth circle
