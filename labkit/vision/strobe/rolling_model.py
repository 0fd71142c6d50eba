"""The camera as the strobe under a rolling shutter: a per-row phase model
(docs/explanation/strobe-analysis.md, *Rolling shutter with the camera as the strobe*).

Without a lamp the camera's short exposure is the strobe (Fig. 6.20). A rolling shutter starts
row ``r`` of frame ``k`` a line time ``L`` after row ``r - 1``, so each row samples the motion at
its own rotor phase

    psi(k, r) = psi_0 + 2 pi c k + omega r,    omega = 2 pi f_rot L,                  (R1)

with ``c`` the apparent cycles per frame of the phase model. At a few hundred hertz and a
readout of ~20 ms, body rows a pixel apart see the body a few degrees of phase apart: the
silhouette is a smear of most of a revolution, and no single pose describes a frame.

The model here describes each row instead. At the phase of row r the body is the rectangle of
Eq. 5.97's motion: its axis at ``alpha_0 + theta``, ``theta = phi sin psi``, its centre of mass at
``c_0 - delta tan(theta) n + eps tan(theta) u`` (``u`` the rest axis, ``n`` across it; a rotation
about the rotation centre ``c_0 + delta u + eps n``, so the fit itself finds which side of the
silhouette the centre swings across). Row r of the image is that rectangle's slice by the row
(:func:`slice_intervals`), the rows make a coverage image, the lens blurs it (a Gaussian core and
a halo, whose fraction and widths are fitted: the blur mixes neighbouring rows and so shrinks the
row-to-row swing, which the fit must know), and a cubic tone curve (gamma, contrast, polarity;
solved linearly at every step) maps coverage to grey levels. ``phi``, ``delta``, ``eps``,
``psi_0``, ``omega`` (unless the user gives the readout), the rest axis, the lens blur, the centre
with a slow drift (a tripod that wanders) and per frame the body's two half sizes (a square plate
that turns about its axis breathes) are fitted to the pixels near the body's edges in up to
``MAX_FIT_FRAMES`` frames (:func:`fit_rolling`, a bounded Levenberg-Marquardt); a linear model of
the row centres over a grid of line times starts it (:func:`initial_guess`).

The standard errors come from the fit's Jacobian, with the residual variance scaled up by
the area over which residuals are correlated (:func:`correlation_area`: lens blur, 8x8
compression blocks); a geometry whose rows run along the body carries little row-wise
information, and the errors say so.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from labkit.vision.shared.frames import open_frames
from labkit.vision.strobe.body import BodyPose, flatten_illumination

MAX_FIT_FRAMES = 14
PAD_PX = 26  # model image margin beyond the crop: the halo's reach at its widest (3 x 8.7 px)
BIN_RADIUS_PX = 30  # crops are binned so that the body's half diagonal is about this many pixels
MARGIN_PX = 10  # crop margin beyond the body's reach
BAND_OUT, BAND_IN = 6, 2  # residual pixels (binned): this far outside / inside the half-coverage edge
GRID_STEPS = 90  # line times tried by the linear start, from 0 to one frame of readout
# finite-difference step, relative to max(1, |x|): the model renders in float32, whose resolution
# on image coordinates of ~1000 px is ~1e-4 px, so steps of ~1e-8 would difference round-off
DIFF_STEP = 1e-4
MAX_ITERATIONS = 25
COST_TOL = 1e-5  # relative decrease of the cost below which the fit has settled
GLOBAL = ("phi", "delta", "eps", "psi0", "omega", "alpha0", "sigma_core", "sigma_halo", "halo_fraction",
          "cx", "cy", "x1", "x2", "y1", "y2")  # centre and its drift over the clip (quadratic)
PER_FRAME = ("half_length", "half_width")  # a square plate turning about its axis breathes


@dataclass
class Crops:
    """Flattened grey crops of the frames used: frame indices, the crop's top-left corner in the
    image (x0, y0), the crops (n, h, w) binned ``bin`` x ``bin`` (a large body needs no more
    pixels than a small one) and the residual band per crop (n, h, w) bool."""

    frames: np.ndarray
    x0: int
    y0: int
    values: np.ndarray
    band: np.ndarray
    bin: int = 1


def slice_intervals(y: np.ndarray, cx: np.ndarray, cy: np.ndarray, alpha: np.ndarray,
                    half_length: np.ndarray | float,
                    half_width: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
    """Left and right ends (x) of the slice of a rectangle by the horizontal lines at ``y``: centre
    (cx, cy), axis at ``alpha`` (from image +x towards +y), half sizes along and across it. Rows
    that miss it get ``lo > hi``. All arguments broadcast."""
    ca, sa = np.cos(alpha), np.sin(alpha)
    dy = y - cy
    big = 1e9
    with np.errstate(divide="ignore", invalid="ignore"):
        # |X ca + dy sa| <= A  and  |-X sa + dy ca| <= B, with X = x - cx
        safe_c = np.where(np.abs(ca) > 1e-12, ca, 1e-12)
        safe_s = np.where(np.abs(sa) > 1e-12, sa, 1e-12)
        a1, a2 = (-half_length - dy * sa) / safe_c, (half_length - dy * sa) / safe_c
        b1, b2 = (dy * ca - half_width) / safe_s, (dy * ca + half_width) / safe_s
    lo_a, hi_a = np.minimum(a1, a2), np.maximum(a1, a2)
    lo_b, hi_b = np.minimum(b1, b2), np.maximum(b1, b2)
    inside_a = np.abs(dy * sa) <= half_length
    inside_b = np.abs(dy * ca) <= half_width
    lo_a = np.where(np.abs(ca) > 1e-12, lo_a, np.where(inside_a, -big, big))
    hi_a = np.where(np.abs(ca) > 1e-12, hi_a, np.where(inside_a, big, -big))
    lo_b = np.where(np.abs(sa) > 1e-12, lo_b, np.where(inside_b, -big, big))
    hi_b = np.where(np.abs(sa) > 1e-12, hi_b, np.where(inside_b, big, -big))
    return cx + np.maximum(lo_a, lo_b), cx + np.minimum(hi_a, hi_b)


def drift(g: dict, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The body's rest centre per frame: ``cx + x1 tau + x2 tau^2`` (and y), tau the frame's time
    over the clip scaled to [-1, 1] (a tripod that wanders slowly)."""
    x = g["cx"] + tau * (g["x1"] + tau * g["x2"])
    y = g["cy"] + tau * (g["y1"] + tau * g["y2"])
    return x, y


