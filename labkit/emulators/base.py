"""Emulators: byte-level stand-ins for real devices, driven by a shared seeded plant.

An :class:`Emulator` sees the host's bytes (``receive``) and produces the device's bytes
(``emit``) as a function of clock time, so the same object can sit behind a ``sim://``
port (virtual or real clock) or a pseudo-terminal (``labkit emulate``). Emulators carry
their *own* formatting code: they must not share parsing code with the drivers in a way
that would hide a protocol bug (docs/explanation/architecture.md#emulators-speak-the-bytes).

Faults are switchable and seeded (docs/explanation/device-rules.md#emulator-faults), given as
``faults=name:value,...`` in
the ``sim://`` URL and parsed by :func:`parse_faults`. Every emulator understands the common
ones handled here; protocol-specific ones are documented on each emulator.
"""

from __future__ import annotations

import random
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar

from labkit.emulators.rig_plant import RigPlant

#: pyserial's POSIX message when a USB adapter is unplugged mid-read
#: (docs/explanation/device-rules.md#unplugged-adapters)
DISCONNECT_MESSAGE = (
    "device reports readiness to read but returned no data "
    "(device disconnected or multiple access on port?)"
)

COMMON_FAULTS = {
    "garbage": "probability per emitted chunk of inserting 1-8 junk bytes (0x00/0xFF/random)",
    "split": "probability of splitting an emitted chunk into two reads",
    "drop_reply": "probability of not answering a command at all",
    "delay": "extra reply latency in seconds",
    "disconnect_at": "clock time (s after open) at which the device disappears",
    "reconnect_after": "seconds after a disconnect at which it comes back (power-on state)",
    "wrong_baud": "1: the host's bytes are received as if at the wrong baud (all garbled)",
}

#: protocol-specific fault knobs (documented on each emulator module); with COMMON_FAULTS
#: the only names :func:`parse_faults` accepts, so a typo cannot silently test nothing
PROTOCOL_FAULTS = {
    "overload": "balances, tachometers, motor controllers: over-range / over-temperature",
    "underload": "balances: probability per weight reply of an underload reply",
    "unstable": "balances: probability a reply is forced dynamic",
    "error_reply": "balances, labkit-tach, labkit-strobe: probability a command gets an error reply",
    "reset_at": "s after open of a device reset (power-on state)",
    "stop_at": "streaming devices: s after open at which the output stops (meter switched off, "
               "cable pulled at the meter); the port stays open",
    "mid_frame": "the first bytes after open are the tail of a frame/line",
    "noisy": "labkit-tach, labkit-strobe: probability per line of a rejected glitch",
    "low_vin": "Pololu SMC: low-VIN error",
    "fault_code": "VESC: report this fault code and refuse to run",
    "zero_at": "tachometers: s after open from which the meter reads 0 (target lost; labkit-tach: "
               "lines of 0 RPM with the zero flag Z)",
    "stuck_at": "tachometers: s after open from which the value stays what it was (labkit-tach: the "
                "sequence number and time still advance; Lutron, Monarch: the same frame)",
    "repeat_at": "tachometers: s after open from which the same line/frame is sent again and again "
                 "(labkit-tach: its sequence number too)",
    "lag_s": "tachometers: the reading shows the speed of this many seconds ago",
    "stall_at": "motor controllers: s after open from which the motor does not follow its command "
                "(rotor jammed: it stops whatever the duty)",
}
#: faults that ``labkit emulate --fault-on-usr2 ROLE:NAME`` can start at the signal (NAME_at = now)
TIMED_FAULTS = ("zero", "stuck", "repeat", "stop", "stall", "disconnect", "reset")
KNOWN_FAULTS = frozenset(COMMON_FAULTS) | frozenset(PROTOCOL_FAULTS)


