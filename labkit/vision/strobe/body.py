"""The floating body in one stroboscope frame, and its orientation over a clip
(docs/explanation/strobe-analysis.md, *Stroboscope*).

Per frame (:func:`measure_body`): the lamp's banding and gradients are evened out by row and
column medians; the body is the largest blob of Otsu's dark or bright class that does not touch
the border; it is measured by moments of a soft mask whose ramp runs from 40 % to 60 % of the
body's contrast against a ring around it. That ramp keeps edges unbiased (a symmetric edge profile
keeps its centre) while a flash shadow under 40 % of the contrast does not pull the moments (room
light's ghost of the revolution is taken out in linear light before the body is measured again,
see :mod:`labkit.vision.strobe.room_light`). The axis angle comes two
ways: from the second moments (2-fold, for elongated bodies) and four-fold (the sides of a cube's
square silhouette: the fourth-order complex moment ``sum w (z - z_c)^4``, which is
``-|c| e^{4 i alpha}`` for a square at angle alpha), so a square body has an orientation too.
Each pose also carries the same angles from moments linear in intensity
(:func:`linear_moments`, blur-invariant), which a clip without a ghost uses instead.

Over the clip (:func:`orient_clip`): the rest axis is the body's own mean orientation (circular
mean of the n-fold angles, n = 2 or 4), so the tilt ``theta_k = alpha_k - alpha_rest`` (wrapped
to ``(-pi/n, pi/n]``) and the lateral position across the rest axis do not depend on whether the
rotor axis is vertical, horizontal (Fig. 5.19) or rolled in the image.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import cv2
import numpy as np

MIN_BODY_AREA_PX = 30
MIN_CONTRAST = 25.0
RAMP = (0.4, 0.6)  # soft-mask ramp, fraction of the body's contrast
FLAT_LEVEL = 200.0  # background of a dark-body frame after flattening
DARK_FLAT_LEVEL = 20.0  # background of a bright-body frame after flattening
SQUARE_ANISOTROPY = 0.25  # below it the silhouette is too square for a 2-fold moment axis
LINEAR_WINDOW_PX = 3  # the linear moments' window: the half-coverage region grown by this much
#: a midline straying more than this (px rms) is a bent silhouette: a rolling shutter (rolling_analysis)
MAX_BEND_PX = 0.4  # midline of a straight body: measured <= 0.27 px with noise, blur and compression


@dataclass
class BodyPose:
    """One frame's body: centroid (px), axis angles, second moments, area.

    ``angle2_rad``: major axis from image +x towards +y (down), mod pi (moments);
    ``angle4_rad``: side direction mod pi/2 (fourth-order moment); ``anisotropy``: (l1 - l2)/(l1 + l2)
    of the second moments (0 for a square, -> 1 for a needle)."""

    x: float
    y: float
    angle2_rad: float
    angle4_rad: float
    anisotropy: float
    mu20: float
    mu02: float
    mu11: float
    area_px: float
    contrast: float
    bend_px: float = 0.0
    crop: BodyCrop | None = field(default=None, repr=False, compare=False)
    linear: tuple[float, float, float] | None = None  # angle2, angle4, anisotropy (see linear_moments)

    def measured_crop(self) -> BodyCrop:
        """The crop :func:`measure_flat` kept; the ghost measures read it before the clip's light
        drops it (a pose without one cannot say where its body was)."""
        if self.crop is None:
            raise ValueError(f"body pose at ({self.x:.1f}, {self.y:.1f}) px has no crop: only poses from "
                             "measure_flat carry one, and the clip's light drops it once read")
        return self.crop

    def with_linear_angles(self) -> BodyPose:
        """This pose with the axis angles of :func:`linear_moments` (for clips without a ghost)."""
        if self.linear is None:
            return self
        angle2, angle4, anisotropy = self.linear
        return replace(self, angle2_rad=angle2, angle4_rad=angle4, anisotropy=anisotropy, linear=None)

    def half_length_along(self, angle_rad: float) -> float:
        """Half length of the body along direction ``angle_rad`` (uniform bar: L^2/12 second moment)."""
        c, s = math.cos(angle_rad), math.sin(angle_rad)
        return math.sqrt(max(0.0, 3 * (c * c * self.mu20 + 2 * c * s * self.mu11 + s * s * self.mu02)))


def flatten_illumination(gray: np.ndarray) -> np.ndarray:
    """Even out row and column brightness (rolling-shutter flash bands, lamp gradients): each row,
    then each column, brought to the frame's median. The body covers a minority of each row and
    column, so the medians are background. On a bright background (a dark body) the light is a
    gain and is divided out, the background brought to ``FLAT_LEVEL`` in every frame (flicker and
    the number of flashes per exposure drop out); on a dark background (a lit body) the medians
    are too near zero to divide by and are subtracted (background at ``DARK_FLAT_LEVEL``)."""
    g = gray.astype(np.float32)
    level = float(np.median(g))
    if level > 0.5 * (float(g.min()) + float(g.max())):
        g = g + 1.0
        g *= FLAT_LEVEL / np.maximum(np.median(g, axis=1, keepdims=True), 1.0)
        g *= FLAT_LEVEL / np.maximum(np.median(g, axis=0, keepdims=True), 1.0)
        return g
    g -= np.median(g, axis=1, keepdims=True)
    g -= np.median(g, axis=0, keepdims=True) - DARK_FLAT_LEVEL
    return g


def _largest_blob(blur: np.ndarray, t: float):
    h, w = blur.shape
    best = None
    for dark in (True, False):
        mask = ((blur <= t) if dark else (blur > t)).astype(np.uint8)
        n, labels, stats, _ = cv2.connectedComponentsWithStats(mask, connectivity=8)
        for i in range(1, n):
            x, y, bw, bh, area = stats[i]
            touches = x == 0 or y == 0 or x + bw == w or y + bh == h
            if area < MIN_BODY_AREA_PX or touches or area > 0.5 * h * w:
                continue
            if best is None or area > best[0]:
                best = (area, dark, labels == i, (x, y, bw, bh))
    return best


@dataclass
class BodyCrop:
    """Where the body is in a frame and its levels, for the clip's ghost measures
    (:func:`labkit.vision.strobe.analyse.ghost_fraction`,
    :func:`labkit.vision.strobe.room_light.read_clip_light`)."""

    x0: int
    y0: int
    region: np.ndarray  # uint8 blob mask
    dark: bool
    body_level: float
    bg_level: float


def _pose_from_cover(cover: np.ndarray, near: np.ndarray, x0: int, y0: int, contrast: float,
                     crop: BodyCrop) -> BodyPose | None:
    soft = np.clip((cover - RAMP[0]) / (RAMP[1] - RAMP[0]), 0, 1).astype(np.float32) * near
    m = cv2.moments(soft)
    if m["m00"] <= 0:
        return None
    mu20, mu02, mu11 = m["mu20"] / m["m00"], m["mu02"] / m["m00"], m["mu11"] / m["m00"]
    cx, cy = m["m10"] / m["m00"], m["m01"] / m["m00"]
    yy, xx = np.mgrid[0:soft.shape[0], 0:soft.shape[1]]
    angle2, angle4, anisotropy = _axis_angles(soft, m, xx - cx, yy - cy)
    side = angle2 if anisotropy >= SQUARE_ANISOTROPY else angle4  # a square has no major axis
    pose = BodyPose(x0 + cx, y0 + cy, angle2, angle4, anisotropy, mu20, mu02, mu11, float(m["m00"]), contrast,
                    bend_px=_bend(soft, xx - cx, yy - cy, side), linear=linear_moments(cover, near))
    pose.crop = crop
    return pose


def _axis_angles(w: np.ndarray, m: dict, dx: np.ndarray, dy: np.ndarray) -> tuple[float, float, float]:
    """2-fold axis angle, 4-fold side angle and anisotropy of the weights ``w`` with moments ``m``."""
    mu20, mu02, mu11 = m["mu20"] / m["m00"], m["mu02"] / m["m00"], m["mu11"] / m["m00"]
    spread = math.hypot(0.5 * (mu20 - mu02), mu11)
    anisotropy = 2 * spread / (mu20 + mu02) if mu20 + mu02 > 0 else 0.0
    z4 = np.sum(w * (dx + 1j * dy) ** 4)  # a square's is -|c| e^{4i alpha}
    return 0.5 * math.atan2(2 * mu11, mu20 - mu02), 0.25 * float(np.angle(-z4)), anisotropy


def linear_moments(cover: np.ndarray, near: np.ndarray) -> tuple[float, float, float] | None:
    """Axis angles and anisotropy from moments linear in intensity: the coverage itself (the frame
    less its background, over the body's contrast), unclipped, in a window around the
    half-coverage region. A symmetric lens blur adds its variance to both principal second
    moments and leaves their axes, and the fourth-order side angle, where they were; the blurred
    image is smooth, so pixel sums sample it without the bias that a mask's steep edge (the soft
    ramp) gets at a small body's rounded corners. A ghost or shadow inside the window pulls these
    moments, so :func:`labkit.vision.strobe.analyse._read_poses` uses them only for clips without a
    measurable ghost. None when the window holds no weight."""
    half = ((cover > 0.5) & (near > 0)).astype(np.uint8)
    size = 2 * LINEAR_WINDOW_PX + 1
    w = (cover * cv2.dilate(half, np.ones((size, size), np.uint8))).astype(np.float32)
    m = cv2.moments(w)
    if m["m00"] <= 0:
        return None
    yy, xx = np.mgrid[0:w.shape[0], 0:w.shape[1]]
    return _axis_angles(w, m, xx - m["m10"] / m["m00"], yy - m["m01"] / m["m00"])


def _bend(soft: np.ndarray, dx: np.ndarray, dy: np.ndarray, angle: float) -> float:
    """How far the body's midline strays from a straight line (px, mass-weighted rms over 2 px
    slices along ``angle``, the middle 80 %): ~0 for a straight body; large when a rolling
    shutter shows different rows at different rotor phases and bends the silhouette."""
    c, s = math.cos(angle), math.sin(angle)
    along, across = dx * c + dy * s, -dx * s + dy * c
    w = soft.ravel()
    keep = w > 0
    a, x, w = along.ravel()[keep], across.ravel()[keep], w[keep]
    if a.size < 10:
        return 0.0
    lo, hi = np.percentile(a, [10, 90])
    bins = np.arange(lo, hi + 2.0, 2.0)
    k = np.digitize(a, bins)
    mass = np.bincount(k, w, minlength=len(bins) + 1)
    mean = np.bincount(k, w * x, minlength=len(bins) + 1) / np.maximum(mass, 1e-9)
    inside = (mass > 0) & (np.arange(len(mass)) > 0) & (np.arange(len(mass)) < len(bins))
    if inside.sum() < 3:
        return 0.0
    centres = (bins[np.arange(len(mass))[inside] - 1] + 1.0)
    coef = np.polyfit(centres, mean[inside], 1, w=np.sqrt(mass[inside]))
    resid = mean[inside] - np.polyval(coef, centres)
    return float(np.sqrt(np.average(resid ** 2, weights=mass[inside])))


def measure_body(frame: np.ndarray) -> BodyPose | None:
    """Measure the body in one frame (BGR or grey); None when no contrasting body is visible."""
    gray = frame if frame.ndim == 2 else cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY)
    return measure_flat(flatten_illumination(gray))


def measure_flat(flat: np.ndarray) -> BodyPose | None:
    """:func:`measure_body` on a frame already through :func:`flatten_illumination`."""
    blur = cv2.GaussianBlur(flat, (5, 5), 0)
    # opencv's stubs type dst as required; None (a new array) is the documented Python call
    scaled = cv2.normalize(blur, None, 0, 255, cv2.NORM_MINMAX).astype(np.uint8)  # type: ignore[call-overload]
    t8, _ = cv2.threshold(scaled, 0, 255, cv2.THRESH_BINARY | cv2.THRESH_OTSU)
    lo_v, hi_v = float(blur.min()), float(blur.max())
    best = _largest_blob(blur, lo_v + (hi_v - lo_v) * t8 / 255.0)
    if best is None:
        return None
    _, dark, region, (x, y, bw, bh) = best
    pad = 6
    x0, y0 = max(0, x - pad), max(0, y - pad)
    x1, y1 = min(flat.shape[1], x + bw + pad), min(flat.shape[0], y + bh + pad)
    g = flat[y0:y1, x0:x1]
    reg = region[y0:y1, x0:x1].astype(np.uint8)
    inner = cv2.erode(reg, np.ones((3, 3), np.uint8))
    ring = (cv2.dilate(reg, np.ones((2 * pad - 1, 2 * pad - 1), np.uint8))
            - cv2.dilate(reg, np.ones((5, 5), np.uint8)))
    body_px = g[inner > 0] if inner.any() else g[reg > 0]
    if ring.sum() == 0 or body_px.size == 0:
        return None
    bg_level, body_level = float(np.median(g[ring > 0])), float(np.median(body_px))
    contrast = abs(body_level - bg_level)
    if contrast < MIN_CONTRAST or (body_level < bg_level) != dark:  # flat is in grey levels
        return None
    cover = (g - bg_level) / (body_level - bg_level)
    near = cv2.dilate(reg, np.ones((5, 5), np.uint8))
    # the body is where coverage passes one half: Otsu's class may take in part of a flash shadow
    # and the soft mask is read only within a pixel of that half-coverage region, so a shadow or
    # ghost a little below the ramp's lower end adds nothing through noise
    half = ((cover > 0.5) & (near > 0)).astype(np.uint8)
    if half.sum() >= MIN_BODY_AREA_PX:
        reg, near = half, cv2.dilate(half, np.ones((3, 3), np.uint8))
    crop = BodyCrop(x0, y0, reg, dark, body_level, bg_level)
    return _pose_from_cover(cover, near, x0, y0, contrast, crop)


def static_light(flat: np.ndarray) -> np.ndarray:
    """The frame as the clip's static light accumulates it (3x3 mean: less noise in the max; see
    :func:`labkit.vision.strobe.analyse.ghost_fraction`)."""
    return cv2.blur(flat, (3, 3))


def _wrap(a: np.ndarray, period: float) -> np.ndarray:
    return (a + period / 2) % period - period / 2


@dataclass
class ClipOrientation:
    """The body's rest axis and the per-frame tilt and lateral position about it.

    ``axis``: unit vector of the rest axis in image coordinates, pointing at the body's "top" end
    (the end nearer image-up; +x if the axis is horizontal). ``normal``: the axis turned a quarter
    turn clockwise on screen (image-up axis -> normal +x); positive tilt turns the top towards
    ``normal``. ``symmetry``: 2 (elongated) or 4 (square silhouette: tilt is mod pi/2).
    ``lateral_other_px``: the centroid along ``axis`` (what would be lateral if the magnet axis
    were the other side of the silhouette, see :meth:`swapped`)."""

    rest_angle_rad: float
    axis: np.ndarray
    normal: np.ndarray
    symmetry: int
    tilt_rad: np.ndarray
    lateral_px: np.ndarray
    lateral_other_px: np.ndarray
    anisotropy: float
    offsets: np.ndarray  # centroids (N, 2) less their mean

    @property
    def rest_axis_deg(self) -> float:
        """Rest axis direction on screen, counter-clockwise from image +x, in [0, 180)."""
        return round(math.degrees(math.atan2(-self.axis[1], self.axis[0])), 9) % 180.0

    def swapped(self) -> ClipOrientation:
        """The same clip with the other side of the silhouette as the magnet axis: the centre of
        mass moves across the magnet axis (Eq. 5.97), and for a plate seen edge-on that is its
        short side. Tilt is unchanged (both sides turn together)."""
        return _oriented(self.rest_angle_rad + math.pi / 2, self.symmetry, self.tilt_rad,
                         self.offsets, self.anisotropy)


def _oriented(angle: float, symmetry: int, tilt: np.ndarray, offsets: np.ndarray,
              anisotropy: float) -> ClipOrientation:
    axis = np.array([math.cos(angle), math.sin(angle)])
    if axis[1] > 1e-9 or (abs(axis[1]) <= 1e-9 and axis[0] < 0):
        axis = -axis
    normal = np.array([-axis[1], axis[0]])
    return ClipOrientation(angle, axis, normal, symmetry, tilt, offsets @ normal, offsets @ axis, anisotropy,
                           offsets)


def orient_clip(poses: list[BodyPose]) -> ClipOrientation:
    """Rest axis as the circular mean of the per-frame n-fold angles (the major axis for an
    elongated body); tilt and lateral about it. Which side is the magnet axis is decided later,
    from the motion at the apparent frequency (:meth:`ClipOrientation.swapped`)."""
    anisotropy = float(np.median([p.anisotropy for p in poses]))
    symmetry = 4 if anisotropy < SQUARE_ANISOTROPY else 2
    angles = np.array([p.angle4_rad if symmetry == 4 else p.angle2_rad for p in poses])
    rest = float(np.angle(np.mean(np.exp(1j * symmetry * angles)))) / symmetry
    tilt = _wrap(angles - rest, 2 * math.pi / symmetry)
    centres = np.array([[p.x, p.y] for p in poses])
    return _oriented(rest, symmetry, tilt, centres - centres.mean(axis=0), anisotropy)
