"""Rows for ``labkit reproduce`` from the fitting side: the paper's Fig. 6.18 caption data.

Each row is ``{"id", "quantity", "paper", "labkit", "rel_diff", "ok", "note"}`` (the
reproduce table format of the model issue); ``labkit reproduce`` can add them with
``rows += fit_reproduce_rows()``.
"""

from __future__ import annotations

from importlib import resources

from labkit.fit.data import load_table
from labkit.fit.table_fit import FitOptions, fit_table

PAPER_C = {"1": 4.7e5, "2": 6.63e5}   # Eq. 6.37 fits in the text after Fig. 6.18
TOLERANCE = 0.01


def fig618_csv() -> str:
    return str(resources.files("labkit") / "data" / "paper" / "fig6_18_spin_critical.csv")


def fit_reproduce_rows() -> list[dict]:
    report = fit_table(load_table(fig618_csv()), "spin-critical", FitOptions(omega_c=3000.0))
    rows = []
    for name, paper in PAPER_C.items():
        p = report.series[name].params["C"]
        rel = (p.value - paper) / paper
        rows.append({"id": f"fig6.18/series{name}/C",
                     "quantity": "C of Eq. 6.37 (omega_c = 3000 rad/s), s^-2",
                     "paper": paper, "labkit": p.value, "rel_diff": rel, "ok": abs(rel) <= TOLERANCE,
                     "note": f"least squares in spin v_S; 95 % CI [{p.ci95[0]:.4g}, {p.ci95[1]:.4g}]"})
    return rows
