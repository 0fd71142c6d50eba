"""A rotator / floator pair in the point-dipole model: axial force, bound state, speed limits.

The floator hangs beneath the rotator on its spin axis (the paper's set-ups, Sec. 6.0.6 case
(3)) or sits above it. The cycle-averaged axial force at a distance r comes from the
co-rotating steady state of :func:`labkit.model.floator_equilibrium.steady_state` (cone plus
lateral circle, split into the PFR of the cyclic moment and the attraction of the static one,
Eq. 5.84-5.85). For a point dipole the force along the axis is mirror-symmetric, so "beneath"
only changes the sign of the weight: the load pushing the floator away is +m g beneath and
-m g above (Eq. 6.19).

Speeds: the PFR falls as omega^-2 (Eq. 5.81) while the attraction hardly changes, so

* above a **maximum speed** the equilibrium would sit closer than contact (the magnets touch);
* below a **minimum speed** the net attraction at the stiffness limit (below Eq. 6.22) no longer
  carries the weight, and the floator falls.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from labkit.errors import LabkitError
from labkit.model.cone import cone_angle_tilted_dipole
from labkit.model.floator_equilibrium import FloatorSetup, FloatorState, steady_state
from labkit.predict.axial import AxialBoundState, axial_bound_state
from labkit.predict.magnets import Magnet
from labkit.units import G0

K_M = 1e-7  # mu0 / 4 pi
MAX_RESIDUAL = 1e-9
MAX_CONE_RAD = math.pi / 4  # beyond this the "steady state" is not the small-cone branch


@dataclass(frozen=True)
class Pair:
    """Rotator and floator magnets, rotator tilt gamma (rad, Eq. 5.25) and where the floator is."""

    rotator: Magnet
    floator: Magnet
    gamma: float
    placement: str = "beneath"  # or "above"
    gravity: float = G0

    def setup(self, omega: float) -> FloatorSetup:
        f = self.floator
        return FloatorSetup(self.rotator.moment_a_m2, f.moment_a_m2, f.mass_kg,
                            f.inertia_radial_kg_m2, f.inertia_axial_kg_m2, omega, self.gamma)

    @property
    def contact_distance(self) -> float:
        """Centre distance at which the magnets touch along the axis."""
        return self.rotator.axial_half_extent_m + self.floator.axial_half_extent_m

    @property
    def load(self) -> float:
        """External axial force pushing the floator away from the rotator: its weight, signed."""
        w = self.floator.mass_kg * self.gravity
        return w if self.placement == "beneath" else -w

    @property
    def dipole_constant(self) -> float:
        """M = mu0 m_R m_F / 4 pi (Eq. 5.71)."""
        return K_M * self.rotator.moment_a_m2 * self.floator.moment_a_m2

    def torques(self, r: float) -> tuple[float, float]:
        """(tau_C, tau_S) on the floator at distance r on the axis (Eq. 5.28)."""
        m = self.dipole_constant / r**3
        return m * math.cos(self.gamma), 2 * m * math.sin(self.gamma)


@dataclass
class ForceCurve:
    """Cycle-averaged axial force F(r) (N, positive away from the rotator) at one speed, cached."""

    pair: Pair
    omega: float
    states: dict[float, FloatorState | None] = field(default_factory=dict)
    evaluations: int = 0

    def state(self, r: float) -> FloatorState | None:
        if r not in self.states:
            self.evaluations += 1
            try:
                with np.errstate(all="ignore"):
                    self.states[r] = steady_state(self.pair.setup(self.omega), r)
            except (OverflowError, ValueError, FloatingPointError, np.linalg.LinAlgError):
                self.states[r] = None
        st = self.states[r]
        if st is None or not math.isfinite(st.force_z) or st.residual > MAX_RESIDUAL or st.phi > MAX_CONE_RAD:
            return None
        return st

    def __call__(self, r: float) -> float:
        st = self.state(float(r))
        return math.nan if st is None else st.force_z

    def search_range(self) -> tuple[float, float]:
        r0 = self.pair.contact_distance
        return r0, SEARCH_RANGE_CONTACTS * r0

    def stiffness_limit(self, xtol: float, guess: float | None = None) -> tuple[float, float]:
        """(r, largest net attraction) over the search range: a log-spaced scan (narrow around
        ``guess`` when given), then Brent to ``xtol``."""
        lo, hi = self.search_range()
        if guess is not None:
            grid = np.geomspace(max(lo, guess / 1.4), min(hi, guess * 1.4), 7)
            values = self._scan(grid)
            i = int(np.argmin(values))
            if 0 < i < len(grid) - 1 or (i == 0 and grid[0] == lo):
                return self._refine(grid, values, i, xtol)
        grid = np.geomspace(lo, hi, 25)
        values = self._scan(grid)
        i = int(np.argmin(values))
        if not np.isfinite(values[i]):
            return lo, -math.inf
        return self._refine(grid, values, i, xtol)

    def _scan(self, grid: np.ndarray) -> np.ndarray:
        values = np.array([self(r) for r in grid])
        return np.where(np.isfinite(values), values, np.inf)

    def _refine(self, grid: np.ndarray, values: np.ndarray, i: int, xtol: float) -> tuple[float, float]:
        a, b = grid[max(i - 1, 0)], grid[min(i + 1, len(grid) - 1)]

        if not (np.isfinite(values[max(i - 1, 0)]) and np.isfinite(values[min(i + 1, len(grid) - 1)])):
            return float(grid[i]), -float(values[i])  # next to distances without a steady state

        def f(r: float) -> float:
            v = self(r)
            return v if math.isfinite(v) else 1e30

        res = minimize_scalar(f, bounds=(a, b), method="bounded", options={"xatol": xtol, "maxiter": 100})
        if res.fun <= values[i]:
            return float(res.x), -float(res.fun)
        return float(grid[i]), -float(values[i])

    def bound_state(self, xtol: float = 1e-9) -> AxialBoundState:
        lo, hi = self.search_range()
        lim = self.stiffness_limit(xtol)
        return axial_bound_state(self, self.pair.load, lo, hi, xtol=xtol, r_limit=lim)


class NoSmallConeError(LabkitError):
    """No small-cone steady state exists anywhere a bound state is looked for (the speed is far
    too low): refused at once instead of minutes of steady-state solves that cannot succeed."""


#: a search range reaches this many contact distances (:meth:`ForceCurve.search_range`)
SEARCH_RANGE_CONTACTS = 40.0


#: a speed below this fraction of the estimated minimum speed is refused: a slip, not a margin
FAR_BELOW_MIN_SPEED = 0.1
#: that estimate scales the force split solved at this many times the asked speed (fast solves)
REFERENCE_SPEED_FACTOR = 100.0


def far_cone_angle(pair: Pair, omega: float, contacts: float = SEARCH_RANGE_CONTACTS) -> float:
    """The floator's cone angle (rad, Eq. 5.30, closed form) ``contacts`` contact distances from
    the rotator (default: the far end of the search range, the smallest cone anywhere in it,
    since the torque falls as r^-3). pi/2 when the static torque outweighs the inertia."""
    r = contacts * pair.contact_distance
    tau = K_M * pair.rotator.moment_a_m2 * pair.floator.moment_a_m2 / r**3
    inertia = pair.floator.inertia_radial_kg_m2
    if inertia * omega**2 - 2.0 * tau * math.sin(pair.gamma) <= 0:
        return math.pi / 2
    return abs(float(cone_angle_tilted_dipole(tau, pair.gamma, inertia, omega)))


def check_speed_can_bind(pair: Pair, omega: float, rpm_per_rad_s: float = 60 / (2 * math.pi)) -> None:
    """NoSmallConeError when even at the far end of the search range the cone (Eq. 5.30) exceeds
    :data:`MAX_CONE_RAD`: no steady state of the small-cone branch exists at any distance, so no
    bound state. ``labkit predict --speed-rpm 25`` (the "000" forgotten) is refused in
    milliseconds instead of 14 minutes of solves. Deterministic: the model's closed form."""
    phi = far_cone_angle(pair, omega)
    if phi <= MAX_CONE_RAD:
        _check_far_below_min_speed(pair, omega, rpm_per_rad_s)
        return
    rpm = omega * rpm_per_rad_s
    hint = f"; did you mean {rpm * 1e3:g} rpm?" if far_cone_angle(pair, omega * 1e3) <= MAX_CONE_RAD else ""
    r_far = SEARCH_RANGE_CONTACTS * pair.contact_distance
    raise NoSmallConeError(
        f"no bound state at {rpm:g} rpm: even {r_far * 1e3:.0f} mm from the rotator "
        f"({SEARCH_RANGE_CONTACTS:g} contact distances) the floator's cone under the rotating dipole "
        f"(Eq. 5.30) would be {phi:.2f} rad, "
        f"beyond the small-cone branch (<= {MAX_CONE_RAD:.3f} rad) the PFR needs; the rotor must turn "
        f"far faster{hint}")


