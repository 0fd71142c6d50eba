"""Fig. 6.18 in the report (issue 27): error bars from the trials' spread and the paper's curve."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from labkit.cli import main
from labkit.fit.data import load_table
from labkit.protocols import SpinCritical
from labkit.protocols.paper_figures import PAPER_FIG618
from labkit.report.build import spread_column


@given(st.floats(300.0, 3000.0), st.floats(1e5, 1e6))
def test_the_paper_curve_is_eq_6_37(w, c):
    """-k w^2 = C (1 - w/w_c) with k = v/w - 1, at the curve's v."""
    curve = type(PAPER_FIG618)(PAPER_FIG618.name, PAPER_FIG618.formula, "spin-critical",
                               {"C": c, "omega_c": 3000.0})
    v = curve.at(w)
    k = v / w - 1.0
    assert -k * w * w == pytest.approx(c * (1.0 - w / 3000.0), rel=1e-9, abs=1e-6)


def test_an_emulated_series_reports_spreads_and_leaves_out_disagreeing_steps(tmp_path):
    assert main(["run", "emulated-fig618", "spin-critical", "--sessions", str(tmp_path),
                 "--no-progress"]) == 0
    session = next(tmp_path.iterdir())
    points = json.loads((session / "results.json").read_text())["points"]
    assert {c.name for c in SpinCritical.row} == set(points[0])
    for p in points:
        if len(p["trials"]) > 1:
            spins = [t["spin_rad_s"] for t in p["trials"][-2:]] if p["consistent"] else \
                [t["spin_rad_s"] for t in p["trials"]]
            assert p["spin_std_rad_s"] == pytest.approx(float(np.std(spins, ddof=1)), rel=1e-9)
        else:
            assert p["spin_std_rad_s"] is None
    table = load_table(session)
    spread = spread_column(table, "spin_rad_s")
    assert spread is not None and np.isfinite(spread).sum() == sum(len(p["trials"]) > 1 for p in points)
    assert main(["report", str(session)]) == 0
    report = (session / "report" / "report.md").read_text()
    assert "Model comparison" in report and "| yes |" in report
    fits = json.loads((session / "report" / "fits.json").read_text())
    n_consistent = sum(1 for p in points if p["consistent"] and p["rotor_rad_s"] is not None)
    if n_consistent < len(points):  # the emulated rig's first step often needs more trials than it has
        assert fits["eq637"]["series"]["all"]["n"] == n_consistent
        assert any("left out of the fit" in w for w in fits["eq637"]["series"]["all"]["warnings"])
