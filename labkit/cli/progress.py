"""Progress lines for jobs that may run longer than about 2 s (docs/reference/vision.md, *Commands*).

:class:`ProgressLines` prints nothing for a short job. Once ``after_s`` has passed it prints one
line on stderr at most every ``every_s``: ``labkit analyse laser: clip.mp4: 450 of 900 frames
(3 s so far)``. Lines, not a redrawn bar: they read the same in a terminal, a log file and CI.
"""

from __future__ import annotations

import sys
import time
from typing import TextIO

AFTER_S = 2.0  # a job shorter than this says nothing
EVERY_S = 2.0  # at most one line per this many seconds


class ProgressLines:
    """Callable ``(done, total)`` for per-item hooks; ``total`` <= 0 means unknown."""

    def __init__(self, label: str, unit: str, *, after_s: float = AFTER_S, every_s: float = EVERY_S,
                 stream: TextIO | None = None, clock=time.monotonic) -> None:
        self.label, self.unit = label, unit
        self.after_s, self.every_s = after_s, every_s
        self.stream = stream
        self._clock = clock
        self._start = clock()
        self._last: float | None = None
        self.lines = 0

    def __call__(self, done: int, total: int = 0) -> None:
        now = self._clock()
        if now - self._start < self.after_s or (self._last is not None and now - self._last < self.every_s):
            return
        self._last = now
        of = f" of {total}" if total > 0 else ""
        self.say(f"{done}{of} {self.unit}")

    def say(self, what: str) -> None:
        """One line now if the job has run past ``after_s`` (e.g. "fitting" after the frames)."""
        now = self._clock()
        if now - self._start < self.after_s:
            return
        print(f"{self.label}: {what} ({now - self._start:.0f} s so far)", file=self.stream or sys.stderr,
              flush=True)
        self.lines += 1
