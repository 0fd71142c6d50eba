"""Injected time (docs/explanation/architecture.md#injected-time): every wait, settle, ramp and timeout goes
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
import json
import os
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any


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
    """Wall time from ``time.monotonic``; periodic jobs each get a daemon thread.

    ``on_run(name, t)``, when set, is called each time a job runs (with the reading the job is
    given): a recorded session keeps its speed loop's ticks (:class:`TickRecorder`) so that a
    faithful replay ticks when the recording did. ``on_done(name, t, end)`` is called when a
    job's run ends, and the hook also hears where the main (protocol) thread stood still."""

    is_virtual = False
    #: ``on_run(name, t)`` at each job run; ``on_run(STALL_JOB, planned, woke)`` when the main
    #: thread woke from a sleep more than :data:`STALL_S` late; ``on_run(LATE_JOB, last, t)``
    #: when it read the clock more than :data:`STALL_S` after its previous read or wake-up
    on_run: Callable[..., None] | None = None
    #: ``on_done(name, t, end)`` when a job's run that began at ``t`` ended at ``end``
    on_done: Callable[[str, float, float], None] | None = None
    #: the main thread's last clock reading or wake-up (while ``on_run`` is set)
    _main_last: float | None = None

    def now(self) -> float:
        t = time.monotonic()
        if self.on_run is not None:
            self._main_read(t)
        return t

    def _main_read(self, t: float) -> None:
        """The main thread read the clock at ``t``: long after its previous read or wake-up it
        stood still outside a sleep (waiting for a lock a slow control tick held, a blocking
        call, a loaded CPU), which a faithful replay repeats (:class:`ReplayClock`)."""
        hook = self.on_run
        if hook is None or threading.current_thread() is not threading.main_thread():
            return
        last, self._main_last = self._main_last, t
        if last is not None and t - last > STALL_S:
            hook(LATE_JOB, last, t, read_site())

    def sleep(self, dt: float) -> None:
        if dt > 0:
            start = time.monotonic()
            if self.on_run is not None:
                self._main_read(start)
            time.sleep(dt)
            hook = self.on_run
            if hook is not None and threading.current_thread() is threading.main_thread():
                woke = time.monotonic()
                self._main_last = woke
                if woke - (start + dt) > STALL_S:  # the protocol's thread stood still (a loaded PC)
                    hook(STALL_JOB, start + dt, woke)

    def every(self, period: float, callback: Callable[[float], None], name: str = "") -> PeriodicJob:
        if period <= 0:
            raise ValueError("period must be > 0")
        job = PeriodicJob(period, callback, name)

        def loop() -> None:
            next_t = time.monotonic()
            while not job.cancelled:
                next_t += period
                try:
                    t = time.monotonic()
                    if self.on_run is not None:
                        self.on_run(name, t)
                    callback(t)
                    done = self.on_done
                    if done is not None:
                        done(name, t, time.monotonic())
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


#: the session file holding recorded job runs (one ``{"job": NAME, "t": T}`` per line)
TICKS_FILE = "clock.jsonl"
#: the jobs whose runs a real-clock session records (their timing makes the run's decisions)
RECORDED_JOBS = frozenset({"speed-control"})
#: the protocol thread's late wake-ups: ``{"job": STALL_JOB, "t": planned, "woke": actual}``
STALL_JOB = "main-stall"
#: a wake-up later than this (s) is recorded (a faithful replay then stands still as long)
STALL_S = 0.05
#: a replayed sleep ends where a recorded stall was planned when within this (s)
STALL_MATCH_S = 0.01
#: the protocol thread stood still outside a sleep: ``{"job": LATE_JOB, "t": last, "woke": read}``
#: (its clock read ``read`` came more than :data:`STALL_S` after its previous read or wake-up)
LATE_JOB = "main-late"
#: a replayed protocol thread at most this far (s) before a recorded stand-still begins stands still
LATE_MATCH_S = 0.04
#: stream readers (jobs named ``ROLE-reader``) whose run, from its start to the moment its lines
#: were handed to the consumers, took longer than this (s), or during which a recorded job (a
#: speed-loop tick) began, are recorded: ``{"job": NAME, "t": start, "done": end}``; lines read
#: in such a run are delivered at ``end`` (after that tick: on a loaded PC a tick 0.6 ms after a
#: read, its lines handed over 1 ms later, saw the tachometer silent; a replay that delivered
#: them at the read did not)
READER_SUFFIX = "-reader"
DELIVERY_S = 0.002


