"""Figures of docs/explanation/laser-analysis.md (laser part): loops and symmetry of Eq. 6.38's patterns, and
the ``--overlay`` picture for an ok, a doubtful and a failed result.

    python analysis/vision_doc_figures.py [OUT_DIR]      # default out/vision-doc-figures

Writes loops-symmetry.png and overlay-{ok,doubtful,failed}.png. The copies docs/explanation/laser-analysis.md
shows are committed under docs/img (small PNGs): refresh them with ``... docs/img``.
"""

from __future__ import annotations

import math
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

import cv2
import numpy as np

from labkit.synth import laser_truth, render_laser, write_clip
from labkit.synth.presets import laser_pattern, laser_preset
from labkit.vision.laser.analyse import analyse_laser, symmetry_of
from labkit.vision.laser.overlay import draw_overlay
from labkit.vision.shared.curves import Pattern, a_for_k

PANEL = 180


def _panel(kind: str, loops: int, b: float) -> np.ndarray:
    """One pattern drawn white on black with its loops and symmetry written under it."""
    img = np.zeros((PANEL + 34, PANEL, 3), np.uint8)
    scale = 0.42 * PANEL / (1 + b)
    p = Pattern(kind, (PANEL / 2, PANEL / 2), math.pi / 2, scale=scale, b=b, loops=loops)
    pts = p.points(np.linspace(0, 2 * math.pi, 3000))
    cv2.polylines(img, [np.round(pts * 16).astype(np.int32).reshape(-1, 1, 2)], True, (255, 255, 255), 1,
                  cv2.LINE_AA, 4)
    sym = symmetry_of(kind, p.k)
    lines = [f"{kind[:4]}. a={a_for_k(p.k):+.3f}", f"loops {loops}, symmetry {sym}"]
    for i, text in enumerate(lines):
        cv2.putText(img, text, (6, PANEL + 12 + 14 * i), cv2.FONT_HERSHEY_SIMPLEX, 0.38, (120, 220, 255), 1,
                    cv2.LINE_AA)
    return img


def loops_figure() -> np.ndarray:
    """Epitrochoids with 2-5 loops (top) and hypotrochoids with 3-6 loops (bottom)."""
    top = [_panel("epitrochoid", n, 0.9 if n == 2 else 0.6) for n in (2, 3, 4, 5)]
    bottom = [_panel("hypotrochoid", n, 0.6) for n in (3, 4, 5, 6)]
    return np.vstack([np.hstack(top), np.hstack(bottom)])


def _overlay(folder: Path, name: str, spec, post=None) -> np.ndarray:
    path = write_clip(folder / f"{name}.mp4", (post(f) if post else f for f in render_laser(spec)), spec.fps,
                      "mp4v", laser_truth(spec))
    traces: list[np.ndarray] = []
    result = analyse_laser(str(path), on_trace=traces.append)
    q = result.quality
    print(f"{name}: {result.pattern.type} {q.verdict} {list(q.reasons)}")
    return draw_overlay(traces[0], result)


def overlay_figures(folder: Path) -> dict[str, np.ndarray]:
    size = (640, 480)
    ok = replace(laser_preset("medium", size, seed=3), frames=45,
                 pattern=laser_pattern("epitrochoid", size, loops=5, b=0.35, rotation_deg=15))
    # short arcs of a 3-loop hypotrochoid in a short clip: a third of the pattern never lit
    doubtful = replace(laser_preset("medium", size, seed=4), frames=36, cycle_hz=9.9, exposure_s=0.006,
                       pattern=laser_pattern("hypotrochoid", size, loops=3, b=0.8, rotation_deg=30))
    circle = replace(laser_preset("easy", size, seed=5), frames=45,
                     pattern=laser_pattern("circle", size))

    def scribble(frame: np.ndarray) -> np.ndarray:  # a second, unrelated bright stroke
        out = frame.copy()
        cv2.line(out, (40, 60), (600, 90), (60, 60, 255), 4, cv2.LINE_AA)
        cv2.line(out, (600, 90), (560, 460), (60, 60, 255), 4, cv2.LINE_AA)
        return out

    return {"ok": _overlay(folder, "ok", ok), "doubtful": _overlay(folder, "doubtful", doubtful),
            "failed": _overlay(folder, "failed", circle, scribble)}


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(out / "loops-symmetry.png"), loops_figure(), [cv2.IMWRITE_PNG_COMPRESSION, 9])
    with tempfile.TemporaryDirectory() as tmp:
        for name, image in overlay_figures(Path(tmp)).items():
            small = cv2.resize(image, (480, 360), interpolation=cv2.INTER_AREA)
            cv2.imwrite(str(out / f"overlay-{name}.png"), small, [cv2.IMWRITE_PNG_COMPRESSION, 9])


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/vision-doc-figures"))
