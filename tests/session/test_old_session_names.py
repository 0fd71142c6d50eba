"""``labkit.session.load_session``, the old name of ``load_session_record``, still works and
warns; ``labkit.load_session`` is the DataFrames view (docs/decisions/0035-one-name-per-thing.md)."""

from __future__ import annotations

from pathlib import Path

import pytest

import labkit
import labkit.session
from labkit.session import SessionRecord, load_session_record

SESSION = Path(__file__).resolve().parents[2] / "recordings" / "sessions" / "speed-sweep-clean"


def test_the_old_name_warns_and_reads_the_same_record():
    with pytest.warns(DeprecationWarning, match="load_session_record"):
        old = labkit.session.load_session
    assert old is load_session_record
    record = old(SESSION)
    assert isinstance(record, SessionRecord) and record.meta["protocol"] == "speed-sweep"


def test_one_name_one_type():
    frames = labkit.load_session(SESSION)
    record = load_session_record(SESSION)
    assert type(frames).__name__ == "SessionFrames" and frames.record.meta == record.meta
    assert len(frames.points) == len(record.completed_points()) > 0
