"""Table 5.3-style stability maps of the conical motion (paper Sec. 5.1.3, Table 5.3, Eq. 5.46).

A point is an axisymmetric body (``i_a``, ``i_r``) in a uniform rotating field (``omega``,
``tau_c``, ``ratio = tau_S / tau_C``), started on its conical equilibrium (Eq. 5.35, 5.12)
with the paper's bias ``bias_y`` (rad/s) added to the angular velocity about y. It is run for
``cycles`` drive periods with the batch kernel (:mod:`labkit.numerics.kernels`) and judged as
in ``labkit reproduce`` (Table 5.3 rows): *unstable* if the dipole's zenith angle leaves the
cone angle by 10x its early deviation and by more than 0.05 rad, or by more than 0.2 rad.
"""

from __future__ import annotations

import math

import numpy as np

from labkit.numerics import kernels
from labkit.numerics.checks import DEFAULT_MEMORY_BYTES, NumericsError
from labkit.sim.equilibrium import cone_angle_axisymmetric, conical_angular_velocity_at, conical_orientation

EARLY_FRACTION = 0.02  # the deviation in the first 2 % of the run sets the scale of the kick
GROWTH_FACTOR = 10.0
MIN_DEVIATION = 0.05
LOST_DEVIATION = 0.2
SAMPLES_PER_PERIOD = 4


def table5_3_rows() -> list[dict]:
    """The 36 rows of Table 5.3 as sweep points (with the paper's verdict for comparison)."""
    from labkit.reproduce.paper_data import TABLE_5_3

    return [
        {
            "row": no,
            "i_a": i_a,
            "i_r": i_r,
            "omega": omega,
            "tau_c": tau_c,
            "ratio": ratio,
            "bias_y": bias,
            "paper": "unstable" if tilted else "stable",
        }
        for no, i_a, i_r, omega, tau_c, ratio, _min, bias, _phi0, _phi, tilted, _crit in TABLE_5_3
    ]


def configurations() -> list[dict]:
    """The distinct body/drive configurations of Table 5.3 (I_A, I_R, omega, tau_C)."""
    seen, out = set(), []
    for row in table5_3_rows():
        cfg = (row["i_a"], row["i_r"], row["omega"], row["tau_c"])
        if cfg not in seen:
            seen.add(cfg)
            out.append({"i_a": cfg[0], "i_r": cfg[1], "omega": cfg[2], "tau_c": cfg[3]})
    return out


def map_points(ratios: list[float], configs: list[dict] | None = None, bias_y: float = 0.5) -> list[dict]:
    """A stability map: every configuration x every ``tau_S / tau_C`` ratio."""
    return [
        {**cfg, "ratio": float(r), "bias_y": bias_y} for cfg in (configs or configurations()) for r in ratios
    ]


FIG_5_12 = {"i_a": 1e-7, "i_r": 1e-7, "omega": 80 * math.pi, "tau_c": 1e-3}


def fig5_12_points(ks: list[float], ratios: list[float], bias_y: float = 0.5) -> list[dict]:
    """Fig. 5.12's map: a spinning isotropic body (I = 1e-7, omega = 80 pi, tau_C = 1e-3) over
    the spin parameter ``k`` (spin ratio q = v_S / omega = k + 1, Eq. 5.65-5.66) and
    ``tau_S / tau_C``, started on the spinning cone of Eq. 5.67/5.68."""
    return [{**FIG_5_12, "spin_k": float(k), "ratio": float(r), "bias_y": bias_y} for k in ks for r in ratios]


