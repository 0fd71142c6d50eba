"""``labkit bench vision`` on a small clip: every quality setting is reported with its time, its
ratio to decode-only reading and its accuracy against the synthetic ground truth."""

import re

from labkit.cli import main
from labkit.cli.bench_vision import settings


def test_bench_vision_reports_every_setting_with_ratio_and_accuracy(capsys, tmp_path):
    rc = main(["bench", "vision", "--strobe", "no", "--size", "320x240", "--frames", "64",
               "--level", "medium", "--repeats", "2", "--keep", str(tmp_path)])
    out = capsys.readouterr().out
    assert rc == 0
    assert (tmp_path / "bench-ellipse-medium-320x240.mp4").exists()
    rows = {line[:46].strip(): line[46:] for line in out.splitlines() if re.search(r"\d\.\d\dx", line)}
    assert "decode only (VideoCapture.read, BGR)" in rows  # the reference against itself: the noise
    for name, _ in settings((0, 0, 320, 240)):
        row = rows[name]
        ratio = re.search(r"(\d+\.\d\d)x \((\d+\.\d\d)-(\d+\.\d\d)\)", row)
        assert ratio and float(ratio[2]) <= float(ratio[1]) <= float(ratio[3])
        centre = re.search(r"centre +(\d+\.\d\d) px +axes +(\d+\.\d\d) %", row)
        assert centre, row
        assert float(centre[1]) < 3.0  # every setting still finds the ellipse


def test_bench_vision_prints_the_strobe_ratios_and_peak_memory(capsys, tmp_path):
    """One row per clip (small and large body, with and without room light), each with its time
    over the clip's duration, its peak memory and its errors against the renderer's truth."""
    rc = main(["bench", "vision", "--strobe", "only", "--strobe-sizes", "320x240", "--strobe-frames", "45",
               "--keep", str(tmp_path)])
    out = capsys.readouterr().out
    assert rc == 0
    rows = [line for line in out.splitlines() if line.startswith("320x240")]
    assert len(rows) == 4 and len(list(tmp_path.glob("strobe-320x240-*.avi"))) == 4
    for row in rows:
        ratios = re.findall(r"(\d+\.\d\d)x", row)
        assert len(ratios) == 2 and all(float(r) > 0 for r in ratios), row
        peak = re.search(r"x +(\d+) +[-+]\d", row)
        assert peak and 30 < int(peak[1]) < 2000, row  # MB: a Python with numpy and OpenCV
        assert re.search(r"[-+]\d+\.\d\d% +[-+]\d+\.\d\d px", row), row
    assert re.search(r"slowest: .* the clip's duration in CPU time; peak memory \d+ MB", out)
