"""The worker's heartbeat: how the supervisor of ``labkit run`` knows the run process still works.

A worker stopped with SIGSTOP, frozen in a deadlock or starved of the CPU is alive to
``waitpid`` but commands nothing: with the controller's watchdog off the motor keeps its
last duty (issue 29: 13 645 RPM with the run frozen). So the supervisor also watches a
counter in memory shared across the fork (``mmap`` of one anonymous page):

* the worker's **speed-control tick** increments it (a guard of
  :class:`labkit.control.loop.SpeedControl`, called every control period), so a control loop
  that stopped ticking while it should tick stops the beat;
* while no tick is due (before the first setpoint, after an interlock, a stop or the first
  Ctrl-C) a small **pulse thread** beats instead every :data:`PULSE_S`, so a slow but healthy
  step (a balance settling, the final writes) never looks frozen; it also beats between ticks,
  until a due tick is :data:`TICK_STALE_S` overdue (a tick stuck in a device call);
* the beat only counts while **armed**: from the start of the protocol until its motors are
  stopped and its ports closed (docs/decisions/0018-heartbeat-and-drift.md).

The supervisor (:class:`HeartbeatWatch`) declares the worker frozen when the counter has not
moved for :data:`HEARTBEAT_TIMEOUT_S` of its *own* waking time: time the supervisor itself
spent stopped (SIGSTOP, Ctrl-Z then ``fg``) is not held against the worker.
"""

from __future__ import annotations

import mmap
import struct
import threading
import time
from typing import Any

#: no beat for this long (s, supervisor awake) = the worker is frozen
HEARTBEAT_TIMEOUT_S = 1.0
#: a control tick this overdue (s) stops the pulse thread's beats: a tick stuck in a device
#: call for longer (a reply timeout is at most 1 s) is a control loop that controls nothing
TICK_STALE_S = 1.0
#: the pulse thread's period (s) while no control tick is due
PULSE_S = 0.1
#: the supervisor's polling period (s)
WATCH_S = 0.1
#: a gap this long between two of the supervisor's own polls means the supervisor was stopped
#: or starved: the worker's silence is measured afresh from there
OWN_GAP_S = 0.5

_LAYOUT = struct.Struct("<QQ")  # beat counter, armed flag


class Heartbeat:
    """Two 64-bit words shared by supervisor and worker (created before the fork)."""

    def __init__(self) -> None:
        self._mem = mmap.mmap(-1, _LAYOUT.size)  # MAP_SHARED | MAP_ANONYMOUS: survives fork()
        self._count = 0

    def beat(self) -> None:
        self._count += 1
        _LAYOUT.pack_into(self._mem, 0, self._count, self.armed_flag)

    @property
    def armed_flag(self) -> int:
        return _LAYOUT.unpack_from(self._mem, 0)[1]

    def arm(self, armed: bool) -> None:
        self._count += 1
        _LAYOUT.pack_into(self._mem, 0, self._count, 1 if armed else 0)

    def read(self) -> tuple[int, bool]:
        """(counter, armed) as the other process last wrote them."""
        count, armed = _LAYOUT.unpack_from(self._mem, 0)
        return count, bool(armed)


class WorkerPulse:
    """Worker side: beat from the control tick, and from a thread while no tick is due."""

    def __init__(self, heartbeat: Heartbeat, control: Any) -> None:
        self.heartbeat = heartbeat
        self.control = control
        self.last_tick: float | None = None
        self.stale_s = max(TICK_STALE_S, 4.0 * float(getattr(control, "period_s", 0.05)))
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._pulse, name="labkit-heartbeat", daemon=True)

    def start(self) -> WorkerPulse:
        self.control.guards.append(self.on_tick)
        self.heartbeat.arm(True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Motors stopped and ports closed: the supervisor no longer needs to watch."""
        self._done.set()
        self.heartbeat.arm(False)

    def on_tick(self) -> None:
        """A guard of the speed control: called every control period; never trips."""
        self.last_tick = time.monotonic()
        self.heartbeat.beat()
        return None

    def tick_overdue(self) -> bool:
        """True when the control loop should tick and has not for ``stale_s``."""
        c = self.control
        if self.last_tick is None or c.tripped is not None or c.stopped or c.zero_requested:
            return False  # no tick due: nothing turns under this loop's command
        return time.monotonic() - self.last_tick > self.stale_s

    def _pulse(self) -> None:
        while not self._done.wait(PULSE_S):
            if not self.tick_overdue():
                self.heartbeat.beat()


class HeartbeatWatch:
    """Supervisor side: call :meth:`frozen_for` every poll; the silence (s) once it is too long."""

    def __init__(self, heartbeat: Heartbeat, timeout_s: float = HEARTBEAT_TIMEOUT_S) -> None:
        self.heartbeat = heartbeat
        self.timeout_s = timeout_s
        self._last_count = -1
        self._since = time.monotonic()
        self._last_poll = self._since

    def frozen_for(self) -> float | None:
        """Seconds without a beat while armed, if above the timeout; else None."""
        now = time.monotonic()
        own_gap = now - self._last_poll
        self._last_poll = now
        count, armed = self.heartbeat.read()
        if count != self._last_count or not armed or own_gap > OWN_GAP_S:
            self._last_count, self._since = count, now
            return None
        silent = now - self._since
        return silent if silent > self.timeout_s else None
