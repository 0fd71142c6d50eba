"""Every recorded session under recordings/sessions/ replays bit-for-bit from its cassettes."""

import json
from pathlib import Path

import pytest

from labkit.protocols.launch import replay_session

SESSIONS = sorted((Path(__file__).resolve().parents[2] / "recordings" / "sessions").glob("*/run.json"))


def test_there_are_two_recordings_per_protocol():
    protocols = [json.loads(p.read_text())["protocol"] for p in SESSIONS]
    assert protocols.count("speed-sweep") >= 2 and protocols.count("spin-critical") >= 2


@pytest.mark.parametrize("run_json", SESSIONS, ids=[p.parent.name for p in SESSIONS])
def test_replay_reproduces_the_results_exactly(run_json):
    session = run_json.parent
    recorded = json.loads((session / "results.json").read_text())
    result = replay_session(session)
    assert result.identical, result.differences[:5]
    assert result.outcome.results == recorded
    assert result.outcome.status == json.loads(run_json.read_text())["status"]
