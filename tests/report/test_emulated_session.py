"""End to end through the real protocol code: an emulated Fig. 5.25 sweep, then fit and report."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from labkit.cli import main
from labkit.protocols.launch import execute, prepare_run
from labkit.rig import bundled_rig_path

TRUE_EXPONENT = -2.0   # the emulated rig's model plant: the PFR of its magnets, ~ w^-2 (Eq. 5.81)


@pytest.fixture(scope="module")
def emulated_sweep(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("sessions")
    prep = prepare_run(str(bundled_rig_path("emulated-fig525")), "speed-sweep",
                       ["speeds_rpm=6000:20000:3500", "record_s=1"], clock="virtual", session_root=root)
    outcome = execute(prep, root)
    assert outcome.status == "completed", outcome
    return Path(outcome.session)


def test_fit_recovers_emulator_exponent(emulated_sweep: Path, capsys):
    assert main(["fit", str(emulated_sweep), "--model", "power-law", "--json", "-"]) == 0
    b = json.loads(capsys.readouterr().out)["series"]["all"]["params"]["b"]
    assert abs(b["value"] - TRUE_EXPONENT) < 0.05


def test_report_of_a_real_session(emulated_sweep: Path, tmp_path: Path):
    assert main(["report", str(emulated_sweep), "--out", str(tmp_path / "r")]) == 0
    text = (tmp_path / "r" / "report.md").read_text()
    assert "| protocol | speed-sweep |" in text and "| rig | emulated-fig525 |" in text
    assert "## Events" in text and "| setpoint |" in text
    # a clean run: the tachometer's zero-speed lines at rest are listed, and nothing is suspect
    flags = text.split("## Device flags")[1].split("\n## ")[0]
    assert "| rotor_tach | zero_speed |" in flags and "Only informational flags" in flags
    assert "Warning" not in flags
    # the rig file's floator inertia gives K and tau_S, not the ratios
    assert "| K |" in text and "| tau_S |" in text and "floator inertia (kg m^2) | 3e-07" in text
    fits = json.loads((tmp_path / "r" / "fits.json").read_text())
    assert set(fits) == {"power-law", "pfr-omega2", "pfr-force"}


def test_spin_critical_session_fit_and_report(tmp_path_factory):
    """The emulated Fig. 6.18 rig breaks the bound state by Eq. 6.37 with C = 4.7e5."""
    root = tmp_path_factory.mktemp("spin")
    prep = prepare_run(str(bundled_rig_path("emulated-fig618")), "spin-critical", [], clock="virtual",
                       session_root=root)
    outcome = execute(prep, root)
    assert outcome.status == "completed", outcome
    session = Path(outcome.session)
    out = tmp_path_factory.mktemp("spin-report")
    assert main(["report", str(session), "--out", str(out)]) == 0
    fits = json.loads((out / "fits.json").read_text())
    C = fits["eq637"]["series"]["all"]["params"]["C"]["value"]
    assert C == pytest.approx(4.7e5, rel=0.03)
    comparison = (out / "report.md").read_text().split("## Model comparison")[1]
    assert "Eq. 5.69 (no omega_c term)" in comparison
