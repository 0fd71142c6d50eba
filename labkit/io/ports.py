"""Opening ports from URLs: the one seam between drivers and wires
(docs/explanation/architecture.md#the-port-url-is-the-seam).

``open_port(url, clock=..., baudrate=..., timeout=...)`` accepts everything
``serial.serial_for_url`` does (device paths, ``socket://``, ``loop://``, ``hwgrep://``, pty
paths) plus the schemes of the URL-handler packages registered with pyserial
(``serial.protocol_handler_packages``):

* ``record://<inner-url>?cassette=PATH&port=NAME`` - tee every byte to a cassette;
* ``replay://<cassette>?mode=strict|timed`` - serve a cassette (both: this package);
* ``sim://<protocol>?seed=N&faults=...`` - an emulator: registered by :mod:`labkit.emulators`
  when it is imported (the transport knows no emulator; docs/decisions/0005-emulators-own-sim-urls.md).

labkit's ports wait on the given clock (default :func:`labkit.io.clock.current_clock`);
native ports ignore it. A serial device is held by one process at a time
(:mod:`labkit.io.port_lock`): a second opener gets ``PortBusy`` naming the holder's PID.
"""

from __future__ import annotations

import threading
from typing import Any

import serial

from labkit.errors import PortURLError
from labkit.io.clock import Clock, current_clock
from labkit.io.port_lock import lock_device, unlock

HANDLER_PACKAGE = "labkit.io.urlhandlers"
_register_lock = threading.Lock()


def register_url_handlers(package: str = HANDLER_PACKAGE) -> None:
    """Make pyserial find the ``protocol_<scheme>`` modules of ``package`` (idempotent);
    by default ``record://`` and ``replay://``."""
    with _register_lock:
        if package not in serial.protocol_handler_packages:
            serial.protocol_handler_packages.append(package)


def open_port(url: str, *, clock: Clock | None = None, **serial_settings: Any) -> serial.SerialBase:
    """Open ``url`` with pyserial settings (``baudrate``, ``bytesize``, ``parity``, ``timeout``...).

    Raises ``serial.SerialException`` when the port cannot be opened and
    :class:`labkit.errors.PortURLError` for a malformed labkit URL.
    """
    register_url_handlers()
    try:
        port = serial.serial_for_url(url, do_not_open=True, **serial_settings)
    except ValueError as exc:
        if url.lower().startswith("sim://") and "not known" in str(exc):
            raise PortURLError(url, "sim:// ports are served by labkit.emulators; import it first") from None
        raise
    if hasattr(port, "clock"):
        port.clock = clock if clock is not None else current_clock()
    lock = lock_device(str(getattr(port, "port", None) or url))  # PortBusy if another run has it
    try:
        port.open()
    except BaseException:
        unlock(lock)
        raise
    if lock is not None:
        _release_on_close(port, lock)
    return port


def _release_on_close(port: serial.SerialBase, lock: int) -> None:
    """``port.close()`` also drops the device lock (the process's exit always does)."""
    close = port.close
    held = [lock]  # released once: a second close must never close an fd reused since

    def close_and_unlock() -> None:
        try:
            close()
        finally:
            if held:
                unlock(held.pop())

    port.close = close_and_unlock


register_url_handlers()
