"""A camera that stops sending mid-burst during a run: the step ends with one line naming the
camera, its URL and what it stopped doing, within the URL's timeout, and the rotor is stopped
(the run's rules for device faults). Real clock: motor and tachometer are in-process emulators,
the camera an MJPEG stream on a loopback server that falls silent 0.3 s into the first burst."""

from __future__ import annotations

import threading
import time

from labkit.protocols.launch import execute, prepare_run
from labkit.rig import bundled_rig_path

from .loopback import LoopbackMjpeg

TIMEOUT_S = 1.0


class StallWhenSettled:
    """A run sink: once the first step has settled (the burst starts), silence the server."""

    def __init__(self, server: LoopbackMjpeg) -> None:
        self.server = server
        self.stalled_at: float | None = None

    def on_event(self, event) -> None:
        kind = event.get("type") if isinstance(event, dict) else getattr(event, "type", None)
        if kind == "settled" and self.stalled_at is None:
            self.stalled_at = time.monotonic() + 0.3
            threading.Timer(0.3, self.server.stall.set).start()


def test_a_silent_camera_ends_the_step_in_one_line_and_the_rotor_stops(tmp_path, emulation):
    text = bundled_rig_path("emulated-camera").read_text()
    with LoopbackMjpeg(fps=30) as server:
        url = f"{server.url}?timeout_s={TIMEOUT_S:g}"
        start = text.index('port = "sim://camera')
        end = text.index("\n", start)
        rig = tmp_path / "camera-over-http.toml"
        rig.write_text(text[:start] + f'port = "{url}"' + text[end:])
        sink = StallWhenSettled(server)
        prep = prepare_run(str(rig), "cone-sweep", ["speeds_rpm=5000,6000"], session_root=tmp_path,
                           sinks=[sink])
        outcome = execute(prep, session_root=tmp_path)
        ended = time.monotonic()
    assert outcome.status == "failed"
    reason = outcome.reason or ""
    assert "\n" not in reason
    assert f"camera camera at {url}" in reason and "stopped sending frames" in reason
    assert sink.stalled_at is not None and ended - sink.stalled_at < TIMEOUT_S + 2.5
    plant = emulation.plant("model-fig525")
    motor = plant.motor("rotor")
    assert motor.duty == 0.0  # commanded to zero on the fault path
    assert plant.speed(time.monotonic() + 5.0) < 1.0  # and it spins down (tau 0.4 s)