def parse_faults(text: str | None) -> dict[str, float]:
    """Parse ``"garbage:0.1,disconnect_at:5"`` (also ``=`` or ``;``) into a dict of floats.

    A bare name means 1 (``"overload"`` -> ``{"overload": 1.0}``). Raises ValueError naming
    the bad item, also for a name outside :data:`KNOWN_FAULTS` (a mistyped fault would
    otherwise run a clean emulator).
    """
    out: dict[str, float] = {}
    if not text:
        return out
    for item in text.replace(";", ",").split(","):
        item = item.strip()
        if not item:
            continue
        sep = ":" if ":" in item else ("=" if "=" in item else None)
        name, _, value = item.partition(sep) if sep else (item, "", "1")
        if name.strip() not in KNOWN_FAULTS:
            raise ValueError(f"unknown fault {name.strip()!r}; known: {', '.join(sorted(KNOWN_FAULTS))}")
        try:
            out[name.strip()] = float(value)
        except ValueError:
            raise ValueError(f"fault {name.strip()!r}: {value!r} is not a number") from None
    return out


@dataclass
class Emulator:
    """Base of all emulators. Subclasses implement ``handle`` (commands) and ``produce``.

    * ``receive(data, t)``: host -> device bytes arriving at time ``t``.
    * ``emit(t)``: device -> host bytes that are ready at time ``t`` (the port calls it
      whenever the host reads or asks ``in_waiting``).
    * ``connected(t)``: False while unplugged; the port then raises SerialException with
      :data:`DISCONNECT_MESSAGE`.
    """

    protocol: ClassVar[str] = ""
    kind: ClassVar[str] = ""

    plant: RigPlant
    seed: int = 0
    faults: dict[str, float] = field(default_factory=dict)
    role: str = ""
    #: protocol-specific options from the sim:// query string or the rig file (strings)
    options: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.rng = random.Random(self.seed)
        self._outbox: list[tuple[float, bytes]] = []  # (ready time, bytes)
        self._opened_at: float | None = None
        self.power_on_count = 0
        #: set by a pty host around ``receive`` when it found bytes waiting after a late wake:
        #: the earliest time they could have arrived (labkit.io.pty_host)
        self.arrived_since: float | None = None

    # ---- life cycle -------------------------------------------------------------------
    def open(self, t: float) -> None:
        if self._opened_at is None:
            self._opened_at = t
            self.power_on(t)

    def power_on(self, t: float) -> None:
        """Reset to the power-on state (subclasses add banners, safe-start...)."""
        self.power_on_count += 1

    def since_open(self, t: float) -> float:
        return t - (self._opened_at if self._opened_at is not None else t)

    def fault_on(self, name: str, t: float) -> bool:
        """True once the time-triggered fault ``name`` (``zero_at``, ...) has begun at ``t``."""
        at = self.faults.get(name)
        return at is not None and self._opened_at is not None and self.since_open(t) >= at

    def start_fault(self, name: str, t: float) -> None:
        """Start the time-triggered fault ``name`` (``zero``, ``stall``...) now, from outside
        (``labkit emulate --fault-on-usr2``): ``NAME_at`` becomes the time since open."""
        if name not in TIMED_FAULTS:
            raise ValueError(f"fault {name!r} cannot be started on a signal; "
                             f"use one of {', '.join(TIMED_FAULTS)}")
        self.faults[f"{name}_at"] = max(0.0, self.since_open(t))

    def connected(self, t: float) -> bool:
        at = self.faults.get("disconnect_at")
        if at is None or self.since_open(t) < at:
            return True
        back = self.faults.get("reconnect_after")
        return back is not None and self.since_open(t) >= at + back

    # ---- bytes ------------------------------------------------------------------------
    def receive(self, data: bytes, t: float) -> None:
        if self.faults.get("wrong_baud"):
            data = bytes(self.rng.randrange(256) for _ in data)
        self.handle(data, t)

    def handle(self, data: bytes, t: float) -> None:
        """Process host bytes (subclasses). Use ``reply`` to answer."""

    def produce(self, t: float) -> None:
        """Queue unsolicited output due up to ``t`` (streaming devices)."""

    def reply(self, data: bytes, t: float, latency: float = 0.0) -> None:
        """Queue ``data`` to be readable at ``t + latency`` (+ the ``delay`` fault)."""
        if self.rng.random() < self.faults.get("drop_reply", 0.0):
            return
        self._queue(data, t + latency + self.faults.get("delay", 0.0))

    def _queue(self, data: bytes, ready: float) -> None:
        garbage = self.faults.get("garbage", 0.0)
        if garbage and self.rng.random() < garbage:
            junk = bytes(self.rng.choice((0x00, 0xFF, self.rng.randrange(256)))
                         for _ in range(self.rng.randint(1, 8)))
            data = junk + data if self.rng.random() < 0.5 else data + junk
        split = self.faults.get("split", 0.0)
        if split and len(data) > 1 and self.rng.random() < split:
            cut = self.rng.randint(1, len(data) - 1)
            self._outbox.append((ready, data[:cut]))
            self._outbox.append((ready + 0.002, data[cut:]))
        else:
            self._outbox.append((ready, data))

    def emit(self, t: float) -> bytes:
        self.produce(t)
        ready = [c for c in self._outbox if c[0] <= t]
        if not ready:
            return b""
        self._outbox = [c for c in self._outbox if c[0] > t]
        ready.sort(key=lambda c: c[0])
        return b"".join(c[1] for c in ready)

    def next_ready_time(self) -> float | None:
        """When the next queued byte becomes readable (None if nothing is queued)."""
        return min((c[0] for c in self._outbox), default=None)

    def next_output_time(self, t: float) -> float | None:
        """Earliest clock time at which ``emit`` may return new bytes, if known.

        The base knows only queued replies. Streaming emulators override this to include
        their next unsolicited frame; a ``sim://`` port on a virtual clock then jumps straight
        there instead of polling in small steps (labkit.emulators.sim_port).
        """
        return self.next_ready_time()


