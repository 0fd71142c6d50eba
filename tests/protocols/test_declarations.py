"""Protocols declare their parameters (units, bounds), their row (columns, units) and their
presentation (hints); the start document carries them, and old sessions get them from the
one legacy table (ADR 0021)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from labkit import documents as doc
from labkit.hints import Column, Curve, Hints, HintsError, ReportFit
from labkit.protocols import PROTOCOLS, ListSink, SpeedSweep, SpinCritical
from labkit.protocols.declaration import param_specs
from labkit.protocols.legacy_hints import LEGACY_HINTS, hints_for
from labkit.protocols.params import ParamError, resolve_params
from labkit.protocols.replay import replay_session
from labkit.protocols.replay_compare import ADDED_KEYS

SESSIONS = sorted((Path(__file__).resolve().parents[2] / "recordings" / "sessions").iterdir())


@pytest.mark.parametrize("protocol", [SpeedSweep, SpinCritical])
def test_hints_survive_the_start_document_as_json(protocol):
    hints = protocol.hints
    assert hints is not None
    text = json.dumps(hints.to_json(), allow_nan=False)   # strict JSON: events.jsonl
    assert Hints.from_json(json.loads(text)) == hints


@pytest.mark.parametrize("session", SESSIONS, ids=lambda p: p.name)
def test_every_recorded_row_has_exactly_the_declared_columns(session):
    results = json.loads((session / "results.json").read_text())
    declared = {c.name for c in PROTOCOLS[results["protocol"]].row}
    for point in results["points"]:  # less the keys added after the recordings were made
        assert set(point) == declared - (ADDED_KEYS - set(point)), (session.name, set(point) ^ declared)


def test_a_replayed_run_starts_with_its_declaration_and_old_sessions_had_none(tmp_path):
    session = next(s for s in SESSIONS if s.name == "speed-sweep-clean")
    recorded = json.loads((session / "events.jsonl").read_text().splitlines()[0])
    assert recorded["type"] == "start" and "hints" not in recorded   # recorded before ADR 0021
    sink = ListSink()
    assert replay_session(session, sinks=[sink]).identical
    (start,) = sink.of_type("start")
    assert isinstance(start, doc.RunStart)
    line = json.loads(json.dumps(start.to_json()))
    assert doc.document_from_json(line) == start
    protocol = PROTOCOLS[start.protocol]
    assert hints_for(start.protocol, line["hints"]) == protocol.hints
    assert [c["name"] for c in line["row"]] == [c.name for c in protocol.row]
    units = {p["name"]: p["unit"] for p in line["param_specs"]}
    assert units["speeds_rpm"] == "RPM" and units["record_s"] == "s" and units["repeats"] == ""
    # the old start document's protocol name finds the same hints through the legacy table
    assert hints_for(recorded["protocol"], recorded.get("hints")) == protocol.hints


def test_the_legacy_table_answers_names_then_columns_then_nothing():
    assert hints_for("spin-critical") is LEGACY_HINTS["spin-critical"]
    assert hints_for(None, None, ["speed_rpm", "force_g", "n"]) is LEGACY_HINTS["speed-sweep"]
    assert hints_for("my-protocol", None, ["gap_mm", "torque_n"]) is None


def test_param_specs_give_units_and_the_caps_every_suffix_obeys():
    specs = {p.name: p for p in param_specs(SpinCritical.defaults, {})}
    assert specs["start_rpm"].unit == "RPM" and specs["step_pct"].unit == "%"
    assert specs["floator_mass_g"].unit == "g"
    for name in ("start_rpm", "place_timeout_s"):
        low, high = specs[name].low, specs[name].high
        resolve_params(SpinCritical.defaults, {name: float(high)})
        with pytest.raises(ParamError, match=name):
            resolve_params(SpinCritical.defaults, {name: float(high) * 1.001 + 1.0})
        assert low is not None and low <= 0


def test_a_declared_bound_is_enforced_and_never_widens_a_cap():
    bounds = {"record_s": (0.5, 1e12), "repeats": (1, 5)}
    specs = {p.name: p for p in param_specs(SpeedSweep.defaults, bounds)}
    assert specs["record_s"].low == 0.5 and specs["record_s"].high < 1e12   # the cap of "_s" holds
    assert resolve_params(SpeedSweep.defaults, ["repeats=5"], "speed-sweep", bounds)["repeats"] == 5
    with pytest.raises(ParamError, match=r"--set repeats: 6 is outside the protocol's bounds \[1, 5\]"):
        resolve_params(SpeedSweep.defaults, ["repeats=6"], "speed-sweep", bounds)
    with pytest.raises(ParamError, match=r"record_s: 0.1 s is outside"):
        resolve_params(SpeedSweep.defaults, ["record_s=0.1"], "speed-sweep", bounds)


def test_hints_that_cannot_be_drawn_are_refused_with_their_reason():
    with pytest.raises(HintsError, match="residual 'log'"):
        Hints("x", "y", "x", "", "y", "", residual="log")
    with pytest.raises(HintsError, match="model 'spline'"):
        Curve("paper", "y = f(x)", "spline", {})
    with pytest.raises(HintsError, match="cannot be read"):
        Hints.from_json({"x": "speed_rpm"})


def test_a_plugin_without_report_fits_gets_its_live_fit_in_the_report():
    hints = Hints("gap_mm", "torque_mn_m", "gap", "mm", "torque", "mN m", fit="power-law")
    (only,) = hints.fits_for_report()
    assert only == ReportFit("power-law", "power-law fit: torque [mN m] against gap [mm]", "power-law",
                             "torque [mN m] against gap [mm]", x="gap_mm", y="torque_mn_m")
    assert hints.entity_root == "/torque_mn_m_vs_gap_mm"
    assert hints.point_xy({"gap_mm": 2, "torque_mn_m": None}) is None
    assert Column("gap_mm", "mm").unit == "mm"


def test_a_fresh_speed_sweep_produces_exactly_its_declared_row(tmp_path, capsys):
    """The declaration follows the code: a run today, not only the recordings, has the row."""
    from labkit.cli import main

    assert main(["demo", "--sessions", str(tmp_path), "--no-progress", "--set", "speeds_rpm=8000,10000",
                 "--set", "record_s=0.5"]) == 0, capsys.readouterr().err
    session = next(tmp_path.iterdir())
    points = json.loads((session / "results.json").read_text())["points"]
    declared = {c.name for c in SpeedSweep.row}
    assert len(points) == 2 and all(set(p) == declared for p in points)
    start = json.loads((session / "events.jsonl").read_text().splitlines()[0])
    assert Hints.from_json(start["hints"]) == SpeedSweep.hints
