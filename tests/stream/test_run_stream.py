"""A protocol run streamed with --rerun save:FILE holds what the run measured, and only that."""

import json

from labkit.cli import main
from labkit.stream.readback import column, entity_paths


def test_demo_streams_speeds_forces_points_fit_and_events(tmp_path, capsys):
    rrd = tmp_path / "demo.rrd"
    code = main(["demo", "--sessions", str(tmp_path / "s"), "--no-progress", "--rerun", f"save:{rrd}",
                 "--set", "speeds_rpm=6000:12000:2000"])
    assert code == 0, capsys.readouterr().err
    entities = entity_paths(rrd)
    assert {"/rig/rotor/speed_rpm", "/rig/rotor/setpoint_rpm", "/rig/rotor/target_rpm",
            "/results/points", "/results/fit", "/events"} <= entities
    assert any(e.startswith("/rig/balance/") for e in entities)
    # nothing the fig525 rig does not have
    assert not any("floator" in e for e in entities)

    session = next((tmp_path / "s").iterdir())
    results = json.loads((session / "results.json").read_text())
    steps, points = column(rrd, "/results/points", "Points2D:positions", "step")
    assert len(points[-1]) == len(results["points"]) == 4
    # the last logged point is the last result row (x in kRPM, y in grams)
    last = results["points"][-1]
    assert abs(points[-1][-1][0] - last["speed_rpm"] / 1000) < 1e-3
    assert abs(points[-1][-1][1] - last["force_g"]) < 1e-3 * max(1.0, abs(last["force_g"]))

    times, speeds = column(rrd, "/rig/rotor/speed_rpm", "Scalars:scalars", "time")
    assert len(speeds) > 10 and max(v[0] for v in speeds) > 11000


def test_without_rerun_option_the_demo_still_saves_an_rrd_in_the_session(tmp_path, capsys):
    assert main(["demo", "--sessions", str(tmp_path), "--no-progress",
                 "--set", "speeds_rpm=8000,10000"]) == 0
    session = next(tmp_path.iterdir())
    out = capsys.readouterr().out
    assert f"rerun {session / 'run.rrd'}" in out
    assert "/results/points" in entity_paths(session / "run.rrd")


def test_replay_of_a_recorded_spin_critical_session_streams_its_pairs(tmp_path, capsys):
    session = "recordings/sessions/spin-critical-clean"
    rrd = tmp_path / "replay.rrd"
    assert main(["replay", session, "--rerun", f"save:{rrd}"]) == 0
    results = json.loads(open(f"{session}/results.json").read())
    entities = entity_paths(rrd)
    assert {"/results/points", "/events", "/rig/rotor/speed_rpm"} <= entities
    assert any(e.startswith("/rig/floator_tach/") for e in entities)
    _, points = column(rrd, "/results/points", "Points2D:positions", "step")
    pairs = [p for p in results["points"] if p.get("rotor_rad_s") is not None]
    assert len(points[-1]) == len(pairs)


def test_run_spin_critical_with_rerun_logs_both_tachometers_and_the_pairs(tmp_path, capsys):
    rrd = tmp_path / "run.rrd"
    code = main(["run", "rigs/emulated-fig618.toml", "spin-critical", "--sessions", str(tmp_path / "s"),
                 "--no-progress", "--set", "start_rpm=6600", "--set", "stop_rpm=8000",
                 "--set", "step_pct=15", "--rerun", f"save:{rrd}"])
    assert code == 0, capsys.readouterr().err
    entities = entity_paths(rrd)
    assert {"/rig/rotor/speed_rpm", "/results/points", "/events"} <= entities
    assert any(e.startswith("/rig/floator_tach/") for e in entities)
    session = next((tmp_path / "s").iterdir())
    results = json.loads((session / "results.json").read_text())
    pairs = [p for p in results["points"] if p.get("rotor_rad_s") is not None]
    _, points = column(rrd, "/results/points", "Points2D:positions", "step")
    assert pairs and len(points[-1]) == len(pairs)
