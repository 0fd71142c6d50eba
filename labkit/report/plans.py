"""Which fits a report runs for a given data set, and the paper's reference curves.

A speed sweep (Fig. 5.25) is compared against a free power law, Eq. 5.81 with tau_S = 0 (pure
omega^-2) and Eq. 5.81 with tau_S free; spin-critical pairs (Fig. 6.18) against Eq. 6.37 with
omega_c = 3000, with omega_c fitted, and Eq. 5.69 (no omega_c term); cone angles against Eq.
5.24/5.68 with and without a static torque; MBS data against Eq. 5.85 / 6.13. Each plan is
fitted in one residual space, so its AIC values compare.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from labkit.fit.data import Table
from labkit.fit.overlay import Overlay
from labkit.fit.table_fit import FitOptions

PAPER_FIG525 = (224e6, -1.9)  # y[g] = 224e6 x[rpm]^-1.9


@dataclass(frozen=True)
class PlannedFit:
    slug: str
    title: str
    model: str
    options: FitOptions
    figure_title: str = ""
    overlays: tuple[Overlay, ...] = ()
    note: str = ""


@dataclass(frozen=True)
class Plan:
    kind: str
    fits: tuple[PlannedFit, ...]
    notes: tuple[str, ...] = field(default_factory=tuple)


def plan_for(table: Table, protocol: str | None, inertia: float | None, model: str | None = None,
             x: str | None = None, y: str | None = None) -> Plan:
    """The fits for this data: by ``model`` when given, else by protocol or column names."""
    cols = set(table.numeric)
    if model is not None:
        return Plan(model, (PlannedFit(model, model, model, FitOptions(x=x, y=y, inertia=inertia)),))
    if protocol == "speed-sweep" or {"speed_rpm", "force_g"} <= cols:
        return _sweep(table, inertia)
    if protocol == "spin-critical" or {"rotor_rad_s", "spin_rad_s"} <= cols:
        return _spin()
    if cols & {"cone_angle_rad", "cone_angle_deg", "phi_rad", "phi_deg"}:
        return _cone(inertia)
    if cols & {"distance_m", "distance_mm"} and cols & {"force_n", "force_g"}:
        return Plan("mbs-force", (
            PlannedFit("mbs-force", "MBS force profile, Eq. 5.85 (free exponents)", "mbs-force",
                       FitOptions()),
            PlannedFit("mbs-force-d38", "Eq. 5.85 with d = 3.8 (paper)", "mbs-force",
                       FitOptions(fixed={"d": 3.8}))))
    if cols & {"distance_m", "distance_mm"} and cols & {"speed_rad_s", "speed_rpm"}:
        return Plan("mbs-distance", (PlannedFit("mbs-distance", "Equilibrium distance vs speed, Eq. 6.13",
                                                "mbs-distance", FitOptions()),))
    return Plan("unknown", ())


def _sweep(table: Table, inertia: float | None) -> Plan:
    speeds = table.numeric.get("speed_rpm")
    overlays: tuple[Overlay, ...] = ()
    if speeds is not None and np.isfinite(speeds).any():
        lo, hi = np.nanmin(speeds), np.nanmax(speeds)
        if lo > 0:
            x = np.geomspace(lo, hi, 100)
            a, b = PAPER_FIG525
            overlays = (Overlay("paper Fig. 5.25: y = 224e6 x^-1.9", x, a * x**b,
                                x_name="speed_rpm", y_name="force_g"),)
    note_i = "" if inertia else " (no floator inertia in the rig file: K/I and tau_S/I are reported)"
    return Plan("speed-sweep", (
        PlannedFit("power-law", "Power law y = a x^b (Fig. 5.25)", "power-law", FitOptions(),
                   "PFR force vs rotor speed (cf. paper Fig. 5.25)", overlays),
        PlannedFit("pfr-omega2", "Eq. 5.81 with tau_S = 0: F = K / (I omega^2)", "pfr-force",
                   FitOptions(inertia=inertia, fixed={"tau_S": 0.0}), note=note_i),
        PlannedFit("pfr-force", "Eq. 5.81: F = K / (I omega^2 - tau_S)", "pfr-force",
                   FitOptions(inertia=inertia), note=note_i),
    ))


def _spin() -> Plan:
    return Plan("spin-critical", (
        PlannedFit("eq637", "Eq. 6.37 with omega_c = 3000 rad/s (paper)", "spin-critical",
                   FitOptions(omega_c=3000.0), "Spin-critical pairs (cf. paper Fig. 6.18)"),
        PlannedFit("eq637-fit", "Eq. 6.37 with omega_c fitted", "spin-critical", FitOptions(omega_c="fit")),
        PlannedFit("eq569", "Eq. 5.69 (no omega_c term)", "spin-critical", FitOptions(omega_c=math.inf)),
    ), notes=("The paper's caption fits give C = 4.7e5 (series 1) and 6.63e5 (series 2) with "
              "omega_c = 3000 rad/s.",))


def _cone(inertia: float | None) -> Plan:
    return Plan("cone-angle", (
        PlannedFit("cone-angle", "Eq. 5.24 / 5.68: tau_C and tau_S", "cone-angle",
                   FitOptions(inertia=inertia), "Cone angle vs rotor speed"),
        PlannedFit("cone-angle-s0", "Eq. 5.24 with tau_S = 0", "cone-angle",
                   FitOptions(inertia=inertia, fixed={"tau_S": 0.0})),
    ))
