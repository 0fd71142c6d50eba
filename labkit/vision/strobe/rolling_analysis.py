"""When and how ``labkit analyse strobe`` uses the per-row model of
:mod:`labkit.vision.strobe.rolling_model` (docs/explanation/strobe-analysis.md, *Rolling shutter
with the camera as the strobe*), what it reports, and the verdict's checks of it.

It applies when the camera is the strobe (``--rotor-hz`` without ``--strobe-hz``) and the clip
shows a rolling shutter: the silhouette is bent (the ``body_bend_px`` evidence) or the user gives
``--readout-ms`` above 0 (``--readout-ms 0`` says the shutter is global and keeps the per-frame
analysis). The magnet axis is the side of the silhouette across which the centre of mass swings
(the fit's rotation centre lies along it): ``beta = |offset| tan(phi)`` (Eq. 5.97).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from labkit.vision.strobe.body import MAX_BEND_PX, BodyPose, ClipOrientation
from labkit.vision.strobe.phase import PhaseModel
from labkit.vision.strobe.rolling_model import (
    GRID_STEPS,
    Crops,
    FitInput,
    collect_crops,
    fit_rolling,
    initial_guess,
    row_centres,
)

MIN_ENDS_COS = 0.7  # see ends_separation: below it the ends hold under half the information
MIN_ROW_CROSSING_DEG = 30.0  # the body's long side at least this steep, or rows run along it
MIN_FIT_FRAMES = 6
MIN_ROWS = 20  # rows that cut the body fully, over all frames, for the linear start
MAX_RESIDUAL_NOISE = 3.0  # fit residual rms against the pixel noise of the background
NOISE_FLOOR = 1.0  # grey levels: compression flattens a quiet background below its true noise


def rolling_applies(model: PhaseModel | None, rotor_hz: float | None, readout_s: float | None,
                    bend_px: float) -> bool:
    """The camera is the strobe and the shutter rolls (given, or seen as a bent silhouette)."""
    if model is None or model.kind != "camera" or not rotor_hz:
        return False
    if readout_s is not None:
        return readout_s > 0
    return bend_px > MAX_BEND_PX


def _noise(crops: Crops) -> float:
    """Pixel noise of the crops' background away from the body: robust spread of the difference
    of horizontal neighbours, over sqrt(2)."""
    away = ~np.array([cv2.dilate(b.astype(np.uint8), np.ones((5, 5), np.uint8)) > 0 for b in
                      (crops.band & _near(crops))])
    d = np.diff(crops.values, axis=2)
    keep = away[:, :, 1:] & away[:, :, :-1]
    if keep.sum() < 50:
        return 0.0
    v = d[keep]
    return float(1.4826 * np.median(np.abs(v - np.median(v))) / math.sqrt(2))


def _near(crops: Crops) -> np.ndarray:
    """Band pixels that are not the one-in-nine background sample (see strobe_rolling._bands)."""
    sparse = np.zeros(crops.values.shape[1:], bool)
    sparse[::3, ::3] = True
    return crops.band & ~sparse[None]


def ends_separation(omega: float, along: np.ndarray, half_along: float, across: np.ndarray,
                    half_across: float) -> float | None:
    """When the centre swings along the side of the silhouette that the rows cut lengthwise (rows
    cross the pair of sides parallel to the swing), only the body's two ends show the swing, and
    a change of the body's size (a square plate turning about its axis) moves them apart just as
    the swing does when they are read half a rotor cycle apart. Returns |cos(Delta/2)|, Delta the
    rotor phase between the rows of the two ends (1: ends read in phase, the swing fully seen;
    0: not separable from the size), or None when interior rows show the swing."""
    if 2 * half_along * abs(along[1]) <= 2 * half_across * abs(across[1]):
        return None
    delta = omega * 2 * half_along * abs(along[1])
    return abs(math.cos(delta / 2))


def _amplitudes(g: dict, stats: dict, blur: float):
    """phi, beta, the rotation centre's offset, their errors, and the magnet axis (unit vector,
    angle) from the fit: the magnet axis is the rest axis u when the centre swings across it."""
    free, cov = stats["free"], stats["cov"]
    idx = {k: i for i, k in enumerate(free)}
    phi = g["phi"]
    on_u = abs(g["delta"]) >= abs(g["eps"])
    key = "delta" if on_u else "eps"
    offset = abs(g[key])
    angle = g["alpha0"] + (0.0 if on_u else math.pi / 2)
    grad = np.zeros(len(free))
    grad[idx["phi"]] = offset / math.cos(phi) ** 2
    grad[idx[key]] = math.copysign(math.tan(phi), g[key])
    beta = offset * math.tan(phi)
    beta_se = float(math.sqrt(max(grad @ cov @ grad, 0.0)))
    return (phi / blur, stats["se"]["phi"] / blur, beta / blur, beta_se / blur, offset, stats["se"][key],
            on_u, angle)


def _towards_top(g: dict, on_u: bool, angle: float) -> bool | None:
    """Is the rotation centre towards the body's top end (the end nearer image-up) from the centre
    of mass? It is at ``delta u`` (or ``eps n``) from it."""
    axis = np.array([math.cos(angle), math.sin(angle)])
    top = -axis if (axis[1] > 1e-9 or (abs(axis[1]) <= 1e-9 and axis[0] < 0)) else axis
    u = np.array([math.cos(g["alpha0"]), math.sin(g["alpha0"])])
    rc = g["delta"] * u if on_u else g["eps"] * np.array([-u[1], u[0]])
    dot = float(rc @ top)
    return None if dot == 0 else dot > 0


def _long_side_from_rows(alpha0: float, half_u: float, half_n: float) -> float:
    """Angle (deg, 0-90) between the silhouette's longer side and the image rows."""
    angle = alpha0 if half_u >= half_n else alpha0 + math.pi / 2
    return abs(math.degrees(math.atan(math.tan(angle))))


