"""Notes and names in any encoding survive `labkit report` (issue 27): a Latin-1 byte in
`--notes` or in the session's folder name (a lone surrogate in Python) and a lone surrogate
escaped in run.json are written out as escapes, not a UnicodeEncodeError traceback."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

SESSIONS = Path(__file__).resolve().parents[2] / "recordings" / "sessions"


def test_a_latin1_name_and_lone_surrogates_in_notes_make_a_report(tmp_path):
    session = tmp_path / os.fsdecode(b"caf\xe9-session")  # a folder named on a Latin-1 system
    shutil.copytree(SESSIONS / "speed-sweep-clean", session)
    meta = json.loads((session / "run.json").read_text())
    meta["notes"] = "magnet caf\udce9, \ud800 end"  # as run.json holds `--notes $'caf\xe9'`
    (session / "run.json").write_text(json.dumps(meta))
    env = {k: v for k, v in os.environ.items() if k != "PYTHONIOENCODING"}
    done = subprocess.run([sys.executable, "-m", "labkit", "report", os.fsencode(session)],
                          capture_output=True, env={**env, "LC_ALL": "C.UTF-8"}, timeout=120)
    err = done.stderr.decode("utf-8", "replace")
    assert done.returncode == 0 and "Traceback" not in err, err
    assert b"report written: " + os.fsencode(session).replace(b"\xe9", b"\\udce9") in done.stdout, done.stdout
    report = (session / "report" / "report.md").read_text(encoding="utf-8")
    assert "| notes | magnet caf\\xe9, \\ud800 end |" in report, report