class TickRecorder:
    """``RealClock.on_run`` hook appending the runs of :data:`RECORDED_JOBS` to ``path``
    (each line flushed; a failure to write only stops the recording of ticks)."""

    def __init__(self, path: str | os.PathLike[str], clock: RealClock) -> None:
        self._file: Any = open(path, "a", encoding="utf-8")  # noqa: SIM115 - closed by close()
        self._lock = threading.Lock()
        self.clock = clock
        clock._main_last = None
        clock.on_run = self
        clock.on_done = self.done
        #: when the last recorded job's run (a speed-loop tick) began
        self._last_job_t: float | None = None

    def __call__(self, name: str, t: float, woke: float | None = None, site: str | None = None) -> None:
        if name not in RECORDED_JOBS and name not in (STALL_JOB, LATE_JOB):
            return
        if name in RECORDED_JOBS:
            self._last_job_t = t
        extra = "" if woke is None else f', "woke": {woke!r}'
        self._write(name, t, extra + ("" if site is None else f", \"site\": {json.dumps(site)}"))

    def done(self, name: str, t: float, end: float) -> None:
        """A job's run ended: a stream reader's that handed its lines over late, or after a
        recorded job's run began, is recorded."""
        tick = self._last_job_t
        if name.endswith(READER_SUFFIX) and (end - t > DELIVERY_S or (tick is not None and t < tick < end)):
            self._write(name, t, f', "done": {end!r}')

    def _write(self, name: str, t: float, extra: str) -> None:
        with self._lock:
            if self._file is None:
                return
            try:
                self._file.write(f'{{"job": "{name}", "t": {t!r}{extra}}}\n')
                self._file.flush()
            except OSError:
                self._file = None

    def close(self) -> None:
        """Stop recording; never raises (it runs on every exit path of a run)."""
        self.clock.on_run = None
        self.clock.on_done = None
        with self._lock:
            if self._file is not None:
                try:
                    self._file.close()
                except OSError:
                    pass  # a full disk: the ticks written so far stay readable
                self._file = None


def record_ticks(clock: Clock, session: str | os.PathLike[str]) -> TickRecorder | None:
    """On a real clock, keep when the speed loop ticks in SESSION/clock.jsonl (a faithful
    replay ticks then too, so it sees the readings the recording's loop saw); None on a
    virtual clock or when the file cannot be opened (the session's own writes report that)."""
    if not isinstance(clock, RealClock):
        return None
    try:
        return TickRecorder(os.path.join(session, TICKS_FILE), clock)
    except OSError:
        return None


def _clock_rows(session: str | os.PathLike[str]) -> list[dict[str, Any]]:
    """The rows of SESSION/clock.jsonl (torn or damaged lines skipped); [] without the file."""
    rows: list[dict[str, Any]] = []
    try:
        with open(os.path.join(session, TICKS_FILE), encoding="utf-8") as f:
            for line in f:
                try:
                    row = json.loads(line)
                    float(row["t"])
                    str(row["job"])
                except (ValueError, KeyError, TypeError):
                    continue  # a torn last line
                rows.append(row)
    except OSError:
        return []
    return rows


