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
* below both, the controller's own command timeout (``options.command_timeout_ms`` /
  ``timeout_ms``, required for real hardware by the rig file) stops the motor if the whole
  machine goes (docs/safety.md).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import os
import signal
import sys
import threading
from collections.abc import Callable
from pathlib import Path
from typing import Any

#: the worker's exit statuses that mean "the worker itself stopped the motors"
CLEAN_EXITS = frozenset({0, 2, 3, 130})
FORWARDED = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP, signal.SIGQUIT)
PR_SET_PDEATHSIG = 1
SI_KERNEL = 0x80  # si_code of a signal the kernel (a terminal's Ctrl-C) sent, not kill()


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
    worker = os.fork()
    if worker == 0:
        signal.pthread_sigmask(signal.SIG_SETMASK, old_mask)
        _die_with_parent(parent)
        return work()
    try:
        status = _watch(worker, sigset)
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old_mask)
    return _after_worker(rig, worker, status, err, sessions)


def _watch(worker: int, sigset: set[int]) -> int:
    """Pass ``kill``-sent stop signals on to the worker until it ends; its wait status."""
    while True:
        info = signal.sigtimedwait(sigset, 0.5)
        if info is not None and info.si_signo != signal.SIGCHLD:
            # Ctrl-C typed on the terminal reached the worker (same process group) already, and a
            # second one would mean "safe state now"; the others are idempotent in the worker, and
            # a hang-up may reach only the session's leader: always pass those on
            typed_ctrl_c = info.si_signo == signal.SIGINT and info.si_code == SI_KERNEL
            if not typed_ctrl_c and info.si_pid != worker:
                try:
                    os.kill(worker, info.si_signo)
                except ProcessLookupError:
                    pass
        pid, status = os.waitpid(worker, os.WNOHANG)
        if pid == worker:
            return status


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
    stopped = [role for role in rig.devices if rig.devices[role].kind == "motor" and role not in failed]
    print(f"labkit run: the run process (PID {worker}) {how}; the supervisor commanded "
          f"{', '.join(stopped) or 'no motor'} to zero", file=err)
    for role, why in failed.items():
        print(f"labkit run: could not stop {role}: {why}; cut the motor's power", file=err)
    if sessions is not None:
        _close_sessions(sessions, worker, how, failed, err)
    return 3 if failed else code


def _close_sessions(sessions: str | Path, worker: int, how: str, failed: dict[str, str], err: Any) -> None:
    """Record the dead worker's session as ``killed`` and say how to resume it."""
    from labkit.session.orphans import close_killed_sessions

    stop = "the supervisor stopped the motors"
    if failed:
        stop = "the supervisor could not stop " + ", ".join(failed)
    for session in close_killed_sessions(sessions, worker, f"the run process (PID {worker}) {how}; {stop}"):
        hint = "" if failed else f"; resume with: labkit run --resume {session}"
        print(f"labkit run: session {session} recorded as killed{hint}", file=err)


def stop_motors(rig: Any) -> dict[str, str]:
    """Open every motor port of ``rig`` and send STOP; ``{role: reason}`` of those that failed."""
    from labkit.devices.base import driver_class
    from labkit.devices.motor.keepalive import stop_failure_text
    from labkit.io.clock import RealClock
    from labkit.io.ports import open_port

    clock = RealClock()
    failed = {}
    for role, dev in rig.devices.items():
        if dev.kind != "motor":
            continue
        port = None
        try:
            cls = driver_class(dev.kind, dev.protocol)
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
