"""Stroboscope analysis (Sec. 5.4.3, Fig. 6.14, 6.20): segment the floating magnet in every frame,
measure its orientation and centroid, recover the apparent phase, and fit the tilt amplitude phi,
the lateral amplitude beta and the offset of the rotation centre from the centre of mass
``delta = beta / tan(phi)`` (Eq. 5.97).

Model per frame k with apparent phase ``psi_k``: tilt ``theta_k = phi sin(psi_k)`` (from the
vertical, top of the body towards +x) and centroid ``x_k = x_0 - delta tan(theta_k)``. A rolling
shutter shears the body in proportion to its lateral velocity, which adds a tilt in quadrature
with the lateral motion; taking only the tilt component in phase with ``x_k`` removes it. Motion
blur averages shapes; the soft (grey-level) mask keeps the moments unbiased.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from labkit.errors import VideoError
from labkit.vision.curves import a_for_k, ellipse_from_coefficients, trochoid_from_coefficients
from labkit.vision.fit import CIRCLE_MAX_ELLIPTICITY, MAX_TROCHOID_B, trochoid_beats
from labkit.vision.frames import open_frames

MIN_BODY_AREA_PX = 30
MIN_CONTRAST = 25.0


@dataclass
class BodyPose:
    """One frame's body: centroid (px), tilt from the vertical (rad), half length (px)."""

    x: float
    y: float
    tilt_rad: float
    half_length_px: float
    area_px: float


def segment_body(frame: np.ndarray) -> BodyPose | None:
    """Find the body (dark or bright on a contrasting background) and measure it by grey-level
    moments of a soft mask. Returns None when no body is visible."""
    gray = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    blur = cv2.GaussianBlur(gray, (5, 5), 0)
    t, _ = cv2.threshold(blur, 0, 255, cv2.THRESH_BINARY | cv2.THRESH_OTSU)
    lo, hi = blur[blur <= t], blur[blur > t]
    if lo.size == 0 or hi.size == 0 or float(hi.mean()) - float(lo.mean()) < MIN_CONTRAST:
        return None
    lo_level, hi_level = float(np.median(lo)), float(np.median(hi))
    best = None
    for dark in (True, False):
        mask = ((blur <= t) if dark else (blur > t)).astype(np.uint8)
        n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
        h, w = mask.shape
        for i in range(1, n):
            x, y, bw, bh, area = stats[i]
            touches = x == 0 or y == 0 or x + bw == w or y + bh == h
            if area < MIN_BODY_AREA_PX or touches or area > 0.5 * h * w:
                continue
            if best is None or area > best[0]:
                best = (area, dark, labels == i, (x, y, bw, bh))
    if best is None:
        return None
    _, dark, region, (x, y, bw, bh) = best
    pad = 4
    x0, y0 = max(0, x - pad), max(0, y - pad)
    x1, y1 = min(gray.shape[1], x + bw + pad), min(gray.shape[0], y + bh + pad)
    g = gray[y0:y1, x0:x1].astype(np.float32)
    near = cv2.dilate(region[y0:y1, x0:x1].astype(np.uint8), np.ones((2 * pad + 1, 2 * pad + 1), np.uint8))
    body_level, bg_level = (lo_level, hi_level) if dark else (hi_level, lo_level)
    soft = np.clip((g - bg_level) / (body_level - bg_level), 0, 1) * near
    m = cv2.moments(soft)
    if m["m00"] <= 0:
        return None
    cx, cy = m["m10"] / m["m00"], m["m01"] / m["m00"]
    mu20, mu02, mu11 = m["mu20"] / m["m00"], m["mu02"] / m["m00"], m["mu11"] / m["m00"]
    alpha = 0.5 * math.atan2(2 * mu11, mu20 - mu02)  # major axis from +x towards +y (down)
    tilt = math.atan2(math.cos(alpha), -math.sin(alpha))  # from image-up, towards +x
    if tilt > math.pi / 2:
        tilt -= math.pi
    elif tilt <= -math.pi / 2:
        tilt += math.pi
    lam1 = 0.5 * (mu20 + mu02) + math.sqrt(0.25 * (mu20 - mu02) ** 2 + mu11 ** 2)
    return BodyPose(x0 + cx, y0 + cy, tilt, math.sqrt(3 * lam1), float(m["m00"]))


def apparent_cycles_per_frame(rotor_hz: float, strobe_hz: float) -> float:
    """Alias of the rotor frequency sampled by the strobe, in cycles per flash, in [-0.5, 0.5)."""
    r = rotor_hz / strobe_hz
    return r - math.floor(r + 0.5)


