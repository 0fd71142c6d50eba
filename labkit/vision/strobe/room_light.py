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
alone; its coverage is linear in intensity, so :func:`labkit.vision.strobe.body.linear_moments`
measures it without the bias a ghost gives any threshold or mask. The swing the ghost is made
with comes from the previous measurement, so :func:`labkit.vision.strobe.analyse.analyse_strobe`
repeats the two until the tilt settles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from labkit.vision.shared.frames import open_frames
from labkit.vision.strobe.body import FLAT_LEVEL, BodyPose, measure_flat
from labkit.vision.strobe.room_light_fit import MAX_AMBIENT, NormalSums, fit_room_light

__all__ = ["ClipLight", "ENCODING_GAMMA", "Swing", "fit_room_light", "ghost_free_poses", "linear_darkening",
           "read_clip_light", "revolution_average", "swing_of", "GhostFit", "fit_ghosts",
           "poses_without_ghost"]

ENCODING_GAMMA = 2.2  # cameras write sRGB / Rec. 709-like grey levels: linear = (v / 255) ** 2.2
PAD_PX = 24  # margin kept around the region the body sweeps
REVOLUTION_SAMPLES = 24  # tilts per revolution in the ghost
BLUR_SIGMAS_PX = (0.5, 1.0, 2.0, 4.0, 8.0, 16.0)  # Gaussians whose mix stands for the lens blur
SILHOUETTE_LEVELS = (0.3, 0.5, 0.7, 0.9)
ZONE_LEVEL = 0.02  # pixels with this much ghost, or within ZONE_PX of the body, enter the fit
ZONE_PX = 8
ROUNDS = 4  # rounds of ghost, room light and silhouette per swing
WARM_ROUNDS = 2  # ... when the last swing's fit gives the first ghost
FIT_FRAMES = 6  # frames (evenly spread over the clip) whose pixels fit the share and the blur mix


@dataclass
class ClipLight:
    """The clip's linear darkening in the box the body sweeps: ``stack`` (frames, h, w), 1 on the
    body's core; ``row_weight`` (frames, h): the mean row light over each row's light (a row
    that saw fewer flashes has more room light in it); ``origin`` (x0, y0) of the box."""

    stack: np.ndarray
    row_weight: np.ndarray
    origin: tuple[int, int]


