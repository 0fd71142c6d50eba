"""Room light in a stroboscope clip, taken out in linear light (docs/explanation/strobe-analysis.md, *Room
light: the ghost of the revolution*).

Light adds in the sensor, not in the 8-bit grey levels a camera writes. The frames are taken back
to linear light (the sRGB-like encoding curve, exponent ``ENCODING_GAMMA``), evened out by rows and
columns (lamp gradients, rolling-shutter flash bands) and by a smooth surface fitted around the
body (a lamp's bright spot), and read as the body's darkening ``D_k``: 0 on the background, 1 on
the body's core. With room light a fraction ``a`` of a row's light, frame ``k`` is

    D_k = (1 - a) c_k + a h_k,

the body's own coverage in the flashes ``c_k`` plus the ghost ``h_k`` of the revolution it is
making (the fraction of that revolution each pixel is covered). The ghost is the body's own
silhouette carried through the swing of Eq. 5.97, so it is made from the frame itself: ``D_k``
turned about the rotation centre to the tilts of one revolution and averaged
(:func:`revolution_average`; a plate that spins changes its silhouette, and with it the ghost,
from frame to frame, which a mean over frames would miss). The room light is the same from
frame to frame while the flash light of a row is not (a rolling shutter sees n or n + 1 flashes
per row), so ``a`` of row r in frame k is ``alpha / L_kr`` with ``L_kr`` the row's light.
``alpha`` is fitted together with the lens blur of the body (a mix of its silhouettes at several
coverage levels, each blurred by Gaussians of several widths, :func:`_blur_basis`): the blur is
the same all round the edge, the ghost is not (large beside the part that stays covered, small
beside the tips), which is what tells the two apart. Then ``c_k = (D_k - a h_k) / (1 - a)`` is the body
alone; its coverage is linear in intensity, so :func:`labkit.vision.strobe_body.linear_moments`
measures it without the bias a ghost gives any threshold or mask. The swing the ghost is made
with comes from the previous measurement, so :func:`labkit.vision.strobe.analyse_strobe`
repeats the two until the tilt settles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from labkit.vision.frames import open_frames
from labkit.vision.strobe_body import FLAT_LEVEL, BodyPose, measure_flat

ENCODING_GAMMA = 2.2  # cameras write sRGB / Rec. 709-like grey levels: linear = (v / 255) ** 2.2
PAD_PX = 24  # margin kept around the region the body sweeps
REVOLUTION_SAMPLES = 24  # tilts per revolution in the ghost
BLUR_SIGMAS_PX = (0.5, 1.0, 2.0, 4.0, 8.0, 16.0)  # Gaussians whose mix stands for the lens blur
SILHOUETTE_LEVELS = (0.3, 0.5, 0.7, 0.9)
MAX_AMBIENT = 0.9  # a row's room-light share is clipped here (1 would leave no flash light to measure)
ZONE_LEVEL = 0.02  # pixels with this much ghost, or within ZONE_PX of the body, enter the fit
ZONE_PX = 8
ROUNDS = 4  # rounds of ghost, room light and silhouette per swing
ALPHA_TOL = 1e-5  # the lens-blur / room-light alternation stops when the share moves by less
MAX_ALTERNATIONS = 200  # ... or after this many (it converges linearly, ~25 on the suite's clips)


@dataclass
class ClipLight:
    """The clip's linear darkening in the box the body sweeps: ``stack`` (frames, h, w), 1 on the
    body's core; ``row_weight`` (frames, h): the mean row light over each row's light (a row
    that saw fewer flashes has more room light in it); ``origin`` (x0, y0) of the box."""

    stack: np.ndarray
    row_weight: np.ndarray
    origin: tuple[int, int]


def linear_darkening(gray: np.ndarray, dark: bool,
                     gamma: float = ENCODING_GAMMA) -> tuple[np.ndarray, np.ndarray]:
    """A frame's linear-light darkening (a dark body; brightening for a bright one), evened out by
    row and column medians, and each row's light (its median, linear); ``gamma`` the camera's
    encoding exponent."""
    lin = (gray.astype(np.float32) * (1 / 255)) ** gamma
    rows = np.median(lin, axis=1, keepdims=True)
    if dark:
        lin = lin / np.maximum(rows, 1e-6)
        lin = lin / np.maximum(np.median(lin, axis=0, keepdims=True), 1e-6)
        return 1.0 - lin, rows[:, 0]
    lin = lin - rows
    return lin - np.median(lin, axis=0, keepdims=True), np.ones(len(rows), np.float32)


def remove_smooth_background(stack: np.ndarray, body_zone: np.ndarray) -> np.ndarray:
    """Subtract from each frame a quadratic surface fitted to its pixels outside ``body_zone``
    (what row and column medians leave of a lamp's round bright spot)."""
    h, w = stack.shape[1:]
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    xx, yy = xx / max(w, 1), yy / max(h, 1)
    basis = np.stack([np.ones_like(xx), xx, yy, xx * xx, xx * yy, yy * yy], axis=-1).reshape(-1, 6)
    outside = ~body_zone.ravel()
    if outside.sum() < 30:
        return stack
    solve = np.linalg.pinv(basis[outside])
    smooth = [(basis @ (solve @ d.ravel()[outside])).reshape(h, w) for d in stack]
    return (stack - np.stack(smooth)).astype(np.float32)


def read_clip_light(path: str, poses: list[BodyPose | None], dark: bool, size: tuple[int, int],
                    gamma: float = ENCODING_GAMMA) -> ClipLight:
    """Read the clip again and keep its linear darkening in the box the bodies sweep (plus
    ``PAD_PX``); ``poses`` (with crops) say where that is."""
    found = [p for p in poses if p is not None]
    w, h = size
    x0 = max(0, min(p.crop.x0 for p in found) - PAD_PX)
    y0 = max(0, min(p.crop.y0 for p in found) - PAD_PX)
    x1 = min(w, max(p.crop.x0 + p.crop.region.shape[1] for p in found) + PAD_PX)
    y1 = min(h, max(p.crop.y0 + p.crop.region.shape[0] for p in found) + PAD_PX)
    frames, rows = [], []
    for _, frame in open_frames(path).frames():
        if len(frames) == len(poses):
            break
        gray = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        d, light = linear_darkening(gray, dark, gamma)
        frames.append(d[y0:y1, x0:x1])
        rows.append(light[y0:y1])
    zone = np.zeros((y1 - y0, x1 - x0), np.uint8)
    for p in found:
        c = p.crop
        rh, rw = c.region.shape
        zone[c.y0 - y0:c.y0 - y0 + rh, c.x0 - x0:c.x0 - x0 + rw] |= c.region
    zone = cv2.dilate(zone, np.ones((PAD_PX + 1, PAD_PX + 1), np.uint8)) > 0
    stack = remove_smooth_background(np.stack(frames), zone)
    core = [float(stack[k, int(p.y) - y0, int(p.x) - x0]) for k, p in enumerate(poses[:len(stack)])
            if p is not None]
    scale = max(float(np.median(core)), 1e-6) if core else 1.0
    light = np.stack(rows)
    return ClipLight(stack / scale, (float(np.median(light)) / np.maximum(light, 1e-6)).astype(np.float32),
                     (x0, y0))


def revolution_average(image: np.ndarray, centre: tuple[float, float], tilt_now: float,
                       tilts: np.ndarray) -> np.ndarray:
    """``image`` turned about ``centre`` from ``tilt_now`` to each of ``tilts`` (rad; positive
    turns the body's top towards the clip normal, clockwise on screen) and averaged."""
    h, w = image.shape
    out = np.zeros_like(image)
    for t in tilts:
        m = cv2.getRotationMatrix2D(centre, -math.degrees(t - tilt_now), 1.0)
        out += cv2.warpAffine(image, m, (w, h), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    return out / len(tilts)


@dataclass
class Swing:
    """The swing a ghost is made with: per frame with a body, the tilt (rad) and the rotation
    centre (px, in the frame); and the tilts of one revolution."""

    tilt: np.ndarray
    centre: np.ndarray
    revolution: np.ndarray


def swing_of(poses: list[BodyPose], axis: np.ndarray, tilt: np.ndarray, lateral: np.ndarray,
             fitted_tilt: np.ndarray, phi: float) -> Swing:
    """The rotation centre lies ``d`` along the body axis from the centre of mass, with
    ``lateral = -d tilt`` (Eq. 5.97 for small angles), ``d`` by least squares over the clip;
    ``fitted_tilt`` the Eq. 5.97 fit at each frame, ``phi`` its amplitude."""
    tt = float(tilt @ tilt)
    d = -float(lateral @ tilt) / tt if tt > 0 else 0.0
    c, s = np.cos(fitted_tilt), np.sin(fitted_tilt)
    axes = np.column_stack([axis[0] * c - axis[1] * s, axis[0] * s + axis[1] * c])
    com = np.array([[p.x, p.y] for p in poses])
    psi = 2 * math.pi * (np.arange(REVOLUTION_SAMPLES) + 0.5) / REVOLUTION_SAMPLES
    return Swing(np.asarray(fitted_tilt, float), com + d * axes, phi * np.sin(psi))


def _blur_basis(cover: np.ndarray) -> np.ndarray:
    """The body's silhouettes at ``SILHOUETTE_LEVELS`` of its coverage, each blurred by each of
    ``BLUR_SIGMAS_PX`` (pixels, columns): the lens's image of the body is close to a mix of these.
    One silhouette is not enough: a halo takes light from a thin body's middle, so its
    half-coverage outline is thinner than the body."""
    return np.stack([cv2.GaussianBlur((cover > level).astype(np.float32), (0, 0), s).ravel()
                     for level in SILHOUETTE_LEVELS for s in BLUR_SIGMAS_PX], axis=1)


def fit_room_light(d: np.ndarray, h: np.ndarray, weight: np.ndarray, blurred: np.ndarray
                   ) -> tuple[float, np.ndarray]:
    """``alpha`` of ``d = (1 - a) B p + a h`` with ``a = alpha * weight`` (pixels flattened;
    ``blurred`` the columns ``B`` of :func:`_blur_basis`, ``p`` the lens's mix), by alternating
    least squares between the blur ``p`` and ``alpha`` until ``alpha`` moves by less than
    ``ALPHA_TOL`` (at most ``MAX_ALTERNATIONS``); returns both.

    Everything is in float64: the columns are close to collinear, and normal equations formed in
    float32 gave answers that changed with the BLAS kernel (a room-light share of 0.75 for 0.39 on
    one CPU path). While no row's share is clipped, ``(1 - a)^2 = 1 - 2 alpha w + alpha^2 w^2``,
    so the normal equations of every alternation are a quadratic in ``alpha`` whose coefficient
    matrices are formed once (one pass over the pixels instead of one per alternation)."""
    d, h, w, b = (np.asarray(v, np.float64) for v in (d, h, weight, blurred))
    bw = b * w[:, None]
    gram = [b.T @ b, bw.T @ b, bw.T @ bw]
    rhs = [b.T @ d, bw.T @ (d + h), bw.T @ (w * h)]
    w_max = float(w.max(initial=0.0))

    def normal_equations(alpha: float) -> tuple[np.ndarray, np.ndarray]:
        if 0.0 <= alpha and alpha * w_max <= MAX_AMBIENT:  # no share clipped: the quadratic holds
            return (gram[0] - 2 * alpha * gram[1] + alpha * alpha * gram[2],
                    rhs[0] - alpha * rhs[1] + alpha * alpha * rhs[2])
        a = np.clip(alpha * w, 0.0, MAX_AMBIENT)
        m = b * (1 - a)[:, None]
        return m.T @ m, m.T @ (d - a * h)

    alpha, p = 0.0, np.zeros(b.shape[1])
    for _ in range(MAX_ALTERNATIONS):
        normal, right = normal_equations(alpha)
        p = np.linalg.solve(normal + 1e-9 * np.trace(normal) * np.eye(len(normal)), right)
        g = b @ p
        x = w * (h - g)
        xx = float(x @ x)
        alpha, before = (float(x @ (d - g)) / xx if xx > 0 else 0.0), alpha
        if abs(alpha - before) < ALPHA_TOL:
            break
    return alpha, p


def ghost_free_poses(light: ClipLight, poses: list[BodyPose | None], swing: Swing,
                     covers: list[np.ndarray | None] | None = None
                     ) -> tuple[list[BodyPose | None], float, list[np.ndarray | None]]:
    """The bodies measured on ``c_k`` (module docstring); returns them, the room light's share of
    the mean row light (``alpha``) and the coverages ``c_k`` (the next round's edges). The ghost
    is made first from the frames themselves, then from the fitted blurred silhouettes (noise in
    a frame would otherwise be in its ghost too and pull ``alpha`` up)."""
    x0, y0 = light.origin
    slot = {k: j for j, k in enumerate(k for k, p in enumerate(poses) if p is not None)}  # swing's index
    frames = [k for k in slot if k < len(light.stack)]  # a second read that ends early has fewer
    centres = [(float(cx - x0), float(cy - y0)) for cx, cy in swing.centre]
    shape = light.stack.shape[1:]
    covers_now = {k: light.stack[k] if covers is None or covers[k] is None else covers[k] for k in frames}
    weights = {k: np.broadcast_to(light.row_weight[k][:, None], shape) for k in frames}
    near = np.ones((2 * ZONE_PX + 1, 2 * ZONE_PX + 1), np.uint8)
    mix = None
    for _ in range(ROUNDS):
        ghosts, rows = {}, []
        for k in frames:
            j = slot[k]
            basis = _blur_basis(covers_now[k])  # this round's fit, and the last round's fitted body
            source = light.stack[k] if mix is None else (basis @ mix).reshape(shape).astype(np.float32)
            ghosts[k] = revolution_average(source, centres[j], float(swing.tilt[j]), swing.revolution)
            body = cv2.dilate((covers_now[k] > 0.5).astype(np.uint8), near) > 0
            zone = (body | (ghosts[k] > ZONE_LEVEL)).ravel()
            rows.append((light.stack[k].ravel()[zone], ghosts[k].ravel()[zone], weights[k].ravel()[zone],
                         basis[zone]))
        alpha, mix = fit_room_light(*(np.concatenate(column) for column in zip(*rows, strict=True)))
        for k in frames:
            a = np.clip(alpha * light.row_weight[k], 0.0, MAX_AMBIENT)[:, None]
            covers_now[k] = (light.stack[k] - a * ghosts[k]) / (1.0 - a)
    result: list[BodyPose | None] = [None] * len(poses)
    new_covers: list[np.ndarray | None] = [None] * len(poses)
    for k in frames:
        cover = covers_now[k]
        new_covers[k] = cover
        pose = measure_flat((FLAT_LEVEL * (1.0 - np.clip(cover, -1.0, 2.0))).astype(np.float32))
        if pose is None:
            continue
        pose.x += x0
        pose.y += y0
        pose.crop = None
        result[k] = pose.with_linear_angles()
    return result, alpha, new_covers
