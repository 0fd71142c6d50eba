"""``labkit report``: the folder exists, is self-contained and carries the fitted numbers."""

from __future__ import annotations

import json
import re
from importlib import resources
from pathlib import Path

import cv2
import numpy as np
import pytest

from labkit.cli import main
from labkit.fit import FitOptions, fit_table, load_table
from labkit.fit.synthetic import write_sweep_session
from labkit.report import markdown as md
from labkit.report.build import build_report

PNG = b"\x89PNG\r\n\x1a\n"
PAPER_CSV = resources.files("labkit") / "data" / "paper" / "fig6_18_spin_critical.csv"


def images_linked(report: Path) -> list[str]:
    return re.findall(r"!\[[^\]]*\]\(([^)]+)\)", report.read_text())


def test_speed_sweep_session_report(tmp_path: Path):
    session = write_sweep_session(tmp_path / "sweep", noise=0.02, seed=3)
    (session / "rig.toml").write_text("[bodies.floator]\ninertia_radial_kg_m2 = 1e-7\n")
    report = build_report(session)
    assert report == session / "report" / "report.md"
    text = report.read_text()
    folder = report.parent
    # self-contained: every linked figure is a PNG inside the folder
    links = images_linked(report)
    assert {"fig-power-law.png", "fig-pfr-force.png", "fig-pfr-omega2.png"} <= set(links)
    for name in links:
        assert (folder / name).read_bytes()[:8] == PNG
    # metadata, data table and the fitted numbers
    assert "emulated-fig5.25" in text and "synthetic test session" in text
    assert (folder / "data.csv").read_text().startswith("speed_rpm,speed_rad_s,force_g")
    expected = fit_table(load_table(session), "power-law").series["all"]
    assert md.num(expected.params["b"].value) in text
    assert md.num(expected.params["a"].value) in text
    fits = json.loads((folder / "fits.json").read_text())
    assert fits["power-law"]["series"]["all"]["params"]["b"]["ci95"][0] < -1.8
    assert "## Model comparison" in text and "ΔAIC" in text


def test_spin_critical_report_from_paper_csv(tmp_path: Path):
    report = build_report(str(PAPER_CSV), tmp_path / "fig618")
    text = report.read_text()
    for name, C in (("1", 4.7e5), ("2", 6.63e5)):
        res = fit_table(load_table(str(PAPER_CSV)), "spin-critical", FitOptions(omega_c=3000.0)).series[name]
        assert res.params["C"].value == pytest.approx(C, rel=0.01)
        assert md.num(res.params["C"].value) in text
    assert "fig-eq637.png" in images_linked(report)
    comparison = text.split("## Model comparison")[1]
    rows = [line for line in comparison.splitlines() if line.startswith("| ")][1:]
    assert sorted(line.split(" | ")[0] for line in rows) == ["| 1"] * 3 + ["| 2"] * 3


def test_csv_with_unknown_columns_needs_a_model(tmp_path: Path):
    csv = tmp_path / "mystery.csv"
    x = np.linspace(1, 10, 8)
    csv.write_text("u,v\n" + "".join(f"{a},{3 * a**-2}\n" for a in x))
    text = build_report(csv).read_text()
    assert "No model applies" in text
    text = build_report(csv, tmp_path / "r2", model="power-law", x="u", y="v").read_text()
    assert "fig-power-law.png" in text


def make_clip(path: Path, center=(80, 60), axes=(30, 18), angle=20.0, frames=12) -> None:
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 30.0, (160, 120))
    assert writer.isOpened()
    for i in range(frames):
        img = np.zeros((120, 160, 3), np.uint8)
        t = 2 * np.pi * i / frames
        x = center[0] + axes[0] * np.cos(t)
        y = center[1] + axes[1] * np.sin(t)
        cv2.circle(img, (int(x), int(y)), 3, (255, 255, 255), -1)
        writer.write(img)
    writer.release()


def test_video_result_contact_sheet(tmp_path: Path):
    clip = tmp_path / "clip.avi"
    make_clip(clip)
    result = tmp_path / "laser.json"
    result.write_text(json.dumps({
        "source": str(clip), "frames": 12, "fps": 30.0, "size": [160, 120],
        "pattern": {"type": "ellipse", "center_px": [80, 60], "semi_axes_px": [30, 18], "rotation_deg": 0.0,
                    "ellipticity": 0.4, "loops": 1, "trochoid": None, "rms_residual_px": 0.8},
        "tilt_rad": {"major": 0.19, "minor": 0.12}, "quality": {}}))
    report = build_report(result, tmp_path / "video-report")
    text = report.read_text()
    assert "contact-sheet.png" in images_linked(report)
    assert (report.parent / "contact-sheet.png").read_bytes()[:8] == PNG
    assert "ellipse" in text and "0.19" in text


