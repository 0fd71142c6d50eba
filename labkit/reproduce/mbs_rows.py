"""Stiffness numbers below Eq. 6.22 and the Fig. 6.18 spin / speed relation (Eq. 6.37)."""

from __future__ import annotations

from labkit.model.mbs import (
    loaded_equilibrium,
    max_outward_load,
    spin_for_speed,
    stiffness,
    stiffness_limit_distance,
)
from labkit.reproduce import Row, compare
from labkit.reproduce.paper_data import EQ_6_21, EQ_6_22, FIG_6_18
from labkit.units import G0


def _eq_6_22() -> list[Row]:
    p = EQ_6_21
    args = (p["a_r"], p["b_r"], p["a_a"], p["b_a"])
    weight = EQ_6_22["floator_mass_g"] * 1e-3 * G0
    load = max_outward_load(*args)
    rows = [
        compare("eq6.22/r_max_cm", "S > 0 for r < r_max (cm)", EQ_6_22["r_max_cm"],
                stiffness_limit_distance(*args), 2e-3),
        compare("eq6.22/max_load_N", "max outward load (N)", EQ_6_22["max_load_N"], load, 5e-3),
        compare("eq6.22/max_mass_g", "heaviest floator beneath (g)", EQ_6_22["max_mass_g"],
                load / G0 * 1e3, 0.01, "the paper's 11.8 g corresponds to 0.116 N"),
        compare("eq6.22/r_eq_cm", "weightless equilibrium (cm)", EQ_6_22["r_eq_cm"],
                loaded_equilibrium(0.0, *args), 2e-3),
    ]
    # (1) F_E = 0, (2) floator above the rotator: weight pushes it towards, (3) beneath: away
    for i, f_ext in zip((1, 2, 3), (0.0, -weight, weight), strict=True):
        r = loaded_equilibrium(f_ext, *args)
        s_n_per_m = float(stiffness(r, *args)) * 100.0  # N/cm -> N/m
        rows.append(compare(f"eq6.22/stiffness_{i}", "stiffness at equilibrium (N/m)",
                            EQ_6_22[f"stiffness_{i}"], s_n_per_m, 0.01,
                            f"r_eq = {r:.3f} cm, 4 g floator"))
    return rows


def _fig_6_18() -> list[Row]:
    rows = []
    for name, series in FIG_6_18.items():
        for i, (v, omega) in enumerate(zip(series["v"], series["omega"], strict=True), start=1):
            model = float(spin_for_speed(omega, series["C"]))
            # the paper calls the fit ">90 %": compare spin on the scale of omega
            diff = model - v
            rows.append(Row(f"fig6.18/{name}/{i}", "spin v_S (rad/s) at this omega, Eq. 6.37",
                            float(v), model, diff / omega, abs(diff) <= 0.1 * omega,
                            f"omega = {omega} rad/s, C = {series['C']:.3g}; rel_diff is over omega"))
    return rows


def rows(quick: bool = False, prefix: str = "") -> list[Row]:
    if prefix == "eq6.22":
        return _eq_6_22()
    if prefix == "fig6.18":
        return _fig_6_18()
    return _eq_6_22() + _fig_6_18()
