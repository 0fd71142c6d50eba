"""Every virtual-clock session under recordings/sessions/ replays from its cassettes: points exactly,
fits within the documented tolerance (their last digits depend on the CPU's BLAS kernels). The
real-clock ones (real-*) replay faithfully: tests/session/test_real_clock_replay.py."""

import json
import shutil
from pathlib import Path

import pytest

from labkit.hints import analysis_keys
from labkit.protocols import get_protocol
from labkit.protocols.analysis_versions import cross_version
from labkit.protocols.replay import replay_session
from labkit.protocols.replay_compare import ADDED_KEYS, REPLAY_FIT_RTOL

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings" / "sessions"
SESSIONS = [p for p in sorted(RECORDINGS.glob("*/run.json"))
            if json.loads(p.read_text()).get("clock") != "real"]


def test_there_are_two_recordings_per_protocol():
    protocols = [json.loads(p.read_text())["protocol"] for p in SESSIONS]
    assert protocols.count("speed-sweep") >= 2 and protocols.count("spin-critical") >= 2


@pytest.mark.parametrize("run_json", SESSIONS, ids=[p.parent.name for p in SESSIONS])
def test_replay_reproduces_the_results_exactly(run_json):
    session = run_json.parent
    recorded = json.loads((session / "results.json").read_text())
    result = replay_session(session)
    assert result.identical, result.differences[:5]
    replayed = result.outcome.results["points"]
    # every recorded key exactly, but an image analysis's numbers within REPLAY_FIT_RTOL (their last
    # digits follow the CPU's SIMD path), or within the analysis's stated accuracy when another
    # version of it made the recording (docs/explanation/replay.md#analysis-versions); a key newer
    # than the recording (ADR 0018) only added
    protocol = get_protocol(recorded["protocol"])
    cross = cross_version(protocol, json.loads(run_json.read_text()))
    tolerant = analysis_keys(protocol.row) | (frozenset(cross.accuracy) if cross else frozenset())
    assert (result.analysis_note is not None) == (cross is not None)
    for p, rec in zip(replayed, recorded["points"], strict=True):
        assert {k: p[k] for k in rec if k in p and k not in tolerant} == \
            {k: v for k, v in rec.items() if k not in tolerant}
        for k in tolerant & set(rec):
            if cross is not None and k in cross.accuracy:
                assert cross.agrees(k, p[k], rec[k], p, rec), (k, p[k], rec[k])
            else:
                assert p[k] == pytest.approx(rec[k], rel=REPLAY_FIT_RTOL, nan_ok=True)
    assert all(set(p) - set(rec) <= ADDED_KEYS for p, rec in zip(replayed, recorded["points"], strict=True))
    assert result.outcome.status == json.loads(run_json.read_text())["status"]


def _replay_after_editing_fit(tmp_path, scale):
    copy = tmp_path / "edited"
    sweep = next(p for p in SESSIONS if p.parent.name.startswith("speed-sweep"))  # its fit has a "b"
    shutil.copytree(sweep.parent, copy)
    results = json.loads((copy / "results.json").read_text())
    b = results["fit"]["params"]["b"]
    b["value"] *= scale
    (copy / "results.json").write_text(json.dumps(results))
    return replay_session(copy), b["value"]


def test_a_fit_differing_in_its_last_digits_still_replays(tmp_path):
    result, _ = _replay_after_editing_fit(tmp_path, 1 + 1e-11)   # another CPU's BLAS
    assert result.identical, result.differences


def test_a_fit_beyond_the_tolerance_is_a_difference_with_both_values(tmp_path):
    result, edited = _replay_after_editing_fit(tmp_path, 1 + 10 * REPLAY_FIT_RTOL)
    assert not result.identical
    (line,) = result.differences
    assert "results.fit.params.b.value" in line and repr(edited) in line and "tolerance" in line


def _replay_after_editing_cone_angle(tmp_path, scale):
    """The cone-sweep fixture with step 0's cone angle scaled in results.json and events.jsonl (the
    fixture was made by laser analysis version 1: compared within that analysis's stated accuracy,
    tests/session/test_analysis_versions.py holds a session of today's version to 1e-6)."""
    copy = tmp_path / "edited"
    shutil.copytree(RECORDINGS / "cone-sweep-clean", copy)
    results = json.loads((copy / "results.json").read_text())
    results["points"][0]["cone_angle_rad"] *= scale
    (copy / "results.json").write_text(json.dumps(results))
    events = [json.loads(line) for line in (copy / "events.jsonl").read_text().splitlines()]
    for event in events:
        point = event.get("point") if isinstance(event, dict) else None
        if isinstance(point, dict) and point.get("step") == 0 and "cone_angle_rad" in point:
            point["cone_angle_rad"] *= scale
    (copy / "events.jsonl").write_text("".join(json.dumps(e) + "\n" for e in events))
    return replay_session(copy)


def test_an_image_analysis_number_differing_in_its_last_digits_still_replays(tmp_path):
    """cone_angle_rad comes out of OpenCV and least squares (Column.analysis): another CPU's SIMD
    path moves its last digits, and an exact replay must still pass there."""
    result = _replay_after_editing_cone_angle(tmp_path, 1 + 1e-10)
    assert result.identical, result.differences[:5]


def test_an_image_analysis_number_beyond_the_tolerance_is_named(tmp_path):
    result = _replay_after_editing_cone_angle(tmp_path, 1.03)  # beyond the laser analysis's 1 %
    assert not result.identical
    assert any("cone_angle_rad" in d for d in result.differences), result.differences
