"""The camera model and the stroboscope scene: flashes per exposure, rolling-shutter skew, body
coverage, Eq. 5.97 truth."""

from __future__ import annotations

import math

import numpy as np
import pytest

from labkit.footage import Body, Camera, Lamp, Lighting, Mount, StrobeShot, Swing, render_strobe, strobe_truth
from labkit.footage.body import SUPERSAMPLE, coverage, outline
from labkit.footage.camera import develop, flicker_rows
from labkit.footage.strobe_scene import light_times, pose


def _shot(**kw) -> StrobeShot:
    base = dict(body=Body("cylinder", 60, 24), swing=Swing(0.1, 50.0, 201.0), lamp=Lamp(199.5, 0.0013),
                camera=Camera((160, 120), 30.0, 1 / 60, gamma=1.0, read_noise=0.0, psf_core_px=0.0),
                centre_px=(80.0, 60.0), frames=12)
    base.update(kw)
    return StrobeShot(**base)


def test_flash_count_per_exposure_follows_the_lamp_not_the_frame_rate():
    shot = _shot()
    counts = [len(light_times(shot, k)[0]) // 3 for k in range(60)]  # 3 sub-samples per flash
    # 199.5 Hz into 1/60 s windows (+ no readout): 3.325 flashes, so 3 or 4 per frame
    assert set(counts) == {3, 4}
    assert np.mean(counts) == pytest.approx(199.5 / 60, abs=0.05)
    truth = strobe_truth(shot)
    assert truth["flashes_per_exposure"] == pytest.approx(3.325)
    assert [f["flashes"] for f in truth["per_frame"]] == counts[:12]


def test_frame_brightness_counts_the_flashes():
    # background-only rows: linear level proportional to the flashes the frame caught
    shot = _shot(camera=Camera((160, 120), 30.0, 1 / 60, gamma=1.0, read_noise=0.0, psf_core_px=0.0))
    frames = list(render_strobe(shot))
    counts = [f["flashes"] for f in strobe_truth(shot)["per_frame"]]
    level = [float(f[:10].mean()) for f in frames]
    per_flash = [lv / n for lv, n in zip(level, counts, strict=True)]
    assert max(per_flash) / min(per_flash) < 1.01
    assert max(level) / min(level) == pytest.approx(4 / 3, rel=0.02)


def test_harmonic_and_signed_apparent_frequency():
    for rotor, m, f_app in ((199.5 * 2 - 1.5, 2, -1.5), (199.5 + 2.0, 1, 2.0)):
        truth = strobe_truth(_shot(swing=Swing(0.1, 50.0, rotor)))
        assert truth["harmonic"] == m
        assert truth["apparent_hz"] == pytest.approx(f_app)
        # frame to frame the mean phase advances by 2 pi f_app / fps (flashes are 1/199.5 s apart)
        ph = np.unwrap([f["phase_rad"] for f in truth["per_frame"]])
        assert np.median(np.diff(ph)) == pytest.approx(2 * math.pi * f_app / 30.0, abs=0.05)


def test_rolling_shutter_skews_a_vertical_edge_by_the_known_amount():
    # the camera pans at 2000 px/s; rows are read 40 ms top to bottom: each row sees the body
    # 40 ms / 119 later than the one above, so a vertical edge leans by 2000 * 0.04 / 119 px per row
    readout, speed = 0.04, 2000.0
    cam = Camera((160, 120), 30.0, 1e-4, readout_s=readout, gamma=1.0, read_noise=0.0)
    shot = _shot(swing=Swing(0.0, 0.0, 50.0), lamp=Lamp(None), camera=cam, frames=1,
                 body=Body("cylinder", 80, 30), mount=Mount((speed, 0.0), t_ref=0.0))
    frame = next(iter(render_strobe(shot)))[:, :, 0].astype(float)
    bg = np.median(frame[:, :5])
    dark = np.clip((bg - frame) / (bg - frame.min()), 0, 1)
    rows = np.arange(35, 85)  # inside the body, away from its ends
    xs = np.arange(frame.shape[1])
    centre = [(dark[r] * xs).sum() / dark[r].sum() for r in rows]  # where the body crosses the row
    slope = np.polyfit(rows, centre, 1)[0]
    assert slope == pytest.approx(speed * readout / 119, rel=0.03)


@pytest.mark.parametrize("axis_deg", [0.0, 23.0, 90.0, 137.0])
def test_body_coverage_has_the_right_area_and_centroid(axis_deg):
    corners = outline((40.3, 31.7), axis_deg, 50.0, 18.0)
    cov = coverage(corners, (0, 0, 90, 70))
    assert cov.sum() == pytest.approx(50 * 18, rel=0.01)
    y, x = np.mgrid[0:70, 0:90]
    # edges snap to the finer grid: the centroid is within half a fine pixel
    assert (cov * x).sum() / cov.sum() == pytest.approx(40.3, abs=0.5 / SUPERSAMPLE)
    assert (cov * y).sum() / cov.sum() == pytest.approx(31.7, abs=0.5 / SUPERSAMPLE)


def test_strobe_truth_is_eq_5_97_and_the_poses_follow_it():
    shot = _shot(swing=Swing(0.15, -40.0, 202.0, 0.3), rest_deg=90.0, roll_deg=10.0)
    truth = strobe_truth(shot)
    assert truth["lateral_amplitude_px"] == pytest.approx(40 * math.tan(0.15))
    assert truth["rc_offset_px"] == pytest.approx(40.0)
    assert truth["axis_image_deg"] == pytest.approx(100.0)
    # the centre of mass swings across the rest axis (axis at 100 deg from image-up)
    across = np.array([math.cos(math.radians(100)), math.sin(math.radians(100))])
    t = np.linspace(0, 1 / 202.0, 400)
    lateral = np.array([(np.array(pose(shot, float(x))[0]) - shot.centre_px) @ across for x in t])
    assert np.abs(lateral).max() == pytest.approx(truth["lateral_amplitude_px"], rel=1e-4)
    tilt = np.array([pose(shot, float(x))[1] for x in t]) - 100.0
    assert np.abs(tilt).max() == pytest.approx(math.degrees(0.15), rel=1e-4)


def test_flicker_is_the_mean_over_each_rows_window():
    light = Lighting(level=0.2, flicker=0.5, mains_hz=50.0)
    cam = Camera((40, 100), 30.0, 1 / 1000, readout_s=0.02)
    f = flicker_rows(light, cam, 0)
    # a 1 ms window on 100 Hz flicker barely averages it: rows swing almost the full +-0.5;
    # the rows span 20 ms = 2 flicker periods
    assert f.max() > 1.45 and f.min() < 0.55
    long = flicker_rows(light, Camera((40, 100), 30.0, 1 / 100, readout_s=0.02), 0)
    assert np.allclose(long, 1.0, atol=1e-6)  # a whole flicker period averages out


def test_saturation_and_noise():
    rng = np.random.default_rng(1)
    cam = Camera((64, 64), read_noise=0.02, shot_noise=0.0, gamma=1.0)
    img = np.full((64, 64, 3), 3.0, np.float32)
    assert (develop(img.copy(), cam, rng) == 255).all()  # far above full well: clipped
    mid = develop(np.full((64, 64, 3), 0.5, np.float32), cam, rng).astype(float)
    assert mid.std() == pytest.approx(0.02 * 255, rel=0.1)