def _check_far_below_min_speed(pair: Pair, omega: float, rpm_per_rad_s: float) -> None:
    """NoSmallConeError when ``omega`` is below :data:`FAR_BELOW_MIN_SPEED` of the minimum speed
    estimated by :func:`scaled_min_speed_guess` from the force split at
    :data:`REFERENCE_SPEED_FACTOR` times ``omega`` (PFR ~ omega^-2, Eq. 5.81). Only looked at when
    the closed-form cone at contact exceeds :data:`MAX_CONE_RAD` (a slow speed: at normal speeds
    nothing is added) and the weight pulls the floator away (beneath the rotator)."""
    if pair.load <= 0 or far_cone_angle(pair, omega, 1.0) <= MAX_CONE_RAD:
        return
    reference = ForceCurve(pair, omega * REFERENCE_SPEED_FACTOR)
    reference.stiffness_limit(1e-7)
    w_min = scaled_min_speed_guess(reference)
    if not (math.isfinite(w_min) and omega < FAR_BELOW_MIN_SPEED * w_min):
        return
    rpm, min_rpm = omega * rpm_per_rad_s, w_min * rpm_per_rad_s
    hint = f"; did you mean {rpm * 1e3:g} rpm?" if w_min <= omega * 1e3 <= 5 * w_min else ""
    raise NoSmallConeError(
        f"no bound state at {rpm:g} rpm: the minimum speed is about {float(f'{min_rpm:.2g}'):g} rpm (the "
        f"force split solved at {rpm * REFERENCE_SPEED_FACTOR:g} rpm, its PFR scaled as omega^-2, "
        f"Eq. 5.81); below a tenth of it there is no bound state to predict and the solves take "
        f"minutes{hint}")


