"""Balance emulators: MT-SICS and A&D standard format, and the base every balance and
load-cell emulator shares (the HX711 sketches are in :mod:`labkit.emulators.hx711_sketch`).

All of them weigh the shared plant's PFR force (``plant.force(t)``, N; by default the fitted
law of Fig. 5.25, ``y[g] = 224e6 * rpm**-1.9``) sampled at the device's update rate, plus
seeded Gaussian noise, a linear zero drift and creep (the reading creeps by a fraction of a
load change with a time constant). A reading is *unstable* while the standard deviation of
the last ``window_s`` of samples is above ``stable_std_g``, so a motor ramp shows as
``S D`` / ``US`` and ``S``/``Z``/``T`` wait until the force settles. Zero and tare really
move the offset. They format their own bytes (no code shared with the drivers).

Options (sim:// query or rig file): ``unit`` (g, or N where the device can), ``decimals``,
``rate_hz``, ``noise_g``, ``drift_g_per_s``, ``creep`` (fraction), ``creep_tau_s``,
``capacity_g``, ``stable_std_g``, ``window_s``, ``stability_timeout_s``, ``serial``.
A&D also ``mode=stream``, ``ack=0|1``; HX711 ``preset``, ``calibration`` (counts/g for
``unit=raw``), ``startup_s``, ``tare_s``.

Fault knobs besides the common ones (docs/explanation/device-rules.md#emulator-faults): ``overload`` /
``underload``
(probability per weight reply), ``unstable`` (probability a reply is forced dynamic),
``error_reply`` (probability a command gets ``EL`` / ``EC,E02``), ``reset_at`` (s after
open: power-on junk, ``I4`` line on MT-SICS, zero and tare lost), ``mid_frame`` (the first
streamed line starts mid-line), ``wrong_baud`` (garbles both directions), ``stop_at`` (HX711:
s after open at which the sketch stops printing). Host bytes that
are not printable ASCII get ``ET`` / ``EC,E00``; unknown commands ``ES`` / ``EC,E01``.
"""

from __future__ import annotations

import math
import random
from collections import deque
from dataclasses import dataclass
from typing import ClassVar

from labkit.emulators.base import Emulator, register_emulator
from labkit.units import G0

JUNK = b"\x00\xff\xfe"


@dataclass(frozen=True)
class Tick:
    """One internal update of the weighing cell."""

    t: float
    gross_n: float
    stable: bool


class LoadSignal:
    """The load cell's own sample stream: force + drift + creep + noise, and a stability flag.

    Samples fall on a fixed grid ``t0 + k / rate_hz`` and use their own seeded generator,
    so the values do not depend on when or how often the host asks.
    """

    def __init__(self, force, seed: int, rate_hz: float, noise_n: float, drift_n_per_s: float,
                 creep: float, creep_tau_s: float, window_s: float, stable_std_n: float) -> None:
        self.force = force
        self.rng = random.Random(seed * 7919 + 1)
        self.period = 1.0 / rate_hz
        self.noise_n = noise_n
        self.drift_n_per_s = drift_n_per_s
        self.creep = creep
        self.creep_tau_s = creep_tau_s
        self.stable_std_n = stable_std_n
        self.window: deque[float] = deque(maxlen=max(2, int(round(window_s * rate_hz))))
        self.t0 = 0.0
        self.k = 0
        self.lagged_n = 0.0
        self.last = Tick(0.0, 0.0, True)

    def start(self, t: float) -> None:
        self.t0, self.k = t, 0
        self.lagged_n = self.force(t)
        self.window.clear()
        self.last = self._sample(t)

    def next_time(self) -> float:
        return self.t0 + (self.k + 1) * self.period

    def _sample(self, t: float) -> Tick:
        force = self.force(t)
        self.lagged_n += (force - self.lagged_n) * (1.0 - math.exp(-self.period / self.creep_tau_s))
        gross = (force + self.creep * self.lagged_n + self.drift_n_per_s * (t - self.t0)
                 + self.rng.gauss(0.0, self.noise_n))
        self.window.append(gross)
        full = len(self.window) == self.window.maxlen
        mean = sum(self.window) / len(self.window)
        std = math.sqrt(sum((x - mean) ** 2 for x in self.window) / len(self.window))
        return Tick(t, gross, full and std <= self.stable_std_n)

    def advance(self, t: float) -> list[Tick]:
        """Samples due up to ``t`` (at most the last 10 000 after a long gap)."""
        ticks: list[Tick] = []
        due = int(math.floor((t - self.t0) / self.period + 1e-9))
        if due - self.k > 10_000:
            self.k = due - 10_000
        while self.k < due:
            self.k += 1
            self.last = self._sample(self.t0 + self.k * self.period)
            ticks.append(self.last)
        return ticks


