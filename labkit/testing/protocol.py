"""A driver against a list of byte pairs, in memory: PyMeasure's ``expected_protocol`` for labkit.

::

    from labkit.devices.balance.mtsics import MtSicsBalance
    from labkit.testing import expected_protocol

    with expected_protocol(MtSicsBalance, [
        (b"@\\r\\n", b'I4 A "B207696838"\\r\\n'),      # the driver resets the balance on open
        (b"S\\r\\n", b"S S      12.34 g\\r\\n"),
    ]) as balance:
        assert balance.read_stable().value == 0.01234

Each pair is ``(what the driver must write, what the device answers)``. ``None`` as the first
element is output the device gives unasked (a banner, a stream line), queued as soon as the
exchanges before it are done; ``None`` as the second is no answer. The exchange is strict:
a write that differs from the next expected bytes fails at once (:class:`ProtocolMismatch`,
naming the exchange and both byte strings), and leaving the block with exchanges not done or
answers never read fails too. No plant, no emulator, no clock fixture: the driver runs on its
own :class:`~labkit.io.clock.VirtualClock` (a read with nothing to read times out instantly).
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from serial.serialutil import to_bytes

from labkit.io.clock import Clock, VirtualClock
from labkit.io.clocked import ClockedSerial

Pair = tuple[bytes | None, bytes | None]


class ProtocolMismatch(AssertionError):
    """The driver did not speak the expected protocol (wrong bytes, too few, too many)."""


class ExchangePort(ClockedSerial):
    """An in-memory port that answers the byte pairs it was given, in order, and nothing else."""

    def __init__(self, pairs: Sequence[Pair], clock: Clock, timeout: float = 0.5, **settings: Any) -> None:
        self.pairs = [(None if w is None else bytes(w), None if r is None else bytes(r)) for w, r in pairs]
        self.done = 0                       # exchanges completed
        self._written = bytearray()         # bytes of the exchange in progress
        self._rx = bytearray()
        self.log: list[tuple[str, bytes]] = []   # ("write"|"read", bytes), for messages
        super().__init__(port="expected-protocol://", timeout=timeout, **settings)
        self.clock = clock

    # ---- life cycle ---------------------------------------------------------------------
    def open(self) -> None:
        self._require_openable()
        self.is_open = True
        self._queue_unasked()

    def close(self) -> None:
        self.is_open = False

    # ---- the device side ----------------------------------------------------------------
    def _queue_unasked(self) -> None:
        while self.done < len(self.pairs) and self.pairs[self.done][0] is None:
            self._rx += self.pairs[self.done][1] or b""
            self.done += 1

    def _expected(self) -> bytes | None:
        return self.pairs[self.done][0] if self.done < len(self.pairs) else None

    def write(self, data: bytes) -> int:
        self._require_open()
        data = to_bytes(data)
        self.log.append(("write", data))
        self._written += data
        while self._written:
            expected = self._expected()
            if expected is None:
                raise ProtocolMismatch(f"after the last of {len(self.pairs)} exchanges the driver wrote "
                                       f"{bytes(self._written)!r}")
            if self._written.startswith(expected):
                del self._written[:len(expected)]
                self._rx += self.pairs[self.done][1] or b""
                self.done += 1
                self._queue_unasked()
            elif expected.startswith(self._written):
                break                       # the rest of the command is still to come
            else:
                raise ProtocolMismatch(f"exchange {self.done}: expected the driver to write {expected!r}, "
                                       f"it wrote {bytes(self._written)!r}")
        return len(data)

    @property
    def in_waiting(self) -> int:
        self._require_open()
        return len(self._rx)

    def reset_input_buffer(self) -> None:
        self._require_open()
        self._rx.clear()

    def read(self, size: int = 1) -> bytes:
        self._require_open()
        if not self._rx and self._timeout:
            self._resolve_clock().sleep(self._timeout)   # nothing will come: time out
        out = bytes(self._rx[:size])
        del self._rx[:size]
        if out:
            self.log.append(("read", out))
        return out

    def check_finished(self) -> None:
        """Raise :class:`ProtocolMismatch` unless every exchange happened and was read."""
        if self._written and self._expected() is None:
            raise ProtocolMismatch(f"after the last of {len(self.pairs)} exchanges the driver wrote "
                                   f"{bytes(self._written)!r}")
        if self._written:
            raise ProtocolMismatch(f"exchange {self.done}: the driver wrote only {bytes(self._written)!r} "
                                   f"of {self._expected()!r}")
        if self.done < len(self.pairs):
            missing = [w for w, _ in self.pairs[self.done:]]
            raise ProtocolMismatch(f"{len(missing)} expected exchange(s) never happened, "
                                   f"next: {missing[0]!r}")
        if self._rx:
            raise ProtocolMismatch(f"the driver never read {bytes(self._rx)!r}")


@contextmanager
def expected_protocol(driver_class: type, pairs: Sequence[Pair], *, name: str = "", timeout: float = 0.5,
                      clock: Clock | None = None, **options: Any) -> Iterator[Any]:
    """``driver_class(port, clock, name, **options)`` on an :class:`ExchangePort` of ``pairs``;
    on leaving the block the driver is closed and the exchange checked complete."""
    the_clock = clock if clock is not None else VirtualClock()
    port = ExchangePort(pairs, the_clock, timeout=timeout, **getattr(driver_class, "default_serial", {}))
    driver = driver_class(port, the_clock, name=name or getattr(driver_class, "protocol", ""), **options)
    failed = False
    try:
        yield driver
    except BaseException:
        failed = True
        raise
    finally:
        driver.close()
        if not failed:
            port.check_finished()