def linear_darkening(gray: np.ndarray, dark: bool, gamma: float = ENCODING_GAMMA,
                     box: tuple[int, int, int, int] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """A frame's linear-light darkening (a dark body; brightening for a bright one), evened out by
    row and column medians, and each row's light (its median, linear); ``gamma`` the camera's
    encoding exponent. ``box`` (x0, y0, x1, y1): only that part of both is returned (and only its
    columns' medians are taken; a row's and a column's median still run over the whole frame)."""
    if gray.dtype == np.uint8:  # the encoding curve as a table: the same numbers, no power per pixel
        lin = _linear_table(gamma)[gray]
    else:
        lin = (gray.astype(np.float32) * (1 / 255)) ** gamma
    rows = np.median(lin, axis=1, keepdims=True)
    x0, y0, x1, y1 = box or (0, 0, gray.shape[1], gray.shape[0])
    if dark:
        lin = lin[:, x0:x1] / np.maximum(rows, 1e-6)
        lin = lin / np.maximum(np.median(lin, axis=0, keepdims=True), 1e-6)
        return 1.0 - lin[y0:y1], rows[y0:y1, 0]
    lin = lin[:, x0:x1] - rows
    return (lin - np.median(lin, axis=0, keepdims=True))[y0:y1], np.ones(y1 - y0, np.float32)


def _linear_table(gamma: float) -> np.ndarray:
    """Linear light of each grey level 0..255 (float32, as computed per pixel)."""
    return (np.arange(256, dtype=np.float32) * np.float32(1 / 255)) ** np.float32(gamma)


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
    stack = stack.astype(np.float32, copy=False)
    for d in stack:  # in place, a frame at a time: memory is the stack, not three of it
        coef = (solve * d.ravel()[outside]).sum(axis=1)  # elementwise: no BLAS threads (strobe_ghost_fit)
        # sum() starts from the int 0, which numpy's stubs keep in the type; the value is an array
        d -= np.asarray(sum(float(c) * basis[:, i] for i, c in enumerate(coef))).reshape(h, w)
    return stack


def read_clip_light(path: str, poses: list[BodyPose | None], dark: bool, size: tuple[int, int],
                    gamma: float = ENCODING_GAMMA, grays: list[np.ndarray] | None = None) -> ClipLight:
    """Keep the clip's linear darkening in the box the bodies sweep (plus ``PAD_PX``); ``poses``
    (with crops) say where that is. ``grays``: the clip's grey frames when the first read kept
    them (decoded once), else the clip is read again."""
    found = [p for p in poses if p is not None]
    w, h = size
    crops = [p.measured_crop() for p in found]
    x0 = max(0, min(c.x0 for c in crops) - PAD_PX)
    y0 = max(0, min(c.y0 for c in crops) - PAD_PX)
    x1 = min(w, max(c.x0 + c.region.shape[1] for c in crops) + PAD_PX)
    y1 = min(h, max(c.y0 + c.region.shape[0] for c in crops) + PAD_PX)
    frames = np.empty((len(poses), y1 - y0, x1 - x0), np.float32)
    rows: list[np.ndarray] = []
    again = grays if grays is not None else (f for _, f in open_frames(path).frames())
    for frame in again:
        if len(rows) == len(poses):
            break
        gray = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
        frames[len(rows)], light = linear_darkening(gray, dark, gamma, (x0, y0, x1, y1))
        rows.append(light)
    zone = np.zeros((y1 - y0, x1 - x0), np.uint8)
    for c in crops:
        rh, rw = c.region.shape
        zone[c.y0 - y0:c.y0 - y0 + rh, c.x0 - x0:c.x0 - x0 + rw] |= c.region
    zone = cv2.dilate(zone, np.ones((PAD_PX + 1, PAD_PX + 1), np.uint8)) > 0
    stack = remove_smooth_background(frames[:len(rows)], zone)
    core = [float(stack[k, int(p.y) - y0, int(p.x) - x0]) for k, p in enumerate(poses[:len(stack)])
            if p is not None]
    scale = max(float(np.median(core)), 1e-6) if core else 1.0
    light = np.stack(rows)
    stack /= scale
    return ClipLight(stack, (float(np.median(light)) / np.maximum(light, 1e-6)).astype(np.float32),
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


def _gaussian(image: np.ndarray, sigma: float) -> np.ndarray:
    """``image`` blurred by a Gaussian of ``sigma`` px; wide ones (``sigma >= 8``) on a copy shrunk
    by 2 (4 from 16 px on) and scaled back by cubic interpolation: the same smooth column (a room
    light share within 0.001 of the full-size one's on tests/vision/test_strobe_ghost.py's bars)
    for a third of the work."""
    factor = 4 if sigma >= 16 else 2 if sigma >= 8 else 1
    h, w = image.shape
    if factor == 1 or min(h, w) < 4 * factor:
        return cv2.GaussianBlur(image, (0, 0), sigma)
    small = cv2.resize(image, (-(-w // factor), -(-h // factor)), interpolation=cv2.INTER_AREA)
    return cv2.resize(cv2.GaussianBlur(small, (0, 0), sigma / factor), (w, h), interpolation=cv2.INTER_CUBIC)


def _blur_basis(cover: np.ndarray) -> np.ndarray:
    """The body's silhouettes at ``SILHOUETTE_LEVELS`` of its coverage, each blurred by each of
    ``BLUR_SIGMAS_PX`` (pixels, columns): the lens's image of the body is close to a mix of these.
    One silhouette is not enough: a halo takes light from a thin body's middle, so its
    half-coverage outline is thinner than the body."""
    return np.stack([_gaussian((cover > level).astype(np.float32), s).ravel()
                     for level in SILHOUETTE_LEVELS for s in BLUR_SIGMAS_PX], axis=1)


def _mixed(basis: np.ndarray, mix: np.ndarray) -> np.ndarray:
    """``basis @ mix`` (float32) column by column: no BLAS call big enough to start its threads."""
    out = np.zeros(len(basis), np.float32)
    for column, weight in zip(basis.T, mix, strict=True):
        out += np.float32(weight) * column
    return out


def spread_frames(frames: list[int], count: int) -> list[int]:
    """At most ``count`` of ``frames``, evenly spread from the first to the last."""
    if len(frames) <= count:
        return list(frames)
    picks = np.round(np.linspace(0, len(frames) - 1, count)).astype(int)
    return [frames[i] for i in sorted(set(picks.tolist()))]


@dataclass
class GhostFit:
    """The room light's share ``alpha`` of the mean row light, and per fitted frame its ghost and
    its coverage without the ghost (the next round's edges)."""

    alpha: float
    ghosts: dict[int, np.ndarray]
    covers: dict[int, np.ndarray]
    mix: np.ndarray | None = None  # the lens's blur mix (columns of _blur_basis)

    def ghost_for(self, frame: int) -> np.ndarray:
        """The ghost of ``frame``, or of the nearest fitted frame (the ghost is the whole
        revolution: it changes between frames only as the silhouette does, a plate's as it spins)."""
        return self.ghosts[min(self.ghosts, key=lambda f: (abs(f - frame), f))]


def fit_ghosts(light: ClipLight, poses: list[BodyPose | None], swing: Swing,
               covers: dict[int, np.ndarray] | None = None, last: GhostFit | None = None) -> GhostFit:
    """Fit the room light's share and the blur mix (module docstring) on ``FIT_FRAMES`` of the
    frames with a body, spread over the clip, their normal equations accumulated frame by frame
    (:class:`labkit.vision.strobe.room_light_fit.NormalSums`). The ghost is made first from the frames
    themselves, then from the fitted blurred silhouettes (noise in a frame would otherwise be in
    its ghost too and pull ``alpha`` up). ``swing`` holds one entry per pose that is not None;
    ``covers``: the last fit's coverages, the starting edges. ``last``: the previous swing's fit,
    whose coverages and blur mix make the first ghost already (then ``WARM_ROUNDS`` rounds)."""
    if last is not None:
        covers = last.covers
    x0, y0 = light.origin
    slot = {k: j for j, k in enumerate(k for k, p in enumerate(poses) if p is not None)}  # swing's index
    fitted = spread_frames([k for k in slot if k < len(light.stack)], FIT_FRAMES)  # a 2nd read: maybe fewer
    shape = light.stack.shape[1:]
    covers_now = {k: (covers or {}).get(k, light.stack[k]) for k in fitted}
    near = np.ones((2 * ZONE_PX + 1, 2 * ZONE_PX + 1), np.uint8)
    mix, alpha, ghosts = (None if last is None else last.mix), 0.0, {}
    for _ in range(ROUNDS if mix is None else WARM_ROUNDS):
        sums = NormalSums(len(SILHOUETTE_LEVELS) * len(BLUR_SIGMAS_PX))
        for k in fitted:
            j = slot[k]
            basis = _blur_basis(covers_now[k])  # this round's fit, and the last round's fitted body
            source = light.stack[k] if mix is None else _mixed(basis, mix).reshape(shape)
            centre = (float(swing.centre[j][0] - x0), float(swing.centre[j][1] - y0))
            ghosts[k] = revolution_average(source, centre, float(swing.tilt[j]), swing.revolution)
            body = cv2.dilate((covers_now[k] > 0.5).astype(np.uint8), near) > 0
            zone = (body | (ghosts[k] > ZONE_LEVEL)).ravel()
            weight = np.broadcast_to(light.row_weight[k][:, None], shape).ravel()
            sums.add(light.stack[k].ravel()[zone], ghosts[k].ravel()[zone], weight[zone], basis[zone])
        alpha, mix = sums.solve()
        for k in fitted:
            covers_now[k] = _without_ghost(light, k, alpha, ghosts[k])
    return GhostFit(alpha, ghosts, covers_now, mix)


def _without_ghost(light: ClipLight, frame: int, alpha: float, ghost: np.ndarray) -> np.ndarray:
    """``c_k = (D_k - a h_k) / (1 - a)``, each row's share ``a`` clipped at ``MAX_AMBIENT``."""
    a = np.clip(alpha * light.row_weight[frame], 0.0, MAX_AMBIENT)[:, None]
    return (light.stack[frame] - a * ghost) / (1.0 - a)


def poses_without_ghost(light: ClipLight, poses: list[BodyPose | None],
                        fit: GhostFit) -> list[BodyPose | None]:
    """Every frame with a body measured on its coverage less the room light's ghost (a fitted
    frame's own, else the nearest fitted frame's), axes from the linear moments."""
    x0, y0 = light.origin
    result: list[BodyPose | None] = [None] * len(poses)
    for k, p in enumerate(poses[:len(light.stack)]):
        if p is None:
            continue
        cover = fit.covers[k] if k in fit.covers else _without_ghost(light, k, fit.alpha, fit.ghost_for(k))
        pose = measure_flat((FLAT_LEVEL * (1.0 - np.clip(cover, -1.0, 2.0))).astype(np.float32))
        if pose is None:
            continue
        pose.x += x0
        pose.y += y0
        pose.crop = None
        result[k] = pose.with_linear_angles()
    return result


def ghost_free_poses(light: ClipLight, poses: list[BodyPose | None], swing: Swing,
                     covers: list[np.ndarray | None] | None = None
                     ) -> tuple[list[BodyPose | None], float, list[np.ndarray | None]]:
    """The bodies measured on ``c_k`` (:func:`fit_ghosts`, :func:`poses_without_ghost`); returns
    them, the room light's share of the mean row light (``alpha``) and the coverages ``c_k`` of the
    fitted frames (None for the others)."""
    given = None if covers is None else {k: c for k, c in enumerate(covers) if c is not None}
    fit = fit_ghosts(light, poses, swing, given)
    new_covers: list[np.ndarray | None] = [fit.covers.get(k) for k in range(len(poses))]
    return poses_without_ghost(light, poses, fit), fit.alpha, new_covers