def rolling_analysis(path: str, poses: list[BodyPose | None], orient: ClipOrientation, model: PhaseModel,
                     rotor_hz: float, fps: float, height: int, readout_s: float | None) -> dict | None:
    """Fit the per-row model; returns the ``rolling_shutter`` object of the result JSON, or None
    when the footage gives too little to fit (too few frames read again, or too few rows cutting
    the body: the per-frame result stands, and its bend check names the rolling shutter)."""
    found = [p for p in poses if p is not None]
    crops = collect_crops(path, poses)
    if len(crops.frames) < MIN_FIT_FRAMES or len(row_centres(crops)[0]) < MIN_ROWS:
        return None
    angle = orient.rest_angle_rad if orient.symmetry == 2 else float(
        np.median([p.angle2_rad for p in found]))
    half = (float(np.median([p.half_length_along(angle) for p in found])),
            float(np.median([p.half_length_along(angle + math.pi / 2) for p in found])))
    mean_x, mean_y = np.mean([[p.x, p.y] for p in found], axis=0)
    centre = (float(mean_x), float(mean_y))
    given = FitInput(model.cycles_per_frame, rotor_hz, fps, height, angle, half, centre, readout_s)
    omega_max = 2 * math.pi * rotor_hz / (fps * max(1, height - 1))
    omegas = (np.linspace(0.0, omega_max, GRID_STEPS) if readout_s is None
              else np.array([2 * math.pi * rotor_hz * readout_s / max(1, height - 1)]))
    start = initial_guess(crops, model.cycles_per_frame, omegas)
    g, a, b, stats = fit_rolling(crops, given, start)
    phi, phi_se, beta, beta_se, offset, offset_se, on_u, axis_angle = _amplitudes(g, stats, model.blur_factor)
    line = g["omega"] / (2 * math.pi * rotor_hz)
    line_se = stats["se"].get("omega", 0.0) / (2 * math.pi * rotor_hz)
    u = np.array([math.cos(g["alpha0"]), math.sin(g["alpha0"])])
    n = np.array([-u[1], u[0]])
    # the swing runs along n when the offset is along u (delta), along u when it is along n (eps)
    swing, half_swing, other, half_other = (n, float(np.median(b)), u, float(np.median(a))) if on_u else \
        (u, float(np.median(a)), n, float(np.median(b)))
    noise = _noise(crops)
    return {
        "model": "per-row phase psi = psi_0 + 2 pi c k + 2 pi f_rot L r (Eq. 5.97 per row)",
        "tilt_amplitude_rad": phi, "tilt_amplitude_se_rad": phi_se,
        "lateral_amplitude_px": beta, "lateral_amplitude_se_px": beta_se,
        "rc_offset_px": offset, "rc_offset_se_px": offset_se,
        "towards_top": _towards_top(g, on_u, axis_angle),
        "magnet_axis_deg": round(math.degrees(math.atan2(-math.sin(axis_angle), math.cos(axis_angle))),
                                 9) % 180.0,
        "readout_s": line * max(1, height - 1), "readout_se_s": line_se * max(1, height - 1),
        "readout_given": readout_s is not None, "line_time_s": line,
        "readout_at_bound": bool(readout_s is None and not 0.02 * omega_max < g["omega"] < 0.99 * omega_max),
        "rows_explained": start.explained, "rows_explained_one_phase_per_frame": start.explained_global,
        "ends_separation": ends_separation(g["omega"], swing, half_swing, other, half_other),
        "long_side_from_rows_deg": _long_side_from_rows(g["alpha0"], float(np.median(a)),
                                                        float(np.median(b))),
        "rms_residual": stats["rms"], "noise": noise,
        "residual_noise_ratio": stats["rms"] / max(noise, NOISE_FLOOR),
        "correlation_area_px": stats["inflation"], "frames_fitted": len(crops.frames), "bin": crops.bin,
        "pixels_fitted": stats["pixels"], "iterations": stats["iterations"],
        "converged": stats["converged"],
        "lens_blur_px": {"core": float(g["sigma_core"]), "halo": float(g["sigma_halo"]),
                         "halo_fraction": float(g["halo_fraction"])},
    }