def recorded_ticks(session: str | os.PathLike[str]) -> dict[str, list[float]]:
    """The job runs a session recorded (:class:`TickRecorder`), by job name; {} without any.
    Stand-stills and deliveries (:func:`recorded_runs`) are not among them."""
    out: dict[str, list[float]] = {}
    for row in _clock_rows(session):
        if row["job"] == LATE_JOB or "done" in row:
            continue
        try:
            woke = float(row["woke"]) if "woke" in row else None
        except (ValueError, TypeError):
            continue
        out.setdefault(str(row["job"]), []).append(float(row["t"]))
        if woke is not None:
            out.setdefault(STALL_JOB + "-woke", []).append(woke)
    return out


def recorded_runs(session: str | os.PathLike[str]) -> dict[str, list[tuple[float, float, str]]]:
    """Intervals a session recorded: :data:`LATE_JOB` -> ``(last, woke, site)`` where the
    protocol thread stood still outside a sleep (``site``: :func:`read_site` of its read at
    ``woke``, "" if unknown); ``ROLE-reader`` -> ``(start, done, "")`` of a stream reader's runs
    that handed their lines over late; sorted; {} without any (sessions from an earlier labkit)."""
    out: dict[str, list[tuple[float, float, str]]] = {}
    for row in _clock_rows(session):
        end = row.get("woke") if row["job"] == LATE_JOB else row.get("done")
        if isinstance(end, int | float):
            site = row["site"] if isinstance(row.get("site"), str) else ""
            out.setdefault(str(row["job"]), []).append((float(row["t"]), float(end), str(site)))
    return {name: sorted(runs) for name, runs in out.items()}


#: how many callers name the site of a clock read (:func:`read_site`)
SITE_DEPTH = 3
#: frames of these functions are wrappers of the clock, not the place that reads it
_CLOCK_WRAPPERS = frozenset({"now", "sleep", "sleep_until", "_main_read", "_stand_still", "read_site"})
_IO_DIR = os.path.dirname(os.path.abspath(__file__))


def read_site(depth: int = SITE_DEPTH) -> str:
    """Where the calling thread reads the clock: ``module.py:Qualified.name+LINE`` (``LINE``
    counted from the function's first line, so edits elsewhere in the file do not move it) of
    the first ``depth`` frames outside ``labkit/io`` (ports, clocks) and clock wrappers,
    innermost first, joined by ``<``: the settle loop's read when it sees the loop settled is
    not its timeout check, and an event's read inside a step's ``set`` is not one of the same
    events emitted elsewhere. A recording's read and its replay's have the same site though
    their ports differ (``record://`` and ``replay://`` live in ``labkit/io``)."""
    sites: list[str] = []
    frame = sys._getframe(1)
    while frame is not None and len(sites) < depth:
        code = frame.f_code
        if code.co_name not in _CLOCK_WRAPPERS and os.path.dirname(code.co_filename) != _IO_DIR:
            name, line = getattr(code, "co_qualname", code.co_name), frame.f_lineno - code.co_firstlineno
            sites.append(f"{os.path.basename(code.co_filename)}:{name}+{line}")
        frame = frame.f_back  # type: ignore[assignment]
    return "<".join(sites)


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
            if self._running_jobs:  # jobs do not run jobs
                self._sleep_in_job(dt)
                return
            target = self._woken_at(self._now + dt)
            self._running_jobs = True
            try:
                while self._jobs and self._jobs[0][0] <= target:
                    due, _, job = heapq.heappop(self._jobs)
                    if job.cancelled:
                        continue
                    self._now = max(self._now, due)
                    self._run_job(job)
                    heapq.heappush(self._jobs, (self._due_after(job, due), next(self._seq), job))
            finally:
                self._running_jobs = False
            self._now = max(self._now, target)

    # the steps :class:`ReplayClock` changes
    def _sleep_in_job(self, dt: float) -> None:
        """A sleep inside a job only moves time forward."""
        self._now += dt

    def _woken_at(self, target: float) -> float:
        """When a sleep that ends at ``target`` wakes (here: then)."""
        return target

    def _run_job(self, job: PeriodicJob) -> None:
        job.callback(self._now)

    def _due_after(self, job: PeriodicJob, last: float) -> float:
        """A job's next time after it ran at ``last``."""
        return last + job.period

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
