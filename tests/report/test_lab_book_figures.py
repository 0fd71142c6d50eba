"""Lab-book figures: error bars from the recorded spread, axes with quantity and unit, SVG
beside PNG, events in words; the strobe report's phase figure and phi/beta/delta uncertainties."""

import json
import re
from pathlib import Path

from labkit.cli import main
from labkit.report.build import build_report, event_in_words
from labkit.report.labels import axis_label, residual_label

PNG = b"\x89PNG\r\n\x1a\n"


def test_sweep_report_has_error_bars_unit_labels_and_svg(tmp_path: Path, capsys):
    assert main(["demo", "--sessions", str(tmp_path / "s"), "--no-progress",
                 "--set", "speeds_rpm=6000:12000:2000"]) == 0
    session = next((tmp_path / "s").iterdir())
    points = json.loads((session / "results.json").read_text())["points"]
    assert all("force_stderr_g" in p and "speed_std_rpm" in p for p in points)
    report = build_report(session, tmp_path / "r")
    svg = (report.parent / "fig-power-law.svg").read_text()
    assert (report.parent / "fig-power-law.png").read_bytes()[:8] == PNG
    assert "force [g]" in svg and "rotor speed [RPM]" in svg and "force_g" not in svg
    assert 'id="errorbar-y-all"' in svg and 'id="errorbar-x-all"' in svg
    assert "paper Fig. 5.25" in svg   # the paper's curve is in the figure, drawn above the fit
    text = report.read_text()
    assert "fig-power-law.svg" in text
    digits = [len(n.replace(".", "").lstrip("0")) for n in re.findall(r"\d+\.\d+", text)]
    assert digits and max(digits) <= 6, "a raw float (more than 6 significant digits) in report.md"
    assert "{" not in text.split("## Data")[0], "raw JSON in the metadata or events"


def test_events_are_written_in_words():
    drop = {"type": "drop", "t": 12.256, "rotor_rad_s": 693.97, "spin_rad_s": 174.66, "cause": "balance"}
    assert event_in_words(drop) == ("12.26 s: the floator dropped (balance) at rotor 694 rad/s, "
                                    "spin 174.7 rad/s")
    stop = {"type": "stop", "t": 3.0, "status": "interrupted", "steps_done": 2, "reason": "Ctrl-C"}
    assert event_in_words(stop) == "3.00 s: run interrupted after 2 steps (Ctrl-C)"


def test_labels_name_quantity_and_unit():
    assert axis_label("speed_rpm") == "rotor speed [RPM]"
    assert axis_label("gap_mm") == "gap [mm]"
    assert residual_label("ln(force_g)") == "ln(force [g])"


def _strobe_result(tmp_path: Path, capsys) -> Path:
    clip, out = tmp_path / "strobe.avi", tmp_path / "strobe.json"
    assert main(["synth", "strobe", str(clip), "--level", "easy", "--frames", "40", "--codec", "MJPG",
                 "--rotor-hz", "240", "--strobe-hz", "234", "--seed", "2"]) == 0
    main(["analyse", "strobe", str(clip), "--rotor-hz", "240", "--strobe-hz", "234", "--json", str(out)])
    return out


def test_strobe_report_draws_tilt_and_position_against_phase(tmp_path: Path, capsys):
    result = _strobe_result(tmp_path, capsys)
    report = build_report(result, tmp_path / "r")
    text = report.read_text()
    assert "![tilt and lateral position against phase](fig-strobe-phase.png)" in text
    assert (report.parent / "fig-strobe-phase.png").read_bytes()[:8] == PNG
    svg = (report.parent / "fig-strobe-phase.svg").read_text()
    assert "tilt θ [rad]" in svg and "rotation phase ψ [rad]" in svg
    # the strobe analysis writes a standard error for phi, beta and delta (its "uncertainty")
    assert "no uncertainty" not in text
    assert text.count(" rad |") >= 1 and text.count(" px |") >= 2


def test_strobe_report_shows_standard_errors_the_analysis_wrote(tmp_path: Path, capsys):
    result = _strobe_result(tmp_path, capsys)
    doc = json.loads(result.read_text())
    doc["uncertainty"].update(tilt_amplitude_rad=0.0012, lateral_amplitude_px=0.034, rc_offset_px=0.56)
    result.write_text(json.dumps(doc))
    text = build_report(result, tmp_path / "r").read_text()
    assert "| 0.0012 | rad |" in text and "| 0.034 | px |" in text and "| 0.56 | px |" in text
    assert "no uncertainty" not in text


def test_cone_sweep_report_draws_the_cone_angle_with_error_bars_on_data_and_residuals(tmp_path: Path):
    """The committed cone-sweep session: its Eq. 5.24 figure has the odd/even halves' spread as
    error bars, on the residuals too (where they are visible: the data's are under the markers)."""
    report = build_report(Path("recordings/sessions/cone-sweep-clean"), tmp_path / "r")
    svg = (report.parent / "fig-cone-angle.svg").read_text()
    assert (report.parent / "fig-cone-angle.png").read_bytes()[:8] == PNG
    assert 'id="errorbar-y-all"' in svg and 'id="errorbar-residual-all"' in svg
    assert "cone angle" in svg and "bars: recorded spread" in svg
    assert "fig-cone-angle.png" in report.read_text()
