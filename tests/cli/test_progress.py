"""Progress lines for long jobs (labkit.cli.progress) and the laser analysis' progress hook."""

from __future__ import annotations

import io
from pathlib import Path

from labkit.cli.progress import ProgressLines
from labkit.vision.laser.analyse import analyse_laser

CLIP = Path(__file__).resolve().parents[2] / "recordings" / "videos" / "laser-ellipse-medium.mp4"


class FakeClock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


def test_a_short_job_says_nothing_and_a_long_one_one_line_per_interval():
    clock, out = FakeClock(), io.StringIO()
    progress = ProgressLines("labkit analyse laser: clip.mp4", "frames", stream=out, clock=clock)
    for done in range(1, 8):  # to 1.75 s: silent (steps of 1/4 s: exact in binary)
        clock.t += 0.25
        progress(done, 900)
    assert out.getvalue() == ""
    for done in range(8, 28):  # 2.0 .. 6.75 s: a line at 2 s, 4 s and 6 s
        clock.t += 0.25
        progress(done, 900)
    lines = out.getvalue().splitlines()
    assert len(lines) == 3 == progress.lines
    assert lines[0] == "labkit analyse laser: clip.mp4: 8 of 900 frames (2 s so far)"
    progress.say("fitting")
    assert out.getvalue().splitlines()[-1].startswith("labkit analyse laser: clip.mp4: fitting (")


def test_unknown_totals_print_the_count_alone():
    clock, out = FakeClock(), io.StringIO()
    progress = ProgressLines("x", "frames", stream=out, clock=clock, after_s=0.0)
    progress(7, 0)
    assert out.getvalue() == "x: 7 frames (0 s so far)\n"


def test_laser_analysis_reports_its_frames_as_it_reads_them():
    seen: list[tuple[int, int]] = []
    result = analyse_laser(str(CLIP), on_progress=lambda done, total: seen.append((done, total)))
    assert len(seen) >= 2, seen
    done = [d for d, _ in seen]
    assert done == sorted(done) and done[-1] == result.quality.evidence["frames_analysed"]
    assert all(total == seen[0][1] > 0 for _, total in seen)


def test_synth_says_how_far_a_long_clip_is(tmp_path, capsys):
    """Issue 27: `labkit synth` of a long clip printed nothing until done. A clip rendered in
    over 3 s shows `N of 600 frames (...)` lines; one under 2 s stays silent."""
    import time

    from labkit.cli import main

    start = time.monotonic()
    assert main(["synth", "laser", str(tmp_path / "long.mp4"), "--frames", "600"]) == 0
    elapsed = time.monotonic() - start
    lines = [line for line in capsys.readouterr().err.splitlines() if " of 600 frames (" in line]
    if elapsed > 3.0:
        assert lines and lines[0].startswith(f"labkit synth: {tmp_path / 'long.mp4'}: "), (elapsed, lines)
    if elapsed < 2.0:
        assert not lines, (elapsed, lines)
