"""Cassettes: what went over one serial port, byte-exact, as JSON lines
(docs/explanation/architecture.md#cassettes).

Line 1 is a header::

    {"format": "labkit-cassette", "schema": 2, "labkit_version": "0.1.0",
     "created": "2026-11-22T09:00:00+00:00", "port": "balance", "url": "sim://mtsics?seed=3",
     "serial": {"baudrate": 9600, "bytesize": 8, "parity": "N", "stopbits": 1, "timeout": 1.0},
     "device": {"vid_pid": "0403:6001", "serial_number": "A12", ...}, "clock": "real",
     "clock_origin": 8123.456}

(``clock_origin``, the clock's reading at ``t`` = 0, is written since labkit 0.1.0 of
2026-11-27; the cassettes of one run share that clock, so their events can be put on one
time line.)

Then one event per line, ``t`` in seconds since the port was first opened (on the port's
clock). This is each event as :class:`CassetteReader` gives it back (and as schema 1 wrote
it); schema 2 writes the same events shorter, leaving out what the reader restores and
writing an event that repeats a recent one as ``{"t": T, "r": K}``
(:mod:`labkit.io.cassette_lines`)::

    {"t": 0.0,   "port": "balance", "dir": "ctl", "event": "open", "serial": {...}}
    {"t": 0.001, "port": "balance", "dir": "tx",  "data": "SI\\r\\n", "call": "read"}
    {"t": 0.052, "port": "balance", "dir": "rx",  "data": "S S      12.345 g\\r\\n"}
    {"t": 0.300, "port": "balance", "dir": "rx",  "data": "AP8=", "enc": "b64"}
    {"t": 1.300, "port": "balance", "dir": "ctl", "event": "short_read", "asked": 1, "got": 0}
    {"t": 5.000, "port": "balance", "dir": "ctl", "event": "error", "call": "read",
     "class": "SerialException", "module": "serial.serialutil", "message": "device reports..."}

``data`` is UTF-8 text when every character is printable (or CR, LF, TAB), else base64 with
``"enc": "b64"``. Each ``rx`` event is exactly what one read call returned (chunk-preserving);
``short_read`` follows a read that returned fewer bytes than asked (``got`` 0: a timeout).
A ``tx`` event is written before the bytes go out; if the write fails, an ``error`` event
with ``"tx_recorded": true`` follows it.
Control events: ``open``, ``close``, ``reconfigure``, ``reset_input_buffer``, ``short_read``,
``error``, ``identity``.
"""

from __future__ import annotations

import base64
import binascii
import json
import os
import threading
from collections.abc import Iterator
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from labkit import __version__
from labkit.errors import CassetteError
from labkit.io.cassette_lines import LineDecoder, LineEncoder

FORMAT = "labkit-cassette"
#: the schema this labkit writes (2: compact lines, :mod:`labkit.io.cassette_lines`)
SCHEMA = 2
#: the schemas it reads
SCHEMAS = (1, 2)
DIRECTIONS = ("tx", "rx", "ctl")
CONTROL_EVENTS = (
    "open", "close", "reconfigure", "reset_input_buffer", "short_read", "error", "identity",
)


def is_printable_text(data: bytes) -> bool:
    """True when ``data`` is UTF-8 made of printable characters, CR, LF and TAB only."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        return False
    return all(ch.isprintable() or ch in "\r\n\t" for ch in text)


def encode_data(data: bytes) -> dict[str, str]:
    """``{"data": text}`` for printable bytes, else ``{"data": base64, "enc": "b64"}``."""
    if is_printable_text(data):
        return {"data": data.decode("utf-8")}
    return {"data": base64.b64encode(data).decode("ascii"), "enc": "b64"}


def decode_data(event: dict[str, Any]) -> bytes:
    """The bytes of an event's ``data`` (inverse of :func:`encode_data`)."""
    data = event.get("data", "")
    if event.get("enc") == "b64":
        return base64.b64decode(data, validate=True)
    return data.encode("utf-8")


