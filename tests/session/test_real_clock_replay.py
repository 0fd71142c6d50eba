"""Sessions recorded on the real clock replay faithfully (docs/explanation/replay.md): the shipped real-clock
recordings (recordings/sessions/real-*, made by analysis/record_real_sessions.py with
`labkit run --clock real` on the ptys of `labkit emulate`) replay through the real protocol,
control and driver code with the recorded decisions and points within tolerance; every shipped
recording re-analyses; a divergence is reported by step, in a physicist's words; a resumed
real-clock session stays on the real clock."""

from __future__ import annotations

import json
import shutil
import sys
from pathlib import Path

import pytest
from session_edits import scale_point, without_digests

from labkit.cli import main
from labkit.io.clock import RealClock, VirtualClock
from labkit.protocols.launch import prepare_run
from labkit.protocols.replay import choose_level, replay_session
from labkit.protocols.replay_compare import decisions
from labkit.session import load_session_record

RECORDINGS = Path(__file__).resolve().parents[2] / "recordings" / "sessions"
ALL = sorted(p.parent for p in RECORDINGS.glob("*/run.json"))
REAL = [p for p in ALL if json.loads((p / "run.json").read_text()).get("clock") == "real"]
#: every real-clock fixture replays faithfully, camera sessions too (their frames served at the
#: recorded times: docs/decisions/0036-camera-frames-in-a-faithful-replay.md)
FAITHFUL = REAL
PRINTED_LEVEL = {"faithful": "replay level: faithful", "analysis": "replay level: analysis only"}
MOTOR_WORDS = ("cut the motor", "motor's power", "cut power")


@pytest.fixture(autouse=True)
def _from_the_checkout(monkeypatch):
    """real-sketch-strobe-sweep names its clips relative to the repository (they are part of the
    fixture), as a lab's session names its clips folder: replay from the checkout's root."""
    monkeypatch.chdir(RECORDINGS.parents[1])


def test_every_shipped_protocol_has_a_real_clock_recording():
    protocols = {json.loads((p / "run.json").read_text())["protocol"] for p in REAL}
    assert {"speed-sweep", "spin-critical", "strobe-sweep", "cone-sweep"} <= protocols
    for session in REAL:
        assert (session / "clock.jsonl").is_file()
        headers = [json.loads(p.read_text().splitlines()[0]) for p in (session / "cassettes").glob("*.jsonl")]
        serial = [h for h in headers if h.get("format") == "labkit-cassette"]
        assert serial and all(isinstance(h["clock_origin"], float) for h in serial)


@pytest.mark.parametrize("session", FAITHFUL, ids=[p.name for p in FAITHFUL])
def test_a_real_clock_recording_replays_faithfully(session, capsys):
    assert main(["replay", str(session)]) == 0
    out = capsys.readouterr()
    assert "replay level: faithful" in out.out
    assert "the same decisions" in out.out
    assert not any(word in (out.out + out.err).lower() for word in MOTOR_WORDS)


@pytest.mark.parametrize("session", FAITHFUL, ids=[p.name for p in FAITHFUL])
def test_the_replay_takes_the_recorded_decisions_at_the_recorded_steps(session):
    record = load_session_record(session)
    result = replay_session(session)
    assert result.level == "faithful" and result.identical, result.differences[:5]
    recorded = decisions(record.events)
    steps = [(d["decision"], d["step"]) for d in recorded]
    assert [(d["decision"], d["step"]) for d in result.decisions] == steps
    for mine, theirs in zip(result.outcome.results["points"], record.results["points"], strict=True):
        for key in ("speed_rpm", "force_g", "rotor_rpm", "spin_rpm"):
            if isinstance(theirs.get(key), float):
                assert mine[key] == pytest.approx(theirs[key], rel=0.005), key


def test_the_unplugged_tachometer_trips_the_same_interlock_in_the_same_step():
    session = RECORDINGS / "real-speed-sweep-tach-unplug"
    recorded = [d for d in decisions(load_session_record(session).events) if d["decision"] == "interlock"]
    result = replay_session(session)
    replayed = [d for d in result.decisions if d["decision"] == "interlock"]
    assert len(recorded) == 1 and "rotor_tach" in recorded[0]["reason"]
    assert [(d["step"], d["key"]) for d in replayed] == [(d["step"], d["key"]) for d in recorded]
    assert result.outcome.status == "failed"


@pytest.mark.parametrize("session", ALL, ids=[p.name for p in ALL])
def test_analysis_only_recomputes_points_and_fit_of_every_shipped_recording(session, capsys):
    assert main(["replay", "--analysis-only", str(session)]) == 0
    out = capsys.readouterr().out
    assert "replay level: analysis only" in out
    assert "recomputed from the recorded bytes" in out and "taken as recorded" not in out
    result = replay_session(session, level="analysis")
    assert result.recomputed
    assert len(result.outcome.results["points"]) == len(load_session_record(session).results["points"])


def test_a_clip_analysed_again_names_an_edited_phi(tmp_path, capsys):
    """real-sketch-strobe-sweep analysed recorded clips (no camera): the run kept each clip's
    window of status lines, so the analysis-only level analyses the clip again and an edited phi
    (in results.json and events.jsonl, run.json's digests dropped) is named."""
    copy = tmp_path / "edited"
    shutil.copytree(RECORDINGS / "real-sketch-strobe-sweep", copy)
    without_digests(copy)
    scale_point(copy, 1, "phi_rad", 1.05)
    assert main(["replay", "--analysis-only", str(copy)]) == 1
    assert "points[1].phi_rad" in capsys.readouterr().err