def test_cli_report_and_errors(tmp_path: Path, capsys):
    session = write_sweep_session(tmp_path / "s")
    assert main(["report", str(session), "--out", str(tmp_path / "out")]) == 0
    assert "report written" in capsys.readouterr().out
    assert (tmp_path / "out" / "report.md").exists()
    assert main(["report", str(tmp_path / "missing")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("labkit report:") and "no such file" in err and "\n" not in err


def test_events_summary_lists_interlocks_and_survives_a_cut_line(tmp_path: Path):
    session = write_sweep_session(tmp_path / "s")
    events = [{"type": "setpoint", "t": 0.0}, {"type": "setpoint", "t": 1.0},
              {"type": "interlock", "t": 2.0, "reason": "tachometer silent"}]
    (session / "events.jsonl").write_text("".join(json.dumps(e) + "\n" for e in events) + '{"type": "poi')
    text = build_report(session).read_text()
    section = text.split("## Events")[1].split("## Data")[0]
    assert "| setpoint | 2 |" in section and "| interlock | 1 |" in section
    assert "tachometer silent" in section


def test_overlay_only_on_figures_in_its_units(tmp_path: Path):
    from labkit.fit.overlay import overlay_from_function
    ov = overlay_from_function("sim", lambda rpm: 224e6 * rpm**-1.9, [6000, 20000],
                               x_name="speed_rpm", y_name="force_g")
    assert ov.fits("speed_rpm", "force_g") and not ov.fits("speed_rad_s", "force_n")
    assert ov.y[0] == pytest.approx(224e6 * 6000**-1.9)
    report = build_report(write_sweep_session(tmp_path / "s"), overlays=(ov,))
    assert (report.parent / "fig-power-law.png").exists()


def test_overlay_csv_on_the_command_line(tmp_path: Path):
    from labkit.fit.overlay import overlays_from_csv
    sim = tmp_path / "sim.csv"
    sim.write_text("speed_rpm,force_g,force_upper_g\n20000,1.5,1.6\n6000,14.8,15.0\n")
    ovs = overlays_from_csv(sim)
    assert [(o.x_name, o.y_name) for o in ovs] == [("speed_rpm", "force_g"), ("speed_rpm", "force_upper_g")]
    assert ovs[0].x.tolist() == [6000.0, 20000.0] and ovs[0].y.tolist() == [14.8, 1.5]   # sorted by x
    session = write_sweep_session(tmp_path / "s")
    assert main(["report", str(session), "--overlay", str(sim)]) == 0
    assert main(["fit", str(session), "--model", "power-law", "--overlay", str(sim),
                 "--plot", str(tmp_path / "p.png")]) == 0
    assert (tmp_path / "p.png").read_bytes()[:8] == PNG


def test_strobe_result_report(tmp_path: Path):
    clip = tmp_path / "strobe.avi"
    make_clip(clip)
    result = tmp_path / "strobe.json"
    result.write_text(json.dumps({
        "source": str(clip), "frames": 12, "fps": 30.0, "apparent_hz": 0.5, "tilt_amplitude_rad": 0.213,
        "lateral_amplitude_px": 4.1, "rc_offset_px": 18.7, "rc_offset_direction": "towards body top",
        "phase_source": "signal",
        "point_pattern": {"type": "ellipse", "center_px": [80, 60], "semi_axes_px": [30, 18],
                          "rotation_deg": 0.0, "ellipticity": 0.4, "loops": 1, "trochoid": None,
                          "rms_residual_px": 0.5},
        "quality": {}}))
    report = build_report(result, tmp_path / "strobe-report")
    text = report.read_text()
    assert "stroboscope" in text and "towards body top" in text
    assert "| cone angle φ | 0.213 (12.20°) | no uncertainty (not in the analysis result) | rad |" in text
    assert "**Not drawn:** the result has no phase per frame." in text
    assert (report.parent / "contact-sheet.png").read_bytes()[:8] == PNG
