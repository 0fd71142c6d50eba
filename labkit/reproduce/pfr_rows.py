"""Table 5.5: effective power law sin(phi) ~ a / (C r^b) of the PFR force (Eq. 5.78-5.80).

For each phi range, 200 points of Eq. 5.78 (C = cot 0.1, so r = 1 at phi = 0.1) are fitted by
least squares in log-log. The paper's fitting method is not stated; b agrees to 0.02, a to 2 %.
"""

from __future__ import annotations

import numpy as np

from labkit.model.pfr_force import distance_for_cone_angle
from labkit.reproduce import Row, compare

# (no, phi_lo, phi_hi, a, b)
TABLE_5_5 = [(1, 0.40, 0.60, 1.3, 2.30), (2, 0.25, 0.40, 1.072, 2.69), (3, 0.15, 0.25, 1.007, 2.88),
             (4, 0.10, 0.25, 1.001, 2.91), (5, 0.05, 0.15, 1.000, 2.97), (6, 0.02, 0.10, 1.000, 2.99)]


def rows(quick: bool = False, prefix: str = "") -> list[Row]:
    c_const = 1.0 / np.tan(0.1)
    out = []
    for no, lo, hi, a, b in TABLE_5_5:
        phi = np.linspace(lo, hi, 200)
        r = distance_for_cone_angle(phi, c_const)
        slope, intercept = np.polyfit(np.log(r), np.log(np.sin(phi)), 1)
        note = f"phi in [{lo}, {hi}] rad, log-log least squares"
        out.append(compare(f"table5.5/{no}/b", "exponent b (Eq. 5.79)", b, float(-slope), 0.0, note,
                           abs_tol=0.02))
        multiplier = float(np.exp(intercept) * c_const)
        out.append(compare(f"table5.5/{no}/a", "multiplier a (Eq. 5.79)", a, multiplier, 0.02, note))
    return out
