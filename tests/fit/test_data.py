"""Loading CSVs, result JSON and sessions; unit conversion by column suffix."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from labkit.errors import DataFileError
from labkit.fit.data import load_table, to_si


def test_csv_with_comments_blanks_and_text(tmp_path: Path):
    p = tmp_path / "d.csv"
    p.write_text("# comment\nseries,speed_rpm,force_g\nA,6000,1.5\n\nB,7000,\n")
    t = load_table(p)
    assert t.text["series"] == ["A", "B"]
    assert t.numeric["speed_rpm"].tolist() == [6000.0, 7000.0]
    assert math.isnan(t.numeric["force_g"][1])


def test_csv_ragged_line_is_named(tmp_path: Path):
    p = tmp_path / "d.csv"
    p.write_text("a,b\n1,2\n3\n")
    with pytest.raises(DataFileError, match=r"d.csv:line 3: 1 fields, header has 2"):
        load_table(p)


def test_results_json_points_and_meta(tmp_path: Path):
    p = tmp_path / "results.json"
    p.write_text(json.dumps({"protocol": "spin-critical", "points": [
        {"rotor_rad_s": 700, "spin_rad_s": 10}, {"rotor_rad_s": 800, "spin_rad_s": 150, "note": "x"}]}))
    t = load_table(p)
    assert t.meta["protocol"] == "spin-critical"
    assert t.numeric["rotor_rad_s"].tolist() == [700.0, 800.0]
    assert t.text["note"] == ["", "x"]


def test_bad_json_names_file(tmp_path: Path):
    p = tmp_path / "results.json"
    p.write_text("{not json")
    with pytest.raises(DataFileError, match="results.json: invalid JSON"):
        load_table(p)
    p.write_text(json.dumps({"protocol": "x"}))
    with pytest.raises(DataFileError, match="results.json:points: expected a list"):
        load_table(p)


@pytest.mark.parametrize("name, value, si_name, si_value", [
    ("speed_rpm", 60.0, "speed_rad_s", 2 * math.pi),
    ("force_g", 1000.0, "force_n", 9.80665),
    ("distance_mm", 24.5, "distance_m", 0.0245),
    ("cone_angle_deg", 180.0, "cone_angle_rad", math.pi),
    ("rotor_hz", 1.0, "rotor_rad_s", 2 * math.pi),
    ("spin_rad_s", 5.0, "spin_rad_s", 5.0),
])
def test_to_si(name, value, si_name, si_value):
    n, v = to_si(name, np.array([value]))
    assert n == si_name and v[0] == pytest.approx(si_value)
