"""Fig. 6.18 of the paper, refitted: the spin-critical pairs of the caption against Eq. 6.37.

Makes: a printed table of C for both series under three models (Eq. 6.37 with omega_c = 3000
as in the paper, Eq. 6.37 with omega_c fitted, Eq. 5.69 without the omega/omega_c term) and a
report folder out/fig6_18-report/ with the Fig. 6.18-style figure, residuals and the model
comparison.

Run: python analysis/fig6_18_spin_critical_fit.py
"""

from __future__ import annotations

import math
from pathlib import Path

from labkit.fit import FitOptions, fit_table, load_table
from labkit.fit.reproduce import PAPER_C, fig618_csv
from labkit.report.build import build_report


def main() -> None:
    table = load_table(fig618_csv())
    variants = {"Eq. 6.37, omega_c = 3000": 3000.0, "Eq. 6.37, omega_c fitted": "fit",
                "Eq. 5.69": math.inf}
    print(f"{'model':<26}{'series':>7}{'C':>12}{'stderr':>10}{'paper C':>10}{'rms v_S':>9}  omega_c")
    for label, omega_c in variants.items():
        report = fit_table(table, "spin-critical", FitOptions(omega_c=omega_c))
        for name, res in report.series.items():
            C, wc = res.params["C"], res.params["omega_c"]
            paper = f"{PAPER_C[name]:.3g}" if omega_c == 3000.0 else ""
            print(f"{label:<26}{name:>7}{C.value:>12.4g}{C.stderr:>10.2g}{paper:>10}"
                  f"{res.rms_residual:>9.3g}  {wc.value:.4g}")
    out = build_report(fig618_csv(), Path("out") / "fig6_18-report")
    print(f"report: {out}")


if __name__ == "__main__":
    main()
