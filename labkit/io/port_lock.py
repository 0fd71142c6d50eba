"""One process per serial device: ``flock`` lock files keyed by the real device path.

A second ``labkit run`` on a rig whose ports are in use would steal the tachometer's bytes
and fight the first run over the motor. :func:`lock_device` takes an exclusive, non-blocking
``flock`` on ``<tmp>/labkit-port-locks/<real device path>.lock`` and writes the holder's PID
and command line into it; the kernel drops the lock when the holder exits, however it exits
(SIGKILL too), so a stale lock file never blocks anybody. Only character devices are locked
(``/dev/ttyUSB0``, ``/dev/ttyACM0``, ``/dev/pts/N``, also reached through a symlink such as
``/dev/serial/by-id/...``); ``sim://``, ``replay://``, ``socket://`` need none.
"""

from __future__ import annotations

import os
import stat
import sys
import tempfile
from pathlib import Path

import serial

from labkit.errors import LabkitError

try:
    import fcntl
except ImportError:  # pragma: no cover - Windows: COM ports are exclusive by themselves
    fcntl = None  # type: ignore[assignment]


class PortBusy(LabkitError, serial.SerialException):
    """Another process holds the device. Names the device and the holder's PID."""

    def __init__(self, device: str, holder: str) -> None:
        self.device, self.holder = device, holder
        super().__init__(f"{device}: port busy, held by {holder}; stop that run first "
                         "(two programs on one port steal each other's bytes)")


def lock_dir() -> Path:
    return Path(os.environ.get("LABKIT_LOCK_DIR") or Path(tempfile.gettempdir()) / "labkit-port-locks")


def device_path(port: str) -> str | None:
    """The real path of ``port`` if it names a character device (a serial port), else None."""
    if "://" in port:
        return None
    real = os.path.realpath(port)
    try:
        return real if stat.S_ISCHR(os.stat(real).st_mode) else None
    except OSError:
        return None


def _lock_file(real: str) -> Path:
    return lock_dir() / (real.strip("/").replace("/", "_") + ".lock")


def _holder(fd: int) -> str:
    try:
        text = os.pread(fd, 400, 0).decode("utf-8", "replace").strip()
    except OSError:
        text = ""
    pid, _, command = text.partition(" ")
    return f"PID {pid} ({command})" if pid.isdigit() and command else (f"PID {pid}" if pid.isdigit()
                                                                       else "another process")


def lock_device(port: str) -> int | None:
    """Lock the device behind ``port`` for this process; the lock's fd (None: nothing to lock).

    Raises :class:`PortBusy` naming the holder's PID if another process has it.
    """
    real = device_path(port)
    if real is None or fcntl is None:
        return None
    path = _lock_file(real)
    shared = "LABKIT_LOCK_DIR" not in os.environ  # a folder the user chose keeps its own mode
    if shared and not path.parent.exists():
        path.parent.mkdir(parents=True, exist_ok=True)
        try:
            path.parent.chmod(0o1777)  # shared by every user of the machine, like /tmp
        except OSError:
            pass
    path.parent.mkdir(parents=True, exist_ok=True)
    try:  # a lock file planted as a symlink (in a folder every user can write) is not followed
        fd = os.open(path, os.O_RDWR | os.O_CREAT | getattr(os, "O_NOFOLLOW", 0), 0o666)
    except OSError as exc:
        raise LabkitError(f"{port}: cannot use the lock file {path} ({exc.strerror or exc}); a symbolic "
                          "link there is refused (labkit does not follow links in a folder every user "
                          "can write): remove it") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        holder = _holder(fd)
        os.close(fd)
        raise PortBusy(port if real == port else f"{port} ({real})", holder) from None
    program = "labkit" if "labkit" in (sys.argv[0] if sys.argv else "") else os.path.basename(
        sys.argv[0] if sys.argv else "python")
    command = " ".join([program, *sys.argv[1:]])[:200]
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"{os.getpid()} {command or 'python'}\n".encode(), 0)
    return fd


def unlock(fd: int | None) -> None:
    if fd is not None:
        try:
            os.close(fd)  # closing the only descriptor drops the flock
        except OSError:
            pass


def check_free(port: str) -> None:
    """Raise :class:`PortBusy` if another process holds ``port`` (does not keep a lock)."""
    unlock(lock_device(port))
