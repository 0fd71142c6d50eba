"""Camera frames in the live view of a run: each analysed burst with the trace the analysis
fitted and the trace the live fit predicts (issue 25).

A protocol that films emits a ``frames`` document (:class:`labkit.documents.FramesTaken`) per
analysed burst: the frames' bytes as the camera sent them (JPEG, logged as they are: no
re-encoding), the fitted ``pattern`` in pixels and ``pattern_at_y``, the pattern's semi-axes for
values of the figure's y. This module draws them; it knows no protocol and no geometry: the
live fit's y at the step's x, looked up in ``pattern_at_y``, is the predicted pattern.

=====================================  ======================================================
entity                                  content
=====================================  ======================================================
``/camera/<device>/image``             every frame of every burst (``time``, ``step``); on
                                       the figure's x timeline the last frame of each step
``/camera/<device>/image/trace``       the pattern the burst analysis fitted (green, labelled
                                       with the verdict and the measured y)
``/camera/<device>/image/fit``         the pattern at the live fit's y for that step (red):
                                       redrawn at every point, so each step's frame carries
                                       the newest fit on the x timeline; on ``time`` it
                                       appears when the fit changes (the fit growing)
=====================================  ======================================================

Pixel coordinates get +0.5 (rerun puts pixel centres there, OpenCV at integers).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

PIXEL_CENTRE = 0.5
TRACE_COLOUR = [60, 230, 60]
FIT_COLOUR = [240, 60, 60]
MEDIA_TYPES = {"jpeg": "image/jpeg", "png": "image/png"}


@dataclass
class CameraStep:
    """What a step's burst left for the fit overlay: its tick on the x timeline and pattern."""

    device: str
    tick: int | None
    pattern: dict[str, Any] | None
    pattern_at_y: dict[str, Any] | None
    last_payload: bytes
    fmt: str


def image_entity(device: str) -> str:
    return f"/camera/{device}/image"


def ellipse_strip(pattern: dict[str, Any], semi_axes: tuple[float, float] | None = None,
                  samples: int = 240) -> np.ndarray | None:
    """Points (N, 2) of ``pattern`` in rerun pixels (+0.5), with other semi-axes for a
    circle/ellipse when given; None for a pattern that cannot be drawn."""
    from labkit.vision.laser.overlay import pattern_curve

    if semi_axes is not None:
        if pattern.get("type") not in ("ellipse", "circle"):
            return None
        pattern = {**pattern, "type": "ellipse", "semi_axes_px": list(semi_axes)}
    curve = pattern_curve(pattern, samples)
    return None if curve is None else np.asarray(curve, dtype=float) + PIXEL_CENTRE


def semi_axes_at(table: dict[str, Any] | None, y: float) -> tuple[float, float] | None:
    """The semi-axes ``pattern_at_y`` gives for ``y`` (linear between its rows); None outside
    its range (no extrapolation) or without a table."""
    if not table or not table.get("y"):
        return None
    ys = np.asarray(table["y"], dtype=float)
    axes = np.asarray(table["semi_axes_px"], dtype=float)
    if not (math.isfinite(y) and ys.min() <= y <= ys.max()):
        return None
    order = np.argsort(ys)
    return (float(np.interp(y, ys[order], axes[order, 0])), float(np.interp(y, ys[order], axes[order, 1])))


