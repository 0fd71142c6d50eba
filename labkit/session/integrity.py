"""A session's files as they were when it ended (issue 27, *sessions you can trust*).

* **Digests.** When a session ends (:meth:`labkit.session.writer.Session.finish`) the SHA-256
  of each recorded file (``events.jsonl``, ``cassettes/*.jsonl``, ``readings/*.jsonl``) is
  written into ``run.json`` as ``digests``. :func:`digest_problems` names each file that no
  longer has its digest (any byte changed, a line moved) or is missing. A digest is not a
  signature: whoever edits a file and ``run.json`` both is not caught by it; a killed run ends
  without digests (its files are then held only by the checks below and by the replay).
* **The cassette's time line.** :func:`timeline_problems`: a cassette's times are clock
  readings since its ``clock_origin``: never negative, and never going back within one thread
  (a thread takes its time and writes its line before it reads or writes again). Between
  threads, whose time and write are not one step, at most :data:`CROSS_THREAD_SLACK_S` back.
  A line moved or two chunks swapped with their times show here, naming file and line.

Cannot be detected without digests: data swapped between two chunks of one reply that keeps
every time (the exact replay's readings and points then differ when the bytes mattered; a
keep-alive's echo does not matter and is not caught).
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

#: a thread may write its line this long after another thread's later time reading
CROSS_THREAD_SLACK_S = 0.1
#: the files whose digests a session keeps, as glob patterns in the session folder
DIGESTED = ("events.jsonl", "cassettes/*.jsonl", "readings/*.jsonl")
#: at most this many time-line problems are listed per cassette
MAX_LISTED = 5


def sha256_of(path: Path) -> str:
    h = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def file_digests(session: Path) -> dict[str, str]:
    """``{relative path: sha256}`` of the session's recorded files (regular files only)."""
    out: dict[str, str] = {}
    for pattern in DIGESTED:
        for path in sorted(session.glob(pattern)):
            if path.is_file() and not path.is_symlink():
                out[path.relative_to(session).as_posix()] = sha256_of(path)
    return out


def digest_problems(session: Path, meta: dict[str, Any]) -> list[str]:
    """Each file whose digest differs from the one ``run.json`` recorded (none recorded: none)."""
    recorded = meta.get("digests")
    if not isinstance(recorded, dict):
        return []
    out = []
    for name, digest in sorted(recorded.items()):
        path = session / str(name)
        if not isinstance(digest, str) or ".." in Path(str(name)).parts:
            out.append(f"{session / 'run.json'}: digests.{name}: not a digest of a session file")
        elif not path.is_file():
            out.append(f"{path}: missing, though run.json recorded its digest when the session ended")
        elif sha256_of(path) != digest:
            out.append(f"{path}: changed after the session ended (its SHA-256 is not the one run.json "
                       "recorded): edited?")
    return out


def timeline_problems(path: Path) -> list[str]:
    """A cassette's times against its own order (module docstring); damaged lines are the
    cassette reader's to report."""
    from labkit.io.cassette_lines import LineDecoder

    out: list[str] = []
    last: dict[Any, tuple[float, int]] = {}
    latest: tuple[float, int] | None = None
    decoder: LineDecoder | None = None
    with path.open(encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, start=1):
            try:
                event = json.loads(line)
                if number == 1 and isinstance(event, dict) and event.get("schema") == 2:
                    decoder = LineDecoder(str(event.get("port", "")))  # repeat lines name their thread
                elif decoder is not None and isinstance(event, dict):
                    event = decoder.decode(event)
            except (ValueError, RecursionError, KeyError, TypeError):
                continue  # a damaged line: the cassette reader names it
            t = event.get("t") if isinstance(event, dict) else None
            if number == 1 or not isinstance(t, int | float) or isinstance(t, bool):
                continue
            th = event.get("th")
            if t < 0:
                out.append(f"{path}:{number}: negative time {t!r} (times count from the cassette's "
                           "clock origin): edited?")
            elif th in last and t < last[th][0]:
                out.append(f"{path}:{number}: time {t!r} goes back from {last[th][0]!r} (line {last[th][1]}, "
                           "the same thread): lines moved or swapped?")
            elif latest is not None and t < latest[0] - CROSS_THREAD_SLACK_S:
                out.append(f"{path}:{number}: time {t!r} is {latest[0] - t:.3g} s before line {latest[1]}'s "
                           f"(more than the {CROSS_THREAD_SLACK_S:g} s two threads can differ): lines moved "
                           "or swapped?")
            last[th] = (float(t), number)
            if latest is None or t > latest[0]:
                latest = (float(t), number)
            if len(out) >= MAX_LISTED:
                out.append(f"{path}: further time problems not listed")
                break
    return out


def integrity_problems(session: Path, meta: dict[str, Any]) -> list[str]:
    """Digest and time-line problems of a session's files (each ``file[:line]: reason``)."""
    out = digest_problems(session, meta)
    for cassette in sorted((session / "cassettes").glob("*.jsonl")):
        if cassette.is_file():
            out += timeline_problems(cassette)
    return out
