"""Host an emulator on a real pseudo-terminal, so any program can open it as a serial port.

``PtyHost(emulator)`` opens a pty pair in raw mode and starts a pump thread: bytes the user
writes to ``host.path`` (``/dev/pts/N``) go to ``emulator.receive``, and whatever
``emulator.emit`` produces is written back. When the emulator's ``connected(t)`` turns
False the host closes the pty, so the user's pyserial read or write fails with a real
``SerialException``/``OSError``; when it comes back the device appears under a *new* path
(``host.path`` changes and ``on_reconnect(new_path)`` is called), like a USB adapter that
re-enumerates as another ttyUSB.

Wrong baud: if the emulator declares ``serial_settings`` and the program opens the pty at
another baud rate, bytes are garbled both ways, as on a real wire. (A Linux pty keeps the
baud rate a program sets but forces 8 data bits and no parity, so only the baud rate can be
checked here; ``sim://`` ports check bytesize, parity and stopbits too.)
"""

from __future__ import annotations

import errno
import fcntl
import os
import random
import select
import termios
import threading
import tty
from collections.abc import Callable
from typing import Protocol

from labkit.io.clock import Clock, current_clock
from labkit.io.clocked import garble


class HostedDevice(Protocol):
    """What a pty host serves: bytes in (``receive``), bytes out (``emit``) as functions of
    clock time, and whether the device is plugged in (an emulator of labkit.emulators)."""

    seed: int
    role: str
    protocol: str

    def open(self, t: float) -> None: ...

    def power_on(self, t: float) -> None: ...

    def connected(self, t: float) -> bool: ...

    def receive(self, data: bytes, t: float) -> None: ...

    def emit(self, t: float) -> bytes: ...

    #: the earliest arrival of bytes found waiting after a late wake, set around ``receive``
    arrived_since: float | None


#: termios speed constant -> baud rate
BAUD_OF_SPEED = {
    getattr(termios, name): int(name[1:])
    for name in dir(termios)
    if name.startswith("B") and name[1:].isdigit() and int(name[1:]) > 0
}

#: how often the pump looks at the emulator when nothing arrives (s)
PUMP_PERIOD_S = 0.002
#: a pump wake this long after the last look was late (the process was not scheduled)
LATE_WAKE_S = 0.02


class _Pty:
    """One pty pair. We keep the slave open too, so the master never sees EIO between users."""

    def __init__(self) -> None:
        self.master, self.slave = os.openpty()
        tty.setraw(self.slave)
        tty.setraw(self.master)
        flags = fcntl.fcntl(self.master, fcntl.F_GETFL)
        fcntl.fcntl(self.master, fcntl.F_SETFL, flags | os.O_NONBLOCK)
        self.path = os.ttyname(self.slave)

    def baudrate(self) -> int | None:
        """The baud rate the program on the slave side set (None if unknown)."""
        try:
            return BAUD_OF_SPEED.get(termios.tcgetattr(self.slave)[5])
        except termios.error:
            return None

    def close(self) -> None:
        for fd in (self.master, self.slave):
            try:
                os.close(fd)
            except OSError:
                pass


