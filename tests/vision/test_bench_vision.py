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
