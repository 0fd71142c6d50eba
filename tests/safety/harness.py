"""The safety matrix's lab: the shipped emulated Fig. 5.25 rig served by `labkit emulate` in
its own process (the emulated controller keeps doing what it was last told after labkit
dies, as a real one does) and `labkit run` on its pseudo-terminals, as a user would start it.

Waits are event-driven (a line in a file, a process ending) with generous timeouts; the
only clock comparison is the acceptance criterion itself: the rotor, read from its own
tachometer, below 300 RPM 3 s after the signal.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
RIG = REPO / "rigs" / "emulated-fig525.toml"
RAD_S_PER_RPM = 2 * 3.141592653589793 / 60
HOLD_RPM = 12000


def labkit(*args: str) -> list[str]:
    return [sys.executable, "-m", "labkit", *args]


def end_process(proc: subprocess.Popen, timeout: float = 15.0) -> None:
    """Terminate, then kill: every process a test starts is gone when it ends."""
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(timeout=timeout)
    for stream in (proc.stdout, proc.stderr):
        if stream is not None:
            stream.close()


def children(pid: int) -> list[int]:
    try:
        return [int(c) for c in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except OSError:  # a kernel without CONFIG_PROC_CHILDREN: the parent PID of every process
        found = []
        for stat in Path("/proc").glob("[0-9]*/stat"):
            try:
                fields = stat.read_text().rsplit(")", 1)[1].split()
            except (OSError, IndexError):
                continue
            if int(fields[1]) == pid:
                found.append(int(stat.parent.name))
        return found


def wait_for(predicate, timeout: float, what: str, proc: subprocess.Popen | None = None, poll: float = 0.05):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        if proc is not None and proc.poll() is not None:
            raise AssertionError(f"{what}: the process ended first ({proc.returncode}): "
                                 f"{proc.stderr.read() if proc.stderr else ''}")
        time.sleep(poll)
    raise AssertionError(f"{what}: not within {timeout} s")


class EmulatedRig:
    """`labkit emulate` of the shipped rig in its own process, and a rig file on its ptys."""

    def __init__(self, workdir: Path, motor_faults: str = "", unplug: tuple[str, ...] = (),
                 watchdog_ms: int = 500, tach_faults: str = "", fault_on_usr2: tuple[str, ...] = (),
                 truth: bool = False, pty_rig_edits: tuple[tuple[str, str], ...] = ()) -> None:
        self.workdir = workdir
        # sensor faults (issue 29): faults of the tachometer's sim:// URL, ROLE:NAME faults started
        # by SIGUSR2 (inject_fault), the emulator's true motor speeds (true_motor), and text
        # replacements in the rig file labkit runs (e.g. a lower max_speed_rpm)
        self.tach_faults = tach_faults
        self.fault_on_usr2 = fault_on_usr2
        self.truth_file = workdir / "truth.jsonl" if truth else None
        self.pty_rig_edits = pty_rig_edits
        self.watchdog_ms = watchdog_ms  # the emulated controller's command timeout (0: off)
        self.motor_faults = motor_faults
        self.unplug_roles = unplug
        self.proc: subprocess.Popen | None = None
        self.paths: dict[str, str] = {}
        self.rig_file = workdir / "pty-rig.toml"

    def __enter__(self) -> EmulatedRig:
        served = self.workdir / "served-rig.toml"
        text = RIG.read_text()
        text = text.replace("command_timeout_ms=500", f"command_timeout_ms={self.watchdog_ms}")
        if self.motor_faults:
            text = text.replace("role=rotor_motor", f"role=rotor_motor&faults={self.motor_faults}")
        if self.tach_faults:
            text = text.replace("role=rotor_tach", f"role=rotor_tach&faults={self.tach_faults}")
        served.write_text(text)
        unplug = [arg for role in self.unplug_roles for arg in ("--unplug-on-usr1", role)]
        unplug += [arg for spec in self.fault_on_usr2 for arg in ("--fault-on-usr2", spec)]
        unplug += ["--truth", str(self.truth_file)] if self.truth_file is not None else []
        self.proc = subprocess.Popen(labkit("emulate", str(served), "--json", *unplug),
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO)
        try:
            self.paths = json.loads(self.proc.stdout.readline())
            for role, path in self.paths.items():
                start = text.index(f"[devices.{role}]")
                line_start = text.index('port = "sim://', start)
                line_end = text.index("\n", line_start)
                text = text[:line_start] + f'port = "{path}"' + text[line_end:]
            # labkit's side on a loaded CI box: generous reply and tachometer timeouts (the
            # matrix is about how a run ends, not about those interlocks; the controller's
            # command timeout stays as shipped)
            text = (text.replace("options = { command_timeout_ms = 500 }",
                                 "options = { command_timeout_ms = 500, reply_timeout_s = 1.0 }")
                    .replace("tach_timeout_s = 0.5", "tach_timeout_s = 2.0"))
            for old, new in self.pty_rig_edits:
                assert old in text, f"pty_rig_edits: {old!r} is not in the rig file"
                text = text.replace(old, new)
            self.rig_file.write_text(text)
        except BaseException:
            end_process(self.proc)
            raise
        return self

    def __exit__(self, *exc: object) -> None:
        if self.proc is not None:
            end_process(self.proc)

    def unplug(self) -> None:
        """Pull the cables of the ``unplug`` roles now (SIGUSR1 to `labkit emulate`)."""
        assert self.proc is not None
        os.kill(self.proc.pid, signal.SIGUSR1)

    def inject_fault(self) -> float:
        """Start the ``fault_on_usr2`` faults now (SIGUSR2 to `labkit emulate`); when (monotonic)."""
        assert self.proc is not None and self.fault_on_usr2
        sent = time.monotonic()
        os.kill(self.proc.pid, signal.SIGUSR2)
        return sent

    def true_motor(self, motor: str = "rotor") -> list[dict]:
        """The emulator's samples of ``motor`` (t monotonic, rpm, duty, stalled), every 20 ms."""
        assert self.truth_file is not None, "EmulatedRig(truth=True)"
        out = []
        for line in self.truth_file.read_text().splitlines():
            try:
                sample = json.loads(line)
            except json.JSONDecodeError:
                continue  # a torn last line while the emulator writes
            if sample.get("motor") == motor:
                out.append(sample)
        return out

    def start_run(self, sessions: Path, record_s: float = 60.0, terminal: bool = False,
                  speed_rpm: float = HOLD_RPM) -> LabkitRun:
        """`labkit run` in its own session and process group (killpg ends all of labkit); with
        ``terminal`` a pseudo-terminal is its controlling terminal, as in a lab's shell window."""
        master = slave = None
        if terminal:
            master, slave = os.openpty()
        try:
            proc = subprocess.Popen(
                labkit("run", str(self.rig_file), "speed-sweep", "--set", f"speeds_rpm={speed_rpm}",
                       "--set", f"record_s={record_s}", "--sessions", str(sessions), "--no-progress"),
                stdin=slave, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=REPO,
                start_new_session=True, preexec_fn=_take_terminal if terminal else None)
        finally:
            if slave is not None:
                os.close(slave)
        return LabkitRun(proc, sessions, master, hold_rpm=speed_rpm)

    def rotor_rpm_at(self, when: float, timeout: float = 20.0) -> float:
        """The rotor speed from its tachometer at the first reading after ``when`` (monotonic)."""
        from labkit.devices.registry import driver_class
        from labkit.io.clock import RealClock
        from labkit.io.ports import open_port

        clock = RealClock()
        cls = driver_class("tachometer", "labkit_tach")
        port = wait_for(lambda: _try_open(open_port, self.paths["rotor_tach"], clock), timeout,
                        "the tachometer's port free again")
        tach = cls(port, clock, name="rotor_tach")
        try:
            reading = tach.wait_reading(timeout=timeout)
            while time.monotonic() < when:
                reading = tach.wait_reading(timeout=timeout)
            return reading.value / RAD_S_PER_RPM
        finally:
            tach.close()


