"""A labkit sketch on the simulated MCU as a lab's device (issue 23): the strobe sketch
(firmware/labkit_strobe) runs on simavr behind a pty, `labkit run strobe-sweep --clock real`
talks to it as to the Arduino on a USB adapter, and the session replays faithfully from its
cassettes. The same recording, made by analysis/record_real_sessions.py, is shipped as
recordings/sessions/real-sketch-strobe-sweep and replayed by tests/session/test_real_clock_replay.py
(there without the toolchain: a replay needs only the cassettes)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

from labkit.protocols.replay import replay_session

ROOT = Path(__file__).resolve().parents[2]


def _recorder():
    path = ROOT / "analysis" / "record_real_sessions.py"
    spec = importlib.util.spec_from_file_location("record_real_sessions", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_real_clock_strobe_sweep_on_the_strobe_sketch_replays_faithfully(firmware, tmp_path):
    recorder = _recorder()
    spec = {**recorder.RECORDINGS["real-sketch-strobe-sweep"], "speeds_rpm": [4000.0], "clip_s": 1.0}
    status, session, err = recorder.record_sketch(spec, tmp_path, tmp_path / "clips", built=firmware)
    assert status == 0 and session is not None, err[-600:]
    meta = json.loads((session / "run.json").read_text())
    assert meta["clock"] == "real" and meta["status"] == "completed"
    point = json.loads((session / "results.json").read_text())["points"][0]
    # the sketch's own status lines: the ICP pulse at 4000 RPM, the driver's DIV 4 and OFFSET 1
    assert abs(point["rotor_hz"] - 4000 / 60) < 1e-3 and abs(point["apparent_hz"] - 1.0) < 2e-3
    assert point["verdict"] == "ok" and point["strobe_flags"] == []
    lines = [json.loads(x) for x in (session / "readings" / "strobe.jsonl").read_text().splitlines()]
    assert lines[0]["type"] == "descriptor" and lines[0]["unit"] == "Hz"   # the stream declared once
    assert lines[1:] and all(x["raw"].startswith("S,") for x in lines[1:])
    result = replay_session(session)
    assert result.level == "faithful" and result.identical, result.differences[:5]
