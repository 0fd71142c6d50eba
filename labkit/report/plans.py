"""Which fits a report runs for a given data set, and the reference curves drawn with them.

A protocol's run gets the fits its hints declare (:class:`labkit.hints.Hints`,
``report_fits``; ADR 0021): a speed sweep (Fig. 5.25) is compared against a free power law,
Eq. 5.81 with tau_S = 0 (pure omega^-2) and Eq. 5.81 with tau_S free; spin-critical pairs
(Fig. 6.18) against Eq. 6.37 with omega_c = 3000, with omega_c fitted, and Eq. 5.69 (no
omega_c term) (labkit/protocols/paper_figures.py). Tables without a protocol get theirs by
column names: cone angles against Eq. 5.24/5.68 with and without a static torque; MBS data
against Eq. 5.85 / 6.13. Each plan is fitted in one residual space, so its AIC values compare.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from labkit.fit.data import Table
from labkit.fit.overlay import Overlay
from labkit.fit.table_fit import FitOptions
from labkit.hints import Hints, ReportFit


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


def plan_for(table: Table, hints: Hints | None, inertia: float | None, model: str | None = None,
             x: str | None = None, y: str | None = None) -> Plan:
    """The fits for this data: by ``model`` when given, else the fits the run's ``hints``
    declare (:func:`labkit.protocols.legacy_hints.hints_for` finds them), else by column names."""
    cols = set(table.numeric)
    if model is not None:
        return Plan(model, (PlannedFit(model, model, model, FitOptions(x=x, y=y, inertia=inertia)),))
    if hints is not None and hints.fits_for_report():
        return plan_from_hints(table, hints, inertia)
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


def _reference_overlay(table: Table, hints: Hints) -> tuple[Overlay, ...]:
    """The hints' reference curve over the data's x range (100 points, geometric)."""
    xs = table.numeric.get(hints.x)
    if hints.reference is None or xs is None or not np.isfinite(xs).any():
        return ()
    lo, hi = np.nanmin(xs), np.nanmax(xs)
    if lo <= 0:
        return ()
    grid = np.geomspace(lo, hi, 100)
    return (Overlay(hints.reference.report_label, grid, hints.reference.at(grid), x_name=hints.x,
                    y_name=hints.y),)


def _options(fit: ReportFit, inertia: float | None) -> FitOptions:
    options = FitOptions(x=fit.x, y=fit.y, inertia=inertia if fit.inertia else None, fixed=dict(fit.fixed))
    if fit.omega_c is not None:
        options = replace(options, omega_c=math.inf if fit.omega_c == "inf" else fit.omega_c)
    return options


def plan_from_hints(table: Table, hints: Hints, inertia: float | None) -> Plan:
    """The report's fits as the hints declare them: options, the reference curve on the fits
    that ask for it, a note where a fit needs the floator's inertia and the rig file has none."""
    overlays = _reference_overlay(table, hints)
    note_i = "" if inertia else " (no floator inertia in the rig file: K/I and tau_S/I are reported)"
    fits = tuple(PlannedFit(f.slug, f.title, f.model, _options(f, inertia), f.figure_title,
                            overlays if f.reference else (), note_i if f.inertia else "")
                 for f in hints.fits_for_report())
    return Plan(hints.figure or hints.fit, fits, hints.notes)


def _cone(inertia: float | None) -> Plan:
    return Plan("cone-angle", (
        PlannedFit("cone-angle", "Eq. 5.24 / 5.68: tau_C and tau_S", "cone-angle",
                   FitOptions(inertia=inertia), "Cone angle vs rotor speed"),
        PlannedFit("cone-angle-s0", "Eq. 5.24 with tau_S = 0", "cone-angle",
                   FitOptions(inertia=inertia, fixed={"tau_S": 0.0})),
    ))
