"""Tachometer emulators: the Lutron 16-byte stream and the labkit pulse counter.

Both read the shared plant: ``source=rotor`` (default; any motor name of the plant) gives
``plant.speed(t, name)``, ``source=floator`` gives the floating magnet's spin
``plant.floator_spin(t)`` (the Fig. 6.18 set-up's second tachometer). They write their own
bytes with their own formatting code (no code shared with the drivers).

Fault knobs besides the common ones of :mod:`labkit.emulators.base`
(docs/explanation/device-rules.md#emulator-faults):

* ``overload`` - Lutron: over-range frames; labkit-tach: every line flagged ``O``.
* ``mid_frame`` - the first bytes after open are the tail of a frame/line.
* ``noisy`` - labkit-tach: probability per line of a rejected glitch (flag ``N``).
* ``error_reply`` - labkit-tach: probability of answering a valid command ``ERR busy``.
* ``reset_at`` - labkit-tach: clock time (s after open) of a device reset (banner, seq 0,
  settings back to defaults).
* ``wrong_baud`` - also garbles what the device sends (the host reads at the wrong rate).
* ``stop_at`` - s after open at which the device stops sending (meter switched off, cable
  pulled at the meter end): no more bytes, but the port stays open and ``in_waiting`` works.
  A frozen meter.
* ``zero_at`` - s after open from which the meter reads zero (reflective mark lost, cable
  pulled at the sensor end); labkit-tach: ``0.0`` RPM lines with the zero flag ``Z`` at once
  (as after its zero timeout).
* ``stuck_at`` - s after open from which the value stays what it was; labkit-tach: the
  sequence number and ``t_ms`` still advance, rpm, period and pulses do not; Lutron and
  Monarch: the same frame again and again.
* ``repeat_at`` - s after open from which the same line or frame is sent again and again
  (labkit-tach: the same sequence number too).
* ``lag_s`` - the reading shows the speed of ``lag_s`` seconds ago (a slow filter).

Time-triggered faults can also start on a signal: ``labkit emulate --fault-on-usr2 ROLE:NAME``.
"""

from __future__ import annotations

import collections
import math

from labkit.emulators.base import Emulator, SketchLines, register_emulator

TWO_PI = 2.0 * math.pi


