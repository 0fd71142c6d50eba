"""A session made by another version of its image analysis (docs/explanation/replay.md#analysis-versions,
ADR 0040): its numbers are compared within the analysis's stated accuracy, and the replay says
so; by the same version a change beyond relative 1e-6 fails; a change beyond the accuracy fails
across versions too. Sessions without versions in run.json (every shipped fixture) are version 1."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from session_edits import scale_point, without_digests

from labkit.cli import main
from labkit.protocols.analysis_versions import recorded_version
from labkit.protocols.registry import get_protocol
from labkit.protocols.runner import normalise
from labkit.vision.laser.version import LASER_ANALYSIS
from labkit.vision.strobe.version import STROBE_ANALYSIS

SESSIONS = Path(__file__).resolve().parents[2] / "recordings" / "sessions"
OLDER = LASER_ANALYSIS.version - 1


@pytest.fixture(scope="module")
def fresh(tmp_path_factory) -> Path:
    """A cone sweep recorded now (virtual clock, 2 speeds, bursts of 10 frames): made by today's
    laser analysis."""
    root = tmp_path_factory.mktemp("fresh")
    assert main(["run", "emulated-camera", "cone-sweep", "--sessions", str(root), "--no-progress",
                 "--set", "speeds_rpm=5000,6000", "--set", "burst_frames=10", "--set", "halves=false"]) == 0
    (session,) = root.glob("*-cone-sweep")
    return session


def _copy(name: str | Path, tmp_path: Path, laser_version: int | None) -> Path:
    source = name if isinstance(name, Path) else SESSIONS / name
    session = tmp_path / source.name
    shutil.copytree(source, session)
    without_digests(session)  # the edits below change events.jsonl
    if laser_version is not None:
        meta = json.loads((session / "run.json").read_text())
        meta["analyses"] = {"laser": laser_version}
        (session / "run.json").write_text(json.dumps(meta))
    return session


def _move_cone_angle(session: Path, step: int, factor: float) -> None:
    """Step ``step``'s cone angle (rad and deg) times ``factor``, and results.json's fit made again
    from the points, as a session an older analysis made would hold them."""
    for key in ("cone_angle_rad", "cone_angle_deg"):
        scale_point(session, step, key, factor)
    results = json.loads((session / "results.json").read_text())
    results["fit"] = normalise(get_protocol("cone-sweep").fit(results["points"]))
    (session / "results.json").write_text(json.dumps(results))


def test_a_session_without_versions_is_version_1():
    meta = json.loads((SESSIONS / "cone-sweep-clean" / "run.json").read_text())
    assert "analyses" not in meta
    assert recorded_version(meta, "laser") == 1
    assert recorded_version({"analyses": {"laser": 3}}, "laser") == 3


def test_a_new_session_records_its_version_and_replays_within_1e_6(fresh, capsys):
    assert json.loads((fresh / "run.json").read_text())["analyses"] == {"laser": LASER_ANALYSIS.version}
    assert main(["replay", str(fresh)]) == 0
    out = capsys.readouterr().out
    assert "points, results identical to results.json" in out and "recorded with" not in out


def test_by_the_same_version_a_change_beyond_1e_6_fails(fresh, tmp_path, capsys):
    session = _copy(fresh, tmp_path, None)
    _move_cone_angle(session, 1, 1 + 1e-4)  # 100x the 1e-6 of the same analysis, 1 % of 1 %
    assert main(["replay", str(session)]) == 1
    captured = capsys.readouterr()
    assert "results.points[1].cone_angle_rad" in captured.err and "points[0]" not in captured.err
    assert "beyond relative tolerance 1e-06" in captured.err
    assert "recorded with" not in captured.out


def test_the_same_change_in_a_session_of_an_older_version_passes_and_says_so(fresh, tmp_path, capsys):
    session = _copy(fresh, tmp_path, OLDER)
    _move_cone_angle(session, 1, 1 + 1e-4)
    assert main(["replay", str(session)]) == 0
    out = capsys.readouterr().out
    assert f"analysis laser {LASER_ANALYSIS.version}, recorded with {OLDER}: compared within" in out


def test_a_version_1_recording_replays_within_its_stated_accuracy_and_says_so(tmp_path, capsys):
    """cone-sweep-clean was made by laser analysis version 1 (no versions in its run.json)."""
    session = _copy("cone-sweep-clean", tmp_path, None)
    _move_cone_angle(session, 2, 1 + 1e-4)
    assert main(["replay", str(session)]) == 0
    out = capsys.readouterr().out
    assert (f"analysis laser {LASER_ANALYSIS.version}, recorded with 1: compared within its stated "
            "accuracy (tilt 1 %") in out
    assert "image-analysis numbers within the analysis's stated accuracy" in out
    assert "points, results identical" not in out


def test_a_change_beyond_the_stated_accuracy_fails_across_versions(tmp_path, capsys):
    session = _copy("cone-sweep-clean", tmp_path, OLDER)
    _move_cone_angle(session, 2, 1.03)  # 3 %: beyond the laser analysis's 1 %
    assert main(["replay", str(session)]) == 1
    captured = capsys.readouterr()
    assert "results.points[2].cone_angle_rad" in captured.err
    assert "beyond the laser analysis's stated accuracy (1 %)" in captured.err
    assert "this point does not follow from the cassettes (cone_angle_deg" in captured.err  # events.jsonl too


def test_a_verdict_that_flips_fails_across_versions(tmp_path, capsys):
    session = _copy("cone-sweep-clean", tmp_path, OLDER)
    results = json.loads((session / "results.json").read_text())
    results["points"][4]["verdict"] = "doubtful"
    results["fit"] = normalise(get_protocol("cone-sweep").fit(results["points"]))
    (session / "results.json").write_text(json.dumps(results))
    assert main(["replay", str(session)]) == 1
    assert "results.points[4].verdict: replay 'ok', recording 'doubtful'" in capsys.readouterr().err


def test_the_analysis_only_level_compares_across_versions_too(fresh, tmp_path, capsys):
    session = _copy("real-cone-sweep", tmp_path, OLDER)
    _move_cone_angle(session, 1, 1 + 1e-4)
    assert main(["replay", "--analysis-only", str(session)]) == 0
    assert f"recorded with {OLDER}" in capsys.readouterr().out
    today = _copy(fresh, tmp_path, None)  # made by today's version: 1e-6
    _move_cone_angle(today, 1, 1 + 1e-4)
    assert main(["replay", "--analysis-only", str(today)]) == 1
    err = capsys.readouterr().err
    assert "points[1].cone_angle_rad" in err and "points[0]" not in err


def test_every_image_analysis_column_names_a_quantity_its_analysis_states():
    """A column compared within 1e-6 by the same version needs a stated accuracy for another."""
    for name, analysis in (("cone-sweep", LASER_ANALYSIS), ("strobe-sweep", STROBE_ANALYSIS)):
        protocol = get_protocol(name)
        assert protocol.image_analysis is analysis
        for column in protocol.row:
            if column.analysis:
                assert column.accuracy in analysis.accuracy, (name, column.name)
            if column.accuracy_of:
                assert column.accuracy_of in {c.name for c in protocol.row}


def test_a_faithful_replay_compares_across_versions(tmp_path, capsys):
    session = _copy("real-cone-sweep", tmp_path, OLDER)
    _move_cone_angle(session, 1, 1 + 1e-4)
    assert main(["replay", str(session)]) == 0
    out = capsys.readouterr().out
    assert "replay level: faithful" in out and f"recorded with {OLDER}" in out
    assert "image analyses within their stated accuracy" in out
