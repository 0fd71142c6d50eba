"""A supervising process for ``labkit run`` on real ports: the rotor stops when either dies.

No signal handler runs on SIGKILL, the OOM killer or a crashed interpreter. So ``labkit run``
on a rig with a real motor port forks (docs/decisions/0012-safe-exit-supervisor-and-watchdogs.md):

* the **worker** (the child) runs the protocol exactly as before and owns every port; when
  the supervisor dies the kernel sends the worker SIGTERM (``PR_SET_PDEATHSIG``), which takes
  the Ctrl-C path: motors to zero, session closed;
* the **supervisor** (the parent, the PID the user sees) holds no port. It passes SIGTERM,
  SIGHUP and SIGQUIT on to the worker, and SIGINT when sent with ``kill`` (Ctrl-C typed on
  the terminal reaches both and is not passed twice: a second one would force the safe
  state at once), and when the worker ends abnormally
  (killed by a signal, a crash) it re-opens every motor port of the rig and sends STOP;
* a worker that stops working without dying (SIGSTOP, a freeze) stops its **heartbeat**
  (:mod:`labkit.control.heartbeat`); after :data:`HEARTBEAT_TIMEOUT_S` of silence the
  supervisor ends it with SIGKILL (a stopped process cannot run a SIGTERM handler, and only
  its end releases the port locks and keeps a continued worker from re-sending its last
  duty), then re-opens the motor ports and sends STOP, and records the session as killed;
* the supervisor itself survives being stopped and continued, and treats Ctrl-Z (SIGTSTP)
  as a stop request, which it passes on like SIGTERM;
* below both, the controller's own command timeout (``options.command_timeout_ms`` /
  ``timeout_ms``, required for real hardware by the rig file) stops the motor if the whole
  machine goes (docs/explanation/safety.md).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import errno
import os
import signal
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from labkit.control.heartbeat import HEARTBEAT_TIMEOUT_S, WATCH_S, Heartbeat, HeartbeatWatch

#: the worker's exit statuses that mean "the worker itself stopped the motors"
CLEAN_EXITS = frozenset({0, 2, 3, 130})
FORWARDED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT, signal.SIGTSTP)
#: signals typed on the terminal reach the whole foreground group: never passed on twice
TYPED = (signal.SIGINT, signal.SIGTSTP)
PR_SET_PDEATHSIG = 1
SI_KERNEL = 0x80  # si_code of a signal the kernel (a terminal's Ctrl-C) sent, not kill()
#: si_code values a real signal of ours carries: kill(), the kernel, sigqueue, tgkill, and
#: SIGCHLD's CLD_EXITED..CLD_CONTINUED (anything else is not a signal: see _next_signal)
SI_CODES = frozenset({0, SI_KERNEL, -1, -6, 1, 2, 3, 4, 5, 6})
#: how long the supervisor waits for a SIGKILLed frozen worker to be reaped before it sends STOP
REAP_S = 0.5
#: the worker's heartbeat (set in the worker after the fork; None in a one-process run)
_worker_heartbeat: Heartbeat | None = None


class Frozen:
    """What :func:`_watch` returns for a worker that stopped beating: silence (s) and its status."""

    def __init__(self, silent_s: float, status: int | None) -> None:
        self.silent_s, self.status = silent_s, status


#: worker PID -> (its process identity, when it was forked), to close only its own sessions
_workers: dict[int, tuple[str | None, float]] = {}


def worker_heartbeat() -> Heartbeat | None:
    """The heartbeat this process must beat (it is a supervised worker), else None."""
    return _worker_heartbeat



def needs_supervisor(rig: Any) -> bool:
    """Supervise when a motor is on a real port and this is the ``labkit`` program itself.

    ``LABKIT_SUPERVISOR=0`` turns it off, ``=1`` forces it; never inside another program
    (pytest, a notebook) that would find itself forked.
    """
    setting = os.environ.get("LABKIT_SUPERVISOR", "auto")
    if setting == "0" or not hasattr(os, "fork") or not hasattr(signal, "sigtimedwait"):
        return False
    real_motor = any(d.kind == "motor" and not d.port.startswith(("sim://", "replay://"))
                     for d in rig.devices.values())
    if not real_motor or threading.active_count() != 1:
        return False
    if setting == "1":
        return True
    program = Path(sys.argv[0]).name if sys.argv and sys.argv[0] else ""
    return program in ("__main__.py", "labkit") and "labkit" in sys.argv[0] and "pytest" not in sys.modules


def _die_with_parent(parent: int) -> None:
    """Worker side: SIGTERM when the supervisor dies (Linux), also if it died already."""
    libc_name = ctypes.util.find_library("c")
    if libc_name and sys.platform.startswith("linux"):
        try:
            ctypes.CDLL(libc_name, use_errno=True).prctl(PR_SET_PDEATHSIG, int(signal.SIGTERM), 0, 0, 0)
        except (OSError, AttributeError):
            pass
    if os.getppid() != parent:
        os.kill(os.getpid(), signal.SIGTERM)


def supervised(rig: Any, work: Callable[[], int], err: Any = None,
               sessions: str | Path | None = None) -> int:
    """Run ``work()`` in a forked worker watched by this process; the worker's exit status.

    In the worker this function returns what ``work()`` returns (the caller exits with it).
    If the worker dies without closing its session under ``sessions``, the supervisor records
    it as ``killed`` after stopping the motors (labkit.session.orphans).
    """
    err = err or sys.stderr
    sigset = set(FORWARDED) | {signal.SIGCHLD}
    old_mask = signal.pthread_sigmask(signal.SIG_BLOCK, sigset)
    parent = os.getpid()
    sys.stdout.flush()
    sys.stderr.flush()
    heartbeat = Heartbeat()
    forked_at = time.time()
    worker = os.fork()
    if worker == 0:
        global _worker_heartbeat
        _worker_heartbeat = heartbeat
        signal.signal(signal.SIGTSTP, signal.SIG_IGN)  # the run's handler makes Ctrl-Z a stop
        signal.pthread_sigmask(signal.SIG_SETMASK, old_mask)
        _die_with_parent(parent)
        return work()
    from labkit.session.process import process_identity

    _workers[worker] = (process_identity(worker), forked_at)  # which sessions are its: orphans.py
    try:
        status = _watch(worker, sigset, HeartbeatWatch(heartbeat))
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old_mask)
    if isinstance(status, Frozen):
        return _after_frozen_worker(rig, worker, status, err, sessions)
    return _after_worker(rig, worker, status, err, sessions)


def _watch(worker: int, sigset: set[signal.Signals], heartbeat: HeartbeatWatch | None = None) -> int | Frozen:
    """Pass ``kill``-sent stop signals on to the worker until it ends (its wait status) or its
    heartbeat stops (:class:`Frozen`: the worker was ended with SIGKILL)."""
    while True:
        info = _next_signal(sigset, WATCH_S)
        if info is not None and info.si_signo != signal.SIGCHLD:
            # Ctrl-C or Ctrl-Z typed on the terminal reached the worker (same process group)
            # already, and a second Ctrl-C would mean "safe state now"; the others are idempotent
            # in the worker, and a hang-up may reach only the session's leader: always pass those on
            typed = info.si_signo in TYPED and info.si_code == SI_KERNEL
            if not typed and info.si_pid != worker:
                try:
                    os.kill(worker, info.si_signo)
                except ProcessLookupError:
                    pass
        pid, status = os.waitpid(worker, os.WNOHANG)
        if pid == worker:
            return status
        silent = heartbeat.frozen_for() if heartbeat is not None else None
        if silent is not None:
            return Frozen(silent, _kill_and_reap(worker))


def _next_signal(sigset: set[signal.Signals], timeout_s: float) -> Any:
    """The next of ``sigset`` (blocked) sent to this process, waiting up to ``timeout_s``; or None.

    Never blocks inside ``sigtimedwait``: CPython 3.11 retries one interrupted by SIGSTOP and
    SIGCONT with the remaining time and, once that is negative, either raises ``OSError:
    [Errno 22]`` or returns a ``struct_siginfo`` of uninitialised memory (seen: ``si_signo=2``,
    a SIGINT nobody sent). So: sleep with the signals blocked, then take one that
    ``sigpending`` shows is there, without waiting, and check that it is one.
    """
    pending = signal.sigpending() & sigset
    if not pending:
        time.sleep(timeout_s)
        pending = signal.sigpending() & sigset
    if not pending:
        return None
    try:
        info = signal.sigtimedwait(pending, 0)
    except InterruptedError:
        return None
    except OSError as exc:
        if exc.errno == errno.EINVAL:
            return None
        raise
    genuine = info is not None and info.si_signo in pending and info.si_code in SI_CODES
    return info if genuine else None


def _kill_and_reap(worker: int) -> int | None:
    """SIGKILL (works on a stopped process too) and its wait status; None if not reaped in time."""
    try:
        os.kill(worker, signal.SIGKILL)
    except ProcessLookupError:
        pass
    deadline = time.monotonic() + REAP_S
    while True:
        pid, status = os.waitpid(worker, os.WNOHANG)
        if pid == worker:
            return status
        if time.monotonic() > deadline:
            return None  # uninterruptible sleep (a hung USB driver): STOP anyway, it may fail
        time.sleep(0.01)


def _after_frozen_worker(rig: Any, worker: int, frozen: Frozen, err: Any,
                         sessions: str | Path | None = None) -> int:
    """Motors to zero after the frozen worker was ended; report and close its session."""
    failed = stop_motors(rig)
    if frozen.status is None:  # still not reaped: wait for it now that the STOP went out
        _, frozen.status = os.waitpid(worker, 0)
    how = (f"stopped responding (no heartbeat for {frozen.silent_s:.1f} s, limit "
           f"{HEARTBEAT_TIMEOUT_S:.1f} s: stopped with SIGSTOP, frozen or starved) and was ended "
           "with SIGKILL")
    _report_stop(rig, worker, how, failed, err, sessions)
    return 3 if failed else 128 + signal.SIGKILL


def _report_stop(rig: Any, worker: int, how: str, failed: dict[str, str], err: Any,
                 sessions: str | Path | None) -> None:
    """Say which motors the supervisor stopped after the worker ended ``how``, which it could
    not, and record the worker's session as killed."""
    stopped = [role for role in rig.devices if rig.devices[role].kind == "motor" and role not in failed]
    print(f"labkit run: the run process (PID {worker}) {how}; the supervisor commanded "
          f"{', '.join(stopped) or 'no motor'} to zero", file=err)
    for role, why in failed.items():
        print(f"labkit run: could not stop {role}: {why}; cut the motor's power", file=err)
    if sessions is not None:
        _close_sessions(sessions, worker, how, failed, err)


