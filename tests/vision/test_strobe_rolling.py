"""A rolling shutter with the camera as the strobe (issue 11; Fig. 6.20 without a lamp): every image
row samples the rotor at its own phase, so the silhouette is a smear of most of a revolution. The
per-row phase model (labkit.vision.strobe.rolling_model) fits Eq. 5.97 row by row.

The suite clip is drawn by the independent renderer (labkit.footage), which shares no code with
the analysis; the unit tests check the row slices against that renderer's rectangle coverage and
recover known parameters from synthetic slices."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from labkit.footage.body import coverage, outline
from labkit.footage.output import write_footage
from labkit.footage.strobe_scene import render_strobe, strobe_truth
from labkit.footage.suite import suite_cases
from labkit.footage.suite_build import build_shot
from labkit.footage.suite_eval import analysis_inputs, score_strobe
from labkit.vision.strobe.analyse import analyse_strobe
from labkit.vision.strobe.phase import choose_phase_model
from labkit.vision.strobe.rolling_analysis import ends_separation, rolling_applies
from labkit.vision.strobe.rolling_model import (
    Crops,
    FitInput,
    fit_rolling,
    initial_guess,
    make_crops,
    render,
    slice_intervals,
)

MM_PER_PX = 0.05  # any scale: the millimetres must be the reported pixels scaled
CASE = "strobe-cylinder-37-medium"  # 320x240, no lamp, 1/5600 s exposure, readout 0.79 frame, rotor 243 Hz


@pytest.fixture(scope="module")
def rolling_clip(tmp_path_factory):
    (case,) = [c for c in suite_cases(only="strobe", difficulty="medium") if c.name == CASE]
    shot = replace(build_shot(case), frames=24)  # 2.6 apparent cycles (the suite has 60 frames)
    assert shot.lamp.hz is None and shot.camera.readout_s > 0  # the combination under test
    truth = strobe_truth(shot)
    path = write_footage(tmp_path_factory.mktemp("rolling") / "clip.mp4", render_strobe(shot),
                         shot.camera.fps, truth, jpeg_quality=shot.camera.jpeg_quality)
    given = analysis_inputs(truth)
    assert "strobe_hz" not in given  # the user gives the rotor frequency only: the camera is the strobe
    return truth, analyse_strobe(str(path), mm_per_px=MM_PER_PX, **given)


def test_rolling_camera_strobe_clip_is_within_tolerance(rolling_clip):
    truth, result = rolling_clip
    failures, errors = score_strobe(result.to_json(), truth)
    assert failures == [], errors
    assert result.verdict != "failed"
    rolling = result.rolling_shutter
    assert rolling is not None
    # the readout was not given: the footage tells it (renderer: 26.2 ms)
    assert not rolling.readout_given
    assert rolling.readout_s == pytest.approx(truth["readout_s"], rel=0.05)
    # the per-frame model would have been far off: the result's per-frame series is the smear's
    assert rolling.rows_explained > 0.9 > rolling.rows_explained_one_phase_per_frame + 0.3
    # the millimetres are the per-row model's amplitudes too, not the per-frame fit's (which were
    # 7.6 times smaller on this clip before the result was typed)
    in_mm, u = result.in_mm, result.uncertainty
    assert in_mm is not None and result.rc_offset_px is not None
    assert in_mm.lateral_amplitude_mm == pytest.approx(result.lateral_amplitude_px * MM_PER_PX, rel=1e-12)
    assert in_mm.rc_offset_mm == pytest.approx(result.rc_offset_px * MM_PER_PX, rel=1e-12)
    assert u.in_mm.lateral_amplitude_mm == pytest.approx(u.lateral_amplitude_px * MM_PER_PX, rel=1e-12)


def test_row_slices_match_an_independent_rectangle_coverage():
    """slice_intervals against labkit.footage.body (its own fill and supersampling): per row the
    covered width and its centre, for a rectangle rolled by an odd angle."""
    centre, axis_deg, length, width = (40.3, 41.7), 23.0, 50.0, 18.0
    roi = (0, 0, 90, 90)
    cover = coverage(outline(centre, axis_deg, length, width), roi)
    # footage: axis_deg from image-up towards +x; here alpha from image +x towards +y
    alpha = math.radians(axis_deg) - math.pi / 2
    rows = np.arange(90, dtype=float)
    sub = rows[:, None] + (np.arange(8) + 0.5) / 8 - 0.5
    lo, hi = slice_intervals(sub, centre[0], centre[1], alpha, length / 2, width / 2)
    widths = np.clip(hi - lo, 0, None).mean(axis=1)
    mass = cover.sum(axis=1)
    full = mass > 0.9 * mass.max()
    assert full.sum() > 20
    # px: the renderer's vertices snap to a 1/4 px grid and its edges are inset by 0.45 fine px
    assert np.abs(widths - mass)[full].max() < 0.3
    assert np.abs(widths - mass)[full].mean() < 0.12
    mid = np.where(hi > lo, 0.5 * (lo + hi), 0.0)
    centres = (mid * np.clip(hi - lo, 0, None)).sum(axis=1) / np.maximum(widths * 8, 1e-9)
    xs = np.arange(90)
    measured = (cover * xs).sum(axis=1) / np.maximum(mass, 1e-9)
    assert np.abs(centres - measured)[full].max() < 0.2


def _synthetic(g: dict, frames: np.ndarray, c: float, rng) -> Crops:
    n = len(frames)
    crops = Crops(frames, 30, 38, np.zeros((n, 64, 64), np.float32), np.ones((n, 64, 64), bool))
    tau = (frames - frames.mean()) / (np.ptp(frames) / 2)
    cover = render(g, np.full(n, 22.0), np.full(n, 8.0), frames, tau, c, crops)
    grey = 200.0 - 150.0 * cover ** 0.8 + rng.normal(0.0, 2.0, cover.shape)  # a dark body, a tone curve
    return make_crops(frames, 30, 38, grey.astype(np.float32))


def test_per_row_model_recovers_tilt_offset_and_line_time_from_synthetic_slices():
    rng = np.random.default_rng(3)
    truth = {"phi": 0.1, "delta": 35.0, "eps": 0.0, "psi0": 0.7, "omega": 0.15, "alpha0": -1.45,
             "sigma_core": 1.3, "sigma_halo": 4.0, "halo_fraction": 0.15, "cx": 60.0, "cy": 70.0,
             "x1": 0.0, "x2": 0.0, "y1": 0.0, "y2": 0.0}
    c, frames = 0.09, np.arange(0, 40, 4)
    crops = _synthetic(truth, frames, c, rng)
    given = FitInput(c, 240.0, 30.0, 240, -1.5, (21.0, 9.0), (60.5, 70.0))
    omega_max = 2 * math.pi * 240.0 / (30.0 * 239)
    start = initial_guess(crops, c, np.linspace(0, omega_max, 90))
    assert start.omega == pytest.approx(truth["omega"], rel=0.1)  # the linear start already finds it
    g, _, _, stats = fit_rolling(crops, given, start)
    assert g["phi"] == pytest.approx(truth["phi"], rel=0.02)
    assert abs(g["delta"]) == pytest.approx(truth["delta"], rel=0.03)
    assert g["omega"] == pytest.approx(truth["omega"], rel=0.01)
    assert stats["se"]["phi"] < 0.01 * truth["phi"]
    # given the readout, the line time is held where it was put
    fixed = replace(given, readout_s=truth["omega"] / (2 * math.pi * 240.0) * 239)
    g2, _, _, stats2 = fit_rolling(crops, fixed, start)
    assert "omega" not in stats2["se"] and g2["omega"] == pytest.approx(truth["omega"], rel=1e-9)
    assert g2["phi"] == pytest.approx(truth["phi"], rel=0.02)


def test_when_the_per_row_model_applies():
    camera = choose_phase_model(243.0, None, None, None, None, 30.0)
    lamp = choose_phase_model(243.0, 200.0, None, None, None, 30.0)
    assert rolling_applies(camera, 243.0, None, bend_px=2.0)  # a bent silhouette shows the rolling shutter
    assert not rolling_applies(camera, 243.0, None, bend_px=0.2)  # a straight one: global shutter
    assert rolling_applies(camera, 243.0, 0.02, bend_px=0.2)  # --readout-ms given
    assert not rolling_applies(camera, 243.0, 0.0, bend_px=2.0)  # --readout-ms 0: a global shutter
    assert not rolling_applies(lamp, 243.0, None, bend_px=2.0)  # a lamp: not this model


def test_ends_read_half_a_cycle_apart_cannot_show_a_swing_along_the_rows():
    up, right = np.array([0.0, 1.0]), np.array([1.0, 0.0])
    # swing along a vertical long side: only the ends show it; 100 rows apart at pi/100 per row
    assert ends_separation(math.pi / 100, up, 50.0, right, 10.0) == pytest.approx(0.0, abs=1e-9)
    assert ends_separation(2 * math.pi / 100, up, 50.0, right, 10.0) == pytest.approx(1.0)
    # swing across a vertical long side: every row shows it
    assert ends_separation(math.pi / 100, right, 10.0, up, 50.0) is None


@pytest.fixture(scope="module")
def rows_along_the_body(tmp_path_factory):
    """The same clip with the rotor axis horizontal (Fig. 5.19): the cylinder lies along the rows."""
    (case,) = [c for c in suite_cases(only="strobe", difficulty="medium") if c.name == CASE]
    shot = replace(build_shot(case), frames=24, rest_deg=90.0)
    truth = strobe_truth(shot)
    path = write_footage(tmp_path_factory.mktemp("rolling-along") / "clip.mp4", render_strobe(shot),
                         shot.camera.fps, truth, jpeg_quality=shot.camera.jpeg_quality)
    return truth, str(path)


def test_rows_along_the_body_are_doubtful_and_name_the_rolling_shutter(rows_along_the_body):
    truth, path = rows_along_the_body
    given = analysis_inputs(truth)
    # a horizontal body hardly bends: the per-frame analysis runs, and its verdict names the cause
    plain = analyse_strobe(path, **given)
    assert plain.quality.verdict != "ok"
    assert any("rolling shutter" in r for r in plain.quality.reasons)
    # given the readout, the per-row model runs and says it is poorly conditioned
    per_row = analyse_strobe(path, **given, readout_s=truth["readout_s"])
    assert per_row.rolling_shutter.long_side_from_rows_deg < 30
    assert per_row.quality.verdict != "ok"
    assert any("rows run along the body" in r for r in per_row.quality.reasons)
