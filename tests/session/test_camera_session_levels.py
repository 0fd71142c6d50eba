"""A real-clock camera session is re-analysed, not replayed faithfully (the faithful level serves
serial cassettes only), and the analysis-only level says that a protocol without an analysis
rule had its points taken as recorded rather than claiming it recomputed them (issue 23)."""

import json
import shutil
from pathlib import Path

from labkit.cli import main

FIXTURE = Path(__file__).resolve().parents[2] / "recordings" / "sessions" / "cone-sweep-clean"


def test_a_real_clock_camera_session_says_why_it_is_re_analysed_and_what_was_not(tmp_path, capsys):
    session = tmp_path / "cone"
    shutil.copytree(FIXTURE, session)
    meta = json.loads((session / "run.json").read_text())
    meta["clock"] = "real"  # as a lab's cone-sweep records it
    (session / "run.json").write_text(json.dumps(meta))
    (session / "clock.jsonl").write_text("")
    assert main(["replay", str(session)]) == 0
    captured = capsys.readouterr()
    assert "cassettes/camera.jsonl holds camera frames" in captured.err
    assert "no analysis-only rule for protocol 'cone-sweep'" in captured.err
    assert "points taken as recorded" in captured.out + captured.err
    assert "recomputed from the recorded bytes" not in captured.out + captured.err
