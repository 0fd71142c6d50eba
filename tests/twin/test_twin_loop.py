"""Closed loop: the model plant measured through every emulated instrument gives back what went
in, and a rig file whose moments are 20 % off is caught."""

import json
from pathlib import Path

from labkit.cli import main
from labkit.emulators.twin_model import params_from_rig
from labkit.rig import load_rig
from labkit.twin.run import balance_rows

RIGS = Path(__file__).resolve().parents[2] / "rigs"


def test_labkit_twin_recovers_the_put_in_values_inside_their_intervals(tmp_path, capsys):
    code = main(["twin", str(RIGS / "emulated-fig525.toml"), "--out", str(tmp_path), "--seed", "3",
                 "--only", "balance", "--only", "spin", "--json", "-"])
    captured = capsys.readouterr()
    out = captured.err  # with --json - the markdown goes to stderr, the JSON alone to stdout
    report = json.loads((tmp_path / "twin-report.json").read_text())
    assert json.loads(captured.out) == report
    assert "labkit twin: part 1 of 2, Fig. 5.25: the speed sweep" in out and "part 2 of 2, Fig. 6.18" in out
    names = [r["name"] for r in report["rows"]]
    assert names == ["twin/fig5.25/moment_product", "twin/fig5.25/gap", "twin/fig6.18/C",
                     "twin/fig6.18/break_phi"]
    for r in report["rows"]:
        lo, hi = r["ci95"]
        assert lo <= r["put_in"] <= hi and lo < hi, r
        assert abs(r["rel_diff"]) < 0.02, r
    assert code == 0 and "Verdict: every put-in value lies inside" in out
    assert (tmp_path / "twin-report.md").read_text().count("| twin/") == 4


def test_a_rig_file_with_moments_20_percent_off_is_detected(tmp_path):
    # the plant is the shipped rig; the analysis believes a rig file with m_F 20 % too strong
    wrong_text = (RIGS / "emulated-fig525.toml").read_text().replace("dipole_moment_a_m2 = 2.0",
                                                                     "dipole_moment_a_m2 = 2.4")
    wrong_file = tmp_path / "wrong.toml"
    wrong_file.write_text(wrong_text)
    wrong = params_from_rig(load_rig(wrong_file))
    rows, _ = balance_rows(RIGS / "emulated-fig525.toml", wrong, tmp_path, seed=0)
    by_name = {r["name"]: r for r in rows}
    product = by_name["twin/fig5.25/moment_product"]
    assert product["put_in"] == 0.93 * 2.4
    half = (product["ci95"][1] - product["ci95"][0]) / 2
    assert not product["ok"] and abs(product["residual"]) > 10 * half       # missed by far
    assert abs(product["recovered"] / (0.93 * 2.0) - 1) < 0.01                # the truth comes back
    gap = by_name["twin/fig5.25/gap"]
    assert not gap["ok"] and abs(gap["residual"]) > (gap["ci95"][1] - gap["ci95"][0]) / 2