class PtyHost:
    """Serve ``emulator`` on ``/dev/pts/N`` until :meth:`close`. Use as a context manager too."""

    def __init__(
        self,
        emulator: HostedDevice,
        clock: Clock | None = None,
        on_reconnect: Callable[[str], None] | None = None,
    ) -> None:
        self.emulator = emulator
        self.clock = clock if clock is not None else current_clock()
        self.on_reconnect = on_reconnect
        self.dropped_bytes = 0  # device output lost because nobody read the pty
        self.paths: list[str] = []  # every path this device has had, oldest first
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self._pulled = False  # unplug(): gone until _back_at (None: for good)
        self._back_at: float | None = None
        self._looked_at: float | None = None  # when the pump last looked for host bytes
        self._pty: _Pty | None = _Pty()
        self._spare: _Pty | None = None
        self.path = self._pty.path
        self.paths.append(self.path)
        self.emulator.open(self.clock.now())
        self.error: BaseException | None = None
        self._garble_rng = random.Random(emulator.seed * 7919 + 23)
        self._thread = threading.Thread(target=self._run, name=f"pty-{emulator.role}", daemon=True)
        self._thread.start()

    @property
    def connected(self) -> bool:
        return self._pty is not None

    def unplug(self, back_after_s: float | None = None) -> None:
        """Pull the cable now: the pty hangs up; it comes back under a new path after
        ``back_after_s`` (clock seconds), or never (None). Tests use this instead of a fault
        scheduled at a clock time, which a loaded machine may reach before the test is ready."""
        self._back_at = None if back_after_s is None else self.clock.now() + back_after_s
        self._pulled = True

    # -- pump ---------------------------------------------------------------------------
    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                self._step()
        except BaseException as exc:  # noqa: BLE001 - kept for close() / the caller to see
            self.error = exc

    def _step(self) -> None:
        now = self.clock.now()
        with self._lock:
            if self._pulled:
                if self._pty is not None:
                    self._unplug()
                if self._back_at is None or now < self._back_at:
                    self._stop.wait(PUMP_PERIOD_S)
                    return
                self._pulled = False
                self._replug(now)
                return
            if self._pty is None:
                if self.emulator.connected(now):
                    self._replug(now)
                else:
                    self._stop.wait(PUMP_PERIOD_S)
                    return
            elif not self.emulator.connected(now):
                self._unplug()
                return
            pty = self._pty
            assert pty is not None  # plugged in: _replug made one above if there was none
        ready, _, _ = select.select([pty.master], [], [], PUMP_PERIOD_S)
        now = self.clock.now()
        with self._lock:
            if self._pty is not pty:
                return
            wrong_baud = self.wrong_baud(pty)
            if ready:
                try:
                    data = os.read(pty.master, 4096)
                except OSError as exc:
                    if exc.errno not in (errno.EAGAIN, errno.EIO):
                        raise
                    data = b""
                if data:
                    # bytes found waiting after a late wake may have come any time since the pump
                    # last looked: a device's command timeout must not count that wait against
                    # the host (motor emulators read ``arrived_since``)
                    self.emulator.arrived_since = self._arrived_since(now)
                    self.emulator.receive(garble(data, self._garble_rng) if wrong_baud else data, now)
                    self.emulator.arrived_since = None
            out = self.emulator.emit(now)
            if out:
                self._write(pty, garble(out, self._garble_rng) if wrong_baud else out)
            self._looked_at = now

    def _arrived_since(self, now: float) -> float | None:
        """After a late wake (this process was not scheduled for a while) the earliest time
        bytes found waiting could have arrived: when the pump last looked; None after a prompt
        wake (they arrived just now). A real device reads its UART as bytes come: commands sent
        on time must not look late to its command timeout because the emulator was starved."""
        looked = self._looked_at
        return looked if looked is not None and now - looked > LATE_WAKE_S else None

    def wrong_baud(self, pty: _Pty) -> bool:
        """True when the emulated device expects another baud rate than the program set."""
        expected = (getattr(self.emulator, "serial_settings", None) or {}).get("baudrate")
        if expected is None:
            return False
        actual = pty.baudrate()
        return actual is not None and actual != expected

    def _write(self, pty: _Pty, data: bytes) -> None:
        view = memoryview(data)
        while view:
            try:
                n = os.write(pty.master, view)
            except BlockingIOError:
                self.dropped_bytes += len(view)  # like a UART whose host buffer overflowed
                return
            view = view[n:]

    def _unplug(self) -> None:
        """Device gone: reserve the next pty first (so the new path differs), then hang up."""
        assert self._pty is not None
        self._spare = _Pty()
        self._pty.close()
        self._pty = None

    def _replug(self, now: float) -> None:
        self._pty, self._spare = (self._spare or _Pty()), None
        self.path = self._pty.path
        self.paths.append(self.path)
        self.emulator.power_on(now)
        if self.on_reconnect is not None:
            self.on_reconnect(self.path)

    # -- life cycle ---------------------------------------------------------------------
    def close(self) -> None:
        """Stop the pump and release the pty (idempotent)."""
        self._stop.set()
        if self._thread.is_alive() and threading.current_thread() is not self._thread:
            self._thread.join(timeout=2.0)
        with self._lock:
            for pty in (self._pty, self._spare):
                if pty is not None:
                    pty.close()
            self._pty = self._spare = None

    def __enter__(self) -> PtyHost:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return f"PtyHost({self.emulator.protocol!r}, path={self.path!r})"
