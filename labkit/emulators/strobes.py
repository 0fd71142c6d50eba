"""The labkit stroboscope's emulator (``sim://labkit_strobe``, ``firmware/labkit_strobe``,
docs/reference/devices-strobe.md): status lines about the plant's rotor, written with its own
formatting code (none shared with the driver).

It follows ``plant.tach_reading(t, source)`` (``source=rotor`` by default, any motor of the
plant, or ``floator``) and emulates what the firmware reports, not its interrupts: the
mean rotor frequency of each window, a strobe frequency of (f_rot - offset)/m while locked
and lit, an apparent angle that advances by the offset per second while it flashes (and
goes on from where it was after a dark spell, as the firmware does), and the flags: ``Z``
no rotation (below 1 Hz), ``L`` not locked (rotor below 5 Hz or above 4 kHz, flag ``O``,
or for the first 5 revolutions after it came into range), ``X`` lamp off, ``W`` width
over T/4, ``R`` offset over 1/4 revolution per flash, ``N`` (fault ``noisy``).

Options: ``rate_hz`` (1), ``offset_hz`` (0.5), ``width_us`` (20), ``divider`` (1): the
power-on settings; ``boot_s`` (0.2: bootloader after the DTR reset of opening the port),
``version`` (1.0), ``source`` (rotor). Faults besides the common ones
(docs/explanation/device-rules.md#emulator-faults): ``noisy`` (probability per line of a
rejected noise pulse), ``error_reply``, ``reset_at``, ``stop_at``, ``mid_frame``.
"""

from __future__ import annotations

import math

from labkit.emulators.base import Emulator, SketchLines, register_emulator

TWO_PI = 2.0 * math.pi
MIN_HZ, MAX_HZ, STOP_HZ = 5.0, 4000.0, 1.0
LOCK_REVOLUTIONS = 5


