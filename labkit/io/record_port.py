"""``record://<inner-url>?cassette=PATH&port=NAME``: a port that tees every byte to a cassette.

Wraps *any* port URL (a real device, ``hwgrep://``, ``sim://``, a pty path). Each read call
becomes one ``rx`` event holding exactly what it returned (plus ``short_read`` when it
returned fewer bytes than asked, including empty reads on timeout); each write is a ``tx``
event; open, close, reconfigure, reset_input_buffer and errors are ``ctl`` events. See
:mod:`labkit.io.cassette` for the format.
"""

from __future__ import annotations

from typing import Any

import serial
from serial.serialutil import to_bytes

from labkit.io.calls import current_call, current_thread_tag
from labkit.io.cassette import CassetteWriter, make_header
from labkit.io.clocked import ClockedSerial
from labkit.io.urls import parse_record_url

#: exceptions a port raises for wire trouble (recorded, then re-raised)
WIRE_ERRORS = (serial.SerialException, OSError)


def usb_identity(device_path: str) -> dict[str, Any]:
    """VID:PID, serial number, manufacturer... of a native serial device, or {} if unknown."""
    try:
        from serial.tools import list_ports

        for info in list_ports.comports():
            if info.device == device_path and info.vid is not None:
                return {
                    "vid_pid": f"{info.vid:04X}:{info.pid:04X}",
                    "serial_number": info.serial_number,
                    "manufacturer": info.manufacturer,
                    "product": info.product,
                    "description": info.description,
                    "location": info.location,
                }
    except Exception:  # noqa: BLE001 - identity is a nicety; recording must not fail on it
        return {}
    return {}


def error_fields(exc: BaseException, call: str) -> dict[str, Any]:
    """The ``error`` control event's fields for an exception."""
    return {
        "event": "error",
        "call": call,
        "class": type(exc).__name__,
        "module": type(exc).__module__,
        "message": str(exc),
        "errno": getattr(exc, "errno", None),
    }


