"""`labkit demo` end to end, and `labkit replay` agreeing (or not) with a session's results."""

import json
import shutil
from pathlib import Path

from labkit.cli import main

RECORDED = Path(__file__).resolve().parents[2] / "recordings" / "sessions" / "speed-sweep-clean"


def test_demo_runs_the_sweep_saves_a_session_and_says_where(tmp_path, capsys):
    code = main(["demo", "--sessions", str(tmp_path), "--no-progress", "--set", "speeds_rpm=6000:18000:6000",
                 "--set", "record_s=1"])
    out = capsys.readouterr().out
    assert code == 0
    (session,) = list(tmp_path.iterdir())
    assert f"session: {session}" in out
    assert "labkit replay" in out and "fitted power law" in out
    results = json.loads((session / "results.json").read_text())
    assert results["protocol"] == "speed-sweep" and len(results["points"]) == 3
    meta = json.loads((session / "run.json").read_text())
    assert meta["status"] == "completed" and meta["clock"] == "virtual"
    assert meta["rerun"].endswith("run.rrd")
    for role in ("rotor_motor", "rotor_tach", "balance"):
        assert (session / "cassettes" / f"{role}.jsonl").stat().st_size > 0
    assert (session / "readings" / "balance.parquet").exists()


def test_replay_cli_reports_identical_results(capsys):
    assert main(["replay", str(RECORDED)]) == 0
    assert "results identical" in capsys.readouterr().out


def test_replay_cli_names_the_difference_when_results_were_edited(tmp_path, capsys):
    copy = tmp_path / "edited"
    shutil.copytree(RECORDED, copy)
    results = json.loads((copy / "results.json").read_text())
    results["points"][1]["force_g"] += 0.001
    (copy / "results.json").write_text(json.dumps(results))
    assert main(["replay", str(copy)]) == 1
    err = capsys.readouterr().err
    assert "results.points[1].force_g" in err


def test_export_csv(tmp_path, capsys):
    copy = tmp_path / "s"
    shutil.copytree(RECORDED, copy)
    assert main(["replay", str(copy), "--export-csv"]) == 0
    header, first = (copy / "readings" / "balance.csv").read_text().splitlines()[:2]
    assert header == "t,quantity,value,unit,stable,overload,flags"
    assert len(first.split(",")) == 7     # a recording from before flags: an empty flags cell
