"""The strobe report's phase figure: tilt and lateral position of the body against the
rotation phase, with the fitted sinusoids of Eq. 5.97 (docs/reference/reports.md).

A strobe analysis (``labkit analyse strobe --json``) records each frame's phase
(``phase_per_frame``) and the fitted amplitudes: cone angle phi (``tilt_amplitude_rad``),
lateral amplitude beta (``lateral_amplitude_px``) and RC offset delta = beta / tan(phi)
(``rc_offset_px``, Eq. 5.97), and the per-frame tilt and lateral position it fitted
(``per_frame``). Standard errors are read from the JSON's ``uncertainty`` object when the
analysis wrote them; the report never invents one.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from labkit.report.figures import DPI, save

#: (label, value key, unit, stderr keys the analysis may write)
MOTION = (
    ("cone angle φ", "tilt_amplitude_rad", "rad",
     ("tilt_amplitude_stderr_rad", "tilt_amplitude_rad_stderr", "phi_stderr_rad")),
    ("lateral amplitude β", "lateral_amplitude_px", "px",
     ("lateral_amplitude_stderr_px", "lateral_amplitude_px_stderr", "beta_stderr_px")),
    ("RC offset δ (Eq. 5.97)", "rc_offset_px", "px",
     ("rc_offset_stderr_px", "rc_offset_px_stderr", "delta_stderr_px")),
    ("lateral amplitude β", "lateral_amplitude_mm", "mm",
     ("lateral_amplitude_stderr_mm", "lateral_amplitude_mm_stderr", "beta_stderr_mm")),
    ("RC offset δ (Eq. 5.97)", "rc_offset_mm", "mm",
     ("rc_offset_stderr_mm", "rc_offset_mm_stderr", "delta_stderr_mm")),
)


def find_stderr(doc: dict[str, Any], keys: tuple[str, ...], value_key: str | None = None) -> float | None:
    """The standard error of ``value_key``: ``uncertainty[value_key]`` as ``labkit analyse strobe``
    writes it, else the first of ``keys`` found in the result, its ``quality`` or
    ``stderr``/``uncertainty`` objects; None when the analysis recorded none."""
    written = doc.get("uncertainty")
    if value_key is not None and isinstance(written, dict):
        value = written.get(value_key)
        if isinstance(value, int | float) and math.isfinite(value):
            return float(value)
    places = [doc] + [doc.get(k) for k in ("quality", "stderr", "uncertainty", "uncertainties")]
    for place in places:
        if not isinstance(place, dict):
            continue
        for key in keys:
            value = place.get(key)
            if isinstance(value, int | float) and math.isfinite(value):
                return float(value)
    return None


def motion_rows(doc: dict[str, Any]) -> list[list[str]]:
    """Rows ``quantity, value, standard error, unit`` for phi, beta and delta."""
    rows = []
    for label, key, unit, stderr_keys in MOTION:
        value = doc.get(key)
        if not isinstance(value, int | float):
            continue
        stderr = find_stderr(doc, stderr_keys, key)
        shown = f"{value:.4g}" + (f" ({math.degrees(value):.2f}°)" if unit == "rad" else "")
        rows.append([label, shown, "no uncertainty (not in the analysis result)" if stderr is None
                     else f"{stderr:.2g}", unit])
    return rows


def fitted_frames(doc: dict[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(frame index, lateral position [px], tilt [rad])`` the analysis fitted (``per_frame``)."""
    per_frame = doc.get("per_frame")
    if not isinstance(per_frame, dict):
        raise ValueError("the strobe result has no per-frame tilt and position (written by an older "
                         "labkit): run labkit analyse strobe --json again")
    return (np.asarray(per_frame["index"], dtype=int), np.asarray(per_frame["lateral_px"], dtype=float),
            np.asarray(per_frame["tilt_rad"], dtype=float))


def sinusoid(phase: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, float]:
    """Least squares of ``y = c0 + c1 sin(psi) + c2 cos(psi)``: coefficients and rms residual."""
    m = np.column_stack([np.ones_like(phase), np.sin(phase), np.cos(phase)])
    coef, *_ = np.linalg.lstsq(m, y, rcond=None)
    return coef, float(np.sqrt(np.mean((y - m @ coef) ** 2)))


def _curve(coef: np.ndarray, grid: np.ndarray) -> np.ndarray:
    return coef[0] + coef[1] * np.sin(grid) + coef[2] * np.cos(grid)


def phase_figure(doc: dict[str, Any], path: str | Path) -> Path:
    """Tilt (top) and lateral position (bottom) against phase, with the fitted sinusoids."""
    phases_all = np.asarray(doc["phase_per_frame"], dtype=float)
    idx, x, tilt = fitted_frames(doc)
    keep = idx < len(phases_all)
    idx, x, tilt = idx[keep], x[keep], tilt[keep]
    if len(idx) < 3:
        raise ValueError(f"only {len(idx)} frames with a body")
    psi = phases_all[idx]
    grid = np.linspace(0.0, 2.0 * math.pi, 361)
    fig = Figure(figsize=(7.0, 6.0), dpi=DPI)
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, 1, sharex=True, gridspec_kw={"hspace": 0.08})
    ct, rms_t = sinusoid(psi, tilt)
    cx, rms_x = sinusoid(psi, x)
    x0 = cx[0]
    phi = doc.get("tilt_amplitude_rad")
    beta = doc.get("lateral_amplitude_px")
    delta = doc.get("rc_offset_px")
    for ax, y, coef, rms, label, name in (
        (axes[0], tilt, ct, rms_t, "tilt θ [rad]", f"φ = {phi:.4g} rad" if phi is not None else "φ"),
        (axes[1], x - x0, cx - np.array([x0, 0.0, 0.0]), rms_x, "lateral position x - x₀ [px]",
         f"β = {beta:.4g} px" if beta is not None else "β"),
    ):
        ax.plot(psi, y, "o", ms=4, color="tab:blue", label=f"frames ({len(psi)})")
        ax.plot(grid, _curve(coef, grid), "-", color="tab:red", lw=1.8,
                label=f"fitted sinusoid: {name}, rms residual {rms:.2g}")
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="best")
    axes[1].set_xlabel("rotation phase ψ [rad]")
    axes[1].set_xlim(0.0, 2.0 * math.pi)
    axes[1].set_xticks([0, math.pi / 2, math.pi, 3 * math.pi / 2, 2 * math.pi],
                       ["0", "π/2", "π", "3π/2", "2π"])
    delta_text = f", δ = β / tan φ = {delta:.4g} px (Eq. 5.97)" if delta is not None else ""
    axes[0].set_title(f"Strobe: tilt and lateral position against phase{delta_text}", fontsize=10)
    fig.subplots_adjust(left=0.13, right=0.97, top=0.93, bottom=0.09)
    return save(fig, path)