def _sin_fit(psi: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, float]:
    m = np.column_stack([np.ones_like(psi), np.sin(psi), np.cos(psi)])
    coef, *_ = np.linalg.lstsq(m, y, rcond=None)
    resid = y - m @ coef
    return coef, float(np.sqrt(np.mean(resid ** 2)))


def estimate_cycles_per_frame(k: np.ndarray, series: list[np.ndarray]) -> float:
    """Apparent frequency (cycles per frame, in (0, 0.5]) that best explains the series as
    sinusoids: the maximum of the summed normalised least-squares periodogram, refined locally."""
    def power(f: float) -> float:
        total = 0.0
        for y in series:
            var = float(np.var(y))
            if var <= 0:
                continue
            _, rms = _sin_fit(2 * math.pi * f * k, y)
            total += 1 - rms ** 2 / var
        return total

    n = max(8, int(k.max() - k.min() + 1))
    grid = np.linspace(0.5 / n, 0.5, 8 * n)
    best = float(grid[int(np.argmax([power(f) for f in grid]))])
    step = grid[1] - grid[0]
    a, b = max(1e-6, best - step), min(0.5, best + step)
    for _ in range(40):  # golden-section refinement around the grid maximum
        c1, c2 = b - 0.618 * (b - a), a + 0.618 * (b - a)
        if power(c1) > power(c2):
            b = c2
        else:
            a = c1
    return 0.5 * (a + b)


def analyse_strobe(path: str, rotor_hz: float | None = None, strobe_hz: float | None = None,
                   apparent_hz: float | None = None, mm_per_px: float | None = None,
                   point: str = "tip", on_frame=None) -> dict:
    """Analyse a stroboscope video; returns the ``labkit analyse strobe`` JSON.

    Phase comes from ``rotor_hz`` and ``strobe_hz`` (one flash per frame), from ``apparent_hz``
    (at the file's frame rate), or from the signal itself. ``point``: the body point whose
    trajectory is classified, ``tip`` (top end of the body axis), ``bottom`` or ``centroid``.
    ``on_frame(index, t_s, bgr)`` is called for every frame (live streams hook in here).
    """
    source = open_frames(path)
    fps = source.fps or (strobe_hz or 0.0)
    poses: list[BodyPose | None] = []
    levels = []
    for index, frame in source.frames():
        if on_frame is not None:
            on_frame(index, index / fps if fps else 0.0, frame)
        levels.append((int(frame.min()), int(frame.max())))
        poses.append(segment_body(frame))
    lo, hi = min(v[0] for v in levels), max(v[1] for v in levels)
    if hi < 16:
        raise VideoError(source.path, f"all frames are black (brightest grey level {hi})")
    if lo > 245:
        raise VideoError(source.path, "all frames are white (saturated); reduce exposure or gain")
    idx = np.array([i for i, p in enumerate(poses) if p is not None])
    if len(idx) < 6:
        raise VideoError(source.path, f"no body found: a contrasting body was segmented in {len(idx)} of "
                                      f"{len(poses)} frames (need 6); check lighting and framing")
    x = np.array([poses[i].x for i in idx])
    y = np.array([poses[i].y for i in idx])
    tilt = np.array([poses[i].tilt_rad for i in idx])
    half = float(np.median([poses[i].half_length_px for i in idx]))
    if rotor_hz and strobe_hz:
        cpf, phase_source = apparent_cycles_per_frame(rotor_hz, strobe_hz), "rotor and strobe frequencies"
        fps = strobe_hz
    elif apparent_hz:
        if not fps:
            raise VideoError(source.path, "the file has no frame rate; give --rotor-hz and --strobe-hz")
        cpf, phase_source = apparent_hz / fps, "apparent frequency"
    else:
        cpf = estimate_cycles_per_frame(idx.astype(float), [x - x.mean(), tilt - tilt.mean()])
        phase_source = "signal"
    k_all = np.arange(len(poses), dtype=float)
    psi = 2 * math.pi * cpf * idx
    cx, rms_x = _sin_fit(psi, x)
    ct, rms_t = _sin_fit(psi, tilt)
    beta = float(math.hypot(cx[1], cx[2]))
    if beta > 3 * rms_x / math.sqrt(len(idx)) + 1e-9:
        e = np.array([cx[1], cx[2]]) / beta
        in_phase = float(ct[1:] @ e)
        quad = float(ct[1] * -e[1] + ct[2] * e[0])
        phi = abs(in_phase)
        offset = math.atan2(cx[2], cx[1]) + (math.pi if in_phase < 0 else 0.0)
        # x = x0 - delta tan(theta): x in antiphase with the tilt means the centre is towards the top
        direction = "towards body top" if in_phase < 0 else "towards body bottom"
    else:
        phi, quad = float(math.hypot(ct[1], ct[2])), 0.0
        offset, direction = math.atan2(ct[2], ct[1]), None
    delta = beta / math.tan(phi) if phi > 0 else None
    phases = [float((2 * math.pi * cpf * k + offset) % (2 * math.pi)) for k in k_all]
    sign = {"tip": 1.0, "bottom": -1.0, "centroid": 0.0}[point]
    px = x + sign * half * np.sin(tilt)
    py = y - sign * half * np.cos(tilt)
    if len(idx) >= 8:
        point_pattern = phase_pattern(np.column_stack([px, py]), np.array(phases)[idx])
    else:
        point_pattern = {"type": "none", "reason": f"only {len(idx)} frames with a body"}
    out = {"source": source.path, "frames": len(poses), "fps": fps, "apparent_hz": abs(cpf) * fps,
           "tilt_amplitude_rad": phi, "lateral_amplitude_px": beta, "rc_offset_px": delta,
           "phase_per_frame": phases, "point_pattern": point_pattern,
           "rc_offset_direction": direction, "phase_source": phase_source,
           "quality": {"frames_with_body": len(idx), "body_half_length_px": half,
                       "tilt_quadrature_rad": quad, "rms_residual_x_px": rms_x,
                       "rms_residual_tilt_rad": rms_t,
                       "point": point, "truncated": source.truncated}}
    if mm_per_px:
        out["lateral_amplitude_mm"] = beta * mm_per_px
        out["rc_offset_mm"] = None if delta is None else delta * mm_per_px
    return out


