"""Errors meant for people: each names what failed, where, and why
(docs/explanation/architecture.md#errors-are-for-people).

The CLI prints ``str(error)`` of any :class:`LabkitError` as one line and exits non-zero;
no traceback reaches a user for an expected fault.
"""

from __future__ import annotations


class LabkitError(Exception):
    """Base of every expected, user-facing labkit error."""


def show_bytes(data: bytes, limit: int = 48) -> str:
    """Render the tail of a byte string for an error message (repr of at most ``limit`` bytes)."""
    tail = bytes(data[-limit:])
    prefix = "..." if len(data) > limit else ""
    return prefix + repr(tail)


class DeviceError(LabkitError):
    """A device did something unexpected. Names device, command and the last bytes seen."""

    def __init__(self, device: str, command: str, last_bytes: bytes, reason: str) -> None:
        self.device = device
        self.command = command
        self.last_bytes = bytes(last_bytes)
        self.reason = reason
        super().__init__(
            f"{device}: {reason} (command {command!r}, last bytes {show_bytes(self.last_bytes)})"
        )


class DeviceTimeout(DeviceError):
    """No (complete) reply within the command's timeout."""


class DeviceDisconnected(DeviceError):
    """The port went away (detected by real I/O, not ``is_open``)."""


class DeviceReplyError(DeviceError):
    """The device answered with an error code (MT-SICS ES/ET/EL, A&D EC, VESC fault...)."""


class RigFileError(LabkitError):
    """A rig file is wrong. Formats as ``file:key: reason``."""

    def __init__(self, file: str, key: str, reason: str) -> None:
        self.file, self.key, self.reason = str(file), key, reason
        super().__init__(f"{self.file}:{key}: {reason}")


class SessionError(LabkitError):
    """A session directory cannot be created, written or read. Names the path."""


class VideoError(LabkitError):
    """A video or image cannot be analysed. Names the file and the problem."""

    def __init__(self, file: str, problem: str) -> None:
        self.file, self.problem = str(file), problem
        super().__init__(f"{self.file}: {problem}")


class ReplayMismatch(LabkitError):
    """What a driver wrote during replay differs from the cassette."""


class PortURLError(LabkitError, ValueError):
    """A port URL (``sim://``, ``record://``, ``replay://``...) cannot be used. Names URL and reason."""

    def __init__(self, url: str, reason: str) -> None:
        self.url, self.reason = url, reason
        super().__init__(f"{url}: {reason}")


class CassetteError(LabkitError):
    """A cassette file is unreadable. Names file, line and problem."""

    def __init__(self, file: str, line: int, problem: str) -> None:
        self.file, self.line, self.problem = str(file), line, problem
        super().__init__(f"{self.file}:{line}: {problem}")


class SafetyError(LabkitError):
    """An interlock tripped (speed above limit, tachometer silent, ...). Motors are at zero."""


class DataFileError(LabkitError):
    """A data file (CSV, results.json, session) cannot be used. Formats as ``file:key: reason``."""

    def __init__(self, file: str, key: str, reason: str) -> None:
        self.file, self.key, self.reason = str(file), key, reason
        super().__init__(f"{self.file}:{key}: {reason}" if key else f"{self.file}: {reason}")


class FitError(LabkitError):
    """A fit cannot give a trustworthy answer (too few points, NaN, a parameter at a bound...).

    Names the model, the series and what to change in the data.
    """
