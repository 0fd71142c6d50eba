"""Commands to labkit's own Arduino sketches (``labkit_tach``, ``labkit_strobe``): both stream
status lines on their own and answer a text command with one ``OK``/``ID ...``/``ERR ...``
line, which the driver's :class:`~labkit.devices.link.ReplyQueue` hands over."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from labkit.errors import DeviceReplyError, DeviceTimeout

#: a command whose reply does not come is sent this many times in all
COMMAND_ATTEMPTS = 3


class SketchCommands:
    """For drivers of labkit's sketches. They provide ``name``, ``clock``, ``replies`` (a
    ReplyQueue), ``reader`` (its StreamReader), ``reply_timeout_s``, ``_alive`` (set by the
    reader on the first line) and ``_check_reader()``."""

    name: str
    clock: Any
    replies: Any
    reader: Any
    reply_timeout_s: float
    _alive: bool
    _check_reader: Callable[[], None]  # raises the reader thread's error in the caller's thread

    def _wait_alive(self, timeout: float, first_line: str) -> None:
        """Wait for the sketch's boot banner or its first ``first_line``; DeviceTimeout after
        ``timeout`` s (wrong port or baud)."""
        deadline = self.clock.now() + timeout
        while not self._alive:
            self._check_reader()
            if self.clock.now() >= deadline:
                raise DeviceTimeout(self.name, "open", self.reader.last_bytes,
                                    f"no boot banner or {first_line} in {timeout} s (wrong port or baud?)")
            self.clock.sleep(0.005)

    def _exchange(self, data: bytes, label: str) -> bytes:
        """Send ``data`` and return the reply line; ``ERR ...`` raises DeviceReplyError, no reply
        after ``COMMAND_ATTEMPTS`` sends DeviceTimeout, both naming the command and last bytes."""
        for _attempt in range(COMMAND_ATTEMPTS):
            self.replies.replies.clear()
            self.replies.write(data, label)
            if self.replies.wait(bool, self.reply_timeout_s):
                reply = self.replies.replies.popleft()
                if reply.startswith(b"ERR"):
                    raise DeviceReplyError(self.name, label, self.reader.last_bytes,
                                           f"device answered {reply.decode('ascii', 'replace')!r}")
                return reply
        raise DeviceTimeout(self.name, label, self.reader.last_bytes, f"no reply in {self.reply_timeout_s} s")