@dataclass
class Pending:
    """A command waiting for stability (``S``, ``Z``, ``T``)."""

    command: str
    since: float


class BalanceEmulator(Emulator):
    """Shared weighing state: signal, zero, tare, pending stable commands, stream, faults."""

    kind: ClassVar[str] = "balance"
    default_unit: ClassVar[str] = "g"
    default_rate_hz: ClassVar[float] = 20.0
    serial_settings: ClassVar[dict] = {"baudrate": 9600, "bytesize": 8, "parity": "N", "stopbits": 1}

    def __post_init__(self) -> None:
        super().__post_init__()
        opt = self.options
        self.unit = str(opt.get("unit", self.default_unit))
        self.decimals = int(opt.get("decimals", 4 if self.unit == "N" else 2))
        self.capacity_n = float(opt.get("capacity_g", 220.0)) * 1e-3 * G0
        self.stability_timeout_s = float(opt.get("stability_timeout_s", 5.0))
        self.serial_number = str(opt.get("serial", "B207696838"))
        g = 1e-3 * G0
        self.signal = LoadSignal(
            self.plant.force, self.seed,
            rate_hz=float(opt.get("rate_hz", self.default_rate_hz)),
            noise_n=float(opt.get("noise_g", 0.002)) * g,
            drift_n_per_s=float(opt.get("drift_g_per_s", 1e-5)) * g,
            creep=float(opt.get("creep", 5e-4)),
            creep_tau_s=float(opt.get("creep_tau_s", 20.0)),
            window_s=float(opt.get("window_s", 0.5)),
            stable_std_n=float(opt.get("stable_std_g", 0.01)) * g,
        )
        self.zero_n = 0.0
        self.tare_n = 0.0
        self.streaming = False
        self.pending: list[Pending] = []
        self._inbuf = b""
        self._last_rx = -math.inf
        self._reset_done = False
        self._mid_frame_done = False

    # ---- life cycle -------------------------------------------------------------------
    def power_on(self, t: float) -> None:
        super().power_on(t)
        self._outbox.clear()
        self.signal.start(t)
        self.zero_n = self.signal.last.gross_n  # balances zero themselves at power-on
        self.tare_n = 0.0
        self.streaming = self.options.get("mode") == "stream"
        self.pending = []
        self._inbuf = b""
        if self.power_on_count > 1:
            self._queue(JUNK, t)
        self.banner(t)

    def banner(self, t: float) -> None:
        """What the device prints at power-on (subclasses)."""

    # ---- weighing ---------------------------------------------------------------------
    def to_unit(self, newtons: float) -> float:
        return newtons if self.unit == "N" else newtons / (1e-3 * G0)

    def weigh(self, tick: Tick) -> tuple[str, float | None]:
        """``("S"|"D"|"+"|"-", value in the display unit)``; no value for +/-."""
        above_zero = tick.gross_n - self.zero_n
        if above_zero > self.capacity_n or self._chance("overload"):
            return "+", None
        if above_zero < -0.1 * self.capacity_n or self._chance("underload"):
            return "-", None
        stable = tick.stable and not self._chance("unstable")
        return ("S" if stable else "D"), self.to_unit(above_zero - self.tare_n)

    def _chance(self, fault: str) -> bool:
        p = self.faults.get(fault, 0.0)
        return bool(p) and self.rng.random() < p

    def advance(self, t: float) -> None:
        """Bring the cell up to ``t``: due samples, stream lines, pending commands, reset."""
        at = self.faults.get("reset_at")
        if at is not None and not self._reset_done and self.since_open(t) >= at:
            self._reset_done = True
            self.power_on(t)
        if self._inbuf and t - self._last_rx > 1.0:  # half a command, never finished
            self._inbuf = b""
            self.command_timeout(self._last_rx + 1.0)
        for tick in self.signal.advance(t):
            self.on_tick(tick)

    def on_tick(self, tick: Tick) -> None:
        for pending in list(self.pending):
            if tick.stable:
                self.pending.remove(pending)
                self.complete(pending, tick, ok=True)
            elif tick.t - pending.since >= self.stability_timeout_s:
                self.pending.remove(pending)
                self.complete(pending, tick, ok=False)
        if self.streaming:
            self.stream_line(tick)

    def complete(self, pending: Pending, tick: Tick, ok: bool) -> None:
        """Answer a command that waited for stability (subclasses)."""

    def stream_line(self, tick: Tick) -> None:
        """One line of continuous output (subclasses)."""

    def zero_now(self, tick: Tick) -> None:
        self.zero_n = tick.gross_n
        self.tare_n = 0.0

    def tare_now(self, tick: Tick) -> None:
        self.tare_n = tick.gross_n - self.zero_n

    def produce(self, t: float) -> None:
        self.advance(t)

    def next_output_time(self, t: float) -> float | None:
        times = [self.next_ready_time()]
        if self.streaming or self.pending:
            times.append(self.signal.next_time())
        at = self.faults.get("reset_at")
        if at is not None and not self._reset_done and self._opened_at is not None:
            times.append(self._opened_at + at)
        if self._inbuf:
            times.append(self._last_rx + 1.0 + 1e-9)
        return min((x for x in times if x is not None), default=None)

    # ---- bytes ------------------------------------------------------------------------
    def _queue(self, data: bytes, ready: float) -> None:
        if self.faults.get("mid_frame") and not self._mid_frame_done and self.streaming:
            self._mid_frame_done = True
            data = data[len(data) // 2:]
        if self.faults.get("wrong_baud"):
            data = bytes(self.rng.randrange(256) for _ in data)
        super()._queue(data, ready)

    def command_timeout(self, t: float) -> None:
        """Answer a command whose bytes stopped coming (A&D E03; MT-SICS: ET)."""
        self.bad_bytes(t)

    def handle(self, data: bytes, t: float) -> None:
        self.advance(t)
        self._last_rx = t
        if any(not (0x20 <= b <= 0x7E or b in (0x0D, 0x0A)) for b in data):
            self._inbuf = b""  # a UART flags parity/framing errors per character
            self.bad_bytes(t)
            return
        self._inbuf += data
        while True:
            idx = min((i for i in (self._inbuf.find(b"\n"), self._inbuf.find(b"\r")) if i >= 0),
                      default=-1)
            if idx < 0:
                break
            line, self._inbuf = self._inbuf[:idx], self._inbuf[idx + 1:]
            if line:
                self.command(line, t)
        if len(self._inbuf) > 64:  # a runaway line without terminator
            self._inbuf = b""
            self.bad_bytes(t)

    def command(self, line: bytes, t: float) -> None:
        """One command line from the host (subclasses)."""

    def bad_bytes(self, t: float) -> None:
        """Answer bytes that are not a command (subclasses)."""

    @staticmethod
    def printable(line: bytes) -> bool:
        return all(0x20 <= b <= 0x7E for b in line)


@register_emulator
class MtSicsEmulator(BalanceEmulator):
    """Mettler Toledo MT-SICS level 0/1 (+ ``SIR``, ``TA``, ``TAC``), 9600 8N1, CR LF.

    Identification as the MT-SICS reference manual gives it: ``I1`` (levels and versions),
    ``I2``, ``I3`` (software version), ``I4`` (serial number), ``I5`` (software ID).
    ``ZI``/``TI`` act at once and say whether the weight was stable (``S``) or not (``D``).
    """

    protocol = "mtsics"
    model = "XS205 DualRange"
    #: replies to I1, I3, I5 (levels 0 and 1 implemented; versions as an XS balance's)
    info_lines: ClassVar[dict[str, str]] = {
        "I1": 'I1 A "01" "2.20" "2.20" "1.00" "1.50"',
        "I3": 'I3 A "4.00 10.28.0.493.142"',
        "I5": 'I5 A "11671158C"',
    }

    def banner(self, t: float) -> None:
        self._queue(f'I4 A "{self.serial_number}"\r\n'.encode("ascii"), t)

    def _weight_line(self, cid: str, status: str, value: float | None) -> bytes:
        if value is None:
            return f"{cid} {status}\r\n".encode("ascii")
        return f"{cid} {status} {value:>10.{self.decimals}f} {self.unit}\r\n".encode("ascii")

    def bad_bytes(self, t: float) -> None:
        self.reply(b"ET\r\n", t, 0.01)

    def command(self, line: bytes, t: float) -> None:
        if not self.printable(line):
            self.bad_bytes(t)
            return
        words = line.decode("ascii").strip().split()
        if not words:
            return
        cmd = words[0]
        tick = self.signal.last
        if self._chance("error_reply"):
            self.reply(b"EL\r\n", t, 0.02)
            return
        if cmd == "@":
            self.streaming = False
            self.pending = []
            self.reply(f'I4 A "{self.serial_number}"\r\n'.encode("ascii"), t, 0.02)
        elif cmd == "I2":
            cap = self.to_unit(self.capacity_n)
            self.reply(f'I2 A "{self.model} {cap:.{self.decimals}f} {self.unit}"\r\n'.encode("ascii"),
                       t, 0.02)
        elif cmd == "I4":
            self.reply(f'I4 A "{self.serial_number}"\r\n'.encode("ascii"), t, 0.02)
        elif cmd in self.info_lines:
            self.reply(self.info_lines[cmd].encode("ascii") + b"\r\n", t, 0.02)
        elif cmd in ("SI", "SIR"):
            self.streaming = cmd == "SIR"
            status, value = self.weigh(tick)
            self.reply(self._weight_line("S", status, value), t, 0.02)
        elif cmd in ("S", "Z", "T"):
            self.streaming = False
            if tick.stable:
                self.complete(Pending(cmd, t), tick, ok=True)
            else:
                self.pending.append(Pending(cmd, t))
        elif cmd in ("ZI", "TI"):
            self.complete(Pending(cmd[0], t), tick, ok=True, immediate=True)
        elif cmd == "TA":
            self.reply(self._weight_line("TA", "A", self.to_unit(self.tare_n)), t, 0.02)
        elif cmd == "TAC":
            self.tare_n = 0.0
            self.reply(b"TAC A\r\n", t, 0.02)
        else:
            self.reply(b"ES\r\n", t, 0.02)

    def complete(self, pending: Pending, tick: Tick, ok: bool, immediate: bool = False) -> None:
        cmd = pending.command
        cid = cmd + ("I" if immediate else "")
        if not ok:
            self.reply(f"{cid} I\r\n".encode("ascii"), tick.t, 0.02)
            return
        status, value = self.weigh(tick)
        if immediate and status not in "+-":  # ZI S / ZI D, TI S / TI D: stable or not
            done = "S" if status == "S" else "D"
            if cmd == "Z":
                self.zero_now(tick)
                self.reply(f"ZI {done}\r\n".encode("ascii"), tick.t, 0.05)
            else:
                self.tare_now(tick)
                self.reply(self._weight_line("TI", done, self.to_unit(self.tare_n)), tick.t, 0.05)
            return
        if cmd == "S":
            status = status if status in "+-" else "S"
            self.reply(self._weight_line("S", status, value), tick.t, 0.02)
        elif cmd == "Z":
            if status in "+-":
                self.reply(f"{cid} {status}\r\n".encode("ascii"), tick.t, 0.02)
            else:
                self.zero_now(tick)
                self.reply(f"{cid} A\r\n".encode("ascii"), tick.t, 0.05)
        elif cmd == "T":
            if status in "+-":
                self.reply(f"{cid} {status}\r\n".encode("ascii"), tick.t, 0.02)
            else:
                self.tare_now(tick)
                self.reply(self._weight_line(cid, "S", self.to_unit(self.tare_n)), tick.t, 0.05)

    def stream_line(self, tick: Tick) -> None:
        status, value = self.weigh(tick)
        self.reply(self._weight_line("S", status, value), tick.t)


@register_emulator
class AndStdEmulator(BalanceEmulator):
    """A&D standard format, 2400 7E1: ``ST``/``US``/``OL`` lines, ACK (0x06) and ``EC,Exx``.

    ``R``/``Z``/``T`` answer ACK on receipt and ACK on completion; command bytes that
    trickle in with more than 1 s between them get ``EC,E03``.
    """

    protocol = "and_std"
    default_rate_hz = 10.0
    serial_settings = {"baudrate": 2400, "bytesize": 7, "parity": "E", "stopbits": 1}
    model = "FX-300i"

    def __post_init__(self) -> None:
        super().__post_init__()
        self.ack_on = self.options.get("ack", "1") not in ("0", "false", "no")

    def _ack(self, t: float, latency: float = 0.01) -> None:
        if self.ack_on:
            self.reply(b"\x06\r\n", t, latency)

    def _data(self, status: str, value: float | None) -> bytes:
        unit = f"{self.unit:>3}"
        if value is None:  # the manuals' overload line (HR-A, FX-i, GX-A): no unit field
            return b"OL,+9999999E+19\r\n" if status == "+" else b"OL,-9999999E+19\r\n"
        header = "ST" if status == "S" else "US"
        digits = f"{abs(value):08.{self.decimals}f}"[-8:]
        sign = "-" if value < 0 and float(digits) != 0 else "+"
        return f"{header},{sign}{digits}{unit}\r\n".encode("ascii")

    def command_timeout(self, t: float) -> None:
        self.reply(b"EC,E03\r\n", t, 0.01)

    def bad_bytes(self, t: float) -> None:
        self.reply(b"EC,E00\r\n", t, 0.01)

    def command(self, line: bytes, t: float) -> None:
        if not self.printable(line):
            self.bad_bytes(t)
            return
        cmd = line.decode("ascii").strip()
        tick = self.signal.last
        if len(cmd) > 16:
            self.reply(b"EC,E04\r\n", t, 0.01)
            return
        if self._chance("error_reply"):
            self.reply(b"EC,E02\r\n", t, 0.02)
            return
        if cmd in ("Q", "SI", "PRT"):
            self.reply(self._data(*self.weigh(tick)), t, 0.03)
        elif cmd == "SIR":
            self.streaming = True
        elif cmd == "S":
            if tick.stable:
                self.complete(Pending("S", t), tick, ok=True)
            else:
                self.pending.append(Pending("S", t))
        elif cmd == "C":
            self.streaming = False
            self.pending = [p for p in self.pending if p.command != "S"]
            self._ack(t)
        elif cmd in ("R", "Z", "T"):
            self._ack(t)
            self.pending.append(Pending("T" if cmd == "T" else "Z", t))
        elif cmd in ("ON", "OFF", "P"):
            self._ack(t)
        elif cmd == "?ID":
            self.reply(b"ID,LAB-0123\r\n", t, 0.03)
        elif cmd == "?SN":
            self.reply(f"SN,{self.serial_number[-8:]}\r\n".encode("ascii"), t, 0.03)
        elif cmd == "?TN":
            self.reply(f"TN,{self.model:>8}\r\n".encode("ascii"), t, 0.03)
        else:
            self.reply(b"EC,E01\r\n", t, 0.01)

    def complete(self, pending: Pending, tick: Tick, ok: bool) -> None:
        if not ok:
            self.reply(b"EC,E11\r\n", tick.t, 0.01)
            return
        status, value = self.weigh(tick)
        if pending.command == "S":
            self.reply(self._data(status, value), tick.t, 0.03)
        elif status in "+-":
            self.reply(b"EC,E17\r\n", tick.t, 0.01)
        else:
            (self.tare_now if pending.command == "T" else self.zero_now)(tick)
            self._ack(tick.t, 0.3)

    def stream_line(self, tick: Tick) -> None:
        self.reply(self._data(*self.weigh(tick)), tick.t)
