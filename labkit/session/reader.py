"""Reading a session back (complete, or cut short by a crash) for resume, replay and analysis.

Every file is read inside the session directory only (:func:`labkit.session.paths.session_file`),
with a size bound, and never raises anything but :class:`SessionError` naming the file:

* ``run.json`` and ``results.json``: one JSON document each, at most :data:`MAX_JSON_BYTES`;
  unreadable (bad bytes, bad JSON, nested deeper than :data:`MAX_JSON_DEPTH`) is an error.
* ``events.jsonl`` and ``readings/ROLE.jsonl``: one JSON object per line. A torn last line
  (a crash mid-write: no newline at its end) is skipped silently. Any other damaged line (not
  UTF-8, not JSON, not an object, longer than :func:`line_limit`) is skipped and reported as
  ``file:line: damaged line skipped (reason)`` in :attr:`SessionRecord.problems`. A skipped
  event is never guessed at: a point it held is missing, so ``--resume`` measures that step
  again. Documented in docs/reference/protocols.md (Resume).
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from labkit.errors import SessionError
from labkit.readings import declared
from labkit.session.paths import session_file

MAX_JSON_BYTES = 64_000_000        # run.json, results.json
MAX_JSONL_BYTES = 4_000_000_000    # events.jsonl, readings/ROLE.jsonl
MAX_LINE_BYTES = 1_000_000         # one reading, or any line of a file but events.jsonl
#: one event: the results event repeats results.json (2.5 MB for a 4 736-point sweep), so its
#: line may be as long as that file may be
MAX_EVENT_LINE_BYTES = MAX_JSON_BYTES
MAX_JSON_DEPTH = 64                # nesting of any document or line


def _depth_ok(raw: bytes) -> bool:
    """Nesting depth of a JSON text below :data:`MAX_JSON_DEPTH` (counted outside strings)."""
    depth, in_string, escaped = 0, False, False
    for byte in raw:
        if in_string:
            if escaped:
                escaped = False
            elif byte == 0x5C:      # backslash
                escaped = True
            elif byte == 0x22:      # quote
                in_string = False
        elif byte == 0x22:
            in_string = True
        elif byte in (0x5B, 0x7B):
            depth += 1
            if depth > MAX_JSON_DEPTH:
                return False
        elif byte in (0x5D, 0x7D):
            depth -= 1
    return True


def parse_json_bytes(raw: bytes) -> Any:
    """JSON from bytes; ValueError with a short reason for anything that is not usable JSON."""
    if not _depth_ok(raw):
        raise ValueError(f"nested deeper than {MAX_JSON_DEPTH} levels")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(f"not UTF-8 text (byte {exc.start})") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"not JSON ({exc.msg} at line {exc.lineno} column {exc.colno})") from None
    except RecursionError:
        raise ValueError("nested too deeply") from None


def _regular_file(path: Path, limit: int) -> None:
    if not path.is_file():
        raise SessionError(f"{path}: not a regular file")
    size = path.stat().st_size
    if size > limit:
        raise SessionError(f"{path}: {size} bytes, more than the limit of {limit}")


def read_json_file(path: Path, limit: int = MAX_JSON_BYTES) -> Any:
    """One JSON document, bounded. SessionError as ``file: reason``."""
    _regular_file(path, limit)
    try:
        with open(path, "rb") as f:
            raw = f.read(limit + 1)
    except OSError as exc:
        raise SessionError(f"{path}: unreadable: {exc.strerror or exc}") from None
    try:
        return parse_json_bytes(raw)
    except ValueError as exc:
        raise SessionError(f"{path}: unreadable: {exc}") from None


def line_limit(path: Path) -> int:
    """The longest line a session file may hold: :data:`MAX_EVENT_LINE_BYTES` in events.jsonl,
    else :data:`MAX_LINE_BYTES`."""
    return MAX_EVENT_LINE_BYTES if path.name == "events.jsonl" else MAX_LINE_BYTES


def _skip_line(f: Any) -> None:
    """Read past the rest of an over-long line, a megabyte at a time."""
    while True:
        chunk = f.readline(1 << 20)
        if not chunk or chunk.endswith(b"\n"):
            return


def iter_jsonl_lines(path: Path, problems: list[str] | None = None,
                     limit: int = MAX_JSONL_BYTES) -> Iterator[tuple[int, dict[str, Any]]]:
    """``(line number, object)`` for each good line of a JSONL file, read as it is asked for
    (see the module docstring). Damaged lines are skipped; each is reported in ``problems`` as
    ``file:line: reason``."""
    _regular_file(path, limit)
    longest = line_limit(path)
    try:
        with open(path, "rb") as f:
            number = 0
            while True:
                raw = f.readline(longest + 1)
                if not raw:
                    break
                number += 1
                torn = not raw.endswith(b"\n")
                if torn and len(raw) > longest:
                    _skip_line(f)
                    if problems is not None:
                        problems.append(f"{path}:{number}: damaged line skipped "
                                        f"(longer than {longest} bytes)")
                    continue
                if not raw.strip():
                    continue
                try:
                    value = parse_json_bytes(raw)
                    if not isinstance(value, dict):
                        raise ValueError(f"a JSON {type(value).__name__}, not an object")
                except ValueError as exc:
                    if not torn and problems is not None:  # a torn line is the last (crash mid-write)
                        problems.append(f"{path}:{number}: damaged line skipped ({exc})")
                    continue
                yield number, value
    except OSError as exc:
        raise SessionError(f"{path}: unreadable: {exc.strerror or exc}") from None


def read_jsonl_lines(path: Path, problems: list[str] | None = None,
                     limit: int = MAX_JSONL_BYTES) -> list[tuple[int, dict[str, Any]]]:
    """``(line number, object)`` for each good line of a JSONL file (see the module docstring).

    Damaged lines are skipped; each is reported in ``problems`` as ``file:line: reason``."""
    return list(iter_jsonl_lines(path, problems, limit))


def read_jsonl(path: Path, problems: list[str] | None = None) -> list[dict[str, Any]]:
    """The good lines of a JSONL file as objects (damaged ones reported in ``problems``)."""
    return [row for _, row in read_jsonl_lines(Path(path), problems)]


@dataclass
class SessionRecord:
    path: Path
    meta: dict[str, Any]
    events: list[dict[str, Any]]
    results: dict[str, Any] | None
    #: line number in events.jsonl of each event (same order as ``events``)
    event_lines: list[int] = field(default_factory=list)
    #: ``file:line: reason`` of every damaged line skipped while reading
    problems: list[str] = field(default_factory=list)

    @property
    def protocol(self) -> str:
        return str(self.meta["protocol"])

    @property
    def params(self) -> dict[str, Any]:
        return dict(self.meta.get("params") or {})

    @property
    def run_id(self) -> str | None:
        """The run's id (run.json, else its documents'); None for a session recorded before run ids."""
        found = self.meta.get("run_id") or next((e["run_id"] for e in self.events if e.get("run_id")), None)
        return str(found) if found else None

    def rig_path(self) -> Path:
        """The session's rig copy; SessionError if run.json points outside the session."""
        name = self.meta.get("rig_file", "rig.toml")
        if not isinstance(name, str):
            raise SessionError(f"{self.path / 'run.json'}: rig_file must be a file name, got {name!r}")
        return session_file(self.path, name)

    def completed_points(self) -> list[dict[str, Any]]:
        """Result rows of the steps this session finished (``point`` events), as recorded."""
        return [e["point"] for e in self.events if e.get("type") == "point"]

    def point_events(self) -> list[tuple[str, Any]]:
        """``(where, point)`` of every ``point`` event: where = ``events.jsonl:LINE``."""
        lines = self.event_lines or [0] * len(self.events)
        return [(f"{self.path / 'events.jsonl'}:{n}", e.get("point"))
                for n, e in zip(lines, self.events, strict=True) if e.get("type") == "point"]

    def readings(self, role: str) -> list[dict[str, Any]]:
        """The readings of ``readings/ROLE.jsonl``, each with its stream's quantity and unit
        (:func:`labkit.readings.declared`)."""
        path = session_file(self.path, "readings", f"{role}.jsonl")
        return [row for _, row in declared(iter_jsonl_lines(path, self.problems))] if path.exists() else []


