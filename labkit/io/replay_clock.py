"""The clock of a faithful replay (docs/explanation/replay.md, docs/decisions/0019-faithful-replay.md):
a :class:`~labkit.io.clock.VirtualClock` that runs jobs when the recording ran them and stands
still where the recording's protocol thread did (``SESSION/clock.jsonl``,
:class:`~labkit.io.clock.TickRecorder`)."""

from __future__ import annotations

import bisect
import heapq
import threading
from collections.abc import Callable

from labkit.io.clock import (
    LATE_JOB,
    LATE_MATCH_S,
    STALL_JOB,
    STALL_MATCH_S,
    PeriodicJob,
    VirtualClock,
    read_site,
)


class ReplayClock(VirtualClock):
    """A virtual clock on which periodic jobs take none of their caller's time.

    On a :class:`VirtualClock` a job that waits (a motor status query waiting for its reply)
    moves everyone's time forward, as if the threads took turns. Replaying a real-clock
    recording (``replay://...?mode=faithful``), where the control thread's queries ran beside
    the protocol's balance polls, that stolen time would put the protocol behind the recorded
    device. Here a wait inside a job moves only the job's own time (``now()`` inside the job),
    and the caller resumes at the time it slept to.

    ``schedules``: job name -> the clock readings at which that job ran in the recording (a
    stream reader's reads, the speed loop's ticks): such a job runs at those times, so it sees
    what it saw then; once they run out it runs every period. The recorded stalls of the
    protocol's thread (:data:`STALL_JOB`) make the replayed sleep that ended there end late
    as it did.

    ``runs`` (:func:`recorded_runs`): where the protocol thread stood still outside a sleep
    (:data:`LATE_JOB`): a clock read or sleep of the replayed protocol within such an interval
    (or up to :data:`LATE_MATCH_S` before it) first waits until the recording's thread moved
    on; and a stream reader's runs that handed their lines over late: a scheduled read within
    one runs at its end, seeing the clock of its read, so that neither the protocol nor the
    speed loop sees those lines before the recording's did.
    """

    def __init__(self, start: float = 0.0, schedules: dict[str, list[float]] | None = None,
                 runs: dict[str, list[tuple[float, float, str]]] | None = None, site_root: str = "") -> None:
        super().__init__(start)
        #: a site's frame where the run begins (``runner.py:Runner.run+``): its callers (``labkit
        #: run``'s launcher in the recording, ``labkit replay`` here) are not compared
        self.site_root = site_root
        self._job_time = 0.0
        #: job name -> the times (sorted) it ran in the recording: it runs then, not every period
        self.schedules = {name: (list(times) if name.startswith(STALL_JOB) else sorted(times))
                          for name, times in (schedules or {}).items()}
        self._next_fire: dict[int, int] = {}
        runs = runs or {}
        self._late = list(runs.get(LATE_JOB, []))
        self._late_next = 0
        self._standing = False
        #: the replayed protocol's thread (the one that made the clock): only it stands still
        self._protocol_thread = threading.current_thread()
        #: reader job name -> (starts, ends) of its late deliveries
        self._deliveries = {name: ([run[0] for run in r], [run[1] for run in r])
                            for name, r in runs.items() if name != LATE_JOB}
        #: job id -> the clock reading its next (delayed) run sees
        self._run_reading: dict[int, float] = {}
        #: how many stand-stills and late deliveries the replay repeated
        self.repeated = {"stood_still": 0, "delivered_late": 0}

    def every(self, period: float, callback: Callable[[float], None], name: str = "") -> PeriodicJob:
        times = self.schedules.get(name)
        if not times:
            return super().every(period, callback, name)
        job = PeriodicJob(period, callback, name)
        with self._lock:
            index = bisect.bisect_right(times, self._now)
            self._next_fire[id(job)] = index
            heapq.heappush(self._jobs, (self._due_after(job, self._now), next(self._seq), job))
        return job

    def _woken_at(self, target: float) -> float:
        """When the recording's protocol thread woke from the sleep ending at ``target``: later
        than planned where it recorded a stall (``clock.jsonl``), else ``target``."""
        planned = self.schedules.get(STALL_JOB)
        woke = self.schedules.get(STALL_JOB + "-woke")
        if not planned or not woke or len(planned) != len(woke):
            return target
        i = bisect.bisect_left(planned, target - STALL_MATCH_S)
        if i < len(planned) and abs(planned[i] - target) <= STALL_MATCH_S:
            return max(target, woke[i])
        return target

    def _due_after(self, job: PeriodicJob, last: float) -> float:
        """A scheduled job's next recorded time (then every period once they run out); a
        reader's read in a run that delivered late: that run's end (:meth:`_delivered_at`)."""
        times = self.schedules.get(job.name)
        index = self._next_fire.get(id(job))
        if times is None or index is None:
            return last + job.period
        while index < len(times) and times[index] <= last:
            index += 1
        self._next_fire[id(job)] = index + 1
        if index >= len(times):
            return last + job.period
        return self._delivered_at(job, times[index])

    def _delivered_at(self, job: PeriodicJob, read: float) -> float:
        """When the lines of a read at ``read`` reached the consumers: the end of the recorded
        run holding it (the job then runs, seeing ``read`` on the clock), else ``read``."""
        found = self._deliveries.get(job.name)
        if not found:
            return read
        starts, ends = found
        i = bisect.bisect_right(starts, read + TIME_EPS_S) - 1
        if i < 0 or ends[i] <= read:
            return read
        self._run_reading[id(job)] = read
        self.repeated["delivered_late"] += 1
        return ends[i]

    def now(self) -> float:
        if self._late and self._may_stand_still():
            self._stand_still()
        return self._now + self._job_time

    def sleep(self, dt: float) -> None:
        if self._late and self._may_stand_still():
            self._stand_still()
        super().sleep(dt)

    def _may_stand_still(self) -> bool:
        """The protocol's own read, not a job's nor a stand-still's nor another thread's."""
        return (not self._running_jobs and not self._standing
                and threading.current_thread() is self._protocol_thread)

    def _stand_still(self) -> None:
        """The protocol reads the clock (or sleeps) where the recording's stood still outside a
        sleep (from the same site, :func:`~labkit.io.clock.read_site`, when it was recorded):
        wait, running the jobs due, until the recording's thread moved on."""
        late, now = self._late, self._now
        while self._late_next < len(late) and late[self._late_next][1] <= now:
            self._late_next += 1
        if self._late_next >= len(late):
            return
        began, woke, site = late[self._late_next]
        if began - LATE_MATCH_S <= now and (not site or _same_site(read_site(), site, self.site_root)):
            self._late_next += 1
            self.repeated["stood_still"] += 1
            self._standing = True
            try:
                super().sleep(woke - now)
            finally:
                self._standing = False

    def _sleep_in_job(self, dt: float) -> None:
        """A wait inside a job: the job's own time only."""
        self._job_time += dt

    def _run_job(self, job: PeriodicJob) -> None:
        reading = self._run_reading.pop(id(job), None)
        if reading is not None:  # a late delivery: the job sees the clock of its read
            self._job_time = reading - self._now
        try:
            job.callback(self._now + self._job_time)
        finally:
            self._job_time = 0.0


#: times (s) closer than this are the same reading
TIME_EPS_S = 1e-9


def _same_site(here: str, recorded: str, root: str = "") -> bool:
    """Whether a replayed read is at the recorded site: the same callers, as many as were
    recorded (a site of fewer frames matches by its first ones), up to the frame starting with
    ``root`` (where the run begins: a read in the runner itself, between two steps, was called
    from ``labkit run``'s launcher in the recording and from ``labkit replay`` in the replay).
    Callers compare by qualified name and line within the function, not by module file: a
    function moved to another module (``RunContext`` from ``runner.py`` to ``context.py``) still
    matches a session recorded before the move."""
    frames = _up_to(recorded.split("<"), root)
    return _up_to(here.split("<"), root)[: len(frames)] == frames


def _up_to(frames: list[str], root: str) -> list[str]:
    """The frames up to ``root`` (inclusive), each without its module file."""
    root = _without_module(root)
    out = [_without_module(f) for f in frames]
    for i, frame in enumerate(out):
        if root and frame.startswith(root):
            return out[: i + 1]
    return out


def _without_module(frame: str) -> str:
    """``runner.py:RunContext.settle+12`` -> ``RunContext.settle+12``."""
    return frame.partition(":")[2] or frame
