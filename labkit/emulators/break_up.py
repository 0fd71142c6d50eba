"""Where the Fig. 6.18 bound state breaks, from a rig's magnets (paper Sec. 6.5, Eq. 6.33-6.37).

A floator trapped beneath the rotator is held where the static attraction F_A balances the
PFR F_R and its weight F_G (Eq. 6.33). The lowest rotor speed that holds it without spin is the
one at which that balance is also tangent, zero stiffness (Eq. 6.34): below it no height holds
the floator. Both forces come from :func:`labkit.model.floator_equilibrium.steady_state`
(the co-rotating cone plus lateral circle of the floator, its cycle-averaged force split into
the static and cyclic parts of Eq. 5.84), so the break-up speed ``omega_0``, height ``r_0`` and
cone angle ``phi_0`` follow from the magnets alone; the paper's power laws of Eq. 6.35-6.36 are
not needed. (The point-dipole field is even in the displacement, so the floator beneath the
rotator is solved above it with its weight pointing away.)

C of Eq. 6.37 is ``(tau_C cos phi + tau_S sin phi) / (I sin phi)`` at the break-up, with
``tau_C = mu0 m_R m_F / (4 pi r_0^3)`` (Eq. 5.73) and ``tau_S = 2 tan(gamma) tau_C`` (Eq. 5.29).
Without spin (k = -1) that is Eq. 5.69 = Eq. 5.35: ``C = omega_0^2`` up to the lateral circle.
Eq. 6.37's empirical factor ``(1 - omega/w_ref)`` then has to hold at the first point of the
series (v = 0 at omega_0), so the law's C is ``C_def / (1 - omega_0 / w_ref)``: the plant traps
from the model's own omega_0. docs/explanation/twin.md compares this with the model's whole critical-spin
curve.

A rig file may fix the cone angle instead (``[geometry] break_phi_rad``, the earlier plant
knob): then C is the same expression at the rig's ``gap`` and that angle, without the factor.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

from labkit.errors import LabkitError
from labkit.units import G0

#: Eq. 6.37's reference speed (rad/s): -k w^2 = C (1 - w / W_REF)
W_REF_RAD_S = 3000.0
#: rotor speeds searched for the break-up (rad/s): 1 000 - 60 000 RPM
OMEGA_RANGE_RAD_S = (104.7, 6283.0)


@dataclass(frozen=True)
class BreakUp:
    """The break-up of a rig: C of Eq. 6.37 and the cone angle, height, speed and torques it
    comes from.

    ``derived`` is False when the rig file fixed the cone angle (``break_phi_rad``); then
    ``omega_rad_s`` is the law's own zero-spin speed and ``gap_m`` the rig's gap."""

    c: float
    phi: float
    gap_m: float
    omega_rad_s: float
    derived: bool
    factor: float            # C = C_def(phi, gap) / factor
    tau_c: float             # N m at gap_m (Eq. 5.73)
    tau_s: float             # N m at gap_m (Eq. 5.29)
    inertia: float           # floator radial moment of inertia, kg m^2

    def phi_from_c(self, c: float) -> float:
        """The cone angle (rad) that gives ``c`` at this break-up's height (inverse of C_def)."""
        return math.atan(self.tau_c / (c * self.factor * self.inertia - self.tau_s))


def c_definition(tau_c: float, tau_s: float, inertia: float, phi: float) -> float:
    """Eq. 6.37's ``C = (tau_C cos phi + tau_S sin phi) / (I sin phi)``."""
    return (tau_c * math.cos(phi) + tau_s * math.sin(phi)) / (inertia * math.sin(phi))


def _torques(p, r: float) -> tuple[float, float]:
    """tau_C and tau_S (N m) of a tilted rotating dipole on its axis at distance r (Eq. 5.28-5.29)."""
    from labkit.model.dipole import K_M
    tau = K_M * p.moment_product / r**3               # Eq. 5.73
    return tau * math.cos(p.tilt_rad), 2.0 * tau * math.sin(p.tilt_rad)


#: largest cone angle (rad) of the Eq. 5.30 estimate at which a height is searched (the paper's
#: break-ups have phi < 0.1; closer in, the phase-lag cone of Eq. 5.24 stops existing)
MAX_SEARCH_PHI = 0.35


def search_heights(p, omega: float) -> tuple[float, float]:
    """Heights (m) searched at ``omega``: from where Eq. 5.30 gives MAX_SEARCH_PHI (or gap/3) to 3 gap."""
    from labkit.model.dipole import K_M
    t = math.tan(MAX_SEARCH_PHI)
    tau = p.i_radial * omega**2 * t / (math.cos(p.tilt_rad) + 2.0 * math.sin(p.tilt_rad) * t)
    return max(p.gap_m / 3.0, (K_M * p.moment_product / tau) ** (1.0 / 3.0)), 3.0 * p.gap_m