def _take_terminal() -> None:
    """In the child, after setsid(): stdin (a pty) becomes the controlling terminal."""
    import fcntl
    import termios

    fcntl.ioctl(0, termios.TIOCSCTTY, 0)


def _try_open(open_port, path: str, clock):
    from labkit.io.port_lock import PortBusy

    try:
        return open_port(path, clock=clock, baudrate=115200, timeout=0.2)
    except PortBusy:
        return None


class LabkitRun:
    """One `labkit run` process (the supervisor) and its session folder."""

    def __init__(self, proc: subprocess.Popen, sessions: Path, terminal: int | None = None,
                 hold_rpm: float = HOLD_RPM) -> None:
        self.proc = proc
        self.hold_rpm = hold_rpm
        self.sessions = sessions
        self.terminal = terminal  # master side of its controlling terminal, if it has one
        self.stderr = ""

    def type_on_terminal(self, keys: bytes) -> float:
        """Type on the run's terminal once it holds its speed (b"\x03" is Ctrl-C)."""
        assert self.terminal is not None
        self.wait_holding()
        self.worker()
        sent = time.monotonic()
        os.write(self.terminal, keys)
        return sent

    def close_terminal(self) -> float:
        """Close the run's terminal window (the kernel hangs up its session) once it holds."""
        assert self.terminal is not None
        self.wait_holding()
        self.worker()
        sent = time.monotonic()
        os.close(self.terminal)
        self.terminal = None
        return sent

    def session(self) -> Path | None:
        found = sorted(self.sessions.glob("*/events.jsonl"))
        return found[0].parent if found else None

    def events(self) -> list[dict]:
        session = self.session()
        if session is None:
            return []
        out = []
        for line in (session / "events.jsonl").read_text().splitlines():
            try:
                out.append(json.loads(line))
            except json.JSONDecodeError:
                pass  # a torn last line while the run writes
        return out

    def wait_holding(self, timeout: float = 90.0) -> None:
        """Until the run's own control events show the rotor within 5 % of the step speed."""
        def near_speed() -> bool:
            for event in reversed(self.events()):
                if event.get("type") == "control":
                    measured = event["loops"]["rotor"].get("measured_rad_s") or 0.0
                    return measured >= 0.95 * self.hold_rpm * RAD_S_PER_RPM
            return False

        wait_for(near_speed, timeout, f"rotor at {self.hold_rpm} RPM", self.proc)

    def wait_event(self, kind: str, timeout: float = 60.0) -> dict:
        """The first event of type ``kind`` (``settled``, ``interlock``...) the run writes."""
        return wait_for(lambda: next((e for e in self.events() if e.get("type") == kind), None),
                        timeout, f"a {kind!r} event", self.proc)

    def worker(self) -> int:
        kids = wait_for(lambda: children(self.proc.pid), 10, "the supervised worker process")
        assert len(kids) == 1, kids
        return kids[0]

    def signal_when_holding(self, name: str, target: str = "supervisor") -> float:
        self.wait_holding()
        signum = getattr(signal, name)
        if target == "group":  # supervisor and worker at once: only the controller's watchdog is left
            self.worker()
            sent = time.monotonic()
            os.killpg(self.proc.pid, signum)
            return sent
        pid = self.worker() if target == "worker" else self.proc.pid
        sent = time.monotonic()
        os.kill(pid, signum)
        return sent

    def fill_filesystem_when_holding(self, filler: Path) -> float:
        """Fill the sessions' file system (a small tmpfs) to the last byte: ENOSPC for the run."""
        import errno

        self.wait_holding()
        self.worker()
        sent = time.monotonic()
        chunk = b"\0" * 65536
        with open(filler, "wb", buffering=0) as f:
            while True:
                try:
                    f.write(chunk)
                except OSError as exc:
                    if exc.errno != errno.ENOSPC:
                        raise
                    if len(chunk) == 1:
                        return sent
                    chunk = chunk[: len(chunk) // 2]

    def fill_disk_when_holding(self) -> float:
        """Make every further write of the run fail with EFBIG, as a full sessions disk does
        with ENOSPC (RLIMIT_FSIZE of the worker set to 0: needs no root, no tmpfs)."""
        import resource

        self.wait_holding()
        worker = self.worker()
        sent = time.monotonic()
        resource.prlimit(worker, resource.RLIMIT_FSIZE, (0, 0))
        return sent

    def finish(self, timeout: float = 60.0) -> str:
        try:
            _, self.stderr = self.proc.communicate(timeout=timeout)
        finally:
            end_process(self.proc)
            if self.terminal is not None:
                os.close(self.terminal)
                self.terminal = None
        return self.stderr

    def run_json(self) -> dict:
        session = self.session()
        assert session is not None
        return json.loads((session / "run.json").read_text())


# ---- frozen worker, stopped supervisor, vanished session (issue 29) ----------------------------
def pause_process(pid: int, seconds: float) -> None:
    """SIGSTOP ``pid``, wait ``seconds``, SIGCONT it (Ctrl-Z then ``fg``, a debugger's pause)."""
    os.kill(pid, signal.SIGSTOP)
    try:
        time.sleep(seconds)
    finally:
        os.kill(pid, signal.SIGCONT)


def delete_session_when_holding(run: LabkitRun) -> float:
    """``rm -rf`` the run's session folder once the rotor holds its speed; when it was done."""
    import shutil

    run.wait_holding()
    run.worker()
    session = run.session()
    assert session is not None
    sent = time.monotonic()
    shutil.rmtree(session)
    return sent