@register_emulator
class LabkitStrobeEmulator(SketchLines, Emulator):
    line_max = 31  # the sketch's command buffer
    protocol = "labkit_strobe"
    kind = "strobe"
    serial_settings = {"baudrate": 115200, "bytesize": 8, "parity": "N", "stopbits": 1}

    def __post_init__(self) -> None:
        super().__post_init__()
        self.version = self.options.get("version", "1.0")
        self.boot_s = float(self.options.get("boot_s", 0.2))
        self.source = self.options.get("source", "rotor")
        self._defaults = (float(self.options.get("offset_hz", 0.5)), int(self.options.get("width_us", 20)),
                          int(self.options.get("divider", 1)), int(self.options.get("rate_hz", 1)),)
        self._line = bytearray()
        self._reset_done = False
        self._started_mid_frame = False
        self._next_t: float | None = None
        self.plant.strobes[self.role or "strobe"] = self  # the emulated camera's lamp

    # ---- power / time -------------------------------------------------------------------
    def power_on(self, t: float) -> None:
        self.offset_hz, self.width_us, self.divider, self.rate_hz = self._defaults
        self.lamp_on = True
        self.seq = 0
        self._boot_t = t
        self._boot_end = t + self.boot_s
        self._window_t = self._boot_end
        self._next_t = self._boot_end + 1.0 / self.rate_hz
        self._in_range_since: float | None = None
        self._phase = 0.0                    # apparent angle, revolutions
        self._line.clear()
        super().power_on(t)
        banner = (f"# labkit-strobe {self.version} offset={self.offset_hz:.3f} width={self.width_us} "
                  f"div={self.divider} rate={self.rate_hz}\n").encode("ascii")
        self._queue(banner, self._boot_end)

    def next_output_time(self, t: float) -> float | None:
        times = [x for x in (self._next_t, self.next_ready_time()) if x is not None]
        return min(times, default=None)

    def stopped(self, t: float) -> bool:
        stop = self.faults.get("stop_at")
        return stop is not None and self._opened_at is not None and self.since_open(t) >= stop

    def _queue(self, data: bytes, ready: float) -> None:
        if not self.stopped(ready):
            super()._queue(data, ready)

    def produce(self, t: float) -> None:
        if self._next_t is None or not self.connected(t):
            return
        at = self.faults.get("reset_at")
        if at is not None and not self._reset_done and self.since_open(t) >= at:
            self._reset_done = True
            self._outbox.clear()
            self.power_on(t)
        while self._next_t is not None and self._next_t <= t:
            when = self._next_t
            data = self.status_line(when)
            self._next_t = when + 1.0 / self.rate_hz
            if self.faults.get("mid_frame") and not self._started_mid_frame:
                self._started_mid_frame = True
                data = data[len(data) // 2:]
            self._queue(data, when)

    # ---- one status window --------------------------------------------------------------
    def _rotor_hz(self, t: float) -> float:
        return abs(self.plant.tach_reading(t, self.source)) / TWO_PI

    def _window_revolutions(self, start: float, end: float, steps: int = 8) -> float:
        """Revolutions of the rotor in [start, end] (trapezoid rule on the plant's speed)."""
        if end <= start:
            return 0.0
        h = (end - start) / steps
        values = [self._rotor_hz(start + i * h) for i in range(steps + 1)]
        return h * (sum(values) - 0.5 * (values[0] + values[-1]))

    def status_line(self, t: float) -> bytes:
        start, self._window_t = self._window_t, t
        f_rot = self._window_revolutions(start, t) / (t - start) if t > start else 0.0
        flags = ""
        in_range = MIN_HZ <= f_rot <= MAX_HZ
        if f_rot < STOP_HZ:
            flags += "Z"
            f_rot = 0.0
        if not in_range:
            self._in_range_since = None
            flags += "L"
            if f_rot >= STOP_HZ:
                flags += "O"
        else:
            if self._in_range_since is None:
                self._in_range_since = start
            if t - self._in_range_since < LOCK_REVOLUTIONS / f_rot + 1.0 / self.rate_hz:
                flags += "L"
        if self.rng.random() < self.faults.get("noisy", 0.0) and "Z" not in flags:
            flags += "N"
        if not self.lamp_on:
            flags += "X"
        period = 1.0 / f_rot if f_rot > 0 else math.inf
        dphi = self.offset_hz * self.divider * period / (1.0 - self.offset_hz * period) if f_rot else 0.0
        if in_range and self.width_us * 1e-6 > period / 4:
            flags += "W"
        if in_range and abs(dphi) > 0.25:
            flags += "R"
        flashing = in_range and self.lamp_on and "R" not in flags and "L" not in flags
        f_strobe = (f_rot - self.offset_hz) / self.divider if flashing else 0.0
        if in_range and self.lamp_on and "R" not in flags:
            # the apparent angle goes on in step with time, also while the lock is regained
            self._phase = (self._phase + self.offset_hz * (t - start)) % 1.0
        phase_deg = round(self._phase * 360.0, 1) % 360.0
        line = (f"S,{self.seq},{int((t - self._boot_t) * 1000.0)},{f_rot:.4f},{max(f_strobe, 0.0):.4f},"
                f"{phase_deg:.1f},{flags or '0'}\n")
        self.seq += 1
        return line.encode("ascii")

    # ---- the flashes, for the emulated camera --------------------------------------------
    def flash_plan(self, t: float) -> tuple[float, float, int, float] | None:
        """What the lamp does at ``t``: (true rotor frequency Hz, offset Hz, divider, flash
        width s), or None while it is dark (off, rotor out of range, offset too large, or not
        yet locked: the first 5 revolutions after the rotor came into range). The true speed,
        not a reading: the flashes follow the rotor's own pulse."""
        if self._next_t is None or not self.lamp_on or t < self._boot_end:
            return None
        w = self.plant.floator_spin(t) if self.source == "floator" else self.plant.speed(t, self.source)
        f_rot = abs(w) / TWO_PI
        if not MIN_HZ <= f_rot <= MAX_HZ or self._in_range_since is None:
            return None
        if t - self._in_range_since < LOCK_REVOLUTIONS / f_rot:
            return None
        period = 1.0 / f_rot
        if abs(self.offset_hz * self.divider * period / (1.0 - self.offset_hz * period)) > 0.25:
            return None
        return f_rot, self.offset_hz, self.divider, min(self.width_us * 1e-6, period / 4)

    # ---- commands -----------------------------------------------------------------------
    def _command(self, text: str, t: float) -> None:
        if text == "ID?":
            self.reply(f"ID labkit-strobe {self.version}\n".encode(), t, 0.001)
        elif text in ("ON", "OFF"):
            self.lamp_on = text == "ON"
            self.reply(b"OK\n", t, 0.001)
        else:
            self.reply(self._setting(text, t), t, 0.001)

    def _setting(self, text: str, t: float) -> bytes:
        name, space, arg = text.partition(" ")
        limits = {"OFFSET": (-100.0, 100.0), "WIDTH": (1, 1000), "DIV": (1, 100), "RATE": (1, 50)}
        if not space or name not in limits:
            return b"ERR unknown command\n"
        try:
            value = float(arg)
        except ValueError:
            return b"ERR bad value\n"
        low, high = limits[name]
        if not (low <= value <= high) or (name != "OFFSET" and value != int(value)):
            return b"ERR bad value\n"
        if name == "OFFSET":
            self.offset_hz = value
        elif name == "WIDTH":
            self.width_us = int(value)
        elif name == "DIV":
            self.divider = int(value)
        else:
            self.rate_hz = int(value)
            self._next_t = t + 1.0 / self.rate_hz
        return b"OK\n"