def make_header(port: str, url: str, serial: dict[str, Any], device: dict[str, Any] | None = None,
                clock: str = "real", clock_origin: float | None = None) -> dict[str, Any]:
    """The header line. ``clock_origin``: the clock's reading at the first open (``t`` = 0),
    so the cassettes of one run share a time base (faithful replay lines them up)."""
    header = {
        "format": FORMAT,
        "schema": SCHEMA,
        "labkit_version": __version__,
        "created": datetime.now(UTC).isoformat(timespec="seconds"),
        "port": port,
        "url": url,
        "serial": serial,
        "device": device or {},
        "clock": clock,
    }
    if clock_origin is not None:
        header["clock_origin"] = clock_origin
    return header


class CassetteWriter:
    """Writes one cassette file (schema 2); thread-safe; every event is flushed at once (a crash
    loses nothing). Events are written as :class:`~labkit.io.cassette_lines.LineEncoder` lines."""

    def __init__(self, path: str | Path, header: dict[str, Any]) -> None:
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._lock = threading.Lock()
        self._file = self.path.open("w", encoding="utf-8")
        self._good_bytes = 0  # length of the file up to its last whole line
        self._encoder = LineEncoder(str(header.get("port", "")))
        self._write_line(json.dumps(header, ensure_ascii=False) + "\n")

    def _write_line(self, line: str) -> None:
        """Append one whole line. On a full disk the torn line is cut off again, the file is
        closed and the OSError raised: what was written stays a valid cassette."""
        try:
            self._file.write(line)
            self._file.flush()
        except OSError:
            fd = self._file.fileno()
            try:
                os.ftruncate(fd, self._good_bytes)
            except OSError:
                pass
            try:
                self._file.close()  # flushing the rest fails again; the file is closed anyway
            except OSError:
                pass
            raise
        self._good_bytes += len(line.encode("utf-8"))

    def event(self, t: float, port: str, direction: str, data: bytes | None = None,
              **fields: Any) -> None:
        """Append one event (``fields`` e.g. ``event="short_read", asked=4, got=0, call="read"``)."""
        body: dict[str, Any] = {"port": port, "dir": direction}
        if data is not None:
            body.update(encode_data(data))
        body.update({k: v for k, v in fields.items() if v is not None})
        with self._lock:
            if not self._file.closed:
                line, token = self._encoder.encode(t, body)
                self._write_line(line)
                self._encoder.commit(token)

    def close(self) -> None:
        with self._lock:
            if not self._file.closed:
                self._file.close()

    def reopen(self) -> None:
        """Append again after :meth:`close` (a port closed and re-opened keeps its cassette)."""
        with self._lock:
            if self._file.closed:
                self._file = self.path.open("a", encoding="utf-8")
                self._good_bytes = self.path.stat().st_size


@dataclass(frozen=True)
class Cassette:
    """A loaded cassette: the header and the events in file order (``data`` decoded to bytes)."""

    path: Path
    header: dict[str, Any]
    events: list[dict[str, Any]]

    @property
    def port(self) -> str:
        return str(self.header.get("port", self.path.stem))


#: A cassette bigger than this is refused before it is read (a long recorded run is ~100 MB).
MAX_CASSETTE_BYTES = 4_000_000_000


def _open_checked(path: Path) -> Any:
    """The cassette opened for reading in binary, after the checks that come before any read."""
    try:
        if path.exists() and not path.is_file():  # /dev/zero, a FIFO: st_size says 0, reading never ends
            raise CassetteError(str(path), 0, "not a regular file (a device, FIFO or folder); a cassette "
                                              "is a text file in the session")
        if path.stat().st_size > MAX_CASSETTE_BYTES:
            raise CassetteError(str(path), 0, f"larger than {MAX_CASSETTE_BYTES} bytes")
        return path.open("rb")
    except OSError as exc:
        raise CassetteError(str(path), 0, f"cannot read cassette: {exc.strerror or exc}") from None


