"""The report reads its fits from the session's start-document hints: hints it cannot read are
an error naming the file and the key, never a report with the wrong fits (ADR 0021)."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from labkit.errors import DataFileError
from labkit.report.build import build_report

SESSION = Path(__file__).resolve().parents[2] / "recordings" / "sessions" / "spin-critical-clean"


def with_start_hints(tmp_path: Path, hints: dict) -> Path:
    session = tmp_path / SESSION.name
    shutil.copytree(SESSION, session)
    lines = (session / "events.jsonl").read_text().splitlines()
    start = json.loads(lines[0])
    assert start["type"] == "start" and "hints" not in start   # recorded before hints
    lines[0] = json.dumps({**start, "hints": hints})
    (session / "events.jsonl").write_text("\n".join(lines) + "\n")
    return session


def test_damaged_hints_name_the_file_and_key(tmp_path):
    session = with_start_hints(tmp_path, {"x": "rotor_rad_s"})
    with pytest.raises(DataFileError, match=r"events.jsonl.*hints.*cannot be read"):
        build_report(session, tmp_path / "out")


def test_the_start_documents_hints_win_over_the_protocol_name(tmp_path):
    hints = {"x": "rotor_rad_s", "y": "spin_rad_s", "x_name": "rotor", "x_unit": "rad/s",
             "y_name": "spin", "y_unit": "rad/s", "fit": "power-law"}
    session = with_start_hints(tmp_path, hints)
    text = build_report(session, tmp_path / "out").read_text()
    assert "### power-law fit: spin [rad/s] against rotor [rad/s]" in text
    assert "Eq. 6.37" not in text   # the legacy table's fits of "spin-critical" were not used
