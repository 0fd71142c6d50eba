"""``sim://camera``: an emulated camera filming the laser trace of the model plant's floator.

At each frame the rotor speed of the shared plant (``plant=model-fig525``, the one the motor
and tachometer emulators drive) gives the model's cone angle phi (the co-rotating steady state of
:func:`labkit.model.floator_equilibrium.steady_state`, Eq. 5.7/5.24, as ``labkit twin`` uses it);
the reflected beam of that cone, turning
at the rotor's frequency, is rendered by :mod:`labkit.footage` on a screen ``screen_mm`` away,
seen at ``mm_per_px``, with the camera's exposure, on the run's clock and seeded (frame ``k``'s
sensor noise is seed ``1000 seed + k``). Frames are JPEG bytes, as from an MJPEG webcam.

Frames are pulled, not pushed: reading frame ``k`` waits on the clock until its exposure has
ended (a virtual clock jumps there, running the speed loop on the way), so a burst takes the
time a real camera's would; it holds the last ``QUEUE_FRAMES`` exposed frames for a reader
that is a little late, and skips to the next slot when the one due has left that queue.
Options (URL query): ``seed``, ``plant``, ``size`` (320x240), ``fps`` (30), ``exposure_s``
(0.004), ``screen_mm`` (500), ``mm_per_px`` (2.0), ``scene``
(``laser``; ``strobe``: the floator side on, lit by the plant's strobe:
:mod:`labkit.emulators.camera_strobe`, with its own options).
"""

from __future__ import annotations

import math
from typing import Any

from labkit.devices.camera.frames import CameraSettings
from labkit.devices.camera.sources import RawFrame, SourceStopped, encode_jpeg
from labkit.devices.camera.urls import CameraRequest
from labkit.emulators.camera_strobe import StrobeScene, model_swing
from labkit.emulators.plant import shared_plant
from labkit.emulators.twin_model import TwinParams

DEFAULTS = {"size": (320, 240), "fps": 30.0, "exposure_s": 0.004, "screen_mm": 500.0, "mm_per_px": 2.0}
SIM_JPEG_QUALITY = 75
#: frames the emulated camera holds for a late reader (a webcam driver queues 2-4)
QUEUE_FRAMES = 3


def model_cone_angle(params: Any, rpm: int) -> float:
    """The model's cone angle (rad) at ``rpm`` (whole RPM: cached); 0 where there is no steady
    cone (rotor at rest or too slow for the floator to follow). The phi of
    :func:`labkit.emulators.camera_strobe.model_swing`: one solve for both scenes."""
    return model_swing(params, rpm)[0]


