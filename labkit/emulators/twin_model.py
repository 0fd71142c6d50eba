"""What the model says a rig's instruments see: the physics behind the model plant.

:class:`TwinParams` holds the magnets and geometry of a rig file (``[bodies.*]``,
``[geometry]``). From them:

* :func:`balance_force_table` - the Fig. 5.25 balance force against rotor speed. Form: a
  table computed once per parameter set (cached in the process) of the *exact* co-rotating
  steady state of :func:`labkit.model.floator_equilibrium.steady_state` - the floator's cone
  (Eq. 5.7) plus its lateral circle (Sec. 5.2), z held as by the balance - i.e. the
  cycle-averaged force of the converged periodic motion the simulator settles into
  (docs/reference/model.md). The balance carries the rotator and is tared with the rotor at rest, so it
  reads the repulsive PFR part (Eq. 5.84's cyclic term); the static attraction of a tilted
  rotator (Eq. 5.85) does not depend on speed and goes into the tare. Between table nodes the
  force is interpolated (cubic Hermite in log-log); :func:`table_error` measures that error against fresh
  steady-state solves (docs/explanation/twin.md quotes it).
* C of Eq. 6.37 for the Fig. 6.18 floator: :func:`labkit.emulators.break_up.break_up` derives
  the break-up (speed, height, cone angle) from the same magnets through Eq. 6.33-6.34.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

from labkit.units import G0

#: the magnets of the shipped emulated rigs (rigs/emulated-fig525.toml): used when a plant is
#: built without a rig file (a bare ``sim://`` URL)
DEFAULT_BODIES = {"m_rotator": 0.93, "m_floator": 2.0, "gap_m": 0.025, "mass_kg": 13.36e-3,
                  "i_radial": 3e-7, "i_axial": 3e-7, "tilt_rad": math.radians(5.0)}


@dataclass(frozen=True)
class TwinParams:
    """SI parameters of a rotator / floator pair as a rig file gives them."""

    m_rotator: float = DEFAULT_BODIES["m_rotator"]    # A m^2
    m_floator: float = DEFAULT_BODIES["m_floator"]    # A m^2
    gap_m: float = DEFAULT_BODIES["gap_m"]            # rotator centre to floator centre
    mass_kg: float = DEFAULT_BODIES["mass_kg"]        # floator mass
    i_radial: float = DEFAULT_BODIES["i_radial"]      # floator, about an axis across its dipole
    i_axial: float = DEFAULT_BODIES["i_axial"]        # floator, about its dipole axis
    tilt_rad: float = DEFAULT_BODIES["tilt_rad"]      # rotator dipole tilt from the rotation plane
    break_phi: float | None = None                    # fixed cone angle at the Fig. 6.18 break-up

    @property
    def moment_product(self) -> float:
        """m_R m_F (A^2 m^4): the balance force depends on the moments only through it."""
        return self.m_rotator * self.m_floator

    def with_product(self, product: float) -> TwinParams:
        """The same rig with the floator moment scaled so that m_R m_F = ``product``."""
        return _replace(self, m_floator=product / self.m_rotator)


#: where rigs/emulated-fig618.toml differs from DEFAULT_BODIES: its rotator tilt and gap
FIG618_CHANGES = {"tilt_rad": math.radians(6.9), "gap_m": 0.0264}


def default_params(preset: str) -> TwinParams:
    """The magnets of the shipped emulated rig of ``preset`` (``model-fig525``/``model-fig618``):
    what a model plant built without a rig file (a bare ``sim://`` URL, a real-clock run) uses."""
    return _replace(TwinParams(), **FIG618_CHANGES) if preset == "model-fig618" else TwinParams()


def _replace(p: TwinParams, **changes: float) -> TwinParams:
    from dataclasses import replace
    return replace(p, **changes)


def params_from_rig(rig: Any) -> TwinParams:
    """The model parameters of a loaded :class:`labkit.rig.Rig`; missing values keep the
    defaults of the shipped emulated rig (listed by :func:`missing_from_rig`)."""
    rot, flo = rig.bodies.get("rotator"), rig.bodies.get("floator")
    d = dict(DEFAULT_BODIES)
    if rot is not None:
        d["m_rotator"] = rot.dipole_moment_a_m2 or d["m_rotator"]
        d["tilt_rad"] = rot.tilt_rad
    if flo is not None:
        d["m_floator"] = flo.dipole_moment_a_m2 or d["m_floator"]
        d["mass_kg"] = flo.mass_kg or d["mass_kg"]
        d["i_radial"] = flo.inertia_radial_kg_m2 or d["i_radial"]
        d["i_axial"] = flo.inertia_axial_kg_m2 or flo.inertia_radial_kg_m2 or d["i_axial"]
    if rig.geometry.gap_m:
        d["gap_m"] = rig.geometry.gap_m
    return TwinParams(**d, break_phi=rig.geometry.break_phi_rad)


def missing_from_rig(rig: Any) -> list[str]:
    """Rig-file keys the model needs but the file lacks (the defaults stand in)."""
    out = []
    rot, flo = rig.bodies.get("rotator"), rig.bodies.get("floator")
    if rot is None or not rot.dipole_moment_a_m2:
        out.append("bodies.rotator.dipole_moment_a_m2")
    if flo is None or not flo.dipole_moment_a_m2:
        out.append("bodies.floator.dipole_moment_a_m2")
    if flo is None or not flo.inertia_radial_kg_m2:
        out.append("bodies.floator.inertia_radial_kg_m2")
    if not rig.geometry.gap_m:
        out.append("geometry.gap_mm")
    return out


def steady_force_n(p: TwinParams, omega: float) -> float:
    """PFR (cyclic) part of the axial force (N) at rotor speed ``omega`` (rad/s), solved afresh."""
    from labkit.model.floator_equilibrium import FloatorSetup, steady_state
    setup = FloatorSetup(p.m_rotator, p.m_floator, p.mass_kg, p.i_radial, p.i_axial, omega, p.tilt_rad)
    return float(steady_state(setup, p.gap_m).force_cyclic_z)


#: table speeds (rad/s): 1 000 - 40 000 RPM, log spaced
TABLE_MIN_RAD_S, TABLE_MAX_RAD_S, TABLE_NODES = 104.7, 4189.0, 48


@dataclass(frozen=True)
class ForceTable:
    """Balance force (N) against rotor speed, log-log interpolated between steady-state nodes."""

    log_omega: tuple[float, ...]
    log_force: tuple[float, ...]

    def force_n(self, omega: float) -> float:
        """The force at ``omega`` (rad/s); 0 below the table (no bound state), the power-law
        tail of the last two nodes above it. Cubic Hermite in (ln w, ln F) with
        central-difference slopes."""
        w = abs(omega)
        xs, ys = self.log_omega, self.log_force
        if w < math.exp(xs[0]):
            return 0.0
        lw = math.log(w)
        i = min(max(_bisect(xs, lw) - 1, 0), len(xs) - 2)
        h = xs[i + 1] - xs[i]
        if lw > xs[-1]:
            return math.exp(ys[-1] + (ys[-1] - ys[-2]) / h * (lw - xs[-1]))
        s = (lw - xs[i]) / h
        d0, d1 = self._slope(i) * h, self._slope(i + 1) * h
        h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
        return math.exp(h00 * ys[i] + h10 * d0 + h01 * ys[i + 1] + h11 * d1)

    def _slope(self, i: int) -> float:
        xs, ys = self.log_omega, self.log_force
        lo, hi = max(i - 1, 0), min(i + 1, len(xs) - 1)
        return (ys[hi] - ys[lo]) / (xs[hi] - xs[lo])


def _bisect(xs: tuple[float, ...], x: float) -> int:
    import bisect
    return bisect.bisect_right(xs, x)


@lru_cache(maxsize=32)
def balance_force_table(p: TwinParams) -> ForceTable:
    """The table of :func:`steady_force_n` for rig ``p`` (computed once per parameter set)."""
    import numpy as np
    omegas = np.geomspace(TABLE_MIN_RAD_S, TABLE_MAX_RAD_S, TABLE_NODES)
    forces = [steady_force_n(p, float(w)) for w in omegas]
    return ForceTable(tuple(float(x) for x in np.log(omegas)), tuple(math.log(f) for f in forces))


def table_error(p: TwinParams, omegas: list[float] | None = None) -> float:
    """Largest relative error of the interpolated table against fresh steady-state solves,
    at the geometric midpoints between nodes (where interpolation is worst) by default."""
    import numpy as np
    table = balance_force_table(p)
    if omegas is None:
        nodes = np.exp(np.asarray(table.log_omega))
        omegas = list(np.sqrt(nodes[:-1] * nodes[1:]))
    return max(abs(table.force_n(w) / steady_force_n(p, w) - 1.0) for w in omegas)


def force_g(p: TwinParams, omega: float) -> float:
    """:class:`ForceTable` force in grams-force (the balance's unit)."""
    return balance_force_table(p).force_n(omega) / 1e-3 / G0