def rolling_checks(v, e: dict) -> None:
    """The verdict's checks of the per-row fit (``v``: the strobe checks' Verdict; ``e``: the
    evidence with ``rolling_shutter``)."""
    r = e["rolling_shutter"]
    if not r["converged"]:
        v.doubt("rolling shutter with the camera as the strobe: the per-row fit did not converge")
    ratio = r.get("residual_noise_ratio")
    if ratio > MAX_RESIDUAL_NOISE:
        v.doubt(f"rolling shutter with the camera as the strobe: the per-row model leaves "
                f"{r['rms_residual']:.1f} grey levels rms, {ratio:.1f}x the pixel noise; the body is not the "
                "rigid rectangle of Eq. 5.97 row by row, or something else moves")
    if r["readout_at_bound"]:
        v.doubt(f"rolling shutter with the camera as the strobe: the readout came out at the end of its "
                f"range ({r['readout_s'] * 1e3:.2f} ms); give --readout-ms if you know it")
    crossing = r["long_side_from_rows_deg"]
    if crossing < MIN_ROW_CROSSING_DEG:
        v.doubt(f"rolling shutter with the camera as the strobe: the rows run along the body (its long side "
                f"{crossing:.0f} deg from them), so few rows cut across it and the per-row model is poorly "
                "conditioned: tilt and lateral amplitude are doubtful (turn the camera so that the rows "
                "cross the body, or use a global shutter or a lamp)")
    ends = r.get("ends_separation")
    if ends is not None:
        half_cycle = (f", and they are read about half a rotor cycle apart (|cos| {ends:.2f}), so the swing "
                      "cannot be told from a change of the body's size") if ends < MIN_ENDS_COS else ""
        v.doubt("rolling shutter with the camera as the strobe: the centre swings along the side the rows "
                f"cut lengthwise, so only the body's two ends show it{half_cycle}; anything else that moves "
                "the ends (a square plate turning about its axis during the readout) biases it by more "
                "than its error, and labkit cannot tell: the lateral amplitude is doubtful (turn the camera "
                "so that the rows cross that side)")