class RecordSerial(ClockedSerial):
    """A recording port. ``inner`` is the wrapped port; ``cassette_path`` where events go."""

    def __init__(self, *args, **kwargs) -> None:
        self.inner: serial.SerialBase | None = None
        self.writer: CassetteWriter | None = None
        self.port_name = ""
        self.cassette_path = ""
        self._t0: float | None = None
        self._failed = False  # after the first wire error of a session nothing more is recorded
        #: why recording stopped (disk full, permissions...): the wire keeps working without it
        self.record_error: str | None = None
        #: the clock reading of the last read that returned bytes, as its cassette holds it (so a
        #: driver timestamps what it read as a faithful replay will: :func:`labkit.io.calls.read_time`)
        self.read_at: float | None = None
        super().__init__(*args, **kwargs)

    # -- events -------------------------------------------------------------------------
    def _event(self, direction: str, data: bytes | None = None, now: float | None = None,
               **fields: Any) -> None:
        """Record one event (at ``now``, default the clock's reading). A cassette that cannot be
        written (disk full) never stops the wire: the failure is kept in ``record_error`` for
        the runner to stop the run safely."""
        if self.writer is not None and not self._failed and self.record_error is None:
            assert self._t0 is not None and self.clock is not None
            t = (self.clock.now() if now is None else now) - self._t0
            try:
                self.writer.event(t, self.port_name, direction, data, th=current_thread_tag(), **fields)
            except OSError as exc:
                self.record_error = f"cannot write {self.cassette_path}: {exc.strerror or exc}"

    def _error(self, exc: BaseException, call: str, **extra: Any) -> None:
        """Record the session's first wire error; a dead port's later failures add nothing."""
        self._event("ctl", **error_fields(exc, current_call(call)), **extra)
        self._failed = True

    def note_identity(self, identity: dict[str, Any]) -> None:
        """Store what the driver learned about the device (model, serial...) in the cassette."""
        self._event("ctl", event="identity", identity=identity)

    # -- life cycle ---------------------------------------------------------------------
    def open(self) -> None:
        self._require_openable()
        from labkit.io.ports import open_port

        spec = parse_record_url(self.portstr)
        clock = self._resolve_clock()
        if self.writer is None:
            self.port_name, self.cassette_path = spec.port, spec.cassette
            self._t0 = clock.now()
            identity = usb_identity(spec.inner_url)
            self.writer = CassetteWriter(spec.cassette, make_header(
                spec.port, spec.inner_url, self.settings_summary(), identity,
                clock="virtual" if clock.is_virtual else "real", clock_origin=self._t0,
            ))
        else:
            self.writer.reopen()
        self._failed = False
        self._event("ctl", event="open", serial=self.settings_summary())
        try:
            self.inner = open_port(spec.inner_url, clock=clock, **self.get_settings())
        except WIRE_ERRORS as exc:
            self._error(exc, "open")
            raise
        self.is_open = True

    def close(self) -> None:
        if self.inner is not None:
            try:
                self.inner.close()
            finally:
                self.inner = None
                self._failed = False  # the close itself is always recorded
                self._event("ctl", event="close", call=current_call("close"))
        if self.writer is not None:
            try:
                self.writer.close()
            except OSError as exc:
                self.record_error = self.record_error or f"cannot write {self.cassette_path}: {exc}"
        self.is_open = False

    def _reconfigure_port(self) -> None:
        if self.inner is not None and self.is_open:
            self.inner.apply_settings(self.get_settings())
            self._event("ctl", event="reconfigure", serial=self.settings_summary())

    # -- modem lines go through to the wrapped port (DTR resets an Arduino) --------------
    def _update_dtr_state(self) -> None:
        if self.inner is not None and self.is_open:
            self.inner.dtr = self._dtr_state

    def _update_rts_state(self) -> None:
        if self.inner is not None and self.is_open:
            self.inner.rts = self._rts_state

    def _update_break_state(self) -> None:
        if self.inner is not None and self.is_open:
            self.inner.break_condition = self._break_state

    # modem status lines: the inner port's
    cts = property(lambda self: self._live().cts)
    dsr = property(lambda self: self._live().dsr)
    ri = property(lambda self: self._live().ri)
    cd = property(lambda self: self._live().cd)

    def _live(self) -> serial.SerialBase:
        self._require_open()
        assert self.inner is not None
        return self.inner

    # -- traffic ------------------------------------------------------------------------
    def write(self, data: bytes) -> int:
        """Record, then write: a reply read by another thread can never precede its command
        in the cassette. A failed write is followed by its ``error`` (``tx_recorded``). A
        failed *recording* never keeps the bytes off the wire (a STOP is always sent)."""
        inner = self._live()
        data = to_bytes(data)
        self._event("tx", data, call=current_call("write"))
        try:
            return inner.write(data)
        except WIRE_ERRORS as exc:
            self._error(exc, "write", tx_recorded=True)
            raise

    def read(self, size: int = 1) -> bytes:
        inner = self._live()
        try:
            data = inner.read(size)
        except WIRE_ERRORS as exc:
            self._error(exc, "read")
            raise
        self._note_read(data, size, len(data) < size, "read")
        return data

    def read_until(self, expected: bytes = b"\n", size: int | None = None) -> bytes:
        inner = self._live()
        try:
            data = inner.read_until(expected, size)
        except WIRE_ERRORS as exc:
            self._error(exc, "read_until")
            raise
        short = not data.endswith(expected) and (size is None or len(data) < size)
        self._note_read(data, size, short, "read_until")
        return data

    def _note_read(self, data: bytes, asked: int | None, short: bool, call: str) -> None:
        if data:
            self.read_at = now = self._resolve_clock().now()
            self._event("rx", data, now, call=current_call(call))
        if short:
            self._event("ctl", event="short_read", asked=asked, got=len(data),
                        call=current_call(call))

    @property
    def in_waiting(self) -> int:
        inner = self._live()
        try:
            return inner.in_waiting
        except WIRE_ERRORS as exc:
            self._error(exc, "in_waiting")
            raise

    def reset_input_buffer(self) -> None:
        inner = self._live()
        try:
            inner.reset_input_buffer()
        except WIRE_ERRORS as exc:
            self._error(exc, "reset_input_buffer")
            raise
        self._event("ctl", event="reset_input_buffer", call=current_call("reset_input_buffer"))

    def reset_output_buffer(self) -> None:
        self._live().reset_output_buffer()


def serial_class_for_url(url: str) -> tuple[str, type[RecordSerial]]:
    """pyserial hook (``labkit.io.urlhandlers.protocol_record``)."""
    parse_record_url(url)
    return url, RecordSerial
