"""``labkit bench sim`` and ``labkit sweep`` through the CLI: JSON schema, bad input -> exit 2."""

from __future__ import annotations

import json

from labkit.cli import main


def test_bench_sim_json_follows_the_issue_schema(tmp_path, capsys):
    out = tmp_path / "bench.json"
    png = tmp_path / "bench.png"
    code = main(
        [
            "bench",
            "sim",
            "--quick",
            "--scene",
            "planar_5_56",
            "--cycles",
            "2",
            "--stress",
            "S9",
            "--peer-scene",
            "conical_5_1",
            "--memory-cycles",
            "200",
            "--json",
            str(out),
            "--plot",
            str(png),
        ]
    )
    assert code == 0
    doc = json.loads(out.read_text())
    assert set(doc["headline"]) == {
        "speedup_vs_dop853_at_equal_error",
        "max_invariant_drift_1e4_cycles",
        "one_body_1e4_cycles_s",
        "two_body_1e4_cycles_s",
        "one_body_1e4_cycles_cpu_s",
        "two_body_1e4_cycles_cpu_s",
        "speedup_vs_compiled_dop853_at_equal_error",
        "compiled_dop853_drift_at_equal_cost_1e4_cycles",
    }
    memory = doc["headline_notes"]["memory"]
    assert memory["exit"] == 0 and memory["peak_rss_mb"] > 10 and "--decimate 1000" in memory["command"]
    peer = doc["compiled_dop853"]
    assert [c["scene"] for c in peer] == ["conical_5_1"]
    rows = peer[0]["by_target"]
    assert list(rows) == ["0.0001", "1e-05", "1e-06", "1e-07", "1e-08", "1e-09", "1e-10"]
    ratios = [r["ratio"] for r in rows.values() if r["ratio"] is not None]
    assert ratios and doc["headline"]["speedup_vs_compiled_dop853_at_equal_error"] == min(ratios)
    drift = peer[0]["drift_1e4_cycles_at_equal_cost"]
    assert drift["peer"]["invariant_drift"] > drift["labkit"]["invariant_drift"] > 0
    assert doc["scenes"] and all(
        set(r) == {"id", "integrator", "setting", "error", "invariant_drift", "wall_s", "n_rhs"}
        for r in doc["scenes"]
    )
    assert {r["integrator"] for r in doc["scenes"]} >= {"splitting4", "dop853"}
    assert [s["id"] for s in doc["stress"]] == ["S9"]
    assert set(doc["headline_targets"]) == set(doc["headline"])
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    text = capsys.readouterr().out
    assert "S9" in text and ("met" in text) and "headline:" in text


def test_bench_sim_bad_input_exits_2_with_one_line(capsys):
    assert main(["bench", "sim", "--quick", "--stress", "S12"]) == 2
    assert "unknown stress case(s) S12" in capsys.readouterr().err
    assert main(["bench", "sim", "--quick", "--target-error", "1e-15"]) == 2
    assert "below what double precision" in capsys.readouterr().err
    assert main(["bench", "sim", "--quick", "--cycles", "1e10"]) == 2
    assert "GiB for the samples" in capsys.readouterr().err


def test_sweep_rows_and_unreachable_scheduler(tmp_path, capsys):
    out = tmp_path / "rows.json"
    assert main(["sweep", "table5.3", "--rows", "--cycles", "10", "--no-progress", "--json", str(out)]) == 0
    doc = json.loads(out.read_text())
    assert len(doc["points"]) == 36 and {p["verdict"] for p in doc["points"]} <= {"stable", "unstable"}
    assert "verdicts agree with Table 5.3" in capsys.readouterr().out
    code = main(["sweep", "table5.3", "--scheduler", "tcp://127.0.0.1:9", "--timeout", "1", "--no-progress"])
    err = capsys.readouterr().err
    assert code == 2 and "did not answer within 1 s" in err and len(err.strip().splitlines()) == 1
    assert main(["sweep", "table5.3", "--ratios", "a:b", "--no-progress"]) == 2
    assert main(["sweep", "table5.3", "--steps", "3", "--no-progress"]) == 2
    capsys.readouterr()
    assert main(["sweep", "table5.3", "--cycles", "100000000", "--no-progress"]) == 2
    assert "GiB of samples per chunk" in capsys.readouterr().err
