"""``labkit simulate``: summary, JSON, bad scenes end as one line with exit 2."""

from __future__ import annotations

import json

from labkit.cli import main


def test_simulate_writes_json(tmp_path, capsys):
    out = tmp_path / "r.json"
    rrd = tmp_path / "sim.rrd"
    rc = main(["simulate", "conical_5_1", "--cycles", "20", "--json", str(out), "--rerun", f"save:{rrd}"])
    assert rc == 0
    text = capsys.readouterr().out
    assert "status     ok" in text and "cone angle mean 0.53598" in text
    data = json.loads(out.read_text())
    assert data["status"] == "ok" and data["integrator"] == "splitting4"
    assert data["spec"] == {"rerun": f"save:{rrd}"}
    assert data["compile"]["kind"] == "rigid" and data["invariant"] == "jacobi"
    assert abs(data["qoi"]["bodies"]["floator"]["cone_angle_rad"]["mean"] - 0.535984) < 1e-5


def test_simulate_bad_scene_is_one_line_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.toml"
    bad.write_text('[[body]]\nname = "x"\nmass_g = 0\ninertia_kg_m2 = 1e-7\n')
    assert main(["simulate", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"labkit simulate: {bad}:body[0].mass_kg: mass must be positive, got 0.0"


def test_simulate_list_and_compile_only(capsys):
    assert main(["simulate", "--list"]) == 0
    assert "mbs_fig6_1" in capsys.readouterr().out
    assert main(["simulate", "pendulum_5_484", "--compile-only"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["kind"] == "reduced_1dof" and summary["equation"] == "Eq. 5.484"


def test_horizon_too_long_for_memory_is_a_clear_error(capsys):
    assert main(["simulate", "mbs_fig6_1", "--cycles", "1e9"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("labkit simulate: ") and "GiB" in err and "--cycles" in err


def test_steps_must_be_a_multiple_of_samples(capsys):
    assert main(["simulate", "conical_5_1", "--steps-per-period", "83"]) == 2
    assert "multiple of the samples per period" in capsys.readouterr().err