def test_a_replay_that_diverges_names_the_step_and_no_motor_instruction(tmp_path, capsys):
    """The tachometer's recording cut short in the middle: the replayed loop finds it silent
    (an interlock the recording never had) and the report says in which step."""
    copy = tmp_path / "cut"
    shutil.copytree(RECORDINGS / "real-speed-sweep", copy)
    tach = copy / "cassettes" / "rotor_tach.jsonl"
    lines = tach.read_text().splitlines(keepends=True)
    tach.write_text("".join(lines[: len(lines) // 2]))
    assert main(["replay", str(copy)]) == 1
    err = capsys.readouterr().err
    assert "the replay diverged at decision" in err and "step " in err and "tachometer" in err
    assert not any(word in err.lower() for word in MOTOR_WORDS)


def test_an_older_real_clock_session_is_re_analysed_and_says_so(tmp_path, capsys):
    copy = tmp_path / "old"
    shutil.copytree(RECORDINGS / "real-speed-sweep", copy)
    (copy / "clock.jsonl").unlink()
    assert choose_level(load_session_record(copy)) == "analysis"
    assert main(["replay", str(copy)]) == 0
    captured = capsys.readouterr()
    assert "analysis only" in captured.out and "re-analysed, not replayed" in captured.err


def test_a_resumed_real_clock_session_stays_on_the_real_clock(tmp_path):
    real = tmp_path / "real"
    shutil.copytree(RECORDINGS / "real-speed-sweep-tach-unplug", real)
    prep = prepare_run(None, None, None, resume=real, session_root=tmp_path / "s")
    prep.lock.release()
    assert isinstance(prep.clock, RealClock)
    virtual = tmp_path / "virtual"
    shutil.copytree(RECORDINGS / "speed-sweep-tach-unplug", virtual)
    prep = prepare_run(None, None, None, resume=virtual, session_root=tmp_path / "s")
    prep.lock.release()
    assert isinstance(prep.clock, VirtualClock)
    prep = prepare_run(None, None, None, resume=real, clock="virtual", session_root=tmp_path / "s")
    prep.lock.release()
    assert isinstance(prep.clock, VirtualClock)  # an explicit --clock still wins


def test_a_run_recorded_on_the_ptys_of_labkit_emulate_replays(tmp_path, capsys):
    """As a lab records: `labkit emulate` in its own process, `labkit run` (real clock) on its
    ptys in another, then `labkit replay` of that session offline."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests/: the safety package
    from safety.harness import EmulatedRig

    with EmulatedRig(tmp_path) as rig:
        run = rig.start_run(tmp_path / "sessions", record_s=1.0)
        run.finish(timeout=120.0)
        session = run.session()
    assert session is not None and json.loads((session / "run.json").read_text())["clock"] == "real"
    assert main(["replay", str(session)]) == 0, capsys.readouterr().err[-2000:]
    assert "replay level: faithful" in capsys.readouterr().out


STAND_STILL_RUN = """
import sys, time
from labkit.protocols.launch import execute, prepare_run

class StandStill:
    # holds the protocol's thread outside the clock for 0.35 s as the step begins (a sink
    # writing its files on a loaded PC): the step settles 0.35 s later after its start
    def on_event(self, event):
        if event.get("type") == "step":
            time.sleep(0.35)

prep = prepare_run(sys.argv[1], "speed-sweep", ["speeds_rpm=6000", "record_s=0.5", "zero=start"],
                   clock="real", session_root=sys.argv[2], sinks=[StandStill()])
sys.exit(0 if execute(prep, sys.argv[2]).status == "completed" else 1)
"""


def test_a_stand_still_outside_a_sleep_is_recorded_and_replayed(tmp_path):
    """A real-clock run whose protocol thread stood still 0.35 s outside any sleep as its step
    began: the settle began 0.35 s after the step. The faithful replay stands still there too
    (clock.jsonl's main-late line) and settles as recorded; without that line (as an older
    labkit replayed) its settle time is 0.35 s longer, beyond the 0.25 s tolerance."""
    import subprocess

    rig = Path(__file__).resolve().parents[2] / "rigs" / "emulated-fig525.toml"
    done = subprocess.run([sys.executable, "-c", STAND_STILL_RUN, str(rig), str(tmp_path / "s")],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    session, = (tmp_path / "s").iterdir()
    rows = [json.loads(line) for line in (session / "clock.jsonl").read_text().splitlines()]
    # the late read: the step's interlock check (SpeedControl.check reads the clock) or the
    # runner's (RunContext's verbs live in context.py)
    assert any(r["job"] == "main-late" and r["woke"] - r["t"] > 0.3
               and ("runner.py:" in r["site"] or "context.py:" in r["site"])
               for r in rows)
    result = replay_session(session)
    assert result.identical, result.differences[:5]
    assert result.timing["stood_still"] >= 1
    older = tmp_path / "older"
    shutil.copytree(session, older)
    (older / "clock.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows if r["job"] != "main-late"))
    naive = replay_session(older)
    assert any("settled after" in d for d in naive.differences), naive.differences
