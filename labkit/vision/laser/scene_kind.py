"""Is this a laser trace at all? (issue 27: a stroboscope clip given to ``labkit analyse laser``
gave a pattern with verdict ``doubtful`` and exit 0.)

A laser trace is a thin bright line on a dark screen. A stroboscope clip is a body: dark before
a lit background (the usual set-up), or lit before a dark one. Two measures on the clip's
accumulated frames (each pixel's brightest value, :func:`labkit.vision.laser.analyse.accumulate`), the
light being what is brighter than the middle of the black level and the brightest level
(99.9th percentile):

* **lit share**: the share of the frame that is light. At most 6.2 % for the shipped and
  synthetic laser clips (room light included), 99.8 % for stroboscope clips on a lit
  background. Over :data:`MAX_LIT_SHARE`: a lit scene.
* **thickness**: twice the light's area over its edge (pixels of the light next to dark): the
  width of a line, the size of a filled shape. In trace line widths (the analysis' own
  ``line_width_px``): 0.5-1.7 for the laser clips, 4.4 for a lit body on a dark background
  (``labkit synth strobe --level hard``). Over :data:`MAX_THICKNESS_WIDTHS`: a filled body.

Either fails the laser verdict with a message naming the strobe analysis. **Limit:** a body
that is only a few line widths wide in the picture (filmed from far away) and does not swing is
as thick as a line: it is not told from a trace.
"""

from __future__ import annotations

import cv2
import numpy as np

from labkit.vision.shared.verdict import Verdict

MAX_LIT_SHARE = 0.5
MAX_THICKNESS_WIDTHS = 3.0


def light_mask(chunk_images: list[np.ndarray], black: float) -> np.ndarray:
    """The light of the whole clip (module docstring) as a 0/1 mask."""
    img = chunk_images[0].copy()
    for image in chunk_images[1:]:
        cv2.max(img, image, dst=img)
    if img.ndim == 3:
        img = cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
    bright = float(np.percentile(img, 99.9))
    return (img > (black + bright) / 2).astype(np.uint8)


def scene_measures(chunk_images: list[np.ndarray], black: float) -> tuple[float, float]:
    """``(lit share, thickness in px)`` of the clip's light."""
    mask = light_mask(chunk_images, black)
    inner = cv2.erode(mask, np.ones((3, 3), np.uint8), borderType=cv2.BORDER_CONSTANT, borderValue=0)
    area, edge = int(mask.sum()), int(mask.sum() - inner.sum())
    return area / mask.size, 2.0 * area / max(edge, 1)


def strobe_scene_verdict(quality: dict, lit: float, thickness_px: float) -> dict:
    """``quality`` with ``lit_share`` and ``light_thickness_widths``, failed when the clip looks
    like a stroboscope clip."""
    width = quality.get("line_width_px")
    widths = thickness_px / max(float(width), 2.0) if isinstance(width, int | float) else None
    quality = {**quality, "lit_share": round(lit, 4),
               "light_thickness_widths": None if widths is None else round(widths, 2)}
    if lit > MAX_LIT_SHARE:
        why = (f"{100 * lit:.0f} % of the frame is lit (a dark body before a lit background), where a laser "
               "trace is a thin line on a dark screen")
    elif widths is not None and widths > MAX_THICKNESS_WIDTHS:
        why = (f"the light is a filled shape {thickness_px:.0f} px thick, {widths:.1f} times the trace's "
               "line width (a lit body), where a laser trace is a thin line")
    else:
        return quality
    reason = (f"this looks like a stroboscope clip, not a laser trace: {why}; analyse it with "
              "labkit analyse strobe")
    verdict = Verdict.from_json(quality)
    verdict.fail(reason, "scene")
    return {**quality, **verdict.as_json()}
