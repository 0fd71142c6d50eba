"""``labkit predict`` end to end: the story's example, the JSON schema, rig files, bad input, the map."""

from __future__ import annotations

import json

import pytest

from labkit.cli import main

STORY = ["predict", "--rotator", "cylinder:6x3mm", "--floator", "sphere:10mm", "--speed-rpm", "25000",
         "--tilt-deg", "5"]
ESTIMATE_KEYS = {"value", "unit", "method", "equation", "accuracy", "accuracy_how", "cost_s", "note", "label"}


@pytest.fixture(scope="module")
def story_json(tmp_path_factory):
    out = tmp_path_factory.mktemp("predict") / "story.json"
    import contextlib
    import io

    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        rc = main(STORY + ["--verify-cycles", "600", "--json", str(out)])
    return rc, buf.getvalue(), json.loads(out.read_text())


def test_story_answer(story_json):
    rc, text, data = story_json
    assert rc == 0
    assert "verdict  bound and stable" in text
    assert "WARNING  r_eq" in text and "point-dipole" in text  # 7.1 mm < 2 x 10 mm
    res = data["results"]
    assert res["bound"]["value"] is True
    assert data["bound"] and data["stable"]
    assert data["inputs"]["contact_distance_mm"] == pytest.approx(6.5)  # 1.5 mm + 5 mm
    assert 6.5 < res["r_eq_mm"]["value"] < 20.0
    assert res["min_speed_rpm"]["value"] < 25000 < res["max_speed_rpm"]["value"]
    assert data["verification"]["status"] == "ok"
    assert res["sim_r_mean_mm"]["value"] == pytest.approx(res["r_eq_mm"]["value"], rel=1e-5)


def test_json_schema(story_json):
    _, _, data = story_json
    assert data["schema"] == "labkit.predict/1"
    assert set(data) == {"schema", "inputs", "bound", "stable", "verdict", "results", "scaling",
                         "verification", "warnings", "cost_s"}
    inputs = {"rotator", "floator", "speed_rpm", "tilt_deg", "placement", "contact_distance_mm"}
    assert inputs <= set(data["inputs"])
    for key, est in data["results"].items():
        assert set(est) == ESTIMATE_KEYS, key
        assert est["method"] in ("closed form", "steady-state solve", "simulation", "linear analysis"), key
        assert est["cost_s"] >= 0
    for key in ("r_eq_mm", "axial_stiffness_N_m", "lateral_stiffness_N_m", "cone_angle_deg",
                "growth_rate_1_s", "min_speed_rpm", "max_speed_rpm", "scaling_exponent"):
        assert data["results"][key]["accuracy"] is not None, key
    masses = [row["mass_g"] for row in data["scaling"]]
    assert masses == sorted(masses)
    # Eq. 6.18: speed ~ m^-1/3 in the scaling table
    a, b = data["scaling"][0], data["scaling"][-1]
    ratio = b["eq6_18_min_speed_rpm"] / a["eq6_18_min_speed_rpm"]
    assert ratio == pytest.approx((b["mass_g"] / a["mass_g"]) ** (-1 / 3), rel=1e-9)


def _run(argv, capsys):
    rc = main(argv)
    captured = capsys.readouterr()
    return rc, captured.out, captured.err


@pytest.mark.parametrize("extra, message", [
    (["--rotator", "cone:6x3mm"], "labkit predict: --rotator: unknown shape 'cone'"),
    (["--floator", "sphere"], "labkit predict: --floator: cannot read 'sphere'"),
    (["--grade", "N99"], "labkit predict: --grade: unknown grade 'N99'"),
    (["--grade", "N42", "--remanence-t", "1.3"], "labkit predict: give --grade or --remanence-t, not both"),
    (["--tilt-deg", "95"], "labkit predict: --tilt-deg: must be below 90 degrees"),
    (["--speed-rpm", "-5"], "labkit predict: --speed-rpm: must be positive"),
    (["--map", "tilt=1:2:3"], "labkit predict: --map: 'tilt=1:2:3': expected AXIS=START:STOP:n=COUNT"),
    (["--map", "speed_rpm=1:2:x"],
     "labkit predict: --map: 'speed_rpm=1:2:x': third part 'x' is not a number"),
    (["--map", "tilt_deg=2:8:7"],
     "labkit predict: --map: 'tilt_deg=2:8:7': '2:8:7' is ambiguous: write 2:8:n=7"),
])
def test_bad_options_are_one_line(extra, message, capsys):
    rc, out, err = _run(STORY + extra + ["--no-verify"], capsys)
    assert rc == 2
    assert err.strip().splitlines() == [err.strip()]
    assert err.startswith(message)