_EMULATORS: dict[str, type[Emulator]] = {}


def register_emulator(cls: type[Emulator]) -> type[Emulator]:
    """Class decorator: make ``cls`` available as ``sim://<cls.protocol>``."""
    _EMULATORS[cls.protocol] = cls
    return cls


def emulator_class(protocol: str) -> type[Emulator]:
    import importlib

    # importing a module registers its emulators
    for name in ("balances", "hx711_sketch", "motors", "vesc_emulator", "tachometers", "strobes"):
        module_name = f"labkit.emulators.{name}"
        try:
            importlib.import_module(module_name)
        except ModuleNotFoundError as exc:  # a module not written yet must not hide the others
            if exc.name != module_name:
                raise

    try:
        return _EMULATORS[protocol]
    except KeyError:
        raise KeyError(f"no emulator {protocol!r}; known: {', '.join(sorted(_EMULATORS))}") from None


class SketchLines:
    """Host command lines to an emulated labkit sketch (``labkit_tach``, ``labkit_strobe``):
    bytes sent during its boot or while its cable is out are lost, a line longer than the
    sketch's buffer (``line_max``) is dropped, and each whole line goes to ``_command``. The
    emulator sets ``_line`` (a bytearray) and ``_boot_end``. The ``error_reply`` fault answers
    a command ``ERR busy`` before ``_command`` sees it."""

    line_max = 64
    _line: bytearray
    _boot_end: float
    connected: Callable[[float], bool]  # Emulator's: the cable is in at t
    _command: Callable[[str, float], None]  # each sketch's: one command line at t
    rng: random.Random
    faults: dict[str, Any]
    reply: Callable[..., None]

    def handle(self, data: bytes, t: float) -> None:
        if t < self._boot_end or not self.connected(t):
            return  # the bootloader (or an unplugged cable) eats the bytes
        self._line += data
        while b"\n" in self._line:
            raw, _, rest = bytes(self._line).partition(b"\n")
            self._line = bytearray(rest)
            text = raw.strip().decode("ascii", "replace")
            if not text:
                continue
            if self.rng.random() < self.faults.get("error_reply", 0.0):
                self.reply(b"ERR busy\n", t, 0.001)
                continue
            self._command(text, t)
        if len(self._line) > self.line_max:
            self._line.clear()