def _text_line(path: Path, number: int, raw: bytes) -> str:
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        raise CassetteError(str(path), number, "not UTF-8 text") from None


class CassetteReader:
    """A cassette read front to back, one event at a time (memory flat in its length).

    ``CassetteReader(path)`` reads and checks the header (:attr:`header`); iterating yields the
    events in file order as schema 1 held them (every key restored, ``data`` decoded to
    ``bytes``, ``line`` the file line). Problems raise CassetteError naming file, line and key.
    Reads schema 1 and 2 (:data:`SCHEMAS`)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self._file = _open_checked(self.path)
        try:
            first = self._file.readline()
            if not first.strip():
                raise CassetteError(str(self.path), 1, "empty file, expected a labkit-cassette header")
            header = _json_line(self.path, 1, _text_line(self.path, 1, first))
            if header.get("format") != FORMAT:
                raise CassetteError(str(self.path), 1,
                                    f"format is {header.get('format')!r}, expected {FORMAT!r}")
            if header.get("schema") not in SCHEMAS:
                raise CassetteError(str(self.path), 1, f"schema {header.get('schema')!r} is not supported "
                                                       f"(this labkit reads schemas {SCHEMAS})")
        except BaseException:
            self._file.close()
            raise
        self.header: dict[str, Any] = header
        self._number = 1

    @property
    def port(self) -> str:
        return str(self.header.get("port", self.path.stem))

    def __iter__(self) -> Iterator[dict[str, Any]]:
        decoder = LineDecoder(self.port) if self.header.get("schema") == 2 else None
        try:
            for raw in self._file:
                self._number += 1
                line = _text_line(self.path, self._number, raw)
                if not line.strip():
                    continue
                obj = _json_line(self.path, self._number, line)
                if decoder is not None:
                    try:
                        obj = decoder.decode(obj)
                    except ValueError as exc:
                        raise CassetteError(str(self.path), self._number, str(exc)) from None
                yield _checked_event(self.path, self._number, obj)
        finally:
            self._file.close()

    def close(self) -> None:
        self._file.close()


def load_cassette(path: str | Path) -> Cassette:
    """Read and validate a whole cassette into memory (:class:`CassetteReader` streams it).
    Problems raise CassetteError naming file, line and key."""
    reader = CassetteReader(path)
    return Cassette(reader.path, reader.header, list(reader))


def _json_line(path: Path, number: int, line: str) -> dict[str, Any]:
    try:
        obj = json.loads(line)
    except json.JSONDecodeError as exc:
        raise CassetteError(str(path), number, f"not JSON: {exc.msg}") from None
    except RecursionError:
        raise CassetteError(str(path), number, "not JSON: nested too deeply") from None
    if not isinstance(obj, dict):
        raise CassetteError(str(path), number, "expected a JSON object")
    return obj


def _checked_event(path: Path, number: int, event: dict[str, Any]) -> dict[str, Any]:
    if not isinstance(event.get("t"), (int, float)):
        raise CassetteError(str(path), number, "key 't': missing or not a number")
    direction = event.get("dir")
    if direction not in DIRECTIONS:
        raise CassetteError(str(path), number, f"key 'dir': {direction!r} is not tx, rx or ctl")
    if direction == "ctl" and event.get("event") not in CONTROL_EVENTS:
        raise CassetteError(str(path), number, f"key 'event': {event.get('event')!r} is not one of "
                                               f"{', '.join(CONTROL_EVENTS)}")
    if direction in ("tx", "rx"):
        if not isinstance(event.get("data"), str):
            raise CassetteError(str(path), number, "key 'data': missing or not a string")
        try:
            event = {**event, "bytes": decode_data(event)}
        except (binascii.Error, ValueError):
            raise CassetteError(str(path), number, "key 'data': invalid base64") from None
    event["line"] = number
    return event
