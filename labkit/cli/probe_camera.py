"""``labkit probe camera --port URL``: what a camera accepted and how it delivers, as one JSON line.

Opens the camera (no motor, no run), takes one burst of ``--frames`` frames and prints: ``size``,
``fps`` (what the driver says; null for network streams, whose rate is invented), ``fps_measured``
(from the frames' trusted times), ``format`` (fourcc), ``exposure_s``, ``timestamps`` (``device``
or ``host``: which time frames carry), ``dropped`` (frames the camera lost), ``frame_bytes``
(mean JPEG size) and the backend. A camera that sends nothing within its timeout ends with one
line naming it, its URL and what it stopped doing (exit status 2).
"""

from __future__ import annotations

import json
from typing import Any

from labkit.errors import LabkitError
from labkit.io.clock import Clock


def probe_camera(url: str, frames: int, out: Any, clock: Clock) -> int:
    from labkit.devices.camera import open_camera

    if frames < 2:
        raise LabkitError("--frames must be >= 2 (the rate is measured between frames)")
    if url.lower().startswith("sim://"):
        import labkit.emulators  # noqa: F401 - the emulated camera films the shared model plant
    camera = open_camera(url, clock, name="camera")
    try:
        burst = camera.burst(frames, step="probe")
        span = burst[-1].t - burst[0].t
        s = camera.settings
        line = {"camera": url, "size": f"{s.size[0]}x{s.size[1]}", "fps": s.fps,
                "fps_measured": round((len(burst) - 1) / span, 3) if span > 0 else None,
                "format": s.fourcc, "exposure_s": s.exposure_s, "timestamps": burst[-1].trusted,
                "dropped": camera.dropped, "frames": len(burst),
                "frame_bytes": round(sum(len(f.payload) for f in burst) / len(burst)),
                "backend": s.backend, "requested": s.requested}
    finally:
        camera.close()
    print(json.dumps(line), file=out, flush=True)
    return 0
