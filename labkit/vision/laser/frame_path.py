"""Choose between the decoder's luma plane (fast) and colour frames (safe) for one clip, from a
measurement on its first frames.

Luma is 0.299 R + 0.587 G + 0.114 B, so a red laser keeps only part of its contrast there, while
the colour path scores light by the brightest channel (:func:`labkit.vision.laser.trace.brightness`).
On a dark screen that loss does not matter; on a bright or warm screen a faint trace can sink
into the noise in luma. :func:`choose_frame_path` measures the contrast-to-noise ratio (CNR) of
the accumulated first frames both ways, scored exactly as trace extraction scores light.
"""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from labkit.vision.laser.trace import brightness, contrast_to_noise

# Luma is used when its CNR is ample on its own, or when it keeps most of the colour path's CNR
# and still clears the detection threshold with margin. Measured (docs/explanation/laser-analysis.md, "Luma or
# colour"; 8 probe frames, mp4v): the red laser of the acceptance set on neutral screens keeps
# 0.59-1.5 of the colour CNR in luma at luma CNR 64-263 and fits as well as colour. A pure-red
# faint trace on a warm bright screen keeps 0.36-0.56: at luma CNR 7.2 luma loses the trace
# (no pattern, or a 17 px centre error) where colour (CNR 13-20) fits within 0.4 px.
# Trace extraction needs CNR >= 8 at every part of the pattern; the probe measures the brightest
# point, and fast arcs are about half as bright, hence the floor of 2 x 8 below AMPLE.
AMPLE_LUMA_CNR = 40.0
MIN_LUMA_SHARE = 0.6
MIN_LUMA_CNR = 16.0
PROBE_FRAMES = 8


@dataclass
class FramePathChoice:
    """The decision and the two numbers behind it (JSON ``quality``)."""

    luma: bool
    cnr_luma: float
    cnr_colour: float | None  # None: luma was ample on its own, colour was not measured

    def to_quality(self) -> dict:
        colour = None if self.cnr_colour is None else round(self.cnr_colour, 2)
        return {"frame_path": "luma" if self.luma else "colour", "cnr_luma": round(self.cnr_luma, 2),
                "cnr_colour": colour}


def luma_plane_cnr(planes: list[np.ndarray], roi: tuple[int, int, int, int] | None = None,
                   frame_px: int | None = None) -> float:
    """CNR of the per-pixel maximum of the decoder's luma planes (inside ``roi``). The planes
    are what the luma path analyses, and a CNR is a ratio, so studio-range planes (16-235) score
    like full-range grey up to rounding."""
    x, y, w, h = roi if roi is not None else (0, 0, planes[0].shape[1], planes[0].shape[0])
    luma_max = planes[0][y:y + h, x:x + w].copy()
    for plane in planes[1:]:
        cv2.max(luma_max, plane[y:y + h, x:x + w], dst=luma_max)
    return contrast_to_noise(luma_max, frame_px)


def measure_frame_path(frames: list[np.ndarray], roi: tuple[int, int, int, int] | None = None,
                       frame_px: int | None = None) -> FramePathChoice:
    """CNR of the per-pixel maximum of BGR ``frames`` (inside ``roi`` x, y, w, h) in BT.601 luma
    and in the brightest channel, and whether luma keeps enough of it."""
    x, y, w, h = roi if roi is not None else (0, 0, frames[0].shape[1], frames[0].shape[0])
    colour_max = frames[0][y:y + h, x:x + w].copy()
    luma_max = cv2.cvtColor(colour_max, cv2.COLOR_BGR2GRAY)
    for f in frames[1:]:
        part = f[y:y + h, x:x + w]
        cv2.max(colour_max, part, dst=colour_max)
        cv2.max(luma_max, cv2.cvtColor(part, cv2.COLOR_BGR2GRAY), dst=luma_max)
    cnr_colour = contrast_to_noise(brightness(colour_max), frame_px)
    cnr_luma = contrast_to_noise(luma_max, frame_px)
    keeps_enough = cnr_luma >= MIN_LUMA_SHARE * cnr_colour and cnr_luma >= MIN_LUMA_CNR
    luma = cnr_luma >= AMPLE_LUMA_CNR or keeps_enough
    return FramePathChoice(luma, cnr_luma, cnr_colour)
