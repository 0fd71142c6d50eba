"""``labkit reproduce --only twin``: rows in all four groups, every put-in value inside its 95 %
interval and within 2 % of the recovered one (seed 0, as CI runs it)."""

import json

from labkit.cli import main


def test_reproduce_twin_rows_all_recover_the_put_in_values(tmp_path, capsys):
    out = tmp_path / "twin.json"
    assert main(["reproduce", "--only", "twin", "--json", str(out)]) == 0
    rows = json.loads(out.read_text())
    rows = rows["rows"] if isinstance(rows, dict) else rows
    groups = {r["id"].split("/")[1] for r in rows}
    assert groups == {"fig5.25", "fig6.18", "laser", "strobe"}
    assert {r["id"] for r in rows} >= {"twin/fig5.25/moment_product", "twin/fig6.18/C",
                                       "twin/laser/cone_angle", "twin/strobe/tilt_amplitude",
                                       "twin/strobe/rc_offset"}
    for r in rows:
        assert r["ok"] and abs(r["rel_diff"]) <= 0.02, r
        lo, hi = (float(x) for x in r["note"].split("[")[1].split("]")[0].split(","))
        assert lo <= r["paper"] <= hi, r
    assert "twin/laser/cone_angle" in capsys.readouterr().out