def phase_pattern(points: np.ndarray, phases: np.ndarray) -> dict:
    """Classify a body point's trajectory with known phase per sample: least squares of
    ``c + A e^{i s psi} + B e^{i s k psi}`` (s = +-1, the sense of rotation) for the ellipse
    (k = -1) and the trochoids of Eq. 6.38 (epitrochoid k = 2..7, hypotrochoid k = -2..-6); the
    ellipse wins unless :func:`labkit.vision.fit.trochoid_beats` it. Same JSON layout as
    the laser pattern."""
    z = points[:, 0] + 1j * points[:, 1]
    fits = []
    for k in [-1, *range(2, 8), *range(-2, -7, -1)]:
        for s in (1, -1):
            m = np.column_stack([np.ones_like(z), np.exp(1j * s * phases), np.exp(1j * s * k * phases)])
            coef, *_ = np.linalg.lstsq(m, z, rcond=None)
            rms = float(np.sqrt(np.mean(np.abs(z - m @ coef) ** 2)))
            if k != -1 and abs(coef[2]) > MAX_TROCHOID_B * abs(coef[1]):
                rms = math.inf
            fits.append((rms, k, s, coef))
    ellipse = min((f for f in fits if f[1] == -1), key=lambda f: f[0])
    best = min(fits, key=lambda f: f[0])
    if best[1] == -1 or not trochoid_beats(best[0], abs(best[3][2]), ellipse[0]):
        best = ellipse
    rms, k, s, (c, a, b) = best
    # s = -1 is the same curve traversed backwards: c + A e^{-it} + B e^{-ikt} = c + A e^{it'} ...
    # with t' = -t, so the coefficients describe the point set unchanged.
    center = [float(c.real), float(c.imag)]
    if k == -1:
        p = ellipse_from_coefficients(c, a, b)
        major, minor = p.semi_axes
        ell = 1 - minor / major if major > 0 else 0.0
        kind = "circle" if ell < CIRCLE_MAX_ELLIPTICITY else "ellipse"
        return {"type": kind, "center_px": center, "semi_axes_px": [major, minor],
                "rotation_deg": math.degrees(p.rotation_rad), "ellipticity": ell, "loops": 1,
                "trochoid": None, "rms_residual_px": rms}
    p = trochoid_from_coefficients(c, a, b, k)
    extent = [p.scale * (1 + p.b), p.scale * abs(1 - p.b)]
    return {"type": p.kind, "center_px": center, "semi_axes_px": extent,
            "rotation_deg": math.degrees(p.rotation_rad), "ellipticity": None, "loops": p.loops,
            "trochoid": {"a": a_for_k(k), "b": p.b, "scale_px": p.scale,
                         "rotation_deg": math.degrees(p.rotation_rad)},
            "rms_residual_px": rms}
