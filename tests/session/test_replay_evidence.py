"""An edited session is named by `labkit replay` (issue 27): a reading or a point that no longer
follows from the cassettes' bytes makes the replay exit 1 naming file and line, though
results.json is untouched."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from labkit.cli import main

SESSIONS = Path(__file__).resolve().parents[2] / "recordings" / "sessions"


def _copy(tmp_path: Path, name: str) -> Path:
    session = tmp_path / name
    shutil.copytree(SESSIONS / name, session)
    return session


def _edit_line(path: Path, number: int, edit) -> None:
    lines = path.read_text().splitlines()
    lines[number - 1] = json.dumps(edit(json.loads(lines[number - 1])))
    path.write_text("\n".join(lines) + "\n")


def test_a_doubled_balance_reading_is_named(tmp_path, capsys):
    session = _copy(tmp_path, "speed-sweep-clean")
    _edit_line(session / "readings" / "balance.jsonl", 40, lambda r: {**r, "value": r["value"] * 2})
    assert main(["replay", str(session)]) == 1
    err = capsys.readouterr().err
    assert "readings/balance.jsonl:40: this reading does not follow from the cassette" in err, err


def test_an_edited_point_event_is_named(tmp_path, capsys):
    session = _copy(tmp_path, "speed-sweep-clean")
    events = session / "events.jsonl"
    number = next(i for i, line in enumerate(events.read_text().splitlines(), start=1)
                  if json.loads(line).get("type") == "point")
    _edit_line(events, number, lambda e: {**e, "point": {**e["point"], "force_g": 999.0}})
    assert main(["replay", str(session)]) == 1
    err = capsys.readouterr().err
    named = f"events.jsonl:{number}: this point does not follow from the cassettes (force_g recorded 999.0"
    assert named in err, err


@pytest.mark.parametrize("name", ["speed-sweep-clean", "spin-critical-clean", "cone-sweep-clean",
                                  "strobe-sweep-clean"])
def test_untouched_recordings_replay(tmp_path, name, capsys):
    assert main(["replay", str(SESSIONS / name)]) == 0, capsys.readouterr().err


def _faithful(tmp_path: Path, edit_line: int, edit) -> tuple[Path, int]:
    """A real-clock recording (faithful replay) with one balance reading edited, replayed."""
    session = _copy(tmp_path, "real-speed-sweep")
    _edit_line(session / "readings" / "balance.jsonl", edit_line, edit)
    return session, main(["replay", str(session)])


def test_a_faithful_replay_names_a_doubled_reading(tmp_path, capsys):
    session, code = _faithful(tmp_path, 40, lambda r: {**r, "value": r["value"] * 2})
    err = capsys.readouterr().err
    assert code == 1, err
    assert f"{session / 'readings' / 'balance.jsonl'}:40: value" in err and "does not follow from its bytes" \
        in err, err


def test_a_faithful_replay_names_a_reading_whose_bytes_were_edited_too(tmp_path, capsys):
    def both(r):
        grams = r["value"] * 2e3
        return {**r, "value": grams / 1e3, "raw": r["raw"][:4] + f"{grams:11.2f} g"}

    session, code = _faithful(tmp_path, 40, both)
    err = capsys.readouterr().err
    assert code == 1, err
    assert f"{session / 'readings' / 'balance.jsonl'}:40: this reading's bytes" in err, err


def test_a_faithful_replay_names_a_reading_moved_in_time(tmp_path, capsys):
    session, code = _faithful(tmp_path, 40, lambda r: {**r, "t": r["t"] - 3.0})
    err = capsys.readouterr().err
    assert code == 1, err
    assert f"{session / 'readings' / 'balance.jsonl'}:40: this reading's bytes" in err, err