def _log_root(fn, omega0: float, increasing: bool, rtol: float, first_step: float = 0.05,
              max_factor: float = 1000.0) -> float:
    """Root in omega of ``fn`` (monotone in omega; NaN counts as the low side): bracketed from
    ``omega0`` by steps in log(omega) that double from ``first_step``, then Brent in log(omega).
    NaN when there is no root within ``max_factor`` of ``omega0``."""
    def g(log_w: float) -> float:
        v = fn(math.exp(log_w))
        if not math.isfinite(v):
            return -1.0 if increasing else 1.0
        return v

    x0 = math.log(omega0)
    v0 = g(x0)
    sign_up = (v0 < 0) == increasing  # the root lies above omega0
    reach = math.log(max_factor)
    a, step = x0, first_step
    while abs(a - x0) < reach:
        step = min(step, reach - abs(a - x0))
        b = a + step if sign_up else a - step
        if (g(b) > 0) != (v0 > 0):
            lo, hi = (a, b) if a < b else (b, a)
            return math.exp(brentq(g, lo, hi, xtol=rtol / 4, rtol=1e-15))
        a, step = b, step * 2
    return math.nan


def speed_for_distance(pair: Pair, r: float, omega0: float, rtol: float = 1e-5) -> float:
    """Speed (rad/s) at which the equilibrium sits at distance r: F(r; omega) + load = 0.

    With r the contact distance this is the largest speed of the bound state."""
    return _log_root(lambda w: ForceCurve(pair, w)(r) + pair.load, omega0, increasing=False, rtol=rtol)


def scaled_min_speed_guess(curve: ForceCurve) -> float:
    """First guess of the minimum speed from the force split already solved at one speed: the
    PFR part scaled as omega^-2 (Eq. 5.81), the static attraction held fixed (it hardly depends
    on omega), maximised over the distances in the cache. rad/s; NaN when there is none."""
    states = [st for r in sorted(curve.states) if (st := curve.state(r)) is not None]
    if len(states) < 3:
        return math.nan
    f_c = np.array([st.force_cyclic_z for st in states])
    f_s = np.array([st.force_static_z for st in states])

    def margin(log_w: float) -> float:
        scale = (curve.omega / math.exp(log_w)) ** 2
        return float(np.max(-(f_c * scale + f_s))) - curve.pair.load

    lo, hi = math.log(curve.omega) - 8.0, math.log(curve.omega) + 8.0
    if margin(lo) >= 0 or margin(hi) <= 0:
        return math.nan
    return math.exp(brentq(margin, lo, hi, xtol=1e-6))


def min_speed(pair: Pair, omega0: float, rtol: float = 1e-4, xtol: float = 1e-7,
              guess: float | None = None) -> float:
    """Lowest speed (rad/s) whose largest net attraction still carries the load (Eq. 6.19 with
    the stiffness limit below Eq. 6.22). ``guess`` (e.g. :func:`scaled_min_speed_guess`)
    starts the bracket close to the root."""
    last: dict[str, float] = {}

    def margin(w: float) -> float:
        r, attraction = ForceCurve(pair, w).stiffness_limit(xtol, last.get("r"))
        if math.isfinite(attraction):
            last["r"] = r
        return attraction - pair.load

    start = guess if guess is not None and math.isfinite(guess) and guess > 0 else omega0
    return _log_root(margin, start, increasing=True, rtol=rtol)
