"""Contact sheet of the independent renderer's footage (docs/img/footage-samples.jpg).

Six robustness-suite cases (labkit.footage), one tile each: a single frame and the accumulated
trace of a hard 7-loop epitrochoid clip (short arcs per frame, drifting camera, halo, flicker,
timestamp), a hard long-exposure photo with a stray reflection, a medium hypotrochoid frame, a
stroboscope frame with several flashes per exposure and a rolling shutter, and a camera-as-strobe
frame of a plate magnet whose axis lies horizontal.

    python analysis/footage_samples.py [OUT.jpg]      # default out/footage-samples.jpg
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

from labkit.footage.suite import suite_cases
from labkit.footage.suite_eval import render_case

TILE = (400, 225)


def _frames(path: Path) -> list[np.ndarray]:
    if path.suffix == ".jpg":
        return [cv2.imread(str(path))]
    cap = cv2.VideoCapture(str(path))
    frames = []
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        frames.append(frame)
    cap.release()
    return frames


def _tile(image: np.ndarray, label: str) -> np.ndarray:
    h, w = image.shape[:2]
    scale = min(TILE[0] / w, TILE[1] / h)
    small = cv2.resize(image, (int(w * scale), int(h * scale)), interpolation=cv2.INTER_AREA)
    tile = np.zeros((TILE[1], TILE[0], 3), np.uint8)
    y, x = (TILE[1] - small.shape[0]) // 2, (TILE[0] - small.shape[1]) // 2
    tile[y:y + small.shape[0], x:x + small.shape[1]] = small
    cv2.putText(tile, label, (6, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (0, 0, 0), 2, cv2.LINE_AA)
    cv2.putText(tile, label, (6, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.42, (80, 255, 80), 1, cv2.LINE_AA)
    return tile


def _find(**want) -> object:
    for case in suite_cases():
        if all(getattr(case, k) == v for k, v in want.items()):
            return case
    raise LookupError(f"no suite case with {want}")


def main(out: Path) -> None:
    epi7 = _find(family="epitrochoid", loops=7, difficulty="hard", photo=False)
    picks = [
        (epi7, "frame", "epitrochoid 7, one frame"),
        (epi7, "max", "same clip, all frames"),
        (_find(family="ellipse", difficulty="hard", photo=True), "frame", "long-exposure photo, hard"),
        (_find(family="hypotrochoid", loops=5, difficulty="medium", photo=False), "max", "hypotrochoid 5"),
        (_find(family="strobe", difficulty="hard", flashes=6.0), "frame", "strobe: 6 flashes/exposure"),
        (_find(family="strobe", difficulty="medium", flashes=0.0), "frame", "camera as strobe, rolling"),
    ]
    tiles = []
    with tempfile.TemporaryDirectory() as tmp:
        for case, mode, label in picks:
            path, _ = render_case(case, Path(tmp))
            frames = _frames(path)
            image = np.max(frames, axis=0) if mode == "max" else frames[len(frames) // 2]
            tiles.append(_tile(image, f"{label} ({case.size[0]}x{case.size[1]})"))
    sheet = np.vstack([np.hstack(tiles[i:i + 3]) for i in (0, 3)])
    out.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(out), sheet, [cv2.IMWRITE_JPEG_QUALITY, 85])
    print(f"wrote {out}")


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("out/footage-samples.jpg"))
