"""Fits of the twin: recover the put-in magnets and distances from what the instruments read.

* :func:`fit_moment_product` - m_R m_F from the Fig. 5.25 sweep (balance force against rotor
  speed). Exact scaling of the steady state (Sec. 5.2): torques and forces are both
  proportional to ``P = m_R m_F``, so with ``P -> lambda P`` and ``w -> sqrt(lambda) w`` every
  angle and offset stays and the force scales by lambda:
  ``F(w; P) = (P / P0) F(w sqrt(P0 / P); P0)`` - one cached table serves every trial P.
* :func:`fit_gap` - the rotator-floator distance with the moments held (fresh steady-state
  solves at the measured speeds).
* C of Eq. 6.37 comes from the spin-critical protocol's own fit; :func:`break_phi_from_c`
  inverts Eq. 6.37 for the cone angle at the break-up (at the break-up height and speed of
  :func:`labkit.emulators.break_up.break_up`).

Every fit returns value, stderr (the residual-scaled covariance of weighted least squares)
and the 95 % interval ``value +/- t_{0.975, n-1} stderr`` (:func:`interval_95`); :func:`compare`
makes the twin's row of a fit against the value put in.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any

from labkit.emulators.twin_model import TwinParams, balance_force_table, steady_force_n


def interval_95(value: float, stderr: float, n: int, k: int = 1) -> dict[str, Any]:
    """A fitted value with its stderr and 95 % interval ``value +/- t_{0.975, n-k} stderr``."""
    from scipy.stats import t as student_t
    half = float(student_t.ppf(0.975, max(n - k, 1))) * stderr
    return {"value": value, "stderr": stderr, "ci95": [value - half, value + half], "n": n}


def _fit_one(model, x0: float, speeds: list[float], force: list[float], sigma: list[float]) -> dict:
    import numpy as np
    from scipy.optimize import curve_fit
    w, f, s = (np.asarray(a, float) for a in (speeds, force, sigma))
    s = np.where(s > 0, s, np.nanmax(s) if np.any(s > 0) else 1.0)
    # fitted in units of x0 (so the finite-difference step suits any magnitude)
    (u,), cov = curve_fit(lambda ww, uu: np.array([model(x, uu * x0) for x in ww]), w, f, p0=(1.0,),
                          sigma=s, absolute_sigma=False, epsfcn=1e-8)
    return interval_95(float(u * x0), float(math.sqrt(max(cov[0, 0], 0.0)) * abs(x0)), len(w))


def sweep_points(points: list[dict]) -> tuple[list[float], list[float], list[float]]:
    """(speed rad/s, force N, stderr N) of the speed-sweep result rows that carry a force."""
    rows = [p for p in points if p.get("force_n") is not None and p.get("speed_rad_s")]
    return ([p["speed_rad_s"] for p in rows], [p["force_n"] for p in rows],
            [p.get("force_stderr_n") or 0.0 for p in rows])


def fit_moment_product(params: TwinParams, points: list[dict]) -> dict:
    """m_R m_F (A^2 m^4) from the sweep's (speed, force), the other rig values held."""
    table = balance_force_table(params)
    p0 = params.moment_product

    def model(w: float, p: float) -> float:
        lam = p / p0
        return lam * table.force_n(w / math.sqrt(lam))

    return _fit_one(model, p0, *sweep_points(points))


def fit_gap(params: TwinParams, points: list[dict]) -> dict:
    """Rotator-floator distance (m) from the sweep, the moments held (fresh solves)."""
    return _fit_one(lambda w, r: steady_force_n(replace(params, gap_m=r), w), params.gap_m,
                    *sweep_points(points))


def break_phi_from_c(params: TwinParams, c: dict) -> dict:
    """Cone angle at the break-up (rad) from C of Eq. 6.37 (:meth:`BreakUp.phi_from_c`)."""
    from labkit.emulators.break_up import break_up
    phi = break_up(params).phi_from_c
    lo, hi = c["ci95"]
    return {"value": phi(c["value"]), "stderr": abs(phi(c["value"] + c["stderr"]) - phi(c["value"])),
            "ci95": sorted([phi(lo), phi(hi)]), "n": c["n"]}


def compare(group: str, param: str, put_in: float, fit: dict, unit: str, scale: float = 1.0) -> dict:
    """One row: put-in against recovered, ``ok`` when the put-in value lies in the 95 % interval."""
    lo, hi = (x * scale for x in fit["ci95"])
    value = fit["value"] * scale
    put = put_in * scale
    return {"name": f"twin/{group}/{param}", "group": group, "param": param, "unit": unit,
            "put_in": put, "recovered": value, "stderr": fit["stderr"] * scale, "ci95": [lo, hi],
            "residual": value - put, "rel_diff": (value - put) / put if put else math.nan,
            "ok": bool(lo <= put <= hi), "n": fit.get("n")}