def batch_spec(points: list[dict]) -> tuple[kernels.BatchSpec, np.ndarray]:
    """Nondimensional batch (and the cone angles phi) for the points' initial conditions.

    A point may carry ``spin_k`` (default -1, no spin: Eq. 5.12/5.35; otherwise Eq. 5.62/5.64).
    """
    n = len(points)
    jc, js, a, R, l0, phi = (
        np.empty(n),
        np.empty(n),
        np.empty(n),
        np.empty((n, 3, 3)),
        np.empty((n, 3)),
        np.empty(n),
    )
    for k, p in enumerate(points):
        tau_s = p["ratio"] * p["tau_c"]
        w, i_r, i_a = p["omega"], p["i_r"], p["i_a"]
        spin_k = p.get("spin_k", -1.0)
        phi[k] = cone_angle_axisymmetric(omega=w, tau_c=p["tau_c"], tau_s=tau_s, i_radial=i_r,
                                         i_axial=i_a, spin_k=spin_k)
        R[k] = conical_orientation(phi[k], 0.0)
        omega_vec = conical_angular_velocity_at(omega=w, phi=phi[k], theta=0.0, spin_k=spin_k) + np.array(
            [0.0, p.get("bias_y", 0.0), 0.0]
        )
        inertia_lab = R[k] @ np.diag([i_r, i_r, i_a]) @ R[k].T
        l0[k] = inertia_lab @ omega_vec / (i_r * w)
        jc[k] = p["tau_c"] / (i_r * w * w)
        js[k] = tau_s / (i_r * w * w)
        a[k] = i_a / i_r
    return kernels.BatchSpec(jc, js, a, np.zeros(n), R, l0), phi


def verdicts(zenith: np.ndarray, phi: np.ndarray) -> list[dict]:
    """Stable/unstable per trajectory from its zenith samples (see module docstring)."""
    out = []
    n = zenith.shape[1]
    early_n = max(2, int(math.ceil(EARLY_FRACTION * n)))
    for z, p in zip(zenith, phi, strict=True):
        dev = np.abs(z - p)
        finite = bool(np.all(np.isfinite(dev)))
        d_max = float(np.max(dev)) if finite else math.inf
        early = float(np.max(dev[:early_n])) if finite else math.inf
        grew = (not finite) or d_max > max(GROWTH_FACTOR * early, MIN_DEVIATION) or d_max > LOST_DEVIATION
        out.append(
            {
                "verdict": "unstable" if grew else "stable",
                "phi_rad": float(p),
                "max_deviation_rad": d_max,
                "early_deviation_rad": early,
            }
        )
    return out


def sample_bytes(points: int, cycles: int) -> int:
    """Memory the stroboscopic samples of a chunk need (zenith and Jacobi arrays)."""
    return 2 * 8 * points * (cycles * SAMPLES_PER_PERIOD + 1)


def max_chunk(cycles: int, limit_bytes: int = DEFAULT_MEMORY_BYTES) -> int:
    """The most points whose samples fit in ``limit_bytes`` (at least 1: one point too large
    is refused by :func:`check_chunk`)."""
    return max(1, limit_bytes // sample_bytes(1, cycles))


def check_chunk(points: int, cycles: int, limit_bytes: int = DEFAULT_MEMORY_BYTES) -> None:
    """Refuse a chunk whose samples do not fit in ``limit_bytes``."""
    size = sample_bytes(points, cycles)
    if size <= limit_bytes:
        return
    fit = limit_bytes // sample_bytes(1, cycles)
    if fit >= 1:
        advice = f"use --chunk {fit} or fewer cycles"
    else:
        advice = f"use at most {limit_bytes // (16 * SAMPLES_PER_PERIOD)} cycles"
    raise NumericsError(
        f"{points} points x {cycles} cycles need {size / 2**30:.1f} GiB of samples per chunk "
        f"(limit {limit_bytes / 2**30:.1f} GiB): {advice}"
    )


def evaluate(points: list[dict], cycles: int = 100, steps_per_period: int = 64) -> list[dict]:
    """Run a chunk of points with the numba batch kernel; one verdict dict per point."""
    check_chunk(len(points), int(cycles))
    spec, phi = batch_spec(points)
    res = kernels.run_batch_numba(spec, int(cycles), steps_per_period, SAMPLES_PER_PERIOD)
    out = verdicts(res.zenith, phi)
    for row, jac in zip(out, res.jacobi, strict=True):
        row["jacobi_drift"] = float(np.max(np.abs(jac - jac[0])) / max(abs(jac[0]), 1e-300))
    return out


class Evaluator:
    """A picklable ``evaluate`` with its horizon fixed (what :func:`run_sweep` sends to workers)."""

    def __init__(self, cycles: int = 100, steps_per_period: int = 64) -> None:
        self.cycles = cycles
        self.steps_per_period = steps_per_period

    def __call__(self, points: list[dict]) -> list[dict]:
        return evaluate(points, self.cycles, self.steps_per_period)