def row_poses(g: dict, frames: np.ndarray, tau: np.ndarray, rows: np.ndarray, c: float):
    """Centre (x, y) and axis angle of the body at each (frame, row) by (R1) and Eq. 5.97:
    arrays (n_frames, n_rows)."""
    psi = g["psi0"] + 2 * math.pi * c * frames[:, None] + g["omega"] * rows[None, :]
    theta = g["phi"] * np.sin(psi)
    t = np.tan(theta)
    a0 = g["alpha0"]
    u = (math.cos(a0), math.sin(a0))
    n = (-u[1], u[0])
    x, y = drift(g, tau)
    cx = x[:, None] - g["delta"] * t * n[0] + g["eps"] * t * u[0]
    cy = y[:, None] - g["delta"] * t * n[1] + g["eps"] * t * u[1]
    return cx, cy, a0 + theta


def render(g: dict, half_length: np.ndarray, half_width: np.ndarray, frames: np.ndarray, tau: np.ndarray,
           c: float, crops: Crops) -> np.ndarray:
    """Model coverage images (n, h, w) of the crops (binned ``crops.bin`` x ``crops.bin``): each
    image row is the slice of the pose at that row's own time (R1), sub-sampled at every image
    row inside a binned one (at least two), then the lens blur."""
    h, w = crops.values.shape[1:]
    k = crops.bin
    pad = -(-PAD_PX // k)
    hp, wp = h + 2 * pad, w + 2 * pad
    per = max(2, k)
    # sub-rows in image pixels; each takes the time of the image row it lies in
    sub = crops.y0 + (np.arange(hp)[:, None] - pad) * k + (np.arange(per)[None, :] + 0.5) * k / per - 0.5
    rows = np.floor(sub + 0.5).ravel()
    cx, cy, alpha = row_poses(g, frames, tau, rows, c)
    lo, hi = slice_intervals(sub.ravel()[None, :], cx, cy, alpha, half_length[:, None], half_width[:, None])
    lo = lo.reshape(len(frames), hp, per).astype(np.float32)
    hi = hi.reshape(len(frames), hp, per).astype(np.float32)
    left_px = (crops.x0 + (np.arange(wp) - pad) * k - 0.5).astype(np.float32)
    cover = np.zeros((len(frames), hp, wp), np.float32)
    for j in range(per):
        left = np.maximum(lo[:, :, j, None], left_px)
        right = np.minimum(hi[:, :, j, None], left_px + k)
        cover += np.clip(right - left, 0.0, k)
    cover /= per * k
    out = np.empty((len(frames), h, w), np.float32)
    core, halo = max(g["sigma_core"] / k, 0.05), max(g["sigma_halo"] / k, 0.05)
    f = g["halo_fraction"]
    for i in range(len(frames)):
        img = (1 - f) * cv2.GaussianBlur(cover[i], (0, 0), core)
        if f > 0:
            img += f * cv2.GaussianBlur(cover[i], (0, 0), halo)
        out[i] = img[pad:pad + h, pad:pad + w]
    return out


def tone_residuals(model: np.ndarray, values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """:func:`tone_residual` of each frame, its pixels ``edges[i]:edges[i + 1]`` of the vectors
    (flicker and exposure change a frame's levels, gamma changes its contrast)."""
    out = np.empty_like(values)
    for a, b in zip(edges[:-1], edges[1:], strict=True):
        out[a:b] = tone_residual(model[a:b], values[a:b])
    return out


def tone_residual(model: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Residual of the grey levels against a cubic tone curve of the model coverage, the curve
    solved by linear least squares (gamma, contrast and polarity are unknown): normal equations
    from power sums in float64 (a 4 x 4 system; the coverage lies in [0, 1])."""
    m = model.astype(np.float64)
    powers = [np.ones_like(m), m, m * m]
    powers.append(powers[2] * m)
    sums = [float(m.size)] + [float(np.sum(powers[1] * powers[j])) for j in (0, 1, 2)] + \
        [float(np.sum(powers[2] * powers[j])) for j in (2, 3)] + [float(np.sum(powers[3] * powers[3]))]
    gram = np.array([[sums[i + j] for j in range(4)] for i in range(4)])
    rhs = np.array([float(np.sum(p * values)) for p in powers])  # not BLAS: no thread contention
    coef = np.linalg.lstsq(gram, rhs, rcond=None)[0]
    return values - (coef[0] + m * (coef[1] + m * (coef[2] + m * coef[3])))


def collect_crops(path: str, poses: list[BodyPose | None], max_frames: int = MAX_FIT_FRAMES) -> Crops:
    """Read the video again and keep flattened crops around the body in up to ``max_frames``
    frames with a body, evenly spread over the clip."""
    measured = {i: p for i, p in enumerate(poses) if p is not None}
    found = list(measured)
    pick = sorted(set(found[int(j)] for j in np.linspace(0, len(found) - 1, min(max_frames, len(found)))))
    centres = np.array([[p.x, p.y] for p in measured.values()])
    radius = float(np.median([math.sqrt(3 * (p.mu20 + p.mu02)) for p in measured.values()]))
    reach = 1.3 * radius + float(np.ptp(centres, axis=0).max()) / 2 + MARGIN_PX
    mid = np.median(centres, axis=0)
    source = open_frames(path)
    w, h = source.size
    x0, y0 = max(0, int(mid[0] - reach)), max(0, int(mid[1] - reach))
    x1, y1 = min(w, int(mid[0] + reach) + 1), min(h, int(mid[1] + reach) + 1)
    k = max(1, int(round(radius / BIN_RADIUS_PX)))
    x1, y1 = x0 + (x1 - x0) // k * k, y0 + (y1 - y0) // k * k
    crops, wanted = [], set(pick)
    for index, frame in source.frames():
        if index in wanted:
            gray = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
            crop = flatten_illumination(gray)[y0:y1, x0:x1]
            crops.append(crop.reshape(crop.shape[0] // k, k, crop.shape[1] // k, k).mean(axis=(1, 3)))
        if index >= pick[-1]:
            break
    values = np.array(crops[:len(pick)], np.float32).reshape(-1, (y1 - y0) // k, (x1 - x0) // k)
    return make_crops(np.array(pick[:len(values)]), x0, y0, values, k)


def make_crops(frames: np.ndarray, x0: int, y0: int, values: np.ndarray, k: int = 1) -> Crops:
    """:class:`Crops` of flattened grey crops (binned ``k``), with the pixels the fit reads."""
    return Crops(frames, x0, y0, values, _bands(values), k)


def _bands(values: np.ndarray) -> np.ndarray:
    """The pixels the fit reads: all within ``BAND_OUT`` (binned) pixels outside and ``BAND_IN``
    inside each crop's own half-coverage edge, and one in nine elsewhere (the far background and
    the deep interior say little of the pose but hold the tone curve's ends)."""
    bands = np.zeros(values.shape, bool)
    sparse = np.zeros(values.shape[1:], bool)
    sparse[::3, ::3] = True
    grow = np.ones((2 * BAND_OUT + 1,) * 2, np.uint8)
    shrink = np.ones((2 * BAND_IN + 1,) * 2, np.uint8)
    for i, v in enumerate(values):
        half = (_cover(v) > 0.5).astype(np.uint8)
        bands[i] = ((cv2.dilate(half, grow) > 0) & ~(cv2.erode(half, shrink) > 0)) | sparse
    return bands


def _cover(v: np.ndarray) -> np.ndarray:
    """Rough coverage of a crop: 0 at the border's median, 1 at the far extreme of the body."""
    border = np.concatenate([v[0], v[-1], v[:, 0], v[:, -1]])
    bg = float(np.median(border))
    lo, hi = np.percentile(v, [0.5, 99.5])
    body = lo if bg - lo > hi - bg else hi
    return (v - bg) / (body - bg) if body != bg else np.zeros_like(v)


@dataclass
class Start:
    """The linear start: the best line time on the grid, and the motion it implies."""

    omega: float
    phi: float
    psi0: float
    rc_point: tuple[float, float]  # rotation centre projected onto the row slices' midline
    explained: float
    explained_global: float


def row_centres(crops: Crops) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Frame index, row (image y) and centroid x of every row that cuts the body fully: rows
    whose covered width is at least half the median; and per frame the frame index and the first
    and last such rows (n, 3)."""
    ks, ys, xs, ends = [], [], [], []
    for k, v in zip(crops.frames, crops.values, strict=True):
        cover = np.clip(_cover(v), 0.0, 1.0)
        cover[cover < 0.25] = 0.0
        mass = cover.sum(axis=1)
        if not (mass > 2).any():
            continue
        keep = mass >= 0.5 * np.median(mass[mass > 2])
        cols = crops.x0 + (np.arange(v.shape[1]) + 0.5) * crops.bin - 0.5
        centre = (cover @ cols) / np.maximum(mass, 1e-9)
        rows = crops.y0 + (np.arange(v.shape[0]) + 0.5) * crops.bin - 0.5
        ks.append(np.full(keep.sum(), k))
        ys.append(rows[keep])
        xs.append(centre[keep])
        ends.append((k, rows[keep][0], rows[keep][-1]))
    if not ks:
        return np.zeros(0), np.zeros(0), np.zeros(0), np.zeros((0, 3))
    return np.concatenate(ks), np.concatenate(ys).astype(float), np.concatenate(xs), np.array(ends, float)


def initial_guess(crops: Crops, c: float, omegas: np.ndarray) -> Start:
    """Small-angle model of the row centres: a row at height y of frame k has its slice centre
    on the rest midline ``X0 + S y`` moved by ``-theta (1 + S^2) (y - y*)`` (a turn by theta about
    the rotation centre, whose projection on the midline is at y*), theta by (R1). That is linear
    in ``[per-frame 1, y, y sin, y cos, sin, cos]`` for a given omega; the omega of least residual
    on the grid ``omegas`` wins."""
    k, y, x, ends = row_centres(crops)
    frames = np.unique(k)
    onehot = (k[:, None] == frames[None, :]).astype(float)
    ym = float(y.mean())
    yr = y - ym
    still = np.column_stack([onehot, yr])  # a straight midline, no motion
    total = float(np.sum((x - still @ np.linalg.lstsq(still, x, rcond=None)[0]) ** 2))
    best: tuple[float, float, np.ndarray] | None = None
    rss_global = None
    for omega in omegas:
        psi = 2 * math.pi * c * k + omega * y
        s, co = np.sin(psi), np.cos(psi)
        design = np.column_stack([onehot, yr, yr * s, yr * co, s, co])
        coef, *_ = np.linalg.lstsq(design, x, rcond=None)
        rss = float(np.sum((x - design @ coef) ** 2))
        if omega == omegas[0]:
            rss_global = rss
        if best is None or rss < best[0]:
            best = (rss, omega, coef)
    if best is None:
        raise ValueError("initial_guess needs at least one omega on its grid, got none")
    rss, omega, coef = best
    slope, ay, by, ac, bc = coef[len(frames):]
    gain = 1 + slope ** 2
    phi = math.hypot(ay, by) / gain
    psi0 = math.atan2(-by, -ay)
    ystar = -(ac * ay + bc * by) / max(ay * ay + by * by, 1e-12)
    x_mid = float(np.mean(x - yr * slope))
    side = _side_offset(ends, c, omega, phi, psi0, slope)
    norm = math.sqrt(gain)
    rc = (x_mid + slope * ystar - side / norm, ym + ystar + side * slope / norm)
    explained = 1 - rss / total if total > 0 else 0.0
    explained_global = 1 - (rss_global or total) / total if total > 0 else 0.0
    return Start(float(omega), phi, psi0, rc, explained, explained_global)


def _side_offset(ends: np.ndarray, c: float, omega: float, phi: float, psi0: float, slope: float) -> float:
    """Offset of the rotation centre across the row slices' midline, from the body's ends: a turn
    by theta about it moves every point along the midline by theta times that offset, so the first
    and last full rows move by ``theta p m_y`` (m the midline's unit direction)."""
    if len(ends) < 6 or phi <= 0:
        return 0.0
    m_y = 1 / math.sqrt(1 + slope ** 2)
    y = np.concatenate([ends[:, 1], ends[:, 2]])
    k = np.concatenate([ends[:, 0], ends[:, 0]])
    which = np.concatenate([np.zeros(len(ends)), np.ones(len(ends))])
    theta = phi * np.sin(2 * math.pi * c * k + omega * y + psi0)
    design = np.column_stack([1 - which, which, theta * m_y])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    return float(coef[2])


@dataclass
class FitInput:
    """What :func:`fit_rolling` needs besides the crops: the phase model's apparent cycles per
    frame, the rotor frequency, frame rate and height (for the line time), the silhouette's
    major-axis angle and half sizes, its mean centre, and the readout when the user knows it."""

    cycles_per_frame: float
    rotor_hz: float
    fps: float
    height: int
    axis_rad: float
    half_sizes: tuple[float, float]
    centre: tuple[float, float]
    readout_s: float | None = None


def _omega_max(f: FitInput) -> float:
    """omega for a readout of one whole frame period."""
    return 2 * math.pi * f.rotor_hz / (f.fps * max(1, f.height - 1))


def _start_vector(f: FitInput, start: Start, n: int) -> tuple[dict, np.ndarray, np.ndarray]:
    u = np.array([math.cos(f.axis_rad), math.sin(f.axis_rad)])
    off = np.array(start.rc_point) - np.array(f.centre)
    omega = start.omega if f.readout_s is None else \
        2 * math.pi * f.rotor_hz * f.readout_s / max(1, f.height - 1)
    g = {"phi": max(start.phi, 0.02), "delta": float(off @ u), "eps": float(off @ np.array([-u[1], u[0]])),
         "psi0": start.psi0, "omega": min(max(omega, 1e-4 * _omega_max(f)), _omega_max(f)),
         "alpha0": f.axis_rad, "sigma_core": 1.2, "sigma_halo": 5.0, "halo_fraction": 0.1,
         "cx": f.centre[0], "cy": f.centre[1], "x1": 0.0, "x2": 0.0, "y1": 0.0, "y2": 0.0}
    return g, np.full(n, f.half_sizes[0]), np.full(n, f.half_sizes[1])


_BOUNDS = {"phi": (0.0, 0.8), "sigma_core": (0.3, 4.0), "sigma_halo": (2.0, PAD_PX / 3),
           "halo_fraction": (0.0, 0.6)}


def fit_rolling(crops: Crops, f: FitInput, start: Start) -> tuple[dict, np.ndarray, np.ndarray, dict]:
    """Least squares of the per-row model (module doc) to the band pixels of every crop. Returns
    the global parameters, the per-frame half sizes, their standard errors (dict) and fit
    statistics."""
    n = len(crops.frames)
    g0, a0, b0 = _start_vector(f, start, n)
    free = [k for k in GLOBAL if not (k == "omega" and f.readout_s is not None)]
    tau = (crops.frames - crops.frames.mean()) / max(1.0, float(np.ptp(crops.frames)) / 2)
    values = crops.values[crops.band].astype(np.float64)
    counts = crops.band.reshape(n, -1).sum(axis=1)
    edges = np.concatenate([[0], np.cumsum(counts)])

    def unpack(x: np.ndarray) -> tuple[dict, np.ndarray, np.ndarray]:
        g = dict(g0)
        g.update(zip(free, x[:len(free)], strict=True))
        return g, x[len(free):len(free) + n], x[len(free) + n:]

    def residual(x: np.ndarray) -> np.ndarray:
        g, a, b = unpack(x)
        model = render(g, a, b, crops.frames, tau, f.cycles_per_frame, crops)
        return tone_residuals(model[crops.band].astype(np.float64), values, edges)

    x0 = np.concatenate([[g0[k] for k in free], a0, b0])
    bounds = {**_BOUNDS, "omega": (0.0, 1.02 * _omega_max(f))}
    # the half sizes stay within half and 1.5 times the silhouette's (the band holds the model's edges)
    lo = np.array([bounds.get(k, (-np.inf, np.inf))[0] for k in free] + list(0.5 * a0) + list(0.5 * b0))
    hi = np.array([bounds.get(k, (-np.inf, np.inf))[1] for k in free] + list(1.5 * a0) + list(1.5 * b0))
    x0 = np.clip(x0, lo + 1e-6, np.where(np.isfinite(hi), hi - 1e-6, np.inf))

    def jacobian(x: np.ndarray, r0: np.ndarray) -> np.ndarray:
        return grouped_jacobian(residual, x, r0, hi, len(free), edges)

    x, fun, jac, iterations, converged = levenberg_marquardt(residual, jacobian, x0, lo, hi)
    g, a, b = unpack(x)
    resid = np.zeros(crops.values.shape, np.float64)
    resid[crops.band] = fun
    inflation = correlation_area(resid, crops.band)
    s2 = float(np.sum(fun * fun)) / max(1, len(values) - jac.shape[1]) * inflation
    cov = np.linalg.pinv(jac.T @ jac) * s2
    se = {k: float(math.sqrt(max(cov[i, i], 0.0))) for i, k in enumerate(free)}
    return g, a, b, {"se": se, "cov": cov[:len(free), :len(free)], "free": free, "inflation": inflation,
                     "rms": float(np.sqrt(np.mean(fun ** 2))), "iterations": iterations,
                     "pixels": len(values), "converged": converged}


def levenberg_marquardt(residual, jacobian, x0: np.ndarray, lo: np.ndarray, hi: np.ndarray):
    """Bounded Levenberg-Marquardt (Marquardt's diagonal scaling, steps clipped to the bounds) on
    the normal equations, which are small (parameters x parameters). Returns x, the residuals
    and Jacobian there, the iterations used and whether the cost settled (relative decrease
    below ``COST_TOL``) within ``MAX_ITERATIONS``."""
    x = x0.copy()
    fun = residual(x)
    cost = float(np.sum(fun * fun))
    damping = 1e-3
    jac = jacobian(x, fun)
    for iteration in range(1, MAX_ITERATIONS + 1):
        normal, grad = jac.T @ jac, jac.T @ fun
        scale = np.maximum(np.diag(normal), 1e-12)
        while damping < 1e10:
            step = np.linalg.solve(normal + damping * np.diag(scale), -grad)
            trial = np.clip(x + step, lo, hi)
            trial_fun = residual(trial)
            trial_cost = float(np.sum(trial_fun * trial_fun))
            if trial_cost < cost:
                break
            damping *= 4.0
        else:
            return x, fun, jac, iteration, True  # no step lowers the cost: a minimum
        settled = (cost - trial_cost) < COST_TOL * cost
        x, fun, cost, damping = trial, trial_fun, trial_cost, max(damping / 3.0, 1e-9)
        jac = jacobian(x, fun)
        if settled:
            return x, fun, jac, iteration, True
    return x, fun, jac, MAX_ITERATIONS, False


def grouped_jacobian(residual, x: np.ndarray, r0: np.ndarray, hi: np.ndarray, n_global: int,
                     edges: np.ndarray) -> np.ndarray:
    """Forward differences of ``residual`` at ``x`` (dense, residuals x parameters): one
    evaluation per global parameter, and one per kind of per-frame parameter for all frames at
    once (frame i's parameter moves frame i's pixels only, ``edges[i]:edges[i + 1]``). Steps are
    ``DIFF_STEP`` times max(1, |x|), taken downwards at an upper bound; ``r0`` = residual(x)."""
    jac = np.zeros((len(r0), len(x)))
    step = DIFF_STEP * np.maximum(1.0, np.abs(x))
    step = np.where(x + step > hi, -step, step)
    for j in range(n_global):
        moved = x.copy()
        moved[j] += step[j]
        jac[:, j] = (residual(moved) - r0) / step[j]
    n = len(edges) - 1
    for first in range(n_global, len(x), n):
        moved = x.copy()
        moved[first:first + n] += step[first:first + n]
        diff = residual(moved) - r0
        for i in range(n):
            jac[edges[i]:edges[i + 1], first + i] = diff[edges[i]:edges[i + 1]] / step[first + i]
    return jac


def correlation_area(resid: np.ndarray, mask: np.ndarray, reach: int = 3) -> float:
    """How many pixels' worth of residuals move together: the sum of the residuals'
    autocorrelation over lags up to ``reach`` px (1 for independent pixels). Lens blur and
    8 x 8 compression blocks correlate neighbours; the least-squares errors, which assume
    independent pixels, are scaled up by this."""
    r = np.where(mask, resid, 0.0)
    m = mask.astype(np.float64)
    zero = float(np.sum(r * r) / max(np.sum(m), 1.0))
    if zero <= 0:
        return 1.0
    total = 0.0
    h, w = r.shape[1:]
    for dy in range(-reach, reach + 1):
        for dx in range(-reach, reach + 1):
            a = r[:, max(0, dy):h + min(0, dy), max(0, dx):w + min(0, dx)]
            b = r[:, max(0, -dy):h + min(0, -dy), max(0, -dx):w + min(0, -dx)]
            both = m[:, max(0, dy):h + min(0, dy), max(0, dx):w + min(0, dx)] * \
                m[:, max(0, -dy):h + min(0, -dy), max(0, -dx):w + min(0, -dx)]
            total += float(np.sum(a * b) / max(np.sum(both), 1.0)) / zero
    return max(1.0, total)