class CameraOverlays:
    """The rerun sink's camera part: ``frames(doc)`` per burst, ``point(index, x, y)`` when the
    step's point is done, ``refit(fit)`` after each live fit."""

    def __init__(self, rec: Any, rr: Any) -> None:
        self.rec, self.rr = rec, rr
        self.devices: list[str] = []
        self.steps: dict[tuple[str, int], CameraStep] = {}
        self.timeline: str | None = None   # the figure's x timeline (None: no figure)
        self.y_label = "y"

    def frames(self, e: Any, t0: float, tick: int | None) -> bool:
        """Log a burst's frames and the fitted trace; True when the device is new (the caller
        sends a blueprint with its view)."""
        if not e.payloads:   # read back from events.jsonl: the bytes are in the frame cassette
            return False
        new = e.device not in self.devices
        if new:
            self.devices.append(e.device)
        entity = image_entity(e.device)
        media = MEDIA_TYPES.get(e.fmt, "image/jpeg")
        for t, payload in zip(e.times, e.payloads, strict=False):
            self.rec.set_time("time", duration=max(0.0, float(t) - t0))
            self.rec.log(entity, self.rr.EncodedImage(contents=payload, media_type=media))
        self.rec.log(f"{entity}/fit", self.rr.Clear(recursive=True))   # the last step's prediction
        self._trace(entity, e.pattern, e.verdict, None)
        # a retake replaces the step's first burst: the point is the retake's
        self.steps[(e.device, e.index)] = CameraStep(e.device, tick, e.pattern, e.pattern_at_y,
                                                     e.payloads[-1], e.fmt)
        return new

    def _trace(self, entity: str, pattern: dict[str, Any] | None, verdict: str, y: float | None) -> None:
        strip = ellipse_strip(pattern) if pattern else None
        if strip is None:
            self.rec.log(f"{entity}/trace", self.rr.Clear(recursive=True))
            return
        label = f"fitted trace: {verdict or '?'}" + (f", {self.y_label} = {y:.4g}" if y is not None else "")
        for path, shape in self._shapes(strip, label, TRACE_COLOUR, top=True).items():
            self.rec.log(f"{entity}/trace{path}", shape)

    def _shapes(self, strip: np.ndarray, label: str, colour: list[int], top: bool) -> dict[str, Any]:
        """The curve (thin and on top for the trace, wide beneath for the fit, so both show where
        they coincide) and its label above (trace) or below (fit) the curve."""
        end = strip[int(np.argmin(strip[:, 1]))] if top else strip[int(np.argmax(strip[:, 1]))]
        at = end + (0.0, -6.0 if top else 6.0)
        return {"": self.rr.LineStrips2D([strip], colors=[colour], radii=[0.5 if top else 1.4],
                                         draw_order=3.0 if top else 2.0),
                "/label": self.rr.Points2D([at], colors=[colour], radii=[0.01], labels=[label],
                                           show_labels=True, draw_order=4.0)}

    def _at_tick(self, tick: int) -> None:
        """Log on the x timeline only (the sink sets ``time`` and ``step`` again at its next event)."""
        assert self.timeline is not None
        self.rec.reset_time()
        self.rec.set_time(self.timeline, sequence=tick)

    def point(self, index: int, y: float, verdict: str = "") -> None:
        """Step ``index`` is a point: its last frame and fitted trace on the x timeline."""
        if self.timeline is None:
            return
        for device in self.devices:
            step = self.steps.get((device, index))
            if step is None or step.tick is None:
                continue
            entity = image_entity(device)
            self._at_tick(step.tick)
            self.rec.log(entity, self.rr.EncodedImage(contents=step.last_payload,
                                                      media_type=MEDIA_TYPES.get(step.fmt, "image/jpeg")))
            self._trace(entity, step.pattern, verdict, y)

    def refit(self, fit: Any, x_of: dict[int, float], now: float) -> None:
        """The pattern at the live fit's y of every filmed step (x from ``x_of``: step -> x): on
        ``time`` at ``now`` over the newest burst, and at each step's tick on the x timeline."""
        newest = {d: max(i for (dev, i) in self.steps if dev == d) for d in self.devices}
        shapes = {}
        for (device, index), step in sorted(self.steps.items()):
            x = x_of.get(index)
            y_fit = float(fit.curve(np.asarray([x]))[0][0]) if x is not None else math.nan
            axes = semi_axes_at(step.pattern_at_y, y_fit)
            strip = ellipse_strip(step.pattern, axes) if axes is not None and step.pattern else None
            if strip is not None:
                label = f"live fit after {fit.n} points: {self.y_label} = {y_fit:.4g}"
                shapes[(device, index)] = self._shapes(strip, label, FIT_COLOUR, top=False)
        for device, index in newest.items():
            self.rec.reset_time()   # on ``time`` only (not at the tick a point() just used)
            self.rec.set_time("time", duration=now)
            for path, shape in shapes.get((device, index), {}).items():
                self.rec.log(f"{image_entity(device)}/fit{path}", shape)
        for (device, index), parts in shapes.items():
            tick = self.steps[(device, index)].tick
            if self.timeline is not None and tick is not None:
                self._at_tick(tick)
                for path, shape in parts.items():
                    self.rec.log(f"{image_entity(device)}/fit{path}", shape)