def _make(p, phi: float, r: float, omega: float, derived: bool, factor: float) -> BreakUp:
    tau_c, tau_s = _torques(p, r)
    c = c_definition(tau_c, tau_s, p.i_radial, phi) / factor
    return BreakUp(c, phi, r, omega, derived, factor, tau_c, tau_s, p.i_radial)


def _net_outward_force(p, r: float, omega: float, x0=None):
    """Axial force (N) on the floator beneath the rotator, away from it: PFR + weight - attraction."""
    from labkit.model.floator_equilibrium import FloatorSetup, steady_state
    setup = FloatorSetup(p.m_rotator, p.m_floator, p.mass_kg, p.i_radial, p.i_axial, omega, p.tilt_rad)
    st = steady_state(setup, r, x0)
    return st.force_cyclic_z + st.force_static_z + p.mass_kg * G0, st


def weakest_hold(p, omega: float, r_lo: float, r_hi: float, near: float | None = None) -> tuple[float, float]:
    """(min over r of the net outward force, its height): < 0 means some height holds the floator.
    ``near``: a height close to the minimum (searched from 0.7 to 1.4 times it instead of a grid)."""
    import numpy as np
    from scipy.optimize import minimize_scalar
    if near is None:
        radii = np.geomspace(r_lo, r_hi, 13)
        values = [_net_outward_force(p, float(r), omega)[0] for r in radii]
        i = int(np.argmin(values))
        lo, hi = radii[max(i - 1, 0)], radii[min(i + 1, len(radii) - 1)]
    else:
        lo, hi = max(r_lo, 0.7 * near), min(r_hi, 1.4 * near)
    res = minimize_scalar(lambda r: _net_outward_force(p, r, omega)[0], bounds=(lo, hi), method="bounded",
                          options={"xatol": 1e-9 * r_hi})
    return float(res.fun), float(res.x)


class NoBreakUp(LabkitError, ValueError):
    """The rig's magnets cannot hold the floator beneath the rotator at any searched speed
    (a LabkitError: the CLI prints it as one line)."""


@lru_cache(maxsize=32)
def break_up(p) -> BreakUp:
    """The break-up of rig ``p`` (:class:`labkit.emulators.twin_model.TwinParams`); cached."""
    from labkit.emulators.rig_plant import SpinCriticalLaw
    if p.break_phi is not None:                       # the rig file fixes the cone angle
        made = _make(p, p.break_phi, p.gap_m, 0.0, False, 1.0)
        return _make(p, p.break_phi, p.gap_m, SpinCriticalLaw(c=made.c).min_trap_speed(), False, 1.0)
    from scipy.optimize import brentq

    def hold(w: float, near: float | None = None) -> tuple[float, float]:
        return weakest_hold(p, w, *search_heights(p, w), near)

    lo, hi = OMEGA_RANGE_RAD_S
    held = hold(hi)
    if held[0] >= 0:
        raise NoBreakUp(f"Fig. 6.18 model plant: the floator is not held beneath the rotator even at "
                        f"{hi * 60 / (2 * math.pi):.0f} RPM (static attraction too weak: rotator tilt "
                        f"{math.degrees(p.tilt_rad):.2f} deg); "
                        "set [geometry] break_phi_rad to fix C instead")
    w_held, w = hi, hi / 1.5
    while w >= lo and (last := hold(w))[0] < 0:        # down to the first speed that drops it
        w_held, held, w = w, last, w / 1.5
    if w < lo:
        raise NoBreakUp(f"the floator is held down to {lo:.0f} rad/s: no break-up speed in range")
    near = math.sqrt(last[1] * held[1])
    omega0 = brentq(lambda x: hold(x, near)[0], w, w_held, xtol=1e-7 * w)
    r_lo, r_hi = search_heights(p, omega0)
    _, r0 = hold(omega0)
    if not r_lo * 1.01 < r0 < r_hi * 0.99:
        raise NoBreakUp(f"the break-up height {r0 * 1e3:.1f} mm lies at the edge of the searched "
                        f"{r_lo * 1e3:.1f}-{r_hi * 1e3:.1f} mm (gap_mm of the rig file far off?)")
    phi0 = _net_outward_force(p, r0, omega0)[1].phi
    return _make(p, phi0, r0, omega0, True, 1.0 - omega0 / W_REF_RAD_S)
