"""Run directories: append-only, crash-safe, resumable (see writer.py for the layout)."""

from labkit.errors import SessionError
from labkit.session.export import export_csv, read_jsonl
from labkit.session.reader import SessionRecord, load_session
from labkit.session.writer import Session, check_writable, new_session_dir

__all__ = [
    "Session", "SessionError", "SessionRecord", "check_writable", "export_csv", "load_session",
    "new_session_dir", "read_jsonl",
]
