"""The run blueprints draw the paper's figures as plots with axes, never as spatial views, and
the live fits are `labkit fit`'s fits."""

import csv
import json

import numpy as np
import pytest

from labkit.cli import main
from labkit.protocols.legacy_hints import hints_for
from labkit.stream.blueprints import figure_of, run_blueprint, view_kinds
from labkit.stream.fit_report import x_timeline
from labkit.stream.livefit import eq637_fit, power_law_fit

PAPER_CSV = "labkit/data/paper/fig6_18_spin_critical.csv"
SPATIAL = {"2D", "3D", "Spatial2D", "Spatial3D"}


@pytest.mark.parametrize("protocol", ["speed-sweep", "spin-critical"])
def test_the_figure_is_a_time_series_view_on_the_x_timeline_and_no_view_is_spatial(protocol):
    figure = figure_of(hints_for(protocol))
    blueprint = run_blueprint(figure, ["rotor"], ["balance", "floator_tach"])
    kinds = view_kinds(blueprint)
    root = figure.root
    assert not [k for k in kinds if k[0] in SPATIAL], kinds
    assert ("TimeSeries", f"{root}/plot") in kinds
    assert ("TimeSeries", f"{root}/residual") in kinds
    assert ("TextLog", "/events") in kinds
    # duty has its own view (its own axis), apart from the speed in RPM
    rotor_views = [k for k in kinds if k[1] == "/rig/rotor"]
    assert len(rotor_views) == 2


def test_the_speed_sweep_blueprint_has_no_spatial_view_for_the_results():
    kinds = view_kinds(run_blueprint(figure_of(hints_for("speed-sweep")), ["rotor"], ["balance"]))
    assert not [k for k in kinds if k[1].startswith(("/results", "/fig")) and k[0] != "TimeSeries"]
    assert {k[0] for k in kinds} <= {"TimeSeries", "TextLog"}


def test_live_eq637_fit_is_the_fit_labkit_fit_makes(tmp_path, capsys):
    out = tmp_path / "fit.json"
    assert main(["fit", PAPER_CSV, "--model", "spin-critical", "--json", str(out)]) == 0
    reference = json.loads(out.read_text())["series"]
    with open(PAPER_CSV) as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    for name, ref in reference.items():
        w = [float(r["rotor_rad_s"]) for r in rows if r["series"] == name]
        v = [float(r["spin_rad_s"]) for r in rows if r["series"] == name]
        live = eq637_fit(w, v)
        c, stderr = live.params["C"]
        assert c == pytest.approx(ref["params"]["C"]["value"], rel=1e-9)
        assert stderr == pytest.approx(ref["params"]["C"]["stderr"], rel=1e-6)
        y, lo, hi = live.curve(np.array(w))
        assert np.all(lo < y) and np.all(y < hi)


def test_live_power_law_fit_recovers_a_law_and_has_no_fit_below_three_points():
    x = np.linspace(6000, 20000, 8)
    y = 224e6 * x**-1.9 * (1 + 0.01 * np.sin(x))
    fit = power_law_fit(list(x), list(y))
    assert fit.params["b"][0] == pytest.approx(-1.9, abs=0.01)
    assert fit.params["a"][0] == pytest.approx(224e6, rel=0.1)
    assert power_law_fit([6000, 8000], [10.0, 5.0]) is None


def test_fit_timeline_keeps_x_below_one_apart():
    name, factor = x_timeline("distance_m", np.array([0.005, 0.01, 0.02]))
    ticks = np.round(np.array([0.005, 0.01, 0.02]) * factor)
    assert len(set(ticks)) == 3 and "1e-04" in name
    assert x_timeline("rotor_rad_s", np.array([625.0, 1100.0])) == ("x:rotor_rad_s", 1.0)
