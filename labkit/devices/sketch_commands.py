"""Commands to labkit's own Arduino sketches (``labkit_tach``, ``labkit_strobe``): both stream
status lines on their own and answer a text command with one ``OK``/``ID ...``/``ERR ...``
line, which the driver's :class:`~labkit.devices.link.ReplyQueue` hands over."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from labkit.errors import DeviceReplyError, DeviceTimeout

#: a command whose reply does not come is sent this many times in all
COMMAND_ATTEMPTS = 3


def strip_sketch_junk(line: bytes, line_starts: tuple[bytes, ...]) -> bytes:
    """Drop bytes before the first of a sketch's ``line_starts`` (power-on junk, noise on the
    wire); a line with none of them is returned as it came."""
    if line.startswith(line_starts):
        return line
    found = [i for i in (line.find(start) for start in line_starts) if i > 0]
    return line[min(found):] if found else line


def is_reply(line: bytes) -> bool:
    """Whether a sketch line answers a command (``OK``, ``ERR ...``, ``ID ...``), not a status."""
    return line == b"OK" or line.startswith(b"ERR") or line.startswith(b"ID ")


def parse_sketch_banner(line: bytes, sketch: str) -> dict[str, str] | None:
    """``# <sketch> 1.0 key=value ...`` (the boot banner) -> {"version": "1.0", key: value, ...};
    None for any other line (other ``#`` lines are plain comments)."""
    parts = line.strip().split()
    if len(parts) < 3 or parts[0] != b"#" or parts[1] != sketch.encode("ascii"):
        return None
    out = {"version": parts[2].decode("ascii", "replace")}
    for part in parts[3:]:
        key, sep, value = part.partition(b"=")
        if sep:
            out[key.decode("ascii", "replace")] = value.decode("ascii", "replace")
    return out


def parse_flag_letters(text: bytes, names: dict[str, str]) -> frozenset[str]:
    """A status line's flags: ``b"0"`` -> {}; each letter once, each a key of ``names`` (the
    flag's name); ValueError otherwise."""
    letters = text.decode("ascii", "replace")
    if letters == "0":
        return frozenset()
    if not letters or len(set(letters)) != len(letters) or not all(c in names for c in letters):
        raise ValueError(f"flags {text[:12]!r} not 0 or a set of {'/'.join(names)}")
    return frozenset(names[c] for c in letters)


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
    _resend_config: Callable[[], None]  # the settings again, after a reset, without waiting
    resets: int
    _flag_reset: bool
    banner: dict[str, str]
    _last_seq: int | None

    def _note_banner(self, banner: dict[str, str], lock: Any) -> None:
        """The sketch's boot banner: a second one means the device reset (counted, flagged on the
        next reading, its settings sent again)."""
        with lock:
            reset = self._alive
            if reset:
                self.resets += 1
                self._flag_reset = True
            self.banner = banner
            self._alive = True
            self._last_seq = None
        if reset:
            self._resend_config()

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
