"""Issue 29: a drifting balance with the default zeroing gives the drift-free forces, records
the drift per point and warns per point when it is a large share of the force; ``zero=start``
says on every point that the drift was not measured. Virtual clock, emulated Fig. 5.25 rig."""

from __future__ import annotations

from pathlib import Path

import pytest

from labkit.cli import main
from labkit.protocols.launch import execute, prepare_run
from labkit.protocols.speed_sweep import SpeedSweep

RIGS = Path(__file__).resolve().parents[2] / "rigs"
DRIFT_G_PER_S = 0.05   # the drift: forces 1.7-25.9 % high without rest readings
SPEEDS = "speeds_rpm=6000,10000,14000"


def rig_with_drift(tmp_path: Path, drift_g_per_s: float) -> Path:
    text = (RIGS / "emulated-fig525.toml").read_text()
    assert "role=balance" in text
    rig = tmp_path / f"drift-{drift_g_per_s}.toml"
    rig.write_text(text.replace("role=balance", f"role=balance&drift_g_per_s={drift_g_per_s}"))
    return rig


def sweep(tmp_path: Path, drift_g_per_s: float, *sets: str) -> list[dict]:
    name = f"{drift_g_per_s}-{'-'.join(sets) or 'default'}"
    prep = prepare_run(rig_with_drift(tmp_path, drift_g_per_s), "speed-sweep",
                       [SPEEDS, "record_s=1.0", *sets], session_root=tmp_path / name)
    outcome = execute(prep, tmp_path / name)
    assert outcome.status == "completed", outcome.reason
    return outcome.results["points"]


def test_the_default_zeroing_removes_the_drift_and_names_it_per_point(tmp_path):
    assert SpeedSweep.defaults["zero"] == "each"
    clean = sweep(tmp_path, 0.0)
    drifting = sweep(tmp_path, DRIFT_G_PER_S)
    assert len(clean) == len(drifting) == 3
    for c, d in zip(clean, drifting, strict=True):
        assert d["force_g"] == pytest.approx(c["force_g"], rel=0.02), (c, d)
        assert c["drift_g"] == pytest.approx(0.0, abs=0.01)  # the drift-free balance: nothing to say
        assert c["warnings"] == []
        assert d["drift_g"] > 0.1 and d["drift_n"] == pytest.approx(d["drift_g"] * 9.80665e-3)
        share = d["drift_g"] / d["force_g"]
        if share > SpeedSweep.defaults["drift_warn"]:
            [warning] = d["warnings"]
            assert warning.startswith(f"balance zero drifted {d['drift_g']:+.3f} g by this point")
            assert f"{share:.0%} of the force" in warning
    # the drift grows through the run, and at 14 000 RPM it is a large share of the force
    assert drifting[0]["drift_g"] < drifting[1]["drift_g"] < drifting[2]["drift_g"]
    assert drifting[2]["warnings"]


def test_zero_start_warns_on_every_point_that_the_drift_was_not_measured(tmp_path):
    points = sweep(tmp_path, DRIFT_G_PER_S, "zero=start")
    for point in points:
        assert point["drift_g"] is None and point["drift_n"] == 0.0
        assert point["warnings"][0].startswith("balance drift not measured (zero=start")


def test_labkit_run_prints_each_points_drift_warning(tmp_path, capsys):
    rig = rig_with_drift(tmp_path, DRIFT_G_PER_S)
    code = main(["run", str(rig), "speed-sweep", "--set", SPEEDS, "--set", "record_s=1.0",
                 "--sessions", str(tmp_path / "s"), "--no-progress"])
    err = capsys.readouterr().err
    assert code == 0
    lines = [line for line in err.splitlines() if "balance zero drifted" in line]
    assert lines and all(line.startswith("labkit run: warning: step ") for line in lines)
    assert "labkit run: warning: step 3: balance zero drifted" in err


def test_drift_warn_must_be_a_fraction(tmp_path):
    from labkit.protocols.params import ParamError

    with pytest.raises(ParamError, match="drift_warn"):
        prepare_run(rig_with_drift(tmp_path, 0.0), "speed-sweep", [SPEEDS, "drift_warn=0"],
                    session_root=tmp_path / "x")