class _StreamingTachEmulator(Emulator):
    """Shared scheduling: one frame every 1/rate s, nothing while unplugged or booting."""

    kind = "tachometer"
    default_rate_hz = 1.0

    def __post_init__(self) -> None:
        super().__post_init__()
        self.rate_hz = float(self.options.get("rate_hz", self.default_rate_hz))
        self.source = self.options.get("source", "rotor")
        self._next_t: float | None = None
        self._down = False
        self._started_mid_frame = False
        self._held_frame: bytes | None = None        # stuck_at / repeat_at
        self._seen: collections.deque[tuple[float, float]] = collections.deque()  # lag_s
        self._held_fields: list[str] | None = None   # labkit-tach stuck_at

    def source_speed(self, t: float) -> float:
        """rad/s seen by the sensor: the named motor's speed, or the floator's spin (``lag_s``
        seconds late; 0 once ``zero_at`` has begun)."""
        if self.fault_on("zero_at", t):
            return 0.0
        now = self.plant.tach_reading(t, self.source)
        lag = self.faults.get("lag_s", 0.0)
        if not lag:
            return now
        # the plant cannot go back in time: keep what the sensor saw, show what it saw lag_s ago
        self._seen.append((t, now))
        while len(self._seen) > 1 and self._seen[1][0] <= t - lag:
            self._seen.popleft()
        return self._seen[0][1] if self._seen[0][0] <= t - lag else 0.0

    def faulted_frame(self, t: float, data: bytes) -> bytes:
        """The frame as the ``stuck_at`` / ``repeat_at`` faults send it (the first frame after
        the fault began, again and again; labkit-tach overrides ``stuck_at``)."""
        if data and (self.fault_on("repeat_at", t) or self.fault_on("stuck_at", t)):
            if self._held_frame is None:
                self._held_frame = data
            return self._held_frame
        return data

    def stream_start(self, t: float) -> float:
        return t

    def next_output_time(self, t: float) -> float | None:
        """The next frame or queued reply, so a virtual clock can jump straight there."""
        times = [x for x in (self._next_t, self.next_ready_time()) if x is not None]
        return min(times, default=None)

    def power_on(self, t: float) -> None:
        super().power_on(t)
        self._next_t = self.stream_start(t) + 1.0 / self.rate_hz

    def produce(self, t: float) -> None:
        if self._next_t is None:
            return
        if not self.connected(t):
            self._down = True
            return
        if self._down:  # plugged back in: power-on state
            self._down = False
            self._outbox.clear()
            self.power_on(t)
        self.check_events(t)
        while self._next_t is not None and self._next_t <= t:
            when = self._next_t
            data = self.faulted_frame(when, self.frame(when))
            self._next_t = when + 1.0 / self.rate_hz
            if data:
                self.send(data, when)

    def stopped(self, t: float) -> bool:
        """True once the ``stop_at`` fault has silenced the device (its port stays open)."""
        stop = self.faults.get("stop_at")
        return stop is not None and self._opened_at is not None and self.since_open(t) >= stop

    def _queue(self, data: bytes, ready: float) -> None:
        if not self.stopped(ready):  # switched off: neither frames nor replies
            super()._queue(data, ready)

    def send(self, data: bytes, when: float) -> None:
        if self.faults.get("mid_frame") and not self._started_mid_frame:
            self._started_mid_frame = True
            data = data[len(data) // 2:]
        if self.faults.get("wrong_baud"):
            data = bytes(self.rng.randrange(256) for _ in data)
        self._queue(data, when)

    def check_events(self, t: float) -> None:
        """Time-triggered faults (subclasses)."""

    def frame(self, t: float) -> bytes:  # pragma: no cover - interface
        raise NotImplementedError


@register_emulator
class Lutron16Emulator(_StreamingTachEmulator):
    """A Lutron-format tachometer display streaming 16-byte frames
    (docs/reference/devices-tach-motor.md#lutron16-lutron-16-byte-stream).

    Options: ``rate_hz`` (1), ``annunciator`` (two digits, default ``00``: the real RPM code
    is model-specific, docs/explanation/device-rules.md#open-on-real-hardware), ``display`` (``1``),
    ``noise_rpm`` (Gaussian, 0),
    ``no_target`` (``zero`` or ``hold``: what the meter shows when the beam sees nothing).
    Resolution follows the DT-2236 class: 0.1 RPM below 10 000, 1 RPM up to 99 999, then
    over-range.
    """

    protocol = "lutron16"
    serial_settings = {"baudrate": 9600, "bytesize": 8, "parity": "N", "stopbits": 1}
    default_rate_hz = 1.0

    def __post_init__(self) -> None:
        super().__post_init__()
        self.annunciator = self.options.get("annunciator", "00").encode("ascii")[:2].rjust(2, b"0")
        self.display = self.options.get("display", "1").encode("ascii")[:1]
        self.noise_rpm = float(self.options.get("noise_rpm", 0.0))
        self.hold = self.options.get("no_target", "zero") == "hold"
        self._shown_rpm = 0.0

    def frame(self, t: float) -> bytes:
        rpm = abs(self.source_speed(t)) * 60.0 / TWO_PI
        if rpm > 0 and self.noise_rpm:
            rpm = max(0.0, rpm + self.rng.gauss(0.0, self.noise_rpm))
        if rpm == 0.0 and self.hold:
            rpm = self._shown_rpm
        self._shown_rpm = rpm
        head = b"\x024" + self.display + self.annunciator + b"0"
        if self.faults.get("overload") or round(rpm) > 99_999:
            return head + b"0" + b"  OL    " + b"\r"
        if rpm < 9999.95:
            return head + b"1" + b"%08d" % round(rpm * 10) + b"\r"
        return head + b"0" + b"%08d" % round(rpm) + b"\r"


@register_emulator
class LabkitTachEmulator(SketchLines, _StreamingTachEmulator):
    """The labkit Arduino pulse tachometer
    (docs/reference/devices-tach-motor.md#labkit_tach-the-labkit-pulse-tachometer-labkit-defined,
    ``firmware/labkit_tach``).

    Emulates the firmware's period method: pulse edges at ``ppr`` per revolution are
    time-stamped with ``micros()`` (``tick_us`` resolution, 4 us on a 16 MHz AVR, plus
    ``jitter_us`` Gaussian), the line reports the mean period of the pulses in the window.
    Options: ``ppr`` (1), ``rate_hz`` (10), ``zto_ms`` (1000), ``boot_s`` (0.2: bootloader
    delay after the DTR reset of opening the port), ``dtr_reset`` (1; 0 = the device kept
    running, no banner), ``tick_us`` (4), ``jitter_us`` (0), ``min_period_us`` (50: shorter
    is flagged ``O``), ``version`` (``1.0``).
    """

    protocol = "labkit_tach"
    serial_settings = {"baudrate": 115200, "bytesize": 8, "parity": "N", "stopbits": 1}
    default_rate_hz = 10.0

    def __post_init__(self) -> None:
        super().__post_init__()
        self.version = self.options.get("version", "1.0")
        self.boot_s = float(self.options.get("boot_s", 0.2))
        self.dtr_reset = self.options.get("dtr_reset", "1") not in ("0", "false", "no")
        self.tick_us = float(self.options.get("tick_us", 4.0))
        self.jitter_us = float(self.options.get("jitter_us", 0.0))
        self.min_period_us = float(self.options.get("min_period_us", 50.0))
        self._defaults = (int(self.options.get("ppr", 1)), self.rate_hz,
                          int(self.options.get("zto_ms", 1000)))
        self._line = bytearray()
        self._reset_done = False
        self._boot_t = 0.0

    # ---- power / time -------------------------------------------------------------------
    def stream_start(self, t: float) -> float:
        return self._boot_end

    def power_on(self, t: float) -> None:
        self.ppr, self.rate_hz, self.zto_ms = self._defaults
        first_boot = self.power_on_count == 0
        silent = first_boot and not self.dtr_reset
        self._boot_t = t - (10.0 if silent else 0.0)
        self._boot_end = t if silent else t + self.boot_s
        self.seq = 0 if not silent else 4242
        self._phase = 0.0           # pulses (fractional) since boot
        self._last_pulse: float | None = None
        self._sum_periods_us = 0.0
        self._count = 0
        self._last_period_us: float | None = None
        self._window_t = self._boot_end
        self._line.clear()
        super().power_on(t)
        if not silent:
            banner = (f"# labkit-tach {self.version} ppr={self.ppr} rate={self.rate_hz:g} "
                      f"zto={self.zto_ms}\n").encode("ascii")
            self._queue(banner, self._boot_end)

    def check_events(self, t: float) -> None:
        at = self.faults.get("reset_at")
        if at is not None and not self._reset_done and self.since_open(t) >= at:
            self._reset_done = True
            self._outbox.clear()
            self.power_on(t)

    def _micros(self, t: float) -> float:
        """What ``micros()`` returns at clock time t (tick resolution, jitter)."""
        us = (t - self._boot_t) * 1e6
        if self.jitter_us:
            us += self.rng.gauss(0.0, self.jitter_us)
        return math.floor(us / self.tick_us) * self.tick_us

    # ---- one output window --------------------------------------------------------------
    def faulted_frame(self, t: float, data: bytes) -> bytes:
        """``stuck_at``: rpm, period and pulses of the first line after the fault, with this
        line's sequence number and time; ``repeat_at``: the whole line again."""
        if self.fault_on("stuck_at", t) and not self.fault_on("repeat_at", t) and data.startswith(b"T,"):
            fields = data.decode("ascii").rstrip("\n").split(",")
            if self._held_fields is None:
                self._held_fields = fields[3:]
            return (",".join(fields[:3] + self._held_fields) + "\n").encode("ascii")
        return super().faulted_frame(t, data) if data.startswith(b"T,") else data

    def frame(self, t: float) -> bytes:
        if self.fault_on("zero_at", t):  # no pulses, and the zero timeout taken as elapsed
            self._last_period_us, self._count, self._sum_periods_us = None, 0, 0.0
        speed = abs(self.source_speed(t))
        rate = speed / TWO_PI * self.ppr            # pulses per second
        start = self._window_t
        self._window_t = t
        phase0 = self._phase
        self._phase = phase0 + rate * (t - start)
        first = math.floor(phase0) + 1
        n = math.floor(self._phase) - math.floor(phase0)
        if n > 0 and rate > 0:
            edges = [start + (k - phase0) / rate for k in (first, first + n - 1)]
            prev = self._last_pulse
            if prev is None:      # the first edge only starts the timing
                prev, n = edges[0], n - 1
            if n > 0:
                self._sum_periods_us += self._micros(edges[1]) - self._micros(prev)
                self._count += n
            self._last_pulse = edges[1]
        flags = ""
        pulses = self._count
        if self._count:
            period = self._sum_periods_us / self._count
            self._last_period_us = period
            self._sum_periods_us, self._count = 0.0, 0
        elif self._last_period_us is not None and self._last_pulse is not None \
                and (t - self._last_pulse) * 1000.0 <= self.zto_ms:
            period = self._last_period_us
        else:
            period = 0.0
            self._last_period_us = None
            flags = "Z"
        if period > 0 and (period < self.min_period_us or self.faults.get("overload")):
            flags = "O"
        if flags != "Z" and self.rng.random() < self.faults.get("noisy", 0.0):
            flags += "N"
        rpm = 60e6 / (period * self.ppr) if period > 0 and "Z" not in flags else 0.0
        t_ms = int((t - self._boot_t) * 1000.0)
        line = f"T,{self.seq},{t_ms},{rpm:.1f},{period:.1f},{pulses},{flags or '0'}\n"
        self.seq += 1
        return line.encode("ascii")

    # ---- commands -----------------------------------------------------------------------
    def _command(self, text: str, t: float) -> None:
        if text == "ID?":
            self.reply(f"ID labkit-tach {self.version}\n".encode(), t, 0.001)
            return
        name, _, arg = text.partition(" ")
        limits = {"PPR": (1, 64), "RATE": (1, 200), "ZTO": (10, 10_000)}
        if name not in limits:
            self.reply(b"ERR unknown command\n", t, 0.001)
            return
        try:
            value = int(arg)
        except ValueError:
            value = -1
        low, high = limits[name]
        if not low <= value <= high:
            self.reply(b"ERR bad value\n", t, 0.001)
            return
        if name == "PPR":
            self.ppr = value
            self._phase, self._last_pulse, self._count, self._sum_periods_us = 0.0, None, 0, 0.0
            self._last_period_us = None
        elif name == "RATE":
            self.rate_hz = float(value)
        else:
            self.zto_ms = value
        self.reply(b"OK\n", t, 0.001)


@register_emulator
class MonarchEmulator(_StreamingTachEmulator):
    """A Monarch panel tachometer (ACT-3X class) answering ``@`` commands
    (docs/reference/devices-tach-motor.md#monarch_at-monarch--commands-act-1b-act-3x-f2a1x-tier-2).

    ``@PI`` -> product and firmware lines, ``@D0`` -> one value line, ``@D1``/``@D2`` ->
    ``OK`` and start/stop continuous display data (``rate_hz``, default 2: the display
    updates at most twice a second), anything else -> ``ERR``. Value lines are the RPM with
    one decimal, CR LF ended [U: the real number format is undocumented]. Options:
    ``rate_hz``, ``product`` (``ACT-3X``), ``firmware`` (``1.00``), ``source``. Faults:
    ``error_reply`` (probability of ``ERR`` to a valid command) and the common ones.
    """

    protocol = "monarch_at"
    serial_settings = {"baudrate": 9600, "bytesize": 8, "parity": "N", "stopbits": 1}
    default_rate_hz = 2.0

    def __post_init__(self) -> None:
        super().__post_init__()
        self.product = self.options.get("product", "ACT-3X")
        self.firmware = self.options.get("firmware", "1.00")
        self.streaming = False
        self._command = bytearray()

    def power_on(self, t: float) -> None:
        super().power_on(t)
        self.streaming = False
        self._command = bytearray()

    def value_line(self, t: float) -> bytes:
        rpm = abs(self.source_speed(t)) * 60.0 / TWO_PI
        return f"{rpm:.1f}\r\n".encode("ascii")

    def frame(self, t: float) -> bytes:
        return self.value_line(t) if self.streaming else b""

    def handle(self, data: bytes, t: float) -> None:
        for byte in data:
            if byte == 0x40:                      # '@' starts a command
                self._command = bytearray(b"@")
            elif byte == 0x0D:
                if self._command:
                    self._execute(bytes(self._command[1:]).decode("ascii", "replace"), t)
                self._command = bytearray()
            elif self._command and len(self._command) < 40:
                self._command.append(byte)

    def _execute(self, name: str, t: float) -> None:
        if self.rng.random() < self.faults.get("error_reply", 0.0):
            self.reply(b"ERR\r\n", t, 0.01)
        elif name == "PI":
            self.reply(f"{self.product}\r\n{self.firmware}\r\n".encode("ascii"), t, 0.01)
        elif name == "D0":
            self.reply(self.value_line(t), t, 0.01)
        elif name in ("D1", "D2"):
            self.streaming = name == "D1"
            self.reply(b"OK\r\n", t, 0.01)
        else:
            self.reply(b"ERR\r\n", t, 0.01)
