"""The analysis-only rule of ``cone-sweep`` (:mod:`labkit.protocols.reanalyse`): each step's
burst analysed again from the session's frame cassette (the camera's own bytes, as recorded)
by today's laser analysis (:func:`labkit.protocols.cone_sweep.burst_cone_angle`, Eq. 5.24's
cone angle from the trace's semi-axes, Sec. 5.2.3), with the step's recorded speed. The
emulated or real camera is not needed, nor the recording's timing: this is how a real-clock
camera session is checked (its frames cannot be served on the replay's clock yet)."""

from __future__ import annotations

import math
from typing import Any

from labkit.devices.camera.cassette import read_cassette
from labkit.devices.camera.frames import Frame
from labkit.protocols.cone_sweep import burst_cone_angle, burst_fps
from labkit.session import SessionRecord


class ConeBursts:
    """A cone-sweep session's frame cassette, its frames grouped by burst (``STEP.TAKE``)."""

    def __init__(self, record: SessionRecord, role: str = "camera") -> None:
        header, entries, data = read_cassette(record.path / "cassettes" / f"{role}.jsonl")
        settings = header["settings"]
        width, height = (int(v) for v in str(settings["size"]).split("x"))
        self.size = (width, height)
        self.fps: float | None = settings.get("fps")
        self.bursts: dict[str, list[Frame]] = {}
        for e in entries:
            start = int(e["offset"])
            t_device = e.get("t_device")
            self.bursts.setdefault(str(e.get("step")), []).append(Frame(
                int(e.get("seq") or 0), float(e["t_host"]), None if t_device is None else float(t_device),
                data[start:start + int(e["length"])], int(e.get("dropped_before") or 0)))

    def point(self, step: int, recorded: dict[str, Any], params: dict[str, Any]) -> dict[str, Any]:
        """The step's point with its cone angle, verdict and stderr analysed again from the burst
        the run kept (the retake when it retook one); speeds as recorded."""
        frames = self.bursts.get(f"{step}.{1 if recorded.get('retaken') else 0}", [])
        if not frames:
            return {**recorded, "cone_angle_rad": None, "verdict": "failed",
                    "reasons": [f"no frames of step {step} in the frame cassette"]}
        geometry = (self.size, float(params["screen_distance_mm"]), float(params["mm_per_px"]))
        fps = burst_fps(frames, self.fps)
        result = burst_cone_angle(frames, fps, *geometry)
        result.pop("pattern", None)
        angle = result["cone_angle_rad"]
        stderr = None
        if params.get("halves") and angle is not None and len(frames) >= 8:
            halves = [burst_cone_angle(frames[k::2], fps / 2, *geometry)["cone_angle_rad"] for k in (0, 1)]
            if None not in halves:
                stderr = abs(halves[0] - halves[1]) / 2
        return {**recorded, **result, "cone_angle_stderr_rad": stderr,
                "cone_angle_deg": math.degrees(angle) if angle is not None else None,
                "cone_angle_stderr_deg": math.degrees(stderr) if stderr is not None else None}
