"""Shrinking a frame cassette for a CI fixture: fewer frames, a crop, a smaller picture.

Each burst (frames sharing a ``step`` label) keeps every ``every``-th frame counted back from its
last, which is always kept: a replayed burst then still ends when the recorded one did, so the
run's timeline (and the serial traffic of the other devices) is unchanged;
each kept frame is cropped to ``crop`` = (x, y, w, h) px, scaled by ``scale`` and encoded once
as JPEG at ``quality``. These bytes differ from the camera's, so whatever was computed from the
original frames must be computed again from the shrunk ones (``labkit shrink`` replays the
session and stores the new results). Times, sequence numbers and ``meta`` are kept.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from labkit.devices.camera.cassette import is_fault, read_cassette, sidecar_path


@dataclass(frozen=True)
class Shrink:
    """How to shrink: keep every ``every``-th frame of a burst, crop (x, y, w, h) then scale."""

    every: int = 1
    scale: float = 1.0
    crop: tuple[int, int, int, int] | None = None
    quality: int = 75

    def check(self) -> None:
        if self.every < 1:
            raise ValueError(f"every must be >= 1, got {self.every}")
        if not 0 < self.scale <= 1:
            raise ValueError(f"scale must be in (0, 1], got {self.scale}")
        if not 20 <= self.quality <= 100:
            raise ValueError(f"quality must be in 20..100, got {self.quality}")
        if self.crop is not None and (self.crop[2] <= 0 or self.crop[3] <= 0 or min(self.crop[:2]) < 0):
            raise ValueError(f"crop must be X,Y,W,H with W, H > 0, got {self.crop}")

    def kept(self, n: int) -> int:
        """Frames a burst of ``n`` keeps."""
        return math.ceil(n / self.every)


def shrink_image(payload: bytes, how: Shrink) -> tuple[bytes, tuple[int, int]]:
    """One JPEG cropped, scaled and encoded again; (bytes, (width, height))."""
    import cv2
    import numpy as np

    img = cv2.imdecode(np.frombuffer(payload, np.uint8), cv2.IMREAD_COLOR)
    if img is None:
        raise ValueError(f"a stored frame of {len(payload)} bytes does not decode as JPEG")
    if how.crop is not None:
        x, y, w, h = how.crop
        if x + w > img.shape[1] or y + h > img.shape[0]:
            raise ValueError(f"crop {how.crop} reaches beyond the {img.shape[1]}x{img.shape[0]} frame")
        img = img[y:y + h, x:x + w]
    if how.scale != 1.0:
        size = (max(1, round(img.shape[1] * how.scale)), max(1, round(img.shape[0] * how.scale)))
        img = cv2.resize(img, size, interpolation=cv2.INTER_AREA)
    ok, buf = cv2.imencode(".jpg", img, [cv2.IMWRITE_JPEG_QUALITY, how.quality])
    if not ok:
        raise ValueError("could not encode a shrunk frame")
    return buf.tobytes(), (img.shape[1], img.shape[0])


def shrink_cassette(index: str | Path, how: Shrink) -> dict[str, Any]:
    """Rewrite the frame cassette ``index`` (and its sidecar) in place; returns sizes before/after."""
    how.check()
    p = Path(index)
    header, everything, data = read_cassette(p)
    entries = [e for e in everything if not is_fault(e)]
    faults = [e for e in everything if is_fault(e)]  # kept, each after its burst's kept frames
    before = p.stat().st_size + len(data)
    out_entries: list[dict[str, Any]] = []
    blob = bytearray()
    size = None
    counts: dict[str, int] = {}
    for e in entries:
        counts[json.dumps(e.get("step"))] = counts.get(json.dumps(e.get("step")), 0) + 1
    seen: dict[str, int] = {}
    for e in entries:
        step = json.dumps(e.get("step"))
        k = seen.get(step, 0)
        seen[step] = k + 1
        if (counts[step] - 1 - k) % how.every:
            continue
        start = int(e["offset"])
        payload, size = shrink_image(data[start:start + int(e["length"])], how)
        out_entries.append({**e, "offset": len(blob), "length": len(payload)})
        blob += payload
    settings = dict(header["settings"])
    if size is not None:
        settings["size"] = f"{size[0]}x{size[1]}"
    header = {**header, "settings": settings,
              "shrunk": {"every": how.every, "scale": how.scale, "crop": list(how.crop) if how.crop else None,
                         "quality": how.quality, "frames_before": len(entries)}}
    for fault in faults:
        after = [k for k, e in enumerate(out_entries) if e.get("step") == fault.get("step")]
        out_entries.insert(after[-1] + 1 if after else len(out_entries), fault)
    sidecar_path(p).write_bytes(bytes(blob))
    p.write_text("".join(json.dumps(x) + "\n" for x in [header, *out_entries]), encoding="utf-8")
    return {"cassette": str(p), "frames": [len(entries), len(out_entries) - len(faults)],
            "bytes": [before, p.stat().st_size + len(blob)]}
