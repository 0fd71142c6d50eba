"""Stability map of a rotator / floator pair over a grid (tilt, speed, ...), through
:func:`labkit.numerics.sweep.run_sweep`: local, on a process pool or on a Dask cluster, and
resumable from its JSON-lines store.

Axes are ``tilt_deg`` and ``speed_rpm`` (any one or both); each point is a plain dict holding
the axes and the two magnets, so a store written for other magnets is never reused.
"""

from __future__ import annotations

import math
import time
from itertools import product

import numpy as np

from labkit.predict.magnets import Magnet
from labkit.predict.pair import Pair
from labkit.ranges import RangeError, parse_range

AXES = ("tilt_deg", "speed_rpm")


class MapSpecError(ValueError):
    """A ``--map`` axis that cannot be read."""


#: values per --map axis (the product of the axes is confirmed above CONFIRM_POINTS,
#: docs/reference/command-grammar.md)
MAX_AXIS_VALUES = 10_000


def parse_axis(text: str) -> tuple[str, np.ndarray]:
    """``tilt_deg=2:8:n=7`` -> ("tilt_deg", 7 values from 2 to 8 inclusive); ``2:8:step=1``,
    ``2,4,8`` and ``speed_rpm=20000`` as in :mod:`labkit.ranges` (the old ``2:8:7`` is refused
    with the new spelling: it meant a count here and a step in ``--set``)."""
    name, sep, spec = text.partition("=")
    name = name.strip()
    if not sep or name not in AXES:
        raise MapSpecError(f"{text!r}: expected AXIS=START:STOP:n=COUNT with AXIS one of {', '.join(AXES)}")
    try:
        values = np.array(parse_range(spec, bare="error", limit=MAX_AXIS_VALUES))
    except RangeError as exc:
        raise MapSpecError(f"{text!r}: {exc}") from None
    if name == "speed_rpm" and np.any(values <= 0):
        raise MapSpecError(f"{text!r}: speeds must be positive")
    if name == "tilt_deg" and np.any(np.abs(values) >= 90):
        raise MapSpecError(f"{text!r}: tilts must be below 90 degrees")
    return name, values


def grid_points(axes: dict[str, np.ndarray], pair: Pair, speed_rpm: float | None,
                verify_cycles: int = 0) -> list[dict]:
    """Sweep points: every combination of the axes; a missing axis takes the pair's tilt or
    ``speed_rpm``. ``verify_cycles`` > 0 adds the time-domain check at every bound point."""
    tilts = axes.get("tilt_deg", np.array([math.degrees(pair.gamma)]))
    if "speed_rpm" in axes:
        speeds = axes["speed_rpm"]
    elif speed_rpm is not None:
        speeds = np.array([speed_rpm])
    else:
        raise MapSpecError("the map needs speeds: a speed_rpm axis or --speed-rpm")
    base = {"rotator": _magnet_dict(pair.rotator), "floator": _magnet_dict(pair.floator),
            "placement": pair.placement, "gravity_m_s2": pair.gravity, "verify_cycles": int(verify_cycles)}
    return [{"tilt_deg": float(t), "speed_rpm": float(s), **base} for t, s in product(tilts, speeds)]


def _magnet_dict(m: Magnet) -> dict:
    return {"shape": m.shape, "sizes_m": list(m.sizes_m), "mass_kg": m.mass_kg,
            "inertia_axial_kg_m2": m.inertia_axial_kg_m2, "inertia_radial_kg_m2": m.inertia_radial_kg_m2,
            "moment_a_m2": m.moment_a_m2, "axial_half_extent_m": m.axial_half_extent_m, "size_m": m.size_m}


def _magnet(d: dict) -> Magnet:
    return Magnet(**{**d, "sizes_m": tuple(d["sizes_m"])})


def evaluate_points(points: list[dict]) -> list[dict]:
    """Sweep ``evaluate``: the bound state and the cone's linear stability at each point, plus
    the time-domain check (lateral stiffness, stays bound) when the point asks for it."""
    from labkit.predict.pair import NoSmallConeError
    from labkit.predict.predictor import predict

    rows = []
    for p in points:
        t0 = time.perf_counter()
        pair = Pair(_magnet(p["rotator"]), _magnet(p["floator"]), math.radians(p["tilt_deg"]),
                    p["placement"], p["gravity_m_s2"])
        cycles = int(p.get("verify_cycles", 0))
        try:
            pred = predict(pair, p["speed_rpm"] * 2 * math.pi / 60, run_verify=cycles > 0,
                           verify_cycles=max(cycles, 10), speed_limits=False, scaling=False, xtol=1e-8)
        except NoSmallConeError as exc:  # far too slow: the floator falls, said without minutes of solves
            rows.append({"bound": False, "stable": False, "verdict": str(exc),
                         **{k: math.nan for k in _NUMBERS}, "wall_s": time.perf_counter() - t0})
            continue
        rows.append({
            "bound": pred.bound, "stable": pred.stable, "verdict": pred.verdict,
            "r_eq_mm": _num(pred.value("r_eq_mm")),
            "axial_stiffness_N_m": _num(pred.value("axial_stiffness_N_m")),
            "cone_angle_deg": _num(pred.value("cone_angle_deg")),
            "growth_rate_1_s": _num(pred.value("growth_rate_1_s")),
            "max_load_N": _num(pred.value("max_load_N")),
            "lateral_stiffness_N_m": _num(pred.value("lateral_stiffness_N_m")),
            "wall_s": time.perf_counter() - t0,
        })
    return rows


_NUMBERS = ("r_eq_mm", "axial_stiffness_N_m", "cone_angle_deg", "growth_rate_1_s", "max_load_N",
            "lateral_stiffness_N_m")


def _num(v) -> float:
    return math.nan if v is None else float(v)


def map_symbol(row: dict) -> str:
    """``S`` bound and stable, ``U`` bound but unstable, ``x`` the magnets snap together (too
    fast: the equilibrium would be inside contact), ``.`` the floator falls (too weak)."""
    if not row.get("bound"):
        return "x" if "snap" in (row.get("verdict") or "") else "."
    return "S" if row.get("stable") else "U"


def render_map(rows: list[dict]) -> str:
    """Text map: one line per tilt, one column per speed."""
    tilts = sorted({r["tilt_deg"] for r in rows})
    speeds = sorted({r["speed_rpm"] for r in rows})
    cell = {(r["tilt_deg"], r["speed_rpm"]): map_symbol(r) for r in rows}
    width = max(7, max(len(f"{s:.0f}") for s in speeds) + 1)
    lines = ["tilt_deg \\ speed_rpm " + "".join(f"{s:>{width}.0f}" for s in speeds)]
    for t in tilts:
        lines.append(f"{t:>20.3g} " + "".join(f"{cell.get((t, s), '?'):>{width}}" for s in speeds))
    lines.append("S bound and stable, U bound but unstable, x magnets snap together, . floator falls "
                 "(point dipoles)")
    return "\n".join(lines)