def _after_worker(rig: Any, worker: int, status: int, err: Any, sessions: str | Path | None = None) -> int:
    if os.WIFSIGNALED(status):
        signum = os.WTERMSIG(status)
        how, code = f"was killed by {signal.Signals(signum).name}", 128 + signum
    else:
        code = os.WEXITSTATUS(status)
        if code in CLEAN_EXITS:
            return code
        how = f"ended with status {code} without stopping safely"
    failed = stop_motors(rig)
    _report_stop(rig, worker, how, failed, err, sessions)
    return 3 if failed else code


def _close_sessions(sessions: str | Path, worker: int, how: str, failed: dict[str, str], err: Any) -> None:
    """Record the dead worker's session as ``killed`` and say how to resume it."""
    from labkit.session.orphans import close_killed_sessions

    stop = "the supervisor stopped the motors"
    if failed:
        stop = "the supervisor could not stop " + ", ".join(failed)
    identity, forked_at = _workers.get(worker, (None, None))
    reason = f"the run process (PID {worker}) {how}; {stop}"
    for session in close_killed_sessions(sessions, worker, reason, identity, forked_at):
        hint = "" if failed else f"; resume with: labkit run --resume {session}"
        print(f"labkit run: session {session} recorded as killed{hint}", file=err)


def stop_motors(rig: Any) -> dict[str, str]:
    """Open every motor port of ``rig`` and send STOP; ``{role: reason}`` of those that failed."""
    from labkit.devices.motor.keepalive import stop_failure_text
    from labkit.devices.registry import driver_class
    from labkit.io.clock import RealClock
    from labkit.io.ports import open_port

    clock = RealClock()
    failed = {}
    for role, dev in rig.devices.items():
        if dev.kind != "motor":
            continue
        port = None
        try:
            cls = driver_class("motor", dev.protocol)
            port = open_port(dev.port, clock=clock, **{**getattr(cls, "default_serial", {}), **dev.serial})
            motor = cls(port, clock, name=role, **dev.options)
            motor.stop()
            if motor.stop_error:
                failed[role] = motor.stop_error
        except Exception as exc:  # noqa: BLE001 - report and go on with the other motors
            failed[role] = stop_failure_text(exc)
        finally:
            if port is not None:
                try:
                    port.close()
                except Exception:  # noqa: BLE001 - the STOP was what mattered
                    pass
    return failed
