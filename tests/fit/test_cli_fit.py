"""``labkit fit`` end to end: tables, JSON schema, plots, and one-line errors."""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path

import pytest

from labkit.cli import main

PAPER_CSV = str(resources.files("labkit") / "data" / "paper" / "fig6_18_spin_critical.csv")


def check_schema(doc: dict, model: str, series: set[str], params: set[str]) -> None:
    assert doc["model"] == model
    assert set(doc["series"]) == series
    for s in doc["series"].values():
        assert set(s["params"]) == params
        for p in s["params"].values():
            assert isinstance(p["value"], float) and isinstance(p["stderr"], float)
            lo, hi = p["ci95"]
            assert lo <= p["value"] <= hi
        assert isinstance(s["n"], int) and s["n"] > 0
        assert isinstance(s["rms_residual"], float) and s["rms_residual"] >= 0
        assert isinstance(s["warnings"], list)


def test_spin_critical_csv_json_and_plot(tmp_path: Path, capsys):
    out, png = tmp_path / "fit.json", tmp_path / "fit.png"
    assert main(["fit", PAPER_CSV, "--model", "spin-critical", "--json", str(out), "--plot", str(png)]) == 0
    text = capsys.readouterr().out
    assert "series 1" in text and "series 2" in text and "95 % interval" in text
    doc = json.loads(out.read_text())
    check_schema(doc, "spin-critical", {"1", "2"}, {"C", "omega_c"})
    assert doc["series"]["1"]["params"]["C"]["value"] == pytest.approx(4.70e5, rel=0.01)
    assert doc["series"]["2"]["params"]["C"]["value"] == pytest.approx(6.63e5, rel=0.01)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_power_law_on_session_directory(sweep_session: Path, capsys):
    assert main(["fit", str(sweep_session), "--model", "power-law", "--json", "-"]) == 0
    doc = json.loads(capsys.readouterr().out)
    check_schema(doc, "power-law", {"all"}, {"a", "b"})
    b = doc["series"]["all"]["params"]["b"]
    assert b["ci95"][0] - 0.05 < -1.9 < b["ci95"][1] + 0.05
    assert doc["columns"] == {"x": "speed_rpm", "y": "force_g", "sigma": "force_stderr_g"}


def test_pfr_force_on_session_with_inertia(sweep_session: Path, capsys):
    assert main(["fit", str(sweep_session), "--model", "pfr-force", "--inertia", "1e-7", "--json", "-"]) == 0
    doc = json.loads(capsys.readouterr().out)
    check_schema(doc, "pfr-force", {"all"}, {"K", "tau_S", "I"})
    assert doc["columns"]["x"] == "speed_rad_s" and doc["columns"]["y"] == "force_n"


def test_explicit_columns_and_fix(tmp_path: Path, capsys):
    csv = tmp_path / "cone.csv"
    import numpy as np

    from labkit.fit.models import cone_angle
    w = np.linspace(150, 500, 8)
    phi_deg = np.degrees(cone_angle(w, 1e-3, 1e-4, 1e-7))
    csv.write_text("w_rpm,angle_deg\n" + "".join(f"{x * 60 / (2 * np.pi)},{p}\n" for x, p in zip(w, phi_deg,
                                                                                             strict=True)))
    assert main(["fit", str(csv), "--model", "cone-angle", "--x", "w_rpm", "--y", "angle_deg",
                 "--inertia", "1e-7", "--fix", "tau_S=1e-4", "--json", "-"]) == 0
    doc = json.loads(capsys.readouterr().out)
    p = doc["series"]["all"]["params"]
    assert p["tau_S"]["fixed"] and p["tau_C"]["value"] == pytest.approx(1e-3, rel=1e-6)


