"""The strobe phase models (P1 of docs/explanation/strobe-analysis.md), the standard errors of the Eq. 5.97
fit, and ``labkit analyse strobe`` as a user runs it: verdict in words, overlay PNG, failed exits 1."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import cv2
import numpy as np
import pytest
from strobe_scenes import Scene, write

from labkit.vision.strobe.motion_fit import fit_motion, t1
from labkit.vision.strobe.phase import choose_phase_model, fold


def test_lamp_with_several_flashes_per_frame():
    """199.5 Hz lamp, 200 Hz rotor, 30 fps camera with 1/60 s exposure: f_a = 0.5 Hz in real time,
    1/60 cycle per frame; the one-flash-per-frame model said 0.5/199.5 cycle per frame."""
    m = choose_phase_model(200.0, 199.5, None, None, 1 / 60, 30.0)
    assert (m.kind, m.harmonic_m) == ("lamp", 1)
    assert m.cycles_per_frame == pytest.approx(0.5 / 30)
    assert m.flashes_per_frame == pytest.approx(199.5 / 60)
    assert m.cycles_per_exposure == pytest.approx(0.5 / 60)


def test_second_harmonic_and_negative_apparent_frequency():
    m = choose_phase_model(398.2, 199.5, None, None, None, 30.0)
    assert m.harmonic_m == 2
    assert m.apparent_hz == pytest.approx(398.2 - 399.0)
    assert m.cycles_per_frame == pytest.approx(-0.8 / 30)


def test_one_flash_per_frame_is_the_special_case():
    """F = f_s: c = f_rot / f_s - m, the model labkit had before."""
    m = choose_phase_model(240.0, 15.15, None, None, None, 15.15)
    assert m.cycles_per_frame == pytest.approx(240 / 15.15 - 16)


def test_camera_as_strobe_and_camera_fps_override():
    m = choose_phase_model(240.0, None, None, 15.15, 0.0005, 30.0)
    assert m.kind == "camera"
    assert m.cycles_per_frame == pytest.approx(240 / 15.15 - 16)
    assert m.cycles_per_exposure == pytest.approx(240 * 0.0005)
    assert m.blur_factor == pytest.approx(math.sin(math.pi * 0.12) / (math.pi * 0.12))
    with pytest.raises(ValueError, match="--camera-fps"):
        choose_phase_model(240.0, None, None, None, None, 0.0)


def test_apparent_and_signal_models():
    apparent = choose_phase_model(None, None, 2.4, None, None, 15.15)
    assert apparent.cycles_per_frame == pytest.approx(2.4 / 15.15)
    assert choose_phase_model(None, None, None, None, None, 30.0) is None
    assert fold(-0.13) == pytest.approx(0.13) and fold(0.87) == pytest.approx(0.13)


def test_t1_is_the_first_harmonic_of_tan():
    for phi in (0.05, 0.3, 0.8):
        psi = np.linspace(0, 2 * np.pi, 20000, endpoint=False)
        assert t1(phi) == pytest.approx(2 * np.mean(np.tan(phi * np.sin(psi)) * np.sin(psi)), rel=1e-6)
    assert t1(0.1) == pytest.approx(0.1 + 0.1 ** 3 / 4, rel=1e-4)


def test_standard_errors_match_the_scatter_of_repeated_fits():
    """Eq. 5.97 samples with noise: over 300 seeded repeats the spread of phi, beta and delta
    agrees with the mean reported standard error within 20 %, and the fit is unbiased."""
    phi, delta, n = 0.2, 40.0, 60
    psi = 2 * np.pi * 0.13 * np.arange(n) + 0.7
    rng = np.random.default_rng(5)
    fits = []
    for _ in range(300):
        tilt = phi * np.sin(psi) + rng.normal(0, 0.01, n)
        lateral = 100 - delta * np.tan(phi * np.sin(psi)) + rng.normal(0, 0.3, n)
        fits.append(fit_motion(psi, tilt, lateral))
    for name, se_name, truth in (("phi", "phi_se", phi), ("beta", "beta_se", delta * math.tan(phi)),
                                 ("delta", "delta_se", delta)):
        values = np.array([getattr(f, name) for f in fits])
        reported = np.array([getattr(f, se_name) for f in fits])
        assert np.std(values) == pytest.approx(np.mean(reported), rel=0.2), name
        bound = 3 * np.std(values) / math.sqrt(len(fits)) + 1e-3 * truth
        assert np.mean(values) == pytest.approx(truth, abs=bound), name


def _run(*args):
    return subprocess.run([sys.executable, "-m", "labkit", "analyse", "strobe", *map(str, args)],
                          capture_output=True, text=True, timeout=300)


def test_cli_says_the_verdict_and_draws_the_overlay(tmp_path):
    s = Scene(rest_deg=3.0, seed=12, frames=60)
    clip = write(s, tmp_path / "rotor.avi")
    out, js = tmp_path / "overlay.png", tmp_path / "r.json"
    p = _run(clip, "--rotor-hz", s.rotor_hz, "--strobe-hz", s.strobe_hz, "--overlay", out, "--json", js)
    assert p.returncode == 0, p.stderr
    assert "quality: ok" in p.stdout
    assert "+-" in p.stdout  # uncertainties printed
    doc = json.loads(js.read_text())
    assert doc["quality"]["verdict"] == "ok" and doc["quality"]["reasons"] == []
    assert set(doc["uncertainty"]) >= {"tilt_amplitude_rad", "lateral_amplitude_px", "rc_offset_px"}
    img = cv2.imread(str(out))
    assert img is not None and img.shape[:2] == (240, 320)
    frame = cv2.VideoCapture(str(clip)).read()[1]
    assert np.mean(np.abs(img.astype(int) - frame.astype(int))) > 1.0  # something was drawn


def test_cli_failed_verdict_exits_1_with_one_line(tmp_path):
    s = Scene(frames=12, seed=13)
    clip = write(s, tmp_path / "short.avi")
    p = _run(clip, "--rotor-hz", s.rotor_hz, "--strobe-hz", s.strobe_hz)
    assert p.returncode == 1
    lines = p.stderr.strip().splitlines()
    assert len(lines) == 1 and str(clip) in lines[0] and "too little of the cycle" in lines[0]
    assert "quality: FAILED" in p.stdout
    assert "Traceback" not in p.stderr
