"""A protocol run streamed with --rerun save:FILE holds what the run measured, and only that."""

import json

import numpy as np

from labkit.cli import main
from labkit.stream.readback import column, entity_paths


def test_demo_streams_speeds_forces_points_fit_and_events(tmp_path, capsys):
    rrd = tmp_path / "demo.rrd"
    code = main(["demo", "--sessions", str(tmp_path / "s"), "--no-progress", "--rerun", f"save:{rrd}",
                 "--set", "speeds_rpm=6000:12000:2000"])
    assert code == 0, capsys.readouterr().err
    entities = entity_paths(rrd)
    assert {"/rig/rotor/speed_rpm", "/rig/rotor/setpoint_rpm", "/rig/rotor/target_rpm", "/rig/rotor/duty",
            "/rig/balance/force_g", "/fig5_25/plot/data", "/fig5_25/plot/paper", "/events"} <= entities
    # one unit per quantity: the rotor's tachometer is the loop's speed, the balance a force in g
    assert not any(e.endswith(("/angular_speed", "/mass", "/force")) for e in entities)
    assert not any("floator" in e or e.startswith("/results") for e in entities)

    session = next((tmp_path / "s").iterdir())
    results = json.loads((session / "results.json").read_text())
    n = len(results["points"])
    assert n == 4
    # every point is on the x timeline (RPM) with its force in grams
    x, force = column(rrd, "/fig5_25/plot/data", "Scalars:scalars", "rotor speed [RPM]")
    assert x == [round(p["speed_rpm"]) for p in results["points"]]
    assert np.allclose([f[0] for f in force], [p["force_g"] for p in results["points"]], rtol=1e-9)
    # the fit (with its band and residuals) is logged at every point from the third on
    assert {e for e in entities if e.startswith("/fig5_25/plot/fit/")} == \
        {f"/fig5_25/plot/fit/after_{k:02d}" for k in range(3, n + 1)}
    assert f"/fig5_25/residual/after_{n:02d}" in entities
    _, curve = column(rrd, f"/fig5_25/plot/fit/after_{n:02d}", "Scalars:scalars", "rotor speed [RPM]")
    assert all(lo < y < hi for y, lo, hi in curve)

    times, speeds = column(rrd, "/rig/rotor/speed_rpm", "Scalars:scalars", "time")
    assert len(speeds) > 10 and max(v[0] for v in speeds) > 11000

    # the balance's stream, drawn as its descriptor declares it (kg -> grams), one scalar per
    # reading of the session's readings file (whose first line is that descriptor)
    text = (session / "readings" / "balance.jsonl").read_text()
    descriptor, *lines = [json.loads(x) for x in text.splitlines()]
    assert (descriptor["type"], descriptor["quantity"], descriptor["unit"]) == ("descriptor", "mass", "kg")
    _, grams = column(rrd, "/rig/balance/force_g", "Scalars:scalars", "time")
    drawn = [r["value"] * 1000.0 for r in lines if r["value"] is not None]
    assert len(grams) == len(drawn) and np.allclose([g[0] for g in grams], drawn, rtol=1e-12)


def test_without_rerun_option_the_demo_still_saves_an_rrd_in_the_session(tmp_path, capsys):
    assert main(["demo", "--sessions", str(tmp_path), "--no-progress",
                 "--set", "speeds_rpm=8000,10000"]) == 0
    session = next(tmp_path.iterdir())
    out = capsys.readouterr().out
    assert f"rerun {session / 'run.rrd'}" in out
    assert "/fig5_25/plot/data" in entity_paths(session / "run.rrd")


def test_replay_of_a_recorded_spin_critical_session_streams_its_pairs(tmp_path, capsys):
    session = "recordings/sessions/spin-critical-clean"
    rrd = tmp_path / "replay.rrd"
    assert main(["replay", session, "--rerun", f"save:{rrd}"]) == 0
    results = json.loads(open(f"{session}/results.json").read())
    entities = entity_paths(rrd)
    assert {"/fig6_18/plot/data", "/events", "/rig/rotor/speed_rpm"} <= entities
    assert "/rig/floator_tach/spin_rad_s" in entities
    _, spins = column(rrd, "/fig6_18/plot/data", "Scalars:scalars", "rotor speed [rad/s]")
    pairs = [p for p in results["points"] if p.get("rotor_rad_s") is not None]
    assert len(spins) == len(pairs)
    n = len(pairs)   # Eq. 6.37 is refitted at every drop from the second on
    assert {e for e in entities if e.startswith("/fig6_18/plot/fit/")} == \
        {f"/fig6_18/plot/fit/after_{k:02d}" for k in range(2, n + 1)}


def test_run_spin_critical_with_rerun_logs_both_tachometers_and_the_pairs(tmp_path, capsys):
    rrd = tmp_path / "run.rrd"
    code = main(["run", "rigs/emulated-fig618.toml", "spin-critical", "--sessions", str(tmp_path / "s"),
                 "--no-progress", "--set", "start_rpm=6600", "--set", "stop_rpm=8000",
                 "--set", "step_pct=15", "--rerun", f"save:{rrd}"])
    assert code == 0, capsys.readouterr().err
    entities = entity_paths(rrd)
    assert {"/rig/rotor/speed_rpm", "/fig6_18/plot/data", "/events"} <= entities
    assert "/rig/floator_tach/spin_rad_s" in entities
    session = next((tmp_path / "s").iterdir())
    results = json.loads((session / "results.json").read_text())
    pairs = [p for p in results["points"] if p.get("rotor_rad_s") is not None]
    x, spins = column(rrd, "/fig6_18/plot/data", "Scalars:scalars", "rotor speed [rad/s]")
    assert pairs and x == [round(p["rotor_rad_s"]) for p in pairs]
