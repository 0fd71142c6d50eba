"""Injected time (docs/design/architecture.md#injected-time): every wait, settle, ramp and timeout goes
through a Clock.

* :class:`RealClock` is ``time.monotonic`` and real sleeps; periodic jobs run on threads.
* :class:`VirtualClock` jumps. ``sleep(dt)`` advances time at once and runs every periodic
  job (stream pumps, motor keep-alives) that falls due on the way, in time order, in the
  calling thread. A 10-minute protocol therefore runs in seconds and takes the same
  decisions every time.

Drivers never call :func:`time.sleep` themselves. Code that needs "the" clock of a process
(for example a ``sim://`` port opened by URL) uses :func:`current_clock`.
"""

from __future__ import annotations

import heapq
import itertools
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field


@dataclass
class PeriodicJob:
    """Handle of a job registered with :meth:`Clock.every`; ``cancel()`` stops it."""

    period: float
    callback: Callable[[float], None]
    name: str = ""
    cancelled: bool = False
    _thread: threading.Thread | None = field(default=None, repr=False)

    def cancel(self) -> None:
        self.cancelled = True


class Clock:
    """Interface: ``now()``, ``sleep(dt)``, ``sleep_until(t)``, ``every(period, cb)``."""

    is_virtual: bool = False

    def now(self) -> float:  # pragma: no cover - interface
        raise NotImplementedError

    def sleep(self, dt: float) -> None:  # pragma: no cover - interface
        raise NotImplementedError

    def sleep_until(self, t: float) -> None:
        dt = t - self.now()
        if dt > 0:
            self.sleep(dt)

    def every(self, period: float, callback: Callable[[float], None], name: str = "") -> PeriodicJob:
        raise NotImplementedError  # pragma: no cover - interface


class RealClock(Clock):
    """Wall time from ``time.monotonic``; periodic jobs each get a daemon thread."""

    is_virtual = False

    def now(self) -> float:
        return time.monotonic()

    def sleep(self, dt: float) -> None:
        if dt > 0:
            time.sleep(dt)

    def every(self, period: float, callback: Callable[[float], None], name: str = "") -> PeriodicJob:
        if period <= 0:
            raise ValueError("period must be > 0")
        job = PeriodicJob(period, callback, name)

        def loop() -> None:
            next_t = time.monotonic()
            while not job.cancelled:
                next_t += period
                try:
                    callback(time.monotonic())
                except Exception:  # a job reports its own errors; the thread must not die silently
                    job.cancelled = True
                    raise
                delay = next_t - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
                else:
                    next_t = time.monotonic()

        job._thread = threading.Thread(target=loop, name=f"labkit-{name or 'job'}", daemon=True)
        job._thread.start()
        return job


class VirtualClock(Clock):
    """Deterministic simulated time. ``sleep`` jumps, running due periodic jobs in order."""

    is_virtual = True

    def __init__(self, start: float = 0.0) -> None:
        self._now = float(start)
        self._lock = threading.RLock()
        self._jobs: list[tuple[float, int, PeriodicJob]] = []
        self._seq = itertools.count()
        self._running_jobs = False

    def now(self) -> float:
        return self._now

    def every(self, period: float, callback: Callable[[float], None], name: str = "") -> PeriodicJob:
        if period <= 0:
            raise ValueError("period must be > 0")
        job = PeriodicJob(period, callback, name)
        with self._lock:
            heapq.heappush(self._jobs, (self._now + period, next(self._seq), job))
        return job

    def sleep(self, dt: float) -> None:
        if dt < 0:
            return
        with self._lock:
            target = self._now + dt
            # Jobs do not run jobs: a sleep inside a job only moves time forward.
            if not self._running_jobs:
                self._running_jobs = True
                try:
                    while self._jobs and self._jobs[0][0] <= target:
                        due, _, job = heapq.heappop(self._jobs)
                        if job.cancelled:
                            continue
                        self._now = max(self._now, due)
                        job.callback(self._now)
                        heapq.heappush(self._jobs, (due + job.period, next(self._seq), job))
                finally:
                    self._running_jobs = False
            self._now = max(self._now, target)

    def advance(self, dt: float) -> None:
        """Alias of :meth:`sleep`, reads better in tests."""
        self.sleep(dt)


_current: Clock = RealClock()
_current_lock = threading.Lock()


def current_clock() -> Clock:
    """The process's clock (real unless a runner or test installed a virtual one)."""
    return _current


def set_current_clock(clock: Clock) -> Clock:
    """Install ``clock`` as the process clock; returns the previous one."""
    global _current
    with _current_lock:
        previous, _current = _current, clock
    return previous


class use_clock:  # noqa: N801 - used as a context manager, reads as a verb
    """``with use_clock(VirtualClock()): ...`` installs a clock for the block."""

    def __init__(self, clock: Clock) -> None:
        self.clock = clock
        self._previous: Clock | None = None

    def __enter__(self) -> Clock:
        self._previous = set_current_clock(self.clock)
        return self.clock

    def __exit__(self, *exc: object) -> None:
        assert self._previous is not None
        set_current_clock(self._previous)


class ReplayClock(VirtualClock):
    """A virtual clock on which periodic jobs take none of their caller's time.

    On a :class:`VirtualClock` a job that waits (a motor status query waiting for its reply)
    moves everyone's time forward, as if the threads took turns. Replaying a real-clock
    recording (``replay://...?mode=faithful``), where the control thread's queries ran beside
    the protocol's balance polls, that stolen time would put the protocol behind the recorded
    device. Here a wait inside a job moves only the job's own time (``now()`` inside the job),
    and the caller resumes at the time it slept to.
    """

    def __init__(self, start: float = 0.0) -> None:
        super().__init__(start)
        self._job_time = 0.0

    def now(self) -> float:
        return self._now + self._job_time

    def sleep(self, dt: float) -> None:
        if dt < 0:
            return
        with self._lock:
            if self._running_jobs:  # a wait inside a job: the job's own time only
                self._job_time += dt
                return
            target = self._now + dt
            self._running_jobs = True
            try:
                while self._jobs and self._jobs[0][0] <= target:
                    due, _, job = heapq.heappop(self._jobs)
                    if job.cancelled:
                        continue
                    self._now = max(self._now, due)
                    try:
                        job.callback(self._now)
                    finally:
                        self._job_time = 0.0
                    heapq.heappush(self._jobs, (due + job.period, next(self._seq), job))
            finally:
                self._running_jobs = False
            self._now = max(self._now, target)
