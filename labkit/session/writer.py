"""A run directory, written append-only as the run goes, readable after any crash.

Layout (documented in docs/reference/session-format.md)::

    SESSION/
      run.json            metadata: protocol, params, rig name, versions, git commit, clock,
                          start/end, notes, status and reason, resumed_from
      rig.toml            the rig file exactly as read
      events.jsonl        one event per line (setpoints, settles, points, drops, interlocks...)
      readings/ROLE.jsonl one device's stream: its descriptor (type "descriptor", run_id,
                          device, kind, driver, quantity, unit), then one reading per line
                          (Reading.values_json): t, value, stable, overload, flags
                          (device_reset, tare_lost...), raw
      readings/ROLE.parquet  the same as a table, written at the end (pyarrow)
      cassettes/ROLE.jsonl   every serial byte of that port (record://)
      results.json        {"protocol", "points", "fit"} at the end

Lines are flushed to the OS at least once a second (events at once), so SIGKILL loses at
most the last second. ``run.json`` is replaced atomically (write + rename) so it is never
half-written; a session killed mid-run keeps ``"status": "running"`` unless a supervisor closes
it (labkit.session.orphans).
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import platform
import subprocess
import sys
import time
from importlib import metadata
from pathlib import Path
from typing import Any, TextIO

from labkit.documents import ReadingEvent, RunDocument, StreamDescriptor
from labkit.errors import SessionError
from labkit.session.export import readings_to_parquet
from labkit.session.paths import session_file

FLUSH_INTERVAL_S = 0.5  # wall-clock seconds between flushes of reading files (< 1 s)


def utc_now() -> str:
    return _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds")


def _versions() -> dict[str, str]:
    out = {"python": platform.python_version()}
    for dist in ("labkit", "numpy", "scipy", "pyserial", "rerun-sdk", "pyarrow"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            pass
    return out


def _git_commit() -> str | None:
    """labkit's own commit when it runs from a git checkout; None otherwise (an installed
    labkit inside some other repository, e.g. a venv in the user's project, is not that
    repository's commit)."""
    here = Path(__file__).resolve()
    try:
        out = subprocess.run(["git", "-C", str(here.parent), "rev-parse", "--show-toplevel", "HEAD"],
                             capture_output=True, text=True, timeout=5, check=False)
    except (OSError, subprocess.SubprocessError):
        return None
    lines = out.stdout.split()
    if out.returncode != 0 or len(lines) != 2:
        return None
    top, commit = Path(lines[0]).resolve(), lines[1]
    return commit if here == top / "labkit" / "session" / "writer.py" else None


def _json_default(obj: Any) -> Any:
    if isinstance(obj, bytes):
        return obj.decode("latin-1")
    if isinstance(obj, (set, frozenset)):
        return sorted(obj)
    if hasattr(obj, "item"):  # numpy scalars
        return obj.item()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def dumps(obj: Any) -> str:
    return json.dumps(obj, default=_json_default, separators=(",", ":"))


def write_json_atomic(path: Path, data: Any) -> None:
    tmp = path.with_name(path.name + ".tmp")
    try:
        tmp.write_text(json.dumps(data, default=_json_default, indent=2) + "\n", encoding="utf-8")
        os.replace(tmp, path)
    except OSError:
        tmp.unlink(missing_ok=True)  # a full disk leaves the old file, never a torn one
        raise


def new_session_dir(root: str | Path, protocol: str) -> Path:
    """``root/YYYYmmdd-HHMMSS-protocol`` (``-2``, ``-3``... if taken). Raises SessionError."""
    root = Path(root)
    stamp = _dt.datetime.now(_dt.UTC).strftime("%Y%m%d-%H%M%S")
    try:
        root.mkdir(parents=True, exist_ok=True)
        for n in range(1, 1000):
            path = root / (f"{stamp}-{protocol}" + (f"-{n}" if n > 1 else ""))
            try:
                path.mkdir()
                return path
            except FileExistsError:
                continue
    except OSError as exc:
        raise SessionError(f"{root}: cannot create a session directory: {exc.strerror or exc}") from None
    raise SessionError(f"{root}: too many sessions with the same name")


def check_writable(root: str | Path) -> None:
    """Fail early (before any motor turns) when sessions cannot be written under ``root``."""
    root = Path(root)
    try:
        root.mkdir(parents=True, exist_ok=True)
        probe = root / f".labkit-write-test-{os.getpid()}"
        probe.write_text("")
        probe.unlink()
    except OSError as exc:
        raise SessionError(f"{root}: session directory is not writable: {exc.strerror or exc}") from None


