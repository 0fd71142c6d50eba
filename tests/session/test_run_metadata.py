"""run.json says what ran, with what, from which code, when, and how it ended."""

import json
import re
import subprocess
from pathlib import Path

from labkit.protocols.launch import execute, prepare_run

REPO = Path(__file__).resolve().parents[2]
RIG = REPO / "rigs" / "emulated-fig525.toml"


def test_run_json_records_rig_versions_commit_times_notes_and_status(tmp_path):
    prep = prepare_run(RIG, "speed-sweep", ["speeds_rpm=8000", "record_s=0.5", "zero=start"],
                       session_root=tmp_path)
    outcome = execute(prep, tmp_path, notes="magnet B, new bearing")
    meta = json.loads((outcome.session / "run.json").read_text())
    assert meta["protocol"] == "speed-sweep" and meta["rig"] == "emulated-fig525"
    assert meta["params"]["speeds_rpm"] == [8000.0]
    assert meta["notes"] == "magnet B, new bearing"
    assert meta["status"] == "completed" and meta["reason"] is None
    assert meta["clock"] == "virtual"
    assert meta["started"] <= meta["ended"]          # ISO 8601 UTC strings sort in time order
    assert {"python", "labkit", "numpy", "pyserial"} <= set(meta["versions"])
    head = subprocess.run(["git", "-C", str(REPO), "rev-parse", "HEAD"], capture_output=True, text=True)
    if head.returncode == 0:
        assert meta["git_commit"] == head.stdout.strip()
    else:
        assert meta["git_commit"] is None
    assert meta["git_commit"] is None or re.fullmatch(r"[0-9a-f]{40}", meta["git_commit"])
    assert (outcome.session / meta["rig_file"]).read_text() == RIG.read_text()


def test_a_failed_run_says_why_in_run_json(tmp_path):
    # the rotor tachometer is unplugged 3 s in: an interlock ends the run
    rig = tmp_path / "unplug.toml"
    rig.write_text(RIG.read_text().replace("role=rotor_tach&", "role=rotor_tach&faults=disconnect_at:3&"))
    prep = prepare_run(rig, "speed-sweep", ["speeds_rpm=8000,12000", "record_s=2", "zero=start"],
                       session_root=tmp_path / "s")
    outcome = execute(prep, tmp_path / "s")
    meta = json.loads((outcome.session / "run.json").read_text())
    assert meta["status"] == "failed"
    assert "rotor_tach" in meta["reason"]
    assert meta["ended"] is not None


def test_folder_names_are_utc_and_documented_so(tmp_path, monkeypatch):
    """Issue 27: the folder's stamp is UTC (docs/reference/session-format.md, Layout), whatever TZ says."""
    import datetime as dt
    import time

    from labkit.session import Session

    monkeypatch.setenv("TZ", "Pacific/Kiritimati")  # UTC+14: a local-time stamp would differ by 14 h
    time.tzset()
    try:
        session = Session.create(tmp_path, protocol="speed-sweep", params={}, rig_name="r", rig_text="",
                                 clock="virtual")
    finally:
        monkeypatch.delenv("TZ")
        time.tzset()
    started = dt.datetime.fromisoformat(session.meta["started"])
    assert started.utcoffset() == dt.timedelta(0)
    assert session.path.name == started.strftime("%Y%m%d-%H%M%S") + "-speed-sweep"
    layout = (REPO / "docs" / "reference" / "session-format.md").read_text()
    assert "`YYYYmmdd-HHMMSS-PROTOCOL` from the moment it was created **in UTC**" in layout
    assert "--web-viewer --bind 127.0.0.1" in (REPO / "docs" / "reference" / "streams.md").read_text()