@pytest.mark.parametrize("args, message", [
    (["--model", "power-law", "--x", "nope"], "no numeric column 'nope'"),
    (["--model", "cone-angle"], "cone-angle needs a y column (cone_angle_rad"),
    (["--model", "spin-critical", "--omega-c", "fast"], "--omega-c must be a number"),
    (["--model", "spin-critical", "--fix", "C"], "--fix expects NAME=NUMBER"),
    (["--model", "spin-critical", "--fix", "C=1"], "cannot fix C"),
])
def test_errors_are_one_line_exit_2(args, message, capsys):
    assert main(["fit", PAPER_CSV, *args]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and "\n" not in err and err.startswith("labkit fit:")


def test_missing_input_and_bad_session(tmp_path: Path, capsys):
    assert main(["fit", str(tmp_path / "nothing.csv"), "--model", "power-law"]) == 2
    assert "no such file" in capsys.readouterr().err
    (tmp_path / "empty-session").mkdir()
    assert main(["fit", str(tmp_path / "empty-session"), "--model", "power-law"]) == 2
    assert "no results.json" in capsys.readouterr().err


def test_nan_row_in_csv_names_file_and_row(tmp_path: Path, capsys):
    csv = tmp_path / "sweep.csv"
    csv.write_text("speed_rpm,force_g\n6000,15.0\n8000,\n10000,5.9\n12000,4.2\n")
    assert main(["fit", str(csv), "--model", "power-law"]) == 2
    err = capsys.readouterr().err
    assert "force_g" in err and "row 2" in err and str(csv) in err


def test_bootstrap_intervals_in_json(sweep_session: Path, capsys):
    assert main(["fit", str(sweep_session), "--model", "power-law", "--bootstrap", "200", "--json", "-"]) == 0
    b = json.loads(capsys.readouterr().out)["series"]["all"]["params"]["b"]
    lo, hi = b["bootstrap_ci95"]
    assert lo < b["value"] < hi
    # the bootstrap and the covariance interval agree to within a factor 2 in width
    assert 0.5 < (hi - lo) / (b["ci95"][1] - b["ci95"][0]) < 2.0


def test_steps_without_measurement_are_skipped_with_a_note(tmp_path: Path, capsys):
    """A spin-critical step where the floator never dropped has no pair: skipped, said so."""
    w = [625, 670, 733, 782, 827, 859, 932, 1022, 1100]
    v = [0, 136, 266, 340, 417, 498, 574, 712, 817]
    points = [{"step": i, "rotor_rad_s": a, "spin_rad_s": b, "no_drop": False} for i, (a, b) in
              enumerate(zip(w, v, strict=True))]
    points.append({"step": 9, "rotor_rad_s": None, "spin_rad_s": None, "no_drop": True})
    session = tmp_path / "spin-session"
    session.mkdir()
    (session / "results.json").write_text(json.dumps({"protocol": "spin-critical", "points": points,
                                                      "fit": {}}))
    assert main(["fit", str(session), "--model", "spin-critical", "--json", "-"]) == 0
    s = json.loads(capsys.readouterr().out)["series"]["all"]
    assert s["n"] == 9
    assert any("1 row(s) without any" in m for m in s["warnings"])
    assert s["params"]["C"]["value"] == pytest.approx(4.70e5, rel=0.01)


def test_inertia_from_session_rig_file(sweep_session: Path, capsys):
    rig = '[bodies.floator]\nshape = "sphere"\ninertia_radial_kg_m2 = 3e-7\n'
    (sweep_session / "rig.toml").write_text(rig)
    assert main(["fit", str(sweep_session), "--model", "pfr-force", "--json", "-"]) == 0
    p = json.loads(capsys.readouterr().out)["series"]["all"]["params"]
    assert p["I"]["value"] == 3e-7 and "K" in p and "tau_S" in p


def test_strict_turns_warnings_into_exit_3(tmp_path: Path, capsys):
    csv = tmp_path / "narrow.csv"
    csv.write_text("speed_rpm,force_g\n10000,5.61\n10020,5.58\n10040,5.60\n10060,5.52\n10080,5.57\n10100,5.50\n")
    assert main(["fit", str(csv), "--model", "power-law"]) == 0
    assert "WARNING: exponent b not identifiable" in capsys.readouterr().out
    assert main(["fit", str(csv), "--model", "power-law", "--strict"]) == 3


def test_mbs_parts_fitted_separately_from_csv(tmp_path: Path, capsys):
    """Eq. 5.85's two terms measured separately give well-conditioned exponents."""
    import numpy as np
    rng = np.random.default_rng(11)
    r_mm = np.linspace(18, 32, 12)
    r = r_mm * 1e-3
    c, b, d = 1e-7, 7.5, 3.8
    a = c * 0.0245 ** (b - d)
    rep = a * r**-b * np.exp(rng.normal(0, 0.01, r.size))
    att = -c * r**-d * np.exp(rng.normal(0, 0.01, r.size))
    csv = tmp_path / "mbs.csv"
    csv.write_text("distance_mm,force_n,repulsive_n,attractive_n\n" + "".join(
        f"{x},{p + q},{p},{q}\n" for x, p, q in zip(r_mm, rep, att, strict=True)))
    assert main(["fit", str(csv), "--model", "mbs-force", "--json", "-"]) == 0
    series = json.loads(capsys.readouterr().out)["series"]
    assert set(series) == {"repulsive", "attractive"}
    b_fit, d_fit = series["repulsive"]["params"]["b"], series["attractive"]["params"]["d"]
    assert b_fit["ci95"][0] < 7.5 < b_fit["ci95"][1] and b_fit["stderr"] < 0.1
    assert d_fit["ci95"][0] < 3.8 < d_fit["ci95"][1] and d_fit["stderr"] < 0.1
    assert series["repulsive"]["params"]["a"]["value"] == pytest.approx(a, rel=0.3)