class Session:
    """Writer of one run directory; also a sink (``on_event``) for the runner's events."""

    def __init__(self, path: Path, meta: dict[str, Any]) -> None:
        self.path = path
        self.meta = meta
        self.cassette_dir = path / "cassettes"
        self.readings_dir = path / "readings"
        self.cassette_dir.mkdir(exist_ok=True)
        self.readings_dir.mkdir(exist_ok=True)
        self._events: TextIO = open(path / "events.jsonl", "a", encoding="utf-8")  # noqa: SIM115
        self._readings: dict[str, TextIO] = {}
        self._last_flush = time.monotonic()
        self.closed = False

    # ---- creation -------------------------------------------------------------------------
    @classmethod
    def create(cls, root: str | Path, *, protocol: str, params: dict[str, Any], rig_name: str,
               rig_text: str, clock: str, notes: str = "", resumed_from: str | None = None,
               argv: list[str] | None = None, run_id: str | None = None) -> Session:
        from labkit.session.process import process_identity

        path = new_session_dir(root, protocol)
        meta = {
            "schema": 1,
            "protocol": protocol,
            "params": params,
            "rig": rig_name,
            "rig_file": "rig.toml",
            "clock": clock,
            "started": utc_now(),
            "ended": None,
            "status": "running",
            "reason": None,
            "notes": notes,
            "resumed_from": resumed_from,
            "run_id": run_id,   # every document's run_id (a resumed run keeps the first run's)
            "argv": argv if argv is not None else sys.argv[1:],
            "versions": _versions(),
            "git_commit": _git_commit(),
            "host": platform.node(),
            "pid": os.getpid(),  # lets a supervisor find and close the session of a killed run
            "pid_start": process_identity(os.getpid()),  # ... and not one whose PID was reused
        }
        try:
            (path / "rig.toml").write_text(rig_text, encoding="utf-8")
            write_json_atomic(path / "run.json", meta)
            return cls(path, meta)
        except OSError as exc:
            raise SessionError(f"{path}: cannot write: {exc.strerror or exc}") from None

    # ---- writing --------------------------------------------------------------------------
    def on_event(self, event: RunDocument) -> None:
        if self.closed:
            return
        if isinstance(event, ReadingEvent | StreamDescriptor):
            role = event.device or "unknown"
            f = self._readings.get(role)
            if f is None:
                f = self._readings[role] = open(session_file(self.path, "readings", f"{role}.jsonl"), "a",  # noqa: SIM115
                                                encoding="utf-8")
            if isinstance(event, StreamDescriptor):   # the stream's quantity and unit, once
                f.write(dumps(event.to_json()) + "\n")
            else:
                f.write(dumps(event.reading.values_json()) + "\n")
            self._maybe_flush()
        else:
            self._events.write(dumps(event.to_json()) + "\n")
            self.flush()

    def _maybe_flush(self) -> None:
        if time.monotonic() - self._last_flush >= FLUSH_INTERVAL_S:
            self.flush()

    def flush(self) -> None:
        self._events.flush()
        for f in self._readings.values():
            f.flush()
        self._last_flush = time.monotonic()

    def write_results(self, results: dict[str, Any]) -> None:
        write_json_atomic(self.path / "results.json", results)

    def update_meta(self, **changes: Any) -> None:
        self.meta.update(changes)
        write_json_atomic(self.path / "run.json", self.meta)

    def finish(self, status: str, reason: str | None = None) -> None:
        """Close files, export Parquet, and record the exit status. Raises SessionError only when
        the disk refuses the last writes (the files keep their whole lines: resumable)."""
        if self.closed:
            return
        self.closed = True
        failure: OSError | None = None
        for f in (self._events, *self._readings.values()):
            try:
                f.close()  # flushes; on a full disk the file is closed all the same
            except OSError as exc:
                failure = failure or exc
        if failure is not None:
            raise SessionError(f"cannot write {self.path}: {failure.strerror or failure}; the session "
                               "keeps what was written before (resumable)") from None
        try:
            for role_file in sorted(self.readings_dir.glob("*.jsonl")):
                readings_to_parquet(role_file, role_file.with_suffix(".parquet"))
        except Exception:  # noqa: BLE001 - the JSONL files stay the primary record
            pass
        from labkit.session.integrity import file_digests

        try:
            digests: dict[str, str] | None = file_digests(self.path)  # labkit/session/integrity.py
        except OSError:
            digests = None  # a file that cannot be read back: the session ends without digests
        self.update_meta(ended=utc_now(), status=status, reason=reason, digests=digests)