def test_missing_magnet_and_speed(capsys):
    rc, _, err = _run(["predict", "--rotator", "cylinder:6x3mm"], capsys)
    assert rc == 2 and "--floator missing" in err
    rc, _, err = _run(["predict", "--rotator", "cylinder:6x3mm", "--floator", "sphere:10mm"], capsys)
    assert rc == 2 and "--speed-rpm missing" in err


RIG = """
[bodies.rotator]
shape = "cylinder"
diameter_mm = 6
length_mm = 3
tilt_deg = 5
grade = "N42"

[bodies.floator]
shape = "sphere"
diameter_mm = 10
{extra}
"""


@pytest.mark.parametrize("extra, message", [
    ("mass_g = -4", "rig.toml:bodies.floator.mass_g: must be > 0, got -4"),
    ("colour = 'red'", "rig.toml:bodies.floator.colour: unknown key"),
    ("grade = 'N99'", "rig.toml:bodies.floator.grade: unknown grade 'N99'; known: N35, N38"),
])
def test_bad_rig_files_name_file_and_key(tmp_path, monkeypatch, capsys, extra, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "rig.toml").write_text(RIG.format(extra=extra))
    rc, _, err = _run(["predict", "rig.toml", "--speed-rpm", "25000", "--no-verify"], capsys)
    assert rc == 2
    assert err.strip().startswith(f"labkit predict: {message}")
    assert len(err.strip().splitlines()) == 1


def test_rig_without_floator(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "rig.toml").write_text(RIG.format(extra="").split("[bodies.floator]")[0])
    rc, _, err = _run(["predict", "rig.toml", "--speed-rpm", "25000"], capsys)
    assert rc == 2
    assert err.strip() == "labkit predict: rig.toml:bodies.floator: missing (required for a prediction)"


def test_rig_file_gives_the_same_answer_as_options(tmp_path, monkeypatch, capsys, story_json):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "rig.toml").write_text(RIG.format(extra=""))
    rc, out, _ = _run(["predict", "rig.toml", "--speed-rpm", "25000", "--no-verify", "--no-limits",
                       "--json", "r.json"], capsys)
    assert rc == 0
    data = json.loads((tmp_path / "r.json").read_text())
    assert data["inputs"]["tilt_deg"] == pytest.approx(5.0)
    assert data["results"]["r_eq_mm"]["value"] == pytest.approx(story_json[2]["results"]["r_eq_mm"]["value"],
                                                                rel=1e-9)
    assert "time-domain check skipped" in data["verdict"]
    assert "min_speed_rpm" not in data["results"] and data["scaling"] == []


def test_map_on_a_tiny_grid_resumes(tmp_path, capsys):
    store = tmp_path / "map.jsonl"
    argv = ["predict", "--rotator", "cylinder:6x3mm", "--floator", "sphere:10mm", "--tilt-deg", "5",
            "--map", "speed_rpm=3000:40000:n=3", "--map-verify", "200", "--out", str(store),
            "--json", str(tmp_path / "map.json")]
    rc, out, _ = _run(argv, capsys)
    assert rc == 0 and "3 computed, 0 reused" in out
    rows = {r["speed_rpm"]: r for r in json.loads((tmp_path / "map.json").read_text())["points"]}
    assert rows[21500.0]["bound"] and rows[21500.0]["stable"]
    assert rows[21500.0]["lateral_stiffness_N_m"] > 0  # from the time-domain check
    assert not rows[3000.0]["bound"] and "exceeds" in rows[3000.0]["verdict"]  # below the minimum speed
    assert not rows[40000.0]["bound"] and "snap" in rows[40000.0]["verdict"]  # above the maximum speed
    assert "      .      S      x" in out
    assert len(store.read_text().splitlines()) == 3
    rc, out, _ = _run(argv, capsys)
    assert rc == 0 and "0 computed, 3 reused" in out


def test_above_the_rotator(tmp_path, capsys, story_json):
    out = tmp_path / "above.json"
    rc, text, _ = _run(STORY + ["--above", "--no-verify", "--json", str(out)], capsys)
    assert rc == 0
    data = json.loads(out.read_text())
    assert data["inputs"]["placement"] == "above" and data["bound"]
    # the weight now pushes the floator inwards: closer than beneath (Eq. 6.19 with F_E < 0)
    assert data["results"]["r_eq_mm"]["value"] < story_json[2]["results"]["r_eq_mm"]["value"]
    assert data["results"]["min_speed_rpm"]["value"] is None
    assert "not searched" in data["results"]["min_speed_rpm"]["note"]