class SimCameraSource:
    """The emulated camera (module docstring). ``live = False``: frames are pulled on the clock."""

    live = False

    def __init__(self, request: CameraRequest) -> None:
        self.request = request
        opts = request.options
        self.seed = int(opts.get("seed", 0))
        self.plant_name = opts.get("plant", "model-fig525")
        self.size = request.size or DEFAULTS["size"]
        self.fps = request.fps or DEFAULTS["fps"]
        self.exposure_s = request.exposure_s or DEFAULTS["exposure_s"]
        self.screen_mm = float(opts.get("screen_mm", DEFAULTS["screen_mm"]))
        self.mm_per_px = float(opts.get("mm_per_px", DEFAULTS["mm_per_px"]))
        if self.exposure_s > 1.0 / self.fps:
            raise SourceStopped(f"exposure_s={self.exposure_s:g} is longer than a frame at {self.fps:g} fps")
        #: the camera's fault: it stops sending after this many frames (``stop_after=N``), as a
        #: webcam whose USB link dropped; None never
        self.stop_after = int(opts["stop_after"]) if "stop_after" in opts else None
        self.scene_name = opts.get("scene", "laser")
        if self.scene_name not in ("laser", "strobe"):
            raise SourceStopped(f"scene={self.scene_name!r}: expected laser or strobe")
        self.strobe_scene: Any = None
        if self.scene_name == "strobe":
            self.strobe_scene = StrobeScene(self, opts)
        self.k = 0
        self.sent = 0
        self.t0 = 0.0
        self.clock: Any = None

    def open(self, clock: Any) -> CameraSettings:
        self.clock = clock
        self.plant = shared_plant(self.plant_name)
        self.params = getattr(self.plant, "params", None)
        if self.params is None:
            self.params = TwinParams()
        self.frame_image(clock.now(), 0)  # warm up (imports, the model's first solve): no slot is lost to it
        self.t0 = clock.now()
        asked = {"size": f"{self.size[0]}x{self.size[1]}", "fps": self.fps, "exposure_s": self.exposure_s}
        return CameraSettings(tuple(self.size), self.fps, "MJPG", self.exposure_s, "device", "sim-footage",
                              asked)

    def cone_angle(self, t: float) -> tuple[float, float]:
        """(phi rad, rotor speed rad/s) of the model at clock time ``t``."""
        w = abs(self.plant.speed(t))
        return model_cone_angle(self.params, int(round(w * 30.0 / math.pi))), w

    def read(self, timeout_s: float) -> RawFrame:
        # the next frame slot if it is still in the camera's queue (QUEUE_FRAMES deep, as a V4L2
        # driver's buffers): a reader a little late (a control tick's serial traffic on a virtual
        # clock) gets every frame; one that fell further behind, or was idle, goes on from the
        # next slot not yet started (the slots between: drops, or discarded between bursts)
        if self.stop_after is not None and self.sent >= self.stop_after:
            raise SourceStopped(f"stopped delivering frames (emulated fault: stop_after={self.stop_after})")
        self.sent += 1
        period = 1.0 / self.fps
        now = self.clock.now()
        if self.k < math.floor((now - self.t0 - self.exposure_s) / period + 1e-9) - QUEUE_FRAMES + 1:
            self.k = math.ceil((now - self.t0) / period - 1e-9)
        start = self.t0 + self.k * period
        self.clock.sleep_until(start + self.exposure_s)
        image = self.frame_image(start, self.k)
        seq = self.k
        self.k += 1
        if self.strobe_scene is not None:
            meta = self.strobe_scene.truth(start)
        else:
            phi, w = self.cone_angle(start)
            meta = {"model_cone_angle_rad": phi, "model_speed_rad_s": w}
        return RawFrame(encode_jpeg(image, SIM_JPEG_QUALITY), t_device=start, seq=seq, meta=meta)

    def frame_image(self, start: float, k: int):
        """Frame ``k`` of the scene the URL asks for (the laser trace, or the strobe-lit floator)."""
        if self.strobe_scene is not None:
            return self.strobe_scene.render(start, k)
        return self.render(start, k)

    def render(self, start: float, k: int):
        from labkit.footage import (
            Camera,
            LaserShot,
            Lighting,
            PrecessionNutation,
            Screen,
            ScreenView,
            render_laser,
        )

        phi, w = self.cone_angle(start)
        cycle_hz = max(w / (2 * math.pi), 1e-3)
        beam = math.tan(2.0 * phi)
        phase = 2 * math.pi * ((cycle_hz * start) % 1.0)
        w_px, h_px = self.size
        shot = LaserShot(PrecessionNutation((0.0, 0.0), (beam, 0.0), (0.0, 0.0), -1, cycle_hz, phase),
                         Screen(self.screen_mm, 0.0, hole_mm=3.0),
                         ScreenView((w_px / 2, h_px / 2), self.mm_per_px, 0.0),
                         Camera(tuple(self.size), self.fps, self.exposure_s, 0.0, read_noise=0.004,
                                shot_noise=0.004, psf_core_px=1.2),
                         Lighting(level=0.03), frames=1, power=1.2, seed=1000 * self.seed + k)
        return next(render_laser(shot))

    def truth(self, t: float) -> dict[str, float]:
        """What the model says at clock time ``t`` (for tests and the protocol's comparison)."""
        phi, w = self.cone_angle(t)
        return {"phi_rad": phi, "omega_rad_s": w, "mm_per_px": self.mm_per_px, "screen_mm": self.screen_mm}

    def close(self) -> None:
        pass
