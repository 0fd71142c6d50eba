"""``sim://`` ports: an emulator served as a ``serial.SerialBase`` on any clock.

``write`` hands bytes to ``emulator.receive(data, clock.now())``; ``read``/``in_waiting``
collect ``emulator.emit(clock.now())``. A read with a timeout waits on the clock: on a
:class:`~labkit.io.clock.VirtualClock` it jumps to the emulator's next output time (no
wall time passes), on a real clock it polls with short sleeps.

Faults that belong to the wire are done here:

* disconnect: while ``emulator.connected(t)`` is False every read, write and ``in_waiting``
  raises ``serial.SerialException`` with pyserial's POSIX unplug message; the handle stays
  dead (like a real unplugged adapter) until it is closed and re-opened after the emulator
  reconnects, which power-cycles the emulator;
* wrong serial settings: if the emulator declares ``serial_settings`` (e.g. A&D's
  ``{"baudrate": 2400, "bytesize": 7, "parity": "E"}``) and the port is opened with others,
  bytes are garbled both ways, as on a real wire.
"""

from __future__ import annotations

import random
import threading
from typing import Any

import serial
from serial.serialutil import to_bytes

from labkit.emulators.base import DISCONNECT_MESSAGE, Emulator, emulator_class
from labkit.emulators.plant import shared_plant
from labkit.emulators.urls import parse_sim_url
from labkit.errors import PortURLError
from labkit.io.clocked import LINE_SETTINGS, REAL_POLL_S, VIRTUAL_POLL_S, ClockedSerial, garble, poll_step


def build_emulator(url: str) -> Emulator:
    """The emulator a ``sim://`` URL describes, on its plant in the current emulation
    (:func:`labkit.emulators.plant.current_emulation`)."""
    spec = parse_sim_url(url)
    try:
        cls = emulator_class(spec.protocol)
    except KeyError as exc:
        raise PortURLError(url, str(exc.args[0])) from None
    return cls(
        plant=shared_plant(spec.plant),
        seed=spec.seed,
        faults=dict(spec.faults),
        role=spec.role,
        options=dict(spec.options),
    )


def settings_mismatch(expected: dict[str, Any] | None, actual: dict[str, Any]) -> dict[str, tuple]:
    """``{name: (expected, actual)}`` for each line setting the device expects differently."""
    if not expected:
        return {}
    return {
        key: (expected[key], actual.get(key))
        for key in LINE_SETTINGS
        if key in expected and expected[key] != actual.get(key)
    }


def emulator_wake_time(emulator: Emulator, now: float) -> float | None:
    """When something may change: next output (if the emulator knows it) or a disconnect."""
    candidates = []
    knows_streams = type(emulator).next_output_time is not Emulator.next_output_time
    nxt = emulator.next_output_time(now)
    if nxt is not None:
        candidates.append(nxt)
    if not knows_streams:
        candidates.append(now + VIRTUAL_POLL_S)
    at = emulator.faults.get("disconnect_at")
    opened = getattr(emulator, "_opened_at", None)
    if at is not None and opened is not None and opened + at > now:
        candidates.append(opened + at)
    future = [c for c in candidates if c > now]
    return min(future) if future else None


class SimSerial(ClockedSerial):
    """A ``sim://`` port. The emulator is kept across close/open (a re-plug, not a new device)."""

    def __init__(self, *args, **kwargs) -> None:
        self.emulator: Emulator | None = None
        self._rx = bytearray()
        self._lock = threading.RLock()
        self._dead = False
        self._garble_rng: random.Random | None = None
        self.mismatched_settings: dict[str, tuple] = {}
        super().__init__(*args, **kwargs)

    # -- life cycle ---------------------------------------------------------------------
    def open(self) -> None:
        self._require_openable()
        clock = self._resolve_clock()
        now = clock.now()
        with self._lock:
            if self.emulator is None:
                self.emulator = build_emulator(self.portstr)
                self.emulator.open(now)
            elif self._dead and self.emulator.connected(now):
                self.emulator.power_on(now)
            if not self.emulator.connected(now):
                raise serial.SerialException(
                    f"could not open port {self.portstr}: [Errno 2] No such file or directory"
                )
            self._dead = False
            self._rx.clear()
            self.is_open = True
            self._reconfigure_port()

    def close(self) -> None:
        self.is_open = False

    def _reconfigure_port(self) -> None:
        if self.emulator is None:
            return
        expected = getattr(self.emulator, "serial_settings", None)
        self.mismatched_settings = settings_mismatch(expected, self.settings_summary())
        self._garble_rng = (
            random.Random(self.emulator.seed * 7919 + 17) if self.mismatched_settings else None
        )

    # -- wire ---------------------------------------------------------------------------
    def _check_connected(self, now: float) -> None:
        assert self.emulator is not None
        if self._dead or not self.emulator.connected(now):
            self._dead = True
            raise serial.SerialException(DISCONNECT_MESSAGE)

    def _pull(self, now: float) -> None:
        assert self.emulator is not None
        self._check_connected(now)
        data = self.emulator.emit(now)
        if data and self._garble_rng is not None:
            data = garble(data, self._garble_rng)
        self._rx += data

    @property
    def in_waiting(self) -> int:
        self._require_open()
        with self._lock:
            self._pull(self._resolve_clock().now())
            return len(self._rx)

    def write(self, data: bytes) -> int:
        self._require_open()
        data = to_bytes(data)
        with self._lock:
            now = self._resolve_clock().now()
            self._check_connected(now)
            assert self.emulator is not None
            wire = garble(data, self._garble_rng) if self._garble_rng is not None else data
            self.emulator.receive(wire, now)
        return len(data)

    def reset_input_buffer(self) -> None:
        self._require_open()
        with self._lock:
            self._pull(self._resolve_clock().now())
            self._rx.clear()

    def read(self, size: int = 1) -> bytes:
        self._require_open()
        clock = self._resolve_clock()
        deadline = None if self._timeout is None else clock.now() + self._timeout
        while True:
            with self._lock:
                now = clock.now()
                self._pull(now)
                if len(self._rx) >= size or self._timeout == 0:
                    break
                if deadline is not None and now >= deadline:
                    break
                assert self.emulator is not None
                wake = emulator_wake_time(self.emulator, now)
            if clock.is_virtual:
                target = wake if wake is not None else now + VIRTUAL_POLL_S
                if deadline is not None:
                    target = min(target, deadline)
                clock.sleep_until(target)
            else:
                clock.sleep(poll_step(REAL_POLL_S, now, deadline))
        with self._lock:
            out = bytes(self._rx[:size])
            del self._rx[:size]
        return out


def serial_class_for_url(url: str) -> tuple[str, type[SimSerial]]:
    """pyserial hook (``labkit.emulators.urlhandlers.protocol_sim``)."""
    parse_sim_url(url)  # fail early, with the URL in the message
    return url, SimSerial
