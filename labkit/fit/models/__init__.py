"""The models ``labkit fit`` knows, with their default columns (see docs/reference/fitting.md)."""

from __future__ import annotations

from dataclasses import dataclass

from labkit.fit.models.cone_angle import cone_angle, fit_cone_angle
from labkit.fit.models.mbs import (
    equilibrium_distance,
    fit_mbs_distance,
    fit_mbs_force,
    fit_mbs_parts,
    mbs_force,
)
from labkit.fit.models.pfr_force import fit_pfr_force, pfr_force
from labkit.fit.models.power_law import fit_power_law, power_law
from labkit.fit.models.spin_critical import PAPER_OMEGA_C, critical_spin, fit_spin_critical


@dataclass(frozen=True)
class ModelSpec:
    """A fit model: name, equation, default x/y columns (first present wins), whether the
    columns are converted to SI by unit suffix, and optional extra columns by role."""

    name: str
    equation: str
    x: tuple[str, ...]
    y: tuple[str, ...]
    si: bool
    extra: tuple[tuple[str, tuple[str, ...]], ...] = ()
    options: tuple[str, ...] = ()


MODELS: dict[str, ModelSpec] = {
    "power-law": ModelSpec("power-law", "y = a x^b (Fig. 5.25)",
                           ("speed_rpm", "speed_rad_s", "x"), ("force_gf", "force_g", "force_n", "y"),
                           si=False),
    "pfr-force": ModelSpec("pfr-force", "F = K / (I omega^2 - tau_S) (Eq. 5.81, 5.24)",
                           ("speed_rad_s", "speed_rpm"), ("force_n", "force_g"), si=True,
                           options=("inertia", "fix tau_S")),
    "spin-critical": ModelSpec("spin-critical",
                               "-k omega^2 = C (1 - omega/omega_c), k = v_S/omega - 1 (Eq. 6.37, 5.69)",
                               ("rotor_rad_s", "rotor_rpm", "speed_rad_s"), ("spin_rad_s", "spin_rpm"),
                               si=True, options=("omega_c",)),
    "cone-angle": ModelSpec("cone-angle",
                            "phi = atan(tau_C / (I omega (omega - v_S) - tau_S)) (Eq. 5.24, 5.68)",
                            ("speed_rad_s", "rotor_rad_s", "speed_rpm", "rotor_rpm"),
                            ("cone_angle_rad", "phi_rad", "cone_angle_deg", "phi_deg"), si=True,
                            extra=(("spin", ("spin_rad_s", "spin_rpm")),), options=("inertia", "fix tau_S")),
    "mbs-force": ModelSpec("mbs-force", "F_z = a r^-b - c r^-d (Eq. 5.85)",
                           ("distance_m", "distance_mm", "r_m", "r_mm"), ("force_n", "force_g"), si=True,
                           extra=(("repulsive", ("repulsive_n", "repulsive_g")),
                                  ("attractive", ("attractive_n", "attractive_g"))),
                           options=("fix a|b|c|d",)),
    "mbs-distance": ModelSpec("mbs-distance", "r = (a / (c omega^2))^(1/(b-d)) (Eq. 6.13)",
                              ("speed_rad_s", "speed_rpm", "rotor_rad_s"), ("distance_m", "distance_mm"),
                              si=True),
}

__all__ = [
    "MODELS", "ModelSpec", "PAPER_OMEGA_C", "cone_angle", "critical_spin", "equilibrium_distance",
    "fit_cone_angle", "fit_mbs_distance", "fit_mbs_force", "fit_mbs_parts", "fit_pfr_force",
    "fit_power_law", "fit_spin_critical", "mbs_force", "pfr_force", "power_law",
]