def load_session_record(path: str | Path, skip_types: frozenset[str] = frozenset()) -> SessionRecord:
    """Read ``run.json``, ``events.jsonl`` and ``results.json`` (if any). Raises SessionError.
    Events whose ``type`` is in ``skip_types`` are not kept (a replay needs no control ticks)."""
    p = Path(path)
    run = p / "run.json"
    if not run.exists():
        raise SessionError(f"{p}: not a labkit session (no run.json)")
    meta = read_json_file(session_file(p, "run.json"))
    if not isinstance(meta, dict):
        raise SessionError(f"{run}: must be a JSON object, got a {type(meta).__name__}")
    for key in ("protocol", "params"):
        if key not in meta:
            raise SessionError(f"{run}: missing key {key!r}")
    if not isinstance(meta["protocol"], str) or not isinstance(meta["params"], dict):
        raise SessionError(f"{run}: protocol must be a name and params an object")
    problems: list[str] = []
    events_path = session_file(p, "events.jsonl")
    lines = ([(n, e) for n, e in iter_jsonl_lines(events_path, problems) if e.get("type") not in skip_types]
             if events_path.exists() else [])
    results = None
    results_path = session_file(p, "results.json")
    if results_path.exists():
        results = read_json_file(results_path)
        if not isinstance(results, dict):
            raise SessionError(f"{results_path}: must be a JSON object, got a {type(results).__name__}")
    return SessionRecord(p, meta, [e for _, e in lines], results, [n for n, _ in lines], problems)
